// Workcell simulator speed (target: a 350-profile x 1024-column sweep of the seat scene
// renders in <= 1 s on one core). Run:
//   build/bench/simulator_benchmark --benchmark_filter=Sweep
#include <benchmark/benchmark.h>

#include "datasets/cell.hpp"
#include "datasets/chair_seat.hpp"
#include "datasets/laser_renderer.hpp"
#include "datasets/sensor.hpp"

namespace lasercell::datasets {
namespace {

struct SeatSetup {
  SensorOptions sensor_options;
  SensorModel sensor = MakeSensor(sensor_options);
  ChairSeat seat = MakeChairSeat();
  Scene scene = MakeSeatScene(CellLayout{}, seat, DrawSeatPlacement({}, seat, 1, 0).cell_from_part);

  // Linear sweep over the pallet centre along +x, laser crossing the optical axis 100 mm above
  // the deck, 900 mm in 3.49 s.
  Eigen::Isometry3d Start() const {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = SensorLookingDown(sensor.laser, Eigen::Vector3d::UnitX());
    pose.translation() = Eigen::Vector3d(-450, 0, 244) -
                         pose.linear() * Eigen::Vector3d(0, 0, sensor_options.standoff_mm);
    return pose;
  }
};

void BM_SeatSweep(benchmark::State& state) {
  static const SeatSetup setup;
  LaserRenderOptions options;
  options.fan_rays = static_cast<int>(state.range(0));
  const LaserRenderer renderer(setup.scene, setup.sensor, options);
  SweepTiming timing;  // 350 profiles at 100 Hz
  const Eigen::Isometry3d start = setup.Start();
  const double speed = 900.0 / ((timing.profiles - 1) / timing.rate_hz);
  const auto state_at = [&](double t) {
    SensorState s;
    s.scene_from_sensor = Eigen::Translation3d(speed * t, 0, 0) * start;
    return s;
  };
  std::size_t peaks = 0;
  for (auto _ : state) {
    const SweepResult r = RenderSweep(renderer, state_at, timing, 7, 0, "", /*threads=*/1);
    peaks = r.valid_peaks;
    benchmark::DoNotOptimize(r.profiles.profiles.data());
  }
  state.counters["valid_peaks"] = static_cast<double>(peaks);
  state.counters["profiles_per_s"] = benchmark::Counter(
      static_cast<double>(timing.profiles), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_SeatSweep)
    ->Arg(512)
    ->Arg(1024)
    ->Arg(2048)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_SeatExposure(benchmark::State& state) {
  static const SeatSetup setup;
  const LaserRenderer renderer(setup.scene, setup.sensor, LaserRenderOptions{});
  const Eigen::Isometry3d pose = Eigen::Translation3d(450, 0, 0) * setup.Start();
  for (auto _ : state) {
    const ExposureTruth t = renderer.RenderExact(pose);
    benchmark::DoNotOptimize(t.row_px.data());
  }
}
BENCHMARK(BM_SeatExposure)->Unit(benchmark::kMicrosecond);

void BM_SceneBuild(benchmark::State& state) {
  const ChairSeat seat = MakeChairSeat();
  const Eigen::Isometry3d pose = DrawSeatPlacement({}, seat, 1, 0).cell_from_part;
  for (auto _ : state) {
    const Scene scene = MakeSeatScene(CellLayout{}, seat, pose);
    benchmark::DoNotOptimize(&scene);
  }
  state.counters["triangles"] =
      static_cast<double>(MakeSeatScene(CellLayout{}, seat, pose).TriangleCount());
}
BENCHMARK(BM_SceneBuild)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace lasercell::datasets
BENCHMARK_MAIN();
