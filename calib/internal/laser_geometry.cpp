#include "calib/internal/laser_geometry.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>

#include "core/error.hpp"

namespace lasercell::calib::internal {

void OrientPlane(Eigen::Vector3d& normal, double& offset) {
  if (offset > 0) {
    normal = -normal;
    offset = -offset;
  }
}

TlsPlane FitPlaneTls(const std::vector<Eigen::Vector3d>& points) {
  LASERCELL_CHECK(points.size() >= 3, "FitPlaneTls needs >= 3 points");
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : points) mean += p;
  mean /= static_cast<double>(points.size());
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const auto& p : points) scatter += (p - mean) * (p - mean).transpose();
  scatter /= static_cast<double>(points.size());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(scatter);
  TlsPlane plane;
  plane.normal = eig.eigenvectors().col(0).normalized();
  plane.offset_mm = -plane.normal.dot(mean);
  OrientPlane(plane.normal, plane.offset_mm);
  plane.spread_mm2 = eig.eigenvalues();
  plane.rms_mm = std::sqrt(std::max(0.0, eig.eigenvalues()(0)));
  return plane;
}

}  // namespace lasercell::calib::internal
