#pragma once
// Deterministic parallel loops (TBB), the one parallel-for of every module.
// Every loop here writes results by index (or into per-chunk slots merged in chunk order), so
// the output never depends on the thread count or the scheduling: the chunking is fixed by the
// problem size alone, never by the number of threads.

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cstddef>

namespace lasercell {

/// Calls body(begin, end) over [0, n) in chunks of at most `grain` items. `threads` <= 0 uses
/// every core, 1 runs inline on the calling thread (no TBB at all).
template <typename Body>
void ParallelForChunks(int threads, std::size_t n, std::size_t grain, const Body& body) {
  if (n == 0) return;
  grain = std::max<std::size_t>(grain, 1);
  if (threads == 1 || n <= grain) {
    body(std::size_t{0}, n);
    return;
  }
  auto loop = [&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, grain),
                      [&](const tbb::blocked_range<std::size_t>& r) { body(r.begin(), r.end()); });
  };
  if (threads <= 0) {
    loop();
  } else {
    tbb::task_arena arena(threads);
    arena.execute(loop);
  }
}

/// Number of fixed-size chunks covering n items; use with ParallelForChunks over chunk indices
/// when partial sums must be merged in a fixed order (deterministic reductions).
inline std::size_t ChunkCount(std::size_t n, std::size_t chunk) { return (n + chunk - 1) / chunk; }

}  // namespace lasercell
