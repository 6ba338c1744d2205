// Point-cloud IO speed (targets: rs1_normals.ply, 114k-vertex ASCII, <= 0.3 s; 1M-point binary
// PLY with normals <= 50 ms). Read benchmarks include reading the file from the page cache;
// write benchmarks include the atomic write (temp file, fsync, rename).
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <filesystem>
#include <random>
#include <string>

#include "core/io/file_util.hpp"
#include "core/io/point_cloud_io.hpp"

namespace {

using lasercell::PointCloud;
namespace io = lasercell::io;

/// datasets/real/<set>/<file> in the source tree, else ../shared/data/<set>/<file>; empty if
/// neither exists.
std::string RealDataFile(const std::string& set, const std::string& file) {
  for (const std::string& root : {std::string(LASERCELL_SOURCE_DIR) + "/datasets/real/",
                                  std::string(LASERCELL_SOURCE_DIR) + "/../shared/data/"}) {
    if (std::filesystem::is_regular_file(root + set + "/" + file)) return root + set + "/" + file;
  }
  return {};
}

/// 1M points with unit normals in a 1 m cube (mm), generated once.
const PointCloud& MillionPoints() {
  static const PointCloud cloud = [] {
    std::mt19937 rng(1);
    std::uniform_real_distribution<double> coord(-500.0, 500.0);
    PointCloud c;
    c.positions.reserve(1000000);
    c.normals.reserve(1000000);
    for (int i = 0; i < 1000000; ++i) {
      c.positions.push_back(Eigen::Vector3d{coord(rng), coord(rng), coord(rng)});
      c.normals.push_back(Eigen::Vector3d{coord(rng), coord(rng), coord(rng) + 1e3}.normalized());
    }
    return c;
  }();
  return cloud;
}

/// Temporary files of this process, removed at exit.
struct TempFiles {
  std::string dir = std::filesystem::temp_directory_path().string();
  std::string binary_ply = dir + "/lasercell_bench_1M_" + std::to_string(::getpid()) + ".ply";
  std::string written_ply = dir + "/lasercell_bench_out_" + std::to_string(::getpid()) + ".ply";
  ~TempFiles() {
    std::error_code ec;
    std::filesystem::remove(binary_ply, ec);
    std::filesystem::remove(written_ply, ec);
  }
};
TempFiles& Temp() {
  static TempFiles files;
  return files;
}

/// The 1M-point binary PLY (x y z nx ny nz float), written on first use.
const std::string& BinaryPly1M() {
  static const std::string path = [] {
    io::WritePointCloud(Temp().binary_ply, MillionPoints());
    return Temp().binary_ply;
  }();
  return path;
}

void ReadFileBenchmark(benchmark::State& state, const std::string& path) {
  std::size_t points = 0;
  for (auto _ : state) {
    const PointCloud cloud = io::ReadPointCloud(path);
    points = cloud.size();
    benchmark::DoNotOptimize(cloud.positions.data());
  }
  const auto bytes = static_cast<std::int64_t>(std::filesystem::file_size(path));
  state.SetBytesProcessed(state.iterations() * bytes);
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(points));
}

void BM_ReadAsciiPly_rs1(benchmark::State& state) {
  const std::string path = RealDataFile("uwa", "rs1_normals.ply");
  if (path.empty()) {
    state.SkipWithError("uwa/rs1_normals.ply not found in datasets/real or ../shared/data");
    return;
  }
  ReadFileBenchmark(state, path);
}
BENCHMARK(BM_ReadAsciiPly_rs1)->Unit(benchmark::kMillisecond);

void BM_ReadBinaryPly_1M(benchmark::State& state) { ReadFileBenchmark(state, BinaryPly1M()); }
BENCHMARK(BM_ReadBinaryPly_1M)->Unit(benchmark::kMillisecond);

/// Parsing alone (bytes already in memory).
void BM_ParseBinaryPly_1M(benchmark::State& state) {
  const std::string bytes = io::ReadFileBytes(BinaryPly1M());
  for (auto _ : state) {
    const lasercell::TriangleMesh mesh = io::ParsePly(bytes, "1M.ply");
    benchmark::DoNotOptimize(mesh.vertices.positions.data());
  }
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(bytes.size()));
}
BENCHMARK(BM_ParseBinaryPly_1M)->Unit(benchmark::kMillisecond);

void BM_WriteBinaryPly_1M(benchmark::State& state) {
  const PointCloud& cloud = MillionPoints();
  for (auto _ : state) io::WritePointCloud(Temp().written_ply, cloud);
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(cloud.size()));
}
BENCHMARK(BM_WriteBinaryPly_1M)->Unit(benchmark::kMillisecond);

/// Encoding alone (no file system).
void BM_EncodeBinaryPly_1M(benchmark::State& state) {
  const lasercell::TriangleMesh mesh{MillionPoints(), {}};
  for (auto _ : state) {
    const std::string bytes = io::EncodePly(mesh);
    benchmark::DoNotOptimize(bytes.data());
  }
}
BENCHMARK(BM_EncodeBinaryPly_1M)->Unit(benchmark::kMillisecond);

void BM_ReadCompressedPcd_Kinect(benchmark::State& state) {
  const std::string path = RealDataFile("pcl", "milk_cartoon_all_small_clorox.pcd");
  if (path.empty()) {
    state.SkipWithError("pcl/milk_cartoon_all_small_clorox.pcd not found");
    return;
  }
  ReadFileBenchmark(state, path);
}
BENCHMARK(BM_ReadCompressedPcd_Kinect)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
