// Laser-plane calibration, the parts both methods share: option checks, the result summary and
// the refusal policy, and the Ceres plane solve with its covariance and leave-one-out summaries
// (calib/internal/laser_plane_fit.hpp). The methods: calib/laser_plane_heights.cpp (white plane
// at known heights) and calib/laser_plane_stripe.cpp (stripe on a chessboard, Zhou & Zhang 2005).

#include "calib/laser_plane.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "calib/camera_uncertainty.hpp"
#include "calib/internal/laser_geometry.hpp"
#include "calib/internal/laser_plane_fit.hpp"
#include "core/error.hpp"
#include "core/stats.hpp"

namespace lasercell::calib {

namespace internal {

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

std::string Num(double v, int precision) {
  std::ostringstream s;
  s.precision(precision);
  s << v;
  return s.str();
}

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
  if (count == 0 || !problem.HasParameterBlock(n)) {
    fit.termination = "no observation survived to constrain the plane";
    return fit;  // converged == false: the caller reports the failure
  }
  problem.SetManifold(n, new ceres::SphereManifold<3>());
  if (problem.HasParameterBlock(&z) && !estimate_zero_distance)
    problem.SetParameterBlockConstant(&z);
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

namespace {

/// 1 sigma of the normal's direction (deg): sqrt(trace) of the [n; d] covariance's n block.
double NormalSigmaDeg(const Eigen::Matrix4d& covariance) {
  return std::sqrt(std::max(0.0, covariance.topLeftCorner<3, 3>().trace())) * kRadToDeg;
}

/// 1 sigma of d (mm).
double OffsetSigmaMm(const Eigen::Matrix4d& covariance) {
  return std::sqrt(std::max(0.0, covariance(3, 3)));
}

}  // namespace

void FillPlane(const PlaneFit& fit, LaserPlaneResult& r) {
  r.normal = fit.normal;
  r.offset_mm = fit.offset;
  r.point_mm = -fit.offset * fit.normal;
  r.covariance = fit.covariance;
  r.normal_sigma_deg = NormalSigmaDeg(fit.covariance);
  r.offset_sigma_mm = OffsetSigmaMm(fit.covariance);
  r.converged = fit.converged;
  r.iterations = fit.iterations;
  r.termination = fit.termination;
  if (!fit.covariance_ok) {
    r.warnings.push_back("the covariance could not be computed (rank-deficient problem)");
  }
}

namespace {

// The principal axes of the fit's own plane covariance as error modes (the camera unchanged).
std::vector<SensorErrorMode> FitModes(const Eigen::Matrix4d& covariance) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> eigen(covariance);
  const double largest = eigen.eigenvalues().maxCoeff();
  std::vector<SensorErrorMode> modes;
  for (int k = 3; k >= 0; --k) {  // largest first
    const double lambda = eigen.eigenvalues()(k);
    if (!(lambda > 1e-12 * largest)) continue;
    SensorErrorMode m;
    m.plane_step = std::sqrt(lambda) * eigen.eigenvectors().col(k);
    modes.push_back(std::move(m));
  }
  return modes;
}

}  // namespace

void AddCameraUncertainty(
    const CameraModel& camera, bool include,
    const std::function<std::pair<Eigen::Vector3d, double>(const CameraModel&)>& refit,
    LaserPlaneResult& r) {
  r.error_modes = FitModes(r.covariance);
  if (!include) {
    r.camera_uncertainty_note = "camera uncertainty not included (turned off)";
    return;
  }
  if (const std::string problem = CameraPropagationProblem(camera); !problem.empty()) {
    r.camera_uncertainty_note = "camera uncertainty not included: " + problem;
    return;
  }
  const Eigen::Vector3d n0 = r.normal;
  IntrinsicsAxes axes;
  try {
    axes = PropagateIntrinsicsAxes(camera, [&](const CameraModel& perturbed) {
      auto [n, d] = refit(perturbed);
      if (n.dot(n0) < 0) {  // the same orientation as the nominal plane
        n = -n;
        d = -d;
      }
      Eigen::VectorXd v(4);
      v << n, d;
      return v;
    });
  } catch (const InputError& e) {
    r.camera_uncertainty_note =
        std::string("camera uncertainty not included: a perturbed camera failed: ") + e.what();
    r.warnings.push_back(r.camera_uncertainty_note);
    return;
  }
  r.camera_covariance = axes.responses * axes.responses.transpose();
  std::vector<SensorErrorMode> modes;
  for (Eigen::Index k = 0; k < axes.responses.cols(); ++k) {
    SensorErrorMode m;
    const Eigen::VectorXd step = axes.intrinsics_steps.col(k);
    m.intrinsics_step.assign(step.data(), step.data() + step.size());
    m.plane_step = axes.responses.col(k);
    modes.push_back(std::move(m));
  }
  modes.insert(modes.end(), r.error_modes.begin(), r.error_modes.end());
  r.error_modes = std::move(modes);
  r.camera_uncertainty_included = true;
  r.covariance += r.camera_covariance;
  r.camera_normal_sigma_deg = NormalSigmaDeg(r.camera_covariance);
  r.camera_offset_sigma_mm = OffsetSigmaMm(r.camera_covariance);
  r.normal_sigma_deg = NormalSigmaDeg(r.covariance);
  r.offset_sigma_mm = OffsetSigmaMm(r.covariance);
}

double AngleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) * kRadToDeg;
}

namespace {

/// Median angle (deg) between the rays and the plane.
double MedianTriangulationAngleDeg(const std::vector<Eigen::Vector3d>& rays,
                                   const Eigen::Vector3d& normal) {
  std::vector<double> angles;
  angles.reserve(rays.size());
  for (const auto& r : rays)
    angles.push_back(std::asin(std::min(1.0, std::abs(normal.dot(r.normalized())))) * kRadToDeg);
  return Median(std::move(angles));
}

}  // namespace

void FlagConditioning(LaserPlaneResult& r, const std::vector<Eigen::Vector3d>& rays,
                      double min_deg) {
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
    r.loo_max_offset_change_mm =
        std::max(r.loo_max_offset_change_mm, std::abs(item.loo_offset_change_mm));
  }
  if (!any) {
    r.loo_max_normal_change_deg = kNaN;
    r.loo_max_offset_change_mm = kNaN;
  }
}

}  // namespace internal

using internal::Num;

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
  if (min_peaks_per_column < 1)
    throw OptionError("HeightPlaneOptions.min_peaks_per_column must be >= 1");
  if (!(min_triangulation_angle_deg >= 0 && min_triangulation_angle_deg < 90)) {
    throw OptionError("HeightPlaneOptions.min_triangulation_angle_deg must be in [0, 90)");
  }
}

void StripeOptions::Check() const {
  if (laser_color != "green" && laser_color != "red" && laser_color != "gray") {
    throw OptionError("StripeOptions.laser_color is '" + laser_color +
                      "'; expected green, red or gray");
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
    << " deg / " << Num(offset_sigma_mm, 3) << " mm";
  if (camera_uncertainty_included) {
    s << " (the camera's part " << Num(camera_normal_sigma_deg, 3) << " deg / "
      << Num(camera_offset_sigma_mm, 3) << " mm)";
  } else {
    s << " (camera uncertainty not included)";
  }
  s << "; rms " << Num(rms_mm, 3) << " mm";
  if (method == "heights") s << " (" << Num(rms_px, 3) << " px)";
  s << " over " << points << " points";
  if (!converged) s << "; NOT CONVERGED";
  if (ill_conditioned) s << "; ILL-CONDITIONED";
  return s.str();
}

std::string LaserPlaneResult::RefusalReason() const {
  if (!ill_conditioned && converged) return {};
  return warnings.empty() ? Summary() : warnings.front();
}

}  // namespace lasercell::calib
