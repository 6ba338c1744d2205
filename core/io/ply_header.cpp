#include "core/io/ply_header.hpp"

#include <algorithm>
#include <limits>

#include "core/error.hpp"

namespace lasercell::io::detail {
namespace {

constexpr const char* kTypeList =
    "char uchar short ushort int uint float double (or int8 uint8 int16 uint16 int32 uint32 "
    "float32 float64)";

bool ParsePlyType(std::string_view name, ScalarType* type) {
  struct Entry {
    std::string_view name;
    ScalarType type;
  };
  static constexpr Entry kTypes[] = {
      {"char", ScalarType::kInt8},      {"int8", ScalarType::kInt8},
      {"uchar", ScalarType::kUint8},    {"uint8", ScalarType::kUint8},
      {"short", ScalarType::kInt16},    {"int16", ScalarType::kInt16},
      {"ushort", ScalarType::kUint16},  {"uint16", ScalarType::kUint16},
      {"int", ScalarType::kInt32},      {"int32", ScalarType::kInt32},
      {"uint", ScalarType::kUint32},    {"uint32", ScalarType::kUint32},
      {"float", ScalarType::kFloat32},  {"float32", ScalarType::kFloat32},
      {"double", ScalarType::kFloat64}, {"float64", ScalarType::kFloat64},
  };
  for (const Entry& e : kTypes) {
    if (e.name == name) {
      *type = e.type;
      return true;
    }
  }
  return false;
}

/// Reads a positive int32 ("lasercell_grid 480 640").
bool ParsePositiveInt32(std::string_view token, std::int32_t* value) {
  std::uint64_t v = 0;
  if (!ParseCount(token, &v) || v == 0 || v > std::numeric_limits<std::int32_t>::max()) {
    return false;
  }
  *value = static_cast<std::int32_t>(v);
  return true;
}

}  // namespace

bool PlyElement::HasList() const {
  return std::any_of(properties.begin(), properties.end(),
                     [](const PlyProperty& p) { return p.is_list; });
}

std::uint64_t PlyElement::MinBytes(const PlyProperty* face_list) const {
  std::uint64_t bytes = 0;
  for (const PlyProperty& p : properties) {
    if (!p.is_list) {
      bytes += ScalarSize(p.type);
    } else {
      bytes += ScalarSize(p.count_type) + (&p == face_list ? 3 * ScalarSize(p.type) : 0);
    }
  }
  return bytes;
}

std::uint64_t PlyElement::MinTokens(const PlyProperty* face_list) const {
  std::uint64_t tokens = 0;
  for (const PlyProperty& p : properties) tokens += 1 + (&p == face_list ? 3 : 0);
  return tokens;
}

std::size_t PlyElement::FaceListIndex() const {
  for (std::size_t i = 0; i < properties.size(); ++i) {
    const PlyProperty& p = properties[i];
    if (p.is_list && (p.name == "vertex_indices" || p.name == "vertex_index")) return i;
  }
  return properties.size();
}

bool PlyHeader::HasElement(std::string_view name) const {
  return std::any_of(elements.begin(), elements.end(),
                     [name](const PlyElement& e) { return e.name == name; });
}

const char* PlyFormatName(PlyFormat format) {
  switch (format) {
    case PlyFormat::kAscii:
      return "ascii";
    case PlyFormat::kBinaryLittleEndian:
      return "binary_little_endian";
    case PlyFormat::kBinaryBigEndian:
      return "binary_big_endian";
  }
  return "?";
}

const char* PlyTypeName(ScalarType type) {
  switch (type) {
    case ScalarType::kInt8:
      return "char";
    case ScalarType::kUint8:
      return "uchar";
    case ScalarType::kInt16:
      return "short";
    case ScalarType::kUint16:
      return "ushort";
    case ScalarType::kInt32:
      return "int";
    case ScalarType::kUint32:
      return "uint";
    case ScalarType::kInt64:
      return "int64";
    case ScalarType::kUint64:
      return "uint64";
    case ScalarType::kFloat32:
      return "float";
    case ScalarType::kFloat64:
      return "double";
  }
  return "?";
}

PlyHeader ParsePlyHeader(std::string_view bytes, const std::string& name) {
  if (!(bytes.starts_with("ply\n") || bytes.starts_with("ply\r\n"))) {
    throw FileError(name, "not a PLY file: first line must be 'ply'");
  }
  // Looking for the terminator first keeps a header without one from being parsed into the
  // binary data that follows it.
  if (bytes.find("end_header") == std::string_view::npos) {
    throw FileError(name,
                    "missing 'end_header': the PLY header never ends; the file is "
                    "truncated or not a PLY file");
  }
  PlyHeader header;
  bool have_format = false;
  std::size_t pos = bytes.find('\n') + 1;
  std::size_t line_no = 1;
  while (true) {
    if (pos >= bytes.size()) {
      throw FileError(name,
                      "missing 'end_header': the PLY header never ends; the file is "
                      "truncated or not a PLY file");
    }
    std::size_t eol = bytes.find('\n', pos);
    if (eol == std::string_view::npos) eol = bytes.size();
    const std::string_view line = bytes.substr(pos, eol - pos);
    pos = std::min(eol + 1, bytes.size());
    ++line_no;
    const std::vector<std::string_view> t = SplitTokens(line);
    if (t.empty()) continue;
    auto fail = [&](const std::string& problem) {
      throw FileError(name, "header line " + std::to_string(line_no) + ": " + problem);
    };
    const std::string_view keyword = t[0];
    if (keyword == "end_header") {
      if (!have_format) fail("'end_header' before any 'format' line");
      header.data_offset = pos;
      return header;
    }
    if (keyword == "format") {
      if (t.size() != 3) fail("expected 'format ascii|binary_little_endian|binary_big_endian 1.0'");
      if (t[1] == "ascii") {
        header.format = PlyFormat::kAscii;
      } else if (t[1] == "binary_little_endian") {
        header.format = PlyFormat::kBinaryLittleEndian;
      } else if (t[1] == "binary_big_endian") {
        header.format = PlyFormat::kBinaryBigEndian;
      } else {
        fail("unknown format '" + std::string(t[1]) +
             "'; expected ascii, binary_little_endian or binary_big_endian");
      }
      have_format = true;
    } else if (keyword == "comment") {
      if (t.size() >= 2 && t[1] == "lasercell_format") {
        std::uint64_t version = 0;
        if (t.size() != 3 || !ParseCount(t[2], &version) || version > 1000000) {
          fail("malformed comment; expected 'comment lasercell_format N'");
        }
        header.lasercell_format = static_cast<int>(version);
      } else if (t.size() >= 2 && t[1] == "lasercell_grid") {
        if (t.size() != 4 || !ParsePositiveInt32(t[2], &header.grid_rows) ||
            !ParsePositiveInt32(t[3], &header.grid_cols)) {
          fail(
              "malformed comment; expected 'comment lasercell_grid ROWS COLS' with positive "
              "integers");
        }
      }
    } else if (keyword == "obj_info") {
      // Free text, nothing we use.
    } else if (keyword == "element") {
      PlyElement element;
      if (t.size() != 3) fail("expected 'element NAME COUNT'");
      element.name = std::string(t[1]);
      if (!ParseCount(t[2], &element.count)) {
        fail("element '" + element.name + "' has count '" + std::string(t[2]) +
             "'; expected a non-negative integer");
      }
      element.header_line = line_no;
      header.elements.push_back(std::move(element));
    } else if (keyword == "property") {
      if (header.elements.empty()) fail("'property' before any 'element'");
      PlyProperty property;
      const bool is_list = t.size() >= 2 && t[1] == "list";
      if ((is_list && t.size() != 5) || (!is_list && t.size() != 3)) {
        fail("expected 'property TYPE NAME' or 'property list COUNT_TYPE ITEM_TYPE NAME'");
      }
      property.name = std::string(t.back());
      property.is_list = is_list;
      const std::string_view type_name = is_list ? t[3] : t[1];
      if (!ParsePlyType(type_name, &property.type)) {
        fail("property '" + property.name + "' has unknown type '" + std::string(type_name) +
             "'; supported: " + kTypeList);
      }
      if (is_list &&
          (!ParsePlyType(t[2], &property.count_type) || IsFloating(property.count_type))) {
        fail("list property '" + property.name + "' has count type '" + std::string(t[2]) +
             "'; the count type must be an integer type (uchar, ushort, uint, ...)");
      }
      header.elements.back().properties.push_back(std::move(property));
    } else {
      fail("unknown keyword '" + std::string(keyword) +
           "'; expected format, element, property, comment, obj_info or end_header");
    }
  }
}

}  // namespace lasercell::io::detail
