#pragma once
// A GigE Vision device on a loopback address for the receiver's tests: GVCP on address:3956 over
// Aravis's ArvFakeCamera register model, GVSP image buffers (optionally with a line-timestamp
// chunk) sent once at a fixed rate. Unlike Aravis's own fake camera it loses, reorders and
// duplicates packets and answers (or refuses) packet resends, all drawn from a seed, and reports
// what it did, so a test can tell which buffers a correct receiver must deliver intact.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "triangulation/line_scan.hpp"

namespace lasercell::testing {

inline constexpr std::uint32_t kPixelMono16 = triangulation::kPixelFormatMono16;
inline constexpr std::uint32_t kPixelCoord3dC16 = triangulation::kPixelFormatCoord3dC16;

/// One buffer of the stream.
struct GigeTestFrame {
  std::vector<std::uint16_t> pixels;  ///< width*height, row-major; sent little-endian.
  /// height values when the line-timestamp chunk is on, else empty.
  std::vector<std::uint64_t> line_timestamps_ns;
};

struct GigeTestDeviceOptions {
  std::string address = "127.0.0.2";  ///< IPv4 address bound for GVCP (port 3956) and GVSP.
  std::string serial = "LCTEST";      ///< Fewer than 16 characters.
  std::uint32_t width = 256;          ///< Width register: columns per line.
  std::uint32_t height = 16;          ///< Height register: lines per buffer.
  std::uint32_t pixel_format = kPixelCoord3dC16;
  /// 0: payload type image. Else image with extended chunks: the pixels (chunk id 1) then the
  /// line timestamps (this chunk id, height big-endian u64 values).
  std::uint32_t line_timestamp_chunk_id = 0;
  std::uint64_t first_timestamp_ns = 1000000000;  ///< Leader timestamp of frame 0 (1 GHz ticks).
  double frame_rate_hz = 500.0;
  /// Per packet of a first transmission: probability that it is not sent, that it is held back
  /// behind 1..reorder_depth later packets of its frame, that it is sent twice.
  double loss = 0.0, reorder = 0.0, duplicate = 0.0;
  std::size_t reorder_depth = 4;
  double resend_refusal = 0.0;  ///< Per requested packet: answered "packet unavailable" instead.
  std::uint16_t resend_status = 0;  ///< GVSP status of resent packets (some cameras use 0x0100).
  /// Impairments use std::mt19937_64(seed): for each packet of a frame, in packet id order, four
  /// draws (loss, reorder, reorder delay, duplicate), whatever their outcome. Refusals use a
  /// second generator seeded from `seed`, one draw per requested packet id, so the first
  /// transmissions do not depend on the receiver's resend requests.
  std::uint64_t seed = 1;
};

/// What the device did with one frame; packet ids are GVSP ids (leader 0, trailer packets-1).
struct GigeTestFrameReport {
  std::uint16_t frame_id = 0;  ///< GVSP block id (frame k of the constructor: k+1 until it wraps).
  std::size_t packets = 0;     ///< Leader + data + trailer.
  std::vector<std::uint32_t> dropped, resent, refused;  ///< In the order it happened.
  bool unrecoverable = false;  ///< Some dropped id was never resent (refused or never asked).
};

struct GigeTestDeviceReport {
  std::vector<GigeTestFrameReport> frames;  ///< In sending order; frames[k] is frame k.
  std::size_t packets_sent = 0;             ///< First transmissions, duplicates included.
  std::size_t dropped = 0, duplicated = 0;
  std::size_t reordered = 0;        ///< Held back (even when nothing followed them in the frame).
  std::size_t resend_requests = 0;  ///< PACKETRESEND commands received.
  std::size_t resent = 0, refused = 0;  ///< Packets.
  bool all_sent = false;
};

/// Sends the frames while a controller holds the control channel, AcquisitionStart was written
/// and SCDA/SCP name a destination. Writes of another Width, Height or PixelFormat than the
/// options' are refused (GVCP write-protect): the frames are built for those. The register model
/// is Aravis's fake camera, whose PixelFormat enumeration has no Coord3D_C16 entry: the value
/// reads as an integer, not by name. Datagrams the kernel drops (a receiver's full socket
/// buffer) are not in the report.
class GigeTestDevice {
 public:
  /// Binds address:3956 and starts the device thread; throws std::runtime_error naming the
  /// address when it cannot bind. Frames must each hold width*height pixels (and height
  /// timestamps when the chunk is on), else std::invalid_argument (also for invalid options).
  GigeTestDevice(const GigeTestDeviceOptions& options, std::vector<GigeTestFrame> frames);
  ~GigeTestDevice();  ///< Stops the thread (it polls with <= 20 ms timeouts).
  GigeTestDevice(const GigeTestDevice&) = delete;
  GigeTestDevice& operator=(const GigeTestDevice&) = delete;

  /// Waits until every frame was sent and then linger_ms more (serving resends); false on timeout.
  bool WaitSent(int timeout_ms, int linger_ms = 300);
  GigeTestDeviceReport Report() const;  ///< Thread-safe snapshot.
  const std::string& address() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace lasercell::testing
