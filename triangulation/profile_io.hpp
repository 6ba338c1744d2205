#pragma once
// Laser-profile files: what a laser-triangulation sensor delivers, one peak per image column per
// exposure. Written by the simulator (datasets/) and by recorders, read by triangulation. The
// UDP stream carries the same header once and then the same records.
//
// Conventions: pixel coordinates as in mrcal/OpenCV (the centre of the top-left pixel is
// (0, 0)); `row_px` is the subpixel peak row in full-image coordinates, NaN when the column has
// no peak; column j of a profile is image column `first_column + j`; timestamps are int64
// nanoseconds on the sensor clock; joint values in rad.
//
// ---------------------------------------------------------------------------------------------
// lasercell profile file, format version 1 (also in datasets/PROFILE_FORMAT.md).
// All integers and floats little-endian; floats IEEE-754. Offsets in bytes.
//
// Header (header_bytes long, a multiple of 8):
//    0  8  magic            "\x89LCPROF\n" (89 4C 43 50 52 4F 46 0A)
//    8  4  u32 version       1
//   12  4  u32 header_bytes  total header size including the strings and padding
//   16  4  u32 image_width   sensor columns (e.g. 1024)
//   20  4  u32 image_height  sensor rows (e.g. 1024)
//   24  4  u32 first_column  image column of profile column 0 (region of interest)
//   28  4  u32 columns       columns per profile; first_column + columns <= image_width
//   32  4  u32 joint_count   joint values per profile (0: none recorded)
//   36  4  u32 flags         0 in version 1 (readers reject other values)
//   40  8  u64 profile_count number of profile records that follow
//   48  4  u32 robot_len     then robot_len bytes: robot whose joints are recorded (UTF-8,
//                            e.g. "vision_robot"; empty when joint_count == 0)
//    .  4  u32 metadata_len  then metadata_len bytes: free UTF-8 text (YAML) about the capture
//    .     zero padding up to header_bytes
// Records (profile_count of them, each 16 + 8*joint_count + 12*columns bytes):
//    0  8  u64 sequence      sensor sequence number (gaps mean lost profiles)
//    8  8  i64 timestamp_ns  exposure time, ns
//   16     f64 joints[joint_count]    rad
//    .     f32 row_px[columns]        subpixel peak row; NaN = no peak in this column
//    .     f32 intensity[columns]     peak intensity, 0..1 (0 where row is NaN)
//    .     f32 width_px[columns]      peak width (FWHM), px (0 where row is NaN)
// The file ends exactly after the last record; anything else is an error.
// ---------------------------------------------------------------------------------------------

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace lasercell::triangulation {

/// Current profile file format version.
inline constexpr std::uint32_t kProfileFormatVersion = 1;
/// The 8 magic bytes that open every profile file.
inline constexpr std::string_view kProfileMagic{"\x89LCPROF\n", 8};

/// What is common to all profiles of a file (or stream).
struct ProfileHeader {
  std::uint32_t image_width = 1024;   ///< Sensor columns, px.
  std::uint32_t image_height = 1024;  ///< Sensor rows, px.
  std::uint32_t first_column = 0;     ///< Image column of profile column 0.
  std::uint32_t columns = 1024;       ///< Columns per profile.
  std::uint32_t joint_count = 0;      ///< Joint values per profile (0: none).
  std::string robot;                  ///< Robot whose joints are recorded ("" when none).
  std::string metadata;               ///< Free text (YAML) about the capture.

  /// Throws InputError naming `what` and the field when the header is inconsistent.
  void Check(const std::string& what = "profile header") const;
};

/// One exposure: one peak (or none) per column.
struct Profile {
  std::uint64_t sequence = 0;      ///< Sensor sequence number.
  std::int64_t timestamp_ns = 0;   ///< Exposure time on the sensor clock, ns.
  std::vector<double> joints_rad;  ///< Robot joint values (rad): empty or joint_count long.
  std::vector<float> row_px;       ///< Subpixel peak row per column; NaN = no peak.
  std::vector<float> intensity;    ///< Peak intensity per column, 0..1.
  std::vector<float> width_px;     ///< Peak width per column, px.

  /// A profile of `columns` columns without peaks (rows NaN, intensity and width 0).
  static Profile Empty(std::uint32_t columns, std::uint32_t joint_count = 0);
  /// Number of columns holding a peak.
  std::size_t ValidCount() const;
};

/// A header and its profiles, as stored in one file.
struct ProfileSet {
  ProfileHeader header;
  std::vector<Profile> profiles;
};

/// Throws InputError starting with `what` when a profile does not match the header: vector
/// lengths, an infinite row, a non-finite intensity or width.
void CheckProfile(const ProfileHeader& header, const Profile& profile, const std::string& what);

/// Bytes of one record for a header (16 + 8 * joint_count + 12 * columns).
std::uint64_t ProfileRecordBytes(const ProfileHeader& header);

/// Encodes a whole file. Throws InputError naming the profile and field when a profile does not
/// match the header (vector lengths, a peak with non-finite intensity or width).
std::string EncodeProfiles(const ProfileSet& set);
/// Decodes a whole file held in memory; `name` appears in errors. Throws FileError naming the
/// file and the problem: truncated data, wrong magic, unknown version or flags, a header whose
/// column/ROI fields disagree, a size that does not match profile_count records.
ProfileSet DecodeProfiles(std::string_view bytes, const std::string& name);

/// Encodes only the header (with a given profile_count), e.g. to open a stream.
std::string EncodeProfileHeader(const ProfileHeader& header, std::uint64_t profile_count);
/// Appends one record to `out`; same checks as EncodeProfiles.
void AppendProfileRecord(const ProfileHeader& header, const Profile& profile, std::string* out);

/// Writes a profile file atomically. Throws InputError/FileError.
void WriteProfiles(const std::string& path, const ProfileSet& set);
/// Reads a profile file. Throws FileError naming the file and the problem.
ProfileSet ReadProfiles(const std::string& path);

}  // namespace lasercell::triangulation
