#pragma once
// Line-scan buffers of a 3D line profiler (GigE Vision, gige_source.hpp) turned into profiles,
// without a camera library: the receiver hands over each buffer (or the news that one arrived
// incomplete) and takes sweeps. Tests drive it with plain bytes.
//
// A profiler in 3D mode sends one buffer per N exposures: an image of `width` columns by
// `height` lines whose pixel is the laser peak's row in fixed point (Coord3D_C16 or Mono16,
// 16-bit little-endian, PFNC). Line i of buffer f becomes the profile with sequence number
// f * height + i, so a lost buffer is a gap of `height` sequence numbers, never lines attached to
// another buffer's timestamps. Timestamps: per line from a chunk (one big-endian u64 ns per line,
// as GigE Vision chunks are) when present, else the buffer's timestamp + i / line_rate_hz.
//
// GigE Vision block ids are 16 bit and skip 0 when they wrap; FrameIdUnwrapper makes them a
// running count so sequence numbers keep growing.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "triangulation/profile_io.hpp"
#include "triangulation/udp_assembler.hpp"

namespace lasercell::triangulation {

/// PFNC pixel formats a line profiler sends ranges in.
inline constexpr std::uint32_t kPixelFormatMono16 = 0x01100007;
inline constexpr std::uint32_t kPixelFormatCoord3dC16 = 0x011000B8;
/// "Mono16", "Coord3D_C16", else "0x........".
std::string PixelFormatName(std::uint32_t pixel_format);

/// How line-scan pixels become profiles and sweeps.
struct LineScanOptions {
  double row_scale_px = 1.0 / 16.0;  ///< Peak row per count, px (1/16: 4 subpixel bits).
  double row_offset_px = 0.0;        ///< Peak row of count 0, px.
  std::uint16_t missing_value = 0;   ///< Count meaning "no peak in this column".
  float peak_intensity = 1.0f;       ///< Intensity of every peak (range formats carry none), 0..1.
  /// Lines per second, to time lines of buffers without a timestamp chunk; 0 = unknown (lines
  /// then share their buffer's timestamp and the sweep account counts those buffers).
  double line_rate_hz = 0.0;
  /// Chunk holding one big-endian u64 timestamp (ns) per line; 0 = none.
  std::uint32_t line_timestamp_chunk_id = 0;
  std::size_t max_sweep_profiles = 100000;  ///< A sweep ends when it holds this many profiles.
  /// Throws OptionError naming the field.
  void Check() const;
};

/// One complete buffer as received.
struct LineScanBuffer {
  std::uint64_t frame_id = 0;      ///< Block id as the device sent it (0 = unknown).
  std::int64_t timestamp_ns = 0;   ///< Device timestamp of the buffer (its first line), ns.
  std::uint32_t pixel_format = 0;  ///< PFNC.
  std::uint32_t width = 0;         ///< Columns per line.
  std::uint32_t height = 0;        ///< Lines.
  std::uint32_t x_offset = 0;      ///< Image column of column 0.
  std::string_view image;          ///< width * height 16-bit little-endian pixels (or more bytes).
  std::string_view line_timestamps;  ///< The timestamp chunk's bytes, empty when absent.
};

/// Makes 16-bit block ids that skip 0 on wrap (1..65535, 1, ...) a running count starting at the
/// first id seen. Ids above 65535 (GigE Vision 2 extended ids) are taken as they are.
class FrameIdUnwrapper {
 public:
  /// The running number of `raw`; nullopt for 0 or an id older than the last one (late).
  std::optional<std::uint64_t> Unwrap(std::uint64_t raw);
  /// Forgets the history (a new stream).
  void Reset() { started_ = false; }

 private:
  bool started_ = false;
  std::uint64_t last_raw_ = 0;
  std::uint64_t last_ = 0;
};

/// Why a line-scan sweep ended.
enum class LineScanEnd : std::uint8_t {
  kGap,          ///< No buffer for the source's sweep gap.
  kMaxProfiles,  ///< max_sweep_profiles reached.
  kStopped,      ///< The stream was stopped or flushed.
};
/// "gap", "max_profiles", "stopped".
const char* LineScanEndName(LineScanEnd end);

/// What one line-scan sweep lost. Frame numbers are the unwrapped block ids (equal to the
/// device's ids until they wrap).
struct LineScanAccount {
  std::uint64_t first_frame = 0;
  std::uint64_t last_frame = 0;
  std::size_t buffers_delivered = 0;
  std::vector<std::uint64_t> incomplete_frames;  ///< Arrived with packets missing (or timed out).
  std::vector<SequenceRange> missing_frames;     ///< Skipped block ids: nothing arrived.
  std::vector<std::uint64_t> refused_frames;     ///< Arrived whole but unusable (size, format).
  std::size_t late_buffers = 0;                  ///< Older than the newest: dropped.
  /// Incomplete without a block id (its leader was lost): its id is among missing_frames when a
  /// later buffer arrived, else its lines are still in lost_profiles.
  std::size_t unidentified_buffers = 0;
  std::size_t buffers_without_line_timestamps = 0;  ///< Chunk expected, absent or malformed.
  std::size_t profiles = 0;                         ///< Profiles in the sweep.
  std::uint64_t lost_profiles = 0;  ///< Lines of incomplete, missing and refused buffers.
  LineScanEnd ended_by = LineScanEnd::kGap;
  /// True when nothing was lost.
  bool Clean() const;
  /// One line, e.g. "frames 1-40: 38 buffers, 1 incomplete (7), missing 12-12, 640 profiles
  /// lost, ended by gap".
  std::string Summary() const;
};
/// The account as JSON.
nlohmann::json LineScanAccountJson(const LineScanAccount& account);

/// Converts one buffer's lines to profiles with sequence numbers first_sequence + line. Throws
/// InputError naming the buffer when its format is not a 16-bit one or it holds too few bytes.
/// `timed_by_chunk` (optional) says whether the timestamp chunk timed the lines.
std::vector<Profile> LinesToProfiles(const LineScanBuffer& buffer, const LineScanOptions& options,
                                     std::uint64_t first_sequence, bool* timed_by_chunk = nullptr);

/// A sweep and its account.
struct LineScanSweep {
  ProfileSet set;
  LineScanAccount account;
};

/// Collects buffers into sweeps. Not thread-safe.
class LineScanAssembler {
 public:
  /// `header`: the sensor's geometry (columns, first_column, image size; joint_count 0);
  /// `lines_per_buffer`: the device's buffer height. Throws OptionError / InputError.
  LineScanAssembler(ProfileHeader header, std::uint32_t lines_per_buffer,
                    const LineScanOptions& options);
  /// Adds a complete buffer. A buffer whose geometry or format does not match the header is
  /// refused and accounted. Returns a sweep that reached max_sweep_profiles.
  std::optional<LineScanSweep> AddComplete(const LineScanBuffer& buffer);
  /// Accounts a buffer that arrived incomplete (frame_id 0 when unknown).
  void AddIncomplete(std::uint64_t frame_id);
  /// Ends the open sweep; nullopt when none is open.
  std::optional<LineScanSweep> Finish(LineScanEnd end);
  /// True while a sweep is open.
  bool open() const { return open_; }

 private:
  std::optional<std::uint64_t> Place(std::uint64_t frame_id);
  LineScanSweep TakeSweep(LineScanEnd end);

  ProfileHeader header_;
  std::uint32_t lines_;
  LineScanOptions options_;
  FrameIdUnwrapper unwrap_;
  bool open_ = false;
  std::uint64_t next_frame_ = 0;             // the frame expected next in the open sweep
  std::uint64_t unplaced_unidentified_ = 0;  // id-less incomplete buffers no gap accounted yet
  LineScanSweep sweep_;
};

}  // namespace lasercell::triangulation
