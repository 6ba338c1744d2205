// Laser-plane calibration, method (a): a white plate swept at known heights (see
// calib/laser_plane.hpp for the model, what is known and what is estimated).

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <utility>

#include "calib/cost_functions/plane_point_distance.hpp"
#include "calib/internal/laser_geometry.hpp"
#include "calib/internal/laser_plane_fit.hpp"
#include "calib/laser_plane.hpp"
#include "core/error.hpp"
#include "core/frame_graph.hpp"  // FormatDouble
#include "core/stats.hpp"

namespace lasercell::calib {

using namespace internal;

namespace {

/// One plate observation: the mean peak of a column at one height.
struct ColumnObservation {
  int item = 0;
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();
  Eigen::Vector3d ray = Eigen::Vector3d::Zero();
  Eigen::Vector3d ray_up = Eigen::Vector3d::Zero();    // ray at row - 0.5
  Eigen::Vector3d ray_down = Eigen::Vector3d::Zero();  // ray at row + 0.5
  double height = 0;
  int count = 0;
};

Eigen::Vector3d PlatePoint(const Eigen::Vector3d& ray, const Eigen::Vector3d& m, double height,
                           double zero_distance) {
  return ray * ((height - zero_distance) / m.dot(ray));
}

/// The plate normal tilted by `tilt` rad from m0 towards t (HeightPlaneRayCost).
Eigen::Vector3d TiltedNormal(const Eigen::Vector3d& m0, const Eigen::Vector3d& t, double tilt) {
  return std::cos(tilt) * m0 + std::sin(tilt) * t;
}

/// Weight making n.p + d a row residual in px: 1 / |d(n.p + d)/d row| (times sqrt(count): the
/// observation is a mean of `count` peaks).
double RowWeight(const ColumnObservation& o, const Eigen::Vector3d& m, const Eigen::Vector3d& n,
                 double zero_distance) {
  const double up = n.dot(PlatePoint(o.ray_up, m, o.height, zero_distance));
  const double down = n.dot(PlatePoint(o.ray_down, m, o.height, zero_distance));
  const double slope = std::abs(down - up);  // per px
  return slope > 1e-12 ? std::sqrt(static_cast<double>(o.count)) / slope : 0.0;
}

PlaneFit FitHeights(const std::vector<ColumnObservation>& obs, const Eigen::Vector3d& m0,
                    const Eigen::Vector3d& tilt_direction, const Eigen::Vector3d& n0, double d0,
                    double z0, double a0, bool estimate, bool estimate_tilt, int skip_item) {
  // Two passes: the weights depend (weakly) on the plane; recompute them at the first solution.
  PlaneFit fit;
  Eigen::Vector3d n = n0;
  double d = d0, z = z0, a = a0;
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<double> weights;
    const Eigen::Vector3d m = TiltedNormal(m0, tilt_direction, a);
    for (const auto& o : obs) weights.push_back(RowWeight(o, m, n, z));
    fit = Solve(n, d, z, estimate, a, estimate_tilt,
                [&](ceres::Problem& problem, double* pn, double* pd, double* pz, double* pa) {
                  int count = 0;
                  for (std::size_t k = 0; k < obs.size(); ++k) {
                    if (obs[k].item == skip_item || weights[k] == 0) continue;
                    problem.AddResidualBlock(
                        HeightPlaneRayCost::Create(obs[k].ray, m0, tilt_direction, obs[k].height,
                                                   weights[k]),
                        nullptr, pn, pd, pz, pa);
                    ++count;
                  }
                  return count;
                });
    n = fit.normal;
    d = fit.offset;
    z = fit.zero_distance;
    a = fit.tilt;
  }
  return fit;
}

/// Closed-form start: for candidate D0 the plate points by TLS plane; pick the D0 whose plane
/// explains the rows best (residuals weighted to px).
void InitialHeights(const std::vector<ColumnObservation>& obs, const Eigen::Vector3d& m,
                    const std::vector<double>& candidates, Eigen::Vector3d* n, double* d,
                    double* z) {
  double best = std::numeric_limits<double>::infinity();
  std::vector<Eigen::Vector3d> points(obs.size());
  for (const double cand : candidates) {
    for (std::size_t k = 0; k < obs.size(); ++k)
      points[k] = PlatePoint(obs[k].ray, m, obs[k].height, cand);
    const internal::TlsPlane plane = internal::FitPlaneTls(points);
    double cost = 0;
    for (std::size_t k = 0; k < obs.size(); ++k) {
      const double w = RowWeight(obs[k], m, plane.normal, cand);
      const double r = w * (plane.normal.dot(points[k]) + plane.offset_mm);
      cost += r * r;
    }
    if (cost < best) {
      best = cost;
      *n = plane.normal;
      *d = plane.offset_mm;
      *z = cand;
    }
  }
}

/// The distinct heights; InputError for fewer than 2, or 2 when D0 is to be estimated.
std::set<double> CheckHeights(const std::vector<HeightCapture>& captures, bool estimate) {
  std::set<double> heights;
  for (const auto& c : captures) {
    if (!std::isfinite(c.height_mm))
      throw InputError("capture '" + c.name + "': height is not finite");
    heights.insert(c.height_mm);
  }
  if (heights.size() < 2) {
    throw InputError(
        "planes at one height only: " + std::to_string(captures.size()) + " capture(s), all at " +
        (heights.empty() ? std::string("no height") : Num(*heights.begin()) + " mm") +
        "; the white-plane method needs the plate at >= 2 distinct heights (>= 3 to estimate the "
        "sensor's distance to the plate)");
  }
  if (estimate && heights.size() < 3) {
    throw InputError(
        "planes at only 2 distinct heights: with 2 heights the distance from the sensor to the "
        "plates cannot be estimated together with the laser plane (a one-parameter family of "
        "planes fits exactly); add a capture at a third height or give the distance to the "
        "height-0 plate (--plate-distance-mm)");
  }
  return heights;
}

/// The plate's columns in capture `i`: appends them to `obs` and returns the capture's item;
/// InputError when too few columns hold plate peaks.
LaserPlaneItem PlateColumns(const HeightCapture& c, int i, const HeightPlaneOptions& options,
                            std::vector<ColumnObservation>& obs) {
  LaserPlaneItem item;
  item.name = c.name;
  item.height_mm = c.height_mm;
  std::map<long, std::vector<double>> columns;
  for (const auto& p : c.peaks_px) {
    if (!p.allFinite()) continue;
    columns[std::lround(p.x())].push_back(p.y());
  }
  // Per column the mean of the peaks near the column's median row; then the longest run of
  // neighbouring columns whose rows change by < max_row_step_px: the plate, not the floor or
  // fixtures the edge columns may see instead (they sit many px away).
  std::vector<std::pair<long, std::pair<double, int>>> cells;
  for (auto& [column, rows] : columns) {
    const double median = Median(rows);
    double sum = 0;
    int count = 0;
    for (const double r : rows) {
      if (std::abs(r - median) <= options.inlier_band_px) {
        sum += r;
        ++count;
      }
    }
    if (count < options.min_peaks_per_column) continue;
    cells.push_back({column, {sum / count, count}});
  }
  std::size_t best_begin = 0, best_end = 0;
  for (std::size_t begin = 0; begin < cells.size();) {
    std::size_t end = begin + 1;
    while (end < cells.size() && cells[end].first - cells[end - 1].first <= 2 &&
           std::abs(cells[end].second.first - cells[end - 1].second.first) <
               options.max_row_step_px) {
      ++end;
    }
    if (end - begin > best_end - best_begin) {
      best_begin = begin;
      best_end = end;
    }
    begin = end;
  }
  int used_columns = 0;
  for (std::size_t k = best_begin; k < best_end; ++k) {
    ColumnObservation o;
    o.item = i;
    o.pixel = Eigen::Vector2d(static_cast<double>(cells[k].first), cells[k].second.first);
    o.height = c.height_mm;
    o.count = cells[k].second.second;
    obs.push_back(o);
    ++used_columns;
  }
  if (best_end - best_begin < cells.size()) {
    item.note =
        std::to_string(cells.size() - (best_end - best_begin)) + " columns off the plate dropped";
  }
  if (used_columns < options.min_columns) {
    throw InputError("capture '" + c.name + "' (height " + Num(c.height_mm) + " mm): only " +
                     std::to_string(used_columns) +
                     " columns hold >= " + std::to_string(options.min_peaks_per_column) +
                     " consistent plate peaks (need " + std::to_string(options.min_columns) +
                     "); is the white plate in view at this height?");
  }
  item.used = true;
  item.points = used_columns;
  return item;
}

/// Rays of the observations' pixels and of half a pixel above and below (one batch).
void UnprojectColumns(const CameraModel& camera, std::vector<ColumnObservation>& obs) {
  std::vector<Eigen::Vector2d> pixels;
  for (const auto& o : obs) {
    pixels.push_back(o.pixel);
    pixels.push_back(o.pixel - Eigen::Vector2d(0, 0.5));
    pixels.push_back(o.pixel + Eigen::Vector2d(0, 0.5));
  }
  const std::vector<Eigen::Vector3d> rays = camera.UnprojectMany(pixels);
  for (std::size_t k = 0; k < obs.size(); ++k) {
    if (!rays[3 * k].allFinite() || !rays[3 * k + 1].allFinite() || !rays[3 * k + 2].allFinite()) {
      throw InputError("laser plane: the camera model (" + camera.lensmodel() +
                       ") gives no ray at stripe pixel column " + FormatDouble(obs[k].pixel.x()) +
                       ", row " + FormatDouble(obs[k].pixel.y()) +
                       "; its lens model is not invertible there: recalibrate the camera");
    }
    obs[k].ray = rays[3 * k];
    obs[k].ray_up = rays[3 * k + 1];
    obs[k].ray_down = rays[3 * k + 2];
  }
}

/// The stripe must move between heights, else the rays lie in the laser plane: InputError.
void CheckStripeMoves(const std::vector<HeightCapture>& captures,
                      const std::vector<ColumnObservation>& obs) {
  double largest_shift = 0;
  for (std::size_t a = 0; a < captures.size(); ++a) {
    for (std::size_t b = a + 1; b < captures.size(); ++b) {
      if (captures[a].height_mm == captures[b].height_mm) continue;
      std::map<long, double> rows_a;
      for (const auto& o : obs) {
        if (o.item == static_cast<int>(a)) rows_a[std::lround(o.pixel.x())] = o.pixel.y();
      }
      std::vector<double> shifts;
      for (const auto& o : obs) {
        if (o.item != static_cast<int>(b)) continue;
        const auto it = rows_a.find(std::lround(o.pixel.x()));
        if (it != rows_a.end()) shifts.push_back(std::abs(o.pixel.y() - it->second));
      }
      if (!shifts.empty()) largest_shift = std::max(largest_shift, Median(shifts));
    }
  }
  if (largest_shift < 1.0) {
    throw InputError(
        "ill-conditioned: the laser stripe does not move between the heights (largest median "
        "row shift " +
        Num(largest_shift, 3) +
        " px): the laser plane is (nearly) parallel to the camera rays (the camera centre lies in "
        "it), so its distance cannot be measured; check the sensor geometry and the captures");
  }
}

/// Residuals of the fitted plane and per-height RMS (mm, and px of peak row); the plate points
/// go to `all_points`.
void HeightResiduals(const std::vector<ColumnObservation>& obs, const PlaneFit& fit,
                     const Eigen::Vector3d& m_fit, LaserPlaneResult& result,
                     std::vector<Eigen::Vector3d>* used_rays,
                     std::vector<Eigen::Vector3d>* all_points) {
  double sum_mm = 0, sum_px = 0;
  std::vector<double> item_mm(result.items.size(), 0), item_px(result.items.size(), 0);
  for (const auto& o : obs) {
    const Eigen::Vector3d p = PlatePoint(o.ray, m_fit, o.height, fit.zero_distance);
    const double r = fit.normal.dot(p) + fit.offset;
    const double w = RowWeight(o, m_fit, fit.normal, fit.zero_distance) /
                     std::sqrt(static_cast<double>(o.count));
    result.residuals.push_back({o.item, o.pixel, p, r});
    sum_mm += r * r;
    sum_px += (w * r) * (w * r);
    item_mm[static_cast<std::size_t>(o.item)] += r * r;
    item_px[static_cast<std::size_t>(o.item)] += (w * r) * (w * r);
    used_rays->push_back(o.ray);
    all_points->push_back(p);
  }
  result.points = static_cast<int>(obs.size());
  result.rms_mm = std::sqrt(sum_mm / obs.size());
  result.rms_px = std::sqrt(sum_px / obs.size());
  for (std::size_t i = 0; i < result.items.size(); ++i) {
    result.items[i].rms_mm = std::sqrt(item_mm[i] / result.items[i].points);
    result.items[i].rms_px = std::sqrt(item_px[i] / result.items[i].points);
  }
}

/// Leave one height out, when the rest still determines the plane.
void LeaveOneHeightOut(const std::vector<HeightCapture>& captures,
                       const std::vector<ColumnObservation>& obs, const Eigen::Vector3d& m,
                       const Eigen::Vector3d& tilt_direction, const PlaneFit& fit, bool estimate,
                       bool estimate_tilt, const std::vector<Eigen::Vector3d>& all_points,
                       LaserPlaneResult& result) {
  for (std::size_t i = 0; i < result.items.size(); ++i) {
    std::set<double> rest;
    for (std::size_t j = 0; j < captures.size(); ++j) {
      if (j != i) rest.insert(captures[j].height_mm);
    }
    LaserPlaneItem& item = result.items[i];
    if (rest.size() < 2) {
      item.loo_normal_change_deg = item.loo_offset_change_mm = item.loo_max_displacement_mm = kNaN;
      continue;
    }
    // Two heights left cannot give D0 (nor the tilt): hold them at the full fit's values.
    const bool hold = estimate && rest.size() < 3;
    item.loo_zero_distance_held = hold;
    const PlaneFit loo =
        FitHeights(obs, m, tilt_direction, fit.normal, fit.offset, fit.zero_distance, fit.tilt,
                   estimate && !hold, estimate_tilt && !hold, static_cast<int>(i));
    LooChange(fit.normal, fit.offset, loo.normal, loo.offset, all_points, item);
  }
  SummarizeLoo(result);
}

}  // namespace

LaserPlaneResult CalibrateLaserPlaneFromHeights(const CameraModel& camera,
                                                const std::vector<HeightCapture>& captures,
                                                const HeightPlaneOptions& options) {
  options.Check();
  const Eigen::Vector3d m = options.plate_normal_in_sensor.normalized();
  const bool estimate = !options.zero_distance_mm.has_value();
  const std::set<double> heights = CheckHeights(captures, estimate);

  LaserPlaneResult result;
  result.method = "heights";
  std::vector<ColumnObservation> obs;
  for (std::size_t i = 0; i < captures.size(); ++i) {
    result.items.push_back(PlateColumns(captures[i], static_cast<int>(i), options, obs));
  }
  UnprojectColumns(camera, obs);
  CheckStripeMoves(captures, obs);

  // Start: D0 candidates (plates in front of the sensor: D0 > the largest height).
  std::vector<double> candidates;
  if (estimate) {
    const double top = *heights.rbegin();
    for (int k = 0; k <= 120; ++k)
      candidates.push_back(top + std::pow(10.0, -1.0 + 6.0 * k / 120.0));
  } else {
    candidates.push_back(*options.zero_distance_mm);
  }
  Eigen::Vector3d n0;
  double d0 = 0, z0 = 0;
  InitialHeights(obs, m, candidates, &n0, &d0, &z0);
  // The one observable plate tilt: towards the laser line's direction on the plate.
  const Eigen::Vector3d tilt_direction = n0.cross(m).normalized();
  const bool estimate_tilt = options.estimate_plate_tilt;
  const PlaneFit fit =
      FitHeights(obs, m, tilt_direction, n0, d0, z0, 0.0, estimate, estimate_tilt, -1);
  FillPlane(fit, result);
  result.zero_distance_mm = fit.zero_distance;
  result.zero_distance_sigma_mm = std::sqrt(std::max(0.0, fit.zero_distance_variance));
  result.plate_tilt_deg = fit.tilt * kRadToDeg;
  result.plate_tilt_sigma_deg = std::sqrt(std::max(0.0, fit.tilt_variance)) * kRadToDeg;
  const Eigen::Vector3d m_fit = TiltedNormal(m, tilt_direction, fit.tilt);

  // Residuals, per-height RMS.
  std::vector<Eigen::Vector3d> used_rays, all_points;
  HeightResiduals(obs, fit, m_fit, result, &used_rays, &all_points);
  FlagConditioning(result, used_rays, options.min_triangulation_angle_deg);

  // Leave one height out, when the rest still determines the plane.
  LeaveOneHeightOut(captures, obs, m, tilt_direction, fit, estimate, estimate_tilt, all_points,
                    result);
  // The camera's own uncertainty: the same columns through perturbed cameras.
  AddCameraUncertainty(
      camera, options.include_camera_uncertainty,
      [&](const CameraModel& perturbed) {
        std::vector<ColumnObservation> moved = obs;
        UnprojectColumns(perturbed, moved);
        const PlaneFit refit = FitHeights(moved, m, tilt_direction, fit.normal, fit.offset,
                                          fit.zero_distance, fit.tilt, estimate, estimate_tilt, -1);
        return std::make_pair(refit.normal, refit.offset);
      },
      result);
  if (!result.converged)
    result.warnings.push_back("the solver did not converge: " + result.termination);
  return result;
}

}  // namespace lasercell::calib
