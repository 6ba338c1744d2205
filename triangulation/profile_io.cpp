#include "triangulation/profile_io.hpp"

#include <cmath>
#include <cstring>
#include <limits>

#include "core/error.hpp"
#include "core/io/byte_order.hpp"
#include "core/io/file_util.hpp"

namespace lasercell::triangulation {

namespace {

constexpr std::size_t kFixedHeaderBytes = 48;  // up to and including profile_count
constexpr std::uint64_t kMaxStringBytes = 1u << 24;
constexpr std::uint32_t kMaxColumns = 1u << 20;
constexpr std::uint32_t kMaxJoints = 64;

using io::GetLe;
using io::PutLe;

std::uint64_t PaddedHeaderBytes(const ProfileHeader& header) {
  const std::uint64_t raw =
      kFixedHeaderBytes + 4 + header.robot.size() + 4 + header.metadata.size();
  return (raw + 7) / 8 * 8;
}

std::string ProfileName(std::size_t index) { return "profile " + std::to_string(index); }

}  // namespace

void CheckProfile(const ProfileHeader& header, const Profile& profile, const std::string& what) {
  const auto columns = static_cast<std::size_t>(header.columns);
  if (profile.row_px.size() != columns || profile.intensity.size() != columns ||
      profile.width_px.size() != columns) {
    throw InputError(
        what + ": row_px/intensity/width_px hold " + std::to_string(profile.row_px.size()) + "/" +
        std::to_string(profile.intensity.size()) + "/" + std::to_string(profile.width_px.size()) +
        " values but the header says columns = " + std::to_string(columns) +
        "; every profile needs exactly one value per column");
  }
  if (profile.joints_rad.size() != header.joint_count) {
    throw InputError(
        what + ": joints_rad holds " + std::to_string(profile.joints_rad.size()) +
        " values but the header says joint_count = " + std::to_string(header.joint_count));
  }
  for (std::size_t c = 0; c < columns; ++c) {
    const float row = profile.row_px[c];
    if (std::isinf(row)) {
      throw InputError(what + ": row_px of column " + std::to_string(c) +
                       " is infinite; use NaN for a column without a peak");
    }
    if (!std::isfinite(profile.intensity[c]) || !std::isfinite(profile.width_px[c])) {
      throw InputError(what + ": intensity or width_px of column " + std::to_string(c) +
                       " is not finite");
    }
  }
}

void ProfileHeader::Check(const std::string& what) const {
  if (image_width == 0 || image_height == 0) {
    throw InputError(what + ": image_width and image_height must be > 0 (got " +
                     std::to_string(image_width) + " x " + std::to_string(image_height) + ")");
  }
  if (columns == 0 || columns > kMaxColumns) {
    throw InputError(what + ": columns = " + std::to_string(columns) + " must be in [1, " +
                     std::to_string(kMaxColumns) + "]");
  }
  if (static_cast<std::uint64_t>(first_column) + columns > image_width) {
    throw InputError(what + ": columns mismatch: first_column + columns = " +
                     std::to_string(static_cast<std::uint64_t>(first_column) + columns) +
                     " exceeds image_width = " + std::to_string(image_width));
  }
  if (joint_count > kMaxJoints) {
    throw InputError(what + ": joint_count = " + std::to_string(joint_count) + " is more than " +
                     std::to_string(kMaxJoints));
  }
  if (robot.size() > kMaxStringBytes || metadata.size() > kMaxStringBytes) {
    throw InputError(what + ": robot or metadata text longer than 16 MiB");
  }
}

Profile Profile::Empty(std::uint32_t columns, std::uint32_t joint_count) {
  Profile p;
  p.joints_rad.assign(joint_count, 0.0);
  p.row_px.assign(columns, std::numeric_limits<float>::quiet_NaN());
  p.intensity.assign(columns, 0.0f);
  p.width_px.assign(columns, 0.0f);
  return p;
}

std::size_t Profile::ValidCount() const {
  std::size_t n = 0;
  for (float r : row_px) n += std::isnan(r) ? 0 : 1;
  return n;
}

std::uint64_t ProfileRecordBytes(const ProfileHeader& header) {
  return 16 + 8ull * header.joint_count + 12ull * header.columns;
}

std::string EncodeProfileHeader(const ProfileHeader& header, std::uint64_t profile_count) {
  header.Check();
  const std::uint64_t header_bytes = PaddedHeaderBytes(header);
  std::string out;
  out.reserve(header_bytes);
  out.append(kProfileMagic);
  PutLe<std::uint32_t>(&out, kProfileFormatVersion);
  PutLe<std::uint32_t>(&out, static_cast<std::uint32_t>(header_bytes));
  PutLe<std::uint32_t>(&out, header.image_width);
  PutLe<std::uint32_t>(&out, header.image_height);
  PutLe<std::uint32_t>(&out, header.first_column);
  PutLe<std::uint32_t>(&out, header.columns);
  PutLe<std::uint32_t>(&out, header.joint_count);
  PutLe<std::uint32_t>(&out, 0u);
  PutLe<std::uint64_t>(&out, profile_count);
  PutLe<std::uint32_t>(&out, static_cast<std::uint32_t>(header.robot.size()));
  out.append(header.robot);
  PutLe<std::uint32_t>(&out, static_cast<std::uint32_t>(header.metadata.size()));
  out.append(header.metadata);
  out.resize(header_bytes, '\0');
  return out;
}

namespace {
void AppendRecordUnchecked(const Profile& profile, std::string* out) {
  PutLe<std::uint64_t>(out, profile.sequence);
  PutLe<std::int64_t>(out, profile.timestamp_ns);
  for (double q : profile.joints_rad) PutLe<double>(out, q);
  for (float v : profile.row_px) PutLe<float>(out, v);
  for (float v : profile.intensity) PutLe<float>(out, v);
  for (float v : profile.width_px) PutLe<float>(out, v);
}
}  // namespace

void AppendProfileRecord(const ProfileHeader& header, const Profile& profile, std::string* out) {
  CheckProfile(header, profile, "profile with sequence " + std::to_string(profile.sequence));
  AppendRecordUnchecked(profile, out);
}

std::string EncodeProfiles(const ProfileSet& set) {
  std::string out = EncodeProfileHeader(set.header, set.profiles.size());
  out.reserve(out.size() + set.profiles.size() * ProfileRecordBytes(set.header));
  for (std::size_t i = 0; i < set.profiles.size(); ++i) {
    CheckProfile(set.header, set.profiles[i], ProfileName(i));
    AppendRecordUnchecked(set.profiles[i], &out);
  }
  return out;
}

ProfileSet DecodeProfiles(std::string_view bytes, const std::string& name) {
  const auto fail = [&](const std::string& problem) -> FileError {
    return FileError(name, problem);
  };
  if (bytes.size() < kProfileMagic.size() ||
      bytes.substr(0, kProfileMagic.size()) != kProfileMagic) {
    throw fail("not a lasercell profile file (wrong magic; expected \"\\x89LCPROF\\n\")");
  }
  if (bytes.size() < kFixedHeaderBytes + 4) {
    throw fail("truncated header: " + std::to_string(bytes.size()) +
               " bytes, a version-1 header needs at least " +
               std::to_string(kFixedHeaderBytes + 8));
  }
  const char* p = bytes.data();
  const auto version = GetLe<std::uint32_t>(p + 8);
  if (version != kProfileFormatVersion) {
    throw fail("unknown profile format version " + std::to_string(version) +
               " (this build reads version " + std::to_string(kProfileFormatVersion) +
               "); update lasercell");
  }
  const auto header_bytes = GetLe<std::uint32_t>(p + 12);
  ProfileSet set;
  ProfileHeader& h = set.header;
  h.image_width = GetLe<std::uint32_t>(p + 16);
  h.image_height = GetLe<std::uint32_t>(p + 20);
  h.first_column = GetLe<std::uint32_t>(p + 24);
  h.columns = GetLe<std::uint32_t>(p + 28);
  h.joint_count = GetLe<std::uint32_t>(p + 32);
  const auto flags = GetLe<std::uint32_t>(p + 36);
  const auto profile_count = GetLe<std::uint64_t>(p + 40);
  if (flags != 0) {
    throw fail("unknown header flags " + std::to_string(flags) +
               " (version 1 defines none); the file was written by a newer writer");
  }
  // Strings.
  std::uint64_t offset = kFixedHeaderBytes;
  const auto read_string = [&](const char* field) {
    if (offset + 4 > bytes.size()) {
      throw fail(std::string("truncated header: missing the length of ") + field);
    }
    const std::uint64_t len = GetLe<std::uint32_t>(p + offset);
    offset += 4;
    if (len > kMaxStringBytes || offset + len > bytes.size()) {
      throw fail(std::string("truncated header: ") + field + " declares " + std::to_string(len) +
                 " bytes, the file ends before");
    }
    std::string s(p + offset, p + offset + len);
    offset += len;
    return s;
  };
  h.robot = read_string("robot");
  h.metadata = read_string("metadata");
  if (header_bytes % 8 != 0 || header_bytes < offset || header_bytes - offset >= 8) {
    throw fail("corrupt header: header_bytes = " + std::to_string(header_bytes) +
               " does not match the header's strings (" + std::to_string(offset) + " bytes)");
  }
  if (header_bytes > bytes.size()) {
    throw fail("truncated header: header_bytes = " + std::to_string(header_bytes) + ", file has " +
               std::to_string(bytes.size()) + " bytes");
  }
  try {
    h.Check("header");
  } catch (const InputError& e) {
    throw fail(e.what());
  }
  const std::uint64_t record = ProfileRecordBytes(h);
  const std::uint64_t data = bytes.size() - header_bytes;
  if (profile_count > data / record || data != profile_count * record) {
    const bool truncated = profile_count > data / record;
    throw fail(std::string(truncated ? "truncated data" : "size mismatch") + ": header declares " +
               std::to_string(profile_count) + " profiles of " + std::to_string(h.columns) +
               " columns and " + std::to_string(h.joint_count) + " joints (" +
               std::to_string(record) + " bytes each), but " + std::to_string(data) +
               " data bytes follow the header" +
               (truncated ? "" : "; the columns or joint_count field does not match the data"));
  }
  set.profiles.resize(profile_count);
  const char* q = p + header_bytes;
  for (Profile& prof : set.profiles) {
    prof.sequence = GetLe<std::uint64_t>(q);
    prof.timestamp_ns = GetLe<std::int64_t>(q + 8);
    q += 16;
    prof.joints_rad.resize(h.joint_count);
    for (double& v : prof.joints_rad) {
      v = GetLe<double>(q);
      q += 8;
    }
    for (auto* vec : {&prof.row_px, &prof.intensity, &prof.width_px}) {
      vec->resize(h.columns);
      for (float& v : *vec) {
        v = GetLe<float>(q);
        q += 4;
      }
    }
  }
  return set;
}

void WriteProfiles(const std::string& path, const ProfileSet& set) {
  io::WriteFileAtomically(path, EncodeProfiles(set));
}

ProfileSet ReadProfiles(const std::string& path) {
  return DecodeProfiles(io::ReadFileBytes(path), path);
}

}  // namespace lasercell::triangulation
