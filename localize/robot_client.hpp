#pragma once
// The robot's side of the robot protocol (robot_protocol.hpp): a blocking TCP client for tests,
// `lasercell robot-client` and as a reference for robot programmers. Every call has a timeout.

#include <string>

#include "localize/robot_protocol.hpp"

namespace lasercell::localize {

/// A connection to a pose server.
class RobotClient {
 public:
  /// Connects to "HOST:PORT" within `timeout_ms`. `ascii` chooses the line encoding. Throws
  /// InputError naming the address when it cannot connect.
  RobotClient(const std::string& host_port, bool ascii, double timeout_ms = 5000.0);
  ~RobotClient();
  RobotClient(const RobotClient&) = delete;
  RobotClient& operator=(const RobotClient&) = delete;

  /// Sends a request and waits up to `timeout_ms` for its reply. Throws InputError when the
  /// server closes the connection, does not answer in time or answers something undecodable.
  RobotReply Request(const RobotRequest& request, double timeout_ms = 30000.0);
  /// Sends raw bytes (tests: garbage, half frames).
  void SendRaw(const std::string& bytes);

 private:
  std::string ReadReply(double timeout_ms);
  int fd_ = -1;
  bool ascii_ = false;
  std::string address_;
  std::string pending_;
};

}  // namespace lasercell::localize
