// Line-scan buffers to profiles and sweeps (triangulation/line_scan.hpp), with plain bytes.
#include "triangulation/line_scan.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/io/byte_order.hpp"

namespace lasercell::triangulation {
namespace {

constexpr std::uint32_t kWidth = 6;
constexpr std::uint32_t kLines = 4;

// Pixel (line, column) of frame f: a count that encodes all three; column 2 has no peak.
std::uint16_t Count(std::uint64_t f, std::uint32_t line, std::uint32_t c) {
  return c == 2 ? 0 : static_cast<std::uint16_t>(1000 + 100 * (f % 7) + 10 * line + c);
}

std::string Image(std::uint64_t f) {
  std::string bytes;
  for (std::uint32_t line = 0; line < kLines; ++line) {
    for (std::uint32_t c = 0; c < kWidth; ++c) io::PutLe<std::uint16_t>(&bytes, Count(f, line, c));
  }
  return bytes;
}

LineScanBuffer Buffer(std::uint64_t frame_id, const std::string& image) {
  LineScanBuffer b;
  b.frame_id = frame_id;
  b.timestamp_ns = 1'000'000 * static_cast<std::int64_t>(frame_id);
  b.pixel_format = kPixelFormatCoord3dC16;
  b.width = kWidth;
  b.height = kLines;
  b.x_offset = 10;
  b.image = image;
  return b;
}

ProfileHeader Header() {
  ProfileHeader h;
  h.image_width = 64;
  h.image_height = 512;
  h.first_column = 10;
  h.columns = kWidth;
  return h;
}

TEST(LineScan, PixelsBecomePeakRowsAndLinesAreTimedByTheLineRate) {
  LineScanOptions options;
  options.row_scale_px = 1.0 / 16.0;
  options.row_offset_px = 2.0;
  options.line_rate_hz = 4000.0;  // 250 us per line
  const std::string image = Image(3);
  bool by_chunk = true;
  const std::vector<Profile> lines = LinesToProfiles(Buffer(3, image), options, 100, &by_chunk);
  EXPECT_FALSE(by_chunk);
  ASSERT_EQ(lines.size(), kLines);
  for (std::uint32_t line = 0; line < kLines; ++line) {
    const Profile& p = lines[line];
    EXPECT_EQ(p.sequence, 100 + line);
    EXPECT_EQ(p.timestamp_ns, 3'000'000 + 250'000 * static_cast<std::int64_t>(line));
    for (std::uint32_t c = 0; c < kWidth; ++c) {
      if (c == 2) {
        EXPECT_TRUE(std::isnan(p.row_px[c]));
        EXPECT_EQ(p.intensity[c], 0.0f);
      } else {
        EXPECT_FLOAT_EQ(p.row_px[c], Count(3, line, c) / 16.0f + 2.0f) << line << " " << c;
        EXPECT_EQ(p.intensity[c], 1.0f);
      }
    }
  }
}

TEST(LineScan, ATimestampChunkTimesEveryLine) {
  LineScanOptions options;
  options.line_timestamp_chunk_id = 0x4C540001;
  std::string stamps;
  const std::int64_t t[kLines] = {5'000'017, 5'000'391, 5'000'700, 5'001'333};  // irregular
  for (std::uint32_t i = 0; i < kLines; ++i) io::PutBe<std::uint64_t>(&stamps, t[i]);
  const std::string image = Image(1);
  LineScanBuffer b = Buffer(1, image);
  b.line_timestamps = stamps;
  bool by_chunk = false;
  const std::vector<Profile> lines = LinesToProfiles(b, options, 0, &by_chunk);
  EXPECT_TRUE(by_chunk);
  for (std::uint32_t i = 0; i < kLines; ++i) EXPECT_EQ(lines[i].timestamp_ns, t[i]);
  // A chunk of the wrong size is not used: lines fall back to the buffer's timestamp.
  b.line_timestamps = std::string_view(stamps).substr(0, 8 * kLines - 8);
  const std::vector<Profile> fallback = LinesToProfiles(b, options, 0, &by_chunk);
  EXPECT_FALSE(by_chunk);
  EXPECT_EQ(fallback[3].timestamp_ns, b.timestamp_ns);
}

TEST(LineScan, BuffersThatAreNotRangesOrTooShortAreRefusedByName) {
  const std::string image = Image(1);
  LineScanBuffer b = Buffer(9, image);
  b.pixel_format = 0x01080001;  // Mono8
  try {
    LinesToProfiles(b, LineScanOptions{}, 0);
    FAIL() << "Mono8 accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("buffer 9"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("0x01080001"), std::string::npos) << e.what();
  }
  b = Buffer(9, image);
  b.image = std::string_view(image).substr(0, image.size() - 1);
  EXPECT_THROW(LinesToProfiles(b, LineScanOptions{}, 0), InputError);
}

TEST(LineScan, OptionsNameTheWrongField) {
  const auto message = [](const LineScanOptions& o) {
    try {
      o.Check();
    } catch (const OptionError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  LineScanOptions o;
  o.row_scale_px = 0.0;
  EXPECT_NE(message(o).find("row_scale_px"), std::string::npos);
  o = {};
  o.peak_intensity = 1.5f;
  EXPECT_NE(message(o).find("peak_intensity"), std::string::npos);
  o = {};
  o.line_rate_hz = -1.0;
  EXPECT_NE(message(o).find("line_rate_hz"), std::string::npos);
  o = {};
  o.max_sweep_profiles = 0;
  EXPECT_NE(message(o).find("max_sweep_profiles"), std::string::npos);
}

TEST(FrameIdUnwrap, SixteenBitIdsSkipZeroAndKeepCounting) {
  FrameIdUnwrapper u;
  EXPECT_EQ(u.Unwrap(0), std::nullopt);  // never valid
  EXPECT_EQ(u.Unwrap(65533), 65533u);
  EXPECT_EQ(u.Unwrap(65535), 65535u);        // 65534 lost
  EXPECT_EQ(u.Unwrap(1), 65536u);            // 0 is skipped on wrap
  EXPECT_EQ(u.Unwrap(1), std::nullopt);      // duplicate
  EXPECT_EQ(u.Unwrap(65535), std::nullopt);  // late
  EXPECT_EQ(u.Unwrap(3), 65538u);
  FrameIdUnwrapper extended;  // GigE Vision 2 64-bit ids
  EXPECT_EQ(extended.Unwrap(70000), 70000u);
  EXPECT_EQ(extended.Unwrap(70002), 70002u);
  EXPECT_EQ(extended.Unwrap(70001), std::nullopt);
}

TEST(LineScanSweeps, LostBuffersAreGapsOfWholeBuffersAndEveryKindIsAccounted) {
  LineScanOptions options;
  options.line_rate_hz = 1000.0;
  LineScanAssembler assembler(Header(), kLines, options);
  std::vector<std::string> images;
  for (int f = 0; f < 10; ++f) images.push_back(Image(f));
  EXPECT_FALSE(assembler.AddComplete(Buffer(1, images[1])));
  EXPECT_FALSE(assembler.AddComplete(Buffer(2, images[2])));
  // 3 and 4 never arrive; 5 arrives incomplete; 6 has another width; 7 is fine; 2 comes late.
  assembler.AddIncomplete(5);
  LineScanBuffer wide = Buffer(6, images[6]);
  wide.width = kWidth - 1;
  EXPECT_FALSE(assembler.AddComplete(wide));
  EXPECT_FALSE(assembler.AddComplete(Buffer(7, images[7])));
  EXPECT_FALSE(assembler.AddComplete(Buffer(2, images[2])));
  const std::optional<LineScanSweep> sweep = assembler.Finish(LineScanEnd::kGap);
  ASSERT_TRUE(sweep);
  EXPECT_FALSE(assembler.open());
  const LineScanAccount& a = sweep->account;
  EXPECT_EQ(a.first_frame, 1u);
  EXPECT_EQ(a.last_frame, 7u);
  EXPECT_EQ(a.buffers_delivered, 3u);
  EXPECT_EQ(a.missing_frames, (std::vector<SequenceRange>{{3, 4}}));
  EXPECT_EQ(a.incomplete_frames, (std::vector<std::uint64_t>{5}));
  EXPECT_EQ(a.refused_frames, (std::vector<std::uint64_t>{6}));
  EXPECT_EQ(a.late_buffers, 1u);
  EXPECT_EQ(a.lost_profiles, 4u * kLines);
  EXPECT_EQ(a.profiles, 3u * kLines);
  EXPECT_FALSE(a.Clean());
  EXPECT_NE(a.Summary().find("missing 3-4"), std::string::npos) << a.Summary();
  // Profiles keep their frame's sequence numbers, so the gap shows in the sweep itself.
  ASSERT_EQ(sweep->set.profiles.size(), 3u * kLines);
  EXPECT_EQ(sweep->set.profiles[kLines].sequence, 2u * kLines);
  EXPECT_EQ(sweep->set.profiles[2 * kLines].sequence, 7u * kLines);
  EXPECT_FLOAT_EQ(sweep->set.profiles[2 * kLines].row_px[0], Count(7, 0, 0) / 16.0f);
  const nlohmann::json j = LineScanAccountJson(a);
  EXPECT_EQ(j["missing_frames"], nlohmann::json::parse("[[3, 4]]"));
  EXPECT_EQ(j["ended_by"], "gap");
}

TEST(LineScanSweeps, IdlessIncompleteBuffersAreLostOnceWhetherAGapShowsThemOrNot) {
  LineScanOptions options;
  options.line_rate_hz = 1000.0;
  LineScanAssembler assembler(Header(), kLines, options);
  const std::string image = Image(0);
  assembler.AddComplete(Buffer(1, image));
  assembler.AddIncomplete(0);  // frame 2's leader was lost: Aravis cannot name it
  assembler.AddComplete(Buffer(3, image));
  assembler.AddIncomplete(0);  // frame 4, the last one: no later buffer shows its gap
  const LineScanSweep sweep = *assembler.Finish(LineScanEnd::kStopped);
  EXPECT_EQ(sweep.account.unidentified_buffers, 2u);
  EXPECT_EQ(sweep.account.missing_frames, (std::vector<SequenceRange>{{2, 2}}));
  EXPECT_EQ(sweep.account.lost_profiles, 2u * kLines);
}

TEST(LineScanSweeps, ASweepEndsAtMaxProfilesAndTheNextContinuesTheSequence) {
  LineScanOptions options;
  options.line_rate_hz = 1000.0;
  options.max_sweep_profiles = 2 * kLines;
  LineScanAssembler assembler(Header(), kLines, options);
  const std::string image = Image(0);
  EXPECT_FALSE(assembler.AddComplete(Buffer(65534, image)));
  const std::optional<LineScanSweep> first = assembler.AddComplete(Buffer(65535, image));
  ASSERT_TRUE(first);
  EXPECT_EQ(first->account.ended_by, LineScanEnd::kMaxProfiles);
  EXPECT_TRUE(first->account.Clean());
  EXPECT_FALSE(assembler.AddComplete(Buffer(1, image)));  // the id wrapped, skipping 0
  const LineScanSweep second = *assembler.Finish(LineScanEnd::kGap);
  EXPECT_EQ(second.account.first_frame, 65536u);
  EXPECT_EQ(second.set.profiles.front().sequence, 65536u * kLines);
  EXPECT_EQ(assembler.Finish(LineScanEnd::kGap), std::nullopt);
}

TEST(LineScanSweeps, ASensorWithJointsOrNoLinesIsRefused) {
  ProfileHeader h = Header();
  h.joint_count = 6;
  EXPECT_THROW(LineScanAssembler(h, kLines, LineScanOptions{}), InputError);
  EXPECT_THROW(LineScanAssembler(Header(), 0, LineScanOptions{}), InputError);
}

}  // namespace
}  // namespace lasercell::triangulation
