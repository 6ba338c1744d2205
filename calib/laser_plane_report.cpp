#include "calib/laser_plane_report.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <vector>

#include "core/format.hpp"
#include "core/json_io.hpp"

namespace lasercell::calib {

namespace {

nlohmann::json Number(double v) { return json::FiniteOrNull(v); }

}  // namespace

nlohmann::json LaserPlaneJson(const LaserPlaneResult& r, const std::string& camera) {
  nlohmann::json j;
  j["format"] = "lasercell.laser_plane";
  j["version"] = 1;
  j["method"] = r.method;
  j["frame"] = "sensor";
  j["camera"] = camera;
  j["plane"] = {{"normal", {r.normal.x(), r.normal.y(), r.normal.z()}},
                {"offset_mm", r.offset_mm},
                {"point_mm", {r.point_mm.x(), r.point_mm.y(), r.point_mm.z()}},
                {"equation", "normal . p + offset_mm = 0, p in the sensor frame (mm)"}};
  nlohmann::json cov = nlohmann::json::array();
  for (int a = 0; a < 4; ++a) {
    nlohmann::json row = nlohmann::json::array();
    for (int b = 0; b < 4; ++b) row.push_back(Number(r.covariance(a, b)));
    cov.push_back(row);
  }
  j["covariance_n_d"] = cov;
  j["normal_sigma_deg"] = Number(r.normal_sigma_deg);
  j["offset_sigma_mm"] = Number(r.offset_sigma_mm);
  j["camera_uncertainty_included"] = r.camera_uncertainty_included;
  if (r.camera_uncertainty_included) {
    j["camera_normal_sigma_deg"] = Number(r.camera_normal_sigma_deg);
    j["camera_offset_sigma_mm"] = Number(r.camera_offset_sigma_mm);
  } else {
    j["camera_uncertainty_note"] = r.camera_uncertainty_note;
  }
  j["rms_mm"] = Number(r.rms_mm);
  if (r.method == "heights") j["rms_px"] = Number(r.rms_px);
  j["points"] = r.points;
  j["converged"] = r.converged;
  j["iterations"] = r.iterations;
  j["median_triangulation_angle_deg"] = Number(r.median_triangulation_angle_deg);
  j["ill_conditioned"] = r.ill_conditioned;
  if (r.zero_distance_mm) {
    j["plate_zero_distance_mm"] = Number(*r.zero_distance_mm);
    j["plate_zero_distance_sigma_mm"] = Number(r.zero_distance_sigma_mm);
    j["plate_tilt_deg"] = Number(r.plate_tilt_deg);
    j["plate_tilt_sigma_deg"] = Number(r.plate_tilt_sigma_deg);
  }
  j["leave_one_out"] = {{"max_normal_change_deg", Number(r.loo_max_normal_change_deg)},
                        {"max_offset_change_mm", Number(r.loo_max_offset_change_mm)}};
  nlohmann::json items = nlohmann::json::array();
  for (const auto& it : r.items) {
    nlohmann::json e = {{"name", it.name},
                        {"used", it.used},
                        {"note", it.note},
                        {"points", it.points},
                        {"rms_mm", Number(it.rms_mm)}};
    if (r.method == "heights") {
      e["height_mm"] = it.height_mm;
      e["rms_px"] = Number(it.rms_px);
    } else {
      e["corner_reprojection_rms_px"] = Number(it.reprojection_rms_px);
      e["scan"] = it.scan_along_rows ? "rows" : "columns";
    }
    e["leave_one_out"] = {{"normal_change_deg", Number(it.loo_normal_change_deg)},
                          {"offset_change_mm", Number(it.loo_offset_change_mm)},
                          {"max_displacement_mm", Number(it.loo_max_displacement_mm)}};
    if (r.method == "heights")
      e["leave_one_out"]["plate_distance_held"] = it.loo_zero_distance_held;
    items.push_back(e);
  }
  j[r.method == "heights" ? "heights" : "images"] = items;
  j["warnings"] = r.warnings;
  return j;
}

report::HtmlReport LaserPlaneReport(const LaserPlaneResult& r, const CameraModel& camera) {
  report::HtmlReport page("Laser plane calibration (" + r.method + ")");
  page.AddHeading("Result");
  for (const auto& w : r.warnings) page.AddWarning(w);
  page.AddKeyValues({
      {"method", r.method == "heights" ? "white plane at known heights"
                                       : "laser stripe on a chessboard (Zhou & Zhang 2005)"},
      {"plane (sensor frame)", "n = [" + FormatSignificant(r.normal.x(), 9) + ", " +
                                   FormatSignificant(r.normal.y(), 9) + ", " +
                                   FormatSignificant(r.normal.z(), 9) +
                                   "], d = " + FormatSignificant(r.offset_mm, 9) + " mm"},
      {"p0 (nearest the sensor origin)", "[" + FormatSignificant(r.point_mm.x(), 7) + ", " +
                                             FormatSignificant(r.point_mm.y(), 7) + ", " +
                                             FormatSignificant(r.point_mm.z(), 7) + "] mm"},
      {"1 sigma normal / offset", FormatSignificant(r.normal_sigma_deg, 3) + " deg / " +
                                      FormatSignificant(r.offset_sigma_mm, 3) + " mm"},
      {"of it the camera's uncertainty",
       r.camera_uncertainty_included ? FormatSignificant(r.camera_normal_sigma_deg, 3) + " deg / " +
                                           FormatSignificant(r.camera_offset_sigma_mm, 3) + " mm"
                                     : r.camera_uncertainty_note},
      {"RMS residual",
       FormatSignificant(r.rms_mm, 4) + " mm" +
           (r.method == "heights" ? " (" + FormatSignificant(r.rms_px, 3) + " px of peak row)"
                                  : "")},
      {"points", std::to_string(r.points)},
      {"median ray-to-plane angle",
       FormatSignificant(r.median_triangulation_angle_deg, 4) + " deg"},
      {"leave-one-out: max normal / offset change",
       FormatSignificant(r.loo_max_normal_change_deg, 3) + " deg / " +
           FormatSignificant(r.loo_max_offset_change_mm, 3) + " mm"},
      {"converged", r.converged ? "yes (" + std::to_string(r.iterations) + " iterations)"
                                : "NO: " + r.termination},
  });
  if (r.zero_distance_mm) {
    page.AddParagraph("Distance from the sensor origin to the height-0 plate: " +
                      FormatSignificant(*r.zero_distance_mm, 8) + " mm (1 sigma " +
                      FormatSignificant(r.zero_distance_sigma_mm, 3) +
                      " mm). Plate normal tilted from the given one towards the laser line by " +
                      FormatSignificant(r.plate_tilt_deg, 4) + " deg (1 sigma " +
                      FormatSignificant(r.plate_tilt_sigma_deg, 3) + " deg).");
  }
  const bool heights = r.method == "heights";
  page.AddHeading(heights ? "Per height" : "Per image");
  std::vector<std::vector<std::string>> rows;
  std::vector<std::string> labels;
  std::vector<double> rms;
  for (const auto& it : r.items) {
    rows.push_back({it.name, it.used ? "yes" : "no",
                    heights ? FormatSignificant(it.height_mm, 4)
                            : FormatSignificant(it.reprojection_rms_px, 3),
                    std::to_string(it.points), FormatSignificant(it.rms_mm, 4),
                    FormatSignificant(it.loo_normal_change_deg, 3),
                    FormatSignificant(it.loo_offset_change_mm, 3),
                    FormatSignificant(it.loo_max_displacement_mm, 3), it.note});
    if (it.used) {
      labels.push_back(std::filesystem::path(it.name).filename().string());
      rms.push_back(it.rms_mm);
    }
  }
  page.AddTable({heights ? "capture" : "image", "used", heights ? "height (mm)" : "corner RMS (px)",
                 "points", "RMS (mm)", "LOO normal change (deg)", "LOO d change (mm)",
                 "LOO max displacement (mm)", "note"},
                rows);
  page.AddBars(heights ? "RMS residual per height" : "RMS residual per image", labels, rms,
               "RMS (mm)");
  page.AddHeading("Residuals");
  std::vector<double> values;
  std::map<int, report::Series> by_item, coverage;
  for (const auto& res : r.residuals) {
    values.push_back(res.residual_mm);
    auto& s = by_item[res.item];
    s.name =
        std::filesystem::path(r.items[static_cast<std::size_t>(res.item)].name).filename().string();
    s.x.push_back(heights ? res.pixel.x()
                          : (r.items[static_cast<std::size_t>(res.item)].scan_along_rows
                                 ? res.pixel.y()
                                 : res.pixel.x()));
    s.y.push_back(res.residual_mm);
    auto& c = coverage[res.item];
    c.name = s.name;
    c.x.push_back(res.pixel.x());
    c.y.push_back(res.pixel.y());
  }
  page.AddHistogram("Laser-plane residuals", values, "signed distance from the plane (mm)");
  std::vector<report::Series> along, cover;
  for (auto& [k, s] : by_item) along.push_back(s);
  for (auto& [k, s] : coverage) cover.push_back(s);
  report::PlotOptions along_options;
  along_options.x_label =
      heights ? "image column (px)"
              : "position along the stripe: column, or row for vertical stripes (px)";
  along_options.y_label = "residual (mm)";
  page.AddScatter("Residual along the laser line", along, along_options);
  report::PlotOptions cover_options;
  cover_options.x_label = "column (px)";
  cover_options.y_label = "row (px)";
  cover_options.equal_aspect = true;
  cover_options.y_down = true;
  cover_options.range = {0, static_cast<double>(camera.width_px() - 1), 0,
                         static_cast<double>(camera.height_px() - 1)};
  page.AddScatter("Stripe coverage of the image", cover, cover_options);
  return page;
}

LaserPlaneEntry LaserPlaneCellEntry(const LaserPlaneResult& result, EdgeProvenance provenance) {
  LaserPlaneEntry entry;
  entry.frame = "sensor";
  entry.normal = result.normal;
  entry.point_mm = result.point_mm;
  entry.covariance = result.covariance;
  if (result.camera_uncertainty_included) entry.camera_covariance = result.camera_covariance;
  entry.error_modes = result.error_modes;
  provenance.residual_summary = result.method + ": rms " + FormatSignificant(result.rms_mm, 3) +
                                " mm over " + std::to_string(result.points) + " points, 1-sigma " +
                                FormatSignificant(result.normal_sigma_deg, 3) + " deg / " +
                                FormatSignificant(result.offset_sigma_mm, 3) + " mm";
  entry.provenance = std::move(provenance);
  return entry;
}

}  // namespace lasercell::calib
