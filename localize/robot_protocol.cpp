#include "localize/robot_protocol.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <vector>

#include "core/io/byte_order.hpp"
#include "core/se3.hpp"

namespace lasercell::localize {

namespace {

using io::GetBe;
using io::PutBe;

std::int32_t Fixed(double value, double scale) {
  const double v = std::round(value * scale);
  return static_cast<std::int32_t>(std::clamp(v, -2147483647.0, 2147483647.0));
}

// Pose -> x y z (unit 1/scale_mm mm), rx ry rz (unit 1/scale_deg degrees).
std::array<std::int32_t, 6> PoseInts(const Eigen::Isometry3d& pose) {
  const Eigen::Vector3d t = pose.translation();
  const Eigen::Vector3d r = FixedXyzDegFromRotation(pose.linear());
  return {Fixed(t.x(), 1000), Fixed(t.y(), 1000), Fixed(t.z(), 1000),
          Fixed(r.x(), 1000), Fixed(r.y(), 1000), Fixed(r.z(), 1000)};
}

Eigen::Isometry3d PoseFromValues(const double* v) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
  pose.linear() = RotationFromFixedXyzDeg(Eigen::Vector3d(v[3], v[4], v[5]));
  return pose;
}

// A part name in an ASCII reply: at most this many printable, non-space ASCII bytes.
constexpr std::size_t kMaxAsciiPartName = 48;
// Largest magnitude of a number in an ASCII reply (mm, ms); the encoder clamps to it.
constexpr double kMaxAsciiValue = 1e9;
bool IsNameByte(char c) { return c > ' ' && c <= '~'; }

std::vector<std::string_view> Tokens(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < line.size() && out.size() < 32) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    const std::size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
    if (i > start) out.push_back(line.substr(start, i - start));
  }
  return out;
}

bool ParseDouble(std::string_view token, double* value) {
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), *value);
  return ec == std::errc() && end == token.data() + token.size() && std::isfinite(*value);
}

bool ParseInt(std::string_view token, std::int32_t* value) {
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), *value);
  return ec == std::errc() && end == token.data() + token.size();
}

RobotDecode Fail(std::string error) { return {std::nullopt, std::move(error)}; }

std::optional<RobotCommand> CommandNamed(std::string_view name) {
  if (name == "LOOK") return RobotCommand::kLook;
  if (name == "NEXT") return RobotCommand::kNext;
  if (name == "PING") return RobotCommand::kPing;
  return std::nullopt;
}

const char* CommandName(RobotCommand command) {
  switch (command) {
    case RobotCommand::kLook:
      return "LOOK";
    case RobotCommand::kNext:
      return "NEXT";
    case RobotCommand::kPing:
      return "PING";
  }
  return "PING";
}

}  // namespace

const char* ReplyStatusName(ReplyStatus status) {
  switch (status) {
    case ReplyStatus::kOk:
      return "ok";
    case ReplyStatus::kNoPart:
      return "no_part";
    case ReplyStatus::kNoMore:
      return "no_more";
    case ReplyStatus::kNoSweep:
      return "no_sweep";
    case ReplyStatus::kBadRequest:
      return "bad_request";
    case ReplyStatus::kFailed:
      return "failed";
    case ReplyStatus::kAlive:
      return "alive";
    case ReplyStatus::kBusy:
      return "busy";
  }
  return "failed";
}

RobotDecode DecodeBinaryRequest(std::string_view frame) {
  if (frame.size() != kRobotRequestBytes) return Fail("a request frame is 48 bytes");
  std::int32_t v[12];
  for (int i = 0; i < 12; ++i) v[i] = GetBe<std::int32_t>(frame.data() + 4 * i);
  if (static_cast<std::uint32_t>(v[0]) != kRobotRequestMagic) return Fail("wrong magic");
  if (v[1] != kRobotProtocolVersion) return Fail("unknown version " + std::to_string(v[1]));
  if (v[2] < 1 || v[2] > 3) return Fail("unknown command " + std::to_string(v[2]));
  if (v[10] != 0 && v[10] != 1) return Fail("pose flag must be 0 or 1");
  RobotRequest request;
  request.command = static_cast<RobotCommand>(v[2]);
  request.request_id = v[3];
  if (v[10] == 1) {
    double values[6];
    for (int i = 0; i < 6; ++i) values[i] = v[4 + i] / 1000.0;
    request.base_from_flange = PoseFromValues(values);
  }
  return {request, ""};
}

RobotDecode DecodeAsciiRequest(std::string_view line) {
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  if (line.size() >= kRobotMaxLineBytes) return Fail("line longer than 200 bytes");
  const std::vector<std::string_view> t = Tokens(line);
  if (t.empty()) return Fail("empty line");
  const auto command = CommandNamed(t[0]);
  if (!command) return Fail("unknown command (LOOK, NEXT or PING)");
  RobotRequest request;
  request.command = *command;
  if (t.size() == 1) return {request, ""};
  if (*command != RobotCommand::kLook || t.size() != 7) {
    return Fail("LOOK takes no values or six (x y z mm, rx ry rz degrees); NEXT and PING none");
  }
  double values[6];
  for (int i = 0; i < 6; ++i) {
    if (!ParseDouble(t[1 + i], &values[i])) return Fail("pose value is not a finite number");
    if (std::abs(values[i]) > kMaxAsciiValue) {
      return Fail("pose value beyond +-1e9 (mm or degrees)");
    }
  }
  request.base_from_flange = PoseFromValues(values);
  return {request, ""};
}

std::string EncodeBinaryRequest(const RobotRequest& request) {
  std::string out;
  PutBe<std::uint32_t>(&out, kRobotRequestMagic);
  PutBe<std::int32_t>(&out, kRobotProtocolVersion);
  PutBe<std::int32_t>(&out, static_cast<std::int32_t>(request.command));
  PutBe<std::int32_t>(&out, request.request_id);
  const std::array<std::int32_t, 6> pose = request.base_from_flange
                                               ? PoseInts(*request.base_from_flange)
                                               : std::array<std::int32_t, 6>{};
  for (std::int32_t v : pose) PutBe<std::int32_t>(&out, v);
  PutBe<std::int32_t>(&out, request.base_from_flange ? 1 : 0);
  PutBe<std::int32_t>(&out, 0);
  return out;
}

std::string EncodeAsciiRequest(const RobotRequest& request) {
  std::string out = CommandName(request.command);
  if (request.command == RobotCommand::kLook && request.base_from_flange) {
    const Eigen::Vector3d t = request.base_from_flange->translation();
    const Eigen::Vector3d r = FixedXyzDegFromRotation(request.base_from_flange->linear());
    char buffer[160];
    std::snprintf(buffer, sizeof buffer, " %.3f %.3f %.3f %.3f %.3f %.3f", t.x(), t.y(), t.z(),
                  r.x(), r.y(), r.z());
    out += buffer;
  }
  return out + "\n";
}

std::string EncodeBinaryReply(const RobotReply& reply) {
  std::string out;
  PutBe<std::uint32_t>(&out, kRobotReplyMagic);
  PutBe<std::int32_t>(&out, kRobotProtocolVersion);
  PutBe<std::int32_t>(&out, static_cast<std::int32_t>(reply.status));
  PutBe<std::int32_t>(&out, reply.request_id);
  PutBe<std::int32_t>(&out, reply.part_index);
  PutBe<std::int32_t>(&out, reply.instance);
  const bool pose = reply.status == ReplyStatus::kOk;
  const std::array<std::int32_t, 6> values =
      pose ? PoseInts(reply.target_from_grasp) : std::array<std::int32_t, 6>{};
  for (std::int32_t v : values) PutBe<std::int32_t>(&out, v);
  PutBe<std::int32_t>(&out, reply.instances_left);
  PutBe<std::int32_t>(&out, Fixed(reply.position_sigma_mm, 1000));
  PutBe<std::int32_t>(&out, Fixed(reply.latency_ms, 1000));
  PutBe<std::int32_t>(&out, 0);
  return out;
}

std::string EncodeAsciiReply(const RobotReply& reply) {
  const bool pose = reply.status == ReplyStatus::kOk;
  Eigen::Vector3d t = Eigen::Vector3d::Zero(), r = Eigen::Vector3d::Zero();
  if (pose) {
    t = reply.target_from_grasp.translation();
    r = FixedXyzDegFromRotation(reply.target_from_grasp.linear());
  }
  std::string part = reply.part.empty() ? "-" : reply.part.substr(0, kMaxAsciiPartName);
  std::replace_if(
      part.begin(), part.end(), [](char c) { return !IsNameByte(c); }, '_');
  char buffer[kRobotMaxLineBytes];
  std::snprintf(buffer, sizeof buffer,
                "%s %d %d %s %d %.3f %.3f %.3f %.3f %.3f %.3f %d %.3f %.3f\n",
                ReplyStatusName(reply.status), reply.request_id, reply.part_index, part.c_str(),
                reply.instance, std::clamp(t.x(), -kMaxAsciiValue, kMaxAsciiValue),
                std::clamp(t.y(), -kMaxAsciiValue, kMaxAsciiValue),
                std::clamp(t.z(), -kMaxAsciiValue, kMaxAsciiValue), r.x(), r.y(), r.z(),
                reply.instances_left, std::clamp(reply.position_sigma_mm, 0.0, kMaxAsciiValue),
                std::clamp(reply.latency_ms, 0.0, kMaxAsciiValue));
  return buffer;
}

std::optional<RobotReply> DecodeBinaryReply(std::string_view frame) {
  if (frame.size() != kRobotReplyBytes) return std::nullopt;
  std::int32_t v[16];
  for (int i = 0; i < 16; ++i) v[i] = GetBe<std::int32_t>(frame.data() + 4 * i);
  if (static_cast<std::uint32_t>(v[0]) != kRobotReplyMagic || v[1] != kRobotProtocolVersion ||
      v[2] < 0 || v[2] > 7) {
    return std::nullopt;
  }
  RobotReply reply;
  reply.status = static_cast<ReplyStatus>(v[2]);
  reply.request_id = v[3];
  reply.part_index = v[4];
  reply.instance = v[5];
  // Only an ok reply carries a pose (the encoder writes zeros otherwise).
  if (reply.status == ReplyStatus::kOk) {
    double values[6];
    for (int i = 0; i < 6; ++i) values[i] = v[6 + i] / 1000.0;
    reply.target_from_grasp = PoseFromValues(values);
  }
  reply.instances_left = v[12];
  reply.position_sigma_mm = v[13] / 1000.0;
  reply.latency_ms = v[14] / 1000.0;
  return reply;
}

std::optional<RobotReply> DecodeAsciiReply(std::string_view line) {
  if (!line.empty() && line.back() == '\n') line.remove_suffix(1);
  const std::vector<std::string_view> t = Tokens(line);
  if (t.size() != 14) return std::nullopt;
  RobotReply reply;
  bool known = false;
  for (std::int32_t s = 0; s <= 7; ++s) {
    if (t[0] == ReplyStatusName(static_cast<ReplyStatus>(s))) {
      reply.status = static_cast<ReplyStatus>(s);
      known = true;
    }
  }
  double values[6];
  if (!known || !ParseInt(t[1], &reply.request_id) || !ParseInt(t[2], &reply.part_index) ||
      !ParseInt(t[4], &reply.instance) || !ParseInt(t[11], &reply.instances_left) ||
      !ParseDouble(t[12], &reply.position_sigma_mm) || !ParseDouble(t[13], &reply.latency_ms)) {
    return std::nullopt;
  }
  for (int i = 0; i < 6; ++i) {
    if (!ParseDouble(t[5 + i], &values[i])) return std::nullopt;
  }
  // The ranges the encoder writes (it clamps to them): anything beyond is not a reply.
  const auto within = [](double v) { return std::abs(v) <= kMaxAsciiValue; };
  if (!std::all_of(values, values + 6, within) || !(reply.position_sigma_mm >= 0) ||
      !within(reply.position_sigma_mm) || !(reply.latency_ms >= 0) || !within(reply.latency_ms)) {
    return std::nullopt;
  }
  if (t[3].size() > kMaxAsciiPartName ||
      !std::all_of(t[3].begin(), t[3].end(), [](char c) { return IsNameByte(c); })) {
    return std::nullopt;
  }
  reply.part = t[3] == "-" ? "" : std::string(t[3]);
  if (reply.status == ReplyStatus::kOk) reply.target_from_grasp = PoseFromValues(values);
  return reply;
}

std::string ReplyText(const RobotReply& reply) {
  std::string text = ReplyStatusName(reply.status);
  if (reply.status != ReplyStatus::kOk) return text;
  const Eigen::Vector3d t = reply.target_from_grasp.translation();
  const Eigen::Vector3d a = FixedXyzDegFromRotation(reply.target_from_grasp.linear());
  char buffer[400];
  std::snprintf(buffer, sizeof buffer,
                " part %d%s%s instance %d  x y z %.3f %.3f %.3f mm  rx ry rz %.3f %.3f %.3f deg"
                "  sigma %.3f mm  %d left",
                reply.part_index, reply.part.empty() ? "" : " ", reply.part.c_str(), reply.instance,
                t.x(), t.y(), t.z(), a.x(), a.y(), a.z(), reply.position_sigma_mm,
                reply.instances_left);
  return text + buffer;
}

}  // namespace lasercell::localize
