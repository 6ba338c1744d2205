#pragma once
// Internal to core/io (not installed, not part of the public API): what the PLY and PCD codecs
// share. Scalar types and unaligned, byte-order-aware loads/stores (always through memcpy, so
// misaligned data is fine); a whitespace-token cursor over in-memory ASCII data that parses with
// std::from_chars; the mapping of file field names to PointCloud attributes; and CloudBuilder,
// which collects decoded points and drops non-finite ones.

#include <array>
#include <bit>
#include <charconv>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/io/point_cloud_io.hpp"
#include "core/point_cloud.hpp"

namespace lasercell::io::detail {

/// Scalar types found in PLY and PCD files.
enum class ScalarType : std::uint8_t {
  kInt8,
  kUint8,
  kInt16,
  kUint16,
  kInt32,
  kUint32,
  kInt64,
  kUint64,
  kFloat32,
  kFloat64
};

/// Bytes per value.
std::size_t ScalarSize(ScalarType type);
/// True for kFloat32 / kFloat64.
inline bool IsFloating(ScalarType type) {
  return type == ScalarType::kFloat32 || type == ScalarType::kFloat64;
}

/// True when data stored in little-endian (or big-endian) order must be byte-swapped here.
inline bool SwapFromLittle() { return std::endian::native != std::endian::little; }
inline bool SwapFromBig() { return std::endian::native != std::endian::big; }

/// Reads a T from possibly misaligned memory, reversing the bytes when `swap`.
template <typename T>
inline T LoadRaw(const char* p, bool swap) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, p, sizeof(T));
  if (swap) {
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
  }
  T value;
  std::memcpy(&value, b, sizeof(T));
  return value;
}

/// Writes a T to possibly misaligned memory, reversing the bytes when `swap`.
template <typename T>
inline void StoreRaw(char* p, T value, bool swap) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, &value, sizeof(T));
  if (swap) {
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
  }
  std::memcpy(p, b, sizeof(T));
}

/// Reads one value of `type` at p as a double (64-bit integers beyond 2^53 lose precision,
/// which only matters for fields that must fit int32 anyway).
inline double LoadAsDouble(const char* p, ScalarType type, bool swap) {
  switch (type) {
    case ScalarType::kInt8:
      return LoadRaw<std::int8_t>(p, swap);
    case ScalarType::kUint8:
      return LoadRaw<std::uint8_t>(p, swap);
    case ScalarType::kInt16:
      return LoadRaw<std::int16_t>(p, swap);
    case ScalarType::kUint16:
      return LoadRaw<std::uint16_t>(p, swap);
    case ScalarType::kInt32:
      return LoadRaw<std::int32_t>(p, swap);
    case ScalarType::kUint32:
      return LoadRaw<std::uint32_t>(p, swap);
    case ScalarType::kInt64:
      return static_cast<double>(LoadRaw<std::int64_t>(p, swap));
    case ScalarType::kUint64:
      return static_cast<double>(LoadRaw<std::uint64_t>(p, swap));
    case ScalarType::kFloat32:
      return LoadRaw<float>(p, swap);
    case ScalarType::kFloat64:
      return LoadRaw<double>(p, swap);
  }
  return 0.0;
}

/// Outcome of parsing one ASCII token.
enum class ScanStatus { kOk, kEnd, kMalformed };

/// Walks whitespace-separated tokens of in-memory text. Line structure is not enforced (PLY and
/// PCD ASCII data are read as token streams); Line() recovers the line for error messages.
class AsciiCursor {
 public:
  /// Cursor over text[offset..]; `text` must outlive the cursor.
  AsciiCursor(std::string_view text, std::size_t offset)
      : begin_(text.data()), pos_(text.data() + offset), end_(text.data() + text.size()) {}

  /// Parses the next token as a value of `type` (integers must be integers; "nan"/"inf" are
  /// accepted for floating types) and returns it as a double.
  ScanStatus Next(ScalarType type, double* value);
  /// Skips the next token without parsing it (fields that are not kept); kEnd at the end.
  ScanStatus Skip();
  /// The token at the cursor (or at the failed parse), for error messages; at most 40 chars.
  std::string CurrentToken() const;
  /// 1-based line of the cursor within the whole text (counts newlines; only for errors).
  std::size_t Line() const;
  /// Bytes from the cursor to the end.
  std::size_t Remaining() const { return static_cast<std::size_t>(end_ - pos_); }

 private:
  static bool IsSpace(char c) {
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
  }
  template <typename T>
  ScanStatus ParseAs(T* out);

  const char* begin_;
  const char* pos_;
  const char* end_;
};

/// PointCloud attribute a file field maps to.
enum class Slot : std::uint8_t {
  kX,
  kY,
  kZ,
  kNx,
  kNy,
  kNz,
  kIntensity,
  kProfile,
  kColumn,
  kTimestamp,
  kCount,
  kIgnored
};
inline constexpr std::size_t kSlotCount = static_cast<std::size_t>(Slot::kCount);

/// Maps a field name (case-insensitive) to an attribute: x y z; nx ny nz or normal_x normal_y
/// normal_z; intensity or scalar_intensity (CloudCompare); profile; column; timestamp.
Slot SlotForName(std::string_view name);

/// Parses an unsigned decimal count ("element vertex N", "POINTS N"); false when malformed.
bool ParseCount(std::string_view token, std::uint64_t* value);

/// Splits a header line into whitespace-separated tokens.
std::vector<std::string_view> SplitTokens(std::string_view line);

/// True when count * unit_bytes <= available, computed without overflow.
inline bool FitsIn(std::uint64_t count, std::uint64_t unit_bytes, std::uint64_t available) {
  return unit_bytes == 0 || count <= available / unit_bytes;
}

/// One field of a fixed-layout binary record: the value for record i is at
/// base + start + i * step (point-major data: step = record size; field-major data, as in
/// PCD binary_compressed: start = field block offset, step = field size).
struct FieldLoad {
  std::size_t start, step, slot;
  ScalarType type;
};

/// Collects decoded points into a PointCloud. Which attributes exist is fixed up front by the
/// slots present in the file (normals only when all of nx ny nz are present). Points with a
/// non-finite position or normal are dropped and counted; TakeRemap() gives each file index's new
/// index (or -1) when faces need it.
class CloudBuilder {
 public:
  /// `present[s]` says whether slot s occurs in the file; `name` is used in error messages.
  CloudBuilder(const std::array<bool, kSlotCount>& present, std::size_t expected_points,
               bool track_remap, const std::string& name);

  /// Adds the point whose slot values are `v` (indexed by Slot; absent slots are not read).
  /// `index` is its position in the file (for messages, the remap table and derived grids).
  void Add(const double* v, std::uint64_t index);
  /// Makes Add() set profile = index / width and column = index % width (organized files
  /// whose grid cell is implied by the point's position); requires both slots to be present.
  void DeriveGridFromIndex(std::uint64_t width) { derive_width_ = width; }
  /// Number of points dropped for a non-finite position or normal.
  std::size_t dropped() const { return dropped_; }
  /// Takes the new index of every file point (-1 when dropped); empty when nothing was
  /// dropped or remapping was not tracked.
  std::vector<std::int64_t> TakeRemap() { return std::move(remap_); }
  /// Takes the collected cloud.
  PointCloud Take() { return std::move(cloud_); }

 private:
  std::int32_t ToInt32(double value, const char* field, std::uint64_t index) const;
  void Drop(std::uint64_t index);

  PointCloud cloud_;
  bool has_normals_, has_intensity_, has_profile_, has_column_, has_timestamp_;
  bool track_remap_;
  std::uint64_t derive_width_ = 0;
  std::size_t dropped_ = 0;
  std::vector<std::int64_t> remap_;
  const std::string& name_;
};

/// Assigns each file field a slot: a slot goes to the first eligible field with its name (lists
/// and multi-valued fields are not eligible), normals only when nx, ny and nz are all present.
/// Sets `kept[s]` for the slots that will be filled and appends the fields not kept to
/// `ignored`. Returns the slot of every field (Slot::kIgnored for fields not kept).
std::vector<Slot> AssignSlots(const std::vector<std::string>& names,
                              const std::vector<bool>& eligible, std::array<bool, kSlotCount>* kept,
                              std::vector<std::string>* ignored);

/// Shortest round-trip decimal text of a value (std::to_chars), appended to `out`.
void AppendNumber(std::string& out, double value);
void AppendNumber(std::string& out, float value);
void AppendNumber(std::string& out, std::int64_t value);

/// Decodes `count` records of fixed layout into `builder` (the caller has checked that the
/// bytes are there). Native-order float32 fields take a fast path.
void DecodeFixed(const char* base, std::uint64_t count, const std::vector<FieldLoad>& fields,
                 bool swap, CloudBuilder& builder);

/// Checks that a cloud (and faces) can be written: Validate(what), face indices inside the
/// vertices, and positions within float range unless options.positions_as_double. Throws
/// InputError starting with `what`.
void CheckWritable(const PointCloud& cloud, std::span<const Eigen::Vector3i> faces,
                   const WriteOptions& options, const std::string& what);

/// Which vertex fields a cloud is written with, in this order: x y z, normals, intensity,
/// profile, column, timestamp (PLY and PCD use the same order and binary layout).
struct VertexLayout {
  bool normals, intensity, profile, column, timestamp;
  bool double_positions;  ///< x y z as float64 rather than float32.

  VertexLayout(const PointCloud& c, const WriteOptions& o)
      : normals(c.HasNormals()),
        intensity(c.HasIntensity()),
        profile(c.HasProfile()),
        column(c.HasColumn()),
        timestamp(c.HasTimestamps()),
        double_positions(o.positions_as_double) {}
  /// Bytes of one binary vertex.
  std::size_t Stride() const {
    return 3 * (double_positions ? 8 : 4) + (normals ? 12 : 0) + (intensity ? 4 : 0) +
           (profile ? 4 : 0) + (column ? 4 : 0) + (timestamp ? 8 : 0);
  }
};

/// Appends the vertices in binary (byte-swapped when `swap`), layout.Stride() bytes each.
void AppendBinaryVertices(std::string& out, const PointCloud& cloud, const VertexLayout& layout,
                          bool swap);
/// Appends the vertices as ASCII, one line each, values separated by single spaces.
void AppendAsciiVertices(std::string& out, const PointCloud& cloud, const VertexLayout& layout);

/// PLY encoder without validation (callers validate with a message naming their target).
std::string EncodePlyUnchecked(const PointCloud& cloud, std::span<const Eigen::Vector3i> faces,
                               const WriteOptions& options);
/// PCD encoder without validation.
std::string EncodePcdUnchecked(const PointCloud& cloud, const WriteOptions& options);

}  // namespace lasercell::io::detail
