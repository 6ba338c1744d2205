// Wavefront OBJ reading and the extension dispatch of ReadMesh (mesh_io.hpp).
#include <cctype>
#include <charconv>
#include <cmath>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.hpp"
#include "core/io/file_util.hpp"
#include "core/io/mesh_io.hpp"

namespace lasercell::io {
namespace {

std::vector<std::string_view> SplitWords(std::string_view line) {
  std::vector<std::string_view> words;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    const std::size_t begin = i;
    while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    if (i > begin) words.push_back(line.substr(begin, i - begin));
  }
  return words;
}

// Statements that carry no geometry lasercell uses.
bool IsSkippedStatement(std::string_view word) {
  static constexpr std::string_view kSkipped[] = {"vt", "vn",     "vp",       "o",        "g",
                                                  "s",  "usemtl", "mtllib",   "l",        "p",
                                                  "mg", "bevel",  "c_interp", "d_interp", "lod"};
  for (std::string_view s : kSkipped) {
    if (word == s) return true;
  }
  return false;
}

class ObjParser {
 public:
  ObjParser(std::string_view text, const std::string& name) : text_(text), name_(name) {}

  TriangleMesh Parse() {
    std::size_t at = 0;
    while (at <= text_.size()) {
      std::size_t end = text_.find('\n', at);
      if (end == std::string_view::npos) end = text_.size();
      std::string_view line = text_.substr(at, end - at);
      ++line_;
      at = end + 1;
      if (const std::size_t hash = line.find('#'); hash != std::string_view::npos) {
        line = line.substr(0, hash);
      }
      const std::vector<std::string_view> words = SplitWords(line);
      if (words.empty()) continue;
      if (words[0] == "v") {
        Vertex(words);
      } else if (words[0] == "f") {
        Face(words);
      } else if (!IsSkippedStatement(words[0])) {
        Fail("unknown statement '" + std::string(words[0]) + "'");
      }
      if (end == text_.size()) break;
    }
    if (mesh_.vertices.positions.empty()) Fail("no vertices ('v' lines): not an OBJ mesh");
    return std::move(mesh_);
  }

 private:
  void Vertex(const std::vector<std::string_view>& words) {
    if (words.size() != 4 && words.size() != 5) Fail("'v' needs x y z [w]");
    Eigen::Vector3d p;
    for (int k = 0; k < 3; ++k) p[k] = Number(words[static_cast<std::size_t>(k) + 1]);
    if (words.size() == 5) {
      const double w = Number(words[4]);
      if (!(w != 0.0)) Fail("'v' has w = 0");
      p /= w;
    }
    mesh_.vertices.positions.push_back(p);
  }

  void Face(const std::vector<std::string_view>& words) {
    if (words.size() < 4) Fail("'f' needs at least three vertices");
    std::vector<int> corner;
    for (std::size_t i = 1; i < words.size(); ++i) corner.push_back(Index(words[i]));
    for (std::size_t i = 2; i < corner.size(); ++i) {
      mesh_.faces.emplace_back(corner[0], corner[i - 1], corner[i]);
    }
  }

  // "i", "i/t", "i//n", "i/t/n"; 1-based, negative = relative to the last vertex.
  int Index(std::string_view word) {
    const std::string_view first = word.substr(0, word.find('/'));
    long long i = 0;
    const auto [end, ec] = std::from_chars(first.data(), first.data() + first.size(), i);
    if (ec != std::errc() || end != first.data() + first.size() || i == 0) {
      Fail("face vertex '" + std::string(word) + "' is not a vertex index");
    }
    const auto n = static_cast<long long>(mesh_.vertices.positions.size());
    const long long zero_based = i > 0 ? i - 1 : n + i;
    if (zero_based < 0 || zero_based >= n) {
      Fail("face vertex index " + std::to_string(i) + " is out of range (" + std::to_string(n) +
           " vertices so far)");
    }
    return static_cast<int>(zero_based);
  }

  double Number(std::string_view word) {
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

  [[noreturn]] void Fail(const std::string& problem) const {
    throw FileError(name_, "OBJ line " + std::to_string(line_) + ": " + problem);
  }

  std::string_view text_;
  const std::string& name_;
  TriangleMesh mesh_;
  int line_ = 0;
};

}  // namespace

TriangleMesh DecodeObj(std::string_view text, const std::string& name) {
  return ObjParser(text, name).Parse();
}

TriangleMesh ReadMesh(const std::string& path, ReadReport* report) {
  const std::string ext = LowerExtension(path);
  if (ext == ".ply") return ReadPlyMesh(path, report);
  TriangleMesh mesh;
  if (ext == ".stl") {
    mesh = ReadStlMesh(path);
  } else if (ext == ".obj") {
    mesh = DecodeObj(ReadFileBytes(path), path);
  } else {
    throw FileError(path, "unknown mesh extension '" + ext +
                              "': give an .stl, .obj or .ply mesh (or a .step/.iges part)");
  }
  if (report) {
    *report = ReadReport{};
    report->format = ext.substr(1);
    report->points_in_file = mesh.vertices.size();
    report->faces = mesh.faces.size();
  }
  return mesh;
}

void WriteMesh(const std::string& path, const TriangleMesh& mesh) {
  const std::string ext = LowerExtension(path);
  if (ext == ".stl") {
    WriteStlMesh(path, mesh);
  } else if (ext == ".ply") {
    WritePlyMesh(path, mesh);
  } else {
    throw FileError(path, "cannot write a mesh as '" + ext + "': give an .stl or .ply path");
  }
}

}  // namespace lasercell::io
