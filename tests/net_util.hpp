#pragma once
// Loopback helpers for the tests that start servers as processes (127.0.0.1 only).

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

namespace lasercell::test {

/// A port on 127.0.0.1 that was free a moment ago for `type` (SOCK_DGRAM or SOCK_STREAM); a
/// process started right after can bind it (the kernel hands ephemeral ports out in turn).
inline int FreeLoopbackPort(int type) {
  const int fd = socket(AF_INET, type, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr);
  socklen_t len = sizeof addr;
  getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len);
  close(fd);
  return ntohs(addr.sin_port);
}

}  // namespace lasercell::test
