#include "core/isolated_call.hpp"

#include <poll.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <exception>

#include "core/error.hpp"

namespace lasercell {
namespace {

// The child's reply: one tag byte, then the bytes or the message.
constexpr char kReturned = 'R';
constexpr char kInputError = 'I';
constexpr char kOtherError = 'O';

bool WriteAll(int fd, const char* data, std::size_t size) {
  while (size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    data += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

[[noreturn]] void ChildReply(int fd, char tag, const std::string& payload) {
  const bool ok = WriteAll(fd, &tag, 1) && WriteAll(fd, payload.data(), payload.size());
  // _exit: no atexit handlers, static destructors or leak check of the copied parent state.
  ::_exit(ok ? 0 : 3);
}

[[noreturn]] void RunChild(int fd, const std::function<std::string()>& work) {
  // A fault in `work` ends the child by its signal, which the parent reports; handlers the
  // caller installed (a sanitizer's, a fuzzer's) would instead report it as the caller's crash.
  for (const int fault : {SIGSEGV, SIGBUS, SIGFPE, SIGILL}) std::signal(fault, SIG_DFL);
  try {
    ChildReply(fd, kReturned, work());
  } catch (const InputError& e) {
    ChildReply(fd, kInputError, e.what());
  } catch (const std::exception& e) {
    ChildReply(fd, kOtherError, e.what());
  } catch (...) {
    ChildReply(fd, kOtherError, "an exception that is not a std::exception");
  }
}

}  // namespace

bool IsFaultSignal(int signal) {
  return signal == SIGSEGV || signal == SIGBUS || signal == SIGFPE || signal == SIGILL;
}

IsolatedOutcome RunIsolated(const std::function<std::string()>& work, double timeout_s) {
  LASERCELL_CHECK(timeout_s > 0, "RunIsolated: the timeout must be positive");
  int fds[2];
  if (::pipe(fds) != 0) {
    throw InternalError(std::string("RunIsolated: pipe failed: ") + std::strerror(errno));
  }
  const pid_t pid = ::fork();
  if (pid < 0) {
    const int error = errno;
    ::close(fds[0]);
    ::close(fds[1]);
    throw InternalError(std::string("RunIsolated: fork failed: ") + std::strerror(error));
  }
  if (pid == 0) {
    ::close(fds[0]);
    RunChild(fds[1], work);
  }
  ::close(fds[1]);
  std::string reply;
  char buffer[65536];
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  bool timed_out = false;
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) {
      timed_out = true;
      break;
    }
    pollfd p{fds[0], POLLIN, 0};
    const int ready = ::poll(&p, 1, static_cast<int>(std::min<long long>(left.count(), 1000)));
    if (ready < 0 && errno == EINTR) continue;
    if (ready <= 0) continue;
    const ssize_t n = ::read(fds[0], buffer, sizeof(buffer));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    reply.append(buffer, static_cast<std::size_t>(n));
  }
  ::close(fds[0]);
  if (timed_out) ::kill(pid, SIGKILL);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  IsolatedOutcome outcome;
  if (timed_out) {
    outcome.kind = IsolatedOutcome::Kind::kTimedOut;
    return outcome;
  }
  if (WIFSIGNALED(status)) {
    outcome.signal = WTERMSIG(status);
    return outcome;
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || reply.empty()) return outcome;
  const char tag = reply[0];
  reply.erase(0, 1);
  if (tag == kReturned) {
    outcome.kind = IsolatedOutcome::Kind::kReturned;
    outcome.bytes = std::move(reply);
  } else if (tag == kInputError) {
    outcome.kind = IsolatedOutcome::Kind::kInputError;
    outcome.message = std::move(reply);
  } else if (tag == kOtherError) {
    outcome.kind = IsolatedOutcome::Kind::kOtherError;
    outcome.message = std::move(reply);
  }
  return outcome;
}

}  // namespace lasercell
