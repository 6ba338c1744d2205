// `lasercell bench registration`: lasercell's LocalizeInCloud next to OpenCV cv::ppf_match_3d and
// PCL PPFRegistration (+ their ICPs), and ICP alone (ours vs PCL point-to-plane), on the same
// in-memory clouds in one process; a Markdown table of stage times and pose errors against the
// committed rs1 reference pose (BENCHMARKS.md). The methods run in bench_registration.cpp, the
// table is built in bench_report.cpp; `lasercell bench robustness` is in bench_robustness.cpp.
// Units: mm, deg in the table; times are wall milliseconds.
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/io/file_util.hpp"
#include "core/io/point_cloud_io.hpp"
#include "datasets/synthetic_scan.hpp"
#include "registration/localize_in_cloud.hpp"
#include "registration/ppf_model.hpp"
#include "tools/bench.hpp"
#include "tools/bench_registration.hpp"
#include "tools/bench_report.hpp"

namespace lasercell::tools {
namespace {

using registration::PpfModel;

struct RegistrationBenchArgs {
  std::string model = LASERCELL_SOURCE_DIR "/datasets/real/uwa/parasaurolophus_6700.bin.ply";
  std::string scene = LASERCELL_SOURCE_DIR "/datasets/real/uwa/rs1_normals.bin.ply";
  std::string reference =
      LASERCELL_SOURCE_DIR "/tests/registration/data/rs1_parasaurolophus_reference.txt";
  int runs = 20;
  int threads = 1;
  std::vector<double> opencv_sampling = {0.1, 0.025};
  bool skip_opencv = false;
  bool skip_pcl = false;
  int icp_starts = 20;
  std::string json_out;
};

void RunRegistrationBench(const RegistrationBenchArgs& args) {
  const PointCloud model_cloud = io::ReadPointCloud(args.model);
  const PointCloud scene = io::ReadPointCloud(args.scene);
  if (model_cloud.normals.empty() || scene.normals.empty()) {
    throw InputError("--model and --scene must carry normals (the peers do not estimate them)");
  }
  const Eigen::Isometry3d reference = datasets::ReadPoseFile(args.reference);
  const PoseEvaluator evaluate(model_cloud, scene, reference);

  PpfModel model;
  std::vector<BenchRow> rows = RunLasercell(model_cloud, scene, {args.runs, args.threads}, &model);
  const double diameter = model.diameter_mm();
  if (!args.skip_opencv) {
    std::fprintf(stderr,
                 "bench: OpenCV PPF3DDetector, trained up to 5 times (quadratic; minutes)...\n");
    OpenCvBenchOptions o;
    o.scene_sample_steps = args.opencv_sampling;
    o.threads = args.threads;
    o.runs = args.runs;
    for (BenchRow& r : RunOpenCvPpf(model_cloud, scene, o)) rows.push_back(std::move(r));
    // The same detector at lasercell's sampling: model and scene voxel 0.04 x diameter, distance
    // step 0.05 x diameter, every 5th scene point a reference (relativeSceneSampleStep 1/5).
    registration::LocalizeOptions defaults;
    OpenCvBenchOptions ours = o;
    ours.label = "OpenCV PPF at lasercell's sampling";
    ours.relative_sampling_step = model.sampling_step_mm() / diameter;
    ours.relative_distance_step = model.distance_step_mm() / diameter;
    ours.relative_scene_distance = ours.relative_sampling_step;
    ours.scene_sample_steps = {1.0 / static_cast<double>(defaults.matching.reference_stride)};
    for (BenchRow& r : RunOpenCvPpf(model_cloud, scene, ours)) rows.push_back(std::move(r));
  }
  if (!args.skip_pcl) {
    std::fprintf(stderr, "bench: PCL PPFRegistration...\n");
    PclBenchOptions o;
    registration::LocalizeOptions defaults;
    o.sampling_step_mm = model.sampling_step_mm();
    o.distance_step_mm = model.distance_step_mm();
    o.angle_step_rad = model.angle_step_rad();
    o.reference_stride = static_cast<unsigned>(defaults.matching.reference_stride);
    o.cluster_translation_mm = defaults.cluster_radius_relative * diameter;
    o.cluster_rotation_rad = defaults.clustering.rotation_threshold_rad;
    o.icp_max_distance_mm = defaults.icp_max_distance_relative * diameter;
    o.icp_iterations = defaults.icp.max_iterations;
    o.runs = args.runs;
    for (BenchRow& r : RunPclPpf(model_cloud, scene, o)) rows.push_back(std::move(r));
  }

  const double correct_mm = 0.1 * diameter;
  std::printf(
      "lasercell bench registration: model %s (%zu points, diameter %.1f mm), scene %s "
      "(%zu points); threads %d; pose error vs reference %s (RMS err = RMS displacement of the "
      "model points); top pose: <= 2 mm (the target), near (<= 0.1 x diameter = %.1f mm) or "
      "WRONG\n\n",
      args.model.c_str(), model_cloud.size(), diameter, args.scene.c_str(), scene.size(),
      args.threads, args.reference.c_str(), correct_mm);
  const nlohmann::json json_rows = PrintRegistrationTable(rows, evaluate, reference, correct_mm);
  PrintSpeedupsOverOpenCv(rows, rows[1], evaluate);
  const nlohmann::json icp = RunIcpComparison(model, scene, reference, evaluate,
                                              {args.icp_starts, args.threads, !args.skip_pcl});
  if (!args.json_out.empty()) {
    const nlohmann::json j = {{"format", "lasercell.bench_registration"},
                              {"version", 1},
                              {"model", args.model},
                              {"scene", args.scene},
                              {"threads", args.threads},
                              {"runs", args.runs},
                              {"diameter_mm", diameter},
                              {"rows", json_rows},
                              {"icp_only", icp}};
    io::WriteFileAtomically(args.json_out, j.dump(2) + "\n");
  }
}

}  // namespace

void AddBenchCommands(CLI::App& app) {
  CLI::App* bench =
      app.add_subcommand("bench", "End-to-end speed/accuracy benchmarks against peer libraries");
  bench->require_subcommand(1);

  CLI::App* reg = bench->add_subcommand(
      "registration",
      "lasercell vs OpenCV ppf_match_3d vs PCL PPF (+ ICP) on UWA rs1 / parasaurolophus");
  auto args = std::make_shared<RegistrationBenchArgs>();
  reg->add_option("--model", args->model, "Model cloud with normals (mm)")->capture_default_str();
  reg->add_option("--scene", args->scene, "Scene cloud with normals (mm)")->capture_default_str();
  reg->add_option("--reference", args->reference,
                  "Reference scene_from_model (16 numbers, '#' comments)")
      ->capture_default_str();
  reg->add_option("--runs", args->runs,
                  "Runs of every method (medians; model builds and trainings: min(runs, 5))")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  reg->add_option("--threads", args->threads, "Threads for lasercell and OpenCV (0 = all cores)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  reg->add_option("--opencv-sampling", args->opencv_sampling,
                  "OpenCV relativeSceneSampleStep values")
      ->delimiter(',')
      ->check(CLI::Range(1e-4, 1.0))
      ->capture_default_str();
  reg->add_option("--icp-starts", args->icp_starts, "Perturbed starts for the ICP-only comparison")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  reg->add_flag("--skip-opencv", args->skip_opencv,
                "Do not run OpenCV (its training takes about a minute)");
  reg->add_flag("--skip-pcl", args->skip_pcl, "Do not run PCL");
  reg->add_option("--json", args->json_out, "Also write every row as JSON");
  reg->callback([args] { RunRegistrationBench(*args); });

  CLI::App* rob = bench->add_subcommand(
      "robustness", "Found rate vs noise: the parasaurolophus at random poses in rs1 clutter");
  auto rargs = std::make_shared<RobustnessBenchArgs>();
  rob->add_option("--placements", rargs->placements, "Random model poses per noise level")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  rob->add_option("--noise", rargs->noise_mm, "Gaussian noise sigma per level, mm")
      ->delimiter(',')
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  rob->add_option("--seed", rargs->seed, "Placement/noise seed")->capture_default_str();
  rob->add_option("--threads", rargs->threads, "Localization threads (0 = all cores)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  rob->add_option("--json", rargs->json_out, "Also write every trial as JSON");
  rob->callback([rargs] { RunRobustnessBench(*rargs); });

  AddBenchPeaksCommand(*bench);
  AddCalibrationBenchCommand(*bench);
  AddTable1BenchCommand(*bench);
  AddSpeedBenchCommand(*bench);
  AddStreamBenchCommand(*bench);
  AddServeBenchCommand(*bench);
  AddServeLoadBenchCommand(*bench);
}

}  // namespace lasercell::tools
