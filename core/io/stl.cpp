#include <array>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <map>

#include "core/error.hpp"
#include "core/frame_graph.hpp"  // FormatDouble
#include "core/io/file_util.hpp"
#include "core/io/mesh_io.hpp"

namespace lasercell::io {

namespace {

constexpr std::size_t kHeaderBytes = 80;
constexpr std::size_t kTriangleBytes = 50;

void PutU32(std::string& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
}

void PutFloat(std::string& out, double v) {
  PutU32(out, std::bit_cast<std::uint32_t>(static_cast<float>(v)));
}

std::uint32_t GetU32(std::string_view bytes, std::size_t at) {
  std::uint32_t v = 0;
  for (int i = 0; i < 4; ++i) {
    v |= static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[at + i])) << (8 * i);
  }
  return v;
}

float GetFloat(std::string_view bytes, std::size_t at) {
  return std::bit_cast<float>(GetU32(bytes, at));
}

}  // namespace

std::string EncodeBinaryStl(const TriangleMesh& mesh, const std::string& header) {
  if (header.size() > kHeaderBytes || header.rfind("solid", 0) == 0) {
    throw InputError("STL header must be at most 80 bytes and must not start with 'solid'");
  }
  const auto& v = mesh.vertices.positions;
  std::string out = header;
  out.resize(kHeaderBytes, '\0');
  out.reserve(kHeaderBytes + 4 + kTriangleBytes * mesh.faces.size());
  PutU32(out, static_cast<std::uint32_t>(mesh.faces.size()));
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    const Eigen::Vector3i& face = mesh.faces[f];
    for (int k = 0; k < 3; ++k) {
      if (face[k] < 0 || static_cast<std::size_t>(face[k]) >= v.size()) {
        throw InputError("STL export: face " + std::to_string(f) + " refers to vertex " +
                         std::to_string(face[k]) + " of " + std::to_string(v.size()));
      }
    }
    Eigen::Vector3d n = (v[face[1]] - v[face[0]]).cross(v[face[2]] - v[face[0]]);
    n = n.norm() > 0 ? Eigen::Vector3d(n.normalized()) : Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k) PutFloat(out, n[k]);
    for (int c = 0; c < 3; ++c) {
      for (int k = 0; k < 3; ++k) PutFloat(out, v[face[c]][k]);
    }
    out.push_back('\0');  // attribute byte count
    out.push_back('\0');
  }
  return out;
}

namespace {

// Merges identical vertices in first-seen order.
class VertexMerger {
 public:
  explicit VertexMerger(TriangleMesh* mesh) : mesh_(mesh) {}
  int Add(const Eigen::Vector3d& p) {
    auto [it, added] = index_.emplace(std::array<double, 3>{p.x(), p.y(), p.z()},
                                      static_cast<int>(mesh_->vertices.positions.size()));
    if (added) mesh_->vertices.positions.push_back(p);
    return it->second;
  }

 private:
  TriangleMesh* mesh_;
  std::map<std::array<double, 3>, int> index_;
};

TriangleMesh DecodeBinary(std::string_view bytes, std::uint64_t count, const std::string& name) {
  TriangleMesh mesh;
  VertexMerger merger(&mesh);
  std::size_t at = kHeaderBytes + 4;
  for (std::uint64_t t = 0; t < count; ++t, at += kTriangleBytes) {
    Eigen::Vector3i face;
    for (int c = 0; c < 3; ++c) {
      Eigen::Vector3d p;
      for (int k = 0; k < 3; ++k) p[k] = GetFloat(bytes, at + 12 + 12 * c + 4 * k);
      if (!p.allFinite()) {
        throw FileError(name, "binary STL triangle " + std::to_string(t) +
                                  " has a non-finite vertex coordinate");
      }
      face[c] = merger.Add(p);
    }
    mesh.faces.push_back(face);
  }
  return mesh;
}

// Line-by-line tokenizer for ASCII STL with line numbers for messages.
class AsciiStlReader {
 public:
  AsciiStlReader(std::string_view text, const std::string& name) : text_(text), name_(name) {}

  TriangleMesh Read() {
    TriangleMesh mesh;
    VertexMerger merger(&mesh);
    Expect("solid");
    SkipRestOfLine();
    for (;;) {
      const std::string_view word = Word();
      if (word == "endsolid") break;
      if (word != "facet")
        Fail("expected 'facet' or 'endsolid', found '" + std::string(word) + "'");
      Expect("normal");
      for (int k = 0; k < 3; ++k) Number();
      Expect("outer");
      Expect("loop");
      Eigen::Vector3i face;
      for (int c = 0; c < 3; ++c) {
        Expect("vertex");
        Eigen::Vector3d p;
        for (int k = 0; k < 3; ++k) p[k] = Number();
        face[c] = merger.Add(p);
      }
      Expect("endloop");
      Expect("endfacet");
      mesh.faces.push_back(face);
    }
    return mesh;
  }

 private:
  std::string_view Word() {
    while (at_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[at_]))) {
      if (text_[at_] == '\n') ++line_;
      ++at_;
    }
    const std::size_t begin = at_;
    while (at_ < text_.size() && !std::isspace(static_cast<unsigned char>(text_[at_]))) ++at_;
    if (begin == at_) Fail("unexpected end of file (a truncated ASCII STL?)");
    return text_.substr(begin, at_ - begin);
  }
  void Expect(std::string_view keyword) {
    const std::string_view word = Word();
    if (word != keyword) {
      Fail("expected '" + std::string(keyword) + "', found '" + std::string(word) + "'");
    }
  }
  double Number() {
    const std::string_view word = Word();
    double v = 0;
    const auto [end, ec] = std::from_chars(word.data(), word.data() + word.size(), v);
    if (ec != std::errc() || end != word.data() + word.size() || !std::isfinite(v)) {
      std::string problem = "'";
      problem.append(word);
      problem.append("' is not a finite number");
      Fail(problem);
    }
    return v;
  }
  void SkipRestOfLine() {
    while (at_ < text_.size() && text_[at_] != '\n') ++at_;
  }
  [[noreturn]] void Fail(const std::string& problem) const {
    throw FileError(name_, "ASCII STL line " + std::to_string(line_) + ": " + problem);
  }

  std::string_view text_;
  const std::string& name_;
  std::size_t at_ = 0;
  int line_ = 1;
};

}  // namespace

TriangleMesh DecodeStl(std::string_view bytes, const std::string& name) {
  if (bytes.size() >= kHeaderBytes + 4) {
    const std::uint64_t count = GetU32(bytes, kHeaderBytes);
    if (bytes.size() == kHeaderBytes + 4 + kTriangleBytes * count) {
      return DecodeBinary(bytes, count, name);
    }
  }
  std::size_t first = 0;
  while (first < bytes.size() && std::isspace(static_cast<unsigned char>(bytes[first]))) ++first;
  if (bytes.substr(first, 5) == "solid") return AsciiStlReader(bytes, name).Read();
  if (bytes.size() < kHeaderBytes + 4) {
    throw FileError(name, "not an STL file (" + std::to_string(bytes.size()) +
                              " bytes, shorter than the 84-byte binary header and not ASCII)");
  }
  const std::uint64_t count = GetU32(bytes, kHeaderBytes);
  throw FileError(name, "binary STL declares " + std::to_string(count) + " triangles (" +
                            std::to_string(kHeaderBytes + 4 + kTriangleBytes * count) +
                            " bytes) but has " + std::to_string(bytes.size()) +
                            " bytes: truncated or not an STL file");
}

std::string EncodeAsciiStl(const TriangleMesh& mesh, const std::string& name) {
  const auto& v = mesh.vertices.positions;
  std::string out = "solid " + name + "\n";
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    const Eigen::Vector3i& face = mesh.faces[f];
    for (int k = 0; k < 3; ++k) {
      if (face[k] < 0 || static_cast<std::size_t>(face[k]) >= v.size()) {
        throw InputError("STL export: face " + std::to_string(f) + " refers to vertex " +
                         std::to_string(face[k]) + " of " + std::to_string(v.size()));
      }
    }
    Eigen::Vector3d n = (v[face[1]] - v[face[0]]).cross(v[face[2]] - v[face[0]]);
    n = n.norm() > 0 ? Eigen::Vector3d(n.normalized()) : Eigen::Vector3d::Zero();
    out += "  facet normal " + FormatDouble(n.x()) + " " + FormatDouble(n.y()) + " " +
           FormatDouble(n.z()) + "\n    outer loop\n";
    for (int c = 0; c < 3; ++c) {
      const Eigen::Vector3d& p = v[face[c]];
      out += "      vertex " + FormatDouble(p.x()) + " " + FormatDouble(p.y()) + " " +
             FormatDouble(p.z()) + "\n";
    }
    out += "    endloop\n  endfacet\n";
  }
  out += "endsolid " + name + "\n";
  return out;
}

void WriteStlMesh(const std::string& path, const TriangleMesh& mesh) {
  WriteFileAtomically(path, EncodeBinaryStl(mesh));
}

TriangleMesh ReadStlMesh(const std::string& path) { return DecodeStl(ReadFileBytes(path), path); }

}  // namespace lasercell::io
