// Positioning covariance of an identified robot (calib/robot_positioning.hpp): the hand-eye
// terms against their closed forms, parameters that do not move the point, bad input. Its
// statistical check against held-out poses is JointIdentification.ReportedSigmaCoversTheTruth.

#include "calib/robot_positioning.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.hpp"
#include "core/se3.hpp"
#include "datasets/robots.hpp"

namespace lasercell::calib {
namespace {

using ::testing::HasSubstr;

Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

// A result with the hand-eye estimated, a sphere centre and the radius (which move nothing).
JointIdentificationResult HandEyeResult(const Matrix6d& hand_eye_covariance) {
  JointIdentificationResult r;
  r.robot = NominalUr5();
  r.flange_from_sensor =
      PoseFromRotationVector(Eigen::Vector3d(0.3, -0.2, 1.4), Eigen::Vector3d(12, -95, 160));
  r.covariance_names = {"hand_eye_rx", "hand_eye_ry", "hand_eye_rz", "hand_eye_tx", "hand_eye_ty",
                        "hand_eye_tz", "centre_0_x",  "centre_0_y",  "centre_0_z",  "radius"};
  r.covariance = Eigen::MatrixXd::Identity(10, 10) * 4.0;  // centres and radius: 2 mm sigma
  r.covariance.topLeftCorner<6, 6>() = hand_eye_covariance;
  return r;
}

// p_base = B (Exp(w) (R0 p + t0) + u): d/du = R_B, d/dw = -R_B [R0 p + t0]x, so
// Sigma_p = R_B (K Sigma_w K^T + Sigma_u) R_B^T with K = -[p_flange]x (cross terms included).
TEST(PointCovarianceInBase, HandEyeTermsMatchTheirClosedForm) {
  Eigen::Matrix<double, 6, 6> a = Eigen::Matrix<double, 6, 6>::Random();
  Matrix6d cov = a * a.transpose() * 1e-4;
  cov.topLeftCorner<3, 3>() *= 1e-4;  // rad^2: ~0.01 deg against ~0.1 mm
  const JointIdentificationResult r = HandEyeResult(cov);
  const std::vector<double> q = {0.4, -1.6, 1.7, -1.5, -1.6, 0.3};
  const Eigen::Vector3d p(5, -20, 650);
  const Eigen::Isometry3d base_from_flange = r.robot.BaseFromFlange(q);
  Eigen::Matrix<double, 3, 6> jac;
  jac.leftCols<3>() = -base_from_flange.linear() * Skew(r.flange_from_sensor * p);
  jac.rightCols<3>() = base_from_flange.linear();
  const Eigen::Matrix3d expected = jac * cov * jac.transpose();
  const Eigen::Matrix3d got = PointCovarianceInBase(r, q, p);
  EXPECT_LT((got - expected).norm(), 1e-6 * expected.norm()) << got << "\n\n" << expected;
}

TEST(PointCovarianceInBase, NothingEstimatedThatMovesThePointGivesZero) {
  JointIdentificationResult r = HandEyeResult(Matrix6d::Zero());
  const std::vector<double> q = {0.4, -1.6, 1.7, -1.5, -1.6, 0.3};
  EXPECT_EQ(PointCovarianceInBase(r, q, Eigen::Vector3d(0, 0, 700)), Eigen::Matrix3d::Zero());
  // A joint offset moves it: the working point 700 mm out swings about joint 1's axis.
  r.covariance_names[6] = "joint_offset_1";
  r.covariance = Eigen::MatrixXd::Zero(10, 10);
  r.covariance(6, 6) = 1e-8;  // 1e-4 rad
  const Eigen::Matrix3d c = PointCovarianceInBase(r, q, Eigen::Vector3d(0, 0, 700));
  const Eigen::Vector3d p =
      r.robot.BaseFromFlange(q) * (r.flange_from_sensor * Eigen::Vector3d(0, 0, 700));
  // Joint 1 turns about base z through the origin: dp = z x p per rad.
  const Eigen::Vector3d dp = Eigen::Vector3d::UnitZ().cross(p);
  EXPECT_LT((c - 1e-8 * dp * dp.transpose()).norm(), 1e-6 * c.norm()) << c;
}

TEST(PointCovarianceInBase, RejectsBadInput) {
  const JointIdentificationResult r = HandEyeResult(Matrix6d::Identity() * 1e-6);
  try {
    PointCovarianceInBase(r, {0.1, 0.2}, Eigen::Vector3d(0, 0, 700));
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("2 joint values for a 6-joint robot"));
  }
  EXPECT_THROW(PointCovarianceInBase(r, {0, 0, 0, 0, 0, std::nan("")}, Eigen::Vector3d::Zero()),
               InputError);
  JointIdentificationResult misnamed = r;
  misnamed.covariance_names[2] = "hand_eye_yz";
  try {
    PointCovarianceInBase(misnamed, {0, 0, 0, 0, 0, 0}, Eigen::Vector3d::Zero());
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("unknown covariance parameter 'hand_eye_yz'"));
  }
  JointIdentificationResult wrong = r;
  wrong.covariance_names.pop_back();
  try {
    PointCovarianceInBase(wrong, {0, 0, 0, 0, 0, 0}, Eigen::Vector3d::Zero());
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("10x10 for 9 named parameters"));
  }
}

}  // namespace
}  // namespace lasercell::calib
