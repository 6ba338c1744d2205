// `lasercell reference-pose --model MODEL --scene SCENE (--out POSE.txt | --check POSE.txt)
//  [--opencv-sampling S] [--json FILE] [--viewpoint X,Y,Z] [--starts N] [--threads N]`:
// the reference pose of a part in a real scan that ships no ground truth
// (registration/reference_pose.hpp), written as a 4x4 row-major scene_from_model with the account
// of how it was obtained and checked as '#' comments (datasets::WritePoseFile). With --check the
// committed pose file is read instead of established. With --opencv-sampling an independent
// implementation, OpenCV's cv::ppf_match_3d (PPF3DDetector(S, 0.05), match at 1/10 of the scene,
// its ICP(100, 0.005, 2.5, 8) on the top 2 poses, as its sample does), is run on the same clouds
// and its poses are scored against the reference (RMS displacement of the model's points).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/io/point_cloud_io.hpp"
#include "core/json_io.hpp"
#include "datasets/synthetic_scan.hpp"
#include "registration/reference_pose.hpp"
#include "tools/bench_registration.hpp"
#include "tools/commands.hpp"

namespace lasercell::tools {
namespace {

struct ReferencePoseArgs {
  std::string model, scene, out, check, json;
  std::vector<double> viewpoint;
  double opencv_sampling = 0.0;  // 0: OpenCV not run
  int starts = -1;               // -1: the library default
  int threads = 0;
  bool quiet = false;
};

/// OpenCV's top poses after its ICP, scored against `reference`.
nlohmann::json OpenCvAgainst(const PointCloud& model, const PointCloud& scene,
                             const Eigen::Isometry3d& reference, double sampling, bool quiet) {
  OpenCvBenchOptions options;
  options.relative_sampling_step = sampling;
  options.scene_sample_steps = {0.1};
  options.threads = 0;
  const std::vector<BenchRow> rows = RunOpenCvPpf(model, scene, options);
  const PoseEvaluator evaluate(model, scene, reference);
  nlohmann::json poses = nlohmann::json::array();
  for (std::size_t i = 0; i < rows.back().poses.size(); ++i) {
    const PoseError e = evaluate(rows.back().poses[i]);
    poses.push_back({{"rank", i + 1},
                     {"scene_from_model", json::Pose(rows.back().poses[i])},
                     {"rms_mm", e.rms_mm},
                     {"rotation_deg", e.rotation_deg},
                     {"centroid_mm", e.centroid_mm},
                     {"within_2mm", e.within_2mm}});
    if (!quiet) {
      std::printf("OpenCV pose %zu (%s): %.3f mm RMS from the reference, %.2f deg\n", i + 1,
                  rows.back().note.c_str(), e.rms_mm, e.rotation_deg);
    }
  }
  return {{"method", rows.back().method},
          {"note", rows.front().note + " " + rows.back().note},
          {"train_ms", rows.back().build_ms},
          {"poses", std::move(poses)}};
}

void Run(const ReferencePoseArgs& args) {
  if (args.out.empty() == args.check.empty())
    throw InputError("reference-pose: give --out (establish a reference) or --check (read one)");
  if (args.opencv_sampling != 0.0 && !(args.opencv_sampling > 0.0 && args.opencv_sampling < 1.0))
    throw InputError("--opencv-sampling: a fraction of the model diameter in (0, 1), e.g. 0.04");
  registration::ReferencePoseOptions options;
  if (!args.viewpoint.empty()) {
    options.viewpoint =
        registration::Viewpoint::AtPoint({args.viewpoint[0], args.viewpoint[1], args.viewpoint[2]});
  }
  if (args.starts >= 0) options.random_starts = args.starts;
  options.threads = args.threads;
  options.Check();
  Eigen::Isometry3d reference = Eigen::Isometry3d::Identity();
  if (!args.check.empty()) reference = datasets::ReadPoseFile(args.check);  // before the clouds
  const PointCloud model = io::ReadPointCloud(args.model);
  const PointCloud scene = io::ReadPointCloud(args.scene);
  nlohmann::json out = {{"format", "lasercell.reference_pose"},
                        {"version", 1},
                        {"model", args.model},
                        {"scene", args.scene}};
  if (args.check.empty()) {
    const registration::ReferencePose ref =
        registration::EstablishReferencePose(model, scene, options);
    if (!ref.found) throw InputError(args.scene + ": " + ref.message);
    const std::string comment = "Reference pose scene_from_model (4x4 row-major, mm) of\n  model " +
                                args.model + "\nin scene " + args.scene +
                                ",\nmade by `lasercell reference-pose` " +
                                "(registration/reference_pose.hpp):\n" + ref.Report();
    datasets::WritePoseFile(args.out, ref.scene_from_model, comment);
    if (!args.quiet) std::printf("%swrote %s\n", ref.Report().c_str(), args.out.c_str());
    out["established"] = registration::ReferencePoseJson(ref);
    reference = ref.scene_from_model;
  } else {
    out["checked"] = args.check;
  }
  out["reference"] = json::MatrixRows(reference);
  if (args.opencv_sampling > 0.0)
    out["opencv"] = OpenCvAgainst(model, scene, reference, args.opencv_sampling, args.quiet);
  if (!args.json.empty()) json::WriteFile(args.json, out);
}

}  // namespace

void AddReferencePoseCommand(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand(
      "reference-pose",
      "Reference pose of a part in a real scan without ground truth: high-effort search, "
      "refinement to a fixed point, basin and kernel checks; optionally scored by OpenCV's PPF");
  auto args = std::make_shared<ReferencePoseArgs>();
  cmd->add_option("--model", args->model, "Model cloud or mesh with normals (PLY/PCD, mm)")
      ->required();
  cmd->add_option("--scene", args->scene, "Scene cloud (PLY/PCD, mm)")->required();
  cmd->add_option("--out", args->out, "Establish the reference and write it here (atomically)");
  cmd->add_option("--check", args->check, "Read this reference pose file instead");
  cmd->add_option("--opencv-sampling", args->opencv_sampling,
                  "Also run OpenCV's PPF with this model sampling (fraction of the diameter, "
                  "e.g. 0.04) and score its poses against the reference");
  cmd->add_option("--json", args->json, "Result JSON (written atomically)");
  cmd->add_option("--viewpoint", args->viewpoint,
                  "Scanner position X,Y,Z in the scene frame, mm (default: the origin)")
      ->delimiter(',')
      ->expected(3);
  cmd->add_option("--starts", args->starts, "Random starts of the basin check (default 20)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--threads", args->threads, "Worker threads (0 = all cores)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--quiet", args->quiet, "Print nothing on success");
  cmd->callback([args] { Run(*args); });
}

}  // namespace lasercell::tools
