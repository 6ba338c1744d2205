#pragma once
// Runs work that lasercell does not own end to end — a third-party reader given a damaged
// file — in a child process, so that a crash inside it becomes an error message instead of
// ending the program. OpenCASCADE's STEP/IGES translators dereference entities a damaged file
// leaves out (a face list naming a missing face: SIGSEGV inside libTKIGES); that is the use.
//
// The child is a fork of the caller: `work` sees the caller's memory as it was at the call and
// sends its result back as bytes. Nothing it changes reaches the caller. Costs one fork (about
// a millisecond); not for tight loops.
//
// In the child a memory fault (SIGSEGV, SIGBUS, SIGFPE, SIGILL) is not caught by handlers the
// caller installed (a sanitizer's, a fuzzer's): it ends the child, and the caller decides what
// it means. A sanitizer's report on an error it detects itself still ends in abort().
//
// Thread safety: fork copies only the calling thread. `work` must not need a lock another
// thread may hold at the call (the caller takes the locks `work` needs before calling), and must
// not use a thread pool started before the call.

#include <functional>
#include <string>

namespace lasercell {

/// How an isolated call ended.
struct IsolatedOutcome {
  enum class Kind {
    kReturned,    ///< `work` returned; `bytes` holds its result.
    kInputError,  ///< `work` threw InputError; `message` holds what().
    kOtherError,  ///< `work` threw anything else; `message` holds what() when it had one.
    kCrashed,     ///< The child ended by a signal (`signal`) or exited without a result.
    kTimedOut,    ///< The child ran longer than the timeout and was killed.
  };
  Kind kind = Kind::kCrashed;
  std::string bytes;    ///< kReturned: what `work` returned.
  std::string message;  ///< kInputError / kOtherError: the exception's message.
  int signal = 0;       ///< kCrashed by a signal: its number (SIGSEGV = 11), else 0.
};

/// True for the signals of a memory or arithmetic fault (SIGSEGV, SIGBUS, SIGFPE, SIGILL).
bool IsFaultSignal(int signal);

/// Runs `work` in a forked child and reports how it ended; a child still running after
/// `timeout_s` seconds (> 0) is killed (SIGKILL). Throws InternalError when the child cannot be
/// started (pipe or fork failed).
IsolatedOutcome RunIsolated(const std::function<std::string()>& work, double timeout_s);

}  // namespace lasercell
