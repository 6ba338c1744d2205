// `lasercell simulate cell --out DIR [--seed N] [--config SIM.yaml | --profile NAME]`,
// `lasercell simulate seat --placements N --out DIR [--seed N] [--config SIM.yaml]` and
// `lasercell simulate pallet --scenes N --out DIR [--seed N] [--config SIM.yaml]`:
// the workcell simulator (datasets/simulate.hpp, datasets/simulate_pallets.hpp). Same seed and
// config -> identical bytes.
#include <cstdio>
#include <memory>
#include <string>

#include "core/error.hpp"
#include "datasets/sim_config.hpp"
#include "datasets/sim_profile.hpp"
#include "datasets/simulate.hpp"
#include "datasets/simulate_pallets.hpp"
#include "tools/commands.hpp"

namespace lasercell::tools {
namespace {

struct SimulateArgs {
  std::string out, config, profile;
  long long seed = -1;  // -1: from the config (default 1)
  int placements = 10;
  int scenes = 1;
  int threads = 0;
  bool quiet = false;
};

datasets::SimConfig Config(const SimulateArgs& args) {
  if (!args.config.empty() && !args.profile.empty()) {
    throw OptionError(
        "give --profile or --config, not both (a config file names its base with "
        "'profile: " +
        args.profile + "')");
  }
  datasets::SimConfig config =
      args.config.empty()
          ? datasets::SimConfigForProfile(args.profile.empty() ? "ideal" : args.profile)
          : datasets::LoadSimConfig(args.config);
  if (args.seed >= 0) config.seed = static_cast<std::uint64_t>(args.seed);
  return config;
}

ProgressCallback Progress(bool quiet) {
  if (quiet) return {};
  return StderrProgress(40);
}

void AddCommon(CLI::App* cmd, SimulateArgs& args) {
  cmd->add_option("--out", args.out, "Output folder (created when missing)")->required();
  cmd->add_option("--seed", args.seed, "Random seed (default: the config's, 1)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--config", args.config, "Simulator config YAML (datasets/SIMULATOR.md)");
  cmd->add_option("--profile", args.profile,
                  "Named simulation profile: ideal (default; exact projection + white noise) or "
                  "realistic (speckle, reflections, timing and encoder noise, DH errors, CAD != "
                  "part; datasets/SIMULATOR.md)");
  cmd->add_option("--threads", args.threads, "Worker threads (0 = all cores); output identical")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--quiet", args.quiet, "No progress, no summary");
}

}  // namespace

void AddSimulateCommands(CLI::App& app) {
  CLI::App* sim = app.add_subcommand("simulate", "Simulated captures of the workcell, with truth");
  sim->require_subcommand(1);

  CLI::App* cell = sim->add_subcommand(
      "cell",
      "Every calibration capture (planes, spheres, trajectory), part scenes, images, truth");
  auto cell_args = std::make_shared<SimulateArgs>();
  AddCommon(cell, *cell_args);
  cell->callback([cell_args] {
    const auto report = datasets::SimulateCell(Config(*cell_args), cell_args->out,
                                               Progress(cell_args->quiet), cell_args->threads);
    if (!cell_args->quiet)
      std::printf("%s -> %s\n", report.Summary().c_str(), cell_args->out.c_str());
  });

  CLI::App* seat = sim->add_subcommand(
      "seat", "Chair-seat scenes at random placements like the paper's Table I, with truth");
  auto seat_args = std::make_shared<SimulateArgs>();
  AddCommon(seat, *seat_args);
  seat->add_option("--placements", seat_args->placements, "Number of scenes (>= 1)")
      ->check(CLI::PositiveNumber);
  seat->callback([seat_args] {
    const auto report =
        datasets::SimulateSeats(Config(*seat_args), seat_args->placements, seat_args->out,
                                Progress(seat_args->quiet), seat_args->threads);
    if (!seat_args->quiet)
      std::printf("%s -> %s\n", report.Summary().c_str(), seat_args->out.c_str());
  });

  CLI::App* pallet = sim->add_subcommand(
      "pallet",
      "Seat, seat back and armrest lying on the pallet (the paper's Fig. 4), one sweep per scene, "
      "with STEP models, part files and truth");
  auto pallet_args = std::make_shared<SimulateArgs>();
  AddCommon(pallet, *pallet_args);
  pallet->add_option("--scenes", pallet_args->scenes, "Number of scenes (>= 1)")
      ->check(CLI::PositiveNumber);
  pallet->callback([pallet_args] {
    const auto report =
        datasets::SimulatePallets(Config(*pallet_args), pallet_args->scenes, pallet_args->out, {},
                                  Progress(pallet_args->quiet), pallet_args->threads);
    if (!pallet_args->quiet)
      std::printf("%s -> %s\n", report.Summary().c_str(), pallet_args->out.c_str());
  });
}

}  // namespace lasercell::tools
