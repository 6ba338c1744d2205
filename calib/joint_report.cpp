#include "calib/joint_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <vector>

#include "core/frame_graph.hpp"
#include "core/json_io.hpp"
#include "core/se3.hpp"

namespace lasercell::calib {

namespace {

using report::HtmlReport;
constexpr double kRadToDeg = 180.0 / std::numbers::pi;

nlohmann::json ObservabilityJson(const ObservabilityReport& o) {
  nlohmann::json dirs = nlohmann::json::array();
  for (const UnidentifiableDirection& d : o.directions) {
    dirs.push_back({{"parameters", d.parameters},
                    {"null_vector_components", d.components},
                    {"relative_singular_value", d.relative_singular_value},
                    {"action", d.fixed_parameter.empty()
                                   ? "none (degenerate)"
                                   : "fixed " + d.fixed_parameter + " at its input value"}});
  }
  std::vector<double> sv(o.singular_values.data(),
                         o.singular_values.data() + o.singular_values.size());
  return {{"column_scaled", true},
          {"singular_values", sv},
          {"condition_number", o.condition_number},
          {"unidentifiable", dirs}};
}

// Predicted 1-sigma of the working point in the base (calib/robot_positioning.hpp).
nlohmann::json PositioningJson(const PositioningUncertainty& u, const char* includes) {
  return {{"rms", u.rms_mm},
          {"max", u.max_mm},
          {"poses", u.poses},
          {"point", "centroid of each sweep's laser points, middle profile's joints"},
          {"includes", includes}};
}

nlohmann::json SweepsJson(const std::vector<SweepResidual>& sweeps) {
  nlohmann::json out = nlohmann::json::array();
  for (const SweepResidual& s : sweeps) {
    out.push_back({{"name", s.name},
                   {"sphere", s.sphere},
                   {"points", s.points},
                   {"rms_mm", s.rms_mm},
                   {"mean_mm", s.mean_mm},
                   {"max_abs_mm", s.max_abs_mm}});
  }
  return out;
}

nlohmann::json SpheresJson(const std::vector<Eigen::Vector3d>& c,
                           const std::vector<Eigen::Vector3d>& s) {
  nlohmann::json out = nlohmann::json::array();
  for (std::size_t i = 0; i < c.size(); ++i) {
    out.push_back({{"sphere", i},
                   {"centre_in_base_mm", json::Vector(c[i])},
                   {"sigma_mm", json::Vector(s[i])}});
  }
  return out;
}

nlohmann::json OffsetsJson(const JointIdentificationResult& r) {
  const std::vector<double> values = DhParameterVector(r.robot);
  nlohmann::json offsets = nlohmann::json::array();
  for (std::size_t k = 0; k < 6 && k < r.parameter_names.size(); ++k) {
    offsets.push_back({{"joint", k + 1},
                       {"offset_deg", values[k] * kRadToDeg},
                       {"sigma_deg", r.parameter_sigmas[k] * kRadToDeg},
                       {"correction_deg", r.parameter_corrections[k] * kRadToDeg},
                       {"estimated", static_cast<bool>(r.parameter_estimated[k])}});
  }
  return offsets;
}

// a, d (mm) and alpha (rad -> deg) of every joint: DhParameterVector order after the offsets.
nlohmann::json DhJson(const JointIdentificationResult& r) {
  const std::vector<double> values = DhParameterVector(r.robot);
  nlohmann::json dh = nlohmann::json::array();
  for (std::size_t k = 6; k < r.parameter_names.size(); ++k) {
    const bool angle = k >= 18;
    const double unit = angle ? kRadToDeg : 1.0;
    dh.push_back({{"parameter", r.parameter_names[k]},
                  {"unit", angle ? "deg" : "mm"},
                  {"value", values[k] * unit},
                  {"correction", r.parameter_corrections[k] * unit},
                  {"sigma", r.parameter_sigmas[k] * unit},
                  {"estimated", static_cast<bool>(r.parameter_estimated[k])}});
  }
  return dh;
}

std::string Fmt(const char* format, double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

/// Report plots shared by both calibrations: per-sweep errors, residual histogram, singular
/// values.
void AddCommonReport(HtmlReport& report, const std::vector<SweepResidual>& sweeps,
                     const std::vector<double>& residuals, const ObservabilityReport& obs) {
  report.AddHeading("Per-pose errors");
  std::vector<std::string> labels;
  std::vector<double> rms, mean;
  std::vector<std::vector<std::string>> rows;
  for (const SweepResidual& s : sweeps) {
    labels.push_back(std::filesystem::path(s.name).stem().string());
    rms.push_back(s.rms_mm);
    mean.push_back(s.mean_mm);
    rows.push_back({s.name, std::to_string(s.sphere), std::to_string(s.points),
                    Fmt("%.4f", s.rms_mm), Fmt("%.4f", s.mean_mm), Fmt("%.4f", s.max_abs_mm)});
  }
  report.AddBars("RMS point-to-sphere distance per pose", labels, rms, "rms (mm)");
  report.AddBars("Mean signed distance per pose: a pose error shows as a bias", labels, mean,
                 "mean (mm)");
  report.AddTable({"sweep", "sphere", "points", "rms (mm)", "mean (mm)", "max |r| (mm)"}, rows);
  report.AddHeading("Residuals");
  report.AddHistogram("Point-to-sphere distances", residuals, "signed distance (mm)", 40);
  report.AddHeading("Observability");
  report.AddParagraph(obs.Summary());
  std::vector<std::string> idx;
  std::vector<double> logsv;
  for (Eigen::Index i = 0; i < obs.singular_values.size(); ++i) {
    idx.push_back(std::to_string(i + 1));
    logsv.push_back(std::log10(std::max(1e-300, obs.singular_values[i])));
  }
  report.AddBars("Singular values of the column-scaled identification Jacobian", idx, logsv,
                 "log10 singular value");
  for (const UnidentifiableDirection& d : obs.directions) {
    std::string names;
    for (const std::string& n : d.parameters) names += (names.empty() ? "" : ", ") + n;
    report.AddWarning("not identifiable from these poses: " + names +
                      (d.fixed_parameter.empty()
                           ? ""
                           : " -> fixed " + d.fixed_parameter + " at its input value"));
  }
}

/// Correlation table of a covariance (sigma on the diagonal).
void AddCorrelation(HtmlReport& report, const Eigen::MatrixXd& cov,
                    const std::vector<std::string>& names, const std::string& title) {
  report.AddHeading(title);
  std::vector<std::string> header = {""};
  for (const std::string& n : names) header.push_back(n);
  std::vector<std::vector<std::string>> rows;
  for (Eigen::Index i = 0; i < cov.rows(); ++i) {
    std::vector<std::string> row = {names[static_cast<std::size_t>(i)]};
    for (Eigen::Index j = 0; j < cov.cols(); ++j) {
      row.push_back(i == j ? Fmt("σ %.3g", std::sqrt(cov(i, i)))
                           : Fmt("%.2f", cov(i, j) / std::sqrt(cov(i, i) * cov(j, j))));
    }
    rows.push_back(std::move(row));
  }
  report.AddTable(header, rows);
}

std::string SweepsLine(const SphereSweepRun& run) {
  return run.sweeps_path + " (" + run.sweep_set + ", " + std::to_string(run.sweep_count) + ")";
}

}  // namespace

nlohmann::json JointCalibrationJson(const JointIdentificationResult& r, const SphereSweepRun& run) {
  nlohmann::json j = {
      {"format", "lasercell.joint_calibration"},
      {"version", 1},
      {"robot", run.robot},
      {"sweep_set", run.sweep_set},
      {"sphere_centres", run.touches_path.empty() ? "free" : "from touches " + run.touches_path},
      {"converged", r.converged},
      {"termination", r.termination},
      {"iterations", r.iterations},
      {"residual_rms_mm", r.rms_mm},
      {"points_used", r.points_used},
      {"points_rejected", r.points_rejected},
      {"variance_factor", r.variance_factor},
      {"sweep_bias_ratio", r.sweep_bias_ratio},
      {"positioning_sigma_mm",
       PositioningJson(r.positioning, run.with_hand_eye ? "robot parameters and hand-eye"
                                                        : "robot parameters (hand-eye held)")},
      {"joint_offsets", OffsetsJson(r)},
      {"radius_mm", r.radius_mm},
      {"radius_sigma_mm", r.radius_sigma_mm},
      {"spheres", SpheresJson(r.sphere_centres_in_base, r.sphere_centre_sigmas)},
      {"sweeps", SweepsJson(r.sweeps)},
      {"observability", ObservabilityJson(r.observability)},
      {"covariance",
       {{"parameters", r.covariance_names},
        {"matrix", json::Rows(r.covariance)},
        {"units", "rad for angles, mm for lengths"}}},
      {"warnings", r.warnings}};
  if (run.dh_deltas) j["dh_parameters"] = DhJson(r);
  if (run.with_hand_eye && r.flange_from_sensor_covariance) {
    j["vision_flange_from_sensor"] = json::Pose(r.flange_from_sensor);
    j["vision_flange_from_sensor_covariance"] = json::Covariance(*r.flange_from_sensor_covariance);
  }
  return j;
}

report::HtmlReport JointCalibrationReport(const JointIdentificationResult& r,
                                          const SphereSweepRun& run) {
  HtmlReport report("lasercell calibrate joints: " + run.robot);
  report.AddKeyValues({{"result", r.Summary()},
                       {"sweeps", SweepsLine(run)},
                       {"hand-eye", run.with_hand_eye ? "estimated" : "held (from the cell)"},
                       {"DH deltas", run.dh_deltas ? "estimated" : "not estimated"}});
  for (const std::string& w : r.warnings) report.AddWarning(w);
  std::vector<std::vector<std::string>> rows;
  for (int k = 0; k < 6; ++k) {
    rows.push_back({std::to_string(k + 1),
                    Fmt("%.5f", r.robot.joints()[k].joint_offset_rad * kRadToDeg),
                    Fmt("%.5f", r.parameter_sigmas[k] * kRadToDeg),
                    Fmt("%.5f", r.parameter_corrections[k] * kRadToDeg),
                    r.parameter_estimated[k] ? "estimated" : "fixed (not identifiable)"});
  }
  report.AddHeading("Joint offsets");
  report.AddTable({"joint", "offset (deg)", "1σ (deg)", "correction (deg)", "status"}, rows);
  AddCommonReport(report, r.sweeps, r.residuals_mm, r.observability);
  AddCorrelation(report, r.covariance, r.covariance_names,
                 "Covariance (σ on the diagonal, correlations off it)");
  return report;
}

nlohmann::json LaserHandEyeJson(const LaserHandEyeResult& r, const SphereSweepRun& run) {
  return {{"format", "lasercell.laser_hand_eye"},
          {"version", 1},
          {"robot", run.robot},
          {"sweep_set", run.sweep_set},
          {"converged", r.converged},
          {"vision_flange_from_sensor", json::Pose(r.flange_from_sensor)},
          {"covariance", json::Covariance(r.covariance)},
          {"residual_rms_mm", r.rms_mm},
          {"points_used", r.points_used},
          {"positioning_sigma_mm", PositioningJson(r.positioning, "hand-eye only (robot held)")},
          {"radius_mm", r.radius_mm},
          {"radius_sigma_mm", r.radius_sigma_mm},
          {"spheres", SpheresJson(r.sphere_centres_in_base, r.sphere_centre_sigmas)},
          {"sweeps", SweepsJson(r.sweeps)},
          {"observability", ObservabilityJson(r.observability)},
          {"warnings", r.warnings}};
}

report::HtmlReport LaserHandEyeReport(const LaserHandEyeResult& r, const SphereSweepRun& run) {
  HtmlReport report("lasercell calibrate handeye-laser");
  report.AddKeyValues({{"result", r.Summary()},
                       {"vision_flange_from_sensor", PoseToFileNotation(r.flange_from_sensor)},
                       {"sweeps", SweepsLine(run)}});
  for (const std::string& w : r.warnings) report.AddWarning(w);
  AddCommonReport(report, r.sweeps, r.residuals_mm, r.observability);
  AddCorrelation(report, r.covariance, {"rx", "ry", "rz", "tx", "ty", "tz"},
                 "Hand-eye covariance (rad, mm; σ on the diagonal, correlations off it)");
  return report;
}

}  // namespace lasercell::calib
