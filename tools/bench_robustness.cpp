// `lasercell bench robustness`: the synthetic robustness curve. The UWA
// parasaurolophus is rendered at seeded random poses into the real rs1 clutter (its real instance
// cut out), z-buffered from the scanner, with Gaussian range noise (datasets/synthetic_scan.hpp),
// and localized with LocalizeInCloud at default options. A trial succeeds when the top candidate's
// ADD (Hinterstoisser et al. 2012: mean distance between the model's points under the true and the
// found pose) is <= 0.05 x the model diameter after ICP. The same placements are used at every
// noise level, so the rows form a curve. Per level one scene without the part (the noisy clutter,
// normals re-estimated) must give found = false; a found part there is a false positive.
#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/io/file_util.hpp"
#include "core/json_io.hpp"
#include "core/se3.hpp"
#include "datasets/rng.hpp"
#include "datasets/synthetic_scan.hpp"
#include "registration/localize_in_cloud.hpp"
#include "registration/ppf_model.hpp"
#include "tools/bench.hpp"

namespace lasercell::tools {
namespace {

namespace fs = std::filesystem;

constexpr char kUwaDir[] = "datasets/real/uwa";
constexpr char kReferenceFile[] = "tests/registration/data/rs1_parasaurolophus_reference.txt";

// The source tree holding the bundled data: $LASERCELL_SOURCE_DIR, else the nearest ancestor of
// the working directory or of the executable that has datasets/real/uwa.
std::string FindSourceRoot() {
  auto has_data = [](const fs::path& root) {
    std::error_code ec;
    return fs::is_regular_file(root / kUwaDir / "parasaurolophus_6700.ply", ec);
  };
  if (const char* env = std::getenv("LASERCELL_SOURCE_DIR"); env != nullptr && *env != '\0') {
    if (!has_data(env))
      throw FileError(std::string(env) + "/" + kUwaDir,
                      "LASERCELL_SOURCE_DIR has no bundled UWA data");
    return env;
  }
  std::vector<fs::path> starts;
  std::error_code ec;
  starts.push_back(fs::current_path(ec));
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) starts.push_back(exe.parent_path());
  for (fs::path dir : starts) {
    for (; !dir.empty(); dir = dir.parent_path()) {
      if (has_data(dir)) return dir.string();
      if (dir == dir.parent_path()) break;
    }
  }
  throw FileError(kUwaDir,
                  "bundled UWA data not found above the working directory or the executable; "
                  "run from the source tree or set LASERCELL_SOURCE_DIR");
}

// Mean distance of the model's points between two poses, mm (ADD).
double AddMm(const std::vector<Eigen::Vector3d>& points, const Eigen::Isometry3d& a,
             const Eigen::Isometry3d& b) {
  double sum = 0.0;
  for (const auto& p : points) sum += (a * p - b * p).norm();
  return sum / static_cast<double>(points.size());
}

// Nearest-rank percentile of a sorted vector (q in [0, 1]).
double Percentile(const std::vector<double>& sorted, double q) {
  if (sorted.empty()) return std::numeric_limits<double>::quiet_NaN();
  const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(sorted.size())));
  return sorted[std::clamp<std::size_t>(rank, 1, sorted.size()) - 1];
}

struct LevelStats {
  double noise_mm = 0.0;
  int trials = 0, found = 0, within_1mm = 0, wrong_pose = 0, nothing = 0, failed_occluded = 0;
  std::vector<double> add_mm;  // per trial; +inf when nothing was reported
  std::vector<double> time_ms;
  bool no_part_found = false;
};

std::string Cell(double v, const char* format) {
  if (!std::isfinite(v)) return "not found";
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

void CheckArgs(const RobustnessBenchArgs& args) {
  if (args.placements < 1) throw OptionError("bench robustness: --placements must be >= 1");
  if (args.noise_mm.empty())
    throw OptionError("bench robustness: --noise needs at least one level");
  for (double sigma : args.noise_mm) {
    if (!(sigma >= 0.0) || !std::isfinite(sigma))
      throw OptionError("bench robustness: noise levels must be >= 0 mm");
  }
  if (args.threads < 0)
    throw OptionError("bench robustness: --threads must be >= 0 (0 = all cores)");
}

// What every trial of the curve shares.
struct Trials {
  const RobustnessBenchArgs& args;
  const datasets::Rs1SyntheticData& data;
  const registration::PpfModel& model;
  const registration::LocalizeOptions& options;
  Eigen::Vector3d centroid;  // of the model, for the random placements
  double threshold_mm;       // ADD threshold of a success
};

// Placement i at noise level `level`: renders the scene, localizes, counts the outcome into
// `stats` and returns the trial's JSON.
nlohmann::json RunTrial(const Trials& bench, std::size_t level, int i,
                        const datasets::SyntheticScanOptions& scan_options, LevelStats& stats) {
  const RobustnessBenchArgs& args = bench.args;
  const datasets::Rs1SyntheticData& data = bench.data;
  // Same placement at every level; the noise has its own stream per level and placement.
  std::mt19937_64 pose_rng(datasets::StreamSeed(args.seed, static_cast<std::uint64_t>(i)));
  std::mt19937_64 noise_rng(datasets::StreamSeed(datasets::StreamSeed(args.seed, 1000003 + level),
                                                 static_cast<std::uint64_t>(i)));
  const Eigen::Isometry3d truth = datasets::RandomPlacementInRs1(bench.centroid, pose_rng);
  const datasets::SyntheticScan scan = datasets::RenderSyntheticScan(
      data.clutter, data.part_surface, {truth}, scan_options, noise_rng);
  // Fraction of the part's surface that the clutter leaves visible (the part alone, rendered
  // alike).
  const std::size_t alone = datasets::VisibleFromOrigin(data.part_surface.Transformed(truth),
                                                        scan_options.zbuffer_cell_mm,
                                                        scan_options.zbuffer_depth_tolerance_mm)
                                .size();
  const double unoccluded =
      alone > 0 ? static_cast<double>(scan.part_points) / static_cast<double>(alone) : 0.0;

  const registration::LocalizationResult result =
      registration::LocalizeInCloud(scan.cloud, bench.model, bench.options);
  const double add =
      result.found ? AddMm(data.model.positions, truth, result.candidates.front().scene_from_model)
                   : std::numeric_limits<double>::infinity();
  const bool success = add <= bench.threshold_mm;
  ++stats.trials;
  stats.found += success ? 1 : 0;
  stats.within_1mm += add <= 1.0 ? 1 : 0;
  stats.wrong_pose += result.found && !success ? 1 : 0;
  stats.nothing += result.found ? 0 : 1;
  stats.failed_occluded += !success && unoccluded < 0.5 ? 1 : 0;
  stats.add_mm.push_back(add);
  stats.time_ms.push_back(result.timings.total_ms);

  nlohmann::json t;
  t["noise_mm"] = stats.noise_mm;
  t["placement"] = i;
  t["scene_from_model_true"] = json::MatrixFlat(truth);
  t["scene_points"] = scan.cloud.size();
  t["part_points"] = scan.part_points;
  t["unoccluded_fraction"] = unoccluded;
  t["found"] = result.found;
  t["success"] = success;
  t["time_ms"] = result.timings.total_ms;
  if (result.found) {
    const registration::LocalizationCandidate& best = result.candidates.front();
    t["add_mm"] = add;
    t["rotation_error_deg"] =
        RotationDistance(best.scene_from_model, truth) * 180.0 / 3.14159265358979323846;
    t["translation_error_mm"] = TranslationDistance(best.scene_from_model, truth);
    t["scene_from_model_found"] = json::MatrixFlat(best.scene_from_model);
    t["support"] = best.verification.support;
    t["icp_rmse_mm"] = best.icp.rmse_mm;
  } else {
    t["add_mm"] = nullptr;
    t["message"] = result.message;
  }
  return t;
}

// The scene without the part: the clutter with this level's noise, normals re-estimated. Sets
// stats.no_part_found; returns the scene's JSON.
nlohmann::json RunSceneWithoutPart(const Trials& bench, std::size_t level,
                                   const datasets::SyntheticScanOptions& scan_options,
                                   LevelStats& stats) {
  datasets::SyntheticScanOptions empty_options = scan_options;
  empty_options.clutter_noise_sigma_mm = stats.noise_mm;
  std::mt19937_64 empty_rng(datasets::StreamSeed(bench.args.seed, 2000003 + level));
  datasets::SyntheticScan empty = datasets::RenderSyntheticScan(
      bench.data.clutter, bench.data.part_surface, {}, empty_options, empty_rng);
  if (stats.noise_mm > 0.0) empty.cloud.normals.clear();
  const registration::LocalizationResult empty_result =
      registration::LocalizeInCloud(empty.cloud, bench.model, bench.options);
  stats.no_part_found = empty_result.found;
  std::fprintf(stderr, "[robustness] sigma %.2f mm: scene without the part -> found = %s\n",
               stats.noise_mm, empty_result.found ? "true (FALSE POSITIVE)" : "false");
  return {{"noise_mm", stats.noise_mm},
          {"scene_points", empty.cloud.size()},
          {"found", empty_result.found},
          {"message", empty_result.message},
          {"time_ms", empty_result.timings.total_ms}};
}

// The Markdown table, one row per noise level (sorts each level's ADDs and times); returns the
// rows as JSON.
nlohmann::json PrintCurve(const RobustnessBenchArgs& args, std::vector<LevelStats>& levels,
                          double diameter_mm, double threshold_mm) {
  std::printf(
      "Synthetic robustness: UWA parasaurolophus in real rs1 clutter, %d placements per level, "
      "seed %u, "
      "%d thread(s)\n",
      args.placements, args.seed, args.threads);
  std::printf(
      "model diameter %.1f mm; success = top candidate's ADD <= 0.05 x diameter = %.2f mm after "
      "ICP\n\n",
      diameter_mm, threshold_mm);
  std::printf(
      "| noise sigma (mm) | trials | found (ADD <= %.2f mm) | ADD <= 1 mm | wrong pose | nothing "
      "found | "
      "failures < 50 %% visible | median ADD (mm) | p90 ADD (mm) | median time (ms) | scene "
      "without part |\n",
      threshold_mm);
  std::printf("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|\n");
  nlohmann::json summary = nlohmann::json::array();
  for (LevelStats& s : levels) {
    std::sort(s.add_mm.begin(), s.add_mm.end());
    std::sort(s.time_ms.begin(), s.time_ms.end());
    const double n = s.trials;
    const double median_add = Percentile(s.add_mm, 0.5), p90_add = Percentile(s.add_mm, 0.9);
    const double median_ms = Percentile(s.time_ms, 0.5);
    std::printf(
        "| %.2f | %d | %.1f %% | %.1f %% | %.1f %% | %.1f %% | %d | %s | %s | %.1f | %s |\n",
        s.noise_mm, s.trials, 100.0 * s.found / n, 100.0 * s.within_1mm / n,
        100.0 * s.wrong_pose / n, 100.0 * s.nothing / n, s.failed_occluded,
        Cell(median_add, "%.3f").c_str(), Cell(p90_add, "%.3f").c_str(), median_ms,
        s.no_part_found ? "found (false positive)" : "not found (correct)");
    summary.push_back(
        {{"noise_mm", s.noise_mm},
         {"trials", s.trials},
         {"found_fraction", s.found / n},
         {"within_1mm_fraction", s.within_1mm / n},
         {"wrong_pose_fraction", s.wrong_pose / n},
         {"nothing_found_fraction", s.nothing / n},
         {"median_add_mm",
          std::isfinite(median_add) ? nlohmann::json(median_add) : nlohmann::json(nullptr)},
         {"p90_add_mm", std::isfinite(p90_add) ? nlohmann::json(p90_add) : nlohmann::json(nullptr)},
         {"median_time_ms", median_ms},
         {"no_part_false_positive", s.no_part_found}});
  }
  std::printf(
      "\n(ADD percentiles count a trial with nothing found as infinite; time is LocalizeInCloud's "
      "total, "
      "scene generation excluded.)\n");
  std::fflush(stdout);
  return summary;
}

}  // namespace

void RunRobustnessBench(const RobustnessBenchArgs& args) {
  CheckArgs(args);
  const std::string root = FindSourceRoot();
  std::fprintf(stderr, "[robustness] loading %s/%s ...\n", root.c_str(), kUwaDir);
  const datasets::Rs1SyntheticData data =
      datasets::LoadRs1SyntheticData(root + "/" + kUwaDir, root + "/" + kReferenceFile);
  const auto build_start = std::chrono::steady_clock::now();
  const registration::PpfModel model = registration::PpfModel::Build(data.model);
  const double build_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - build_start)
          .count();
  const double diameter_mm = model.diameter_mm();
  const double threshold_mm = 0.05 * diameter_mm;
  const Eigen::Vector3d centroid = data.model.Centroid();
  std::fprintf(stderr,
               "[robustness] model: %zu points, diameter %.1f mm (ADD threshold %.2f mm), built in "
               "%.0f ms\n",
               data.model.size(), diameter_mm, threshold_mm, build_ms);

  registration::LocalizeOptions options;
  options.threads = args.threads;
  const Trials bench{args, data, model, options, centroid, threshold_mm};

  nlohmann::json trials = nlohmann::json::array();
  nlohmann::json no_part = nlohmann::json::array();
  std::vector<LevelStats> levels;
  for (std::size_t level = 0; level < args.noise_mm.size(); ++level) {
    LevelStats stats;
    stats.noise_mm = args.noise_mm[level];
    datasets::SyntheticScanOptions scan_options;
    scan_options.noise_sigma_mm = stats.noise_mm;
    for (int i = 0; i < args.placements; ++i) {
      trials.push_back(RunTrial(bench, level, i, scan_options, stats));
      if ((i + 1) % 20 == 0 || i + 1 == args.placements) {
        std::fprintf(stderr, "[robustness] sigma %.2f mm: %d/%d placements, %d found\n",
                     stats.noise_mm, i + 1, args.placements, stats.found);
      }
    }
    no_part.push_back(RunSceneWithoutPart(bench, level, scan_options, stats));
    levels.push_back(std::move(stats));
  }
  nlohmann::json summary = PrintCurve(args, levels, diameter_mm, threshold_mm);

  if (!args.json_out.empty()) {
    nlohmann::json j;
    j["benchmark"] = "robustness";
    j["placements"] = args.placements;
    j["noise_mm"] = args.noise_mm;
    j["seed"] = args.seed;
    j["threads"] = args.threads;
    j["diameter_mm"] = diameter_mm;
    j["add_threshold_mm"] = threshold_mm;
    j["model_build_ms"] = build_ms;
    j["summary"] = std::move(summary);
    j["trials"] = std::move(trials);
    j["no_part"] = std::move(no_part);
    io::WriteFileAtomically(args.json_out, j.dump(1) + "\n");
    std::fprintf(stderr, "[robustness] wrote %s\n", args.json_out.c_str());
  }
}

}  // namespace lasercell::tools
