// `lasercell bench serve JOB.yaml`: pick cycles against the pose server on loopback
// (localize/pose_server.hpp), in one process: a robot client sends LOOK (and NEXT) cycle after
// cycle; the server runs the job on its profile file each time. Reported: the client's round
// trip against the time the LOOK handler itself took (reading the sweep + running the job), so
// their difference is what the server and the protocol add; and resident memory after warm-up
// and at the end.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "core/error.hpp"
#include "core/json_io.hpp"
#include "core/process_memory.hpp"
#include "core/stats.hpp"
#include "localize/job.hpp"
#include "localize/job_run.hpp"
#include "localize/pose_server.hpp"
#include "localize/robot_client.hpp"
#include "localize/serve_load.hpp"
#include "tools/bench.hpp"

namespace lasercell::tools {
namespace {

struct ServeBenchArgs {
  std::string job;
  int cycles = 100;
  int warmup = 5;
  int threads = 1;
  std::string json_out;
};

double Ms(std::chrono::steady_clock::duration d) {
  return std::chrono::duration<double, std::milli>(d).count();
}

void RunServeBench(const ServeBenchArgs& args) {
  if (args.cycles < 1 || args.warmup < 0) {
    throw OptionError("bench serve: --cycles must be >= 1 and --warmup >= 0");
  }
  const localize::Job job = localize::ReadJobFile(args.job);
  localize::JobRunOptions run;
  run.threads = args.threads;
  localize::JobRunner runner(job, run);
  const localize::LookHandler look = localize::JobLookHandler(runner);
  std::vector<double> handler_ms;
  localize::PoseServerOptions options;
  options.bind_address = "127.0.0.1";
  localize::PoseServer server(
      [&](const localize::RobotRequest& request) {
        const auto t0 = std::chrono::steady_clock::now();
        localize::LookOutcome out = look(request);
        handler_ms.push_back(Ms(std::chrono::steady_clock::now() - t0));
        return out;
      },
      options);
  std::atomic<bool> stop{false};
  std::thread serving([&] { server.Serve(stop); });
  std::vector<double> round_trip_ms, overhead_ms, reply_latency_ms;
  int errors = 0, found = 0;
  double rss_after_warmup = 0.0;
  {
    localize::RobotClient robot("127.0.0.1:" + std::to_string(server.port()), false);
    for (int i = 0; i < args.warmup + args.cycles; ++i) {
      if (i == args.warmup) rss_after_warmup = ResidentMb();
      localize::RobotRequest request;
      request.command = localize::RobotCommand::kLook;
      request.request_id = i;
      const auto t0 = std::chrono::steady_clock::now();
      const localize::RobotReply reply = robot.Request(request, 120000.0);
      const double trip = Ms(std::chrono::steady_clock::now() - t0);
      request.command = localize::RobotCommand::kNext;
      const localize::RobotReply next = robot.Request(request);
      const bool ok = reply.request_id == i && next.status == localize::ReplyStatus::kNoMore &&
                      (reply.status == localize::ReplyStatus::kOk ||
                       reply.status == localize::ReplyStatus::kNoPart);
      errors += ok ? 0 : 1;
      if (i < args.warmup) continue;
      found += reply.status == localize::ReplyStatus::kOk ? 1 : 0;
      round_trip_ms.push_back(trip);
      overhead_ms.push_back(trip - handler_ms.back());
      reply_latency_ms.push_back(reply.latency_ms);
    }
  }
  stop = true;
  serving.join();
  const double rss_end = ResidentMb();
  const double growth = 100.0 * (rss_end - rss_after_warmup) / rss_after_warmup;
  std::vector<double> sorted = overhead_ms;
  std::sort(sorted.begin(), sorted.end());
  std::printf(
      "pose server on loopback: %d pick cycles (LOOK + NEXT) of %s after %d warm-up cycles, "
      "%d thread(s)\n\n"
      "| cycles | errors | grasps found | round trip median (ms) | LOOK handler median (ms) | "
      "server overhead median / max (ms) | sweep-to-reply median (ms) | RSS after warm-up / "
      "end (MB) | growth |\n|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n"
      "| %d | %d | %d | %.1f | %.1f | %.3f / %.3f | %.1f | %.1f / %.1f | %.2f %% |\n",
      args.cycles, args.job.c_str(), args.warmup, args.threads, args.cycles, errors, found,
      Median(round_trip_ms),
      Median(std::vector<double>(handler_ms.end() - args.cycles, handler_ms.end())),
      Median(overhead_ms), sorted.back(), Median(reply_latency_ms), rss_after_warmup, rss_end,
      growth);
  json::WriteFile(args.json_out, {{"benchmark", "serve"},
                                  {"job", args.job},
                                  {"cycles", args.cycles},
                                  {"warmup", args.warmup},
                                  {"threads", args.threads},
                                  {"errors", errors},
                                  {"found", found},
                                  {"round_trip_ms", round_trip_ms},
                                  {"overhead_ms", overhead_ms},
                                  {"reply_latency_ms", reply_latency_ms},
                                  {"rss_after_warmup_mb", rss_after_warmup},
                                  {"rss_end_mb", rss_end}});
}

struct ServeLoadArgs {
  std::string job;
  localize::ServeLoadOptions load;
  int threads = 1;
  std::string json_out;
};

void RunServeLoadBench(const ServeLoadArgs& args) {
  const localize::Job job = localize::ReadJobFile(args.job);
  localize::JobRunOptions run;
  run.threads = args.threads;
  localize::JobRunner runner(job, run);
  const localize::ServeLoadReport report = localize::RunServeLoad(
      localize::JobLookHandler(runner), args.load,
      [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); });
  std::printf(
      "pose server on loopback under %d misbehaving clients, %s (%llu replies per valid "
      "cycle)\n\n%s",
      report.clients, args.job.c_str(), static_cast<unsigned long long>(report.reference_replies),
      report.Markdown().c_str());
  for (const std::string& p : report.problems) std::printf("- %s\n", p.c_str());
  if (!args.json_out.empty()) json::WriteFile(args.json_out, report.Json());
}

}  // namespace

void AddServeLoadBenchCommand(CLI::App& bench) {
  CLI::App* cmd = bench.add_subcommand(
      "serve-load",
      "The pose server under misbehaving clients: every valid request answered right, memory");
  auto args = std::make_shared<ServeLoadArgs>();
  cmd->add_option("job", args->job, "Job file (its profile file is the sweep of every LOOK)")
      ->required();
  cmd->add_option("--clients", args->load.clients, "Connections at once")->capture_default_str();
  cmd->add_option("--seconds", args->load.seconds, "Wall time of the load")->capture_default_str();
  cmd->add_option("--warmup", args->load.warmup_seconds, "Seconds before memory is measured")
      ->capture_default_str();
  cmd->add_option("--valid-fraction", args->load.valid_fraction, "Share of connections that behave")
      ->capture_default_str();
  cmd->add_option("--seed", args->load.seed, "Seed of the clients' choices")->capture_default_str();
  args->load.server.send_buffer_bytes = 8192;
  // Above the clients, so that a refused connection would be the server's fault: with a limit
  // of exactly 8, 8 clients saw ~4 of 65 connections refused in 40 s, the server then holding 9
  // established ones (not yet explained). The limit itself is tested in pose_server_test.
  args->load.server.max_clients = 16;
  cmd->add_option("--send-buffer", args->load.server.send_buffer_bytes,
                  "Server's kernel send buffer per connection, bytes (0 = the system's): small, "
                  "so unread replies reach the server's own bound within the run")
      ->capture_default_str();
  cmd->add_option("--max-clients", args->load.server.max_clients,
                  "Server's connection limit (beyond it, connections are closed at once)")
      ->capture_default_str();
  cmd->add_option("--threads", args->threads, "Job threads (0 = all cores)")->capture_default_str();
  cmd->add_option("--json", args->json_out, "Also write the report as JSON");
  cmd->callback([args] { RunServeLoadBench(*args); });
}

void AddServeBenchCommand(CLI::App& bench) {
  CLI::App* cmd = bench.add_subcommand(
      "serve", "Pick cycles against the pose server on loopback: overhead over the job, memory");
  auto args = std::make_shared<ServeBenchArgs>();
  cmd->add_option("job", args->job, "Job file (its profile file is the sweep of every LOOK)")
      ->required();
  cmd->add_option("--cycles", args->cycles, "Measured cycles")->capture_default_str();
  cmd->add_option("--warmup", args->warmup, "Cycles before measuring")->capture_default_str();
  cmd->add_option("--threads", args->threads, "Job threads (0 = all cores)")->capture_default_str();
  cmd->add_option("--json", args->json_out, "Also write every cycle as JSON");
  cmd->callback([args] { RunServeBench(*args); });
}

}  // namespace lasercell::tools
