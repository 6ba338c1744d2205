// `lasercell bench table1 --placements N [--cells K]`: Skotheim et al. 2012's Table I through the
// whole product (datasets/table1_bench.hpp). Prints the Markdown section for BENCHMARKS.md and
// writes every trial as JSON.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "core/io/file_util.hpp"
#include "core/progress.hpp"
#include "datasets/table1_bench.hpp"
#include "tools/bench.hpp"
#include "tools/commands.hpp"

namespace lasercell::tools {
namespace {

struct Table1Args {
  datasets::Table1Options options;
  std::string json_out;
  std::string markdown_out;
};

void RunTable1(const Table1Args& args) {
  const ProgressCallback progress = StderrProgress();
  const nlohmann::json j = datasets::RunTable1Bench(args.options, progress);
  const std::string md = datasets::Table1Markdown(j);
  std::printf("%s", md.c_str());
  if (!args.json_out.empty()) io::WriteFileAtomically(args.json_out, j.dump(2) + "\n");
  if (!args.markdown_out.empty()) io::WriteFileAtomically(args.markdown_out, md);
}

}  // namespace

void AddTable1BenchCommand(CLI::App& bench) {
  CLI::App* cmd = bench.add_subcommand(
      "table1",
      "Skotheim et al.'s Table I through the calibrated chain: simulate, calibrate, "
      "localize N seats, hole error after PPF and ICP, uncertainty, time per part");
  auto args = std::make_shared<Table1Args>();
  datasets::Table1Options& o = args->options;
  cmd->add_option("--placements", o.placements, "Seat placements")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  cmd->add_option("--cells", o.cells,
                  "Independent simulated cells (seeds SEED, SEED+1, ...), each calibrated from "
                  "its own captures; the placements are split evenly between them, so the "
                  "uncertainty check draws the calibration errors too")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  cmd->add_option("--seed", o.seed, "Simulation seed")->capture_default_str();
  cmd->add_option("--threads", o.threads, "Localization threads (0 = all cores)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--work", o.work_dir, "Folder for the captures, calibration and cache")
      ->capture_default_str();
  cmd->add_option("--config", o.sim_config, "Simulator settings (SIM.yaml; overrides --profile)");
  cmd->add_option("--profile", o.profile, "Simulation profile: realistic or ideal")
      ->capture_default_str();
  cmd->add_option("--options", o.options_file,
                  "Localize options file for the job; its model: section builds the seat model");
  cmd->add_flag("--reuse-captures", o.reuse_captures,
                "Reuse each cell's captures in --work when simulated with the same settings");
  cmd->add_option("--json", args->json_out, "Also write every trial as JSON");
  cmd->add_option("--markdown", args->markdown_out, "Also write the Markdown section");
  cmd->callback([args] { RunTable1(*args); });
}

}  // namespace lasercell::tools
