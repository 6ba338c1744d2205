// Google Benchmark micro-benchmarks of the registration module on the UWA data (rs1 scene,
// parasaurolophus model). Speed targets are measured here, never in unit tests:
//   - model build for a ~1000-point model well under 0.3 s,
//   - rs1 + parasaurolophus_6700 end to end (model prebuilt) <= 40 ms median, single thread.
// Counters report accuracy next to speed: error_mm is the RMS displacement of the model's
// points between the found pose and the committed reference pose.
// Run: build/bench/registration_benchmark --benchmark_repetitions=5

#include <benchmark/benchmark.h>

#include <filesystem>
#include <string>

#include "core/io/point_cloud_io.hpp"
#include "registration/filters.hpp"
#include "registration/kdtree.hpp"
#include "registration/localize_in_cloud.hpp"
#include "registration/normals.hpp"
#include "registration/ppf_matcher.hpp"
#include "registration/ppf_model.hpp"

namespace {

using namespace lasercell;
using namespace lasercell::registration;

std::string UwaFile(const std::string& file) {
  for (const std::string& root : {std::string(LASERCELL_SOURCE_DIR) + "/datasets/real/uwa/",
                                  std::string(LASERCELL_SOURCE_DIR) + "/../shared/data/uwa/"}) {
    if (std::filesystem::is_regular_file(root + file)) return root + file;
  }
  return {};
}

struct Data {
  PointCloud model, scene;
  Eigen::Isometry3d reference = Eigen::Isometry3d::Identity();
  bool ok = false;
};

const Data& UwaData() {
  static const Data data = [] {
    Data d;
    const std::string model = UwaFile("parasaurolophus_6700.ply"),
                      scene = UwaFile("rs1_normals.bin.ply");
    if (model.empty() || scene.empty()) return d;
    d.model = io::ReadPointCloud(model);
    d.scene = io::ReadPointCloud(scene);
    d.reference.matrix() << 0.9942892336, -0.08764531701, 0.06088693151, -74.3320341,  //
        0.09987377689, 0.5631628352, -0.8202882723, -601.364636,                       //
        0.03760516869, 0.8216848054, 0.5687002127, -292.9836609,                       //
        0, 0, 0, 1;  // tests/registration/data/rs1_parasaurolophus_reference.txt
    d.ok = true;
    return d;
  }();
  return data;
}

#define REQUIRE_UWA(state)                                                                \
  if (!UwaData().ok) {                                                                    \
    state.SkipWithError("UWA data not found in datasets/real/uwa or ../shared/data/uwa"); \
    return;                                                                               \
  }

// Model build; arg 0 = sampling step in thousandths of the diameter (40 -> 433 points,
// 25 -> 930 points), arg 1 = threads.
void BM_PpfModelBuild(benchmark::State& state) {
  REQUIRE_UWA(state);
  PpfModelOptions options;
  options.sampling_step_relative = static_cast<double>(state.range(0)) / 1000.0;
  options.threads = static_cast<int>(state.range(1));
  std::size_t points = 0, pairs = 0;
  for (auto _ : state) {
    const PpfModel model = PpfModel::Build(UwaData().model, options);
    points = model.points().size();
    pairs = model.pair_count();
    benchmark::DoNotOptimize(pairs);
  }
  state.counters["model_points"] = static_cast<double>(points);
  state.counters["pairs"] = static_cast<double>(pairs);
}
BENCHMARK(BM_PpfModelBuild)
    ->Args({40, 1})
    ->Args({25, 1})
    ->Args({25, 0})
    ->Unit(benchmark::kMillisecond);

// End to end on rs1 with the model prebuilt; arg = threads (1 or 0 = all cores).
void BM_LocalizeRs1(benchmark::State& state) {
  REQUIRE_UWA(state);
  static const PpfModel model = PpfModel::Build(UwaData().model);
  LocalizeOptions options;
  options.threads = static_cast<int>(state.range(0));
  LocalizationResult result;
  for (auto _ : state) {
    result = LocalizeInCloud(UwaData().scene, model, options);
    benchmark::DoNotOptimize(result.found);
  }
  double error = -1.0;
  if (result.found) {
    double sum = 0.0;
    for (const auto& p : UwaData().model.positions) {
      sum +=
          (result.candidates.front().scene_from_model * p - UwaData().reference * p).squaredNorm();
    }
    error = std::sqrt(sum / static_cast<double>(UwaData().model.size()));
  }
  state.counters["found"] = result.found ? 1 : 0;
  state.counters["error_mm"] = error;
  state.counters["support"] = result.found ? result.candidates.front().verification.support : 0.0;
  state.counters["match_ms"] = result.timings.matching_ms;
  state.counters["icp_ms"] = result.timings.icp_ms;
  state.counters["verify_ms"] = result.timings.verification_ms;
}
BENCHMARK(BM_LocalizeRs1)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();

// Stages on their own (single thread).
void BM_VoxelGridRs1(benchmark::State& state) {
  REQUIRE_UWA(state);
  VoxelGridOptions options;
  options.voxel_size_mm = static_cast<double>(state.range(0)) / 10.0;
  std::size_t out = 0;
  for (auto _ : state) out = VoxelGridDownsample(UwaData().scene, options).size();
  state.counters["points_out"] = static_cast<double>(out);
}
BENCHMARK(BM_VoxelGridRs1)->Arg(125)->Arg(20)->Unit(benchmark::kMillisecond);

void BM_KdTreeBuildRs1(benchmark::State& state) {
  REQUIRE_UWA(state);
  for (auto _ : state) {
    const KdTree tree(UwaData().scene.positions);
    benchmark::DoNotOptimize(tree.size());
  }
}
BENCHMARK(BM_KdTreeBuildRs1)->Unit(benchmark::kMillisecond);

// Normals on the dense rs1 (as for a scene without normals); arg = threads.
void BM_NormalsRs1(benchmark::State& state) {
  REQUIRE_UWA(state);
  PointCloud scene;
  scene.positions = UwaData().scene.positions;
  NormalOptions options;
  options.threads = static_cast<int>(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(EstimateNormals(scene, options).invalid_count);
}
BENCHMARK(BM_NormalsRs1)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();

// Thinning to one point per cell (arg: cell in tenths of a mm; the verification cell of the
// parasaurolophus is ~1.9 mm), as the localizers do before fitting normals.
void BM_OnePerCellRs1(benchmark::State& state) {
  REQUIRE_UWA(state);
  const double cell = static_cast<double>(state.range(0)) / 10.0;
  std::size_t out = 0;
  for (auto _ : state)
    out = OnePerCellIndices(UwaData().scene.positions, cell, CellPoint::kNearestCentre).size();
  state.counters["points_out"] = static_cast<double>(out);
}
BENCHMARK(BM_OnePerCellRs1)->Arg(19)->Arg(125)->Unit(benchmark::kMillisecond);

// Normals at the thinned points only, from the dense neighbourhoods (WithNormalsAtCells), as a
// scene without normals gets them; arg = cell in tenths of a mm. Compare with BM_NormalsRs1/1.
void BM_NormalsAtCellsRs1(benchmark::State& state) {
  REQUIRE_UWA(state);
  PointCloud scene;
  scene.positions = UwaData().scene.positions;
  NormalOptions options;
  options.threads = 1;
  const double cell = static_cast<double>(state.range(0)) / 10.0;
  std::size_t out = 0;
  for (auto _ : state) out = WithNormalsAtCells(scene, cell, options).cloud.size();
  state.counters["points_out"] = static_cast<double>(out);
}
BENCHMARK(BM_NormalsAtCellsRs1)->Arg(19)->Unit(benchmark::kMillisecond);

// The voting alone on rs1's voxel grid (model: 0.04 x diameter), single thread; arg 0 = plain
// Drost voting, 1 = PpfMatchOptions::unique_votes. Counters: the work behind the time.
void BM_MatchPpfRs1(benchmark::State& state) {
  REQUIRE_UWA(state);
  static const PpfModel model = PpfModel::Build(UwaData().model);
  VoxelGridOptions voxel;
  voxel.voxel_size_mm = model.sampling_step_mm();
  const PointCloud sampled = VoxelGridDownsample(UwaData().scene, voxel);
  const KdTree tree(sampled.positions);
  PpfMatchOptions options;
  options.threads = 1;
  options.unique_votes = state.range(0) != 0;
  PpfMatchResult result;
  for (auto _ : state) result = MatchPpf(tree, sampled.normals, model, options);
  state.counters["scene_pairs"] = static_cast<double>(result.scene_pairs);
  state.counters["votes"] = static_cast<double>(result.votes_cast);
  state.counters["hypotheses"] = static_cast<double>(result.hypotheses.size());
}
BENCHMARK(BM_MatchPpfRs1)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
