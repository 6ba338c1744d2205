#include "calib/laser_hand_eye.hpp"

#include <cmath>
#include <cstdio>
#include <numbers>

namespace lasercell::calib {

std::string LaserHandEyeResult::Summary() const {
  char buf[300];
  std::snprintf(buf, sizeof(buf),
                "%s, rms %.4f mm over %zu points, %zu sweeps; 1-sigma %.4f mm / %.5f deg; "
                "positioning 1-sigma %.4f mm (hand-eye only, robot held)",
                converged ? "converged" : "NOT converged", rms_mm, points_used, sweeps.size(),
                std::sqrt(covariance.bottomRightCorner<3, 3>().trace()),
                std::sqrt(covariance.topLeftCorner<3, 3>().trace()) * 180 / std::numbers::pi,
                positioning.rms_mm);
  return buf;
}

LaserHandEyeResult CalibrateLaserHandEye(const DhChain& robot,
                                         const Eigen::Isometry3d& initial_flange_from_sensor,
                                         const std::vector<SphereSweep>& sweeps,
                                         const LaserHandEyeOptions& options) {
  options.Check();
  JointIdentificationOptions o = options.solver;
  o.estimate_joint_offsets = false;
  o.estimate_dh_deltas = false;
  o.estimate_hand_eye = true;
  const JointIdentificationResult r = IdentifyRobot(robot, initial_flange_from_sensor, sweeps, o);
  LaserHandEyeResult out;
  out.converged = r.converged;
  out.flange_from_sensor = r.flange_from_sensor;
  out.covariance = *r.flange_from_sensor_covariance;
  out.sphere_centres_in_base = r.sphere_centres_in_base;
  out.sphere_centre_sigmas = r.sphere_centre_sigmas;
  out.radius_mm = r.radius_mm;
  out.radius_sigma_mm = r.radius_sigma_mm;
  out.rms_mm = r.rms_mm;
  out.points_used = r.points_used;
  out.sweeps = r.sweeps;
  out.residuals_mm = r.residuals_mm;
  out.observability = r.observability;
  out.positioning = r.positioning;
  out.warnings = r.warnings;
  return out;
}

}  // namespace lasercell::calib
