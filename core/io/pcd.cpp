// PCD reader (PCL's Point Cloud Data format, v0.5-v0.7; our own code, PCL is not a dependency
// of core). Header: VERSION, FIELDS, SIZE, TYPE (I/U/F), COUNT, WIDTH, HEIGHT, VIEWPOINT,
// POINTS, DATA ascii|binary|binary_compressed; '#' lines are comments (lasercell writes
// "# lasercell_format 1" and "# lasercell_grid ROWS COLS" there).
//  - binary: points one after another, fields in header order, little endian.
//  - binary_compressed: uint32 compressed size, uint32 uncompressed size, then LZF data that
//    decompresses to the fields one after another (all values of field 1, then of field 2...).
//  - Organized clouds (HEIGHT > 1, WIDTH > 0): grid_rows = HEIGHT, grid_cols = WIDTH and every
//    kept point gets profile = row, column = col (unless the file carries profile/column fields).
//  - VIEWPOINT is validated (7 finite numbers) but not applied: in PCL it is acquisition
//    metadata and points are stored in the cloud's own frame. A non-identity viewpoint is
//    mentioned in ReadReport::notes.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/io/codec.hpp"
#include "core/io/lzf.hpp"
#include "core/io/point_cloud_io.hpp"

namespace lasercell::io {
namespace {

using detail::ScalarType;
using detail::Slot;

enum class PcdData { kAscii, kBinary, kBinaryCompressed };

struct PcdField {
  std::string name;
  ScalarType type = ScalarType::kFloat32;
  std::uint64_t count = 1;  ///< Values per point (e.g. 33 for an FPFH histogram).
};

struct PcdHeader {
  std::vector<PcdField> fields;
  std::uint64_t width = 0, height = 1, points = 0;
  std::array<double, 7> viewpoint{0, 0, 0, 1, 0, 0, 0};  ///< tx ty tz qw qx qy qz.
  PcdData data = PcdData::kAscii;
  std::size_t data_offset = 0;
  int lasercell_format = 0;
  std::int32_t grid_rows = 0, grid_cols = 0;  ///< From "# lasercell_grid" (unorganized files).
};

/// A token fit for an error message: at most 40 printable characters.
std::string Printable(std::string_view token) {
  std::string out;
  for (char c : token.substr(0, 40)) out += (c >= 32 && c < 127) ? c : '?';
  return out;
}

bool ParseDouble(std::string_view token, double* value) {
  const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), *value);
  return ec == std::errc() && ptr == token.data() + token.size();
}

/// Maps TYPE and SIZE ("F" 4) to a scalar type.
bool PcdScalarType(char type, std::uint64_t size, ScalarType* out) {
  static constexpr ScalarType kSigned[] = {ScalarType::kInt8, ScalarType::kInt16,
                                           ScalarType::kInt32, ScalarType::kInt64};
  static constexpr ScalarType kUnsigned[] = {ScalarType::kUint8, ScalarType::kUint16,
                                             ScalarType::kUint32, ScalarType::kUint64};
  const int log2 = size == 1 ? 0 : size == 2 ? 1 : size == 4 ? 2 : size == 8 ? 3 : -1;
  if (log2 < 0) return false;
  if (type == 'I')
    *out = kSigned[log2];
  else if (type == 'U')
    *out = kUnsigned[log2];
  else if (type == 'F' && size >= 4)
    *out = size == 4 ? ScalarType::kFloat32 : ScalarType::kFloat64;
  else
    return false;
  return true;
}

void ParseComment(std::string_view line, PcdHeader* header) {
  const std::vector<std::string_view> t = detail::SplitTokens(line.substr(1));
  std::uint64_t a = 0, b = 0;
  if (t.size() == 2 && t[0] == "lasercell_format" && detail::ParseCount(t[1], &a) && a < 1000000) {
    header->lasercell_format = static_cast<int>(a);
  } else if (t.size() == 3 && t[0] == "lasercell_grid" && detail::ParseCount(t[1], &a) &&
             detail::ParseCount(t[2], &b) && a > 0 && b > 0 && a <= INT32_MAX && b <= INT32_MAX) {
    header->grid_rows = static_cast<std::int32_t>(a);
    header->grid_cols = static_cast<std::int32_t>(b);
  }
}

PcdHeader ParsePcdHeader(std::string_view bytes, const std::string& name) {
  PcdHeader h;
  std::vector<std::string_view> names, sizes, types, counts;
  bool have_width = false, have_points = false;
  std::size_t pos = 0, line_no = 0;
  while (pos < bytes.size()) {
    std::size_t eol = bytes.find('\n', pos);
    if (eol == std::string_view::npos) eol = bytes.size();
    const std::string_view line = bytes.substr(pos, eol - pos);
    pos = std::min(eol + 1, bytes.size());
    ++line_no;
    auto fail = [&](const std::string& problem) {
      throw FileError(name, "header line " + std::to_string(line_no) + ": " + problem);
    };
    if (!line.empty() && line[0] == '#') {
      ParseComment(line, &h);
      continue;
    }
    const std::vector<std::string_view> t = detail::SplitTokens(line);
    if (t.empty()) continue;
    const std::string_view key = t[0];
    const std::vector<std::string_view> args(t.begin() + 1, t.end());
    auto count_arg = [&](std::uint64_t* value) {
      if (args.size() != 1 || !detail::ParseCount(args[0], value)) {
        fail(std::string(key) + " needs one non-negative integer");
      }
    };
    if (key == "VERSION") {
    } else if (key == "FIELDS") {
      names = args;
    } else if (key == "SIZE") {
      sizes = args;
    } else if (key == "TYPE") {
      types = args;
    } else if (key == "COUNT") {
      counts = args;
    } else if (key == "WIDTH") {
      count_arg(&h.width);
      have_width = true;
    } else if (key == "HEIGHT") {
      count_arg(&h.height);
    } else if (key == "POINTS") {
      count_arg(&h.points);
      have_points = true;
    } else if (key == "VIEWPOINT") {
      bool ok = args.size() == 7;
      for (std::size_t k = 0; ok && k < 7; ++k) {
        ok = ParseDouble(args[k], &h.viewpoint[k]) && std::isfinite(h.viewpoint[k]);
      }
      if (!ok) fail("VIEWPOINT needs 7 finite numbers: tx ty tz qw qx qy qz");
    } else if (key == "DATA") {
      if (args.size() == 1 && args[0] == "ascii")
        h.data = PcdData::kAscii;
      else if (args.size() == 1 && args[0] == "binary")
        h.data = PcdData::kBinary;
      else if (args.size() == 1 && args[0] == "binary_compressed")
        h.data = PcdData::kBinaryCompressed;
      else
        fail("DATA must be ascii, binary or binary_compressed");
      h.data_offset = pos;
      break;
    } else {
      fail(line_no == 1 ? "not a PCD file: the header starts with '" + Printable(key) + "'"
                        : "unknown keyword '" + Printable(key) +
                              "'; expected VERSION, FIELDS, SIZE, TYPE, COUNT, WIDTH, HEIGHT, "
                              "VIEWPOINT, POINTS or DATA");
    }
  }
  if (h.data_offset == 0) {
    throw FileError(name,
                    "missing 'DATA' line: the PCD header never ends; the file is "
                    "truncated or not a PCD file");
  }
  if (names.empty()) throw FileError(name, "the header has no FIELDS line");
  if (sizes.size() != names.size() || types.size() != names.size() ||
      (!counts.empty() && counts.size() != names.size())) {
    throw FileError(name, "FIELDS lists " + std::to_string(names.size()) + " fields but SIZE has " +
                              std::to_string(sizes.size()) + ", TYPE " +
                              std::to_string(types.size()) + " and COUNT " +
                              std::to_string(counts.size()) + " entries; they must match");
  }
  for (std::size_t i = 0; i < names.size(); ++i) {
    PcdField f;
    f.name = std::string(names[i]);
    std::uint64_t size = 0;
    if (!detail::ParseCount(sizes[i], &size) || types[i].size() != 1 ||
        !PcdScalarType(types[i][0], size, &f.type)) {
      throw FileError(name, "field '" + f.name + "' has TYPE '" + Printable(types[i]) +
                                "' with SIZE '" + Printable(sizes[i]) +
                                "'; supported: I or U with 1, 2, 4, 8 bytes, F with 4 or 8");
    }
    if (!counts.empty() &&
        (!detail::ParseCount(counts[i], &f.count) || f.count == 0 || f.count > (1u << 20))) {
      throw FileError(name, "field '" + f.name + "' has COUNT '" + Printable(counts[i]) +
                                "'; expected an integer from 1 to 1048576");
    }
    h.fields.push_back(std::move(f));
  }
  if (!have_width) h.width = h.points;
  if (h.width != 0 && h.height > UINT64_MAX / h.width) {
    throw FileError(name, "WIDTH " + std::to_string(h.width) + " x HEIGHT " +
                              std::to_string(h.height) + " is too large");
  }
  if (!have_points) h.points = h.width * h.height;
  if (h.width * h.height != h.points) {
    throw FileError(name, "POINTS " + std::to_string(h.points) + " does not equal WIDTH " +
                              std::to_string(h.width) + " x HEIGHT " + std::to_string(h.height));
  }
  if (h.height > 1 && (h.width > INT32_MAX || h.height > INT32_MAX)) {
    throw FileError(name, "organized grid " + std::to_string(h.height) + " x " +
                              std::to_string(h.width) + " is too large");
  }
  return h;
}

/// Decodes the points of a parsed header.
class PcdReader {
 public:
  PcdReader(std::string_view bytes, const std::string& name, const PcdHeader& header,
            ReadReport* report)
      : bytes_(bytes), name_(name), h_(header), report_(*report) {}

  PointCloud Read();

 private:
  void DecodeAscii(detail::CloudBuilder& builder);
  void DecodeBinary(detail::CloudBuilder& builder, const char* base, bool field_major);
  std::string Decompress(std::size_t stride);

  std::string_view bytes_;
  const std::string& name_;
  const PcdHeader& h_;
  ReadReport& report_;
  std::vector<Slot> slots_;
};

void PcdReader::DecodeAscii(detail::CloudBuilder& builder) {
  detail::AsciiCursor cursor(bytes_, h_.data_offset);
  double v[detail::kSlotCount] = {};
  for (std::uint64_t i = 0; i < h_.points; ++i) {
    for (std::size_t f = 0; f < h_.fields.size(); ++f) {
      const PcdField& field = h_.fields[f];
      for (std::uint64_t c = 0; c < field.count; ++c) {
        double value = 0.0;
        const bool keep = slots_[f] != Slot::kIgnored;
        const detail::ScanStatus status = keep ? cursor.Next(field.type, &value) : cursor.Skip();
        if (status == detail::ScanStatus::kEnd) {
          throw FileError(name_, "data ends at point " + std::to_string(i) + " of " +
                                     std::to_string(h_.points) + " (field '" + field.name +
                                     "'); the file is truncated or POINTS is wrong");
        }
        if (status == detail::ScanStatus::kMalformed) {
          throw FileError(name_, "point " + std::to_string(i) + " (line " +
                                     std::to_string(cursor.Line()) + "): malformed number '" +
                                     cursor.CurrentToken() + "' for field '" + field.name +
                                     "'; fix or re-export the file");
        }
        if (keep) v[static_cast<std::size_t>(slots_[f])] = value;
      }
    }
    builder.Add(v, i);
  }
}

void PcdReader::DecodeBinary(detail::CloudBuilder& builder, const char* base, bool field_major) {
  // Point-major (binary): value of field f of point i at i * stride + offset_f.
  // Field-major (binary_compressed): at points * offset_f + i * field_bytes_f.
  std::size_t stride = 0;
  for (const PcdField& f : h_.fields) stride += detail::ScalarSize(f.type) * f.count;
  std::vector<detail::FieldLoad> fields;
  std::size_t offset = 0;
  for (std::size_t f = 0; f < h_.fields.size(); ++f) {
    const std::size_t field_bytes = detail::ScalarSize(h_.fields[f].type) * h_.fields[f].count;
    if (slots_[f] != Slot::kIgnored) {
      fields.push_back({field_major ? offset * h_.points : offset,
                        field_major ? field_bytes : stride, static_cast<std::size_t>(slots_[f]),
                        h_.fields[f].type});
    }
    offset += field_bytes;
  }
  detail::DecodeFixed(base, h_.points, fields, detail::SwapFromLittle(), builder);
}

std::string PcdReader::Decompress(std::size_t stride) {
  const std::size_t available = bytes_.size() - h_.data_offset;
  if (available < 8) {
    throw FileError(name_,
                    "binary_compressed data ends before its 8-byte size header; the file "
                    "is truncated");
  }
  const char* p = bytes_.data() + h_.data_offset;
  const std::uint32_t compressed = detail::LoadRaw<std::uint32_t>(p, detail::SwapFromLittle());
  const std::uint32_t uncompressed =
      detail::LoadRaw<std::uint32_t>(p + 4, detail::SwapFromLittle());
  if (compressed > available - 8) {
    throw FileError(name_, "binary_compressed block declares " + std::to_string(compressed) +
                               " bytes but only " + std::to_string(available - 8) +
                               " follow; the file is truncated");
  }
  const bool size_matches =
      detail::FitsIn(h_.points, stride, uncompressed) && h_.points * stride == uncompressed;
  if (!size_matches) {
    throw FileError(name_, "binary_compressed block decompresses to " +
                               std::to_string(uncompressed) + " bytes but POINTS " +
                               std::to_string(h_.points) + " x " + std::to_string(stride) +
                               " bytes per point needs a different size; the header or the data "
                               "is corrupt");
  }
  if (uncompressed > detail::LzfMaxDecompressedSize(compressed)) {
    throw FileError(name_, "binary_compressed block claims " + std::to_string(uncompressed) +
                               " bytes from " + std::to_string(compressed) +
                               " compressed bytes, more than LZF can produce; corrupt file");
  }
  std::string out(uncompressed, '\0');
  const std::string problem =
      detail::LzfDecompress({reinterpret_cast<const unsigned char*>(p + 8), compressed},
                            {reinterpret_cast<unsigned char*>(out.data()), out.size()});
  if (!problem.empty()) {
    throw FileError(name_, "corrupt binary_compressed (LZF) data: " + problem);
  }
  return out;
}

PointCloud PcdReader::Read() {
  std::vector<std::string> names;
  std::vector<bool> eligible;
  std::size_t stride = 0, values_per_point = 0;
  for (const PcdField& f : h_.fields) {
    names.push_back(f.name);
    eligible.push_back(f.count == 1);
    stride += detail::ScalarSize(f.type) * f.count;
    values_per_point += f.count;
  }
  std::array<bool, detail::kSlotCount> kept{};
  slots_ = detail::AssignSlots(names, eligible, &kept, &report_.ignored_fields);
  report_.fields_in_file = names;
  for (Slot s : {Slot::kX, Slot::kY, Slot::kZ}) {
    if (!kept[static_cast<std::size_t>(s)]) {
      const char* axis = s == Slot::kX ? "x" : s == Slot::kY ? "y" : "z";
      throw FileError(name_, std::string("FIELDS has no single-valued field '") + axis +
                                 "'; a point needs x, y and z");
    }
  }
  const auto profile = static_cast<std::size_t>(Slot::kProfile);
  const auto column = static_cast<std::size_t>(Slot::kColumn);
  // Organized file without profile/column fields: the grid cell follows from the index. A grid
  // of HEIGHT rows and WIDTH 0 holds no point: the cloud is empty and not organized.
  const bool organized = h_.height > 1 && h_.width > 0;
  const bool derive_grid = organized && !kept[profile] && !kept[column];
  if (derive_grid) kept[profile] = kept[column] = true;

  // Check that the data can hold POINTS before allocating anything of that size.
  const std::size_t available = bytes_.size() - h_.data_offset;
  std::string decompressed;
  if (h_.data == PcdData::kAscii &&
      !detail::FitsIn(h_.points, 2 * values_per_point, available + 1)) {
    throw FileError(name_, "POINTS " + std::to_string(h_.points) + " with " +
                               std::to_string(values_per_point) + " values each cannot fit in " +
                               std::to_string(available) +
                               " bytes of ASCII data (each value "
                               "needs at least 2 bytes); the file is truncated or POINTS is wrong");
  }
  if (h_.data == PcdData::kBinary && !detail::FitsIn(h_.points, stride, available)) {
    throw FileError(name_, "POINTS " + std::to_string(h_.points) + " of " + std::to_string(stride) +
                               " bytes need more than the " + std::to_string(available) +
                               " bytes of binary data; the file is "
                               "truncated or POINTS is wrong");
  }
  if (h_.data == PcdData::kBinaryCompressed) decompressed = Decompress(stride);

  detail::CloudBuilder builder(kept, static_cast<std::size_t>(h_.points), false, name_);
  if (derive_grid) builder.DeriveGridFromIndex(h_.width);
  if (h_.data == PcdData::kAscii) {
    DecodeAscii(builder);
  } else if (h_.data == PcdData::kBinary) {
    DecodeBinary(builder, bytes_.data() + h_.data_offset, false);
  } else {
    DecodeBinary(builder, decompressed.data(), true);
  }
  report_.points_in_file = static_cast<std::size_t>(h_.points);
  report_.dropped_non_finite = builder.dropped();
  PointCloud cloud = builder.Take();
  if (organized) {
    cloud.grid_rows = static_cast<std::int32_t>(h_.height);
    cloud.grid_cols = static_cast<std::int32_t>(h_.width);
  } else {
    cloud.grid_rows = h_.grid_rows;
    cloud.grid_cols = h_.grid_cols;
  }
  const auto& vp = h_.viewpoint;
  if (vp[0] != 0 || vp[1] != 0 || vp[2] != 0 || vp[3] != 1 || vp[4] != 0 || vp[5] != 0 ||
      vp[6] != 0) {
    report_.notes.push_back(
        "VIEWPOINT is not identity; it was not applied (PCL keeps points in "
        "the cloud frame and the viewpoint as metadata)");
  }
  // Sizes and finiteness hold by construction; only grid indices can be out of range.
  try {
    if (cloud.HasProfile() || cloud.HasColumn()) cloud.Validate("points");
  } catch (const InputError& error) {
    throw FileError(name_, error.what());
  }
  return cloud;
}

}  // namespace

PointCloud ParsePcd(std::string_view bytes, const std::string& name, ReadReport* report) {
  const PcdHeader header = ParsePcdHeader(bytes, name);
  ReadReport local;
  local.format = std::string("pcd ") + (header.data == PcdData::kAscii    ? "ascii"
                                        : header.data == PcdData::kBinary ? "binary"
                                                                          : "binary_compressed");
  local.lasercell_format_version = header.lasercell_format;
  PointCloud cloud = PcdReader(bytes, name, header, &local).Read();
  if (report != nullptr) *report = std::move(local);
  return cloud;
}

}  // namespace lasercell::io
