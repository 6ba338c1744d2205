#include "calib/half_sphere_report.hpp"

#include <cstdio>
#include <vector>

#include "core/json_io.hpp"
#include "core/pose_covariance.hpp"

namespace lasercell::calib {
namespace {

constexpr const char* kJsonFormat = "lasercell.calibration_spheres";
constexpr int kJsonVersion = 1;

std::string Num(double v, const char* format = "%.4f") {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

nlohmann::json SphereJson(const HalfSphereResidual& s, const SphereFitResult& f) {
  const Eigen::Vector3d cs = f.CenterCovariance().diagonal().cwiseMax(0.0).cwiseSqrt();
  return {{"sphere", s.sphere},
          {"center_in_sweep", json::Vector(s.center_in_sweep)},
          {"center_sigma_mm", json::Vector(cs)},
          {"center_in_handling_base", json::Vector(s.center_in_handling_base)},
          {"residual_mm", json::Vector(s.residual_mm)},
          {"residual_norm_mm", s.residual_norm_mm},
          {"mahalanobis", s.mahalanobis},
          {"radius_mm", s.radius_mm},
          {"fit",
           {{"points", f.num_inliers + f.num_outliers},
            {"outliers", f.num_outliers},
            {"rms_mm", f.rms_mm},
            {"radius_sigma_mm", f.radius_sigma_mm},
            {"cap_half_angle_deg", f.cap_half_angle_deg},
            {"converged", f.converged}}}};
}

// Result key-values: pose, 1-sigma, residuals, the inputs that were not estimated.
void AddResultTable(report::HtmlReport& rep, const HalfSphereSweepResult& run,
                    const std::string& sweep_frame) {
  const HalfSphereCalibrationResult& r = run.calibration;
  const Eigen::Vector3d rs = RotationSigmaDeg(r.covariance), ts = TranslationSigmaMm(r.covariance);
  const Eigen::Vector3d radius_ts = TranslationSigmaMm(run.radius_covariance);
  const Eigen::Vector3d& up = run.up_in_handling_base;
  rep.AddKeyValues({
      {"handling_base_from_" + sweep_frame, PoseToFileNotation(r.handling_base_from_sweep)},
      {"1-sigma rotation (deg, x y z)",
       Num(rs.x(), "%.5f") + ", " + Num(rs.y(), "%.5f") + ", " + Num(rs.z(), "%.5f")},
      {"1-sigma translation (mm, x y z)", Num(ts.x()) + ", " + Num(ts.y()) + ", " + Num(ts.z())},
      {"residual rms (mm)", Num(r.fit.rms_mm)},
      {"chi2 / dof", Num(r.fit.chi2, "%.3g") + " / " + std::to_string(r.fit.dof)},
      {"touch sigma (mm, per axis)", Num(run.touch_sigma_mm)},
      {"sphere radius tolerance (mm, +-)",
       run.radius_tolerance_mm > 0
           ? Num(run.radius_tolerance_mm) + "; its share of the translation 1-sigma " +
                 Num(radius_ts.x()) + ", " + Num(radius_ts.y()) + ", " + Num(radius_ts.z())
           : std::string("none stated")},
      {"up in handling_base",
       Num(up.x(), "%.3f") + ", " + Num(up.y(), "%.3f") + ", " + Num(up.z(), "%.3f")},
      {"correspondence", "rms " + Num(r.match_rms_mm) + " mm; runner-up " +
                             Num(r.runner_up_match_rms_mm, "%.3g") + " mm"},
      {"segmentation", run.segmentation.Summary()},
  });
}

// Per matched sphere: residual table and bars, then each fit's residual histogram.
void AddSphereSections(report::HtmlReport& rep, const HalfSphereSweepResult& run) {
  const HalfSphereCalibrationResult& r = run.calibration;
  rep.AddHeading("Per-sphere residuals (touched centre - mapped swept centre, handling_base)");
  std::vector<std::vector<std::string>> rows;
  std::vector<std::string> labels;
  std::vector<double> norms;
  for (const auto& s : r.spheres) {
    const auto& f = run.segmentation.spheres[s.swept].fit;
    rows.push_back({std::to_string(s.sphere), Num(s.residual_mm.x()), Num(s.residual_mm.y()),
                    Num(s.residual_mm.z()), Num(s.residual_norm_mm), Num(s.mahalanobis, "%.2f"),
                    std::to_string(f.num_inliers), std::to_string(f.num_outliers), Num(f.rms_mm),
                    Num(f.cap_half_angle_deg, "%.1f")});
    labels.push_back("sphere " + std::to_string(s.sphere));
    norms.push_back(s.residual_norm_mm);
  }
  rep.AddTable({"sphere", "dx (mm)", "dy (mm)", "dz (mm)", "|d| (mm)", "Mahalanobis", "fit points",
                "fit outliers", "fit rms (mm)", "cap half-angle (deg)"},
               rows);
  rep.AddBars("Residual per sphere", labels, norms, "|residual| (mm)");
  rep.AddHeading("Sphere fit residuals");
  for (const auto& s : r.spheres) {
    const auto& f = run.segmentation.spheres[s.swept].fit;
    std::vector<double> inliers;
    for (std::size_t i = 0; i < f.residuals_mm.size(); ++i) {
      if (!f.outlier[i]) inliers.push_back(f.residuals_mm[i]);
    }
    rep.AddHistogram("Sphere " + std::to_string(s.sphere) + " point-to-sphere residuals (" +
                         std::to_string(inliers.size()) + " inliers)",
                     inliers, "residual (mm)");
  }
}

}  // namespace

nlohmann::json HalfSphereResultJson(const HalfSphereSweepResult& run,
                                    const HalfSphereInputNames& inputs, const StaticEdge& edge) {
  const HalfSphereCalibrationResult& r = run.calibration;
  const SphereSegmentationResult& seg = run.segmentation;
  nlohmann::json j;
  j["format"] = kJsonFormat;
  j["version"] = kJsonVersion;
  j["edge"] = {{"parent", "handling_base"}, {"child", inputs.sweep_frame}};
  j["handling_base_from_" + inputs.sweep_frame] = json::Pose(r.handling_base_from_sweep);
  j["pose"] = json::Pose(r.handling_base_from_sweep);
  j["sigma"] = json::Sigma(r.covariance);
  std::vector<double> cov(r.covariance.data(), r.covariance.data() + 36);
  j["covariance"] = {{"order", "[rotation vector (rad); translation (mm)], left perturbation"},
                     {"values", cov}};
  j["rms_mm"] = r.fit.rms_mm;
  j["chi2"] = r.fit.chi2;
  j["dof"] = r.fit.dof;
  j["match_rms_mm"] = r.match_rms_mm;
  j["runner_up_match_rms_mm"] = r.runner_up_match_rms_mm;
  j["touch_sigma_mm"] = run.touch_sigma_mm;
  j["radius_tolerance_mm"] = run.radius_tolerance_mm;
  j["radius_sigma"] = json::Sigma(run.radius_covariance);
  j["up_in_handling_base"] = json::Vector(run.up_in_handling_base);
  j["inputs"] = {{"cell", inputs.cell},
                 {"sweep", inputs.sweep},
                 {"touches", inputs.touches},
                 {"digest", edge.provenance.input_digest}};
  j["spheres"] = nlohmann::json::array();
  for (const auto& s : r.spheres) j["spheres"].push_back(SphereJson(s, seg.spheres[s.swept].fit));
  j["segmentation"] = {{"summary", seg.Summary()},
                       {"spheres", seg.spheres.size()},
                       {"rejected", nlohmann::json::array()}};
  for (const auto& c : seg.rejected) {
    j["segmentation"]["rejected"].push_back(
        {{"center", json::Vector(c.center)}, {"votes", c.votes}, {"reason", c.reason}});
  }
  j["warnings"] = r.warnings;
  j["summary"] = r.Summary();
  return j;
}

report::HtmlReport HalfSphereReport(const HalfSphereSweepResult& run,
                                    const HalfSphereInputNames& inputs) {
  const HalfSphereCalibrationResult& r = run.calibration;
  const SphereSegmentationResult& seg = run.segmentation;
  report::HtmlReport rep("lasercell calibrate spheres: handling_base_from_" + inputs.sweep_frame);
  rep.AddParagraph("Half-sphere calibration of the sweep frame '" + inputs.sweep_frame +
                   "' (for a linear sweep: the sensor at the sweep start) into the handling "
                   "robot's base, from " +
                   std::to_string(r.spheres.size()) + " spheres. Inputs: " + inputs.sweep + ", " +
                   inputs.touches + ".");
  for (const auto& w : r.warnings) rep.AddWarning(w);
  rep.AddHeading("Result");
  AddResultTable(rep, run, inputs.sweep_frame);
  AddSphereSections(rep, run);
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

}  // namespace lasercell::calib
