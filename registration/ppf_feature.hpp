#pragma once
// Point pair features (Drost, Ulrich, Navab, Ilic 2010, "Model Globally, Match Locally", Sec. 3).
// Conventions: points in mm, normals unit, angles in rad.
//  - F(m1, m2) = (|d|, angle(n1, d), angle(n2, d), angle(n1, n2)) with d = m2 - m1  (eq. 1).
//  - T(m1) = the rigid map that moves m1 to the origin and turns n1 onto +x (Sec. 3.3):
//    T(m1) p = R(n1) (p - m1), R(n1) from RotationNormalToX.
//  - The pair's plane angle phi(m1, m2) = atan2(z, y) of T(m1) m2: the angle of m2 about +x.
//    For a model pair (m_r, m_i) and a scene pair (s_r, s_i) with the same feature, the rotation
//    about x that aligns them is alpha = phi_s - phi_m, and the local coordinates (m_r, alpha)
//    give scene_from_model = T(s_r)^-1 R_x(alpha) T(m_r)  (eq. 2-3; alpha split as in Sec. 3.5).

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <numbers>

namespace lasercell::registration {

/// The four-dimensional point pair feature (Drost 2010 eq. 1); distance mm, angles rad in [0, pi].
struct PpfFeature {
  double distance_mm = 0.0;
  double angle_n1_d = 0.0;
  double angle_n2_d = 0.0;
  double angle_n1_n2 = 0.0;
};

/// Angle between two unit vectors, rad in [0, pi] (acos of the clamped dot product).
inline double AngleBetweenUnit(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::clamp(a.dot(b), -1.0, 1.0));
}

/// F(p1, p2) for unit normals n1, n2 (Drost 2010 eq. 1). For coincident points the d-angles
/// are reported as 0.
inline PpfFeature ComputePpf(const Eigen::Vector3d& p1, const Eigen::Vector3d& n1,
                             const Eigen::Vector3d& p2, const Eigen::Vector3d& n2) {
  PpfFeature f;
  const Eigen::Vector3d d = p2 - p1;
  f.distance_mm = d.norm();
  if (f.distance_mm > 0.0) {
    const Eigen::Vector3d u = d / f.distance_mm;
    f.angle_n1_d = AngleBetweenUnit(n1, u);
    f.angle_n2_d = AngleBetweenUnit(n2, u);
  }
  f.angle_n1_n2 = AngleBetweenUnit(n1, n2);
  return f;
}

/// Rotation R with R n = +x for a unit normal n (axis n x e_x, Rodrigues); rotation by pi
/// about y when n is (close to) -x. Deterministic: the same n always gives the same R.
inline Eigen::Matrix3d RotationNormalToX(const Eigen::Vector3d& n) {
  const Eigen::Vector3d axis(0.0, n.z(), -n.y());  // n x e_x
  const double s2 = axis.squaredNorm();
  const double c = n.x();
  if (s2 < 1e-20) {
    if (c > 0.0) return Eigen::Matrix3d::Identity();
    return Eigen::Vector3d(-1.0, 1.0, -1.0).asDiagonal();
  }
  Eigen::Matrix3d k;
  k << 0.0, -axis.z(), axis.y(), axis.z(), 0.0, -axis.x(), -axis.y(), axis.x(), 0.0;
  return Eigen::Matrix3d::Identity() + k + k * k * ((1.0 - c) / s2);
}

/// phi(p1, p2) = angle of R (p2 - p1) about +x, atan2(z, y), rad in (-pi, pi], where
/// R = RotationNormalToX(n1).
inline double PairPlaneAngle(const Eigen::Matrix3d& rotation_n1_to_x, const Eigen::Vector3d& p1,
                             const Eigen::Vector3d& p2) {
  const Eigen::Vector3d d = p2 - p1;
  const double y = rotation_n1_to_x.row(1).dot(d);
  const double z = rotation_n1_to_x.row(2).dot(d);
  return std::atan2(z, y);
}

/// Wraps an angle to [0, 2 pi).
inline double WrapTwoPi(double angle) {
  constexpr double kTwoPi = 2.0 * std::numbers::pi;
  angle = std::fmod(angle, kTwoPi);
  return angle < 0.0 ? angle + kTwoPi : angle;
}

}  // namespace lasercell::registration
