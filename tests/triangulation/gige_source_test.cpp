// GigE Vision line-scan streams through Aravis on loopback (triangulation/gige_source.hpp):
// Aravis's own fake camera, and our seeded device (gige_test_device.hpp) that loses, reorders,
// duplicates and refuses resends; `scan record --gige` as a process. Tests that open GVCP port
// 3956 are in the suites GigeProfileSource and ImpairedGigeStream, which ctest runs one at a time
// (RESOURCE_LOCK in tests/CMakeLists.txt).
#include "triangulation/gige_source.hpp"

#include <arv.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>

#include "core/error.hpp"
#include "tests/cli_util.hpp"
#include "tests/sanitizer_scale.hpp"
#include "tests/triangulation/gige_test_device.hpp"
#include "triangulation/profile_io.hpp"

namespace lasercell::triangulation {
namespace {

// The count a pixel of line `line`, column `c` of frame `f` holds; every 7th column has no peak.
std::uint16_t PatternCount(std::uint64_t f, std::uint32_t line, std::uint32_t c) {
  if (c % 7 == 3) return 0;
  return static_cast<std::uint16_t>(1 + (f * 131 + line * 17 + c * 3) % 16000);
}

// Fills the fake camera's Mono16 buffers with PatternCount. The buffer's data block holds
// width * height 16-bit pixels (the fake camera allocates its payload).
void FillPattern(ArvBuffer* buffer, void*, guint32, guint32, ArvPixelFormat) {
  const std::uint64_t f = arv_buffer_get_frame_id(buffer);
  const auto width = static_cast<std::uint32_t>(arv_buffer_get_image_width(buffer));
  const auto height = static_cast<std::uint32_t>(arv_buffer_get_image_height(buffer));
  size_t size = 0;
  auto* data = static_cast<unsigned char*>(const_cast<void*>(arv_buffer_get_data(buffer, &size)));
  for (std::uint32_t line = 0; line < height; ++line) {
    for (std::uint32_t c = 0; c < width; ++c) {
      const std::uint16_t v = PatternCount(f, line, c);
      data[2 * (line * width + c)] = static_cast<unsigned char>(v & 0xff);
      data[2 * (line * width + c) + 1] = static_cast<unsigned char>(v >> 8);
    }
  }
}

// Every profile equals the pattern of its frame (sequence / lines).
void ExpectPattern(const LineScanSweep& sweep, std::uint32_t lines, double scale) {
  for (const Profile& p : sweep.set.profiles) {
    const std::uint64_t f = p.sequence / lines;
    const auto line = static_cast<std::uint32_t>(p.sequence % lines);
    for (std::size_t c = 0; c < p.row_px.size(); ++c) {
      const std::uint16_t v = PatternCount(f, line, static_cast<std::uint32_t>(c));
      if (v == 0) {
        ASSERT_TRUE(std::isnan(p.row_px[c])) << "frame " << f << " line " << line;
      } else {
        ASSERT_FLOAT_EQ(p.row_px[c], static_cast<float>(v * scale))
            << "frame " << f << " line " << line << " column " << c;
      }
    }
  }
}

std::uint64_t LineTimestampNs(std::uint64_t f, std::uint64_t line) {
  return 1'000'000'000ULL + f * 4'000'000ULL + line * 250'000ULL + (f * 7 + line * 13) % 97;
}

struct FakeCamera {
  explicit FakeCamera(double lost_packet_ratio) {
    g_random_set_seed(20261205);  // the fake camera's losses come from GLib's global generator
    camera = arv_gv_fake_camera_new("127.0.0.1", "LCFAKE");
    ArvFakeCamera* fake = arv_gv_fake_camera_get_fake_camera(camera);
    arv_fake_camera_set_fill_pattern(fake, FillPattern, nullptr);
    arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_ACQUISITION_FRAME_PERIOD_US,
                                   4000);  // 250 buffers/s
    g_object_set(camera, "gvsp-lost-ratio", lost_packet_ratio, nullptr);
  }
  ~FakeCamera() { g_object_unref(camera); }
  ArvGvFakeCamera* camera;
};

GigeSourceOptions FakeOptions() {
  GigeSourceOptions o;
  o.device = "127.0.0.1";
  o.pixel_format = "Mono16";
  o.lines_per_buffer = 16;
  o.line_scan.line_rate_hz = 4000.0;  // 250 buffers/s x 16 lines
  o.line_scan.max_sweep_profiles = 16 * 60;
  o.image_height = 1024;
  // The fake camera runs in this process: under a sanitizer it can pause longer than the default
  // gap between two buffers, which would end the sweep early.
  if (test::kSanitizerBuild) o.sweep_gap_ms = 2000.0;
  return o;
}

TEST(GigeProfileSource, TheFakeCamerasBuffersArriveIntactAsProfiles) {
  FakeCamera fake(0.0);
  GigeProfileSource source(FakeOptions());
  EXPECT_NE(source.Describe().find("Aravis Fake LCFAKE"), std::string::npos) << source.Describe();
  EXPECT_EQ(source.header().columns, 512u);       // the fake camera's Width
  EXPECT_EQ(source.header().image_width, 2048u);  // its SensorWidth
  EXPECT_NE(source.header().metadata.find("pixel_format: \"Mono16\""), std::string::npos);
  const std::optional<LineScanSweep> sweep = source.NextLineScanSweep();
  ASSERT_TRUE(sweep);
  EXPECT_EQ(sweep->account.ended_by, LineScanEnd::kMaxProfiles);
  EXPECT_TRUE(sweep->account.Clean()) << sweep->account.Summary();
  EXPECT_EQ(sweep->set.profiles.size(), 16u * 60u);
  ExpectPattern(*sweep, 16, 1.0 / 16.0);
  // Lines are timed by the line rate from each buffer's timestamp.
  const auto& p = sweep->set.profiles;
  EXPECT_EQ(p[1].timestamp_ns - p[0].timestamp_ns, 250'000);
  const GigeStreamCounters c = source.counters();
  EXPECT_GE(c.completed_buffers, 60u) << c.Summary();
  EXPECT_EQ(c.missing_packets, 0u) << c.Summary();
}

TEST(GigeProfileSource, TheFakeCamerasRandomLossesAreAccountedBufferByBuffer) {
  FakeCamera fake(0.01);  // 1 % of GVSP packets; it never answers resends
  GigeSourceOptions o = FakeOptions();
  o.frame_retention_ms = 60.0;
  GigeProfileSource source(o);
  const std::optional<LineScanSweep> sweep = source.NextLineScanSweep();
  ASSERT_TRUE(sweep);
  const LineScanAccount& a = sweep->account;
  // Every frame between the first and the last is delivered intact or accounted as lost.
  std::uint64_t missing = 0;
  for (const SequenceRange& r : a.missing_frames) missing += r.last - r.first + 1;
  EXPECT_EQ(a.buffers_delivered + a.incomplete_frames.size() + missing + a.refused_frames.size(),
            a.last_frame - a.first_frame + 1)
      << a.Summary();
  EXPECT_GT(a.incomplete_frames.size() + a.unidentified_buffers + missing, 0u) << a.Summary();
  EXPECT_EQ(a.profiles, a.buffers_delivered * 16u);
  ExpectPattern(*sweep, 16, 1.0 / 16.0);
  EXPECT_FALSE(source.LastSweepLoss().empty());
  const GigeStreamCounters c = source.counters();
  EXPECT_GT(c.failures, 0u);
  const std::pair<const char*, std::uint64_t> numbers[] = {
      {"frames_in_sweep", a.last_frame - a.first_frame + 1},
      {"delivered_frames", a.buffers_delivered},
      {"account_incomplete_frames", a.incomplete_frames.size()},
      {"account_missing_frames", missing},
      {"account_unidentified_buffers", a.unidentified_buffers},
      {"account_lost_profiles", a.lost_profiles},
      {"aravis_completed", c.completed_buffers},
      {"aravis_failures", c.failures},
      {"aravis_missing_packets", c.missing_packets},
      {"aravis_resend_requests", c.resend_requests}};
  for (const auto& [name, value] : numbers) RecordProperty(name, std::to_string(value));
}

// Frames for our device: frame k is block id k+1 with PatternCount pixels and, per line, a
// timestamp 250 us apart with a jitter the line rate could not predict.
std::vector<testing::GigeTestFrame> DeviceFrames(std::size_t count, std::uint32_t width,
                                                 std::uint32_t lines, bool timestamps) {
  std::vector<testing::GigeTestFrame> frames(count);
  for (std::size_t k = 0; k < count; ++k) {
    for (std::uint32_t line = 0; line < lines; ++line) {
      for (std::uint32_t c = 0; c < width; ++c) {
        frames[k].pixels.push_back(PatternCount(k + 1, line, c));
      }
      if (timestamps) frames[k].line_timestamps_ns.push_back(LineTimestampNs(k + 1, line));
    }
  }
  return frames;
}

// The seeds of our impairing device: each loses, reorders and duplicates 2 % of packets and
// refuses 30 % of resend requests, so some frames cannot be repaired. Each run's numbers are
// recorded as test properties; scripts/gige-table prints them as BENCHMARKS.md's table.
class ImpairedGigeStream : public ::testing::TestWithParam<std::uint32_t> {};

TEST_P(ImpairedGigeStream, DeliveredExactlyWhereResendsCouldRepairIt) {
  testing::GigeTestDeviceOptions d;
  d.address = "127.0.0.2";
  d.width = 256;
  d.height = 16;
  d.line_timestamp_chunk_id = 0x4C540001;
  d.frame_rate_hz = 250.0;
  d.loss = d.reorder = d.duplicate = 0.02;
  d.resend_refusal = 0.3;
  d.seed = GetParam();
  constexpr std::size_t kFrames = 80;
  testing::GigeTestDevice device(d, DeviceFrames(kFrames, d.width, d.height, true));
  GigeSourceOptions o;
  o.device = d.address;
  o.line_scan.line_timestamp_chunk_id = d.line_timestamp_chunk_id;
  o.frame_retention_ms = 100.0;
  o.sweep_gap_ms = 400.0;
  o.image_height = 1024;
  GigeProfileSource source(o);
  const std::optional<LineScanSweep> sweep = source.NextLineScanSweep();
  ASSERT_TRUE(sweep);
  // The device's report is compared with Aravis's counters below: let the last resend requests
  // (Aravis keeps asking for a frame while it holds it) be answered and counted on both sides
  // first. Without the linger, a sanitizer-build run once counted 11 resent packets on Aravis's
  // side against the device's 10: one answered after the report was taken.
  ASSERT_TRUE(device.WaitSent(5000, 300));
  const testing::GigeTestDeviceReport report = device.Report();
  ASSERT_GT(report.dropped, 0u);
  ASSERT_GT(report.refused, 0u);
  // What a correct receiver must deliver: every frame whose dropped packets were all resent.
  std::set<std::uint64_t> unrecoverable;
  for (const auto& f : report.frames) {
    if (f.unrecoverable) unrecoverable.insert(f.frame_id);
  }
  ASSERT_FALSE(unrecoverable.empty()) << "this seed refuses no needed resend: choose another";
  std::set<std::uint64_t> delivered;
  for (const Profile& p : sweep->set.profiles) delivered.insert(p.sequence / d.height);
  std::set<std::uint64_t> not_delivered;
  for (std::uint64_t f = 1; f <= kFrames; ++f) {
    if (delivered.count(f) == 0) not_delivered.insert(f);
  }
  EXPECT_EQ(not_delivered, unrecoverable);
  // Delivered buffers are intact, their lines timed by the chunk.
  ExpectPattern(*sweep, d.height, 1.0 / 16.0);
  for (const Profile& p : sweep->set.profiles) {
    ASSERT_EQ(p.timestamp_ns, static_cast<std::int64_t>(
                                  LineTimestampNs(p.sequence / d.height, p.sequence % d.height)));
  }
  // The account names every frame that was not delivered (by its block id, or by the gap an
  // id-less incomplete buffer left) and the profiles it held.
  const LineScanAccount& a = sweep->account;
  std::set<std::uint64_t> accounted(a.incomplete_frames.begin(), a.incomplete_frames.end());
  for (const SequenceRange& r : a.missing_frames) {
    for (std::uint64_t f = r.first; f <= r.last; ++f) accounted.insert(f);
  }
  EXPECT_EQ(accounted, unrecoverable) << a.Summary();
  EXPECT_EQ(a.lost_profiles, unrecoverable.size() * d.height) << a.Summary();
  EXPECT_EQ(a.buffers_without_line_timestamps, 0u);
  // Aravis's counters agree with what the device did.
  const GigeStreamCounters c = source.counters();
  EXPECT_EQ(c.resent_packets, report.resent) << c.Summary();
  EXPECT_EQ(c.completed_buffers, kFrames - unrecoverable.size()) << c.Summary();
  EXPECT_EQ(c.underruns, 0u) << c.Summary();
  EXPECT_GT(c.duplicated_packets, 0u) << c.Summary();
  std::uint64_t missing = 0;
  for (const SequenceRange& r : a.missing_frames) missing += r.last - r.first + 1;
  const std::pair<const char*, std::uint64_t> numbers[] = {
      {"frames_sent", kFrames},
      {"device_packets", report.packets_sent},
      {"device_dropped", report.dropped},
      {"device_duplicated", report.duplicated},
      {"device_reordered", report.reordered},
      {"device_resent", report.resent},
      {"device_refused", report.refused},
      {"unrecoverable_frames", unrecoverable.size()},
      {"delivered_frames", a.buffers_delivered},
      {"account_incomplete_frames", a.incomplete_frames.size()},
      {"account_missing_frames", missing},
      {"account_lost_profiles", a.lost_profiles},
      {"delivered_equals_repairable", not_delivered == unrecoverable ? 1u : 0u},
      {"account_equals_unrepairable", accounted == unrecoverable ? 1u : 0u},
      {"aravis_completed", c.completed_buffers},
      {"aravis_failures", c.failures},
      {"aravis_timeouts", c.timeouts},
      {"aravis_missing_packets", c.missing_packets},
      {"aravis_resent_packets", c.resent_packets},
      {"aravis_duplicated_packets", c.duplicated_packets},
      {"aravis_underruns", c.underruns}};
  for (const auto& [name, value] : numbers) RecordProperty(name, std::to_string(value));
}

INSTANTIATE_TEST_SUITE_P(GigeProfileSource, ImpairedGigeStream,
                         ::testing::Values(3u, 11u, 23u, 42u),
                         [](const auto& info) { return "seed" + std::to_string(info.param); });

TEST(GigeProfileSource, ScanRecordWritesTheSweepAndItsAccountFromTheCommandLine) {
  testing::GigeTestDeviceOptions d;
  d.address = "127.0.0.3";
  d.serial = "LCCLI";
  d.width = 128;
  d.height = 8;
  d.frame_rate_hz = 250.0;
  testing::GigeTestDevice device(d, DeviceFrames(30, d.width, d.height, false));
  const std::filesystem::path dir = test::MakeTestDir("gige_cli");
  const std::string out = (dir / "sweep.lcp").string();
  const std::string account = (dir / "account.json").string();
  const test::CommandResult r = test::RunCli(
      "scan record --gige 127.0.0.3 --line-rate 2000 --image-height 1024 "
      "--sweep-gap-ms 300 --timeout-s 5 --out '" +
      out + "' --account-json '" + account + "'");
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("Aravis Fake LCCLI"), std::string::npos) << r.out;
  const ProfileSet set = ReadProfiles(out);
  ASSERT_EQ(set.profiles.size(), 30u * 8u);
  EXPECT_EQ(set.header.columns, 128u);
  EXPECT_NE(set.header.metadata.find("pixel_format: \"Coord3D_C16\""), std::string::npos);
  ExpectPattern(LineScanSweep{set, {}}, 8, 1.0 / 16.0);
  // Lines of a buffer are 1/2000 s apart.
  EXPECT_EQ(set.profiles[1].timestamp_ns - set.profiles[0].timestamp_ns, 500'000);
  std::ifstream in(account);
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["line_scan"]["buffers_delivered"], 30);
  EXPECT_EQ(j["line_scan"]["lost_profiles"], 0);
  EXPECT_EQ(j["gige_counters"]["completed_buffers"], 30);
  // Asking for a pixel format the device refuses exits 2 with one line naming the device.
  const test::CommandResult bad = test::RunCli(
      "scan record --gige 127.0.0.3 --pixel-format Mono8 --line-rate 2000 --out '" + out + "'");
  EXPECT_EQ(bad.exit_code, 2) << bad.out << bad.err;
  EXPECT_NE(bad.err.find("127.0.0.3"), std::string::npos) << bad.err;
  test::RemoveTestDir(dir);
}

TEST(GigeProfileSource, ADeviceThatIsNotThereIsNamed) {
  GigeSourceOptions o;
  o.device = "127.0.0.77";
  o.line_scan.line_rate_hz = 1000.0;
  try {
    GigeProfileSource source(o);
    FAIL() << "opened a device that does not exist";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("127.0.0.77"), std::string::npos) << e.what();
  }
  o.device = "";
  EXPECT_THROW(GigeProfileSource{o}, OptionError);
}

}  // namespace
}  // namespace lasercell::triangulation
