// `lasercell localize --model MODEL --scene SCENE [--viewpoint X,Y,Z] [--options FILE.yaml]
//  [--max-instances N] --out RESULT.json`: the registration pipeline (PPF, clustering,
// verification, ICP) on any oriented point cloud. No part found is "found": false and exit 0.
// The options file, the model source and the result JSON are registration's
// (registration/localize_options_io.hpp, registration/localization_json.hpp).
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "core/io/point_cloud_io.hpp"
#include "core/json_io.hpp"
#include "registration/localization_json.hpp"
#include "registration/localize_in_cloud.hpp"
#include "registration/localize_options_io.hpp"
#include "registration/ppf_model.hpp"
#include "tools/commands.hpp"

namespace lasercell::tools {
namespace {

using registration::LocalizationResult;
using registration::LocalizeSettings;
using registration::PpfModel;

struct LocalizeArgs {
  std::string model, scene, options_file, out, save_model;
  std::vector<double> viewpoint;
  std::vector<double> view_direction;
  int max_instances = 0;  // 0: from the options file (default 1)
  int threads = -1;       // -1: from the options file
  bool quiet = false;
};

void Localize(const LocalizeArgs& args) {
  LocalizeSettings settings;
  if (!args.options_file.empty()) settings = registration::ReadLocalizeOptions(args.options_file);
  registration::LocalizeOptions& options = settings.localize;
  if (!args.viewpoint.empty() && !args.view_direction.empty()) {
    throw InputError("--viewpoint and --view-direction: give one of them, not both");
  }
  if (!args.viewpoint.empty()) {
    options.viewpoint =
        registration::Viewpoint::AtPoint({args.viewpoint[0], args.viewpoint[1], args.viewpoint[2]});
  }
  if (!args.view_direction.empty()) {
    options.viewpoint = registration::Viewpoint::AlongDirection(
        {args.view_direction[0], args.view_direction[1], args.view_direction[2]});
  }
  if (args.max_instances > 0) options.max_instances = static_cast<std::size_t>(args.max_instances);
  if (args.threads >= 0) options.threads = args.threads;
  settings.model.threads = options.threads;
  options.Check();
  settings.model.Check();

  const auto start = std::chrono::steady_clock::now();
  const PpfModel model = registration::LoadOrBuildModel(args.model, settings.model);
  const double model_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  if (!args.save_model.empty()) model.Save(args.save_model);

  const PointCloud scene = io::ReadPointCloud(args.scene);
  const LocalizationResult result = registration::LocalizeInCloud(scene, model, options);
  json::WriteFile(args.out,
                  registration::LocalizationResultJson(result, {args.model, args.scene}, model_ms));
  if (!args.quiet) {
    std::printf("%s\n", result.Summary().c_str());
    // The best pose in cell.yaml's notation, comparable with a frame graph or simulator truth.
    if (result.found) {
      std::printf("scene_from_model: %s\n",
                  PoseToFileNotation(result.candidates.front().scene_from_model).c_str());
    }
    std::printf("wrote %s\n", args.out.c_str());
  }
}

}  // namespace

void AddLocalizeCommand(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand(
      "localize", "Find a part model in a scene cloud: PPF voting, clustering, verification, ICP");
  auto args = std::make_shared<LocalizeArgs>();
  cmd->add_option("--model", args->model,
                  "Part model: PLY mesh (vertex normals from its faces), PLY/PCD cloud "
                  "(normals estimated when absent), or a prebuilt .ppfm model")
      ->required();
  cmd->add_option("--scene", args->scene, "Scene cloud, PLY or PCD (mm)")->required();
  cmd->add_option("--out", args->out, "Result JSON (written atomically)")->required();
  cmd->add_option("--viewpoint", args->viewpoint, "Sensor position X,Y,Z in the scene frame, mm")
      ->delimiter(',')
      ->expected(3);
  cmd->add_option("--view-direction", args->view_direction,
                  "Constant line of sight X,Y,Z (sensor -> scene), e.g. 0,0,-1 for a sweep")
      ->delimiter(',')
      ->expected(3);
  cmd->add_option("--options", args->options_file, "Options YAML (see README)");
  cmd->add_option("--max-instances", args->max_instances, "Instances reported at most (>= 1)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--threads", args->threads, "Worker threads (0 = all cores)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--save-model", args->save_model, "Also write the built model (.ppfm)");
  cmd->add_flag("--quiet", args->quiet, "Print nothing on success");
  cmd->callback([args] { Localize(*args); });
}

}  // namespace lasercell::tools
