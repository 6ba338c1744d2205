#include "calib/intrinsics_report.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/format.hpp"

namespace lasercell::calib {
namespace {

std::string Sci(double v) {
  std::ostringstream s;
  s.precision(6);
  s << v;
  return s.str();
}

}  // namespace

report::HtmlReport IntrinsicsReport(const IntrinsicsResult& r, const std::string& title,
                                    const std::string& inputs) {
  report::HtmlReport page(title);
  const double w = r.camera ? r.camera->width_px() : 0;
  const double h = r.camera ? r.camera->height_px() : 0;
  int used = 0;
  for (const ViewResult& v : r.views) used += v.used ? 1 : 0;

  page.AddHeading("Summary");
  page.AddParagraph(inputs);
  page.AddKeyValues({
      {"lens model", r.camera ? r.camera->lensmodel() : "none"},
      {"image size", FormatFixed(w, 0) + " x " + FormatFixed(h, 0) + " px"},
      {"RMS reprojection error",
       FormatFixed(r.rms_px, 4) +
           " px (per corner, OpenCV's definition; mrcal's per-coordinate RMS is " +
           FormatFixed(r.rms_px / std::sqrt(2.0), 4) + " px)"},
      {"residual sigma", FormatFixed(r.residual_sigma_px, 4) + " px per coordinate"},
      {"views used", std::to_string(used) + " of " + std::to_string(r.views.size())},
      {"corners used / outliers",
       std::to_string(r.num_corners) + " / " + std::to_string(r.num_outliers)},
      {"converged", r.converged ? "yes" : "NO: " + r.termination},
      {"focal length observable", r.focal_observable ? "yes" : "NO"},
      {"spread of board normals", FormatFixed(r.tilt_spread_deg, 1) + " deg"},
      {"board warp (x, y)",
       FormatFixed(r.board_warp_mm.x(), 3) + ", " + FormatFixed(r.board_warp_mm.y(), 3) + " mm"},
  });
  for (const std::string& warning : r.warnings) page.AddWarning(warning);

  page.AddHeading("Intrinsics (1 sigma from the covariance, scaled by the residual variance)");
  std::vector<std::vector<std::string>> rows;
  if (r.camera) {
    const std::vector<double>& v = r.camera->intrinsics();
    const std::size_t shown =
        r.camera->lensmodel().find("SPLINED") != std::string::npos ? 4 : v.size();
    for (std::size_t i = 0; i < shown; ++i) {
      rows.push_back({r.intrinsic_names[i], Sci(v[i]),
                      r.intrinsics_sigma.empty() ? "n/a" : Sci(r.intrinsics_sigma[i])});
    }
    if (shown < v.size()) {
      rows.push_back(
          {"spline knots", std::to_string(v.size() - shown) + " values", "see .cameramodel"});
    }
  }
  page.AddTable({"parameter", "value", "1 sigma"}, rows);

  page.AddHeading("Residuals");
  std::vector<double> norms, rx, ry;
  std::vector<Eigen::Vector2d> origins, vectors;
  report::Series inliers{"inlier corners", {}, {}, false}, outliers{"outliers", {}, {}, false};
  for (const CornerResidual& c : r.corners) {
    if (c.outlier) {
      outliers.x.push_back(c.observed_px.x());
      outliers.y.push_back(c.observed_px.y());
      continue;
    }
    norms.push_back(c.residual_px.norm());
    rx.push_back(c.residual_px.x());
    ry.push_back(c.residual_px.y());
    origins.push_back(c.observed_px);
    vectors.push_back(c.residual_px);
    inliers.x.push_back(c.observed_px.x());
    inliers.y.push_back(c.observed_px.y());
  }
  page.AddHistogram("Residual norm of the inlier corners", norms, "|projected - observed| (px)");
  std::vector<double> both = rx;
  both.insert(both.end(), ry.begin(), ry.end());
  page.AddHistogram("Residual components (x and y)", both, "residual (px)");
  std::vector<double> sorted = norms;
  std::sort(sorted.begin(), sorted.end());
  const double median = sorted.empty() ? 1.0 : std::max(1e-6, sorted[sorted.size() / 2]);
  const double scale = 0.02 * std::max(w, h) / median;
  page.AddVectorField("Residual vectors over the image", origins, vectors, scale, w, h,
                      "residuals magnified " + FormatFixed(scale, 0) +
                          "x (the median residual is " + FormatFixed(median, 3) + " px)");

  page.AddHeading("Views");
  std::vector<std::string> labels;
  std::vector<double> rms;
  for (const ViewResult& v : r.views) {
    if (!v.used) continue;
    labels.push_back(v.name.substr(
        v.name.find_last_of('/') == std::string::npos ? 0 : v.name.find_last_of('/') + 1));
    rms.push_back(v.rms_px);
  }
  page.AddBars("RMS reprojection error per image", labels, rms, "RMS (px)");
  std::vector<std::vector<std::string>> view_rows;
  for (const ViewResult& v : r.views) {
    view_rows.push_back(
        {v.name, v.used ? "yes" : "no: " + v.rejection_reason,
         v.used ? FormatFixed(v.rms_px, 3) : "", v.used ? std::to_string(v.num_corners) : "",
         v.used ? std::to_string(v.num_outliers) : "", v.used ? FormatFixed(v.tilt_deg, 1) : "",
         v.used ? FormatFixed(v.camera_from_board.translation().norm(), 0) : ""});
  }
  page.AddTable({"image", "used", "RMS (px)", "corners", "outliers", "tilt (deg)", "distance (mm)"},
                view_rows);

  page.AddHeading("Coverage and projection uncertainty");
  report::PlotOptions coverage;
  coverage.x_label = "column (px)";
  coverage.y_label = "row (px)";
  coverage.equal_aspect = true;
  coverage.y_down = true;
  coverage.range = {0, w, 0, h};
  std::vector<report::Series> series = {inliers};
  if (!outliers.x.empty()) series.push_back(outliers);
  page.AddScatter("Coverage of the image by the observed corners", series, coverage);
  page.AddHeatmap("Projection uncertainty (1 sigma, worst direction) at " +
                      FormatFixed(r.uncertainty_range_mm, 0) + " mm",
                  r.uncertainty_px, w, h, "px");
  page.AddParagraph(
      "Projection uncertainty: a point at the given range on each cell's ray, held fixed in the "
      "frame of the mean of the board poses (mrcal's mean-frames idea), projected through the "
      "intrinsics; the intrinsics' and poses' covariance (marginal over the board warp, scaled "
      "by the residual variance) propagated to the pixel. Uncovered image areas extrapolate the "
      "lens model: expect large values there.");
  return page;
}

}  // namespace lasercell::calib
