#pragma once
// Helpers shared by ply_test.cpp and pcd_test.cpp: locating the real data files, a seeded
// synthetic cloud with every attribute, a byte builder for hand-made binary files, and
// catching a FileError's message.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>

#include "core/error.hpp"
#include "core/point_cloud.hpp"

namespace lasercell::io::test {

/// Path of a bundled real data file, datasets/real/<set>/<file> (see datasets/real/README.md).
inline std::string RealDataFile(const std::string& set, const std::string& file) {
  return std::string(LASERCELL_SOURCE_DIR) + "/datasets/real/" + set + "/" + file;
}

/// Declares `var` as the path of a bundled real data file; a missing file fails the test (the
/// data ships with the repository, so its absence is a packaging bug, not a reason to skip).
#define LASERCELL_REAL_FILE(var, set, file)                               \
  const std::string var = ::lasercell::io::test::RealDataFile(set, file); \
  if (!std::filesystem::is_regular_file(var)) {                           \
    FAIL() << "bundled real data file " << var << " is missing";          \
  }

/// A cloud of n points with every attribute, coordinates that are not float-representable
/// (so float storage is visible), unit normals and an organized grid of `cols` columns.
inline PointCloud MakeFullCloud(std::size_t n, std::int32_t cols = 7, unsigned seed = 42) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> coord(-500.0, 500.0);
  std::normal_distribution<double> gauss;
  PointCloud c;
  for (std::size_t i = 0; i < n; ++i) {
    c.positions.push_back(Eigen::Vector3d{coord(rng), coord(rng), coord(rng)});
    c.normals.push_back(Eigen::Vector3d{gauss(rng), gauss(rng), gauss(rng) + 3.0}.normalized());
    c.intensity.push_back(static_cast<float>(coord(rng)) * 0.37f);
    c.profile.push_back(static_cast<std::int32_t>(i) / cols);
    c.column.push_back(static_cast<std::int32_t>(i) % cols);
    c.timestamp_s.push_back(1.7e9 + 1e-4 * static_cast<double>(i) + 1e-7 / 3.0);
  }
  c.grid_rows = static_cast<std::int32_t>((n + cols - 1) / cols);
  c.grid_cols = cols;
  return c;
}

/// A double rounded to float32 and widened back. Not inlined on purpose: GCC 12.2's SLP
/// vectorizer at -O2 folds two adjacent (double)(float)x conversions into x (wrong code; see
/// the report of the io work), which made bit-exact comparisons fail spuriously.
[[gnu::noinline]] inline double ThroughFloat(double value) {
  return static_cast<double>(static_cast<float>(value));
}

/// Value stored as float32 and read back as double.
inline Eigen::Vector3d AsFloat(const Eigen::Vector3d& v) {
  return {ThroughFloat(v.x()), ThroughFloat(v.y()), ThroughFloat(v.z())};
}

/// Builds binary file contents byte by byte, independent of the writers under test.
class Bytes {
 public:
  Bytes& Text(const std::string& text) {
    data_ += text;
    return *this;
  }
  /// Appends values in little-endian order, each with its own type's size.
  template <typename... T>
  Bytes& Le(T... values) {
    (Put(values, std::endian::native != std::endian::little), ...);
    return *this;
  }
  /// Appends values in big-endian order.
  template <typename... T>
  Bytes& Be(T... values) {
    (Put(values, std::endian::native != std::endian::big), ...);
    return *this;
  }
  /// Appends raw bytes.
  Bytes& Raw(std::initializer_list<unsigned char> bytes) {
    for (unsigned char b : bytes) data_.push_back(static_cast<char>(b));
    return *this;
  }
  const std::string& str() const { return data_; }

 private:
  template <typename T>
  void Put(T value, bool swap) {
    char b[sizeof(T)];
    std::memcpy(b, &value, sizeof(T));
    if (swap) {
      for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
    }
    data_.append(b, sizeof(T));
  }
  std::string data_;
};

/// Runs f and returns the message of the FileError it throws (a failure when it throws none).
template <typename F>
std::string FileErrorMessage(F&& f) {
  try {
    f();
  } catch (const FileError& error) {
    return error.what();
  }
  ADD_FAILURE() << "expected a lasercell::FileError";
  return {};
}

/// Seeded corruptions of `bytes` (truncations, byte flips, digits replaced by '9'), each passed
/// to `parse`, which must either succeed or throw FileError: anything else (std::bad_alloc,
/// std::length_error, a crash or a sanitizer report) fails the calling test.
template <typename Parse>
void ExpectCorruptionsRejectedCleanly(const std::string& bytes, Parse&& parse, int trials = 400) {
  std::mt19937 rng(1234);
  for (int trial = 0; trial < trials; ++trial) {
    std::string corrupt = bytes;
    std::uniform_int_distribution<std::size_t> at(0, bytes.size() - 1);
    switch (trial % 4) {
      case 0:
        corrupt.resize(at(rng));
        break;
      case 1:
        corrupt[at(rng)] ^= static_cast<char>(1 + rng() % 255);
        break;
      case 2:
        for (int k = 0; k < 4; ++k) corrupt[at(rng)] = static_cast<char>(rng());
        break;
      default:
        for (char& c : corrupt) {
          if (c >= '0' && c <= '8' && rng() % 8 == 0) c = '9';
        }
    }
    try {
      parse(corrupt);
    } catch (const FileError&) {
    }
  }
}

}  // namespace lasercell::io::test
