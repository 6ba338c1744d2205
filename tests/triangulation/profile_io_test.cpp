#include "triangulation/profile_io.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include "core/error.hpp"
#include "core/io/file_util.hpp"
#include "tests/cli_util.hpp"
#include "triangulation/profile_source.hpp"

namespace lasercell::triangulation {
namespace {

ProfileSet MakeSet(std::uint32_t columns, std::uint32_t joints, int profiles) {
  ProfileSet set;
  set.header.image_width = 1024;
  set.header.image_height = 1024;
  set.header.first_column = 1024 - columns;
  set.header.columns = columns;
  set.header.joint_count = joints;
  set.header.robot = joints > 0 ? "vision_robot" : "";
  set.header.metadata = "capture: test\nnote: \"quoted\" text\n";
  for (int i = 0; i < profiles; ++i) {
    Profile p = Profile::Empty(columns, joints);
    p.sequence = 1000 + static_cast<std::uint64_t>(i);
    p.timestamp_ns = -5 + 10'000'123LL * i;  // negative values are legal
    for (std::uint32_t j = 0; j < joints; ++j) p.joints_rad[j] = 0.1 * j - 1.0 / (i + 3);
    for (std::uint32_t c = 0; c < columns; ++c) {
      if ((c + i) % 7 == 0) continue;  // no peak
      p.row_px[c] = 100.0f + 0.3137f * c + 1e-3f * i;
      p.intensity[c] = 1.0f / (1 + c);
      p.width_px[c] = 2.5f + 0.01f * c;
    }
    set.profiles.push_back(std::move(p));
  }
  return set;
}

bool SameBits(float a, float b) { return std::memcmp(&a, &b, sizeof(float)) == 0; }

void ExpectBitIdentical(const ProfileSet& a, const ProfileSet& b) {
  EXPECT_EQ(a.header.image_width, b.header.image_width);
  EXPECT_EQ(a.header.image_height, b.header.image_height);
  EXPECT_EQ(a.header.first_column, b.header.first_column);
  EXPECT_EQ(a.header.columns, b.header.columns);
  EXPECT_EQ(a.header.joint_count, b.header.joint_count);
  EXPECT_EQ(a.header.robot, b.header.robot);
  EXPECT_EQ(a.header.metadata, b.header.metadata);
  ASSERT_EQ(a.profiles.size(), b.profiles.size());
  for (std::size_t i = 0; i < a.profiles.size(); ++i) {
    const Profile& p = a.profiles[i];
    const Profile& q = b.profiles[i];
    EXPECT_EQ(p.sequence, q.sequence);
    EXPECT_EQ(p.timestamp_ns, q.timestamp_ns);
    ASSERT_EQ(p.joints_rad.size(), q.joints_rad.size());
    for (std::size_t j = 0; j < p.joints_rad.size(); ++j) {
      EXPECT_EQ(std::memcmp(&p.joints_rad[j], &q.joints_rad[j], sizeof(double)), 0);
    }
    ASSERT_EQ(p.row_px.size(), q.row_px.size());
    for (std::size_t c = 0; c < p.row_px.size(); ++c) {
      EXPECT_TRUE(SameBits(p.row_px[c], q.row_px[c])) << "profile " << i << " column " << c;
      EXPECT_TRUE(SameBits(p.intensity[c], q.intensity[c]));
      EXPECT_TRUE(SameBits(p.width_px[c], q.width_px[c]));
    }
  }
}

template <typename F>
std::string FileErrorMessage(F&& f) {
  try {
    f();
  } catch (const FileError& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("wrong exception type: ") + e.what();
  }
  return "no exception";
}

TEST(ProfileIo, RoundTripIsBitExactWithJoints) {
  const ProfileSet set = MakeSet(640, 6, 25);
  const std::string bytes = EncodeProfiles(set);
  const std::size_t header = bytes.size() - 25 * ProfileRecordBytes(set.header);
  EXPECT_EQ(header % 8, 0u);
  EXPECT_EQ(ProfileRecordBytes(set.header), 16u + 48u + 12u * 640u);
  const ProfileSet back = DecodeProfiles(bytes, "memory");
  ExpectBitIdentical(set, back);
  // Re-encoding gives the same bytes.
  EXPECT_EQ(EncodeProfiles(back), bytes);
}

TEST(ProfileIo, RoundTripThroughFileWithoutJoints) {
  const ProfileSet set = MakeSet(1024, 0, 3);
  const test::TestDir dir("profile_io");
  const std::string path = dir.File("plain.lcp");
  WriteProfiles(path, set);
  const ProfileSet back = ReadProfiles(path);
  ExpectBitIdentical(set, back);
  EXPECT_EQ(back.profiles[0].ValidCount(), 1024u - 147u);  // c % 7 == 0 has no peak
  EXPECT_TRUE(std::isnan(back.profiles[0].row_px[0]));
}

TEST(ProfileIo, AFileSourceDeliversTheFileAsOneSweepThenNothing) {
  const ProfileSet set = MakeSet(64, 6, 5);
  const test::TestDir dir("profile_source");
  const std::string path = dir.File("sweep.lcp");
  WriteProfiles(path, set);
  FileProfileSource source(path);
  EXPECT_EQ(source.Describe(), "file " + path);
  const std::optional<ProfileSet> sweep = source.NextSweep();
  ASSERT_TRUE(sweep.has_value());
  ExpectBitIdentical(set, *sweep);
  EXPECT_FALSE(source.NextSweep().has_value());
  FileProfileSource missing(dir.File("missing.lcp"));
  EXPECT_THROW(missing.NextSweep(), FileError);
}

TEST(ProfileIo, EmptySetRoundTrips) {
  ProfileSet set;
  set.header.columns = 16;
  set.header.image_width = 16;
  const ProfileSet back = DecodeProfiles(EncodeProfiles(set), "empty");
  EXPECT_TRUE(back.profiles.empty());
  EXPECT_EQ(back.header.columns, 16u);
}

TEST(ProfileIo, LayoutMatchesTheSpec) {
  ProfileSet set = MakeSet(4, 1, 1);
  set.header.robot = "r";
  set.header.metadata = "";
  set.header.first_column = 3;
  set.header.image_width = 7;
  const std::string bytes = EncodeProfiles(set);
  ASSERT_EQ(bytes.substr(0, 8), std::string("\x89LCPROF\n", 8));
  std::uint32_t version, header_bytes, columns, first_column;
  std::memcpy(&version, bytes.data() + 8, 4);
  std::memcpy(&header_bytes, bytes.data() + 12, 4);
  std::memcpy(&first_column, bytes.data() + 24, 4);
  std::memcpy(&columns, bytes.data() + 28, 4);
  EXPECT_EQ(version, 1u);
  EXPECT_EQ(header_bytes, 64u);  // 48 + 4 + 1 + 4 = 57, padded to 64
  EXPECT_EQ(first_column, 3u);
  EXPECT_EQ(columns, 4u);
  EXPECT_EQ(bytes.size(), 64u + 16u + 8u + 12u * 4u);
  std::uint64_t sequence;
  std::memcpy(&sequence, bytes.data() + 64, 8);
  EXPECT_EQ(sequence, 1000u);
  float row1;
  std::memcpy(&row1, bytes.data() + 64 + 16 + 8 + 4, 4);
  EXPECT_EQ(row1, set.profiles[0].row_px[1]);
}

TEST(ProfileIo, TruncatedFileNamesFileAndProblem) {
  const std::string bytes = EncodeProfiles(MakeSet(32, 0, 4));
  const std::string msg =
      FileErrorMessage([&] { DecodeProfiles(bytes.substr(0, bytes.size() - 5), "cut.lcp"); });
  EXPECT_NE(msg.find("cut.lcp"), std::string::npos) << msg;
  EXPECT_NE(msg.find("truncated"), std::string::npos) << msg;
  const std::string msg2 =
      FileErrorMessage([&] { DecodeProfiles(bytes.substr(0, 30), "short.lcp"); });
  EXPECT_NE(msg2.find("short.lcp"), std::string::npos) << msg2;
  EXPECT_NE(msg2.find("truncated"), std::string::npos) << msg2;
}

TEST(ProfileIo, WrongMagicIsRejected) {
  std::string bytes = EncodeProfiles(MakeSet(8, 0, 1));
  bytes[1] = 'X';
  const std::string msg = FileErrorMessage([&] { DecodeProfiles(bytes, "magic.lcp"); });
  EXPECT_NE(msg.find("magic.lcp"), std::string::npos) << msg;
  EXPECT_NE(msg.find("magic"), std::string::npos) << msg;
  EXPECT_NE(FileErrorMessage([&] { DecodeProfiles("ply\nformat ascii", "x.ply"); }).find("magic"),
            std::string::npos);
}

TEST(ProfileIo, UnknownVersionIsRejected) {
  std::string bytes = EncodeProfiles(MakeSet(8, 0, 1));
  const std::uint32_t v2 = 2;
  std::memcpy(bytes.data() + 8, &v2, 4);
  const std::string msg = FileErrorMessage([&] { DecodeProfiles(bytes, "v2.lcp"); });
  EXPECT_NE(msg.find("v2.lcp"), std::string::npos) << msg;
  EXPECT_NE(msg.find("version 2"), std::string::npos) << msg;
}

TEST(ProfileIo, ColumnCountMismatchIsRejected) {
  std::string bytes = EncodeProfiles(MakeSet(64, 0, 3));
  const std::uint32_t columns = 60;  // header no longer matches the records
  std::memcpy(bytes.data() + 28, &columns, 4);
  const std::string msg = FileErrorMessage([&] { DecodeProfiles(bytes, "cols.lcp"); });
  EXPECT_NE(msg.find("cols.lcp"), std::string::npos) << msg;
  EXPECT_NE(msg.find("columns"), std::string::npos) << msg;
  EXPECT_NE(msg.find("mismatch"), std::string::npos) << msg;
  // ROI beyond the image.
  std::string roi = EncodeProfiles(MakeSet(64, 0, 1));
  const std::uint32_t width = 100;
  std::memcpy(roi.data() + 16, &width, 4);
  const std::string msg2 = FileErrorMessage([&] { DecodeProfiles(roi, "roi.lcp"); });
  EXPECT_NE(msg2.find("first_column + columns"), std::string::npos) << msg2;
}

TEST(ProfileIo, TrailingBytesAndFlagsAreRejected) {
  std::string bytes = EncodeProfiles(MakeSet(8, 0, 2));
  EXPECT_NE(FileErrorMessage([&] { DecodeProfiles(bytes + "xx", "tail.lcp"); }).find("mismatch"),
            std::string::npos);
  const std::uint32_t flags = 1;
  std::memcpy(bytes.data() + 36, &flags, 4);
  EXPECT_NE(FileErrorMessage([&] { DecodeProfiles(bytes, "flags.lcp"); }).find("flags"),
            std::string::npos);
}

TEST(ProfileIo, MissingFileIsFileError) {
  const test::TestDir dir("profile_io");
  EXPECT_THROW(ReadProfiles(dir.File("does_not_exist.lcp")), FileError);
}

TEST(ProfileIo, WriterRejectsProfilesThatDoNotMatchTheHeader) {
  ProfileSet set = MakeSet(16, 2, 2);
  set.profiles[1].row_px.pop_back();
  try {
    EncodeProfiles(set);
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("profile 1"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("columns"), std::string::npos) << e.what();
  }
  set = MakeSet(16, 2, 2);
  set.profiles[0].joints_rad.clear();
  EXPECT_THROW(EncodeProfiles(set), InputError);
  set = MakeSet(16, 0, 1);
  set.profiles[0].row_px[3] = std::numeric_limits<float>::infinity();
  EXPECT_THROW(EncodeProfiles(set), InputError);
  set = MakeSet(16, 0, 1);
  set.header.first_column = 1020;
  EXPECT_THROW(EncodeProfiles(set), InputError);
}

TEST(ProfileIo, StreamingHeaderPlusRecordsEqualsWholeFile) {
  const ProfileSet set = MakeSet(20, 1, 5);
  std::string bytes = EncodeProfileHeader(set.header, set.profiles.size());
  for (const Profile& p : set.profiles) AppendProfileRecord(set.header, p, &bytes);
  EXPECT_EQ(bytes, EncodeProfiles(set));
}

}  // namespace
}  // namespace lasercell::triangulation
