#include "triangulation/line_scan.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "core/error.hpp"
#include "core/io/byte_order.hpp"

namespace lasercell::triangulation {

namespace {

// GigE Vision block ids are 16 bit, 1..65535 (0 is invalid), so they wrap modulo 65535.
constexpr std::uint64_t kBlockIdModulus = 65535;
constexpr std::uint64_t kMaxStandardBlockId = 65535;

bool Is16Bit(std::uint32_t pixel_format) {
  return pixel_format == kPixelFormatMono16 || pixel_format == kPixelFormatCoord3dC16;
}

std::string FramesText(const std::vector<std::uint64_t>& frames) {
  std::string s;
  for (std::size_t i = 0; i < frames.size() && i < 4; ++i) {
    if (i > 0) s += ", ";
    s += std::to_string(frames[i]);
  }
  if (frames.size() > 4) s += ", ...";
  return s;
}

}  // namespace

std::string PixelFormatName(std::uint32_t pixel_format) {
  if (pixel_format == kPixelFormatMono16) return "Mono16";
  if (pixel_format == kPixelFormatCoord3dC16) return "Coord3D_C16";
  char text[16];
  std::snprintf(text, sizeof text, "0x%08X", pixel_format);
  return text;
}

void LineScanOptions::Check() const {
  if (!std::isfinite(row_scale_px) || row_scale_px == 0.0) {
    throw OptionError("line scan: row_scale_px must be finite and non-zero (got " +
                      std::to_string(row_scale_px) + ")");
  }
  if (!std::isfinite(row_offset_px)) {
    throw OptionError("line scan: row_offset_px must be finite");
  }
  if (!(peak_intensity > 0.0f && peak_intensity <= 1.0f)) {
    throw OptionError("line scan: peak_intensity must be in (0, 1] (got " +
                      std::to_string(peak_intensity) + ")");
  }
  if (!std::isfinite(line_rate_hz) || line_rate_hz < 0.0) {
    throw OptionError("line scan: line_rate_hz must be >= 0 (0 = unknown), got " +
                      std::to_string(line_rate_hz));
  }
  if (max_sweep_profiles == 0) throw OptionError("line scan: max_sweep_profiles must be >= 1");
}

std::optional<std::uint64_t> FrameIdUnwrapper::Unwrap(std::uint64_t raw) {
  if (raw == 0) return std::nullopt;
  if (!started_) {
    started_ = true;
    last_raw_ = last_ = raw;
    return last_;
  }
  std::uint64_t delta = 0;
  if (raw > kMaxStandardBlockId || last_raw_ > kMaxStandardBlockId) {
    if (raw <= last_raw_) return std::nullopt;
    delta = raw - last_raw_;
  } else {
    delta = (raw - 1 + kBlockIdModulus - (last_raw_ - 1)) % kBlockIdModulus;
    // Half the id space behind is late (a straggler), not a jump ahead.
    if (delta == 0 || delta > kBlockIdModulus / 2) return std::nullopt;
  }
  last_raw_ = raw;
  last_ += delta;
  return last_;
}

const char* LineScanEndName(LineScanEnd end) {
  switch (end) {
    case LineScanEnd::kGap:
      return "gap";
    case LineScanEnd::kMaxProfiles:
      return "max_profiles";
    case LineScanEnd::kStopped:
      return "stopped";
  }
  return "?";
}

bool LineScanAccount::Clean() const {
  return incomplete_frames.empty() && missing_frames.empty() && refused_frames.empty() &&
         late_buffers == 0 && unidentified_buffers == 0 && buffers_without_line_timestamps == 0;
}

std::string LineScanAccount::Summary() const {
  std::string s = "frames " + std::to_string(first_frame) + "-" + std::to_string(last_frame) +
                  ": " + std::to_string(buffers_delivered) + " buffers, " +
                  std::to_string(profiles) + " profiles";
  if (!incomplete_frames.empty()) {
    s += ", " + std::to_string(incomplete_frames.size()) + " incomplete (" +
         FramesText(incomplete_frames) + ")";
  }
  if (!missing_frames.empty()) s += ", missing " + SequenceRangesText(missing_frames);
  if (!refused_frames.empty()) {
    s += ", " + std::to_string(refused_frames.size()) + " refused (" + FramesText(refused_frames) +
         ")";
  }
  if (late_buffers > 0) s += ", " + std::to_string(late_buffers) + " late";
  if (unidentified_buffers > 0) {
    s += ", " + std::to_string(unidentified_buffers) + " incomplete without block id";
  }
  if (buffers_without_line_timestamps > 0) {
    s += ", " + std::to_string(buffers_without_line_timestamps) + " without line timestamps";
  }
  if (lost_profiles > 0) s += ", " + std::to_string(lost_profiles) + " profiles lost";
  return s + "; ended by " + LineScanEndName(ended_by);
}

nlohmann::json LineScanAccountJson(const LineScanAccount& a) {
  nlohmann::json missing = nlohmann::json::array();
  for (const SequenceRange& r : a.missing_frames) missing.push_back({r.first, r.last});
  return {{"first_frame", a.first_frame},
          {"last_frame", a.last_frame},
          {"buffers_delivered", a.buffers_delivered},
          {"incomplete_frames", a.incomplete_frames},
          {"missing_frames", missing},
          {"refused_frames", a.refused_frames},
          {"late_buffers", a.late_buffers},
          {"unidentified_buffers", a.unidentified_buffers},
          {"buffers_without_line_timestamps", a.buffers_without_line_timestamps},
          {"profiles", a.profiles},
          {"lost_profiles", a.lost_profiles},
          {"ended_by", LineScanEndName(a.ended_by)}};
}

std::vector<Profile> LinesToProfiles(const LineScanBuffer& b, const LineScanOptions& options,
                                     std::uint64_t first_sequence, bool* timed_by_chunk) {
  const std::string what = "line-scan buffer " + std::to_string(b.frame_id);
  if (!Is16Bit(b.pixel_format)) {
    throw InputError(what + ": pixel format " + PixelFormatName(b.pixel_format) +
                     " is not a range format; set the device to Coord3D_C16 or Mono16");
  }
  const std::size_t pixels = static_cast<std::size_t>(b.width) * b.height;
  if (b.image.size() < 2 * pixels) {
    throw InputError(what + ": " + std::to_string(b.image.size()) + " bytes for " +
                     std::to_string(b.width) + " x " + std::to_string(b.height) + " 16-bit pixels");
  }
  const bool chunk = options.line_timestamp_chunk_id != 0 &&
                     b.line_timestamps.size() == 8 * static_cast<std::size_t>(b.height);
  if (timed_by_chunk != nullptr) *timed_by_chunk = chunk;
  const double line_period_ns = options.line_rate_hz > 0.0 ? 1e9 / options.line_rate_hz : 0.0;
  const char* bytes = b.image.data();
  const char* stamps = b.line_timestamps.data();
  std::vector<Profile> profiles;
  profiles.reserve(b.height);
  for (std::uint32_t line = 0; line < b.height; ++line) {
    Profile p = Profile::Empty(b.width);
    p.sequence = first_sequence + line;
    p.timestamp_ns =
        chunk ? static_cast<std::int64_t>(io::GetBe<std::uint64_t>(stamps + 8 * line))
              : b.timestamp_ns + static_cast<std::int64_t>(std::llround(line * line_period_ns));
    const char* row = bytes + 2 * static_cast<std::size_t>(line) * b.width;
    for (std::uint32_t c = 0; c < b.width; ++c) {
      const auto count = io::GetLe<std::uint16_t>(row + 2 * c);
      if (count == options.missing_value) continue;
      p.row_px[c] = static_cast<float>(count * options.row_scale_px + options.row_offset_px);
      p.intensity[c] = options.peak_intensity;
    }
    profiles.push_back(std::move(p));
  }
  return profiles;
}

LineScanAssembler::LineScanAssembler(ProfileHeader header, std::uint32_t lines_per_buffer,
                                     const LineScanOptions& options)
    : header_(std::move(header)), lines_(lines_per_buffer), options_(options) {
  options_.Check();
  header_.Check("line-scan sensor");
  if (header_.joint_count != 0) {
    throw InputError("line-scan sensor: joint_count must be 0 (the camera records no joints)");
  }
  if (lines_ == 0) throw InputError("line-scan sensor: lines per buffer must be >= 1");
}

std::optional<std::uint64_t> LineScanAssembler::Place(std::uint64_t frame_id) {
  const std::optional<std::uint64_t> f = unwrap_.Unwrap(frame_id);
  if (!f) {
    if (open_) ++sweep_.account.late_buffers;
    return std::nullopt;
  }
  LineScanAccount& a = sweep_.account;
  if (!open_) {
    open_ = true;
    sweep_ = LineScanSweep{};
    sweep_.set.header = header_;
    sweep_.account.first_frame = *f;
    next_frame_ = *f;
  }
  if (*f > next_frame_) {
    a.missing_frames.push_back({next_frame_, *f - 1});
    a.lost_profiles += (*f - next_frame_) * lines_;
    // Buffers that arrived incomplete without a block id left their ids in this gap.
    unplaced_unidentified_ -= std::min<std::uint64_t>(unplaced_unidentified_, *f - next_frame_);
  }
  a.last_frame = *f;
  next_frame_ = *f + 1;
  return f;
}

std::optional<LineScanSweep> LineScanAssembler::AddComplete(const LineScanBuffer& b) {
  const std::optional<std::uint64_t> f = Place(b.frame_id);
  if (!f) return std::nullopt;
  LineScanAccount& a = sweep_.account;
  if (!Is16Bit(b.pixel_format) || b.width != header_.columns ||
      b.x_offset != header_.first_column || b.height != lines_ ||
      b.image.size() < 2 * static_cast<std::size_t>(b.width) * b.height) {
    a.refused_frames.push_back(*f);
    a.lost_profiles += lines_;
    return std::nullopt;
  }
  bool chunk = false;
  std::vector<Profile> lines = LinesToProfiles(b, options_, *f * lines_, &chunk);
  if (options_.line_timestamp_chunk_id != 0 && !chunk) ++a.buffers_without_line_timestamps;
  for (Profile& p : lines) sweep_.set.profiles.push_back(std::move(p));
  ++a.buffers_delivered;
  if (sweep_.set.profiles.size() >= options_.max_sweep_profiles) {
    return TakeSweep(LineScanEnd::kMaxProfiles);
  }
  return std::nullopt;
}

void LineScanAssembler::AddIncomplete(std::uint64_t frame_id) {
  if (frame_id == 0) {
    if (!open_) {
      open_ = true;
      sweep_ = LineScanSweep{};
      sweep_.set.header = header_;
    }
    ++sweep_.account.unidentified_buffers;
    ++unplaced_unidentified_;  // its lines are lost; counted by the gap it leaves, or at the end
    return;
  }
  const std::optional<std::uint64_t> f = Place(frame_id);
  if (!f) return;
  sweep_.account.incomplete_frames.push_back(*f);
  sweep_.account.lost_profiles += lines_;
}

std::optional<LineScanSweep> LineScanAssembler::Finish(LineScanEnd end) {
  if (!open_) return std::nullopt;
  return TakeSweep(end);
}

LineScanSweep LineScanAssembler::TakeSweep(LineScanEnd end) {
  sweep_.account.profiles = sweep_.set.profiles.size();
  sweep_.account.lost_profiles += unplaced_unidentified_ * lines_;
  unplaced_unidentified_ = 0;
  sweep_.account.ended_by = end;
  open_ = false;
  LineScanSweep out = std::move(sweep_);
  sweep_ = LineScanSweep{};
  return out;
}

}  // namespace lasercell::triangulation
