#pragma once
// The handling robot's protocol (lasercell serve): the robot is the TCP client and asks, the
// server answers one grasp per reply. Two encodings on one port, told apart by the first bytes
// a client sends:
//
// Binary: fixed-size frames of big-endian int32 (what robot controllers read most easily).
//   Request, 12 x int32 = 48 bytes:
//     [0] magic 0x4C435251 ("LCRQ")   [1] version 1   [2] command (1 LOOK, 2 NEXT, 3 PING)
//     [3] request id (echoed)         [4..6] flange x y z, um   [7..9] rx ry rz, millidegrees
//     [10] 1 when [4..9] hold the robot's current flange pose, else 0   [11] 0 (reserved)
//   Reply, 16 x int32 = 64 bytes:
//     [0] magic 0x4C435253 ("LCRS")   [1] version 1   [2] status (ReplyStatus)
//     [3] request id                  [4] part index in the job (-1 none)   [5] instance (1..)
//     [6..8] grasp x y z in the job's target frame (handling_base), um
//     [9..11] rx ry rz, millidegrees  [12] instances left after this one
//     [13] grasp position 1-sigma, um [14] ms from taking the sweep to this reply, x1000 (us)
//     [15] 0 (reserved)
// ASCII: one line per request and reply, '\n' terminated, at most 200 bytes:
//     LOOK [x y z rx ry rz]  |  NEXT  |  PING             (mm, degrees)
//     <STATUS> <request#> <part index> <part> <instance> <x> <y> <z> <rx> <ry> <rz> <left>
//     <sigma_mm> <ms>
//   with STATUS the lower-case status name (ok, no_part, ...), part "-" when there is none
//   (index -1), request# counting the connection's requests from 1.
// Angles: R = Rz(rz) * Ry(ry) * Rx(rx) (fixed axes, x first; Fanuc w p r, KUKA C B A).

#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace lasercell::localize {

/// Request bytes of the binary encoding.
inline constexpr std::size_t kRobotRequestBytes = 48;
/// Reply bytes of the binary encoding.
inline constexpr std::size_t kRobotReplyBytes = 64;
/// Longest ASCII line accepted or written, with its '\n'.
inline constexpr std::size_t kRobotMaxLineBytes = 200;
inline constexpr std::uint32_t kRobotRequestMagic = 0x4C435251;  // "LCRQ"
inline constexpr std::uint32_t kRobotReplyMagic = 0x4C435253;    // "LCRS"
inline constexpr std::int32_t kRobotProtocolVersion = 1;

/// What the robot asks.
enum class RobotCommand : std::int32_t {
  kLook = 1,  ///< Take the next sweep, localize, reply with the first graspable instance.
  kNext = 2,  ///< The next instance of the last LOOK.
  kPing = 3,  ///< Heartbeat: replies kAlive.
};

/// How a request ended. Every failure is a status, never a dropped connection.
enum class ReplyStatus : std::int32_t {
  kOk = 0,          ///< A grasp is in the reply.
  kNoPart = 1,      ///< The sweep was localized; no graspable instance in it.
  kNoMore = 2,      ///< NEXT after the last instance (or before any LOOK).
  kNoSweep = 3,     ///< The source delivered no sweep in time.
  kBadRequest = 4,  ///< Unknown command, wrong magic or version, malformed line.
  kFailed = 5,      ///< The job failed on this sweep (the server's log says why).
  kAlive = 6,       ///< Reply to PING.
  kBusy = 7,        ///< Too many clients; the connection closes after this reply.
};
/// "ok", "no_part", "no_more", "no_sweep", "bad_request", "failed", "alive", "busy".
const char* ReplyStatusName(ReplyStatus status);

/// A decoded request.
struct RobotRequest {
  RobotCommand command = RobotCommand::kPing;
  std::int32_t request_id = 0;
  /// The robot's flange pose when it sent one (informational: logged with the cycle).
  std::optional<Eigen::Isometry3d> base_from_flange;
};

/// A reply.
struct RobotReply {
  ReplyStatus status = ReplyStatus::kNoPart;
  std::int32_t request_id = 0;
  std::int32_t part_index = -1;
  std::string part;  ///< Part name (ASCII encoding only: binary frames carry the index), "".
  std::int32_t instance = 0;
  Eigen::Isometry3d target_from_grasp = Eigen::Isometry3d::Identity();
  std::int32_t instances_left = 0;
  double position_sigma_mm = 0.0;
  double latency_ms = 0.0;  ///< From taking the sweep to this reply.
};

/// Result of decoding: the request, or why the bytes are not one.
struct RobotDecode {
  std::optional<RobotRequest> request;
  std::string error;  ///< Set when request is empty.
};

/// Decodes one binary request frame (exactly kRobotRequestBytes).
RobotDecode DecodeBinaryRequest(std::string_view frame);
/// Decodes one ASCII request line (without its '\n'; a trailing '\r' is ignored).
RobotDecode DecodeAsciiRequest(std::string_view line);
/// Encodes a binary request (the robot side: tests and `lasercell robot-client`).
std::string EncodeBinaryRequest(const RobotRequest& request);
/// Encodes an ASCII request line with its '\n'.
std::string EncodeAsciiRequest(const RobotRequest& request);
/// Encodes a binary reply; values beyond int32 (a pose more than 2 km away) are clamped.
std::string EncodeBinaryReply(const RobotReply& reply);
/// Encodes an ASCII reply line with its '\n'.
std::string EncodeAsciiReply(const RobotReply& reply);
/// A reply for people: the status name and, for an ok reply, "part 0 seat instance 1  x y z ..
/// mm  rx ry rz .. deg  sigma .. mm  0 left" (fixed-axis XYZ angles, as `robot-client` prints).
std::string ReplyText(const RobotReply& reply);
/// Decodes a binary reply (the robot side); nullopt when the frame is not one.
std::optional<RobotReply> DecodeBinaryReply(std::string_view frame);
/// Decodes an ASCII reply line (the robot side); nullopt when the line is not one.
std::optional<RobotReply> DecodeAsciiReply(std::string_view line);

}  // namespace lasercell::localize
