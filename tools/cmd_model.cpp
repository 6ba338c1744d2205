// `lasercell model info FILE|PART.yaml` and `lasercell model build PART.yaml`: a part's model
// (localize/part_model.hpp) as a job would load it. `info` never writes: it loads the cached
// model when there is one and builds in memory otherwise; `build` writes the cache file.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "core/io/file_util.hpp"
#include "localize/part.hpp"
#include "localize/part_model.hpp"
#include "tools/commands.hpp"

namespace lasercell::tools {
namespace {

struct ModelArgs {
  std::string input, cache_dir, units = "mm";
  int threads = 0;
};

// A part file, or a bare model file as a part of its stem's name.
localize::PartDefinition PartOf(const ModelArgs& args) {
  const std::string ext = io::LowerExtension(args.input);
  if (ext == ".yaml" || ext == ".yml") return localize::ReadPartFile(args.input);
  localize::PartDefinition part;
  std::string name;
  for (char c : std::filesystem::path(args.input).stem().string()) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9');
    name += ok ? c : (c >= 'A' && c <= 'Z' ? static_cast<char>(c - 'A' + 'a') : '_');
  }
  part.name = name.empty() || !(name[0] >= 'a' && name[0] <= 'z') ? "part_" + name : name;
  part.model = args.input;
  part.model_path = args.input;
  part.units = localize::IsCadFile(args.input) ? "" : args.units;
  return part;
}

void Info(const ModelArgs& args, bool build) {
  const localize::PartDefinition part = PartOf(args);
  localize::PartModelOptions options;
  options.cache_dir = args.cache_dir;
  options.write_cache = build;
  options.use_cache = build || !part.file.empty() || !args.cache_dir.empty();
  options.threads = args.threads;
  const localize::PartModel model = localize::LoadPartModel(part, options);
  std::printf("%s", localize::PartModelSummary(model).c_str());
}

}  // namespace

void AddModelCommands(CLI::App& app) {
  CLI::App* model = app.add_subcommand("model", "Part models: CAD or mesh -> PPF model");
  model->require_subcommand(1);
  auto args = std::make_shared<ModelArgs>();
  CLI::App* info = model->add_subcommand(
      "info", "Points, diameter, sampling, grasps, build time and cache state of a part");
  info->add_option("input", args->input,
                   "Part file (lasercell.part YAML), or a model file (.step/.iges/.stl/.obj/.ply)")
      ->required();
  info->add_option("--units", args->units, "Unit of a bare mesh file (mm, cm, m, inch)")
      ->capture_default_str();
  info->add_option("--cache-dir", args->cache_dir,
                   "Model cache folder (default: next to the part)");
  info->add_option("--threads", args->threads, "Worker threads (0 = all cores)")
      ->check(CLI::NonNegativeNumber);
  info->callback([args] { Info(*args, false); });
  CLI::App* build = model->add_subcommand(
      "build", "Build a part's PPF model and write it to the cache, so jobs load it");
  build->add_option("input", args->input, "Part file (lasercell.part YAML)")->required();
  build->add_option("--cache-dir", args->cache_dir,
                    "Model cache folder (default: next to the part)");
  build->add_option("--threads", args->threads, "Worker threads (0 = all cores)")
      ->check(CLI::NonNegativeNumber);
  build->callback([args] { Info(*args, true); });
}

}  // namespace lasercell::tools
