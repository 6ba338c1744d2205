// `lasercell calibrate spheres --cell CELL.yaml --sweep SWEEP.ply --touches touches.yaml
//  [--radius-mm R] [--free-radius] [--sweep-frame NAME] [--touch-sigma-mm S] [--up X,Y,Z]
//  [--report FILE.html] [--json FILE.json]`
//
// Half-sphere calibration (issue 7): segments the half spheres out of the sweep, fits them, matches
// them with the handling robot's touches of their tops and sets the static edge
// handling_base <- SWEEP_FRAME in CELL.yaml (only that edge). SWEEP_FRAME defaults to `sensor`:
// the sweep cloud of a linear sweep is in the sensor frame at the sweep start, so the edge is
// handling_base_from_sensor valid for that sweep trajectory (ARCHITECTURE.md, data path 1).
#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <ctime>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "calib/half_sphere_calibration.hpp"
#include "calib/sphere_segmentation.hpp"
#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "core/html_report.hpp"
#include "core/io/file_util.hpp"
#include "core/io/point_cloud_io.hpp"
#include "tools/commands.hpp"

namespace lasercell::tools {
namespace {

constexpr double kRadToDeg = 180.0 / std::numbers::pi;
constexpr const char* kJsonFormat = "lasercell.calibration_spheres";
constexpr int kJsonVersion = 1;

struct SpheresArgs {
  std::string cell, sweep, touches, report, json;
  std::string sweep_frame = "sensor";
  double radius_mm = 0;       // 0: from the touches file
  double touch_sigma_mm = 0;  // 0: the touches file's stated_sigma_mm
  bool free_radius = false;
  std::vector<double> up = {0, 0, 1};
};

std::string UtcNow() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

// FNV-1a 64 over the inputs' bytes: identifies the inputs (not a security digest).
std::string Digest(const std::vector<std::string>& blobs) {
  std::uint64_t h = 1469598103934665603ull;
  for (const std::string& b : blobs) {
    for (unsigned char c : b) {
      h ^= c;
      h *= 1099511628211ull;
    }
  }
  char buf[40];
  std::snprintf(buf, sizeof buf, "fnv1a64:%016llx", static_cast<unsigned long long>(h));
  return buf;
}

std::string Num(double v, const char* format = "%.4f") {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

nlohmann::json Vec(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

nlohmann::json PoseJson(const Eigen::Isometry3d& pose) {
  const QuaternionPose q = QuaternionPose::FromIsometry(pose);
  return {{"translation_mm", Vec(q.translation_mm)},
          {"rotation_wxyz", {q.rotation.w(), q.rotation.x(), q.rotation.y(), q.rotation.z()}}};
}

// The frames must not already be joined by other edges (the tree would get a cycle).
void CheckEdgeFits(const FrameGraph& graph, const std::string& frame, const std::string& cell) {
  if (!graph.HasFrame("handling_base") || !graph.HasFrame(frame)) return;
  for (const StaticEdge& e : graph.static_edges()) {
    if ((e.parent == "handling_base" && e.child == frame) ||
        (e.child == "handling_base" && e.parent == frame)) {
      return;  // our own edge: replaced
    }
  }
  if (graph.Connected("handling_base", frame)) {
    throw InputError(cell + ": handling_base and '" + frame +
                     "' are already connected through other edges (e.g. a hand-eye edge); the "
                     "half-sphere calibration holds only for the sweep it used: pass "
                     "--sweep-frame NAME to store it as a frame of its own (e.g. sweep_start)");
  }
}

nlohmann::json ResultJson(const SpheresArgs& a, const calib::HalfSphereCalibrationResult& r,
                          const calib::SphereSegmentationResult& seg, double touch_sigma,
                          const Eigen::Vector3d& up, const StaticEdge& edge) {
  nlohmann::json j;
  j["format"] = kJsonFormat;
  j["version"] = kJsonVersion;
  j["edge"] = {{"parent", "handling_base"}, {"child", a.sweep_frame}};
  j["handling_base_from_" + a.sweep_frame] = PoseJson(r.handling_base_from_sweep);
  j["pose"] = PoseJson(r.handling_base_from_sweep);
  j["sigma"] = {{"rotation_deg", Vec(r.fit.RotationSigmaDeg())},
                {"translation_mm", Vec(r.fit.TranslationSigmaMm())}};
  std::vector<double> cov(r.covariance.data(), r.covariance.data() + 36);
  j["covariance"] = {{"order", "[rotation vector (rad); translation (mm)], left perturbation"},
                     {"values", cov}};
  j["rms_mm"] = r.fit.rms_mm;
  j["chi2"] = r.fit.chi2;
  j["dof"] = r.fit.dof;
  j["match_rms_mm"] = r.match_rms_mm;
  j["runner_up_match_rms_mm"] = r.runner_up_match_rms_mm;
  j["touch_sigma_mm"] = touch_sigma;
  j["up_in_handling_base"] = Vec(up);
  j["inputs"] = {{"cell", a.cell}, {"sweep", a.sweep}, {"touches", a.touches},
                 {"digest", edge.provenance.input_digest}};
  j["spheres"] = nlohmann::json::array();
  for (const auto& s : r.spheres) {
    const calib::SphereFitResult& f = seg.spheres[s.swept].fit;
    const Eigen::Vector3d cs = f.CenterCovariance().diagonal().cwiseMax(0.0).cwiseSqrt();
    j["spheres"].push_back(
        {{"sphere", s.sphere},
         {"center_in_sweep", Vec(s.center_in_sweep)},
         {"center_sigma_mm", Vec(cs)},
         {"center_in_handling_base", Vec(s.center_in_handling_base)},
         {"residual_mm", Vec(s.residual_mm)},
         {"residual_norm_mm", s.residual_norm_mm},
         {"mahalanobis", s.mahalanobis},
         {"radius_mm", s.radius_mm},
         {"fit", {{"points", f.num_inliers + f.num_outliers}, {"outliers", f.num_outliers},
                  {"rms_mm", f.rms_mm}, {"radius_sigma_mm", f.radius_sigma_mm},
                  {"cap_half_angle_deg", f.cap_half_angle_deg}, {"converged", f.converged}}}});
  }
  j["segmentation"] = {{"summary", seg.Summary()},
                       {"spheres", seg.spheres.size()},
                       {"rejected", nlohmann::json::array()}};
  for (const auto& c : seg.rejected) {
    j["segmentation"]["rejected"].push_back(
        {{"center", Vec(c.center)}, {"votes", c.votes}, {"reason", c.reason}});
  }
  j["warnings"] = r.warnings;
  j["summary"] = r.Summary();
  return j;
}

report::HtmlReport MakeReport(const SpheresArgs& a, const calib::HalfSphereCalibrationResult& r,
                              const calib::SphereSegmentationResult& seg, double touch_sigma,
                              const Eigen::Vector3d& up) {
  report::HtmlReport rep("lasercell calibrate spheres: handling_base_from_" + a.sweep_frame);
  rep.AddParagraph("Half-sphere calibration of the sweep frame '" + a.sweep_frame +
                   "' (for a linear sweep: the sensor at the sweep start) into the handling "
                   "robot's base, from " + std::to_string(r.spheres.size()) +
                   " spheres. Inputs: " + a.sweep + ", " + a.touches + ".");
  for (const auto& w : r.warnings) rep.AddWarning(w);
  rep.AddHeading("Result");
  const Eigen::Vector3d rs = r.fit.RotationSigmaDeg(), ts = r.fit.TranslationSigmaMm();
  rep.AddKeyValues({
      {"handling_base_from_" + a.sweep_frame, PoseToFileNotation(r.handling_base_from_sweep)},
      {"1-sigma rotation (deg, x y z)", Num(rs.x(), "%.5f") + ", " + Num(rs.y(), "%.5f") + ", " + Num(rs.z(), "%.5f")},
      {"1-sigma translation (mm, x y z)", Num(ts.x()) + ", " + Num(ts.y()) + ", " + Num(ts.z())},
      {"residual rms (mm)", Num(r.fit.rms_mm)},
      {"chi2 / dof", Num(r.fit.chi2, "%.3g") + " / " + std::to_string(r.fit.dof)},
      {"touch sigma (mm, per axis)", Num(touch_sigma)},
      {"up in handling_base", Num(up.x(), "%.3f") + ", " + Num(up.y(), "%.3f") + ", " + Num(up.z(), "%.3f")},
      {"correspondence", "rms " + Num(r.match_rms_mm) + " mm; runner-up " +
                             Num(r.runner_up_match_rms_mm, "%.3g") + " mm"},
      {"segmentation", seg.Summary()},
  });
  rep.AddHeading("Per-sphere residuals (touched centre - mapped swept centre, handling_base)");
  std::vector<std::vector<std::string>> rows;
  std::vector<std::string> labels;
  std::vector<double> norms;
  for (const auto& s : r.spheres) {
    const auto& f = seg.spheres[s.swept].fit;
    rows.push_back({std::to_string(s.sphere), Num(s.residual_mm.x()), Num(s.residual_mm.y()),
                    Num(s.residual_mm.z()), Num(s.residual_norm_mm), Num(s.mahalanobis, "%.2f"),
                    std::to_string(f.num_inliers), std::to_string(f.num_outliers),
                    Num(f.rms_mm), Num(f.cap_half_angle_deg, "%.1f")});
    labels.push_back("sphere " + std::to_string(s.sphere));
    norms.push_back(s.residual_norm_mm);
  }
  rep.AddTable({"sphere", "dx (mm)", "dy (mm)", "dz (mm)", "|d| (mm)", "Mahalanobis",
                "fit points", "fit outliers", "fit rms (mm)", "cap half-angle (deg)"},
               rows);
  rep.AddBars("Residual per sphere", labels, norms, "|residual| (mm)");
  rep.AddHeading("Sphere fit residuals");
  for (const auto& s : r.spheres) {
    const auto& f = seg.spheres[s.swept].fit;
    std::vector<double> inliers;
    for (std::size_t i = 0; i < f.residuals_mm.size(); ++i) {
      if (!f.outlier[i]) inliers.push_back(f.residuals_mm[i]);
    }
    rep.AddHistogram("Sphere " + std::to_string(s.sphere) + " point-to-sphere residuals (" +
                         std::to_string(inliers.size()) + " inliers)",
                     inliers, "residual (mm)");
  }
  rep.AddHeading("Covariance of [rotation vector; translation] (left perturbation)");
  std::vector<std::vector<std::string>> cov_rows;
  const char* names[6] = {"rx (rad)", "ry (rad)", "rz (rad)", "tx (mm)", "ty (mm)", "tz (mm)"};
  for (int i = 0; i < 6; ++i) {
    std::vector<std::string> row = {names[i]};
    for (int k = 0; k < 6; ++k) row.push_back(Num(r.covariance(i, k), "%.3g"));
    cov_rows.push_back(row);
  }
  rep.AddTable({"", "rx", "ry", "rz", "tx", "ty", "tz"}, cov_rows);
  if (!seg.rejected.empty()) {
    rep.AddHeading("Rejected sphere candidates");
    std::vector<std::vector<std::string>> rej;
    for (const auto& c : seg.rejected) {
      rej.push_back({Num(c.center.x(), "%.1f") + ", " + Num(c.center.y(), "%.1f") + ", " +
                         Num(c.center.z(), "%.1f"),
                     std::to_string(c.votes), c.reason});
    }
    rep.AddTable({"centre (mm, sweep frame)", "votes", "reason"}, rej);
  }
  return rep;
}

void Run(const SpheresArgs& a) {
  FrameGraph graph = LoadFrameGraph(a.cell);
  FrameGraph().AddFrame(a.sweep_frame);  // throws for a name that is not lower snake case
  CheckEdgeFits(graph, a.sweep_frame, a.cell);
  const std::string touches_text = io::ReadFileBytes(a.touches);
  const calib::SphereTouches touches = calib::ParseTouchesYaml(touches_text, a.touches);
  double radius = a.radius_mm;
  if (radius <= 0) {
    if (!touches.sphere_radius_mm) {
      throw InputError(a.touches + ": no sphere_radius_mm; give --radius-mm R");
    }
    radius = *touches.sphere_radius_mm;
  }
  const double touch_sigma = a.touch_sigma_mm > 0 ? a.touch_sigma_mm : touches.stated_sigma_mm;
  if (a.up.size() != 3) throw InputError("--up: expected X,Y,Z");
  const Eigen::Vector3d up(a.up[0], a.up[1], a.up[2]);

  io::ReadReport read;
  const PointCloud sweep = io::ReadPointCloud(a.sweep, &read);
  calib::SphereSegmentationOptions seg_options;
  seg_options.radius_mm = radius;
  seg_options.fix_radius = !a.free_radius;
  const calib::SphereSegmentationResult seg = calib::SegmentSpheres(sweep, seg_options);
  if (seg.spheres.empty()) {
    std::string why = "no sphere of radius " + Num(radius, "%g") + " mm found (" + seg.Summary() +
                      ")";
    if (!read.unit_hint.empty()) why += "; " + read.unit_hint;
    if (!seg.rejected.empty()) why += "; strongest candidate rejected: " + seg.rejected[0].reason;
    throw FileError(a.sweep, why);
  }
  calib::HalfSphereCalibrationOptions options;
  options.up_in_handling_base = up;
  options.touch_sigma_mm = touch_sigma;
  calib::HalfSphereCalibrationResult result;
  try {
    result = calib::CalibrateHalfSpheres(calib::SweptSpheresFrom(seg), touches.touches, options);
  } catch (const OptionError&) {
    throw;
  } catch (const InputError& e) {
    throw InputError(a.sweep + " + " + a.touches + ": " + e.what());
  }

  // Warnings of the matched spheres' fits (small caps, correlated noise) join the result's.
  for (const auto& s : result.spheres) {
    for (const auto& w : seg.spheres[s.swept].fit.warnings) {
      result.warnings.push_back("sphere " + std::to_string(s.sphere) + ": " + w);
    }
  }
  EdgeProvenance provenance;
  provenance.tool = std::string("lasercell calibrate spheres ") + LASERCELL_VERSION;
  provenance.date = UtcNow();
  provenance.input_digest = Digest({io::ReadFileBytes(a.sweep), touches_text});
  provenance.residual_summary = "rms " + Num(result.fit.rms_mm) + " mm over " +
                                std::to_string(result.spheres.size()) + " spheres, chi2/dof " +
                                Num(result.fit.chi2, "%.3g") + "/" +
                                std::to_string(result.fit.dof);
  const StaticEdge edge = calib::HalfSphereEdge(result, a.sweep_frame, provenance);

  if (!a.json.empty()) {
    io::WriteFileAtomically(
        a.json, ResultJson(a, result, seg, touch_sigma, up.normalized(), edge).dump(2) + "\n");
  }
  if (!a.report.empty()) {
    report::WriteHtmlReport(a.report, MakeReport(a, result, seg, touch_sigma, up.normalized()));
  }
  graph.SetStaticEdge(edge);
  SaveFrameGraph(a.cell, graph);
  std::printf("%s\nhandling_base_from_%s: %s\n", result.Summary().c_str(), a.sweep_frame.c_str(),
              PoseToFileNotation(result.handling_base_from_sweep).c_str());
  for (const auto& w : result.warnings) std::printf("warning: %s\n", w.c_str());
}

}  // namespace

void AddCalibrateSpheresCommand(CLI::App& calibrate) {
  CLI::App* cmd = calibrate.add_subcommand(
      "spheres",
      "Half spheres: sweep + handling-robot touches of their tops -> handling_base <- sweep "
      "frame in CELL.yaml");
  auto a = std::make_shared<SpheresArgs>();
  cmd->add_option("--cell", a->cell, "cell.yaml to update (only its handling_base edge)")
      ->required();
  cmd->add_option("--sweep", a->sweep, "Sweep cloud (PLY/PCD, mm) in the sweep frame")->required();
  cmd->add_option("--touches", a->touches, "Touches file (format lasercell.touches)")->required();
  cmd->add_option("--radius-mm", a->radius_mm,
                  "Sphere radius (default: the touches file's sphere_radius_mm)");
  cmd->add_flag("--free-radius", a->free_radius,
                "Fit each sphere's radius instead of fixing it to the nominal radius");
  cmd->add_option("--sweep-frame", a->sweep_frame,
                  "Frame of the sweep cloud (default sensor: the sensor at the start of a "
                  "linear sweep)");
  cmd->add_option("--touch-sigma-mm", a->touch_sigma_mm,
                  "Per-axis 1-sigma of a touch (default: the file's stated_sigma_mm)");
  cmd->add_option("--up", a->up, "Up (against gravity) in handling_base, X,Y,Z (default 0,0,1)")
      ->delimiter(',')
      ->expected(3);
  cmd->add_option("--report", a->report, "HTML report to write");
  cmd->add_option("--json", a->json, "JSON result to write");
  cmd->callback([a] { Run(*a); });
}

}  // namespace lasercell::tools
