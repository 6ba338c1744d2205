#pragma once
// `lasercell bench ...`: end-to-end speed/accuracy tables that run lasercell and the peer
// libraries side by side on the same inputs in one process (BENCHMARKS.md).
#include <CLI/CLI.hpp>
#include <string>
#include <vector>

namespace lasercell::tools {

/// Registers `bench registration` and `bench robustness` (cmd_bench.cpp).
void AddBenchCommands(CLI::App& app);
/// Registers `bench peaks` under `bench` (bench_peaks.cpp).
void AddBenchPeaksCommand(CLI::App& bench);

/// Registers `bench calibration` under `bench` (bench_calibration.cpp).
void AddCalibrationBenchCommand(CLI::App& bench);

/// Registers `bench table1` under `bench` (bench_table1.cpp).
void AddTable1BenchCommand(CLI::App& bench);

/// Registers `bench speed` under `bench` (bench_speed.cpp).
void AddSpeedBenchCommand(CLI::App& bench);

/// Registers `bench stream` under `bench` (bench_stream.cpp).
void AddStreamBenchCommand(CLI::App& bench);
/// Registers `bench serve` under `bench` (bench_serve.cpp).
void AddServeBenchCommand(CLI::App& bench);
/// Registers `bench serve-load` under `bench` (bench_serve.cpp).
void AddServeLoadBenchCommand(CLI::App& bench);

/// Arguments of `lasercell bench robustness`.
struct RobustnessBenchArgs {
  int placements = 200;  ///< Random model poses per noise level.
  std::vector<double> noise_mm = {0.0, 0.3, 0.5, 1.0, 2.0};  ///< Gaussian sigma per level, mm.
  unsigned seed = 1;                                         ///< Placement/noise seed.
  int threads = 1;                                           ///< Localization threads.
  std::string json_out;                                      ///< Optional JSON with every trial.
};

/// Synthetic robustness curve: the UWA parasaurolophus at random poses in real rs1 clutter with
/// noise; prints found rate (ADD <= 0.05 x diameter after ICP) per noise level
/// (bench_robustness.cpp).
void RunRobustnessBench(const RobustnessBenchArgs& args);

}  // namespace lasercell::tools
