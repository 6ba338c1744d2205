// `lasercell bench speed`: where a localization's time goes, per stage, with the counts that
// explain it, on simulated seat sweeps, real scans and a sweep-size series
// (datasets/speed_bench.hpp). Prints the Markdown section for BENCHMARKS.md and writes the JSON.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "core/io/file_util.hpp"
#include "core/progress.hpp"
#include "datasets/speed_bench.hpp"
#include "tools/bench.hpp"
#include "tools/commands.hpp"

namespace lasercell::tools {
namespace {

struct SpeedArgs {
  datasets::SpeedBenchOptions options;
  std::string json_out;
  std::string markdown_out;
  bool no_seat = false, no_real = false, no_series = false;
};

void RunSpeed(SpeedArgs args) {
  args.options.seat = !args.no_seat;
  args.options.real = !args.no_real;
  args.options.series = !args.no_series;
  const ProgressCallback progress = StderrProgress();
  const nlohmann::json j = datasets::RunSpeedBench(args.options, progress);
  const std::string md = datasets::SpeedMarkdown(j);
  std::printf("%s", md.c_str());
  if (!args.json_out.empty()) io::WriteFileAtomically(args.json_out, j.dump(2) + "\n");
  if (!args.markdown_out.empty()) io::WriteFileAtomically(args.markdown_out, md);
}

}  // namespace

void AddSpeedBenchCommand(CLI::App& bench) {
  CLI::App* cmd = bench.add_subcommand(
      "speed",
      "Time per localization stage with the counts that explain it: simulated seat sweeps, real "
      "scans (UWA rs1/rs22, PCL bunny and milk), a sweep-size series");
  auto args = std::make_shared<SpeedArgs>();
  datasets::SpeedBenchOptions& o = args->options;
  o.source_dir = LASERCELL_SOURCE_DIR;
  if (const char* shared = std::getenv("LASERCELL_SHARED_DATA")) {
    o.shared_data_dir = shared;
  } else if (std::filesystem::is_directory(LASERCELL_SOURCE_DIR "/../shared/data")) {
    o.shared_data_dir = LASERCELL_SOURCE_DIR "/../shared/data";
  }
  cmd->add_option("--runs", o.runs, "Timed runs per case and thread count (median reported)")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  cmd->add_option("--placements", o.placements, "Simulated seat sweeps")
      ->check(CLI::Range(1, 10000))
      ->capture_default_str();
  cmd->add_option("--seed", o.seed, "Simulation seed")->capture_default_str();
  cmd->add_option("--profile", o.profile, "Simulation profile: realistic or ideal")
      ->capture_default_str();
  cmd->add_option("--threads", o.threads, "Thread counts to time, e.g. 1,0 (0 = all cores)")
      ->delimiter(',')
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--series-profiles", o.series_profiles,
                  "Profiles per sweep of the size series (350 gives ~320k points)")
      ->delimiter(',')
      ->check(CLI::Range(10, 100000))
      ->capture_default_str();
  cmd->add_option("--shared-data", o.shared_data_dir,
                  "The shared real-data folder (UWA rs22); default $LASERCELL_SHARED_DATA, else "
                  "../shared/data beside the source tree")
      ->capture_default_str();
  cmd->add_option("--work", o.work_dir, "Folder for the simulated sweeps and the model cache")
      ->capture_default_str();
  cmd->add_option("--options", o.options_file,
                  "Localize options file for every case (its model: section is not used)");
  cmd->add_flag("--no-seat", args->no_seat, "Skip the simulated seat sweeps");
  cmd->add_flag("--no-real", args->no_real, "Skip the real scans");
  cmd->add_flag("--no-series", args->no_series, "Skip the sweep-size series");
  cmd->add_option("--json", args->json_out, "Also write every case as JSON");
  cmd->add_option("--markdown", args->markdown_out, "Also write the Markdown section");
  cmd->callback([args] { RunSpeed(*args); });
}

}  // namespace lasercell::tools
