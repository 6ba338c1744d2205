#include "core/io/codec.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <type_traits>

#include "core/error.hpp"

namespace lasercell::io::detail {
namespace {

/// Inclusive range of an integer type, as doubles (exact up to 32 bits), in ScalarType order.
struct Range {
  double lo, hi;
};
constexpr Range kIntegerRanges[] = {
    {-128.0, 127.0},                                  // kInt8
    {0.0, 255.0},                                     // kUint8
    {-32768.0, 32767.0},                              // kInt16
    {0.0, 65535.0},                                   // kUint16
    {-2147483648.0, 2147483647.0},                    // kInt32
    {0.0, 4294967295.0},                              // kUint32
    {-9223372036854775808.0, 9223372036854775807.0},  // kInt64
    {0.0, 18446744073709551615.0},                    // kUint64
};

std::string Lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

/// True when the number text [first, last) has a negative exponent (so an out-of-range parse
/// was an underflow, not an overflow).
bool IsUnderflow(const char* first, const char* last) {
  for (const char* p = first; p + 1 < last; ++p) {
    if ((*p == 'e' || *p == 'E') && p[1] == '-') return true;
  }
  return false;
}

}  // namespace

std::size_t ScalarSize(ScalarType type) {
  switch (type) {
    case ScalarType::kInt8:
    case ScalarType::kUint8:
      return 1;
    case ScalarType::kInt16:
    case ScalarType::kUint16:
      return 2;
    case ScalarType::kInt32:
    case ScalarType::kUint32:
    case ScalarType::kFloat32:
      return 4;
    case ScalarType::kInt64:
    case ScalarType::kUint64:
    case ScalarType::kFloat64:
      return 8;
  }
  return 0;
}

template <typename T>
ScanStatus AsciiCursor::ParseAs(T* out) {
  const char* first = pos_;
  // std::from_chars rejects a leading '+', which some writers emit.
  if (*first == '+' && first + 1 < end_ && first[1] != '-') ++first;
  auto [ptr, ec] = std::from_chars(first, end_, *out);
  if constexpr (std::is_floating_point_v<T>) {
    if (ec == std::errc::result_out_of_range && IsUnderflow(first, ptr)) {
      *out = (*first == '-') ? -T{0} : T{0};  // e.g. 1e-50 in a float property
      ec = std::errc();
    }
  }
  if (ec != std::errc() || (ptr < end_ && !IsSpace(*ptr))) return ScanStatus::kMalformed;
  pos_ = ptr;
  return ScanStatus::kOk;
}

ScanStatus AsciiCursor::Skip() {
  while (pos_ < end_ && IsSpace(*pos_)) ++pos_;
  if (pos_ == end_) return ScanStatus::kEnd;
  while (pos_ < end_ && !IsSpace(*pos_)) ++pos_;
  return ScanStatus::kOk;
}

ScanStatus AsciiCursor::Next(ScalarType type, double* value) {
  while (pos_ < end_ && IsSpace(*pos_)) ++pos_;
  if (pos_ == end_) return ScanStatus::kEnd;
  ScanStatus status;
  if (type == ScalarType::kFloat32) {
    float f = 0.0f;  // parsed as float so a float property keeps exactly the float's value
    status = ParseAs(&f);
    *value = f;
    return status;
  }
  if (type == ScalarType::kFloat64) return ParseAs(value);
  const char* token = pos_;
  if (type == ScalarType::kUint8 || type == ScalarType::kUint16 || type == ScalarType::kUint32 ||
      type == ScalarType::kUint64) {
    std::uint64_t u = 0;
    status = ParseAs(&u);
    *value = static_cast<double>(u);
  } else {
    std::int64_t i = 0;
    status = ParseAs(&i);
    *value = static_cast<double>(i);
  }
  const Range range = kIntegerRanges[static_cast<std::size_t>(type)];
  if (status == ScanStatus::kOk && (*value < range.lo || *value > range.hi)) {
    pos_ = token;                   // so CurrentToken() shows it
    return ScanStatus::kMalformed;  // e.g. 300 in a uchar property
  }
  return status;
}

std::string AsciiCursor::CurrentToken() const {
  const char* p = pos_;
  while (p < end_ && IsSpace(*p)) ++p;
  const char* q = p;
  while (q < end_ && !IsSpace(*q) && q - p < 40) ++q;
  return std::string(p, q);
}

std::size_t AsciiCursor::Line() const {
  return 1 + static_cast<std::size_t>(std::count(begin_, pos_, '\n'));
}

Slot SlotForName(std::string_view name) {
  const std::string n = Lower(name);
  if (n == "x") return Slot::kX;
  if (n == "y") return Slot::kY;
  if (n == "z") return Slot::kZ;
  if (n == "nx" || n == "normal_x") return Slot::kNx;
  if (n == "ny" || n == "normal_y") return Slot::kNy;
  if (n == "nz" || n == "normal_z") return Slot::kNz;
  if (n == "intensity" || n == "scalar_intensity") return Slot::kIntensity;
  if (n == "profile") return Slot::kProfile;
  if (n == "column") return Slot::kColumn;
  if (n == "timestamp") return Slot::kTimestamp;
  return Slot::kIgnored;
}

bool ParseCount(std::string_view token, std::uint64_t* value) {
  if (token.empty()) return false;
  const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), *value);
  return ec == std::errc() && ptr == token.data() + token.size();
}

std::vector<std::string_view> SplitTokens(std::string_view line) {
  std::vector<std::string_view> tokens;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    const std::size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
    if (i > start) tokens.push_back(line.substr(start, i - start));
  }
  return tokens;
}

std::vector<Slot> AssignSlots(const std::vector<std::string>& names,
                              const std::vector<bool>& eligible, std::array<bool, kSlotCount>* kept,
                              std::vector<std::string>* ignored) {
  std::vector<Slot> slots(names.size(), Slot::kIgnored);
  kept->fill(false);
  for (std::size_t i = 0; i < names.size(); ++i) {
    const Slot s = eligible[i] ? SlotForName(names[i]) : Slot::kIgnored;
    if (s == Slot::kIgnored || (*kept)[static_cast<std::size_t>(s)]) continue;  // first wins
    (*kept)[static_cast<std::size_t>(s)] = true;
    slots[i] = s;
  }
  auto has = [&](Slot s) { return (*kept)[static_cast<std::size_t>(s)]; };
  if (!(has(Slot::kNx) && has(Slot::kNy) && has(Slot::kNz))) {
    for (Slot s : {Slot::kNx, Slot::kNy, Slot::kNz}) (*kept)[static_cast<std::size_t>(s)] = false;
    for (Slot& s : slots) {
      if (s == Slot::kNx || s == Slot::kNy || s == Slot::kNz) s = Slot::kIgnored;
    }
  }
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (slots[i] == Slot::kIgnored) ignored->push_back(names[i]);
  }
  return slots;
}

CloudBuilder::CloudBuilder(const std::array<bool, kSlotCount>& present, std::size_t expected_points,
                           bool track_remap, const std::string& name)
    : has_normals_(present[static_cast<std::size_t>(Slot::kNx)]),
      has_intensity_(present[static_cast<std::size_t>(Slot::kIntensity)]),
      has_profile_(present[static_cast<std::size_t>(Slot::kProfile)]),
      has_column_(present[static_cast<std::size_t>(Slot::kColumn)]),
      has_timestamp_(present[static_cast<std::size_t>(Slot::kTimestamp)]),
      track_remap_(track_remap),
      name_(name) {
  // Callers have checked that the data can hold expected_points before we get here.
  cloud_.positions.reserve(expected_points);
  if (has_normals_) cloud_.normals.reserve(expected_points);
  if (has_intensity_) cloud_.intensity.reserve(expected_points);
  if (has_profile_) cloud_.profile.reserve(expected_points);
  if (has_column_) cloud_.column.reserve(expected_points);
  if (has_timestamp_) cloud_.timestamp_s.reserve(expected_points);
}

std::int32_t CloudBuilder::ToInt32(double value, const char* field, std::uint64_t index) const {
  if (!(value >= -2147483648.0 && value <= 2147483647.0) || value != std::trunc(value)) {
    throw FileError(name_, "point " + std::to_string(index) + ": " + field + " value " +
                               std::to_string(value) +
                               " is not a 32-bit integer; fix the file or drop the field");
  }
  return static_cast<std::int32_t>(value);
}

void CloudBuilder::Drop(std::uint64_t index) {
  ++dropped_;
  if (!track_remap_) return;
  if (remap_.empty()) {  // first drop: every earlier point kept its index
    remap_.resize(static_cast<std::size_t>(index));
    std::iota(remap_.begin(), remap_.end(), std::int64_t{0});
  }
  remap_.push_back(-1);
}

void CloudBuilder::Add(const double* v, std::uint64_t index) {
  auto at = [v](Slot s) { return v[static_cast<std::size_t>(s)]; };
  const Eigen::Vector3d p(at(Slot::kX), at(Slot::kY), at(Slot::kZ));
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  bool finite = p.allFinite();
  if (has_normals_) {
    n = Eigen::Vector3d(at(Slot::kNx), at(Slot::kNy), at(Slot::kNz));
    // PointCloud promises unit normals; some files (the UWA models) store unnormalized ones.
    // Normals already unit to float precision are kept bit-exact; zero-length ones are invalid.
    const double length = n.norm();
    finite = finite && std::isfinite(length) && length > 1e-12;
    if (finite && std::abs(length - 1.0) > 1e-6) n /= length;
  }
  if (!finite) {
    Drop(index);
    return;
  }
  if (!remap_.empty()) remap_.push_back(static_cast<std::int64_t>(cloud_.positions.size()));
  cloud_.positions.push_back(p);
  if (has_normals_) cloud_.normals.push_back(n);
  if (has_intensity_) cloud_.intensity.push_back(static_cast<float>(at(Slot::kIntensity)));
  if (derive_width_ > 0) {
    cloud_.profile.push_back(static_cast<std::int32_t>(index / derive_width_));
    cloud_.column.push_back(static_cast<std::int32_t>(index % derive_width_));
  } else {
    if (has_profile_) cloud_.profile.push_back(ToInt32(at(Slot::kProfile), "profile", index));
    if (has_column_) cloud_.column.push_back(ToInt32(at(Slot::kColumn), "column", index));
  }
  if (has_timestamp_) cloud_.timestamp_s.push_back(at(Slot::kTimestamp));
}

void DecodeFixed(const char* base, std::uint64_t count, const std::vector<FieldLoad>& fields,
                 bool swap, CloudBuilder& builder) {
  double v[kSlotCount] = {};
  const bool native_floats = !swap && std::all_of(fields.begin(), fields.end(), [](const auto& f) {
    return f.type == ScalarType::kFloat32;
  });
  if (native_floats) {  // the common case (x y z nx ny nz float): no per-value type dispatch
    for (std::uint64_t i = 0; i < count; ++i) {
      for (const FieldLoad& f : fields) {
        float value;
        std::memcpy(&value, base + f.start + i * f.step, sizeof(float));
        v[f.slot] = value;
      }
      builder.Add(v, i);
    }
    return;
  }
  for (std::uint64_t i = 0; i < count; ++i) {
    for (const FieldLoad& f : fields) {
      v[f.slot] = LoadAsDouble(base + f.start + i * f.step, f.type, swap);
    }
    builder.Add(v, i);
  }
}

void AppendNumber(std::string& out, double value) {
  char buf[32];
  const auto [ptr, ec] = std::to_chars(buf, buf + sizeof(buf), value);
  out.append(buf, ptr);
}

void AppendNumber(std::string& out, float value) {
  char buf[32];
  const auto [ptr, ec] = std::to_chars(buf, buf + sizeof(buf), value);
  out.append(buf, ptr);
}

void AppendNumber(std::string& out, std::int64_t value) {
  char buf[24];
  const auto [ptr, ec] = std::to_chars(buf, buf + sizeof(buf), value);
  out.append(buf, ptr);
}

void CheckWritable(const PointCloud& cloud, std::span<const Eigen::Vector3i> faces,
                   const WriteOptions& options, const std::string& what) {
  cloud.Validate(what);
  const auto n = static_cast<std::int64_t>(cloud.size());
  for (std::size_t t = 0; t < faces.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      if (faces[t][k] < 0 || faces[t][k] >= n) {
        throw InputError(what + ": face " + std::to_string(t) + " references vertex " +
                         std::to_string(faces[t][k]) + " but there are " + std::to_string(n) +
                         " vertices");
      }
    }
  }
  if (!options.positions_as_double && !cloud.empty()) {
    const BoundingBox box = cloud.Bounds();
    const double limit = std::numeric_limits<float>::max();
    if (box.min.minCoeff() < -limit || box.max.maxCoeff() > limit) {
      throw InputError(what +
                       ": coordinates beyond the float32 range; set "
                       "WriteOptions::positions_as_double");
    }
  }
}

}  // namespace lasercell::io::detail
