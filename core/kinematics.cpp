#include "core/kinematics.hpp"

#include <cmath>
#include <numbers>
#include <string>
#include <utility>

#include "core/error.hpp"

namespace lasercell {

namespace {

/// One DH link transform link_{i-1}_from_link_i for joint angle theta (rad).
Eigen::Isometry3d DhLinkTransform(DhConvention convention, const DhJoint& row, double theta) {
  const double ct = std::cos(theta);
  const double st = std::sin(theta);
  const double ca = std::cos(row.alpha_rad);
  const double sa = std::sin(row.alpha_rad);
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  if (convention == DhConvention::kStandard) {
    // RotZ(theta) * TransZ(d) * TransX(a) * RotX(alpha), multiplied out (Spong et al. 2006,
    // eq. 3.10).
    // clang-format off
    t.linear() << ct, -st * ca,  st * sa,
                  st,  ct * ca, -ct * sa,
                  0,   sa,       ca;
    // clang-format on
    t.translation() << row.a_mm * ct, row.a_mm * st, row.d_mm;
  } else {
    // RotX(alpha_{i-1}) * TransX(a_{i-1}) * RotZ(theta) * TransZ(d) (Craig 1986, eq. 3.6).
    // clang-format off
    t.linear() << ct,      -st,      0,
                  st * ca,  ct * ca, -sa,
                  st * sa,  ct * sa,  ca;
    // clang-format on
    t.translation() << row.a_mm, -sa * row.d_mm, ca * row.d_mm;
  }
  return t;
}

std::string ConventionName(DhConvention convention) {
  return convention == DhConvention::kStandard ? "standard" : "modified";
}

/// A mount given as a matrix, checked and converted once.
QuaternionPose MountFromMatrix(const Eigen::Isometry3d& mount, const char* name) {
  CheckRigidTransform(mount, std::string("DH chain ") + name);
  return QuaternionPose::FromIsometry(mount);
}

}  // namespace

DhChain::DhChain(DhConvention convention, std::vector<DhJoint> joints,
                 const Eigen::Isometry3d& base_from_chain,
                 const Eigen::Isometry3d& chain_from_flange)
    : DhChain(convention, std::move(joints), MountFromMatrix(base_from_chain, "base_from_chain"),
              MountFromMatrix(chain_from_flange, "chain_from_flange")) {}

DhChain::DhChain(DhConvention convention, std::vector<DhJoint> joints,
                 const QuaternionPose& base_from_chain, const QuaternionPose& chain_from_flange)
    : convention_(convention), joints_(std::move(joints)) {
  for (std::size_t i = 0; i < joints_.size(); ++i) {
    const DhJoint& j = joints_[i];
    if (!std::isfinite(j.a_mm) || !std::isfinite(j.alpha_rad) || !std::isfinite(j.d_mm) ||
        !std::isfinite(j.theta_offset_rad) || !std::isfinite(j.joint_offset_rad)) {
      throw InputError("DH chain (" + ConventionName(convention_) + "): joint " +
                       std::to_string(i + 1) +
                       " has a non-finite value (a_mm, alpha_rad, d_mm or an offset); "
                       "every DH parameter must be a finite number in mm or rad");
    }
  }
  set_base_from_chain(base_from_chain);
  set_chain_from_flange(chain_from_flange);
}

void DhChain::set_base_from_chain(const Eigen::Isometry3d& base_from_chain) {
  set_base_from_chain(MountFromMatrix(base_from_chain, "base_from_chain"));
}

void DhChain::set_chain_from_flange(const Eigen::Isometry3d& chain_from_flange) {
  set_chain_from_flange(MountFromMatrix(chain_from_flange, "chain_from_flange"));
}

void DhChain::set_base_from_chain(const QuaternionPose& base_from_chain) {
  CheckQuaternionPose(base_from_chain, "DH chain base_from_chain");
  base_from_chain_ = base_from_chain;
  base_from_chain_matrix_ = base_from_chain_.ToIsometry();
}

void DhChain::set_chain_from_flange(const QuaternionPose& chain_from_flange) {
  CheckQuaternionPose(chain_from_flange, "DH chain chain_from_flange");
  chain_from_flange_ = chain_from_flange;
  chain_from_flange_matrix_ = chain_from_flange_.ToIsometry();
}

std::vector<Eigen::Isometry3d> DhChain::LinkPoses(std::span<const double> joints_rad) const {
  const std::size_t n = joints_.size();
  if (joints_rad.size() != n) {
    throw InputError("DH chain: got " + std::to_string(joints_rad.size()) +
                     " joint values, expected " + std::to_string(n) +
                     " (one angle in rad per joint of the chain)");
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(joints_rad[i])) {
      throw InputError("DH chain: joint value " + std::to_string(i + 1) + " of " +
                       std::to_string(n) + " is not finite (" + std::to_string(joints_rad[i]) +
                       "); pass " + std::to_string(n) + " finite joint angles in rad");
    }
  }
  std::vector<Eigen::Isometry3d> poses;
  poses.reserve(n);
  Eigen::Isometry3d base_from_link = base_from_chain_matrix_;
  for (std::size_t i = 0; i < n; ++i) {
    const DhJoint& row = joints_[i];
    const double theta = joints_rad[i] + row.theta_offset_rad + row.joint_offset_rad;
    base_from_link = base_from_link * DhLinkTransform(convention_, row, theta);
    poses.push_back(base_from_link);
  }
  return poses;
}

Eigen::Isometry3d DhChain::BaseFromFlange(std::span<const double> joints_rad) const {
  const std::vector<Eigen::Isometry3d> links = LinkPoses(joints_rad);
  const Eigen::Isometry3d& base_from_last = links.empty() ? base_from_chain_matrix_ : links.back();
  return base_from_last * chain_from_flange_matrix_;
}

std::unique_ptr<KinematicModel> DhChain::Clone() const { return std::make_unique<DhChain>(*this); }

DhParameterKind DhParameterKindAt(int index, int joints) {
  if (joints <= 0 || index < 0 || index >= NumDhParameters(joints)) {
    throw InputError("DH parameter index " + std::to_string(index) + " is out of range for a " +
                     std::to_string(joints) + "-joint chain (0 .. " +
                     std::to_string(NumDhParameters(joints) - 1) + ")");
  }
  return static_cast<DhParameterKind>(index / joints);
}

std::string DhParameterName(int index, int joints) {
  static constexpr const char* kNames[] = {"joint_offset_", "a_", "d_", "alpha_"};
  const DhParameterKind kind = DhParameterKindAt(index, joints);
  return kNames[static_cast<int>(kind)] + std::to_string(index % joints + 1);
}

std::vector<double> DhParameterVector(const DhChain& chain) {
  const std::size_t n = chain.joints().size();
  std::vector<double> p(4 * n);
  for (std::size_t i = 0; i < n; ++i) {
    const DhJoint& j = chain.joints()[i];
    p[i] = j.joint_offset_rad;
    p[n + i] = j.a_mm;
    p[2 * n + i] = j.d_mm;
    p[3 * n + i] = j.alpha_rad;
  }
  return p;
}

DhChain WithDhParameters(const DhChain& chain, std::span<const double> parameters) {
  const std::size_t n = chain.joints().size();
  if (parameters.size() != 4 * n) {
    throw InputError("DH parameters: got " + std::to_string(parameters.size()) +
                     " values, expected " + std::to_string(4 * n) +
                     " (joint offsets, a, d, alpha)");
  }
  std::vector<DhJoint> joints = chain.joints();
  for (std::size_t i = 0; i < n; ++i) {
    joints[i].joint_offset_rad = parameters[i];
    joints[i].a_mm = parameters[n + i];
    joints[i].d_mm = parameters[2 * n + i];
    joints[i].alpha_rad = parameters[3 * n + i];
  }
  // The constructor checks finiteness; the mounts are copied exactly as stored.
  return DhChain(chain.convention(), std::move(joints), chain.base_from_chain_stored(),
                 chain.chain_from_flange_stored());
}

DhChain NominalUr5() {
  constexpr double kHalfPi = std::numbers::pi / 2;
  // Universal Robots, "DH parameters for calculations of kinematics and dynamics" (UR5, CB3).
  std::vector<DhJoint> joints(6);
  joints[0].d_mm = 89.159;
  joints[0].alpha_rad = kHalfPi;
  joints[1].a_mm = -425.0;
  joints[2].a_mm = -392.25;
  joints[3].d_mm = 109.15;
  joints[3].alpha_rad = kHalfPi;
  joints[4].d_mm = 94.65;
  joints[4].alpha_rad = -kHalfPi;
  joints[5].d_mm = 82.3;
  return DhChain(DhConvention::kStandard, std::move(joints));
}

}  // namespace lasercell
