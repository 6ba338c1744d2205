#include "localize/laser_plane_uncertainty.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <string>

#include "core/error.hpp"

namespace lasercell::localize {

void LaserPlaneUncertainty::Check() const {
  const auto fail = [](const std::string& field, const std::string& problem) {
    throw OptionError("LaserPlaneUncertainty." + field + " " + problem);
  };
  if (!plane_in_sensor.allFinite()) fail("plane_in_sensor", "must be finite");
  if (std::abs(plane_in_sensor.head<3>().norm() - 1.0) > 1e-6) {
    fail("plane_in_sensor", "must have a unit normal");
  }
  if (!(std::abs(plane_in_sensor[3]) >= 1.0)) {
    fail("plane_in_sensor", "passes within 1 mm of the sensor origin: no triangulation baseline");
  }
  if (!covariance.allFinite()) fail("covariance", "must be finite");
  if (!covariance.isApprox(covariance.transpose(), 1e-9 * (1.0 + covariance.norm()))) {
    fail("covariance", "must be symmetric");
  }
  if (target_from_sensor.empty()) fail("target_from_sensor", "must hold a pose per profile");
  if (static_cast<bool>(mode_displacements) != (placement_response.cols() > 0)) {
    fail("mode_displacements", "and placement_response go together: give both or neither");
  }
  if (!placement_response.allFinite()) fail("placement_response", "must be finite");
}

Matrix6d LaserPlanePoseCovariance(const LaserPlaneUncertainty& plane,
                                  std::span<const Eigen::Vector3d> points,
                                  std::span<const Eigen::Vector3d> normals,
                                  std::span<const std::int32_t> profiles) {
  plane.Check();
  if (normals.size() != points.size() || profiles.size() != points.size()) {
    throw InputError("LaserPlanePoseCovariance: " + std::to_string(points.size()) + " points, " +
                     std::to_string(normals.size()) + " normals and " +
                     std::to_string(profiles.size()) + " profile indices must agree");
  }
  if (points.size() < 6) {
    throw InputError("LaserPlanePoseCovariance: " + std::to_string(points.size()) +
                     " points cannot constrain a pose (need >= 6)");
  }
  const double d = plane.plane_in_sensor[3];
  const bool modes = static_cast<bool>(plane.mode_displacements);
  const Eigen::Index k_modes = plane.placement_response.cols();
  Matrix6d h = Matrix6d::Zero();
  Eigen::Matrix<double, 6, 4> b = Eigen::Matrix<double, 6, 4>::Zero();
  Eigen::Matrix<double, 6, Eigen::Dynamic> b_modes =
      Eigen::Matrix<double, 6, Eigen::Dynamic>::Zero(6, k_modes);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const auto profile = static_cast<std::size_t>(profiles[i]);
    if (profiles[i] < 0 || profile >= plane.target_from_sensor.size()) {
      throw InputError("LaserPlanePoseCovariance: point " + std::to_string(i) +
                       " belongs to profile " + std::to_string(profiles[i]) + " but " +
                       std::to_string(plane.target_from_sensor.size()) + " sensor poses are given");
    }
    const Eigen::Isometry3d& target_from_sensor = plane.target_from_sensor[profile];
    const Eigen::Vector3d p_sensor = target_from_sensor.inverse() * points[i];
    Eigen::Matrix<double, 6, 1> a;
    a.head<3>() = points[i].cross(normals[i]);
    a.tail<3>() = normals[i];
    h.noalias() += a * a.transpose();
    if (modes) {
      const Eigen::Matrix<double, 3, Eigen::Dynamic> dp = plane.mode_displacements(p_sensor);
      LASERCELL_CHECK(dp.cols() == k_modes, "mode_displacements disagrees with the modes");
      b_modes.noalias() += a * ((normals[i].transpose() * target_from_sensor.linear()) * dp);
      continue;
    }
    // n_i^T R_i dp_i = (n_i^T R_i p_sensor) (p_sensor^T dn + dd) / d, eq. (1).
    Eigen::Matrix<double, 1, 4> dp_row;
    dp_row.head<3>() = p_sensor.transpose();
    dp_row[3] = 1.0;
    const double along_normal = normals[i].dot(target_from_sensor.linear() * p_sensor) / d;
    b.noalias() += a * (along_normal * dp_row);
  }
  // Pseudo-inverse of H: unconstrained directions (a flat patch's in-plane motion) get nothing.
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eig(h);
  const double floor = 1e-9 * eig.eigenvalues().maxCoeff();
  Eigen::Matrix<double, 6, 1> inverse = Eigen::Matrix<double, 6, 1>::Zero();
  for (int k = 0; k < 6; ++k) {
    if (eig.eigenvalues()[k] > floor) inverse[k] = 1.0 / eig.eigenvalues()[k];
  }
  const Matrix6d h_plus =
      eig.eigenvectors() * inverse.asDiagonal() * eig.eigenvectors().transpose();
  if (modes) {
    const Eigen::Matrix<double, 6, Eigen::Dynamic> x = h_plus * b_modes + plane.placement_response;
    const Matrix6d cov = x * x.transpose();
    return 0.5 * (cov + cov.transpose());
  }
  const Eigen::Matrix<double, 6, 4> a_mat = h_plus * b;
  const Matrix6d cov = a_mat * plane.covariance * a_mat.transpose();
  return 0.5 * (cov + cov.transpose());
}

}  // namespace lasercell::localize
