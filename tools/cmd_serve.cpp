// `lasercell serve JOB.yaml --port P [--udp PORT | --gige DEVICE]`: the pose server for the
// handling robot (localize/pose_server.hpp); each LOOK runs the job on the next sweep of a UDP or
// GigE Vision stream, or on the job's profile file read again. Stops on SIGINT/SIGTERM or after
// --duration-s. `lasercell robot-client HOST:PORT look|next|ping ...`: the robot's side, for tests
// and by hand.
#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "core/error.hpp"
#include "core/se3.hpp"
#include "localize/job.hpp"
#include "localize/job_run.hpp"
#include "localize/pose_server.hpp"
#include "localize/robot_client.hpp"
#include "tools/commands.hpp"

namespace lasercell::tools {
namespace {

std::atomic<bool> g_stop{false};

extern "C" void StopOnSignal(int) { g_stop = true; }

struct ServeArgs {
  std::string job;
  localize::PoseServerOptions server;
  int udp_port = -1;
  std::string udp_bind = "0.0.0.0";
  triangulation::GigeSourceOptions gige;
  double sweep_wait_s = 10.0;
  double duration_s = 0.0;
  int threads = -1;
};

void RunServe(const ServeArgs& args) {
  if (!(args.duration_s >= 0.0)) throw OptionError("--duration-s must be >= 0 (0 = until Ctrl-C)");
  if (!(args.sweep_wait_s > 0.0)) throw OptionError("--sweep-wait-s must be > 0");
  const localize::Job job = localize::ReadJobFile(args.job);
  localize::JobRunOptions run;
  run.threads = args.threads;
  localize::JobRunner runner(job, run);
  const std::shared_ptr<triangulation::ProfileSource> source =
      MakeLiveSource(args.udp_port, args.udp_bind, args.gige, args.sweep_wait_s, "--sweep-wait-s");
  localize::PoseServer server(localize::JobLookHandler(runner, source), args.server);
  server.SetLog([](const std::string& line) {
    std::printf("%s\n", line.c_str());
    std::fflush(stdout);
  });
  std::printf("serving %s on tcp %s:%u; sweeps from %s\n", args.job.c_str(),
              args.server.bind_address.c_str(), server.port(),
              source ? source->Describe().c_str() : ("file " + job.profiles).c_str());
  std::fflush(stdout);
  std::signal(SIGINT, StopOnSignal);
  std::signal(SIGTERM, StopOnSignal);
  if (args.duration_s > 0.0) {
    std::thread([d = args.duration_s] {
      std::this_thread::sleep_for(std::chrono::milliseconds(static_cast<long>(d * 1000)));
      g_stop = true;
    }).detach();
  }
  server.Serve(g_stop);
  std::printf("stopped: %s\n", server.counters().Summary().c_str());
}

struct ClientArgs {
  std::string address;
  std::vector<std::string> commands;
  std::vector<double> pose;
  bool ascii = false;
  double timeout_s = 30.0;
};

void RunRobotClient(const ClientArgs& args) {
  if (!args.pose.empty() && args.pose.size() != 6) {
    throw OptionError("--pose takes six numbers x,y,z,rx,ry,rz (mm, degrees)");
  }
  for (const std::string& name : args.commands) {
    if (name != "look" && name != "next" && name != "ping") {
      throw OptionError("unknown robot command '" + name + "' (look, next or ping)");
    }
  }
  localize::RobotClient client(args.address, args.ascii);
  std::int32_t id = 0;
  for (const std::string& name : args.commands) {
    localize::RobotRequest request;
    request.request_id = ++id;
    if (name == "look") {
      request.command = localize::RobotCommand::kLook;
      if (!args.pose.empty()) {
        Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
        pose.translation() = Eigen::Vector3d(args.pose[0], args.pose[1], args.pose[2]);
        pose.linear() = RotationFromFixedXyzDeg({args.pose[3], args.pose[4], args.pose[5]});
        request.base_from_flange = pose;
      }
    } else if (name == "next") {
      request.command = localize::RobotCommand::kNext;
    } else {
      request.command = localize::RobotCommand::kPing;
    }
    const localize::RobotReply r = client.Request(request, args.timeout_s * 1000.0);
    std::printf("%s: %s", name.c_str(), localize::ReplyText(r).c_str());
    if (r.status == localize::ReplyStatus::kOk) std::printf("  %.1f ms", r.latency_ms);
    std::printf("\n");
  }
}

}  // namespace

void AddServeCommands(CLI::App& app) {
  CLI::App* serve = app.add_subcommand(
      "serve", "Answer the handling robot's LOOK/NEXT requests over TCP by running a job");
  auto s = std::make_shared<ServeArgs>();
  serve->add_option("job", s->job, "Job file (lasercell.job)")->required();
  serve->add_option("--port", s->server.port, "TCP port the robot connects to")->required();
  serve->add_option("--bind", s->server.bind_address, "Listen address")->capture_default_str();
  serve->add_option("--udp", s->udp_port,
                    "Take each LOOK's sweep from this UDP port (default: the job's profile "
                    "file, read again for every LOOK)");
  serve->add_option("--udp-bind", s->udp_bind, "Listen address for --udp")->capture_default_str();
  AddGigeOptions(serve, &s->gige);
  serve
      ->add_option("--sweep-wait-s", s->sweep_wait_s,
                   "How long a LOOK waits for a sweep on --udp or --gige before answering no_sweep")
      ->capture_default_str();
  serve->add_option("--max-clients", s->server.max_clients, "Connections served at once")
      ->capture_default_str();
  serve
      ->add_option("--frame-timeout-ms", s->server.frame_timeout_ms,
                   "A started request must complete within this")
      ->capture_default_str();
  serve
      ->add_option("--idle-timeout-s", s->server.idle_timeout_ms,
                   "Close connections silent for this long (0 = never)")
      ->transform([](std::string v) { return std::to_string(std::stod(v) * 1000.0); });
  serve->add_option("--duration-s", s->duration_s, "Stop after this long (0 = until Ctrl-C)")
      ->capture_default_str();
  serve->add_option("--threads", s->threads, "Worker threads (0 = all cores; default: the job's)");
  serve->callback([s] { RunServe(*s); });

  CLI::App* client = app.add_subcommand(
      "robot-client", "The robot's side of `serve`: send look / next / ping, print the replies");
  auto c = std::make_shared<ClientArgs>();
  client->add_option("address", c->address, "Pose server HOST:PORT")->required();
  client->add_option("commands", c->commands, "look, next or ping, in order")->required();
  client
      ->add_option("--pose", c->pose,
                   "The robot's flange pose sent with look: x,y,z,rx,ry,rz (mm, degrees)")
      ->delimiter(',');
  client->add_flag("--ascii", c->ascii, "Use the line protocol instead of binary frames");
  client->add_option("--timeout-s", c->timeout_s, "Wait this long for each reply")
      ->capture_default_str();
  client->callback([c] { RunRobotClient(*c); });
}

}  // namespace lasercell::tools
