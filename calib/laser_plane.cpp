// Laser-plane calibration: white plane at known heights (seed "Calibration chain" 2) and laser
// stripe on a chessboard of unknown pose (Zhou & Zhang 2005). See laser_plane.hpp.

#include "calib/laser_plane.hpp"

#include <ceres/ceres.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <array>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <set>
#include <sstream>

#include "calib/cost_functions/plane_board_joint.hpp"
#include "calib/cost_functions/plane_point_distance.hpp"
#include "calib/internal/laser_geometry.hpp"
#include "calib/internal/stripe_detection.hpp"
#include "core/error.hpp"

namespace lasercell::calib {

namespace {

// Covariance settings shared by the plane fits: dense SVD with a pseudo-inverse, so a
// degenerate problem gives huge sigmas instead of failing.
ceres::Covariance::Options PlaneCovarianceOptions() {
  ceres::Covariance::Options options;
  options.algorithm_type = ceres::DENSE_SVD;
  options.null_space_rank = -1;
  options.min_reciprocal_condition_number = 1e-14;
  return options;
}

// The covariance blocks PlaneCovariance reads for the plane {n[3], d}.
std::vector<std::pair<const double*, const double*>> PlaneCovarianceBlocks(const double* n,
                                                                           const double* d) {
  return {{n, n}, {n, d}, {d, d}};
}

// Ambient 4x4 covariance of the plane {n, d} (n the unit normal on a SphereManifold<3>, then d),
// scaled by `scale` (the variance of unit weight; 1 when the residuals are already whitened) and
// symmetrized. The normal blocks come from Ceres's tangent-space blocks: C = J C_t J^T with
// J = dPlus/ddelta at 0. Ceres 2.1's own lifting to the ambient space allocates Eigen matrices
// across the libceres boundary, which ASan reports as a bad free in the sanitizer build (Debian's
// libceres vs our instrumented Eigen instantiations); the tangent blocks are plain copies.
// `covariance` must have been computed over PlaneCovarianceBlocks(n, d).
Eigen::Matrix4d PlaneCovariance(const ceres::Covariance& covariance, const double* n,
                                const double* d, double scale) {
  const ceres::SphereManifold<3> sphere;
  Eigen::Matrix<double, 3, 2, Eigen::RowMajor> j;
  sphere.PlusJacobian(n, j.data());
  Eigen::Matrix<double, 2, 2, Eigen::RowMajor> ctt;
  Eigen::Vector2d ctd;
  double cdd = 0;
  covariance.GetCovarianceBlockInTangentSpace(n, n, ctt.data());
  covariance.GetCovarianceBlockInTangentSpace(n, d, ctd.data());
  covariance.GetCovarianceBlock(d, d, &cdd);
  const Eigen::Vector3d cnd = j * ctd;
  Eigen::Matrix4d c;
  c.topLeftCorner<3, 3>() = j * ctt * j.transpose();
  c.topRightCorner<3, 1>() = cnd;
  c.bottomLeftCorner<1, 3>() = cnd.transpose();
  c(3, 3) = cdd;
  c *= scale;
  return 0.5 * (c + c.transpose());
}

constexpr double kRadToDeg = 180.0 / M_PI;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string Num(double v, int precision = 4) {
  std::ostringstream s;
  s.precision(precision);
  s << v;
  return s.str();
}

double Median(std::vector<double> v) {
  if (v.empty()) return kNaN;
  const auto mid = v.begin() + static_cast<long>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

/// The solution of one Ceres plane fit.
struct PlaneFit {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitY();
  double offset = 0;
  double zero_distance = 0;  // D0 (method a)
  double tilt = 0;           // plate tilt (method a), rad
  double tilt_variance = 0;
  Eigen::Matrix4d covariance = Eigen::Matrix4d::Zero();
  double zero_distance_variance = 0;
  bool converged = false;
  bool covariance_ok = false;
  int iterations = 0;
  std::string termination;
};

/// Solver settings shared by the plane fits: tight tolerances, at most 100 iterations, one thread.
ceres::Solver::Options PlaneSolverOptions(ceres::LinearSolverType linear_solver) {
  ceres::Solver::Options options;
  options.linear_solver_type = linear_solver;
  options.max_num_iterations = 100;
  options.function_tolerance = 1e-14;
  options.parameter_tolerance = 1e-14;
  options.num_threads = 1;
  return options;
}

/// Solves `problem` (whose plane parameter blocks are n[3] and d[1]) and records the outcome and
/// the solved plane (normal re-normalized) in `fit`; returns Ceres's final cost (half the sum of
/// squared residuals).
double SolvePlaneProblem(const ceres::Solver::Options& options, ceres::Problem& problem,
                         const double* n, const double* d, PlaneFit* fit) {
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  fit->converged = summary.IsSolutionUsable() && summary.termination_type == ceres::CONVERGENCE;
  fit->iterations = static_cast<int>(summary.iterations.size());
  fit->termination = summary.message;
  fit->normal = Eigen::Vector3d(n[0], n[1], n[2]).normalized();
  fit->offset = *d;
  return summary.final_cost;
}

/// Adds residual blocks given the parameter blocks (normal[3], offset[1], zero_distance[1],
/// tilt[1]).
using AddResiduals = std::function<int(ceres::Problem&, double*, double*, double*, double*)>;

/// Solves, then computes the covariance scaled by the reduced chi-square.
PlaneFit Solve(const Eigen::Vector3d& normal0, double offset0, double zero_distance0,
               bool estimate_zero_distance, double tilt0, bool estimate_tilt,
               const AddResiduals& add) {
  PlaneFit fit;
  double n[3] = {normal0.x(), normal0.y(), normal0.z()};
  double d = offset0;
  double z = zero_distance0;
  double a = tilt0;
  ceres::Problem problem;
  const int count = add(problem, n, &d, &z, &a);
  problem.SetManifold(n, new ceres::SphereManifold<3>());
  if (problem.HasParameterBlock(&z) && !estimate_zero_distance) problem.SetParameterBlockConstant(&z);
  if (problem.HasParameterBlock(&a) && !estimate_tilt) problem.SetParameterBlockConstant(&a);
  ceres::Solver::Options options = PlaneSolverOptions(ceres::DENSE_QR);
  options.gradient_tolerance = 1e-16;
  const double final_cost = SolvePlaneProblem(options, problem, n, &d, &fit);
  fit.zero_distance = z;
  fit.tilt = a;
  const int dof = count - 3 - (estimate_zero_distance ? 1 : 0) - (estimate_tilt ? 1 : 0);
  const double sigma2 = dof > 0 ? 2.0 * final_cost / dof : 0.0;

  ceres::Covariance covariance(PlaneCovarianceOptions());
  std::vector<std::pair<const double*, const double*>> blocks = PlaneCovarianceBlocks(n, &d);
  if (estimate_zero_distance) blocks.push_back({&z, &z});
  if (estimate_tilt) blocks.push_back({&a, &a});
  if (covariance.Compute(blocks, &problem)) {
    fit.covariance = PlaneCovariance(covariance, n, &d, sigma2);
    if (estimate_zero_distance) {
      covariance.GetCovarianceBlock(&z, &z, &fit.zero_distance_variance);
      fit.zero_distance_variance *= sigma2;
    }
    if (estimate_tilt) {
      covariance.GetCovarianceBlock(&a, &a, &fit.tilt_variance);
      fit.tilt_variance *= sigma2;
    }
    fit.covariance_ok = fit.covariance.allFinite();
  }
  // Orient so that d <= 0; the covariance of (-n, -d) is the same matrix.
  internal::OrientPlane(fit.normal, fit.offset);
  return fit;
}

void FillPlane(const PlaneFit& fit, LaserPlaneResult& r) {
  r.normal = fit.normal;
  r.offset_mm = fit.offset;
  r.point_mm = -fit.offset * fit.normal;
  r.covariance = fit.covariance;
  r.normal_sigma_deg = std::sqrt(std::max(0.0, fit.covariance.topLeftCorner<3, 3>().trace())) * kRadToDeg;
  r.offset_sigma_mm = std::sqrt(std::max(0.0, fit.covariance(3, 3)));
  r.converged = fit.converged;
  r.iterations = fit.iterations;
  r.termination = fit.termination;
  if (!fit.covariance_ok) {
    r.warnings.push_back("the covariance could not be computed (rank-deficient problem)");
  }
}

double AngleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) * kRadToDeg;
}

/// Median angle (deg) between the rays and the plane.
double MedianTriangulationAngleDeg(const std::vector<Eigen::Vector3d>& rays,
                                   const Eigen::Vector3d& normal) {
  std::vector<double> angles;
  angles.reserve(rays.size());
  for (const auto& r : rays) angles.push_back(std::asin(std::min(1.0, std::abs(normal.dot(r.normalized())))) * kRadToDeg);
  return Median(std::move(angles));
}

void FlagConditioning(LaserPlaneResult& r, const std::vector<Eigen::Vector3d>& rays, double min_deg) {
  r.median_triangulation_angle_deg = MedianTriangulationAngleDeg(rays, r.normal);
  if (!(r.median_triangulation_angle_deg >= min_deg)) {
    r.ill_conditioned = true;
    r.warnings.push_back(
        "ill-conditioned: the laser plane is (nearly) parallel to the camera rays (median angle " +
        Num(r.median_triangulation_angle_deg, 3) + " deg < " + Num(min_deg, 3) +
        " deg): the camera centre lies close to the laser plane, so triangulation with it is "
        "unreliable; move the laser away from the camera (baseline) or check the inputs");
  }
}

/// Leave-one-out change between two planes, and the largest displacement over points.
void LooChange(const Eigen::Vector3d& n0, double d0, const Eigen::Vector3d& n1, double d1,
               const std::vector<Eigen::Vector3d>& points, LaserPlaneItem& item) {
  item.loo_normal_change_deg = AngleDeg(n0, n1);
  item.loo_offset_change_mm = d1 - d0;
  double worst = 0;
  for (const auto& p : points) {
    // Distance along n0 between the two planes at p's footprint on plane 0.
    const Eigen::Vector3d q = p - (n0.dot(p) + d0) * n0;
    const double denom = n1.dot(n0);
    const double s = std::abs(denom) > 1e-12 ? -(n1.dot(q) + d1) / denom : kNaN;
    worst = std::max(worst, std::abs(s));
  }
  item.loo_max_displacement_mm = worst;
}

void SummarizeLoo(LaserPlaneResult& r) {
  bool any = false;
  r.loo_max_normal_change_deg = 0;
  r.loo_max_offset_change_mm = 0;
  for (const auto& item : r.items) {
    if (!item.used || std::isnan(item.loo_normal_change_deg)) continue;
    any = true;
    r.loo_max_normal_change_deg = std::max(r.loo_max_normal_change_deg, item.loo_normal_change_deg);
    r.loo_max_offset_change_mm = std::max(r.loo_max_offset_change_mm, std::abs(item.loo_offset_change_mm));
  }
  if (!any) {
    r.loo_max_normal_change_deg = kNaN;
    r.loo_max_offset_change_mm = kNaN;
  }
}

// ------------------------------------------------------------------------------------------
// Method (a): white plane at known heights.

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
                        HeightPlaneRayCost::Create(obs[k].ray, m0, tilt_direction, obs[k].height, weights[k]),
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
                    const std::vector<double>& candidates, Eigen::Vector3d* n, double* d, double* z) {
  double best = std::numeric_limits<double>::infinity();
  std::vector<Eigen::Vector3d> points(obs.size());
  for (const double cand : candidates) {
    for (std::size_t k = 0; k < obs.size(); ++k) points[k] = PlatePoint(obs[k].ray, m, obs[k].height, cand);
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

}  // namespace

// ------------------------------------------------------------------------------------------

void HeightPlaneOptions::Check() const {
  if (!plate_normal_in_sensor.allFinite() || plate_normal_in_sensor.norm() < 1e-9) {
    throw OptionError("HeightPlaneOptions.plate_normal_in_sensor must be a finite non-zero vector");
  }
  if (zero_distance_mm && !std::isfinite(*zero_distance_mm)) {
    throw OptionError("HeightPlaneOptions.zero_distance_mm must be finite");
  }
  if (!(inlier_band_px > 0)) throw OptionError("HeightPlaneOptions.inlier_band_px must be > 0");
  if (!(max_row_step_px > 0)) throw OptionError("HeightPlaneOptions.max_row_step_px must be > 0");
  if (min_columns < 3) throw OptionError("HeightPlaneOptions.min_columns must be >= 3");
  if (min_peaks_per_column < 1) throw OptionError("HeightPlaneOptions.min_peaks_per_column must be >= 1");
  if (!(min_triangulation_angle_deg >= 0 && min_triangulation_angle_deg < 90)) {
    throw OptionError("HeightPlaneOptions.min_triangulation_angle_deg must be in [0, 90)");
  }
}

void StripeOptions::Check() const {
  if (laser_color != "green" && laser_color != "red" && laser_color != "gray") {
    throw OptionError("StripeOptions.laser_color is '" + laser_color + "'; expected green, red or gray");
  }
  if (!(min_peak_contrast > 0)) throw OptionError("StripeOptions.min_peak_contrast must be > 0");
  if (!(board_margin_squares >= 0 && board_margin_squares <= 1)) {
    throw OptionError("StripeOptions.board_margin_squares must be in [0, 1]");
  }
  if (!(ambiguity_ratio > 0 && ambiguity_ratio <= 1)) {
    throw OptionError("StripeOptions.ambiguity_ratio must be in (0, 1]");
  }
  if (max_stripe_width_px < 1) throw OptionError("StripeOptions.max_stripe_width_px must be >= 1");
  if (min_peaks_per_image < 3) throw OptionError("StripeOptions.min_peaks_per_image must be >= 3");
  if (!(min_triangulation_angle_deg >= 0 && min_triangulation_angle_deg < 90)) {
    throw OptionError("StripeOptions.min_triangulation_angle_deg must be in [0, 90)");
  }
  if (!(outlier_sigmas > 0)) throw OptionError("StripeOptions.outlier_sigmas must be > 0");
  board_detection.Check();
}

std::string LaserPlaneResult::Summary() const {
  std::ostringstream s;
  s.precision(6);
  s << "laser plane (" << method << "): n = [" << normal.x() << ", " << normal.y() << ", "
    << normal.z() << "], d = " << offset_mm << " mm; 1-sigma " << Num(normal_sigma_deg, 3)
    << " deg / " << Num(offset_sigma_mm, 3) << " mm; rms " << Num(rms_mm, 3) << " mm";
  if (method == "heights") s << " (" << Num(rms_px, 3) << " px)";
  s << " over " << points << " points";
  if (!converged) s << "; NOT CONVERGED";
  if (ill_conditioned) s << "; ILL-CONDITIONED";
  return s.str();
}

LaserPlaneResult CalibrateLaserPlaneFromHeights(const CameraModel& camera,
                                                const std::vector<HeightCapture>& captures,
                                                const HeightPlaneOptions& options) {
  options.Check();
  const Eigen::Vector3d m = options.plate_normal_in_sensor.normalized();
  std::set<double> heights;
  for (const auto& c : captures) {
    if (!std::isfinite(c.height_mm)) throw InputError("capture '" + c.name + "': height is not finite");
    heights.insert(c.height_mm);
  }
  if (heights.size() < 2) {
    throw InputError(
        "planes at one height only: " + std::to_string(captures.size()) + " capture(s), all at " +
        (heights.empty() ? std::string("no height") : Num(*heights.begin()) + " mm") +
        "; the white-plane method needs the plate at >= 2 distinct heights (>= 3 to estimate the "
        "sensor's distance to the plate)");
  }
  const bool estimate = !options.zero_distance_mm.has_value();
  if (estimate && heights.size() < 3) {
    throw InputError(
        "planes at only 2 distinct heights: with 2 heights the distance from the sensor to the "
        "plates cannot be estimated together with the laser plane (a one-parameter family of "
        "planes fits exactly); add a capture at a third height or give the distance to the "
        "height-0 plate (--plate-distance-mm)");
  }

  LaserPlaneResult result;
  result.method = "heights";
  std::vector<ColumnObservation> obs;
  std::vector<Eigen::Vector2d> pixels;
  for (std::size_t i = 0; i < captures.size(); ++i) {
    const HeightCapture& c = captures[i];
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
             std::abs(cells[end].second.first - cells[end - 1].second.first) < options.max_row_step_px) {
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
      o.item = static_cast<int>(i);
      o.pixel = Eigen::Vector2d(static_cast<double>(cells[k].first), cells[k].second.first);
      o.height = c.height_mm;
      o.count = cells[k].second.second;
      obs.push_back(o);
      pixels.push_back(o.pixel);
      pixels.push_back(o.pixel - Eigen::Vector2d(0, 0.5));
      pixels.push_back(o.pixel + Eigen::Vector2d(0, 0.5));
      ++used_columns;
    }
    if (best_end - best_begin < cells.size()) {
      item.note = std::to_string(cells.size() - (best_end - best_begin)) + " columns off the plate dropped";
    }
    if (used_columns < options.min_columns) {
      throw InputError("capture '" + c.name + "' (height " + Num(c.height_mm) + " mm): only " +
                       std::to_string(used_columns) + " columns hold >= " +
                       std::to_string(options.min_peaks_per_column) +
                       " consistent plate peaks (need " + std::to_string(options.min_columns) +
                       "); is the white plate in view at this height?");
    }
    item.used = true;
    item.points = used_columns;
    result.items.push_back(item);
  }
  const std::vector<Eigen::Vector3d> rays = camera.UnprojectMany(pixels);
  for (std::size_t k = 0; k < obs.size(); ++k) {
    obs[k].ray = rays[3 * k];
    obs[k].ray_up = rays[3 * k + 1];
    obs[k].ray_down = rays[3 * k + 2];
  }
  // The stripe must move between heights, else the rays lie in the laser plane.
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
        "row shift " + Num(largest_shift, 3) +
        " px): the laser plane is (nearly) parallel to the camera rays (the camera centre lies in "
        "it), so its distance cannot be measured; check the sensor geometry and the captures");
  }

  // Start: D0 candidates (plates in front of the sensor: D0 > the largest height).
  std::vector<double> candidates;
  if (estimate) {
    const double top = *heights.rbegin();
    for (int k = 0; k <= 120; ++k) candidates.push_back(top + std::pow(10.0, -1.0 + 6.0 * k / 120.0));
  } else {
    candidates.push_back(*options.zero_distance_mm);
  }
  Eigen::Vector3d n0;
  double d0 = 0, z0 = 0;
  InitialHeights(obs, m, candidates, &n0, &d0, &z0);
  // The one observable plate tilt: towards the laser line's direction on the plate.
  const Eigen::Vector3d tilt_direction = n0.cross(m).normalized();
  const bool estimate_tilt = options.estimate_plate_tilt;
  const PlaneFit fit = FitHeights(obs, m, tilt_direction, n0, d0, z0, 0.0, estimate, estimate_tilt, -1);
  FillPlane(fit, result);
  result.zero_distance_mm = fit.zero_distance;
  result.zero_distance_sigma_mm = std::sqrt(std::max(0.0, fit.zero_distance_variance));
  result.plate_tilt_deg = fit.tilt * kRadToDeg;
  result.plate_tilt_sigma_deg = std::sqrt(std::max(0.0, fit.tilt_variance)) * kRadToDeg;
  const Eigen::Vector3d m_fit = TiltedNormal(m, tilt_direction, fit.tilt);

  // Residuals, per-height RMS.
  double sum_mm = 0, sum_px = 0;
  std::vector<double> item_mm(result.items.size(), 0), item_px(result.items.size(), 0);
  std::vector<Eigen::Vector3d> used_rays, all_points;
  for (const auto& o : obs) {
    const Eigen::Vector3d p = PlatePoint(o.ray, m_fit, o.height, fit.zero_distance);
    const double r = fit.normal.dot(p) + fit.offset;
    const double w = RowWeight(o, m_fit, fit.normal, fit.zero_distance) / std::sqrt(static_cast<double>(o.count));
    result.residuals.push_back({o.item, o.pixel, p, r});
    sum_mm += r * r;
    sum_px += (w * r) * (w * r);
    item_mm[static_cast<std::size_t>(o.item)] += r * r;
    item_px[static_cast<std::size_t>(o.item)] += (w * r) * (w * r);
    used_rays.push_back(o.ray);
    all_points.push_back(p);
  }
  result.points = static_cast<int>(obs.size());
  result.rms_mm = std::sqrt(sum_mm / obs.size());
  result.rms_px = std::sqrt(sum_px / obs.size());
  for (std::size_t i = 0; i < result.items.size(); ++i) {
    result.items[i].rms_mm = std::sqrt(item_mm[i] / result.items[i].points);
    result.items[i].rms_px = std::sqrt(item_px[i] / result.items[i].points);
  }
  FlagConditioning(result, used_rays, options.min_triangulation_angle_deg);

  // Leave one height out, when the rest still determines the plane.
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
    const PlaneFit loo = FitHeights(obs, m, tilt_direction, fit.normal, fit.offset, fit.zero_distance,
                                    fit.tilt, estimate && !hold, estimate_tilt && !hold,
                                    static_cast<int>(i));
    LooChange(fit.normal, fit.offset, loo.normal, loo.offset, all_points, item);
  }
  SummarizeLoo(result);
  if (!result.converged) result.warnings.push_back("the solver did not converge: " + result.termination);
  return result;
}

// ------------------------------------------------------------------------------------------
// Method (b): stripe on a chessboard of unknown pose.

StripeImage DecodeStripeImage(const std::string& bytes, const std::string& name) {
  const cv::Mat raw(1, static_cast<int>(bytes.size()), CV_8UC1, const_cast<char*>(bytes.data()));
  cv::Mat image;
  if (!bytes.empty()) image = cv::imdecode(raw, cv::IMREAD_UNCHANGED);
  if (image.empty()) {
    throw FileError(name, "cannot decode the image (not a readable JPEG/PNG/... file)");
  }
  if (image.depth() != CV_8U) {
    cv::Mat converted;
    image.convertTo(converted, CV_8U, image.depth() == CV_16U ? 1.0 / 256.0 : 1.0);
    image = converted;
  }
  if (image.channels() == 4) cv::cvtColor(image, image, cv::COLOR_BGRA2BGR);
  if (image.channels() != 1 && image.channels() != 3) {
    throw FileError(name, "has " + std::to_string(image.channels()) + " channels; expected 1 or 3");
  }
  StripeImage out;
  out.name = name;
  out.width_px = image.cols;
  out.height_px = image.rows;
  out.channels = image.channels();
  const cv::Mat cont = image.isContinuous() ? image : image.clone();
  out.pixels.assign(cont.data, cont.data + cont.total() * cont.elemSize());
  return out;
}

ChessboardSpec ParseChessboardSpec(const std::string& text, const std::string& what) {
  ChessboardSpec spec;
  char x = 0;
  std::string rest = text;
  const std::string prefix = "chessboard:";
  bool ok = rest.rfind(prefix, 0) == 0;
  if (ok) {
    std::istringstream in(rest.substr(prefix.size()));
    char colon = 0;
    ok = static_cast<bool>(in >> spec.cols >> x >> spec.rows >> colon >> spec.square_mm) &&
         (x == 'x' || x == 'X') && colon == ':' && in.peek() == std::char_traits<char>::eof();
  }
  if (!ok || spec.cols < 2 || spec.rows < 2 || !(spec.square_mm > 0) || !std::isfinite(spec.square_mm)) {
    throw OptionError(what + " is '" + text +
                      "'; expected chessboard:COLSxROWS:SQUARE_MM with inner corners COLS, ROWS >= "
                      "2 and the square edge in mm, e.g. chessboard:8x6:40");
  }
  return spec;
}

namespace {

/// Stripe points of one image: board pose, rays of the stripe pixels ∩ board plane.
struct ImagePoints {
  std::vector<Eigen::Vector2d> pixels;
  std::vector<Eigen::Vector3d> rays;
  std::vector<Eigen::Vector3d> points;
  Eigen::Isometry3d camera_from_board = Eigen::Isometry3d::Identity();
  std::vector<Eigen::Vector2d> corners_normalized;  // x/z, y/z of the corners' rays
};

ImagePoints StripePoints(const CameraModel& camera, const StripeObservation& observation,
                         const ChessboardSpec& board, LaserPlaneItem& item) {
  ImagePoints out;
  const Eigen::Isometry3d camera_from_board =
      internal::BoardPose(camera, observation.corners_px, board, &item.reprojection_rms_px);
  out.camera_from_board = camera_from_board;
  for (const auto& r : camera.UnprojectMany(observation.corners_px)) {
    out.corners_normalized.emplace_back(r.x() / r.z(), r.y() / r.z());
  }
  const Eigen::Vector3d board_normal = camera_from_board.linear().col(2);
  const double board_offset = -board_normal.dot(camera_from_board.translation());
  const std::vector<Eigen::Vector3d> rays = camera.UnprojectMany(observation.stripe_px);
  for (std::size_t k = 0; k < rays.size(); ++k) {
    const auto p = internal::IntersectRayPlane(rays[k], board_normal, board_offset);
    if (!p) continue;
    out.pixels.push_back(observation.stripe_px[k]);
    out.rays.push_back(rays[k]);
    out.points.push_back(*p);
  }
  return out;
}

/// Zhou & Zhang's joint refinement: laser plane and board poses from the corners (normalized
/// reprojection, scaled to px / corner sigma) and the stripe rays (distance of ray ∩ board from
/// the laser plane / stripe sigma). The sigmas are estimated from the separate fits and then
/// from this fit's own residuals (two passes), so the covariance is in units of the data.
PlaneFit JointStripeFit(const std::map<int, ImagePoints>& views, const ChessboardSpec& board,
                        const Eigen::Vector2d& focal_px, const Eigen::Vector3d& n0, double d0,
                        double corner_sigma_px, double stripe_sigma_mm,
                        std::map<int, Eigen::Isometry3d>* refined_poses) {
  PlaneFit fit;
  Eigen::Vector3d n_start = n0;
  double d_start = d0;
  std::map<int, std::array<double, 6>> start;
  for (const auto& [i, v] : views) {
    Eigen::AngleAxisd aa(v.camera_from_board.linear());
    const Eigen::Vector3d w = aa.angle() * aa.axis();
    const Eigen::Vector3d t = v.camera_from_board.translation();
    start[i] = {w.x(), w.y(), w.z(), t.x(), t.y(), t.z()};
  }
  for (int pass = 0; pass < 2; ++pass) {
    double n[3] = {n_start.x(), n_start.y(), n_start.z()};
    double d = d_start;
    std::map<int, std::array<double, 6>> poses = start;
    ceres::Problem problem;
    int count = 0;
    std::vector<ceres::ResidualBlockId> corner_blocks, stripe_blocks;
    for (const auto& [i, v] : views) {
      double* pose = poses[i].data();
      for (int j = 0; j < board.rows; ++j) {
        for (int c = 0; c < board.cols; ++c) {
          const std::size_t k = static_cast<std::size_t>(j * board.cols + c);
          corner_blocks.push_back(problem.AddResidualBlock(
              BoardCornerCost::Create(Eigen::Vector3d(c * board.square_mm, j * board.square_mm, 0.0),
                                      v.corners_normalized[k], focal_px / corner_sigma_px),
              nullptr, pose));
          count += 2;
        }
      }
      for (const auto& ray : v.rays) {
        stripe_blocks.push_back(problem.AddResidualBlock(
            StripeOnBoardCost::Create(ray, 1.0 / stripe_sigma_mm), nullptr, n, &d, pose));
        ++count;
      }
    }
    problem.SetManifold(n, new ceres::SphereManifold<3>());
    SolvePlaneProblem(PlaneSolverOptions(ceres::DENSE_SCHUR), problem, n, &d, &fit);
    // Re-estimate each group's sigma from its residuals (unit-weight residuals ~ N(0, 1) when
    // the sigma is right); the second pass uses them.
    const auto group_rms = [&](const std::vector<ceres::ResidualBlockId>& blocks, int per_block) {
      ceres::Problem::EvaluateOptions eval;
      eval.residual_blocks = blocks;
      double cost = 0;
      problem.Evaluate(eval, &cost, nullptr, nullptr, nullptr);
      return std::sqrt(2.0 * cost / (static_cast<double>(blocks.size()) * per_block));
    };
    const double corner_scale = group_rms(corner_blocks, 2);
    const double stripe_scale = group_rms(stripe_blocks, 1);
    ceres::Covariance covariance(PlaneCovarianceOptions());
    fit.covariance_ok = false;
    if (covariance.Compute(PlaneCovarianceBlocks(n, &d), &problem)) {
      // Unit-weight residuals (both groups' sigmas re-estimated above): no further scaling.
      fit.covariance = PlaneCovariance(covariance, n, &d, 1.0);
      fit.covariance_ok = fit.covariance.allFinite();
    }
    if (refined_poses != nullptr) {
      refined_poses->clear();
      for (const auto& [i, p] : poses) {
        const Eigen::Vector3d w(p[0], p[1], p[2]);
        Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
        if (w.norm() > 0) pose.linear() = Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix();
        pose.translation() = Eigen::Vector3d(p[3], p[4], p[5]);
        (*refined_poses)[i] = pose;
      }
    }
    corner_sigma_px *= corner_scale;
    stripe_sigma_mm *= stripe_scale;
    n_start = fit.normal;
    d_start = fit.offset;
    (void)count;
  }
  internal::OrientPlane(fit.normal, fit.offset);
  return fit;
}

PlaneFit FitPoints(const std::vector<Eigen::Vector3d>& points, const std::vector<int>& owner,
                   const Eigen::Vector3d& n0, double d0, int skip_item) {
  return Solve(n0, d0, 0.0, false, 0.0, false, [&](ceres::Problem& problem, double* pn, double* pd, double*, double*) {
    int count = 0;
    for (std::size_t k = 0; k < points.size(); ++k) {
      if (owner[k] == skip_item) continue;
      problem.AddResidualBlock(PlanePointDistanceCost::Create(points[k]), nullptr, pn, pd);
      ++count;
    }
    return count;
  });
}

}  // namespace

StripeObservation DetectStripe(const CameraModel& camera, const StripeImage& image,
                               const ChessboardSpec& board, const StripeOptions& options) {
  options.Check();
  if (image.width_px != camera.width_px() || image.height_px != camera.height_px()) {
    throw InputError("image '" + image.name + "' is " + std::to_string(image.width_px) + "x" +
                     std::to_string(image.height_px) + " but the camera model is " +
                     std::to_string(camera.width_px()) + "x" + std::to_string(camera.height_px()) +
                     "; use the camera that took the images");
  }
  LASERCELL_CHECK(image.pixels.size() == static_cast<std::size_t>(image.width_px) *
                                             image.height_px * image.channels &&
                      (image.channels == 1 || image.channels == 3),
                  "StripeImage buffer size");
  StripeObservation out;
  out.name = image.name;
  const TargetDetection detection =
      DetectTarget(internal::GrayImageOf(image),
                   BoardSpec::Chessboard(board.cols, board.rows, board.square_mm),
                   options.board_detection);
  if (!detection.found()) {
    out.note = "board: " + detection.message;
    return out;
  }
  out.corners_px = detection.corners_px;
  const Eigen::Isometry3d camera_from_board = internal::BoardPose(camera, out.corners_px, board, nullptr);
  // The board region: the inner-corner grid grown by the margin, sampled along its edges
  // (straight on the board, curved in a distorted image).
  const double s = board.square_mm, g = options.board_margin_squares;
  const double x0 = -g * s, y0 = -g * s, x1 = (board.cols - 1 + g) * s, y1 = (board.rows - 1 + g) * s;
  std::vector<cv::Point2f> region;
  const int kSteps = 16;
  const Eigen::Vector2d outline[4] = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
  for (int e = 0; e < 4; ++e) {
    for (int k = 0; k < kSteps; ++k) {
      const Eigen::Vector2d b =
          outline[e] + (outline[(e + 1) % 4] - outline[e]) * (static_cast<double>(k) / kSteps);
      const Eigen::Vector2d q = camera.Project(camera_from_board * Eigen::Vector3d(b.x(), b.y(), 0.0));
      region.emplace_back(static_cast<float>(q.x()), static_cast<float>(q.y()));
    }
  }
  std::vector<cv::Point2f> hull;
  cv::convexHull(region, hull);
  const cv::Mat laser = internal::LaserChannel(image, options.laser_color);
  auto by_columns = internal::StripePeaks(laser, hull, false, options);
  auto by_rows = internal::StripePeaks(laser, hull, true, options);
  out.scan_along_rows = by_rows.size() > by_columns.size();
  out.stripe_px = out.scan_along_rows ? std::move(by_rows) : std::move(by_columns);
  if (static_cast<int>(out.stripe_px.size()) < options.min_peaks_per_image) {
    out.note = "laser stripe not found on the board (" + std::to_string(out.stripe_px.size()) +
               " peaks, need " + std::to_string(options.min_peaks_per_image) + ")";
    out.stripe_px.clear();
    return out;
  }
  out.note = std::string("stripe: one peak per image ") + (out.scan_along_rows ? "row" : "column");
  return out;
}

LaserPlaneResult CalibrateLaserPlaneFromStripes(const CameraModel& camera,
                                                const std::vector<StripeImage>& images,
                                                const ChessboardSpec& board,
                                                const StripeOptions& options) {
  std::vector<StripeObservation> observations;
  for (const StripeImage& image : images) observations.push_back(DetectStripe(camera, image, board, options));
  return CalibrateLaserPlaneFromStripeObservations(camera, observations, board, options);
}

LaserPlaneResult CalibrateLaserPlaneFromStripeObservations(
    const CameraModel& camera, const std::vector<StripeObservation>& observations,
    const ChessboardSpec& board, const StripeOptions& options) {
  options.Check();
  if (board.cols < 2 || board.rows < 2 || !(board.square_mm > 0)) {
    throw OptionError("board must have >= 2 x 2 inner corners and a positive square size");
  }
  const auto& images = observations;
  LaserPlaneResult result;
  result.method = "stripe_chessboard";
  std::vector<Eigen::Vector3d> points, rays;
  std::vector<Eigen::Vector2d> pixels;
  std::vector<int> owner;
  std::map<int, ImagePoints> views;
  int usable = 0;
  for (std::size_t i = 0; i < images.size(); ++i) {
    const StripeObservation& observation = observations[i];
    LaserPlaneItem item;
    item.name = observation.name;
    item.note = observation.note;
    item.scan_along_rows = observation.scan_along_rows;
    ImagePoints found;
    const bool complete = observation.corners_px.size() == static_cast<std::size_t>(board.cols * board.rows);
    if (!observation.corners_px.empty() && !complete) {
      item.note = "has " + std::to_string(observation.corners_px.size()) + " corners, the board " +
                  std::to_string(board.cols * board.rows);
    }
    if (complete && static_cast<int>(observation.stripe_px.size()) >= options.min_peaks_per_image) {
      found = StripePoints(camera, observation, board, item);
    } else if (complete && item.note.empty()) {
      item.note = "too few stripe peaks (" + std::to_string(observation.stripe_px.size()) + ")";
    }
    if (!found.points.empty()) {
      views[static_cast<int>(i)] = found;
      item.used = true;
      item.points = static_cast<int>(found.points.size());
      ++usable;
      for (std::size_t k = 0; k < found.points.size(); ++k) {
        points.push_back(found.points[k]);
        rays.push_back(found.rays[k]);
        pixels.push_back(found.pixels[k]);
        owner.push_back(static_cast<int>(i));
      }
    }
    result.items.push_back(item);
  }
  if (usable < 2) {
    std::string why;
    for (const auto& item : result.items) {
      if (!item.used) why += "; " + item.name + ": " + item.note;
    }
    throw InputError("fewer than 2 usable stripe images (" + std::to_string(usable) + " of " +
                     std::to_string(images.size()) +
                     "): the plane needs the stripe on the board in >= 2 board poses" + why);
  }
  // Start by total least squares, then Ceres; drop gross outliers once (robust sigma).
  internal::TlsPlane start = internal::FitPlaneTls(points);
  PlaneFit fit = FitPoints(points, owner, start.normal, start.offset_mm, -1);
  std::vector<double> abs_res;
  for (const auto& p : points) abs_res.push_back(std::abs(fit.normal.dot(p) + fit.offset));
  const double robust_sigma = 1.4826 * Median(abs_res);
  std::vector<Eigen::Vector3d> kept_points, kept_rays;
  std::vector<Eigen::Vector2d> kept_pixels;
  std::vector<int> kept_owner;
  for (std::size_t k = 0; k < points.size(); ++k) {
    if (abs_res[k] <= options.outlier_sigmas * robust_sigma || robust_sigma == 0) {
      kept_points.push_back(points[k]);
      kept_rays.push_back(rays[k]);
      kept_pixels.push_back(pixels[k]);
      kept_owner.push_back(owner[k]);
    }
  }
  if (kept_points.size() < points.size()) {
    result.warnings.push_back(std::to_string(points.size() - kept_points.size()) +
                              " stripe points farther than " + Num(options.outlier_sigmas) +
                              " robust sigmas from the plane were dropped");
    fit = FitPoints(kept_points, kept_owner, fit.normal, fit.offset, -1);
  }
  // Points of one view share its board-pose error, so the covariance of this point fit is
  // optimistic. Refine plane and board poses jointly (Zhou & Zhang 2005): its covariance carries
  // the pose uncertainty, and the points are re-intersected with the refined boards.
  if (options.joint_refinement) {
    std::map<int, ImagePoints> kept_views;
    for (auto& [i, v] : views) {
      ImagePoints kv = v;
      kv.rays.clear();
      kv.pixels.clear();
      kv.points.clear();
      kept_views[i] = kv;
    }
    for (std::size_t k = 0; k < kept_points.size(); ++k) {
      ImagePoints& kv = kept_views[kept_owner[k]];
      kv.rays.push_back(kept_rays[k]);
      kv.pixels.push_back(kept_pixels[k]);
    }
    double corner_rms = 0;
    for (const auto& item : result.items) corner_rms += item.used ? item.reprojection_rms_px / usable : 0.0;
    const Eigen::Vector2d focal(camera.intrinsics()[0], camera.intrinsics()[1]);
    std::map<int, Eigen::Isometry3d> refined;
    double stripe_rms = 0;
    for (const auto& p : kept_points) stripe_rms += std::pow(fit.normal.dot(p) + fit.offset, 2);
    stripe_rms = std::sqrt(stripe_rms / static_cast<double>(kept_points.size()));
    const PlaneFit joint = JointStripeFit(kept_views, board, focal, fit.normal, fit.offset,
                                          std::max(corner_rms, 0.01), std::max(stripe_rms, 1e-3), &refined);
    if (joint.converged && joint.covariance_ok) {
      fit = joint;
      for (std::size_t k = 0; k < kept_points.size(); ++k) {
        const Eigen::Isometry3d& pose = refined[kept_owner[k]];
        const Eigen::Vector3d m = pose.linear().col(2);
        const auto p = internal::IntersectRayPlane(kept_rays[k], m, -m.dot(pose.translation()));
        if (p) kept_points[k] = *p;
      }
    } else {
      result.warnings.push_back("the joint refinement of plane and board poses failed (" + joint.termination +
                                "); the plane and its covariance come from the point fit and are optimistic");
    }
  }
  FillPlane(fit, result);
  std::vector<double> item_sum(images.size(), 0);
  std::vector<int> item_count(images.size(), 0);
  double sum = 0;
  for (std::size_t k = 0; k < kept_points.size(); ++k) {
    const double r = fit.normal.dot(kept_points[k]) + fit.offset;
    result.residuals.push_back({kept_owner[k], kept_pixels[k], kept_points[k], r});
    sum += r * r;
    item_sum[static_cast<std::size_t>(kept_owner[k])] += r * r;
    ++item_count[static_cast<std::size_t>(kept_owner[k])];
  }
  result.points = static_cast<int>(kept_points.size());
  result.rms_mm = std::sqrt(sum / std::max<std::size_t>(1, kept_points.size()));
  const PlaneFit loo_reference =
      usable >= 3 ? FitPoints(kept_points, kept_owner, fit.normal, fit.offset, -1) : fit;
  for (std::size_t i = 0; i < result.items.size(); ++i) {
    LaserPlaneItem& item = result.items[i];
    if (!item.used) continue;
    item.points = item_count[i];
    item.rms_mm = item_count[i] > 0 ? std::sqrt(item_sum[i] / item_count[i]) : 0.0;
    if (usable < 3) {
      item.loo_normal_change_deg = item.loo_offset_change_mm = item.loo_max_displacement_mm = kNaN;
      continue;
    }
    // Leave-one-out on point fits (cheap) over the final points: the change without this view.
    const PlaneFit loo = FitPoints(kept_points, kept_owner, loo_reference.normal, loo_reference.offset,
                                   static_cast<int>(i));
    LooChange(loo_reference.normal, loo_reference.offset, loo.normal, loo.offset, kept_points, item);
  }
  SummarizeLoo(result);
  // Rays of every image in one plane through the camera centre: the points are on the laser
  // plane (the board planes place them) but the plane passes through the camera.
  FlagConditioning(result, kept_rays, options.min_triangulation_angle_deg);
  if (!result.converged) result.warnings.push_back("the solver did not converge: " + result.termination);
  return result;
}

}  // namespace lasercell::calib
