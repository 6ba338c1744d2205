#include "datasets/speed_bench.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "core/io/point_cloud_io.hpp"
#include "core/parallel.hpp"
#include "core/stats.hpp"
#include "datasets/sim_profile.hpp"
#include "datasets/simulate.hpp"
#include "datasets/simulate_records.hpp"
#include "datasets/synthetic_scan.hpp"
#include "localize/localize_parts.hpp"
#include "localize/part.hpp"
#include "localize/part_model.hpp"
#include "registration/localize_in_cloud.hpp"
#include "registration/localize_options_io.hpp"
#include "registration/reference_pose.hpp"
#include "triangulation/linear_sweep.hpp"
#include "triangulation/sweep.hpp"
#include "triangulation/triangulator.hpp"

namespace lasercell::datasets {
namespace {

// The stages of the tables, in pipeline order. "other" is the rest of the total (the job's grasp
// fits and explained-point removal, the ambiguity check, bookkeeping).
constexpr std::array<const char*, 10> kStages = {"roi",      "normals",    "subsample",    "kdtree",
                                                 "matching", "clustering", "verification", "icp",
                                                 "other",    "total"};
enum Stage {
  kRoi,
  kNormals,
  kSubsample,
  kKdtree,
  kMatching,
  kClustering,
  kVerification,
  kIcp,
  kOther,
  kTotal
};

// One timed run.
struct Sample {
  std::array<double, kStages.size()> ms{};
  std::size_t points = 0, used = 0, sampled = 0, references = 0, pairs = 0, votes = 0;
  bool found = false;
  double error_mm = NAN;  // against the case's reference (NaN: none)
};

void SetOther(Sample* s) {
  double staged = 0.0;
  for (int k = kRoi; k < kOther; ++k) staged += s->ms[k];
  s->ms[kOther] = std::max(0.0, s->ms[kTotal] - staged);
}

Sample FromLocalization(const registration::LocalizationResult& r) {
  Sample s;
  const registration::LocalizationTimings& t = r.timings;
  s.ms = {t.preprocess_ms, t.normals_ms,      t.subsample_ms, t.kdtree_ms, t.matching_ms,
          t.clustering_ms, t.verification_ms, t.icp_ms,       0.0,         t.total_ms};
  SetOther(&s);
  s.points = r.scene_points;
  s.used = r.used_points;
  s.sampled = r.sampled_points;
  s.references = r.reference_points;
  s.pairs = r.scene_pairs;
  s.votes = r.votes_cast;
  s.found = r.found;
  return s;
}

Sample FromParts(const localize::LocalizePartsResult& r) {
  Sample s;
  const localize::PartSearch& search = r.searches.front();
  const registration::LocalizationTimings& t = search.timings;
  s.ms = {r.timings.roi_ms + t.preprocess_ms,
          r.timings.normals_ms + t.normals_ms,
          t.subsample_ms,
          t.kdtree_ms,
          t.matching_ms,
          t.clustering_ms,
          t.verification_ms,
          t.icp_ms,
          0.0,
          r.timings.total_ms};
  SetOther(&s);
  s.points = r.sweep_points;
  s.used = r.normal_points;
  s.sampled = search.sampled_points;
  s.references = search.reference_points;
  s.pairs = search.scene_pairs;
  s.votes = search.votes_cast;
  s.found = !r.instances.empty();
  return s;
}

double MedianOf(const std::vector<Sample>& samples, auto field) {
  std::vector<double> v;
  for (const Sample& s : samples) v.push_back(static_cast<double>(field(s)));
  return v.empty() ? NAN : Median(v);
}

// A case's JSON: per-stage medians, median counts, what they explain, accuracy.
nlohmann::json Summarize(const std::string& name, const std::string& kind, int threads,
                         const std::vector<Sample>& samples, const std::string& accuracy) {
  nlohmann::json stages = nlohmann::json::object();
  for (std::size_t k = 0; k < kStages.size(); ++k)
    stages[kStages[k]] = MedianOf(samples, [k](const Sample& s) { return s.ms[k]; });
  const double pairs = MedianOf(samples, [](const Sample& s) { return s.pairs; });
  const double votes = MedianOf(samples, [](const Sample& s) { return s.votes; });
  const double matching = stages["matching"].get<double>();
  std::size_t found = 0;
  std::vector<double> errors;
  for (const Sample& s : samples) {
    found += s.found ? 1 : 0;
    if (s.found && std::isfinite(s.error_mm)) errors.push_back(s.error_mm);
  }
  const int cores = static_cast<int>(std::max(1U, std::thread::hardware_concurrency()));
  return {{"case", name},
          {"kind", kind},
          {"threads", threads == 0 ? cores : threads},
          {"runs", samples.size()},
          {"stages_ms", stages},
          {"points", MedianOf(samples, [](const Sample& s) { return s.points; })},
          {"used_points", MedianOf(samples, [](const Sample& s) { return s.used; })},
          {"sampled_points", MedianOf(samples, [](const Sample& s) { return s.sampled; })},
          {"reference_points", MedianOf(samples, [](const Sample& s) { return s.references; })},
          {"scene_pairs", pairs},
          {"votes", votes},
          {"entries_per_lookup", pairs > 0 ? votes / pairs : 0.0},
          {"ns_per_pair", pairs > 0 ? matching * 1e6 / pairs : 0.0},
          {"ns_per_vote", votes > 0 ? matching * 1e6 / votes : 0.0},
          {"found", found},
          {"accuracy", accuracy},
          {"error_median_mm", errors.empty() ? nlohmann::json() : nlohmann::json(Median(errors))},
          {"error_max_mm", errors.empty()
                               ? nlohmann::json()
                               : nlohmann::json(*std::max_element(errors.begin(), errors.end()))}};
}

// A seat sweep as a job sees it: points in the sweep frame, each point's line of sight, the
// true hole centre.
struct SeatSweep {
  PointCloud cloud;
  std::vector<Eigen::Vector3d> sight;
  Eigen::Vector3d hole_true = Eigen::Vector3d::Zero();
};

struct SeatSet {
  std::vector<SeatSweep> sweeps;
  std::string part_file;
};

// Simulates `placements` seat sweeps with `profiles` profiles each and triangulates them with the
// simulated sensor's true camera and laser plane, in the sensor frame at the sweep's t0.
SeatSet SimulateSeatSweeps(const SpeedBenchOptions& options, int placements, int profiles,
                           const std::string& dir, const ProgressCallback& progress) {
  SimConfig config = SimConfigForProfile(options.profile);
  config.seed = options.seed;
  config.timing.profiles = profiles;
  SimulateSeats(config, placements, dir, progress, 0);
  const CellTruth truth = MakeCellTruth(config);
  const LinearSweep motion = MakeLinearSweep(config, truth.sensor);
  const triangulation::Triangulator triangulator(truth.sensor.camera,
                                                 truth.sensor.laser.Coefficients());
  triangulation::SweepOptions sweep_options = LinearSweepRecordOf(motion, config).Options();
  sweep_options.threads = 0;
  const FrameGraph graph = LoadFrameGraph(dir + "/truth/cell.yaml");
  SeatSet set;
  set.part_file = dir + "/models/seat.part.yaml";
  const Eigen::Vector3d hole =
      localize::ReadPartFile(set.part_file).Grasp("hole").part_from_grasp.translation_mm;
  for (int i = 0; i < placements; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "seat_%03d", i);
    const triangulation::SweepResult sweep = triangulation::AssembleSweep(
        triangulation::ReadProfiles(dir + "/profiles/" + name + ".lcp"), triangulator,
        sweep_options);
    SeatSweep s;
    s.sight = localize::LinesOfSight(sweep);
    s.cloud = sweep.cloud;
    s.hole_true = motion.cell_from_sensor_start.inverse() * graph.Transform("cell", name) * hole;
    set.sweeps.push_back(std::move(s));
  }
  return set;
}

localize::PartModel LoadSeatModel(const SpeedBenchOptions& options, const std::string& part_file) {
  localize::PartModelOptions mo;
  mo.cache_dir = options.work_dir + "/model_cache";
  mo.load_mesh = false;
  return localize::LoadPartModel(localize::ReadPartFile(part_file), mo);
}

// LocalizeParts on every sweep `runs` times; the error is that of the hole grasp.
registration::LocalizeOptions BaseOptions(const SpeedBenchOptions& options) {
  return options.options_file.empty()
             ? registration::LocalizeOptions{}
             : registration::ReadLocalizeOptions(options.options_file).localize;
}

std::vector<Sample> TimeSeats(const SpeedBenchOptions& options, const SeatSet& set,
                              const localize::PartModel& model, int threads, int runs) {
  localize::LocalizePartsOptions o;
  o.localize = BaseOptions(options);
  o.threads = threads;
  const std::vector<localize::PartRequest> request = {{&model, 1}};
  std::vector<Sample> samples;
  for (const SeatSweep& sweep : set.sweeps) {
    for (int run = 0; run < runs; ++run) {
      const localize::LocalizePartsResult r =
          localize::LocalizeParts(sweep.cloud, sweep.sight, request, o);
      Sample s = FromParts(r);
      if (s.found) {
        for (const localize::GraspPose& g : r.instances.front().grasps) {
          if (g.name == "hole")
            s.error_mm = (g.target_from_grasp.translation() - sweep.hole_true).norm();
        }
      }
      samples.push_back(s);
    }
  }
  return samples;
}

// One real case: a model in a scene, the committed reference pose when there is one.
struct RealCase {
  std::string name;
  std::string model;
  std::string scene;
  double scale = 1.0;  // to mm
  std::string reference;
  std::size_t keep_every = 1;  // every n-th scene point only
  bool drop_normals = false;   // the scene's normals are estimated (an unorganized scan)
};

std::vector<RealCase> RealCases(const SpeedBenchOptions& options, nlohmann::json* skipped) {
  const std::string real = options.source_dir + "/datasets/real";
  const std::string refs = options.source_dir + "/tests/registration/data";
  std::vector<RealCase> cases = {
      {"UWA rs1 + parasaurolophus", real + "/uwa/parasaurolophus_6700.bin.ply",
       real + "/uwa/rs1_normals.bin.ply", 1.0, refs + "/rs1_parasaurolophus_reference.txt"},
      // A ~40k-point unorganized scan whose normals must be estimated: every 3rd point of rs1
      // (38,125 points), its normals dropped.
      {"UWA rs1, every 3rd point, normals estimated", real + "/uwa/parasaurolophus_6700.bin.ply",
       real + "/uwa/rs1_normals.bin.ply", 1.0, refs + "/rs1_parasaurolophus_reference.txt", 3,
       true}};
  if (options.shared_data_dir.empty()) {
    skipped->push_back("UWA rs22: no shared data folder given");
  } else {
    const std::string uwa = options.shared_data_dir + "/uwa";
    cases.push_back({"UWA rs22 + parasaurolophus", uwa + "/parasaurolophus_low_normals2.ply",
                     uwa + "/rs22_proc2.ply", 1.0, refs + "/rs22_parasaurolophus_reference.txt"});
  }
  cases.push_back({"PCL bun0 in bun4", real + "/pcl/bun0.pcd", real + "/pcl/bun4.pcd", 1000.0, ""});
  cases.push_back({"PCL milk in its Kinect scene", real + "/pcl/milk.pcd",
                   real + "/pcl/milk_cartoon_all_small_clorox.pcd", 1000.0,
                   refs + "/milk_reference.txt"});
  return cases;
}

PointCloud ReadScaled(const std::string& path, double scale) {
  PointCloud cloud = io::ReadPointCloud(path);
  if (scale != 1.0)
    for (Eigen::Vector3d& p : cloud.positions) p *= scale;
  return cloud;
}

std::vector<nlohmann::json> RunReal(const SpeedBenchOptions& options, nlohmann::json* skipped,
                                    const ProgressCallback& progress) {
  std::vector<nlohmann::json> rows;
  for (const RealCase& c : RealCases(options, skipped)) {
    const PointCloud model_cloud = ReadScaled(c.model, c.scale);
    PointCloud scene = ReadScaled(c.scene, c.scale);
    if (c.keep_every > 1) {
      std::vector<std::size_t> keep;
      for (std::size_t i = 0; i < scene.size(); i += c.keep_every) keep.push_back(i);
      scene = scene.Subset(keep);
    }
    if (c.drop_normals) scene.normals.clear();
    const Eigen::Isometry3d reference =
        c.reference.empty() ? Eigen::Isometry3d::Identity() : ReadPoseFile(c.reference);
    const registration::PpfModel model = registration::PpfModel::Build(model_cloud);
    for (int threads : options.threads) {
      registration::LocalizeOptions lo = BaseOptions(options);
      lo.threads = threads;
      std::vector<Sample> samples;
      for (int run = 0; run < options.runs; ++run) {
        const registration::LocalizationResult r = registration::LocalizeInCloud(scene, model, lo);
        Sample s = FromLocalization(r);
        if (s.found && !c.reference.empty()) {
          s.error_mm = registration::PoseRmsDistanceMm(
              model_cloud.positions, r.candidates.front().scene_from_model, reference);
        }
        samples.push_back(s);
      }
      rows.push_back(Summarize(c.name, "real", threads, samples,
                               c.reference.empty() ? "found (no reference pose)"
                                                   : "RMS displacement of the model points "
                                                     "from the reference pose"));
      ReportProgress(progress, c.name, 1.0);
    }
  }
  return rows;
}

nlohmann::json RunSeries(const SpeedBenchOptions& options, const ProgressCallback& progress) {
  nlohmann::json series = nlohmann::json::array();
  for (int profiles : options.series_profiles) {
    const std::string dir = options.work_dir + "/series_" + std::to_string(profiles);
    const SeatSet set = SimulateSeatSweeps(options, 1, profiles, dir, progress);
    const localize::PartModel model = LoadSeatModel(options, set.part_file);
    nlohmann::json row = Summarize("seat sweep, " + std::to_string(profiles) + " profiles",
                                   "series", 1, TimeSeats(options, set, model, 1, options.runs),
                                   "hole grasp against the simulator's truth");
    row["profiles"] = profiles;
    row["ns_per_point"] =
        row["stages_ms"]["total"].get<double>() * 1e6 / std::max(1.0, row["points"].get<double>());
    series.push_back(row);
  }
  double mean = 0.0;
  for (const auto& r : series) mean += r["ns_per_point"].get<double>();
  mean /= std::max<std::size_t>(1, series.size());
  double worst = 0.0;
  for (auto& r : series) {
    r["ns_per_point_vs_mean"] = r["ns_per_point"].get<double>() / mean - 1.0;
    worst = std::max(worst, std::abs(r["ns_per_point_vs_mean"].get<double>()));
  }
  return {{"rows", series}, {"mean_ns_per_point", mean}, {"largest_deviation", worst}};
}

}  // namespace

void SpeedBenchOptions::Check() const {
  if (runs < 1) throw OptionError("runs " + std::to_string(runs) + " < 1");
  if (placements < 1) throw OptionError("placements " + std::to_string(placements) + " < 1");
  SimConfigForProfile(profile);  // throws OptionError naming an unknown profile
  if (real && source_dir.empty())
    throw OptionError("source_dir is empty: the real cases read datasets/real from it");
  if (threads.empty()) throw OptionError("threads is empty: give at least one thread count");
  for (int t : threads)
    if (t < 0) throw OptionError("threads: " + std::to_string(t) + " < 0 (0 = all cores)");
  for (int p : series_profiles)
    if (p < 10) throw OptionError("series_profiles: " + std::to_string(p) + " < 10");
}

nlohmann::json RunSpeedBench(const SpeedBenchOptions& options, const ProgressCallback& progress) {
  options.Check();
  std::filesystem::create_directories(options.work_dir);
  nlohmann::json result = {{"format", "lasercell.bench_speed"},
                           {"version", 1},
                           {"runs", options.runs},
                           {"placements", options.placements},
                           {"seed", options.seed},
                           {"profile", options.profile},
                           {"cores", std::max(1U, std::thread::hardware_concurrency())}};
  nlohmann::json cases = nlohmann::json::array();
  nlohmann::json skipped = nlohmann::json::array();
  if (options.seat) {
    const SeatSet set =
        SimulateSeatSweeps(options, options.placements, 350, options.work_dir + "/seats", progress);
    const localize::PartModel model = LoadSeatModel(options, set.part_file);
    for (int threads : options.threads) {
      cases.push_back(
          Summarize("simulated seat sweeps (" + std::to_string(options.placements) + " placements)",
                    "seat", threads, TimeSeats(options, set, model, threads, options.runs),
                    "hole grasp against the simulator's truth"));
      ReportProgress(progress, "seat sweeps", 1.0);
    }
  }
  if (options.real) {
    for (nlohmann::json& row : RunReal(options, &skipped, progress)) cases.push_back(row);
  }
  result["cases"] = cases;
  result["skipped"] = skipped;
  if (options.series) result["series"] = RunSeries(options, progress);
  return result;
}

std::string SpeedMarkdown(const nlohmann::json& result) {
  std::string md;
  char line[512];
  std::snprintf(
      line, sizeof line,
      "#### Where the time goes (`lasercell bench speed --runs %d --placements %d "
      "--profile %s`)\n\nMedians of %d runs per case and thread count (the seat sweeps: of "
      "every run of every placement), model prebuilt, files parsed before the clock "
      "starts; %d core(s). Times in ms.\n\n",
      result["runs"].get<int>(), result["placements"].get<int>(),
      result["profile"].get<std::string>().c_str(), result["runs"].get<int>(),
      result["cores"].get<int>());
  md += line;
  md +=
      "| case | threads | points | roi | normals | voxel | kd-tree | voting | clustering | "
      "verification | ICP | other | **total** | found | error median / max (mm) |\n";
  md += "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  const auto error_text = [](const nlohmann::json& c) {
    if (c["error_median_mm"].is_null()) return std::string("-");
    char b[64];
    std::snprintf(b, sizeof b, "%.3f / %.3f", c["error_median_mm"].get<double>(),
                  c["error_max_mm"].get<double>());
    return std::string(b);
  };
  const auto rows = [&](const nlohmann::json& list) {
    for (const nlohmann::json& c : list) {
      std::snprintf(line, sizeof line, "| %s | %d | %.0f |", c["case"].get<std::string>().c_str(),
                    c["threads"].get<int>(), c["points"].get<double>());
      md += line;
      for (const char* stage : kStages) {
        const double v = c["stages_ms"][stage].get<double>();
        std::snprintf(line, sizeof line, std::string(stage) == "total" ? " **%.1f** |" : " %.1f |",
                      v);
        md += line;
      }
      std::snprintf(line, sizeof line, " %zu/%zu | %s |\n", c["found"].get<std::size_t>(),
                    c["runs"].get<std::size_t>(), error_text(c).c_str());
      md += line;
    }
  };
  rows(result["cases"]);
  md += "\nThe counts that explain the time (medians):\n\n";
  md +=
      "| case | threads | used points | voxel points | reference points | scene pairs | votes "
      "| model entries per looked-up key | ns per pair | ns per vote |\n";
  md += "|---|---|---|---|---|---|---|---|---|---|\n";
  for (const nlohmann::json& c : result["cases"]) {
    std::snprintf(line, sizeof line,
                  "| %s | %d | %.0f | %.0f | %.0f | %.0f | %.0f | %.1f | %.1f | "
                  "%.2f |\n",
                  c["case"].get<std::string>().c_str(), c["threads"].get<int>(),
                  c["used_points"].get<double>(), c["sampled_points"].get<double>(),
                  c["reference_points"].get<double>(), c["scene_pairs"].get<double>(),
                  c["votes"].get<double>(), c["entries_per_lookup"].get<double>(),
                  c["ns_per_pair"].get<double>(), c["ns_per_vote"].get<double>());
    md += line;
  }
  for (const nlohmann::json& s : result["skipped"])
    md += "\nNot run: " + s.get<std::string>() + "\n";
  if (result.contains("series")) {
    const nlohmann::json& series = result["series"];
    md += "\nSweep size series (one seat placement, one thread):\n\n";
    md += "| profiles | points | total (ms) | ns per input point | vs the series mean |\n";
    md += "|---|---|---|---|---|\n";
    for (const nlohmann::json& r : series["rows"]) {
      std::snprintf(line, sizeof line, "| %d | %.0f | %.1f | %.1f | %+.0f %% |\n",
                    r["profiles"].get<int>(), r["points"].get<double>(),
                    r["stages_ms"]["total"].get<double>(), r["ns_per_point"].get<double>(),
                    100.0 * r["ns_per_point_vs_mean"].get<double>());
      md += line;
    }
    std::snprintf(line, sizeof line,
                  "\nTime per input point: largest deviation from the series mean %.0f %% "
                  "(target: within +-25 %%).\n",
                  100.0 * series["largest_deviation"].get<double>());
    md += line;
  }
  return md;
}

}  // namespace lasercell::datasets
