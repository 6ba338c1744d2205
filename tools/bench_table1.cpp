// `lasercell bench table1 --placements N`: Skotheim et al. 2012's Table I, reproduced through
// the whole product: simulate the cell's captures and N seat placements (drawn as in the paper:
// +-100 mm in x and y, +-25 deg tilt, +-180 deg yaw), calibrate camera, laser plane and
// handling_base <- sensor from the captures (datasets/capture_calibration.hpp; never the truth),
// then localize every seat through one JobRunner (localize/job_run.hpp) and compare the hole
// grasp with the truth in handling_base: after PPF (the coarse pose) and after ICP, the share
// within the gripper's +-10 mm, the reported uncertainty against the error (1-sigma coverage,
// 3-sigma exceedances), and the time per part. Prints a Markdown section for BENCHMARKS.md and
// writes every trial as JSON.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "core/io/file_util.hpp"
#include "core/json_io.hpp"
#include "core/pose_covariance.hpp"
#include "core/progress.hpp"
#include "core/stats.hpp"
#include "datasets/capture_calibration.hpp"
#include "datasets/sim_config.hpp"
#include "datasets/simulate.hpp"
#include "localize/job_run.hpp"
#include "tools/bench.hpp"
#include "triangulation/profile_io.hpp"

namespace lasercell::tools {
namespace {

struct Table1Args {
  int placements = 1000;
  int cells = 1;  // independent simulated cells, each calibrated from its own captures
  unsigned seed = 1;
  int threads = 1;
  std::string work_dir = "table1";
  std::string sim_config;
  std::string json_out;
  std::string markdown_out;
};

struct Trial {
  int cell = 0;
  std::string seat;
  bool found = false;
  double ppf_error_mm = NAN, icp_error_mm = NAN;
  bool graspable = false;
  std::string reason;
  Eigen::Vector3d error = Eigen::Vector3d::Zero();  // found - true hole centre, handling_base
  Eigen::Vector3d sigma = Eigen::Vector3d::Zero();  // reported 1-sigma of the hole centre
  double localization_ms = 0, triangulation_ms = 0, run_ms = 0;
};

struct Stats {
  double mean = NAN, sd = NAN, p99 = NAN, max = NAN;
};

Stats Summarize(std::vector<double> v) {
  Stats s;
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  double sum = 0, sq = 0;
  for (double x : v) sum += x;
  s.mean = sum / static_cast<double>(v.size());
  for (double x : v) sq += (x - s.mean) * (x - s.mean);
  s.sd = v.size() > 1 ? std::sqrt(sq / static_cast<double>(v.size() - 1)) : 0.0;
  s.p99 = v[static_cast<std::size_t>(std::ceil(0.99 * static_cast<double>(v.size()))) - 1];
  s.max = v.back();
  return s;
}

datasets::SimConfig ConfigOf(const Table1Args& args, int cell, int seats) {
  datasets::SimConfig config =
      args.sim_config.empty() ? datasets::SimConfig{} : datasets::LoadSimConfig(args.sim_config);
  config.seed = args.seed + static_cast<std::uint64_t>(cell);
  config.seat_count = seats;
  config.capture_seats = config.capture_planes = config.capture_spheres = true;
  config.capture_chessboard_images = config.capture_touches = true;
  config.capture_trajectory = config.capture_laser_line_images = false;
  config.capture_eye_in_hand = config.capture_joint_poses = config.capture_hand_eye_images = false;
  return config;
}

localize::Job JobOf(const std::string& sim, const datasets::CaptureCalibration& cal,
                    const std::string& work, int threads) {
  localize::Job job;
  job.cell = cal.cell_file;
  job.camera = cal.camera_file;
  job.profiles = sim + "/profiles/seat_000.lcp";
  job.linear_record = sim + "/records/linear_sweep.yaml";
  job.threads = threads;
  job.model_cache = work + "/model_cache";
  localize::JobPart part;
  part.file = sim + "/models/seat.part.yaml";
  part.part = localize::ReadPartFile(part.file);
  job.parts.push_back(part);
  return job;
}

Trial RunTrial(localize::JobRunner& runner, const std::string& sim, const std::string& seat,
               const Eigen::Isometry3d& truth, const Eigen::Vector3d& hole_in_part) {
  Trial t;
  t.seat = seat;
  const localize::JobResult r =
      runner.Run(triangulation::ReadProfiles(sim + "/profiles/" + seat + ".lcp"), seat);
  t.localization_ms = r.timings.localization_ms;
  t.triangulation_ms = r.timings.triangulation_ms;
  t.run_ms = r.timings.run_ms;
  if (r.parts.instances.empty()) {
    t.reason = r.parts.searches.front().message;
    return t;
  }
  const localize::PartInstance& inst = r.parts.instances.front();
  const Eigen::Vector3d hole_true = truth * hole_in_part;
  t.found = true;
  t.ppf_error_mm = (inst.candidate.coarse_scene_from_model * hole_in_part - hole_true).norm();
  t.error = inst.target_from_part * hole_in_part - hole_true;
  t.icp_error_mm = t.error.norm();
  t.graspable = inst.graspable;
  t.reason = inst.not_graspable_reason;
  if (inst.covariance_valid) {
    const Eigen::Matrix3d cov =
        PointCovariance(inst.target_from_part, inst.covariance, hole_in_part);
    t.sigma = cov.diagonal().cwiseMax(0.0).cwiseSqrt();
  }
  return t;
}

std::string Row(const char* name, const Stats& s) {
  char buf[200];
  std::snprintf(buf, sizeof buf, "| %s | %.3f | %.3f | %.3f | %.3f |", name, s.mean, s.sd, s.p99,
                s.max);
  return buf;
}

// The Markdown section (numbers from `j`, so text and table agree).
std::string Markdown(const nlohmann::json& j) {
  char buf[900];
  std::string md =
      "### Table I through the calibrated chain (`lasercell bench table1 --placements " +
      std::to_string(j["placements"].get<int>()) + " --cells " +
      std::to_string(j["cells"].get<int>()) + " --seed " +
      std::to_string(j["seed"].get<unsigned>()) + "`)\n\n";
  const nlohmann::json& first = j["calibrations"][0];
  std::snprintf(buf, sizeof buf,
                "Calibrated from the simulated captures (never the truth), %d cell(s), each from "
                "its own captures; the first: %s; %s; %s.\n\n",
                j["cells"].get<int>(), first["camera"].get<std::string>().c_str(),
                first["laser"].get<std::string>().c_str(),
                first["spheres"].get<std::string>().c_str());
  md += buf;
  md +=
      "| hole-centre error in handling_base (mm) | mean | sigma | p99 | max "
      "|\n|---|---|---|---|---|\n";
  const auto stats = [&](const char* key) {
    const nlohmann::json& s = j[key];
    return Stats{s["mean"], s["sd"], s["p99"], s["max"]};
  };
  md += Row("after PPF (coarse pose)", stats("ppf_error_mm")) + "\n";
  md += Row("after ICP", stats("icp_error_mm")) + "\n";
  md += "| Skotheim et al. 2012, 10 placements: after PPF / after ICP | 10.69 / 1.81 | | | |\n\n";
  std::snprintf(
      buf, sizeof buf,
      "Found %d of %d placements; within the gripper's +-10 mm: %d (%.1f %%; the paper: "
      "10 of 10); reported graspable: %d. Reported 1-sigma of the hole centre covers the "
      "error %.1f %% of the time per axis (a Gaussian: 68.3 %%), %d of %d found "
      "placements exceed 3 sigma on some axis (three independent Gaussian axes: %.1f). "
      "Time per part, one thread: localization "
      "median %.1f ms, triangulation median %.1f ms, job run median %.1f ms (the job's "
      "own work: %.1f %% of triangulation + localization); the paper: ~1.7 s.\n",
      j["found"].get<int>(), j["placements"].get<int>(), j["within_10mm"].get<int>(),
      100.0 * j["within_10mm"].get<int>() / j["placements"].get<int>(), j["graspable"].get<int>(),
      100.0 * j["sigma_coverage"].get<double>(), j["beyond_3_sigma"].get<int>(),
      j["found"].get<int>(), j["beyond_3_sigma_expected"].get<double>(),
      j["median_localization_ms"].get<double>(), j["median_triangulation_ms"].get<double>(),
      j["median_run_ms"].get<double>(), 100.0 * j["job_overhead_fraction"].get<double>());
  return md + buf;
}

nlohmann::json StatsJson(const Stats& s) {
  return {{"mean", s.mean}, {"sd", s.sd}, {"p99", s.p99}, {"max", s.max}};
}

nlohmann::json Summary(const Table1Args& args, const std::vector<Trial>& trials,
                       const std::vector<datasets::CaptureCalibration>& cals) {
  std::vector<double> ppf, icp, loc, tri, run, overhead;
  int within = 0, graspable = 0, beyond = 0, covered = 0, axes = 0;
  nlohmann::json rows = nlohmann::json::array();
  for (const Trial& t : trials) {
    loc.push_back(t.localization_ms);
    tri.push_back(t.triangulation_ms);
    run.push_back(t.run_ms);
    overhead.push_back(t.run_ms - t.localization_ms - t.triangulation_ms);
    rows.push_back({{"cell", t.cell},
                    {"seat", t.seat},
                    {"found", t.found},
                    {"ppf_error_mm", json::FiniteOrNull(t.ppf_error_mm)},
                    {"icp_error_mm", json::FiniteOrNull(t.icp_error_mm)},
                    {"graspable", t.graspable},
                    {"reason", t.reason},
                    {"error_mm", json::Vector(t.error)},
                    {"sigma_mm", json::Vector(t.sigma)},
                    {"localization_ms", t.localization_ms}});
    if (!t.found) continue;
    ppf.push_back(t.ppf_error_mm);
    icp.push_back(t.icp_error_mm);
    within += t.icp_error_mm <= 10.0 ? 1 : 0;
    graspable += t.graspable ? 1 : 0;
    bool out3 = false;
    for (int k = 0; k < 3; ++k) {
      if (!(t.sigma[k] > 0)) continue;
      ++axes;
      covered += std::abs(t.error[k]) <= t.sigma[k] ? 1 : 0;
      out3 |= std::abs(t.error[k]) > 3.0 * t.sigma[k];
    }
    beyond += out3 ? 1 : 0;
  }
  const double median_tri = Median(tri), median_loc = Median(loc);
  nlohmann::json calibrations = nlohmann::json::array();
  for (const datasets::CaptureCalibration& cal : cals) {
    calibrations.push_back({{"camera", cal.camera_summary},
                            {"laser", cal.laser_summary},
                            {"spheres", cal.spheres_summary}});
  }
  return {{"format", "lasercell.bench_table1"},
          {"version", 1},
          {"placements", args.placements},
          {"cells", args.cells},
          {"seed", args.seed},
          {"threads", args.threads},
          {"calibrations", calibrations},
          {"found", static_cast<int>(icp.size())},
          {"within_10mm", within},
          {"graspable", graspable},
          {"ppf_error_mm", StatsJson(Summarize(ppf))},
          {"icp_error_mm", StatsJson(Summarize(icp))},
          {"sigma_coverage", axes > 0 ? static_cast<double>(covered) / axes : 0.0},
          {"beyond_3_sigma", beyond},
          // P(some |z_k| > 3 of three independent standard normals) x found.
          {"beyond_3_sigma_expected",
           (1.0 - std::pow(std::erf(3.0 / std::sqrt(2.0)), 3)) * static_cast<double>(icp.size())},
          {"median_localization_ms", median_loc},
          {"median_triangulation_ms", median_tri},
          {"median_run_ms", Median(run)},
          {"job_overhead_fraction", Median(overhead) / (median_tri + median_loc)},
          {"trials", rows}};
}

// One simulated cell: its captures and `seats` placements, calibrated from the captures alone,
// every seat localized through one JobRunner.
std::vector<Trial> RunCell(const Table1Args& args, int cell, int seats,
                           const ProgressCallback& progress,
                           std::vector<datasets::CaptureCalibration>* cals) {
  const std::string dir =
      args.cells == 1 ? args.work_dir : args.work_dir + "/cell_" + std::to_string(cell);
  const std::string sim = dir + "/sim";
  const datasets::SimConfig config = ConfigOf(args, cell, seats);
  std::fprintf(stderr, "cell %d of %d (seed %llu): simulating its captures and %d seats in %s\n",
               cell + 1, args.cells, static_cast<unsigned long long>(config.seed), seats,
               sim.c_str());
  datasets::SimulateCell(config, sim, progress, 0);
  cals->push_back(
      datasets::CalibrateCaptureFolder(sim, dir + "/cal", config.chessboard.board, progress, 0));
  const datasets::CaptureCalibration& cal = cals->back();
  std::fprintf(stderr, "calibrated in %.1f s: %s\n", cal.seconds, cal.spheres_summary.c_str());

  // The model cache is shared: every cell's seat is the same part.
  localize::JobRunner runner(JobOf(sim, cal, args.work_dir, args.threads));
  const FrameGraph truth = LoadFrameGraph(sim + "/truth/cell.yaml");
  const Eigen::Vector3d hole =
      runner.job().parts.front().part.Grasp("hole").part_from_grasp.translation_mm;
  std::vector<Trial> trials;
  for (int i = 0; i < seats; ++i) {
    char seat[32];
    std::snprintf(seat, sizeof seat, "seat_%03d", i);
    trials.push_back(RunTrial(runner, sim, seat, truth.Transform("handling_base", seat), hole));
    trials.back().cell = cell;
    progress("localizing", static_cast<double>(i + 1) / seats);
  }
  return trials;
}

void RunTable1Bench(const Table1Args& args) {
  if (args.placements % args.cells != 0) {
    throw InputError("--placements " + std::to_string(args.placements) +
                     " is not a multiple of --cells " + std::to_string(args.cells) +
                     ": every cell localizes the same number of seats");
  }
  const ProgressCallback progress = [](std::string_view stage, double fraction) {
    std::fprintf(stderr, "\r%-40.*s %5.1f %%", static_cast<int>(stage.size()), stage.data(),
                 100.0 * fraction);
    if (fraction >= 1.0) std::fprintf(stderr, "\n");
  };
  std::vector<datasets::CaptureCalibration> cals;
  std::vector<Trial> trials;
  for (int cell = 0; cell < args.cells; ++cell) {
    const std::vector<Trial> t = RunCell(args, cell, args.placements / args.cells, progress, &cals);
    trials.insert(trials.end(), t.begin(), t.end());
  }
  const nlohmann::json j = Summary(args, trials, cals);
  const std::string md = Markdown(j);
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
  cmd->add_option("--placements", args->placements, "Seat placements")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  cmd->add_option("--cells", args->cells,
                  "Independent simulated cells (seeds SEED, SEED+1, ...), each calibrated from "
                  "its own captures; the placements are split evenly between them, so the "
                  "uncertainty check draws the calibration errors too")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  cmd->add_option("--seed", args->seed, "Simulation seed")->capture_default_str();
  cmd->add_option("--threads", args->threads, "Localization threads (0 = all cores)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--work", args->work_dir, "Folder for the captures, calibration and cache")
      ->capture_default_str();
  cmd->add_option("--config", args->sim_config, "Simulator settings (SIM.yaml)");
  cmd->add_option("--json", args->json_out, "Also write every trial as JSON");
  cmd->add_option("--markdown", args->markdown_out, "Also write the Markdown section");
  cmd->callback([args] { RunTable1Bench(*args); });
}

}  // namespace lasercell::tools
