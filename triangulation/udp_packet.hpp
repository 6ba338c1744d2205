#pragma once
// Profile datagrams: the UDP stream of a laser-triangulation sensor, as in the paper's cell
// (Skotheim et al. 2012, III-A: the sensor PC streams profiles to the localizer over UDP).
// A sweep is a BEGIN datagram, then each profile as one or more FRAGMENT datagrams (a profile
// larger than one datagram is split by columns), then an END datagram. Every fragment carries
// its profile's sequence number, timestamp, joint values and geometry, so any fragment that
// arrives can be placed; a profile is delivered only when all its fragments arrived.
//
// ---------------------------------------------------------------------------------------------
// lasercell profile datagram, version 1 (also in datasets/PROFILE_FORMAT.md).
// Little-endian, floats IEEE-754, offsets in bytes; the datagram's length must be exact.
// Common part (32 bytes):
//    0  4  magic          "LCUD" (4C 43 55 44)
//    4  1  u8 version     1
//    5  1  u8 type        1 = BEGIN, 2 = FRAGMENT, 3 = END
//    6  2  u16 reserved   0
//    8  4  u32 sensor_id  the sensor (a receiver may listen to one)
//   12  4  u32 sweep_id   the sweep; the sender numbers its sweeps
//   16  8  u64 sequence   FRAGMENT: the profile's sequence number; BEGIN/END: the sweep's first
//   24  8  i64 timestamp_ns  FRAGMENT: the profile's exposure time; BEGIN/END: send time
// FRAGMENT (64 + 8*joint_count + 12*column_count bytes):
//   32  2  u16 fragment_index   0 .. fragment_count-1
//   34  2  u16 fragment_count   fragments of this profile (>= 1)
//   36  4  u32 columns          columns of the whole profile
//   40  4  u32 column_offset    first profile column in this fragment
//   44  4  u32 column_count     columns in this fragment (>= 1; offset + count <= columns)
//   48  2  u16 joint_count      joint values that follow
//   50  2  u16 reserved         0
//   52  4  u32 first_column     image column of profile column 0
//   56  4  u32 image_width
//   60  4  u32 image_height
//   64     f64 joints_rad[joint_count]
//    .     f32 row_px[column_count], f32 intensity[column_count], f32 width_px[column_count]
// BEGIN / END (48 + header bytes):
//   32  8  u64 last_sequence    END: the sweep's last sequence number; BEGIN: 0
//   40  8  u64 profile_count    END: profiles the sender sent in this sweep; BEGIN: 0
//   48     the sweep's profile-file header (profile_io.hpp, EncodeProfileHeader with
//          profile_count 0): geometry, the robot whose joints are recorded, metadata
// ---------------------------------------------------------------------------------------------

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "triangulation/profile_io.hpp"

namespace lasercell::triangulation {

/// The four magic bytes of every profile datagram.
inline constexpr std::string_view kDatagramMagic{"LCUD", 4};
/// Current datagram version.
inline constexpr std::uint8_t kDatagramVersion = 1;
/// Bytes before a fragment's joints.
inline constexpr std::size_t kFragmentHeaderBytes = 64;
/// Bytes before a BEGIN/END datagram's profile-file header.
inline constexpr std::size_t kMarkerHeaderBytes = 48;

/// What a datagram is.
enum class DatagramType : std::uint8_t { kBegin = 1, kFragment = 2, kEnd = 3 };

/// Why a datagram was refused (kOk when it was not). Receivers count each reason.
enum class DatagramStatus : std::uint8_t {
  kOk = 0,
  kTooShort,     ///< Shorter than its fixed part.
  kBadMagic,     ///< Not "LCUD".
  kBadVersion,   ///< A version this build does not read.
  kBadType,      ///< Type not 1, 2 or 3.
  kBadLength,    ///< Length differs from what its fields declare.
  kBadFragment,  ///< fragment_index >= fragment_count, or count 0 / over the limit.
  kBadColumns,   ///< Column fields absurd, inconsistent or over the limit.
  kBadJoints,    ///< joint_count over the limit.
  kBadHeader,    ///< A BEGIN/END whose profile-file header does not decode.
  kCount
};
/// Short name of a status, e.g. "bad_magic".
const char* DatagramStatusName(DatagramStatus status);

/// Bounds a receiver accepts; anything beyond is refused before memory is allocated for it.
struct DatagramLimits {
  std::uint32_t max_columns = 16384;   ///< Columns of one profile.
  std::uint32_t max_joints = 32;       ///< Joint values per profile.
  std::uint32_t max_fragments = 1024;  ///< Fragments of one profile.
};

/// A decoded datagram. Views point into the datagram's bytes (valid while they are).
struct Datagram {
  DatagramType type = DatagramType::kFragment;
  std::uint32_t sensor_id = 0;
  std::uint32_t sweep_id = 0;
  std::uint64_t sequence = 0;
  std::int64_t timestamp_ns = 0;
  // FRAGMENT
  std::uint16_t fragment_index = 0;
  std::uint16_t fragment_count = 0;
  std::uint32_t columns = 0;
  std::uint32_t column_offset = 0;
  std::uint32_t column_count = 0;
  std::uint16_t joint_count = 0;
  std::uint32_t first_column = 0;
  std::uint32_t image_width = 0;
  std::uint32_t image_height = 0;
  const char* joints = nullptr;        ///< joint_count little-endian f64.
  const char* columns_data = nullptr;  ///< row_px, intensity, width_px blocks of column_count f32.
  // BEGIN / END
  std::uint64_t last_sequence = 0;
  std::uint64_t profile_count = 0;
  ProfileHeader header;  ///< The sweep's header (BEGIN/END only).
};

/// Decodes one datagram; never throws and never reads outside `bytes`. On a status other than
/// kOk, `out` is unspecified.
DatagramStatus DecodeDatagram(std::string_view bytes, const DatagramLimits& limits, Datagram* out);

/// Copies a fragment's columns into a profile of `columns` columns (sized by the caller).
void CopyFragmentColumns(const Datagram& fragment, Profile* profile);

/// Options of EncodeSweepDatagrams.
struct DatagramOptions {
  std::uint32_t sensor_id = 1;  ///< Written into every datagram.
  std::uint32_t sweep_id = 0;   ///< The sweep's number.
  /// Largest datagram payload, bytes: 1472 fits a 1500-byte Ethernet MTU (IPv4 + UDP headers),
  /// 8972 a 9000-byte jumbo frame; at most 65507 (UDP over IPv4).
  std::size_t max_datagram_bytes = 1472;
  std::int64_t send_time_ns = 0;  ///< Timestamp of the BEGIN/END datagrams.
  /// Throws OptionError naming the field.
  void Check() const;
};

/// A sweep as datagrams, in send order: BEGIN, each profile's fragments, END.
struct SweepDatagrams {
  std::vector<std::string> datagrams;
  /// For each datagram, the index of its profile in the set; -1 for BEGIN and END.
  std::vector<std::int64_t> profile_of;
};

/// Encodes a sweep. Throws InputError when a profile does not match the header (as
/// EncodeProfiles), when sequence numbers do not increase, when the header is too long for one
/// datagram, or when a profile would need more than 65535 fragments.
SweepDatagrams EncodeSweepDatagrams(const ProfileSet& set, const DatagramOptions& options);

}  // namespace lasercell::triangulation
