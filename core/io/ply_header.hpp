#pragma once
// Internal to core/io: the PLY header (format line, elements with their properties, comments)
// as parsed by ParsePlyHeader(); ply.cpp reads the data it describes.

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "core/io/codec.hpp"

namespace lasercell::io::detail {

/// Encoding named on the header's "format" line.
enum class PlyFormat { kAscii, kBinaryLittleEndian, kBinaryBigEndian };

/// One "property" line: a scalar, or a list (length of count_type, then items of type).
struct PlyProperty {
  std::string name;
  ScalarType type = ScalarType::kFloat32;      ///< Scalar type, or the item type of a list.
  bool is_list = false;                        ///< "property list COUNT_TYPE ITEM_TYPE NAME".
  ScalarType count_type = ScalarType::kUint8;  ///< Type of a list's length (integer).
};

/// One "element NAME COUNT" with its properties.
struct PlyElement {
  std::string name;
  std::uint64_t count = 0;  ///< Declared number of instances.
  std::vector<PlyProperty> properties;
  std::size_t header_line = 0;  ///< 1-based line of the "element" line.

  /// True when any property is a list (instances then vary in size).
  bool HasList() const;
  /// Binary bytes of one instance: exact without lists; the minimum otherwise (every list empty,
  /// except `face_list`, which needs at least 3 items).
  std::uint64_t MinBytes(const PlyProperty* face_list) const;
  /// Minimum ASCII values of one instance (same rule for lists).
  std::uint64_t MinTokens(const PlyProperty* face_list) const;
  /// Index of the list property "vertex_indices" or "vertex_index"; properties.size() if none.
  std::size_t FaceListIndex() const;
};

/// Everything the header says.
struct PlyHeader {
  PlyFormat format = PlyFormat::kAscii;
  std::vector<PlyElement> elements;
  std::size_t data_offset = 0;  ///< First byte after the "end_header" line.
  int lasercell_format = 0;     ///< From "comment lasercell_format N".
  std::int32_t grid_rows = 0;   ///< From "comment lasercell_grid ROWS COLS".
  std::int32_t grid_cols = 0;

  /// True when an element of that name is declared.
  bool HasElement(std::string_view name) const;
};

/// Parses the header of in-memory PLY bytes. Throws FileError naming `name`, the header line and
/// the problem: wrong magic, missing or unknown format, unknown keyword or property type, bad
/// counts, missing end_header.
PlyHeader ParsePlyHeader(std::string_view bytes, const std::string& name);

/// "ascii", "binary_little_endian", "binary_big_endian".
const char* PlyFormatName(PlyFormat format);
/// PLY name of a scalar type ("float", "uchar", ...).
const char* PlyTypeName(ScalarType type);

}  // namespace lasercell::io::detail
