#pragma once
// One monotonic clock in nanoseconds for everything that compares times across modules: the UDP
// receiver's arrival times and sweep deadlines, and the pose server's sweep-to-reply latency
// (LookOutcome::sweep_taken_ns is read against it).

#include <chrono>
#include <cstdint>

namespace lasercell {

/// std::chrono::steady_clock now, in ns since its epoch.
inline std::int64_t SteadyNowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

}  // namespace lasercell
