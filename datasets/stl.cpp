#include "datasets/stl.hpp"

#include <array>
#include <bit>
#include <cstdint>
#include <cstring>
#include <map>

#include "core/error.hpp"
#include "core/io/file_util.hpp"

namespace lasercell::datasets {

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

TriangleMesh DecodeBinaryStl(std::string_view bytes, const std::string& name) {
  if (bytes.size() < kHeaderBytes + 4) {
    throw InputError(name + ": not a binary STL file (" + std::to_string(bytes.size()) +
                     " bytes, shorter than the 84-byte header)");
  }
  const std::uint64_t count = GetU32(bytes, kHeaderBytes);
  const std::uint64_t expected = kHeaderBytes + 4 + kTriangleBytes * count;
  if (bytes.size() != expected) {
    throw InputError(name + ": binary STL declares " + std::to_string(count) + " triangles (" +
                     std::to_string(expected) + " bytes) but has " + std::to_string(bytes.size()) +
                     " bytes");
  }
  TriangleMesh mesh;
  std::map<std::array<float, 3>, int> index;
  std::size_t at = kHeaderBytes + 4;
  for (std::uint64_t t = 0; t < count; ++t, at += kTriangleBytes) {
    Eigen::Vector3i face;
    for (int c = 0; c < 3; ++c) {
      std::array<float, 3> p;
      for (int k = 0; k < 3; ++k) p[k] = GetFloat(bytes, at + 12 + 12 * c + 4 * k);
      auto [it, added] = index.emplace(p, static_cast<int>(mesh.vertices.positions.size()));
      if (added) mesh.vertices.positions.emplace_back(p[0], p[1], p[2]);
      face[c] = it->second;
    }
    mesh.faces.push_back(face);
  }
  return mesh;
}

void WriteStlMesh(const std::string& path, const TriangleMesh& mesh) {
  io::WriteFileAtomically(path, EncodeBinaryStl(mesh));
}

TriangleMesh ReadStlMesh(const std::string& path) {
  return DecodeBinaryStl(io::ReadFileBytes(path), path);
}

}  // namespace lasercell::datasets
