// nanoflann vs FLANN on the queries lasercell's registration makes: exact k-nearest neighbours
// (normals, k = 10) and radius search (PPF pairs, connected components) on a real range scan
// (UWA rs1, 114k points, mm). Both exact single-tree kd-trees with the same leaf size.
// Run: build/bench/kdtree_benchmark
#include <benchmark/benchmark.h>

#include <flann/flann.hpp>
#include <nanoflann.hpp>
#include <string>
#include <vector>

#include "core/io/point_cloud_io.hpp"

namespace {

using lasercell::PointCloud;

const PointCloud& Scene() {
  static const PointCloud cloud = [] {
    try {
      return lasercell::io::ReadPointCloud(std::string(LASERCELL_SOURCE_DIR) +
                                           "/datasets/real/uwa/rs1_normals.bin.ply");
    } catch (const std::exception&) {
      return PointCloud{};
    }
  }();
  return cloud;
}

struct Adaptor {
  const std::vector<Eigen::Vector3d>& pts;
  std::size_t kdtree_get_point_count() const { return pts.size(); }
  double kdtree_get_pt(std::size_t i, std::size_t d) const { return pts[i][static_cast<int>(d)]; }
  template <class B>
  bool kdtree_get_bbox(B&) const {
    return false;
  }
};
using NanoTree =
    nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Adaptor>, Adaptor, 3>;
constexpr int kLeafSize = 10;
constexpr int kK = 10;
constexpr double kRadiusMm = 5.0;

void BM_Nanoflann_Build(benchmark::State& state) {
  const auto& cloud = Scene();
  if (cloud.empty()) return state.SkipWithError("datasets/real/uwa/rs1_normals.bin.ply missing");
  Adaptor adaptor{cloud.positions};
  for (auto _ : state) {
    NanoTree tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(kLeafSize));
    benchmark::DoNotOptimize(&tree);
  }
  state.counters["points"] = static_cast<double>(cloud.size());
}

void BM_Flann_Build(benchmark::State& state) {
  const auto& cloud = Scene();
  if (cloud.empty()) return state.SkipWithError("datasets/real/uwa/rs1_normals.bin.ply missing");
  flann::Matrix<double> data(const_cast<double*>(cloud.positions[0].data()), cloud.size(), 3);
  for (auto _ : state) {
    flann::Index<flann::L2_Simple<double>> index(data, flann::KDTreeSingleIndexParams(kLeafSize));
    index.buildIndex();
    benchmark::DoNotOptimize(&index);
  }
}

void BM_Nanoflann_Knn10_All(benchmark::State& state) {
  const auto& cloud = Scene();
  if (cloud.empty()) return state.SkipWithError("data missing");
  Adaptor adaptor{cloud.positions};
  NanoTree tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(kLeafSize));
  std::vector<unsigned> idx(kK);
  std::vector<double> d2(kK);
  for (auto _ : state) {
    for (const auto& p : cloud.positions) {
      benchmark::DoNotOptimize(tree.knnSearch(p.data(), kK, idx.data(), d2.data()));
    }
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(cloud.size()));
}

void BM_Flann_Knn10_All(benchmark::State& state) {
  const auto& cloud = Scene();
  if (cloud.empty()) return state.SkipWithError("data missing");
  flann::Matrix<double> data(const_cast<double*>(cloud.positions[0].data()), cloud.size(), 3);
  flann::Index<flann::L2_Simple<double>> index(data, flann::KDTreeSingleIndexParams(kLeafSize));
  index.buildIndex();
  std::vector<std::size_t> idx(kK);
  std::vector<double> d2(kK);
  flann::SearchParams params;
  params.checks = flann::FLANN_CHECKS_UNLIMITED;
  for (auto _ : state) {
    for (const auto& p : cloud.positions) {
      flann::Matrix<double> q(const_cast<double*>(p.data()), 1, 3);
      flann::Matrix<std::size_t> mi(idx.data(), 1, kK);
      flann::Matrix<double> md(d2.data(), 1, kK);
      benchmark::DoNotOptimize(index.knnSearch(q, mi, md, kK, params));
    }
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(cloud.size()));
}

void BM_Nanoflann_Radius5mm_All(benchmark::State& state) {
  const auto& cloud = Scene();
  if (cloud.empty()) return state.SkipWithError("data missing");
  Adaptor adaptor{cloud.positions};
  NanoTree tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(kLeafSize));
  std::vector<std::pair<unsigned, double>> matches;
  nanoflann::SearchParams params;
  params.sorted = false;
  for (auto _ : state) {
    for (const auto& p : cloud.positions) {
      benchmark::DoNotOptimize(tree.radiusSearch(p.data(), kRadiusMm * kRadiusMm, matches, params));
    }
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(cloud.size()));
}

void BM_Flann_Radius5mm_All(benchmark::State& state) {
  const auto& cloud = Scene();
  if (cloud.empty()) return state.SkipWithError("data missing");
  flann::Matrix<double> data(const_cast<double*>(cloud.positions[0].data()), cloud.size(), 3);
  flann::Index<flann::L2_Simple<double>> index(data, flann::KDTreeSingleIndexParams(kLeafSize));
  index.buildIndex();
  std::vector<std::vector<std::size_t>> idx;
  std::vector<std::vector<double>> d2;
  flann::SearchParams params;
  params.checks = flann::FLANN_CHECKS_UNLIMITED;
  params.sorted = false;
  for (auto _ : state) {
    for (const auto& p : cloud.positions) {
      flann::Matrix<double> q(const_cast<double*>(p.data()), 1, 3);
      benchmark::DoNotOptimize(
          index.radiusSearch(q, idx, d2, static_cast<float>(kRadiusMm * kRadiusMm), params));
    }
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(cloud.size()));
}

BENCHMARK(BM_Nanoflann_Build)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Flann_Build)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Nanoflann_Knn10_All)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Flann_Knn10_All)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Nanoflann_Radius5mm_All)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Flann_Radius5mm_All)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
