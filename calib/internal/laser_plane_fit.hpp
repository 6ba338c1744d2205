#pragma once
// Private pieces shared by the two laser-plane methods (calib/laser_plane_heights.cpp,
// calib/laser_plane_stripe.cpp): the Ceres solve of a plane {n on a SphereManifold<3>, d} with
// its covariance, filling the result, the conditioning flag and the leave-one-out summaries.
// Definitions in calib/laser_plane.cpp.

#include <ceres/ceres.h>

#include <Eigen/Core>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "calib/laser_plane.hpp"

namespace lasercell::calib::internal {

inline constexpr double kRadToDeg = 180.0 / M_PI;
inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// `v` with `precision` significant digits (ostream default format), for messages.
std::string Num(double v, int precision = 4);

/// Covariance settings shared by the plane fits: dense SVD with a pseudo-inverse, so a
/// degenerate problem gives huge sigmas instead of failing.
ceres::Covariance::Options PlaneCovarianceOptions();

/// The covariance blocks PlaneCovariance reads for the plane {n[3], d}.
std::vector<std::pair<const double*, const double*>> PlaneCovarianceBlocks(const double* n,
                                                                           const double* d);

/// Ambient 4x4 covariance of the plane {n, d}, scaled by `scale` and symmetrized; `covariance`
/// must have been computed over PlaneCovarianceBlocks(n, d).
Eigen::Matrix4d PlaneCovariance(const ceres::Covariance& covariance, const double* n,
                                const double* d, double scale);

/// The solution of one Ceres plane fit.
struct PlaneFit {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitY();
  double offset = 0;
  double zero_distance = 0;  ///< D0 (heights method).
  double tilt = 0;           ///< Plate tilt (heights method), rad.
  double tilt_variance = 0;
  Eigen::Matrix4d covariance = Eigen::Matrix4d::Zero();
  double zero_distance_variance = 0;
  bool converged = false;
  bool covariance_ok = false;
  int iterations = 0;
  std::string termination;
};

/// Solver settings shared by the plane fits: tight tolerances, at most 100 iterations, one thread.
ceres::Solver::Options PlaneSolverOptions(ceres::LinearSolverType linear_solver);

/// Solves `problem` (whose plane parameter blocks are n[3] and d[1]) and records the outcome and
/// the solved plane (normal re-normalized) in `fit`; returns Ceres's final cost (half the sum of
/// squared residuals).
double SolvePlaneProblem(const ceres::Solver::Options& options, ceres::Problem& problem,
                         const double* n, const double* d, PlaneFit* fit);

/// Adds residual blocks given the parameter blocks (normal[3], offset[1], zero_distance[1],
/// tilt[1]); returns the number of residuals.
using AddResiduals = std::function<int(ceres::Problem&, double*, double*, double*, double*)>;

/// Solves, then computes the covariance scaled by the reduced chi-square; the plane is
/// oriented so that d <= 0.
PlaneFit Solve(const Eigen::Vector3d& normal0, double offset0, double zero_distance0,
               bool estimate_zero_distance, double tilt0, bool estimate_tilt,
               const AddResiduals& add);

/// Copies the plane, its covariance and sigmas and the solver outcome into the result.
void FillPlane(const PlaneFit& fit, LaserPlaneResult& r);

/// Adds the camera's uncertainty to r's covariance and sigmas (calib/camera_uncertainty.hpp):
/// `refit` solves the plane again through a perturbed camera (without propagating). Without a
/// propagatable covariance, or when !include, records why in r.camera_uncertainty_note.
void AddCameraUncertainty(
    const CameraModel& camera, bool include,
    const std::function<std::pair<Eigen::Vector3d, double>(const CameraModel&)>& refit,
    LaserPlaneResult& r);

/// Angle between two vectors, deg.
double AngleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b);

/// Sets the median ray-to-plane angle and flags the result ill-conditioned below `min_deg`.
void FlagConditioning(LaserPlaneResult& r, const std::vector<Eigen::Vector3d>& rays,
                      double min_deg);

/// Leave-one-out change between two planes, and the largest displacement over points.
void LooChange(const Eigen::Vector3d& n0, double d0, const Eigen::Vector3d& n1, double d1,
               const std::vector<Eigen::Vector3d>& points, LaserPlaneItem& item);

/// The result's leave-one-out maxima over the used items (NaN when none could be refit).
void SummarizeLoo(LaserPlaneResult& r);

}  // namespace lasercell::calib::internal
