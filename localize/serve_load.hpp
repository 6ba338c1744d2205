#pragma once
// A pose server under hostile load (`lasercell bench serve-load`): `clients` robot connections
// at once for `seconds`, each connection choosing, at random, to behave - LOOK, then NEXT until
// NO_MORE, then PING, in binary or ASCII - or to misbehave: garbage bytes, half a frame and a
// disconnect, half a frame and silence past the frame timeout, thousands of PINGs whose replies
// it never reads, malformed ASCII lines. Every reply to a valid request must equal the one the
// same request got before the load began (the job replays one capture, so its answer is fixed)
// and carry the request's id; the process's resident memory is sampled throughout.
#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "localize/pose_server.hpp"

namespace lasercell::localize {

/// Options of RunServeLoad.
struct ServeLoadOptions {
  int clients = 8;               ///< Connections at once (one thread each).
  double seconds = 600.0;        ///< Wall time of the load, s.
  double warmup_seconds = 30.0;  ///< Memory growth is measured from the end of this, s.
  double valid_fraction = 0.4;   ///< Share of connections that behave.
  std::uint64_t seed = 1;        ///< Seeds every client's choices and garbage.
  /// The server's options for the run; bind_address is forced to 127.0.0.1 and port to any.
  PoseServerOptions server;
  /// Throws OptionError naming the field.
  void Check() const;
};

/// What happened under the load.
struct ServeLoadReport {
  double seconds = 0.0;
  int clients = 0;
  std::uint64_t valid_cycles = 0;    ///< LOOK + NEXTs + PING cycles completed and checked.
  std::uint64_t valid_requests = 0;  ///< Requests in them.
  std::uint64_t wrong_answers = 0;   ///< Replies that differ from the reference (or wrong id).
  std::uint64_t failed_cycles = 0;   ///< Valid cycles that got no reply (closed, timeout).
  std::uint64_t garbage = 0, half_frames = 0, stalled_frames = 0, slow_readers = 0,
                bad_lines = 0;          ///< Misbehaving connections by kind.
  std::uint64_t reference_replies = 0;  ///< Replies in one reference cycle (LOOK, NEXTs, PING).
  std::vector<std::string> problems;    ///< The first few wrong answers and failures, described.
  PoseServerCounters server;            ///< The server's own counters at the end.
  double rss_after_warmup_mb = 0.0, rss_max_mb = 0.0, rss_end_mb = 0.0;
  /// (end - after warm-up) / after warm-up, percent.
  double RssGrowthPercent() const;
  nlohmann::json Json() const;
  /// A Markdown table of the run, for BENCHMARKS.md / RELIABILITY.md.
  std::string Markdown() const;
};

/// Serves `look` on loopback and loads it as described at the top of this file. `progress` (may
/// be empty) is called about every 10 s with a one-line status. Throws InputError when the
/// reference cycle before the load fails (the job does not run on its own).
ServeLoadReport RunServeLoad(const LookHandler& look, const ServeLoadOptions& options,
                             const std::function<void(const std::string&)>& progress = {});

}  // namespace lasercell::localize
