// PLY reader (Turk 1994 format; http://paulbourke.net/dataformats/ply/): header parsing, then
// the elements in header order. ASCII data is a token stream parsed with std::from_chars;
// binary data is decoded with memcpy (codec.hpp), vertices without list properties in a fixed
// stride. Before anything proportional to a declared count is allocated, the count is checked
// against the bytes that remain (ASCII: >= 2 bytes per value; binary: count * minimum
// instance size, overflow-safe), so a corrupt header cannot make us allocate gigabytes.
// Vertices with a non-finite position or normal are dropped; faces are remapped to the kept
// vertices and triangles that touch a dropped vertex are dropped too (ReadReport::dropped_faces).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/io/codec.hpp"
#include "core/io/ply_header.hpp"
#include "core/io/point_cloud_io.hpp"

namespace lasercell::io {
namespace {

using detail::ScalarType;
using detail::Slot;

/// Reads the data section of a parsed PLY file.
class PlyReader {
 public:
  PlyReader(std::string_view bytes, const std::string& name, const detail::PlyHeader& header,
            ReadReport* report)
      : bytes_(bytes),
        name_(name),
        header_(header),
        report_(*report),
        ascii_(header.format == detail::PlyFormat::kAscii),
        swap_(header.format == detail::PlyFormat::kBinaryBigEndian ? detail::SwapFromBig()
                                                                   : detail::SwapFromLittle()),
        pos_(header.data_offset),
        cursor_(bytes, header.data_offset) {}

  TriangleMesh Read();

 private:
  void ReadVertices(const detail::PlyElement& e);
  void ReadFaces(const detail::PlyElement& e, std::size_t list_index);
  void SkipElement(const detail::PlyElement& e);
  void CheckRoom(const detail::PlyElement& e, const detail::PlyProperty* face_list);
  double Value(ScalarType type, const detail::PlyElement& e, std::uint64_t index,
               const detail::PlyProperty& p);
  void SkipValue(ScalarType type, const detail::PlyElement& e, std::uint64_t index,
                 const detail::PlyProperty& p);
  std::uint64_t ListLength(const detail::PlyElement& e, std::uint64_t index,
                           const detail::PlyProperty& p);
  void SkipList(std::uint64_t length, const detail::PlyElement& e, std::uint64_t index,
                const detail::PlyProperty& p);
  void FinishFaces();
  [[noreturn]] void Fail(const detail::PlyElement& e, std::uint64_t index,
                         const std::string& problem) const;

  std::string_view bytes_;
  const std::string& name_;
  const detail::PlyHeader& header_;
  ReadReport& report_;
  bool ascii_;
  bool swap_;
  std::size_t pos_;             // binary read position
  detail::AsciiCursor cursor_;  // ASCII read position
  PointCloud vertices_;
  std::vector<std::int64_t> remap_;
  std::uint64_t vertex_count_ = 0;
  bool vertices_read_ = false;
  std::vector<Eigen::Vector3i> faces_;  // file vertex indices until FinishFaces()
};

std::size_t Remaining(std::string_view bytes, std::size_t pos) { return bytes.size() - pos; }

void PlyReader::Fail(const detail::PlyElement& e, std::uint64_t index,
                     const std::string& problem) const {
  std::string where = "element '" + e.name + "' " + std::to_string(index);
  if (ascii_) where += " (line " + std::to_string(cursor_.Line()) + ")";
  throw FileError(name_, where + ": " + problem);
}

double PlyReader::Value(ScalarType type, const detail::PlyElement& e, std::uint64_t index,
                        const detail::PlyProperty& p) {
  double value = 0.0;
  if (ascii_) {
    switch (cursor_.Next(type, &value)) {
      case detail::ScanStatus::kOk:
        return value;
      case detail::ScanStatus::kEnd:
        Fail(e, index,
             "data ends before property '" + p.name + "' (" + std::to_string(index) + " of " +
                 std::to_string(e.count) +
                 " read); the file is truncated or the count in the header is wrong");
      case detail::ScanStatus::kMalformed:
        Fail(e, index,
             "malformed number '" + cursor_.CurrentToken() + "' for property '" + p.name +
                 "' of type " + detail::PlyTypeName(type) + "; fix or re-export the file");
    }
  }
  const std::size_t size = detail::ScalarSize(type);
  if (size > Remaining(bytes_, pos_)) {
    Fail(e, index,
         "data ends inside property '" + p.name + "' (" + std::to_string(index) + " of " +
             std::to_string(e.count) + " read); the file is truncated");
  }
  value = detail::LoadAsDouble(bytes_.data() + pos_, type, swap_);
  pos_ += size;
  return value;
}

void PlyReader::SkipValue(ScalarType type, const detail::PlyElement& e, std::uint64_t index,
                          const detail::PlyProperty& p) {
  // Values we do not keep are not parsed (a foreign writer's odd text there is harmless).
  const bool ok = ascii_ ? cursor_.Skip() == detail::ScanStatus::kOk
                         : detail::ScalarSize(type) <= Remaining(bytes_, pos_);
  if (!ok) {
    Fail(e, index,
         "data ends before property '" + p.name + "' (" + std::to_string(index) + " of " +
             std::to_string(e.count) +
             " read); the file is truncated or the count in the header is wrong");
  }
  if (!ascii_) pos_ += detail::ScalarSize(type);
}

std::uint64_t PlyReader::ListLength(const detail::PlyElement& e, std::uint64_t index,
                                    const detail::PlyProperty& p) {
  const double length = Value(p.count_type, e, index, p);
  if (length < 0) Fail(e, index, "list '" + p.name + "' has negative length");
  return static_cast<std::uint64_t>(length);
}

void PlyReader::SkipList(std::uint64_t length, const detail::PlyElement& e, std::uint64_t index,
                         const detail::PlyProperty& p) {
  if (ascii_) {
    for (std::uint64_t k = 0; k < length; ++k) SkipValue(p.type, e, index, p);
    return;
  }
  if (!detail::FitsIn(length, detail::ScalarSize(p.type), Remaining(bytes_, pos_))) {
    Fail(e, index,
         "list '" + p.name + "' of " + std::to_string(length) +
             " items runs past the end of the file; the file is truncated");
  }
  pos_ += static_cast<std::size_t>(length * detail::ScalarSize(p.type));
}

void PlyReader::CheckRoom(const detail::PlyElement& e, const detail::PlyProperty* face_list) {
  const std::size_t remaining = ascii_ ? cursor_.Remaining() : Remaining(bytes_, pos_);
  if (ascii_) {
    // Every value takes at least one character and one separator (the last one may lack it).
    const std::uint64_t min_bytes = 2 * e.MinTokens(face_list);
    if (detail::FitsIn(e.count, min_bytes, remaining + 1)) return;
    throw FileError(name_, "element '" + e.name + "' declares " + std::to_string(e.count) +
                               " instances but only " + std::to_string(remaining) +
                               " bytes of ASCII data remain (each value needs at least 2 "
                               "bytes); the file is truncated or the count is wrong");
  }
  const std::uint64_t min_bytes = e.MinBytes(face_list);
  if (detail::FitsIn(e.count, min_bytes, remaining)) return;
  throw FileError(name_, "element '" + e.name + "' declares " + std::to_string(e.count) +
                             " instances of at least " + std::to_string(min_bytes) +
                             " bytes but only " + std::to_string(remaining) +
                             " bytes of data remain; the file is truncated or the count is wrong");
}

void PlyReader::ReadVertices(const detail::PlyElement& e) {
  if (vertices_read_) {
    throw FileError(name_, "header line " + std::to_string(e.header_line) +
                               ": a second 'vertex' element; a PLY file has one");
  }
  CheckRoom(e, nullptr);
  std::vector<std::string> names;
  std::vector<bool> eligible;
  for (const auto& p : e.properties) {
    names.push_back(p.name);
    eligible.push_back(!p.is_list);
  }
  std::array<bool, detail::kSlotCount> kept{};
  const std::vector<Slot> slots =
      detail::AssignSlots(names, eligible, &kept, &report_.ignored_fields);
  report_.fields_in_file = names;
  report_.points_in_file = static_cast<std::size_t>(e.count);
  for (Slot s : {Slot::kX, Slot::kY, Slot::kZ}) {
    if (!kept[static_cast<std::size_t>(s)]) {
      const char* axis = s == Slot::kX ? "x" : s == Slot::kY ? "y" : "z";
      throw FileError(name_, "element 'vertex' (header line " + std::to_string(e.header_line) +
                                 ") has no scalar property '" + axis +
                                 "'; a vertex needs x, y and z");
    }
  }
  detail::CloudBuilder builder(kept, static_cast<std::size_t>(e.count), header_.HasElement("face"),
                               name_);
  if (!ascii_ && !e.HasList()) {
    // Fixed stride: CheckRoom proved count * stride bytes are there.
    std::vector<detail::FieldLoad> fields;
    std::size_t offset = 0;
    for (std::size_t j = 0; j < e.properties.size(); ++j) {
      if (slots[j] != Slot::kIgnored) {
        fields.push_back({offset, 0, static_cast<std::size_t>(slots[j]), e.properties[j].type});
      }
      offset += detail::ScalarSize(e.properties[j].type);
    }
    for (detail::FieldLoad& f : fields) f.step = offset;
    detail::DecodeFixed(bytes_.data() + pos_, e.count, fields, swap_, builder);
    pos_ += static_cast<std::size_t>(e.count) * offset;
  } else {
    double v[detail::kSlotCount] = {};
    for (std::uint64_t i = 0; i < e.count; ++i) {
      for (std::size_t j = 0; j < e.properties.size(); ++j) {
        const detail::PlyProperty& p = e.properties[j];
        if (p.is_list) {
          SkipList(ListLength(e, i, p), e, i, p);
          continue;
        }
        if (slots[j] == Slot::kIgnored) {
          SkipValue(p.type, e, i, p);
        } else {
          v[static_cast<std::size_t>(slots[j])] = Value(p.type, e, i, p);
        }
      }
      builder.Add(v, i);
    }
  }
  report_.dropped_non_finite = builder.dropped();
  remap_ = builder.TakeRemap();
  vertices_ = builder.Take();
  vertex_count_ = e.count;
  vertices_read_ = true;
}

void PlyReader::ReadFaces(const detail::PlyElement& e, std::size_t list_index) {
  const detail::PlyProperty& list = e.properties[list_index];
  CheckRoom(e, &list);
  faces_.reserve(faces_.size() + static_cast<std::size_t>(e.count));
  std::vector<std::int32_t> polygon;
  for (std::uint64_t i = 0; i < e.count; ++i) {
    for (std::size_t j = 0; j < e.properties.size(); ++j) {
      const detail::PlyProperty& p = e.properties[j];
      if (j != list_index) {
        if (p.is_list) {
          SkipList(ListLength(e, i, p), e, i, p);
        } else {
          SkipValue(p.type, e, i, p);
        }
        continue;
      }
      const std::uint64_t n = ListLength(e, i, p);
      if (n < 3) {
        Fail(e, i, "face has " + std::to_string(n) + " vertex indices; a face needs at least 3");
      }
      polygon.clear();
      for (std::uint64_t k = 0; k < n; ++k) {
        const double index = Value(p.type, e, i, p);
        // Faces may precede the vertices; FinishFaces() checks those against the count.
        const double limit =
            std::min(vertices_read_ ? static_cast<double>(vertex_count_) : 1e300, 2147483647.0);
        if (!(index >= 0 && index < limit) || index != std::floor(index)) {
          std::string text;
          detail::AppendNumber(text, index);
          Fail(e, i,
               "vertex index " + text +
                   (vertices_read_ ? " is out of range; the file has " +
                                         std::to_string(vertex_count_) + " vertices"
                                   : std::string(" is negative or beyond int32")));
        }
        polygon.push_back(static_cast<std::int32_t>(index));
      }
      // Fan the polygon around its first vertex (keeps the winding of a convex polygon).
      for (std::size_t k = 1; k + 1 < polygon.size(); ++k) {
        faces_.emplace_back(polygon[0], polygon[k], polygon[k + 1]);
      }
    }
  }
}

void PlyReader::SkipElement(const detail::PlyElement& e) {
  CheckRoom(e, nullptr);
  if (e.count > 0) {
    report_.notes.push_back("skipped element '" + e.name + "' (" + std::to_string(e.count) +
                            " instances)");
  }
  // An element without properties occupies no data, whatever its count (up to 2^64 - 1): a loop
  // over its instances would only spin.
  if (e.properties.empty()) return;
  if (!ascii_ && !e.HasList()) {
    pos_ += static_cast<std::size_t>(e.count * e.MinBytes(nullptr));  // CheckRoom: fits
    return;
  }
  for (std::uint64_t i = 0; i < e.count; ++i) {
    for (const detail::PlyProperty& p : e.properties) {
      if (p.is_list) {
        SkipList(ListLength(e, i, p), e, i, p);
      } else {
        SkipValue(p.type, e, i, p);
      }
    }
  }
}

void PlyReader::FinishFaces() {
  std::size_t kept = 0;
  for (std::size_t t = 0; t < faces_.size(); ++t) {
    Eigen::Vector3i face = faces_[t];
    bool dropped = false;
    for (int k = 0; k < 3; ++k) {
      if (static_cast<std::uint64_t>(face[k]) >= vertex_count_) {
        throw FileError(name_, "triangle " + std::to_string(t) + " references vertex " +
                                   std::to_string(face[k]) + " but the file has " +
                                   std::to_string(vertex_count_) + " vertices");
      }
      if (!remap_.empty()) {
        const std::int64_t mapped = remap_[static_cast<std::size_t>(face[k])];
        dropped = dropped || mapped < 0;
        face[k] = static_cast<std::int32_t>(mapped);
      }
    }
    if (dropped) {
      ++report_.dropped_faces;
    } else {
      faces_[kept++] = face;
    }
  }
  faces_.resize(kept);
}

TriangleMesh PlyReader::Read() {
  for (const detail::PlyElement& e : header_.elements) {
    if (e.name == "vertex") {
      ReadVertices(e);
      continue;
    }
    if (e.name == "face") {
      const std::size_t list_index = e.FaceListIndex();
      if (list_index < e.properties.size()) {
        ReadFaces(e, list_index);
        continue;
      }
    }
    SkipElement(e);
  }
  FinishFaces();
  TriangleMesh mesh;
  mesh.vertices = std::move(vertices_);
  mesh.vertices.grid_rows = header_.grid_rows;
  mesh.vertices.grid_cols = header_.grid_cols;
  mesh.faces = std::move(faces_);
  // Sizes and finiteness hold by construction; only grid indices can be out of range.
  try {
    if (mesh.vertices.HasProfile() || mesh.vertices.HasColumn()) mesh.vertices.Validate("vertices");
  } catch (const InputError& error) {
    throw FileError(name_, error.what());
  }
  report_.faces = mesh.faces.size();
  return mesh;
}

}  // namespace

TriangleMesh ParsePly(std::string_view bytes, const std::string& name, ReadReport* report) {
  const detail::PlyHeader header = detail::ParsePlyHeader(bytes, name);
  if (!header.HasElement("vertex")) {
    throw FileError(name, "the header declares no 'element vertex'; nothing to read");
  }
  ReadReport local;
  local.format = "ply " + std::string(detail::PlyFormatName(header.format));
  local.lasercell_format_version = header.lasercell_format;
  TriangleMesh mesh = PlyReader(bytes, name, header, &local).Read();
  if (report != nullptr) *report = std::move(local);
  return mesh;
}

}  // namespace lasercell::io
