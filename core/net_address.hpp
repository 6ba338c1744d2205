#pragma once
// IPv4 socket addresses from what users type: "HOST:PORT" for destinations (a dotted address or
// a name the resolver knows) and dotted addresses for the interface a server listens on. Used by
// the UDP profile stream (triangulation/udp_stream) and the robot protocol's server and client
// (localize/pose_server, robot_client).

#include <netinet/in.h>

#include <cstdint>
#include <string>
#include <utility>

namespace lasercell::net {

/// Splits "HOST:PORT"; throws InputError naming `what` when it is not that or the port is not
/// in 1..65535.
std::pair<std::string, std::uint16_t> ParseHostPort(const std::string& text,
                                                    const std::string& what);
/// The address of "HOST:PORT", resolving a name when it is not a dotted address; throws
/// InputError naming `what`.
sockaddr_in ResolveHostPort(const std::string& text, const std::string& what);
/// The address to listen on: `address` must be dotted IPv4 (0.0.0.0 = every interface); throws
/// InputError naming `what`.
sockaddr_in ListenAddress(const std::string& address, std::uint16_t port, const std::string& what);

}  // namespace lasercell::net
