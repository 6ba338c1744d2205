#include "localize/robot_client.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>

#include "core/error.hpp"
#include "core/net_address.hpp"

namespace lasercell::localize {

RobotClient::RobotClient(const std::string& host_port, bool ascii, double timeout_ms)
    : ascii_(ascii), address_(host_port) {
  const sockaddr_in addr = net::ResolveHostPort(host_port, "pose server address");
  fd_ = socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw InputError("cannot open a TCP socket to " + host_port);
  const int rc = connect(fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof addr);
  pollfd p{fd_, POLLOUT, 0};
  int error = rc == 0 ? 0 : errno;
  if (rc != 0 && errno == EINPROGRESS) {
    error = ETIMEDOUT;
    if (poll(&p, 1, static_cast<int>(timeout_ms)) == 1) {
      socklen_t len = sizeof error;
      getsockopt(fd_, SOL_SOCKET, SO_ERROR, &error, &len);
    }
  }
  if (error != 0) {
    close(fd_);
    throw InputError("cannot connect to pose server " + host_port + ": " + std::strerror(error));
  }
  const int on = 1;
  setsockopt(fd_, IPPROTO_TCP, TCP_NODELAY, &on, sizeof on);
}

RobotClient::~RobotClient() {
  if (fd_ >= 0) close(fd_);
}

void RobotClient::SendRaw(const std::string& bytes) {
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = send(fd_, bytes.data() + done, bytes.size() - done, MSG_NOSIGNAL);
    if (n > 0) {
      done += static_cast<std::size_t>(n);
      continue;
    }
    if (n < 0 && (errno == EAGAIN || errno == EINTR)) {
      pollfd p{fd_, POLLOUT, 0};
      poll(&p, 1, 100);
      continue;
    }
    throw InputError("pose server " + address_ + " closed the connection");
  }
}

std::string RobotClient::ReadReply(double timeout_ms) {
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::microseconds(static_cast<long>(timeout_ms * 1e3));
  for (;;) {
    if (ascii_) {
      const auto end = pending_.find('\n');
      if (end != std::string::npos) {
        std::string line = pending_.substr(0, end + 1);
        pending_.erase(0, end + 1);
        return line;
      }
    } else if (pending_.size() >= kRobotReplyBytes) {
      std::string frame = pending_.substr(0, kRobotReplyBytes);
      pending_.erase(0, kRobotReplyBytes);
      return frame;
    }
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
                          deadline - std::chrono::steady_clock::now())
                          .count();
    pollfd p{fd_, POLLIN, 0};
    if (left <= 0 || poll(&p, 1, static_cast<int>(left)) != 1) {
      throw InputError("pose server " + address_ + " did not answer within " +
                       std::to_string(static_cast<int>(timeout_ms)) + " ms");
    }
    char buffer[1024];
    const ssize_t n = recv(fd_, buffer, sizeof buffer, 0);
    if (n == 0 || (n < 0 && errno != EAGAIN && errno != EINTR)) {
      throw InputError("pose server " + address_ + " closed the connection");
    }
    if (n > 0) pending_.append(buffer, static_cast<std::size_t>(n));
  }
}

RobotReply RobotClient::Request(const RobotRequest& request, double timeout_ms) {
  SendRaw(ascii_ ? EncodeAsciiRequest(request) : EncodeBinaryRequest(request));
  const std::string bytes = ReadReply(timeout_ms);
  const std::optional<RobotReply> reply =
      ascii_ ? DecodeAsciiReply(bytes) : DecodeBinaryReply(bytes);
  if (!reply) throw InputError("pose server " + address_ + " sent a reply that does not decode");
  return *reply;
}

}  // namespace lasercell::localize
