#include "calib/sphere_section_report.hpp"

#include <cmath>

#include "core/format.hpp"
#include "core/frame_graph.hpp"
#include "core/json_io.hpp"

namespace lasercell::calib {
namespace {

nlohmann::json SectionJson(const SphereSection& s) {
  nlohmann::json j = {{"name", s.name}, {"used", s.used}};
  if (!s.used) j["why_not"] = s.why_not;
  if (s.circle.success) {
    j["circle"] = {{"centre_xz_mm", {s.circle.centre.x(), s.circle.centre.y()}},
                   {"radius_mm", s.circle.radius_mm},
                   {"radius_sigma_mm", std::sqrt(std::max(s.circle.covariance(2, 2), 0.0))},
                   {"rms_mm", s.circle.rms_mm},
                   {"inliers", s.circle.inliers},
                   {"outliers", s.circle.outliers},
                   {"arc_deg", s.circle.arc_deg}};
  }
  if (s.used) {
    j["centre_in_sensor_mm"] = json::Vector(s.centre_in_sensor);
    j["centre_in_base_mm"] = json::Vector(s.centre_in_base);
    j["distance_mm"] = s.distance_mm;
    j["leave_one_out"] = {
        {"distance_mm", json::FiniteOrNull(s.loo_distance_mm)},
        {"translation_change_mm", json::FiniteOrNull(s.loo_translation_change_mm)},
        {"rotation_change_deg", json::FiniteOrNull(s.loo_rotation_change_deg)}};
  }
  return j;
}

}  // namespace

nlohmann::json SphereSectionHandEyeJson(const SphereSectionHandEyeResult& r,
                                        const SphereSectionRun& run) {
  nlohmann::json sections = nlohmann::json::array();
  for (const SphereSection& s : r.sections) sections.push_back(SectionJson(s));
  return {{"format", "lasercell.laser_hand_eye_sections"},
          {"version", 1},
          {"inputs",
           {{"poses", run.poses_path},
            {"pose_format", run.pose_format},
            {"profiles", run.profile_paths},
            {"sphere_radius_mm", run.options.sphere_radius_mm},
            {"estimate_radius", run.options.estimate_radius},
            {"sphere_side", run.options.sphere_side > 0 ? "+y" : "-y"}}},
          {"converged", r.converged},
          {"iterations", r.iterations},
          {"flange_from_sensor", json::Pose(r.flange_from_sensor)},
          {"covariance", json::Covariance(r.covariance)},
          {"sphere",
           {{"centre_in_base_mm", json::Vector(r.sphere_centre_in_base)},
            {"centre_sigma_mm", json::Vector(r.sphere_centre_covariance.diagonal().cwiseSqrt())},
            {"radius_mm", r.radius_mm},
            {"radius_sigma_mm", r.radius_sigma_mm}}},
          {"sections_used", r.sections_used},
          {"centre_spread_mm", {{"rms", r.spread_rms_mm}, {"max", r.spread_max_mm}}},
          {"leave_one_out",
           {{"rms_mm", json::FiniteOrNull(r.loo_rms_mm)},
            {"max_mm", json::FiniteOrNull(r.loo_max_mm)},
            {"translation_change_max_mm", json::FiniteOrNull(r.loo_translation_change_max_mm)},
            {"rotation_change_max_deg", json::FiniteOrNull(r.loo_rotation_change_max_deg)}}},
          {"rotation_span_deg", r.rotation_span_deg},
          {"sections", sections},
          {"warnings", r.warnings}};
}

report::HtmlReport SphereSectionHandEyeReport(const SphereSectionHandEyeResult& r,
                                              const SphereSectionRun& run) {
  report::HtmlReport report("lasercell calibrate handeye-laser (sphere sections)");
  report.AddKeyValues({{"result", r.Summary()},
                       {"flange_from_sensor", PoseToFileNotation(r.flange_from_sensor)},
                       {"poses", run.poses_path + " (" + run.pose_format + ")"},
                       {"rotation span", FormatFixed(r.rotation_span_deg, 1) + " deg"}});
  for (const std::string& w : r.warnings) report.AddWarning(w);
  report.AddParagraph(
      "Each profile's circle, lifted off the laser plane to the sphere centre and mapped into "
      "the robot base: with a perfect calibration and robot every centre would fall on one "
      "point. Distance = from the fitted sphere centre; leave-one-out = the same distance "
      "predicted by the calibration of the other poses.");
  std::vector<std::vector<std::string>> rows;
  std::vector<std::string> labels;
  std::vector<double> distances;
  for (const SphereSection& s : r.sections) {
    const bool fit = s.circle.success;
    rows.push_back(
        {s.name, s.used ? "yes" : "no: " + s.why_not,
         fit ? FormatFixed(s.circle.radius_mm, 3) : "-",
         fit ? FormatFixed(s.circle.rms_mm, 4) : "-", fit ? FormatFixed(s.circle.arc_deg, 1) : "-",
         s.used ? FormatFixed(s.distance_mm, 3) : "-",
         s.used && std::isfinite(s.loo_distance_mm) ? FormatFixed(s.loo_distance_mm, 3) : "-"});
    if (s.used) {
      labels.push_back(s.name.substr(s.name.find_last_of('/') + 1));
      distances.push_back(s.distance_mm);
    }
  }
  report.AddTable({"profile", "used", "section radius mm", "circle rms mm", "arc deg",
                   "centre distance mm", "leave-one-out mm"},
                  rows);
  report.AddBars("Sphere centre distance per profile", labels, distances, "mm");
  return report;
}

}  // namespace lasercell::calib
