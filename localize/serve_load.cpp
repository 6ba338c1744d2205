#include "localize/serve_load.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <mutex>
#include <random>
#include <thread>

#include "core/error.hpp"
#include "core/process_memory.hpp"
#include "localize/robot_client.hpp"

namespace lasercell::localize {
namespace {

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

/// The replies of one LOOK, its NEXTs up to NO_MORE, and a PING.
using Cycle = std::vector<RobotReply>;

/// Replies equal in everything the server decides (not the latency, which is measured).
bool SameAnswer(const RobotReply& a, const RobotReply& b) {
  return a.status == b.status && a.part_index == b.part_index && a.part == b.part &&
         a.instance == b.instance && a.instances_left == b.instances_left &&
         a.position_sigma_mm == b.position_sigma_mm &&
         a.target_from_grasp.matrix() == b.target_from_grasp.matrix();
}

/// Runs one valid cycle on a new connection; ids count from `first_id`.
Cycle ValidCycle(const std::string& address, bool ascii, std::int32_t first_id) {
  RobotClient robot(address, ascii);
  Cycle cycle;
  RobotRequest request;
  request.command = RobotCommand::kLook;
  request.request_id = first_id;
  cycle.push_back(robot.Request(request, 300000.0));
  for (int i = 0; i < 1000; ++i) {  // a job has far fewer grasps; bounded regardless
    request.command = RobotCommand::kNext;
    request.request_id = first_id + 1 + i;
    cycle.push_back(robot.Request(request));
    if (cycle.back().status != ReplyStatus::kOk) break;
  }
  request.command = RobotCommand::kPing;
  request.request_id = first_id + 2000;
  cycle.push_back(robot.Request(request));
  return cycle;
}

/// Compares a cycle with the reference; "" when equal, else what differs. Binary replies echo
/// the request's id; ASCII ones count the connection's requests from 1.
std::string CompareCycle(const Cycle& got, const Cycle& reference, bool ascii,
                         std::int32_t first_id) {
  if (got.size() != reference.size()) {
    return std::to_string(got.size()) + " replies instead of " + std::to_string(reference.size());
  }
  for (std::size_t i = 0; i < got.size(); ++i) {
    const auto n = static_cast<std::int32_t>(i);
    const std::int32_t id = ascii ? n + 1 : i + 1 == got.size() ? first_id + 2000 : first_id + n;
    if (got[i].request_id != id) {
      return "reply " + std::to_string(i) + " carries id " + std::to_string(got[i].request_id) +
             ", not " + std::to_string(id);
    }
    if (!SameAnswer(got[i], reference[i])) {
      return "reply " + std::to_string(i) + ": " + ReplyText(got[i]) + "; expected " +
             ReplyText(reference[i]);
    }
  }
  return "";
}

/// Shared state of the client threads.
struct Load {
  std::string address;
  Cycle reference[2];  // binary, ASCII
  ServeLoadOptions options;
  Clock::time_point end;
  std::mutex mutex;
  ServeLoadReport report;

  void Problem(const std::string& what) {
    std::lock_guard<std::mutex> lock(mutex);
    if (report.problems.size() < 10) report.problems.push_back(what);
  }
  void Count(std::uint64_t ServeLoadReport::*field, std::uint64_t n = 1) {
    std::lock_guard<std::mutex> lock(mutex);
    report.*field += n;
  }
};

void Misbehave(Load& load, std::mt19937_64& rng) {
  std::uniform_int_distribution<int> kind(0, 4);
  RobotRequest look;
  look.command = RobotCommand::kLook;
  const std::string frame = EncodeBinaryRequest(look);
  const int k = kind(rng);
  try {
    RobotClient robot(load.address, k == 4);
    if (k == 0) {  // garbage
      std::uniform_int_distribution<int> length(1, 2000), byte(0, 255);
      std::string junk(static_cast<std::size_t>(length(rng)), '\0');
      for (char& c : junk) c = static_cast<char>(byte(rng));
      load.Count(&ServeLoadReport::garbage);
      robot.SendRaw(junk);
      std::this_thread::sleep_for(
          std::chrono::milliseconds(std::uniform_int_distribution<int>(0, 200)(rng)));
    } else if (k == 1) {  // half a frame, then gone
      load.Count(&ServeLoadReport::half_frames);
      robot.SendRaw(
          frame.substr(0, std::uniform_int_distribution<std::size_t>(1, frame.size() - 1)(rng)));
    } else if (k == 2) {  // half a frame, then silence past the frame timeout
      load.Count(&ServeLoadReport::stalled_frames);
      robot.SendRaw(frame.substr(0, frame.size() / 2));
      std::this_thread::sleep_for(
          std::chrono::milliseconds(static_cast<int>(load.options.server.frame_timeout_ms) + 300));
    } else if (k == 3) {  // thousands of PINGs, replies never read
      load.Count(&ServeLoadReport::slow_readers);
      RobotRequest ping;
      std::string pings;
      for (int i = 0; i < 20000; ++i) pings += EncodeBinaryRequest(ping);
      robot.SendRaw(pings);
      std::this_thread::sleep_for(std::chrono::milliseconds(500));
    } else {  // malformed ASCII lines
      load.Count(&ServeLoadReport::bad_lines);
      robot.SendRaw("LOOK 1 2 3\nJUMP\nLOOK 1e12 0 0 0 0 0\n\r\n" + std::string(300, 'x') + "\n");
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  } catch (const InputError&) {
    // The server closed the connection: what it should do to most of these.
  }
}

void ClientThread(Load& load, int index) {
  std::mt19937_64 rng(load.options.seed * 1000003u + static_cast<std::uint64_t>(index));
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::int32_t next_id = 100000 * (index + 1);
  while (Clock::now() < load.end) {
    if (unit(rng) >= load.options.valid_fraction) {
      Misbehave(load, rng);
      continue;
    }
    const bool ascii = unit(rng) < 0.5;
    const std::int32_t first_id = next_id;
    next_id += 3000;
    try {
      const Cycle got = ValidCycle(load.address, ascii, first_id);
      const std::string wrong = CompareCycle(got, load.reference[ascii ? 1 : 0], ascii, first_id);
      load.Count(&ServeLoadReport::valid_cycles);
      load.Count(&ServeLoadReport::valid_requests, got.size());
      if (!wrong.empty()) {
        load.Count(&ServeLoadReport::wrong_answers);
        load.Problem(std::string(ascii ? "ASCII" : "binary") + " cycle: " + wrong);
      }
    } catch (const InputError& e) {
      load.Count(&ServeLoadReport::failed_cycles);
      load.Problem(std::string(ascii ? "ASCII" : "binary") + " cycle failed: " + e.what());
    }
  }
}

}  // namespace

void ServeLoadOptions::Check() const {
  if (clients < 1 || clients > 256)
    throw OptionError("ServeLoadOptions.clients must be in [1, 256]");
  if (!(seconds > 0.0 && seconds <= 86400.0)) {
    throw OptionError("ServeLoadOptions.seconds must be in (0, 86400]");
  }
  if (!(warmup_seconds >= 0.0 && warmup_seconds < seconds)) {
    throw OptionError("ServeLoadOptions.warmup_seconds must be in [0, seconds)");
  }
  if (!(valid_fraction > 0.0 && valid_fraction <= 1.0)) {
    throw OptionError("ServeLoadOptions.valid_fraction must be in (0, 1]");
  }
  server.Check();
}

double ServeLoadReport::RssGrowthPercent() const {
  return rss_after_warmup_mb > 0 ? 100.0 * (rss_end_mb - rss_after_warmup_mb) / rss_after_warmup_mb
                                 : 0.0;
}

nlohmann::json ServeLoadReport::Json() const {
  return {{"benchmark", "serve_load"},
          {"seconds", seconds},
          {"clients", clients},
          {"valid_cycles", valid_cycles},
          {"valid_requests", valid_requests},
          {"wrong_answers", wrong_answers},
          {"failed_cycles", failed_cycles},
          {"misbehaving",
           {{"garbage", garbage},
            {"half_frames", half_frames},
            {"stalled_frames", stalled_frames},
            {"slow_readers", slow_readers},
            {"bad_lines", bad_lines}}},
          {"reference_replies", reference_replies},
          {"problems", problems},
          {"server", server.Summary()},
          {"rss_after_warmup_mb", rss_after_warmup_mb},
          {"rss_max_mb", rss_max_mb},
          {"rss_end_mb", rss_end_mb}};
}

std::string ServeLoadReport::Markdown() const {
  char text[900];
  std::snprintf(
      text, sizeof text,
      "| clients | seconds | valid cycles (requests) | wrong answers | failed cycles | "
      "garbage / half frames / stalled / slow readers / bad lines | RSS after warm-up / max / end "
      "(MB) | growth |\n|---:|---:|---:|---:|---:|---|---|---:|\n"
      "| %d | %.0f | %llu (%llu) | %llu | %llu | %llu / %llu / %llu / %llu / %llu | %.1f / %.1f / "
      "%.1f | %.2f %% |\n",
      clients, seconds, static_cast<unsigned long long>(valid_cycles),
      static_cast<unsigned long long>(valid_requests),
      static_cast<unsigned long long>(wrong_answers),
      static_cast<unsigned long long>(failed_cycles), static_cast<unsigned long long>(garbage),
      static_cast<unsigned long long>(half_frames), static_cast<unsigned long long>(stalled_frames),
      static_cast<unsigned long long>(slow_readers), static_cast<unsigned long long>(bad_lines),
      rss_after_warmup_mb, rss_max_mb, rss_end_mb, RssGrowthPercent());
  return std::string(text) + "\nServer: " + server.Summary() + "\n";
}

ServeLoadReport RunServeLoad(const LookHandler& look, const ServeLoadOptions& options,
                             const std::function<void(const std::string&)>& progress) {
  options.Check();
  PoseServerOptions server_options = options.server;
  server_options.bind_address = "127.0.0.1";
  server_options.port = 0;
  PoseServer server(look, server_options);
  std::atomic<bool> stop{false};
  std::thread serving([&] { server.Serve(stop); });
  Load load;
  load.options = options;
  load.address = "127.0.0.1:" + std::to_string(server.port());
  try {
    load.reference[0] = ValidCycle(load.address, false, 1);
    load.reference[1] = ValidCycle(load.address, true, 1);
  } catch (const InputError& e) {
    stop = true;
    serving.join();
    throw InputError(std::string("serve load: the reference cycle before the load failed: ") +
                     e.what());
  }
  load.report.reference_replies = load.reference[0].size();
  const Clock::time_point t0 = Clock::now();
  load.end = t0 + std::chrono::microseconds(static_cast<long long>(options.seconds * 1e6));
  std::vector<std::thread> clients;
  for (int i = 0; i < options.clients; ++i) clients.emplace_back(ClientThread, std::ref(load), i);
  double next_progress = 10.0;
  while (Clock::now() < load.end) {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    const double t = SecondsSince(t0);
    const double rss = ResidentMb();
    std::lock_guard<std::mutex> lock(load.mutex);
    if (t >= options.warmup_seconds) {
      if (load.report.rss_after_warmup_mb == 0.0) load.report.rss_after_warmup_mb = rss;
      load.report.rss_max_mb = std::max(load.report.rss_max_mb, rss);
    }
    if (progress && t >= next_progress) {
      next_progress += 10.0;
      progress("serve load: " + std::to_string(static_cast<int>(t)) + " s, " +
               std::to_string(load.report.valid_cycles) + " valid cycles, " +
               std::to_string(load.report.wrong_answers) + " wrong, " +
               std::to_string(load.report.failed_cycles) + " failed, RSS " +
               std::to_string(static_cast<int>(rss)) + " MB");
    }
  }
  for (std::thread& c : clients) c.join();
  stop = true;
  serving.join();
  ServeLoadReport report = std::move(load.report);
  report.seconds = SecondsSince(t0);
  report.clients = options.clients;
  report.server = server.counters();
  report.rss_end_mb = ResidentMb();
  report.rss_max_mb = std::max(report.rss_max_mb, report.rss_end_mb);
  return report;
}

}  // namespace lasercell::localize
