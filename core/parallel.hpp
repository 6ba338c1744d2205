#pragma once
// Deterministic parallel loops (TBB), the one parallel-for of every module.
// Every loop here writes results by index (or into per-chunk slots merged in chunk order), so
// the output never depends on the thread count or the scheduling: chunks whose partial results
// are merged are fixed by the problem size alone (ChunkCount), never by the number of threads.
//
// Under ThreadSanitizer the loops run on std::thread instead of TBB: Debian's libtbb is not
// instrumented, so TSan cannot see its synchronisation and would report every hand-over between
// its workers as a race. The std::thread path has the same contract (disjoint ranges of `grain`
// items, exceptions re-thrown on the calling thread), so TSan checks the loop bodies, which are
// ours.

#if defined(__SANITIZE_THREAD__)
#define LASERCELL_THREAD_SANITIZER 1
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define LASERCELL_THREAD_SANITIZER 1
#endif
#endif

#if defined(LASERCELL_THREAD_SANITIZER)
#include <atomic>
#include <exception>
#include <map>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>
#else
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#endif

#include <algorithm>
#include <cstddef>
#include <functional>
#include <utility>

namespace lasercell {

/// Number of fixed-size chunks covering n items; use with ParallelForChunks over chunk indices
/// when partial sums must be merged in a fixed order (deterministic reductions).
inline std::size_t ChunkCount(std::size_t n, std::size_t chunk) { return (n + chunk - 1) / chunk; }

#if defined(LASERCELL_THREAD_SANITIZER)
namespace detail {
/// The ThreadSanitizer build's loop: `threads` workers (the caller is one of them) take chunks
/// of `grain` items in turn from a shared counter; the first exception stops the loop and is
/// re-thrown here once every worker has joined.
template <typename Body>
void ParallelForOnStdThreads(int threads, std::size_t n, std::size_t grain, const Body& body) {
  const std::size_t chunks = ChunkCount(n, grain);
  const std::size_t hardware = std::max(1u, std::thread::hardware_concurrency());
  const std::size_t workers =
      std::min(chunks, threads <= 0 ? hardware : static_cast<std::size_t>(threads));
  std::atomic<std::size_t> next{0};
  std::atomic<bool> failed{false};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto work = [&] {
    for (std::size_t c = next++; c < chunks && !failed; c = next++) {
      try {
        body(c * grain, std::min(n, (c + 1) * grain));
      } catch (...) {
        const std::lock_guard<std::mutex> lock(error_mutex);
        if (!error) error = std::current_exception();
        failed = true;
      }
    }
  };
  std::vector<std::thread> pool;
  for (std::size_t w = 1; w < workers; ++w) pool.emplace_back(work);
  work();
  for (std::thread& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}
}  // namespace detail
#endif

/// Calls body(begin, end) on disjoint ranges that together cover [0, n) once; a range is not
/// split below `grain` items, but the scheduler may hand out larger ones, so a body must not
/// depend on where the ranges start. `threads` <= 0 uses every core, 1 runs [0, n) inline on the
/// calling thread (no TBB at all).
template <typename Body>
void ParallelForChunks(int threads, std::size_t n, std::size_t grain, const Body& body) {
  if (n == 0) return;
  grain = std::max<std::size_t>(grain, 1);
  if (threads == 1 || n <= grain) {
    body(std::size_t{0}, n);
    return;
  }
#if defined(LASERCELL_THREAD_SANITIZER)
  detail::ParallelForOnStdThreads(threads, n, grain, body);
#else
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
#endif
}

/// One T per worker thread, made by `factory` on a thread's first local(): scratch space (vote
/// accumulators, search buffers) that loop bodies reuse across the chunks they run. Results must
/// not live here, since which chunks share a worker depends on the scheduling.
template <typename T>
class WorkerLocal {
 public:
  template <typename Factory>
  explicit WorkerLocal(Factory factory) : slots_(std::move(factory)) {}
#if defined(LASERCELL_THREAD_SANITIZER)
  T& local() {
    const std::lock_guard<std::mutex> lock(mutex_);
    std::unique_ptr<T>& slot = mine_[std::this_thread::get_id()];
    if (!slot) slot = std::make_unique<T>(slots_());
    return *slot;
  }

 private:
  std::function<T()> slots_;
  std::mutex mutex_;
  std::map<std::thread::id, std::unique_ptr<T>> mine_;
#else
  T& local() { return slots_.local(); }

 private:
  tbb::enumerable_thread_specific<T> slots_;
#endif
};

}  // namespace lasercell
