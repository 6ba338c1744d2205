// Triangulation speed (target: >= 100 M points/s per core on the fast path; the sensor's peak
// rate is ~4 M/s). One 1024-column profile per iteration on the simulator's 1024 x 1024
// OPENCV8 camera and true laser plane; items = points (all columns hold a peak). The same
// profile again (warm lookup table) and a stream of distinct ones (cold, as from a sensor).
//   build-bench/bench/triangulation_benchmark --benchmark_repetitions=3
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "calib/camera_model.hpp"
#include "datasets/camera_images.hpp"
#include "datasets/sensor.hpp"
#include "triangulation/peak_detection.hpp"
#include "triangulation/triangulator.hpp"

namespace {

using lasercell::triangulation::TriangulationPath;
using lasercell::triangulation::Triangulator;

const Triangulator& SimTriangulator() {
  static const Triangulator tri = [] {
    const auto sensor = lasercell::datasets::MakeSensor({});
    return Triangulator(sensor.camera, sensor.laser.Coefficients());
  }();
  return tri;
}

// A laser line over a bumpy scene: rows 300..700 with every subpixel phase.
std::vector<float> ProfileRows() {
  std::vector<float> rows(1024);
  for (int u = 0; u < 1024; ++u) {
    rows[u] = static_cast<float>(500.0 + 150.0 * std::sin(u / 97.0) + std::fmod(0.618034 * u, 1.0));
  }
  return rows;
}

void BM_TriangulateFast(benchmark::State& state) {
  const Triangulator& tri = SimTriangulator();
  const std::vector<float> rows = ProfileRows();
  std::vector<Eigen::Vector3d> points(rows.size());
  for (auto _ : state) {
    const auto c = tri.Triangulate(rows, 0, points, TriangulationPath::kFast);
    benchmark::DoNotOptimize(points.data());
    benchmark::DoNotOptimize(c);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(rows.size()));
}
BENCHMARK(BM_TriangulateFast);

// A stream of distinct profiles, as a sensor delivers them: 1024 profiles (4 MB of rows), each a
// different smooth curve anywhere in rows 40..980 with per-column jitter, visited in turn. The
// lookup table is touched where each profile lies, so its lines are mostly cold, unlike the
// repeated profile above, which keeps its few hundred table lines in L1.
std::vector<std::vector<float>> ProfileStream() {
  std::vector<std::vector<float>> stream(1024, std::vector<float>(1024));
  std::uint64_t state = 88172645463325252ULL;  // xorshift64: fixed, so every run sees the same
  auto uniform = [&state] {
    state ^= state << 13;
    state ^= state >> 7;
    state ^= state << 17;
    return static_cast<double>(state >> 11) * (1.0 / 9007199254740992.0);
  };
  for (std::vector<float>& rows : stream) {
    const double centre = 200.0 + 620.0 * uniform(), amplitude = 160.0 * uniform();
    const double period = 40.0 + 200.0 * uniform(), phase = 6.283 * uniform();
    for (int u = 0; u < 1024; ++u) {
      const double row = centre + amplitude * std::sin(u / period + phase) + uniform() - 0.5;
      rows[u] = static_cast<float>(std::clamp(row, 40.0, 980.0));
    }
  }
  return stream;
}

void BM_TriangulateFastStream(benchmark::State& state) {
  const Triangulator& tri = SimTriangulator();
  const std::vector<std::vector<float>> stream = ProfileStream();
  std::vector<Eigen::Vector3d> points(1024);
  std::size_t next = 0;
  for (auto _ : state) {
    const auto c = tri.Triangulate(stream[next], 0, points, TriangulationPath::kFast);
    next = next + 1 == stream.size() ? 0 : next + 1;
    benchmark::DoNotOptimize(points.data());
    benchmark::DoNotOptimize(c);
  }
  state.SetItemsProcessed(state.iterations() * 1024);
}
BENCHMARK(BM_TriangulateFastStream);

void BM_TriangulateExact(benchmark::State& state) {
  const Triangulator& tri = SimTriangulator();
  const std::vector<float> rows = ProfileRows();
  std::vector<Eigen::Vector3d> points(rows.size());
  for (auto _ : state) {
    const auto c = tri.Triangulate(rows, 0, points, TriangulationPath::kExact);
    benchmark::DoNotOptimize(points.data());
    benchmark::DoNotOptimize(c);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(rows.size()));
}
BENCHMARK(BM_TriangulateExact)->Unit(benchmark::kMicrosecond);

void BM_BuildTriangulator(benchmark::State& state) {
  const Triangulator& tri = SimTriangulator();
  for (auto _ : state) {
    Triangulator t(tri.camera(), tri.plane());
    benchmark::DoNotOptimize(&t);
  }
}
BENCHMARK(BM_BuildTriangulator)->Unit(benchmark::kMillisecond)->Iterations(3);

// Peak detection on a 1024 x 1024 8-bit stripe image (per image = per profile).
void BM_DetectPeaks(benchmark::State& state) {
  const lasercell::datasets::ImageRenderer renderer{lasercell::datasets::MakeCameraModel()};
  lasercell::datasets::ExposureTruth ex;
  const std::vector<float> rows = ProfileRows();
  ex.row_px.assign(rows.begin(), rows.end());
  ex.intensity.assign(1024, 0.4);
  ex.width_px.assign(1024, 3.0);
  const auto img = renderer.RenderLaserLine(ex, {}, 1);
  lasercell::triangulation::PeakDetectionOptions o;
  o.estimator = static_cast<lasercell::triangulation::PeakEstimator>(state.range(0));
  for (auto _ : state) {
    auto r = lasercell::triangulation::DetectPeaks(
        lasercell::triangulation::ImageView8{img.pixels.data(), img.width, img.height, 0}, o);
    benchmark::DoNotOptimize(r.profile.row_px.data());
  }
  state.SetItemsProcessed(state.iterations() * 1024);
}
BENCHMARK(BM_DetectPeaks)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
