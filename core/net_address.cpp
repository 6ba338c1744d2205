#include "core/net_address.hpp"

#include <arpa/inet.h>
#include <netdb.h>
#include <sys/socket.h>

#include "core/error.hpp"

namespace lasercell::net {

std::pair<std::string, std::uint16_t> ParseHostPort(const std::string& text,
                                                    const std::string& what) {
  const auto colon = text.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 >= text.size()) {
    throw InputError(what + " '" + text + "' is not HOST:PORT (e.g. 127.0.0.1:5000)");
  }
  const std::string port_text = text.substr(colon + 1);
  unsigned long port = 0;
  for (char c : port_text) {
    if (c < '0' || c > '9' || port > 65535) {
      throw InputError(what + " '" + text + "': port '" + port_text +
                       "' is not a number in 1..65535");
    }
    port = port * 10 + static_cast<unsigned long>(c - '0');
  }
  if (port == 0 || port > 65535) {
    throw InputError(what + " '" + text + "': port must be in 1..65535");
  }
  return {text.substr(0, colon), static_cast<std::uint16_t>(port)};
}

sockaddr_in ResolveHostPort(const std::string& text, const std::string& what) {
  const auto [host, port] = ParseHostPort(text, what);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(port);
  if (inet_pton(AF_INET, host.c_str(), &addr.sin_addr) == 1) return addr;
  addrinfo hints{};
  hints.ai_family = AF_INET;
  addrinfo* found = nullptr;
  const int rc = getaddrinfo(host.c_str(), nullptr, &hints, &found);
  if (rc != 0 || found == nullptr) {
    throw InputError(what + " '" + text + "': cannot resolve host '" + host + "' (" +
                     gai_strerror(rc) + "); give an IPv4 address such as 127.0.0.1");
  }
  addr.sin_addr = reinterpret_cast<const sockaddr_in*>(found->ai_addr)->sin_addr;
  freeaddrinfo(found);
  return addr;
}

sockaddr_in ListenAddress(const std::string& address, std::uint16_t port, const std::string& what) {
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(port);
  if (inet_pton(AF_INET, address.c_str(), &addr.sin_addr) != 1) {
    throw InputError(what + " '" + address +
                     "' is not an IPv4 address (e.g. 0.0.0.0 for every interface)");
  }
  return addr;
}

}  // namespace lasercell::net
