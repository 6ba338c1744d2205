#pragma once
// Profiles from a GigE Vision 3D line profiler (SICK Ranger3, AT C5/C6, scanCONTROL in GigE
// mode) through Aravis 0.8: GVCP to configure, GVSP over UDP for the buffers, Aravis's socket
// path (not its packet socket), packet resends by Aravis. Each buffer holds `Height` exposures
// (line_scan.hpp turns them into profiles); a sweep is what arrives between two pauses of the
// stream (the sensor is triggered while the robot sweeps), or max_sweep_profiles.
//
// Aravis's GLib types stay inside gige_source.cpp.

#include <atomic>
#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "triangulation/line_scan.hpp"
#include "triangulation/profile_source.hpp"

namespace lasercell::triangulation {

/// Options of GigeProfileSource.
struct GigeSourceOptions {
  /// The device: its IPv4 address ("192.168.10.20") or an Aravis device id
  /// ("Vendor-Model-Serial", as `arv-tool-0.8` lists them).
  std::string device;
  std::uint32_t lines_per_buffer = 0;  ///< Written to the device's Height; 0 = keep the device's.
  std::string pixel_format;            ///< Written to PixelFormat ("Coord3D_C16"); "" = keep.
  std::uint32_t packet_size = 0;  ///< GVSP packet size, bytes (8972 with jumbo frames); 0 = keep.
  /// Sensor columns and rows of the profiles' header; 0 = the device's SensorWidth/SensorHeight
  /// (WidthMax/HeightMax when it has none).
  std::uint32_t image_width = 0;
  std::uint32_t image_height = 0;
  /// Use the device's Scan3dCoordinateScale/Offset, when it has them, instead of
  /// line_scan.row_scale_px/row_offset_px.
  bool use_device_scale = true;
  LineScanOptions line_scan;  ///< Pixel decoding, line timing, sweep size.
  /// Buffers queued to the stream. Aravis hands buffers over in block-id order, so one waiting
  /// for a resend holds back the ones after it: keep (packet_timeout_ms + frame_retention_ms) x
  /// buffers per second below this, or frames are lost as underruns.
  std::size_t buffers = 64;
  /// Kernel receive buffer of the stream socket, bytes (Aravis's default is one buffer's
  /// payload, which drops packets whenever its thread stalls).
  int socket_buffer_bytes = 16 << 20;
  double packet_timeout_ms = 20.0;    ///< A missing packet is asked again after this long.
  double frame_retention_ms = 200.0;  ///< A buffer still missing packets is given up after this.
  double sweep_gap_ms = 200.0;        ///< A sweep ends when no buffer arrives for this long.
  /// NextSweep returns nullopt when no buffer arrives for this long and no sweep is open, ms;
  /// 0 = wait for ever.
  double idle_timeout_ms = 0.0;
  /// Throws OptionError naming the field.
  void Check() const;
};

/// Aravis's stream counters since the stream opened (packets are GVSP packets).
struct GigeStreamCounters {
  std::uint64_t completed_buffers = 0;
  std::uint64_t failures = 0;        ///< Buffers that did not complete.
  std::uint64_t underruns = 0;       ///< Frames lost because no buffer was free.
  std::uint64_t timeouts = 0;        ///< Buffers given up after frame_retention_ms.
  std::uint64_t missing_frames = 0;  ///< Block ids skipped entirely.
  std::uint64_t received_packets = 0;
  std::uint64_t missing_packets = 0;     ///< Packets never received in closed buffers.
  std::uint64_t error_packets = 0;       ///< E.g. "packet unavailable" answers to resends.
  std::uint64_t ignored_packets = 0;     ///< Packets of no buffer (late frames, unknown types).
  std::uint64_t resend_requests = 0;     ///< Packets asked again.
  std::uint64_t resent_packets = 0;      ///< Asked-again packets that arrived.
  std::uint64_t duplicated_packets = 0;  ///< Packets received twice.
  std::uint64_t transferred_bytes = 0;
  /// One line.
  std::string Summary() const;
};
/// The counters as JSON.
nlohmann::json GigeStreamCountersJson(const GigeStreamCounters& counters);

/// A profile source on a GigE Vision line profiler.
class GigeProfileSource : public ProfileSource {
 public:
  /// Opens the device, configures it, queues buffers and starts acquisition. Throws InputError
  /// naming the device when it cannot be found or opened, is not GigE Vision, refuses a setting,
  /// or its lines cannot be timed (no line_rate_hz, timestamp chunk or AcquisitionLineRate).
  explicit GigeProfileSource(const GigeSourceOptions& options);
  ~GigeProfileSource() override;
  GigeProfileSource(const GigeProfileSource&) = delete;
  GigeProfileSource& operator=(const GigeProfileSource&) = delete;

  /// The next sweep (see the file comment), or nullopt after idle_timeout_ms of silence or
  /// Stop().
  std::optional<ProfileSet> NextSweep() override;
  /// The next sweep with its account.
  std::optional<LineScanSweep> NextLineScanSweep();
  /// E.g. "gige 192.168.10.20 (SICK Ranger3 22110047)".
  std::string Describe() const override;
  /// The last sweep's account summary when it lost buffers, else "".
  std::string LastSweepLoss() const override;
  /// The account of the sweep returned last; nullptr before the first.
  const LineScanAccount* last_account() const { return last_ ? &*last_ : nullptr; }
  /// Aravis's counters now.
  GigeStreamCounters counters() const;
  /// Profiles' header (geometry and device metadata).
  const ProfileHeader& header() const;
  /// Lines per buffer in use.
  std::uint32_t lines_per_buffer() const;
  /// Makes a waiting NextSweep return nullopt within ~50 ms (callable from another thread).
  void Stop() { stop_ = true; }

 private:
  struct Device;
  GigeSourceOptions options_;
  std::unique_ptr<Device> device_;
  std::unique_ptr<LineScanAssembler> assembler_;
  std::optional<LineScanAccount> last_;
  std::atomic<bool> stop_{false};
};

}  // namespace lasercell::triangulation
