// `lasercell localize --model MODEL --scene SCENE [--viewpoint X,Y,Z] [--options FILE.yaml]
//  [--max-instances N] --out RESULT.json`: the registration pipeline (PPF, clustering,
// verification, ICP) on any oriented point cloud. No part found is "found": false and exit 0.
#include <yaml-cpp/yaml.h>

#include <chrono>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "core/io/file_util.hpp"
#include "core/io/point_cloud_io.hpp"
#include "core/yaml_fields.hpp"
#include "registration/localize_in_cloud.hpp"
#include "registration/ppf_model.hpp"
#include "tools/commands.hpp"

namespace lasercell::tools {
namespace {

using registration::LocalizationCandidate;
using registration::LocalizationResult;
using registration::LocalizeOptions;
using registration::PpfModel;
using registration::PpfModelOptions;

struct LocalizeArgs {
  std::string model, scene, options_file, out, save_model;
  std::vector<double> viewpoint;
  std::vector<double> view_direction;
  int max_instances = 0;  // 0: from the options file (default 1)
  int threads = -1;       // -1: from the options file
  bool quiet = false;
};

// Options file (YAML, every key optional; unknown keys are errors):
//   format: lasercell.localize_options   version: 1
//   threads, max_instances, viewpoint_mm: [x,y,z] | view_direction: [x,y,z],
//   roi: {min_mm: [x,y,z], max_mm: [x,y,z]}, remove_small_clusters,
//   model: {sampling_step_relative, sampling_step_mm, distance_step_relative,
//           distance_step_mm, angle_step_rad, max_model_points},
//   scene_sampling_step_mm,
//   matching: {reference_stride, peaks_per_reference, peak_min_relative, min_votes,
//              spread_features, spread_alpha},
//   clustering: {rotation_threshold_rad, max_clusters}, cluster_radius_relative,
//   verification: {grid_rows, grid_cols, min_support}, support_distance_relative,
//   run_icp, icp_rounds, refined_support_distance_relative, refined_min_support
void ApplyOptionsFile(const std::string& path, LocalizeOptions& o, PpfModelOptions& m) {
  yaml::Fields r = yaml::Fields::Load(path);
  r.ExpectFormat("lasercell.localize_options", 1);
  r.Read("threads", &o.threads);
  r.Read("max_instances", &o.max_instances);
  Eigen::Vector3d v;
  if (r.Read("viewpoint_mm", &v)) o.viewpoint = registration::Viewpoint::AtPoint(v);
  if (r.Read("view_direction", &v)) o.viewpoint = registration::Viewpoint::AlongDirection(v);
  if (r.Has("roi")) {
    o.use_roi = true;
    yaml::Fields roi = r.Sub("roi");
    roi.ReadRequired("min_mm", &o.roi.min);
    roi.ReadRequired("max_mm", &o.roi.max);
    roi.Done();
  }
  r.Read("remove_small_clusters", &o.remove_small_clusters);
  if (r.Has("model")) {
    yaml::Fields s = r.Sub("model");
    s.Read("sampling_step_relative", &m.sampling_step_relative);
    s.Read("sampling_step_mm", &m.sampling_step_mm);
    s.Read("distance_step_relative", &m.distance_step_relative);
    s.Read("distance_step_mm", &m.distance_step_mm);
    s.Read("angle_step_rad", &m.angle_step_rad);
    s.Read("max_model_points", &m.max_model_points);
    s.Done();
  }
  r.Read("scene_sampling_step_mm", &o.scene_sampling_step_mm);
  if (r.Has("matching")) {
    yaml::Fields s = r.Sub("matching");
    s.Read("reference_stride", &o.matching.reference_stride);
    s.Read("peaks_per_reference", &o.matching.peaks_per_reference);
    s.Read("peak_min_relative", &o.matching.peak_min_relative);
    s.Read("min_votes", &o.matching.min_votes);
    s.Read("spread_features", &o.matching.spread_features);
    s.Read("spread_alpha", &o.matching.spread_alpha);
    s.Done();
  }
  if (r.Has("clustering")) {
    yaml::Fields s = r.Sub("clustering");
    s.Read("rotation_threshold_rad", &o.clustering.rotation_threshold_rad);
    s.Read("max_clusters", &o.clustering.max_clusters);
    s.Done();
  }
  r.Read("cluster_radius_relative", &o.cluster_radius_relative);
  if (r.Has("verification")) {
    yaml::Fields s = r.Sub("verification");
    s.Read("grid_rows", &o.verification.grid_rows);
    s.Read("grid_cols", &o.verification.grid_cols);
    s.Read("min_support", &o.verification.min_support);
    s.Done();
  }
  r.Read("support_distance_relative", &o.support_distance_relative);
  r.Read("run_icp", &o.run_icp);
  r.Read("icp_rounds", &o.icp_rounds);
  r.Read("refined_support_distance_relative", &o.refined_support_distance_relative);
  r.Read("refined_min_support", &o.refined_min_support);
  r.Done();
}

// 4x4 homogeneous matrix as an array of 4 rows (row-major), mm.
nlohmann::json PoseJson(const Eigen::Isometry3d& pose) {
  nlohmann::json rows = nlohmann::json::array();
  const Eigen::Matrix4d m = pose.matrix();
  for (int r = 0; r < 4; ++r) rows.push_back({m(r, 0), m(r, 1), m(r, 2), m(r, 3)});
  return rows;
}

nlohmann::json CandidateJson(const LocalizationCandidate& c) {
  nlohmann::json j;
  j["rank"] = c.rank;
  j["scene_from_model"] = PoseJson(c.scene_from_model);
  j["votes"] = c.votes;
  j["score"] = c.score;
  j["support"] = c.verification.support;
  j["coarse_support"] = c.coarse_verification.support;
  if (c.icp_run) {
    j["icp"] = {{"rmse_mm", c.icp.rmse_mm},
                {"inliers", c.icp.inliers},
                {"iterations", c.icp.iterations},
                {"converged", c.icp.converged},
                {"termination", registration::ToString(c.icp.termination)}};
  } else {
    j["icp"] = nullptr;
  }
  if (!c.rejection_reason.empty()) j["rejection_reason"] = c.rejection_reason;
  return j;
}

nlohmann::json ResultJson(const LocalizationResult& r, const LocalizeArgs& args,
                          double model_ms) {
  nlohmann::json j;
  j["format"] = "lasercell.localization";
  j["version"] = 1;
  j["model"] = args.model;
  j["scene"] = args.scene;
  j["found"] = r.found;
  if (!r.found) j["message"] = r.message;
  j["ambiguous"] = r.ambiguous;
  if (r.ambiguous) j["ambiguity_reason"] = r.ambiguity_reason;
  j["candidates"] = nlohmann::json::array();
  for (const auto& c : r.candidates) j["candidates"].push_back(CandidateJson(c));
  j["rejected"] = nlohmann::json::array();
  for (const auto& c : r.rejected) j["rejected"].push_back(CandidateJson(c));
  const auto& t = r.timings;
  j["timings_ms"] = {{"model_build_or_load", model_ms}, {"preprocess", t.preprocess_ms},
                     {"normals", t.normals_ms},         {"subsample", t.subsample_ms},
                     {"kdtree", t.kdtree_ms},           {"matching", t.matching_ms},
                     {"clustering", t.clustering_ms},   {"verification", t.verification_ms},
                     {"icp", t.icp_ms},                 {"total", t.total_ms}};
  j["counts"] = {{"scene_points", r.scene_points},       {"dropped_points", r.dropped_points},
                 {"used_points", r.used_points},         {"sampled_points", r.sampled_points},
                 {"reference_points", r.reference_points}, {"hypotheses", r.hypotheses},
                 {"clusters", r.clusters}};
  return j;
}

// A prebuilt .ppfm, or a model built from a PLY (mesh or cloud: PpfModel::Build takes the
// faces' normals for a mesh without normals) or a PCD cloud.
PpfModel LoadOrBuildModel(const std::string& path, const PpfModelOptions& options) {
  const std::string extension = io::LowerExtension(path);
  if (extension == ".ppfm") return PpfModel::Load(path);
  if (extension == ".ply") return PpfModel::Build(io::ReadPlyMesh(path), options);
  return PpfModel::Build(io::ReadPointCloud(path), options);
}

void Localize(const LocalizeArgs& args) {
  LocalizeOptions options;
  PpfModelOptions model_options;
  if (!args.options_file.empty()) ApplyOptionsFile(args.options_file, options, model_options);
  if (!args.viewpoint.empty() && !args.view_direction.empty()) {
    throw InputError("--viewpoint and --view-direction: give one of them, not both");
  }
  if (!args.viewpoint.empty()) {
    options.viewpoint = registration::Viewpoint::AtPoint(
        {args.viewpoint[0], args.viewpoint[1], args.viewpoint[2]});
  }
  if (!args.view_direction.empty()) {
    options.viewpoint = registration::Viewpoint::AlongDirection(
        {args.view_direction[0], args.view_direction[1], args.view_direction[2]});
  }
  if (args.max_instances > 0) options.max_instances = static_cast<std::size_t>(args.max_instances);
  if (args.threads >= 0) options.threads = args.threads;
  model_options.threads = options.threads;
  options.Check();
  model_options.Check();

  const auto start = std::chrono::steady_clock::now();
  const PpfModel model = LoadOrBuildModel(args.model, model_options);
  const double model_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  if (!args.save_model.empty()) model.Save(args.save_model);

  const PointCloud scene = io::ReadPointCloud(args.scene);
  const LocalizationResult result = registration::LocalizeInCloud(scene, model, options);
  io::WriteFileAtomically(args.out, ResultJson(result, args, model_ms).dump(2) + "\n");
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
