#include "tests/triangulation/gige_test_device.hpp"

#include <arpa/inet.h>
#include <arv.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <mutex>
#include <random>
#include <stdexcept>
#include <thread>
#include <utility>

#include "core/io/byte_order.hpp"

namespace lasercell::testing {
namespace {

using Clock = std::chrono::steady_clock;
using Bytes = std::string;  // built with core/io/byte_order.hpp

constexpr std::uint16_t kGvcpPort = 3956;
constexpr int kPollMs = 20;
constexpr std::size_t kRetainedFrames = 64;

// GVCP (all fields big-endian).
constexpr std::size_t kGvcpHeaderBytes = 8;
constexpr std::uint8_t kGvcpCommandKey = 0x42;
constexpr std::uint8_t kGvcpFlagAckRequired = 0x01;
constexpr std::uint8_t kGvcpFlagExtendedIds = 0x10;
constexpr std::uint16_t kDiscoveryCmd = 0x0002;
constexpr std::uint16_t kPacketResendCmd = 0x0040;
constexpr std::uint16_t kReadRegCmd = 0x0080;
constexpr std::uint16_t kWriteRegCmd = 0x0082;
constexpr std::uint16_t kReadMemCmd = 0x0084;
constexpr std::uint16_t kWriteMemCmd = 0x0086;
constexpr std::uint16_t kStatusNotImplemented = 0x8001;
constexpr std::uint16_t kStatusInvalidParameter = 0x8002;
constexpr std::uint16_t kStatusInvalidAddress = 0x8003;
constexpr std::uint16_t kStatusWriteProtect = 0x8004;
constexpr std::uint16_t kStatusBadAlignment = 0x8005;
constexpr std::size_t kDiscoveryBytes = 0xf8;
constexpr std::size_t kReadMemMaxBytes = 536;

// GigE Vision bootstrap registers; the fake camera's own come from <arvfakecamera.h>.
constexpr std::uint32_t kRegGvcpCapability = 0x0934;
constexpr std::uint32_t kCapWriteMemory = 1u << 1;
constexpr std::uint32_t kCapPacketResend = 1u << 2;
constexpr std::uint32_t kRegPrivilege = 0x0a00;
constexpr std::uint32_t kRegStreamPort = 0x0d00;
constexpr std::uint32_t kRegPacketSize = 0x0d04;
constexpr std::uint32_t kPacketSizeFireTest = 1u << 31;
constexpr std::uint32_t kRegStreamAddress = 0x0d18;
constexpr std::uint32_t kRegWidth = ARV_FAKE_CAMERA_REGISTER_WIDTH;
constexpr std::uint32_t kRegHeight = ARV_FAKE_CAMERA_REGISTER_HEIGHT;
constexpr std::uint32_t kRegAcquisition = ARV_FAKE_CAMERA_REGISTER_ACQUISITION;
constexpr std::uint32_t kRegPixelFormat = ARV_FAKE_CAMERA_REGISTER_PIXEL_FORMAT;

// GVSP, standard (16-bit block, 24-bit packet) ids.
constexpr std::uint32_t kIpUdpBytes = 20 + 8;
constexpr std::uint32_t kGvspHeaderBytes = 8;
// The leader's UDP payload (header + 36 bytes) must fit the receiver's SCPS - 28 bytes.
constexpr std::uint32_t kMinPacketSize = kIpUdpBytes + kGvspHeaderBytes + 36;
constexpr std::uint8_t kContentLeader = 1;
constexpr std::uint8_t kContentTrailer = 2;
constexpr std::uint8_t kContentPayload = 3;
constexpr std::uint16_t kGvspPacketUnavailable = 0x800c;
constexpr std::uint16_t kPayloadImage = 0x0001;
constexpr std::uint16_t kPayloadImageExtendedChunk = 0x4001;
constexpr std::uint32_t kImageChunkId = 1;

// [0, 1) from the top 53 bits: std::uniform_real_distribution differs between standard
// libraries, this does not.
double Uniform(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

Bytes GvspHeader(std::uint16_t status, std::uint16_t block_id, std::uint8_t content_type,
                 std::uint32_t packet_id) {
  Bytes out;
  io::PutBe<std::uint16_t>(&out, status);
  io::PutBe<std::uint16_t>(&out, block_id);
  io::PutBe<std::uint32_t>(&out, (std::uint32_t{content_type} << 24) | (packet_id & 0xffffff));
  return out;
}

sockaddr_in SocketAddress(std::uint32_t ip_host_order, std::uint16_t port) {
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(ip_host_order);
  addr.sin_port = htons(port);
  return addr;
}

void SendTo(int fd, const Bytes& bytes, const sockaddr_in& to) {
  // Errors are ignored: the report counts the device's own impairments only.
  sendto(fd, bytes.data(), bytes.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof to);
}

// No SO_REUSEADDR: with it Linux lets a second UDP socket bind the same address and port, and a
// test that starts two devices on one address would then miss the conflict.
int BindUdp(std::uint32_t ip_host_order, std::uint16_t port, const std::string& address) {
  const int fd = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) throw std::runtime_error("GigeTestDevice: socket(): " + std::string(strerror(errno)));
  const sockaddr_in addr = SocketAddress(ip_host_order, port);
  if (bind(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
    const int err = errno;
    close(fd);
    throw std::runtime_error("GigeTestDevice: cannot bind UDP " + address + ":" +
                             std::to_string(port) + ": " + strerror(err));
  }
  return fd;
}

void CheckProbability(double p, const char* name) {
  if (!(p >= 0.0 && p <= 1.0)) {
    throw std::invalid_argument(std::string("GigeTestDevice: ") + name + " must be in [0, 1]");
  }
}

void CheckOptions(const GigeTestDeviceOptions& o, const std::vector<GigeTestFrame>& frames) {
  const auto fail = [](const std::string& what) {
    throw std::invalid_argument("GigeTestDevice: " + what);
  };
  if (o.width == 0 || o.height == 0) fail("width and height must be positive");
  if (!(o.frame_rate_hz > 0.0) || !std::isfinite(o.frame_rate_hz)) fail("frame_rate_hz <= 0");
  CheckProbability(o.loss, "loss");
  CheckProbability(o.reorder, "reorder");
  CheckProbability(o.duplicate, "duplicate");
  CheckProbability(o.resend_refusal, "resend_refusal");
  if (o.reorder > 0.0 && o.reorder_depth == 0) fail("reorder_depth must be >= 1");
  if (o.serial.empty() || o.serial.size() >= 16) fail("serial must have 1 to 15 characters");
  const std::uint64_t pixels = std::uint64_t{o.width} * o.height;
  const std::size_t stamps = o.line_timestamp_chunk_id != 0 ? o.height : 0;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    if (frames[k].pixels.size() != pixels) {
      fail("frame " + std::to_string(k) + " has " + std::to_string(frames[k].pixels.size()) +
           " pixels, expected width*height = " + std::to_string(pixels));
    }
    if (frames[k].line_timestamps_ns.size() != stamps) {
      fail("frame " + std::to_string(k) + " has " +
           std::to_string(frames[k].line_timestamps_ns.size()) + " line timestamps, expected " +
           std::to_string(stamps));
    }
  }
}

// Chunk layout as Aravis reads it (arv_buffer_get_chunk_data walks back from the end of the
// received bytes): each chunk's data is followed by its [id][length] tag, big-endian.
Bytes BuildPayload(const GigeTestDeviceOptions& o, const GigeTestFrame& frame) {
  Bytes out;
  out.reserve(frame.pixels.size() * 2 + 16 + frame.line_timestamps_ns.size() * 8);
  for (const std::uint16_t px : frame.pixels) {
    io::PutLe<std::uint16_t>(&out, px);
  }
  if (o.line_timestamp_chunk_id != 0) {
    const auto image_bytes = static_cast<std::uint32_t>(out.size());
    io::PutBe<std::uint32_t>(&out, kImageChunkId);
    io::PutBe<std::uint32_t>(&out, image_bytes);
    for (const std::uint64_t t : frame.line_timestamps_ns) io::PutBe<std::uint64_t>(&out, t);
    io::PutBe<std::uint32_t>(&out, o.line_timestamp_chunk_id);
    io::PutBe<std::uint32_t>(&out, 8 * o.height);
  }
  return out;
}

// Leader (id 0), data (1..n), trailer (n+1). Every data packet but the last carries exactly
// SCPS - 36 bytes: Aravis places packet i at (i - 1) * (SCPS - 36).
std::vector<Bytes> BuildPackets(const GigeTestDeviceOptions& o, const Bytes& payload,
                                std::uint16_t block_id, std::uint64_t timestamp,
                                std::uint32_t packet_size) {
  const std::uint16_t payload_type =
      o.line_timestamp_chunk_id != 0 ? kPayloadImageExtendedChunk : kPayloadImage;
  std::vector<Bytes> packets;
  Bytes leader = GvspHeader(0, block_id, kContentLeader, 0);
  io::PutBe<std::uint16_t>(&leader, 0);
  io::PutBe<std::uint16_t>(&leader, payload_type);
  io::PutBe<std::uint64_t>(&leader, timestamp);
  for (const std::uint32_t v : {o.pixel_format, o.width, o.height, 0u, 0u})
    io::PutBe<std::uint32_t>(&leader, v);
  io::PutBe<std::uint32_t>(&leader, 0);  // x and y padding
  packets.push_back(std::move(leader));
  const std::size_t block = packet_size - kIpUdpBytes - kGvspHeaderBytes;
  for (std::size_t offset = 0; offset < payload.size(); offset += block) {
    Bytes data =
        GvspHeader(0, block_id, kContentPayload, static_cast<std::uint32_t>(packets.size()));
    const std::size_t n = std::min(block, payload.size() - offset);
    data.insert(data.end(), payload.begin() + offset, payload.begin() + offset + n);
    packets.push_back(std::move(data));
  }
  Bytes trailer =
      GvspHeader(0, block_id, kContentTrailer, static_cast<std::uint32_t>(packets.size()));
  io::PutBe<std::uint16_t>(&trailer, 0);
  io::PutBe<std::uint16_t>(&trailer, payload_type);
  io::PutBe<std::uint32_t>(&trailer, o.height);  // size_y
  packets.push_back(std::move(trailer));
  return packets;
}

struct Decision {
  bool lost = false, held = false, duplicated = false;
  std::size_t delay = 0;
};

// Always four draws per packet, so changing one probability leaves the other decisions alone.
std::vector<Decision> DrawDecisions(std::mt19937_64& rng, std::size_t n,
                                    const GigeTestDeviceOptions& o) {
  std::vector<Decision> out(n);
  for (Decision& d : out) {
    d.lost = Uniform(rng) < o.loss;
    d.held = Uniform(rng) < o.reorder;
    d.delay = 1 + static_cast<std::size_t>(rng() % std::max<std::size_t>(o.reorder_depth, 1));
    d.duplicated = Uniform(rng) < o.duplicate;
    if (d.lost) d.held = d.duplicated = false;
  }
  return out;
}

// Packet indices in sending order: a held packet goes right after the packet `delay` places
// later in id order (sent or not), or at the end of the frame.
std::vector<std::size_t> SendOrder(const std::vector<Decision>& decisions) {
  std::vector<std::pair<std::size_t, std::size_t>> keyed;  // (key, index)
  const std::size_t n = decisions.size();
  for (std::size_t i = 0; i < n; ++i) {
    const Decision& d = decisions[i];
    if (d.lost) continue;
    keyed.emplace_back(d.held ? 2 * std::min(i + d.delay, n - 1) + 1 : 2 * i, i);
  }
  std::stable_sort(keyed.begin(), keyed.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<std::size_t> order;
  for (const auto& k : keyed) order.push_back(k.second);
  return order;
}

struct GvcpCommand {
  std::uint8_t flags = 0;
  std::uint16_t command = 0;
  std::uint16_t request_id = 0;
  const char* data = nullptr;
  std::size_t size = 0;
};

struct GvcpReply {
  std::uint16_t status = 0;
  Bytes data;
};

// Closes the descriptor, so a constructor that throws half-way leaks nothing.
class UniqueFd {
 public:
  UniqueFd() = default;
  UniqueFd(const UniqueFd&) = delete;
  UniqueFd& operator=(const UniqueFd&) = delete;
  ~UniqueFd() { reset(-1); }
  void reset(int fd) {
    if (fd_ >= 0) close(fd_);
    fd_ = fd;
  }
  int get() const { return fd_; }

 private:
  int fd_ = -1;
};

struct CameraUnref {
  void operator()(ArvFakeCamera* camera) const { g_object_unref(camera); }
};

struct RetainedFrame {
  std::uint16_t block_id = 0;
  std::size_t report_index = 0;
  std::vector<Bytes> packets;
};

}  // namespace

struct GigeTestDevice::Impl {
  Impl(const GigeTestDeviceOptions& o, std::vector<GigeTestFrame> f);
  ~Impl();

  void Run();
  int StreamStep();
  void SendFrame(std::size_t k, const sockaddr_in& to, std::uint32_t packet_size);
  void ReceiveGvcp();
  void HandleGvcp(const char* bytes, std::size_t size, const sockaddr_in& from);
  GvcpReply ReadRegisters(const GvcpCommand& cmd);
  GvcpReply WriteRegisters(const GvcpCommand& cmd);
  GvcpReply ReadMemory(const GvcpCommand& cmd);
  GvcpReply WriteMemory(const GvcpCommand& cmd);
  std::uint16_t WriteRegister(std::uint32_t address, std::uint32_t value);
  void HandleResend(const GvcpCommand& cmd);
  void SendTestPacket();

  std::uint32_t Register(std::uint32_t address) const;
  bool StreamDestination(sockaddr_in* to) const;
  std::uint32_t PacketSize() const;
  bool Readable(std::uint32_t address, std::size_t size) const;
  Bytes ReadBytes(std::uint32_t address, std::size_t size) const;

  const GigeTestDeviceOptions options;
  const std::vector<GigeTestFrame> frames;
  std::uint32_t ip = 0;  // options.address, host order
  UniqueFd gvcp_fd;
  UniqueFd stream_fd;
  std::unique_ptr<ArvFakeCamera, CameraUnref> camera;
  std::size_t xml_size = 0;  // the GenICam file, mapped after the register memory

  // Device thread only.
  std::mt19937_64 impairment_rng;
  std::mt19937_64 refusal_rng;
  std::deque<RetainedFrame> retained;
  std::size_t next_frame = 0;
  std::uint16_t next_block_id = 1;
  bool streaming = false;
  Clock::time_point stream_start;

  mutable std::mutex mutex;
  std::condition_variable sent_cv;
  GigeTestDeviceReport report;  // guarded by mutex

  std::atomic<bool> stop{false};
  std::thread thread;
};

GigeTestDevice::Impl::Impl(const GigeTestDeviceOptions& o, std::vector<GigeTestFrame> f)
    : options(o),
      frames(std::move(f)),
      impairment_rng(o.seed),
      refusal_rng(o.seed ^ 0x9e3779b97f4a7c15ull) {
  CheckOptions(options, frames);
  in_addr parsed{};
  if (inet_pton(AF_INET, options.address.c_str(), &parsed) != 1) {
    throw std::invalid_argument("GigeTestDevice: not an IPv4 address: " + options.address);
  }
  ip = ntohl(parsed.s_addr);
  gvcp_fd.reset(BindUdp(ip, kGvcpPort, options.address));
  stream_fd.reset(BindUdp(ip, 0, options.address));
  camera.reset(arv_fake_camera_new(options.serial.c_str()));
  if (!camera) throw std::runtime_error("GigeTestDevice: arv_fake_camera_new failed");
  arv_fake_camera_get_genicam_xml(camera.get(), &xml_size);
  // The stock fake camera advertises no capabilities; Aravis then never asks for resends.
  guint32 capabilities = 0;
  arv_fake_camera_read_register(camera.get(), kRegGvcpCapability, &capabilities);
  arv_fake_camera_write_register(camera.get(), kRegGvcpCapability,
                                 capabilities | kCapWriteMemory | kCapPacketResend);
  arv_fake_camera_write_register(camera.get(), kRegWidth, options.width);
  arv_fake_camera_write_register(camera.get(), kRegHeight, options.height);
  arv_fake_camera_write_register(camera.get(), kRegPixelFormat, options.pixel_format);
  GInetAddress* inet = g_inet_address_new_from_string(options.address.c_str());
  arv_fake_camera_set_inet_address(camera.get(), inet);
  g_object_unref(inet);
  report.all_sent = frames.empty();
  report.frames.reserve(frames.size());
  thread = std::thread([this] { Run(); });
}

GigeTestDevice::Impl::~Impl() {
  stop = true;
  if (thread.joinable()) thread.join();
}

void GigeTestDevice::Impl::Run() {
  while (!stop) {
    const int timeout_ms = StreamStep();
    pollfd p{gvcp_fd.get(), POLLIN, 0};
    if (poll(&p, 1, timeout_ms) > 0) ReceiveGvcp();
  }
}

// Sends the next frame when it is due; returns how long the thread may wait for commands.
int GigeTestDevice::Impl::StreamStep() {
  if (next_frame >= frames.size()) return kPollMs;
  sockaddr_in to{};
  const bool active = Register(kRegPrivilege) != 0 && Register(kRegAcquisition) != 0;
  if (!active || !StreamDestination(&to)) {
    streaming = false;
    return kPollMs;
  }
  const double period_ns = 1e9 / options.frame_rate_hz;
  const auto offset = [&](std::size_t k) {
    return std::chrono::nanoseconds(std::llround(period_ns * static_cast<double>(k)));
  };
  const Clock::time_point now = Clock::now();
  if (!streaming) {  // (re)start: the next frame goes now, the rest at the frame rate
    streaming = true;
    stream_start = now - offset(next_frame);
  }
  const Clock::time_point due = stream_start + offset(next_frame);
  if (now < due) {
    const auto wait_us = std::chrono::duration_cast<std::chrono::microseconds>(due - now).count();
    return static_cast<int>(std::min<std::int64_t>(kPollMs, (wait_us + 999) / 1000));
  }
  SendFrame(next_frame, to, PacketSize());
  ++next_frame;
  if (next_frame == frames.size()) {
    std::lock_guard<std::mutex> lock(mutex);
    report.all_sent = true;
    sent_cv.notify_all();
  }
  return 0;
}

void GigeTestDevice::Impl::SendFrame(std::size_t k, const sockaddr_in& to,
                                     std::uint32_t packet_size) {
  const std::uint16_t block_id = next_block_id;
  next_block_id = next_block_id == 0xffff ? 1 : next_block_id + 1;  // block id 0 is invalid
  const auto timestamp = options.first_timestamp_ns +
                         static_cast<std::uint64_t>(
                             std::llround(1e9 * static_cast<double>(k) / options.frame_rate_hz));
  std::vector<Bytes> packets =
      BuildPackets(options, BuildPayload(options, frames[k]), block_id, timestamp, packet_size);
  const std::vector<Decision> decisions = DrawDecisions(impairment_rng, packets.size(), options);
  GigeTestFrameReport frame;
  frame.frame_id = block_id;
  frame.packets = packets.size();
  std::size_t sent = 0, duplicated = 0, reordered = 0;
  for (std::size_t i = 0; i < decisions.size(); ++i) {
    if (decisions[i].lost) frame.dropped.push_back(static_cast<std::uint32_t>(i));
    duplicated += decisions[i].duplicated;
    reordered += decisions[i].held;
  }
  for (const std::size_t i : SendOrder(decisions)) {
    const int copies = decisions[i].duplicated ? 2 : 1;
    for (int c = 0; c < copies; ++c) SendTo(stream_fd.get(), packets[i], to);
    sent += static_cast<std::size_t>(copies);
  }
  {
    std::lock_guard<std::mutex> lock(mutex);
    report.packets_sent += sent;
    report.dropped += frame.dropped.size();
    report.duplicated += duplicated;
    report.reordered += reordered;
    report.frames.push_back(std::move(frame));
  }
  retained.push_back(RetainedFrame{block_id, k, std::move(packets)});
  if (retained.size() > kRetainedFrames) retained.pop_front();
}

void GigeTestDevice::Impl::ReceiveGvcp() {
  char buffer[2048];
  for (int n = 0; n < 64; ++n) {
    sockaddr_in from{};
    socklen_t from_size = sizeof from;
    const ssize_t size = recvfrom(gvcp_fd.get(), buffer, sizeof buffer, MSG_DONTWAIT,
                                  reinterpret_cast<sockaddr*>(&from), &from_size);
    if (size < 0) return;
    HandleGvcp(buffer, static_cast<std::size_t>(size), from);
  }
}

void GigeTestDevice::Impl::HandleGvcp(const char* bytes, std::size_t size,
                                      const sockaddr_in& from) {
  if (size < kGvcpHeaderBytes || static_cast<std::uint8_t>(bytes[0]) != kGvcpCommandKey) return;
  GvcpCommand cmd;
  cmd.flags = static_cast<std::uint8_t>(bytes[1]);
  cmd.command = io::GetBe<std::uint16_t>(bytes + 2);
  cmd.request_id = io::GetBe<std::uint16_t>(bytes + 6);
  cmd.data = bytes + kGvcpHeaderBytes;
  cmd.size = std::min<std::size_t>(io::GetBe<std::uint16_t>(bytes + 4), size - kGvcpHeaderBytes);
  GvcpReply reply;
  switch (cmd.command) {
    case kPacketResendCmd:  // never acknowledged
      HandleResend(cmd);
      return;
    case kDiscoveryCmd:
      reply.data = ReadBytes(0, kDiscoveryBytes);
      break;
    case kReadRegCmd:
      reply = ReadRegisters(cmd);
      break;
    case kWriteRegCmd:
      reply = WriteRegisters(cmd);
      break;
    case kReadMemCmd:
      reply = ReadMemory(cmd);
      break;
    case kWriteMemCmd:
      reply = WriteMemory(cmd);
      break;
    default:
      reply.status = kStatusNotImplemented;
      break;
  }
  // Aravis sets ACK_REQUIRED on discovery, reads and writes; the standard allows leaving it off.
  if ((cmd.flags & kGvcpFlagAckRequired) == 0) return;
  Bytes ack;
  io::PutBe<std::uint16_t>(&ack, reply.status);
  io::PutBe<std::uint16_t>(&ack, static_cast<std::uint16_t>(cmd.command + 1));
  io::PutBe<std::uint16_t>(&ack, static_cast<std::uint16_t>(reply.data.size()));
  io::PutBe<std::uint16_t>(&ack, cmd.request_id);
  ack.insert(ack.end(), reply.data.begin(), reply.data.end());
  SendTo(gvcp_fd.get(), ack, from);
}

GvcpReply GigeTestDevice::Impl::ReadRegisters(const GvcpCommand& cmd) {
  GvcpReply reply;
  if (cmd.size == 0 || cmd.size % 4 != 0) {
    reply.status = kStatusInvalidParameter;
    return reply;
  }
  for (std::size_t i = 0; i < cmd.size; i += 4) {
    const std::uint32_t address = io::GetBe<std::uint32_t>(cmd.data + i);
    if (address % 4 != 0) {
      reply.status = kStatusBadAlignment;
      break;
    }
    if (!Readable(address, 4)) {
      reply.status = kStatusInvalidAddress;
      break;
    }
    io::PutBe<std::uint32_t>(&reply.data, Register(address));
  }
  return reply;
}

GvcpReply GigeTestDevice::Impl::WriteRegisters(const GvcpCommand& cmd) {
  GvcpReply reply;
  if (cmd.size == 0 || cmd.size % 8 != 0) {
    reply.status = kStatusInvalidParameter;
    return reply;
  }
  std::uint16_t written = 0;
  for (std::size_t i = 0; i < cmd.size && reply.status == 0; i += 8) {
    reply.status = WriteRegister(io::GetBe<std::uint32_t>(cmd.data + i),
                                 io::GetBe<std::uint32_t>(cmd.data + i + 4));
    if (reply.status == 0) ++written;
  }
  io::PutBe<std::uint16_t>(&reply.data, 0);
  io::PutBe<std::uint16_t>(&reply.data, written);
  return reply;
}

GvcpReply GigeTestDevice::Impl::ReadMemory(const GvcpCommand& cmd) {
  GvcpReply reply;
  if (cmd.size < 8) {
    reply.status = kStatusInvalidParameter;
    return reply;
  }
  const std::uint32_t address = io::GetBe<std::uint32_t>(cmd.data);
  const std::uint16_t count = io::GetBe<std::uint16_t>(cmd.data + 6);
  if (count == 0 || count > kReadMemMaxBytes) {
    reply.status = kStatusInvalidParameter;
  } else if (address % 4 != 0 || count % 4 != 0) {
    reply.status = kStatusBadAlignment;
  } else if (!Readable(address, count)) {
    reply.status = kStatusInvalidAddress;
  } else {
    io::PutBe<std::uint32_t>(&reply.data, address);
    const Bytes data = ReadBytes(address, count);
    reply.data.insert(reply.data.end(), data.begin(), data.end());
  }
  return reply;
}

// Word by word through WriteRegister, so a write-memory gets the same checks as a write-register.
GvcpReply GigeTestDevice::Impl::WriteMemory(const GvcpCommand& cmd) {
  GvcpReply reply;
  if (cmd.size < 8) {
    reply.status = kStatusInvalidParameter;
    return reply;
  }
  const std::uint32_t address = io::GetBe<std::uint32_t>(cmd.data);
  const std::size_t count = cmd.size - 4;
  std::uint16_t written = 0;
  if (address % 4 != 0 || count % 4 != 0) {
    reply.status = kStatusBadAlignment;
  } else {
    for (std::size_t i = 0; i < count && reply.status == 0; i += 4) {
      reply.status = WriteRegister(address + static_cast<std::uint32_t>(i),
                                   io::GetBe<std::uint32_t>(cmd.data + 4 + i));
      if (reply.status == 0) written = static_cast<std::uint16_t>(written + 4);
    }
  }
  io::PutBe<std::uint16_t>(&reply.data, 0);
  io::PutBe<std::uint16_t>(&reply.data, written);
  return reply;
}

std::uint16_t GigeTestDevice::Impl::WriteRegister(std::uint32_t address, std::uint32_t value) {
  if (address % 4 != 0) return kStatusBadAlignment;
  // The GenICam file after the register memory is read-only.
  if (std::uint64_t{address} + 4 > ARV_FAKE_CAMERA_MEMORY_SIZE) return kStatusInvalidAddress;
  // The frames were built for the constructor's geometry: a receiver asking for another one
  // would get buffers it did not ask for, so it gets an error instead.
  if ((address == kRegWidth && value != options.width) ||
      (address == kRegHeight && value != options.height) ||
      (address == kRegPixelFormat && value != options.pixel_format)) {
    return kStatusWriteProtect;
  }
  const bool fire_test = address == kRegPacketSize && (value & kPacketSizeFireTest) != 0;
  if (fire_test) value &= ~kPacketSizeFireTest;
  arv_fake_camera_write_register(camera.get(), address, value);
  if (fire_test) SendTestPacket();
  return 0;
}

void GigeTestDevice::Impl::HandleResend(const GvcpCommand& cmd) {
  {
    std::lock_guard<std::mutex> lock(mutex);
    ++report.resend_requests;
  }
  if ((cmd.flags & kGvcpFlagExtendedIds) != 0 || cmd.size < 12) return;
  const auto block_id = static_cast<std::uint16_t>(io::GetBe<std::uint32_t>(cmd.data) & 0xffff);
  const std::uint32_t first = io::GetBe<std::uint32_t>(cmd.data + 4) & 0xffffff;
  const std::uint32_t last = io::GetBe<std::uint32_t>(cmd.data + 8) & 0xffffff;
  const auto it = std::find_if(retained.rbegin(), retained.rend(),
                               [&](const RetainedFrame& f) { return f.block_id == block_id; });
  sockaddr_in to{};
  if (it == retained.rend() || first > last || !StreamDestination(&to)) return;
  const std::vector<Bytes>& packets = it->packets;
  // Aravis asks up to the id its buffer size allows when it has not seen the trailer.
  const std::uint32_t end = std::min<std::uint32_t>(last + 1, packets.size());
  std::vector<std::uint32_t> resent, refused;
  for (std::uint32_t id = first; id < end; ++id) {
    Bytes packet = packets[id];
    if (Uniform(refusal_rng) < options.resend_refusal) {
      packet.resize(kGvspHeaderBytes);  // same block, content type and packet id
      packet[0] = static_cast<char>(kGvspPacketUnavailable >> 8);
      packet[1] = static_cast<char>(kGvspPacketUnavailable);
      refused.push_back(id);
    } else {
      packet[0] = static_cast<char>(options.resend_status >> 8);
      packet[1] = static_cast<char>(options.resend_status);
      resent.push_back(id);
    }
    SendTo(stream_fd.get(), packet, to);
  }
  std::lock_guard<std::mutex> lock(mutex);
  GigeTestFrameReport& frame = report.frames[it->report_index];
  frame.resent.insert(frame.resent.end(), resent.begin(), resent.end());
  frame.refused.insert(frame.refused.end(), refused.begin(), refused.end());
  report.resent += resent.size();
  report.refused += refused.size();
}

// Aravis's packet-size negotiation fires a test packet and checks only its size.
void GigeTestDevice::Impl::SendTestPacket() {
  sockaddr_in to{};
  const std::uint32_t packet_size = Register(kRegPacketSize) & 0xffff;
  if (packet_size <= kIpUdpBytes + kGvspHeaderBytes || !StreamDestination(&to)) return;
  SendTo(stream_fd.get(), Bytes(packet_size - kIpUdpBytes, 0), to);
}

std::uint32_t GigeTestDevice::Impl::Register(std::uint32_t address) const {
  guint32 value = 0;
  arv_fake_camera_read_register(camera.get(), address, &value);
  return value;
}

bool GigeTestDevice::Impl::StreamDestination(sockaddr_in* to) const {
  const std::uint32_t address = Register(kRegStreamAddress);
  const auto port = static_cast<std::uint16_t>(Register(kRegStreamPort) & 0xffff);
  if (address == 0 || port == 0) return false;
  *to = SocketAddress(address, port);
  return true;
}

std::uint32_t GigeTestDevice::Impl::PacketSize() const {
  return std::max(Register(kRegPacketSize) & 0xffff, kMinPacketSize);
}

// Aravis reads the GenICam file in multiples of 4 bytes, so the last word may run past it.
bool GigeTestDevice::Impl::Readable(std::uint32_t address, std::size_t size) const {
  const std::uint64_t end = ARV_FAKE_CAMERA_MEMORY_SIZE + (xml_size + 3) / 4 * 4;
  return std::uint64_t{address} + size <= end;
}

// ArvFakeCamera's read past the GenICam file is not bounds-checked; clip it and pad with zeros.
Bytes GigeTestDevice::Impl::ReadBytes(std::uint32_t address, std::size_t size) const {
  Bytes out(size, 0);
  const std::uint64_t end = ARV_FAKE_CAMERA_MEMORY_SIZE + xml_size;
  if (address < end) {
    const auto n = static_cast<guint32>(std::min<std::uint64_t>(size, end - address));
    if (n > 0) arv_fake_camera_read_memory(camera.get(), address, n, out.data());
  }
  return out;
}

GigeTestDevice::GigeTestDevice(const GigeTestDeviceOptions& options,
                               std::vector<GigeTestFrame> frames)
    : impl_(std::make_unique<Impl>(options, std::move(frames))) {}

GigeTestDevice::~GigeTestDevice() = default;

bool GigeTestDevice::WaitSent(int timeout_ms, int linger_ms) {
  {
    std::unique_lock<std::mutex> lock(impl_->mutex);
    if (!impl_->sent_cv.wait_for(lock, std::chrono::milliseconds(timeout_ms),
                                 [&] { return impl_->report.all_sent; })) {
      return false;
    }
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(std::max(linger_ms, 0)));
  return true;
}

GigeTestDeviceReport GigeTestDevice::Report() const {
  GigeTestDeviceReport out;
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    out = impl_->report;
  }
  for (GigeTestFrameReport& frame : out.frames) {
    frame.unrecoverable = std::any_of(frame.dropped.begin(), frame.dropped.end(), [&](auto id) {
      return std::find(frame.resent.begin(), frame.resent.end(), id) == frame.resent.end();
    });
  }
  return out;
}

const std::string& GigeTestDevice::address() const { return impl_->options.address; }

}  // namespace lasercell::testing
