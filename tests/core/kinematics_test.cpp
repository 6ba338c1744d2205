// DH kinematics: the UR5 nominal chain against poses derived by hand and against an independent
// composition of elementary Eigen transforms; modified DH against its standard rewrite.

#include "core/kinematics.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <random>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "core/random.hpp"

namespace lasercell {
namespace {

using ::testing::HasSubstr;
constexpr double kPi = std::numbers::pi;

/// Max abs difference of the 3x4 parts, so a failure prints how far apart the poses are.
::testing::AssertionResult PosesNear(const Eigen::Isometry3d& actual,
                                     const Eigen::Isometry3d& expected, double tolerance) {
  const double diff =
      (actual.matrix().topRows<3>() - expected.matrix().topRows<3>()).cwiseAbs().maxCoeff();
  if (diff <= tolerance) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure()
         << "max |difference| " << diff << " > " << tolerance << "\nactual:\n"
         << actual.matrix() << "\nexpected:\n"
         << expected.matrix();
}

/// Pose with rotation given by its columns (the frame's axes in the base) and an origin.
Eigen::Isometry3d PoseFromAxes(const Eigen::Vector3d& x, const Eigen::Vector3d& y,
                               const Eigen::Vector3d& z, const Eigen::Vector3d& origin) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear().col(0) = x;
  pose.linear().col(1) = y;
  pose.linear().col(2) = z;
  pose.translation() = origin;
  return pose;
}

/// Standard DH link by composing Eigen's elementary transforms (not the closed form).
Eigen::Isometry3d ElementaryStandard(double theta, double d, double a, double alpha) {
  return Eigen::Isometry3d(Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitZ()) *
                           Eigen::Translation3d(0, 0, d) * Eigen::Translation3d(a, 0, 0) *
                           Eigen::AngleAxisd(alpha, Eigen::Vector3d::UnitX()));
}

Eigen::Isometry3d ElementaryModified(double alpha, double a, double theta, double d) {
  return Eigen::Isometry3d(
      Eigen::AngleAxisd(alpha, Eigen::Vector3d::UnitX()) * Eigen::Translation3d(a, 0, 0) *
      Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitZ()) * Eigen::Translation3d(0, 0, d));
}

// UR5 table, typed in again here so a typo in NominalUr5 cannot hide.
constexpr double kD1 = 89.159, kA2 = -425.0, kA3 = -392.25, kD4 = 109.15, kD5 = 94.65, kD6 = 82.3;

Eigen::Isometry3d Ur5Reference(const std::vector<double>& q) {
  const double d[6] = {kD1, 0, 0, kD4, kD5, kD6};
  const double a[6] = {0, kA2, kA3, 0, 0, 0};
  const double alpha[6] = {kPi / 2, 0, 0, kPi / 2, -kPi / 2, 0};
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  for (int i = 0; i < 6; ++i) t = t * ElementaryStandard(q[i], d[i], a[i], alpha[i]);
  return t;
}

Eigen::Isometry3d RandomPose(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  const Eigen::Vector3d axis = Draws<3>(n, rng).normalized();
  Eigen::Isometry3d pose(Eigen::AngleAxisd(2.0 * n(rng), axis));
  pose.translation() = 200.0 * Draws<3>(n, rng);
  return pose;
}

TEST(KinematicsTest, Ur5AtZeroMatchesPublishedGeometry) {
  const DhChain ur5 = NominalUr5();
  ASSERT_EQ(ur5.NumJoints(), 6);
  // Derived by hand: at zero the arm lies along -x, the wrist offsets d4 + d6 point along -y,
  // d5 points down; the flange axes are x = x0, y = z0, z = -y0.
  const Eigen::Isometry3d expected =
      PoseFromAxes({1, 0, 0}, {0, 0, 1}, {0, -1, 0}, {-817.25, -191.45, -5.491});
  EXPECT_TRUE(PosesNear(ur5.BaseFromFlange(std::vector<double>(6, 0.0)), expected, 1e-6));
}

TEST(KinematicsTest, Ur5HandDerivedConfigurations) {
  const DhChain ur5 = NominalUr5();
  // Base joint +90 deg: the zero pose rotated about z0.
  const Eigen::Isometry3d zero =
      PoseFromAxes({1, 0, 0}, {0, 0, 1}, {0, -1, 0}, {-817.25, -191.45, -5.491});
  const Eigen::Isometry3d rz(Eigen::AngleAxisd(kPi / 2, Eigen::Vector3d::UnitZ()));
  EXPECT_TRUE(
      PosesNear(ur5.BaseFromFlange(std::vector<double>{kPi / 2, 0, 0, 0, 0, 0}), rz * zero, 1e-6));
  // Shoulder -90 deg: upper arm and forearm point straight up (z = d1 - a2 - a3), the wrist
  // then offsets d5 along -x and d4 + d6 along -y; flange x = -z0, y = x0, z = -y0.
  EXPECT_TRUE(PosesNear(
      ur5.BaseFromFlange(std::vector<double>{0, -kPi / 2, 0, 0, 0, 0}),
      PoseFromAxes({0, 0, -1}, {1, 0, 0}, {0, -1, 0}, {-kD5, -(kD4 + kD6), kD1 - kA2 - kA3}),
      1e-6));
  // Wrist 2 +90 deg: the last link d6 turns from -y to -x; flange x = -y0, y = z0, z = -x0.
  EXPECT_TRUE(PosesNear(
      ur5.BaseFromFlange(std::vector<double>{0, 0, 0, 0, kPi / 2, 0}),
      PoseFromAxes({0, -1, 0}, {0, 0, 1}, {-1, 0, 0}, {kA2 + kA3 - kD6, -kD4, kD1 - kD5}), 1e-6));
  // Wrist 3 only spins the flange about its z axis (-y0): position unchanged.
  const Eigen::Isometry3d spun = ur5.BaseFromFlange(std::vector<double>{0, 0, 0, 0, 0, 0.7});
  EXPECT_NEAR((spun.translation() - zero.translation()).norm(), 0.0, 1e-9);
  EXPECT_TRUE(PosesNear(
      spun, zero * Eigen::Isometry3d(Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ())), 1e-9));
}

TEST(KinematicsTest, Ur5RandomJointsMatchElementaryComposition) {
  const DhChain ur5 = NominalUr5();
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> angle(-2 * kPi, 2 * kPi);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<double> q(6);
    for (double& v : q) v = angle(rng);
    EXPECT_TRUE(PosesNear(ur5.BaseFromFlange(q), Ur5Reference(q), 1e-6)) << "trial " << trial;
  }
}

TEST(KinematicsTest, OffsetsBaseAndFlangeTransformsApply) {
  DhChain chain = NominalUr5();
  std::mt19937 rng(7);
  const Eigen::Isometry3d base_from_chain = RandomPose(rng);
  const Eigen::Isometry3d chain_from_flange = RandomPose(rng);
  chain.set_base_from_chain(base_from_chain);
  chain.set_chain_from_flange(chain_from_flange);
  chain.mutable_joints()[1].theta_offset_rad = 0.25;
  chain.mutable_joints()[4].joint_offset_rad = -0.01;
  const std::vector<double> q = {0.1, -0.2, 0.3, -0.4, 0.5, -0.6};
  std::vector<double> q_shifted = q;
  q_shifted[1] += 0.25;
  q_shifted[4] -= 0.01;
  EXPECT_TRUE(PosesNear(chain.BaseFromFlange(q),
                        base_from_chain * Ur5Reference(q_shifted) * chain_from_flange, 1e-6));
}

TEST(KinematicsTest, ModifiedDhSingleLinkClosedForm) {
  // RotX(pi/2) * TransX(10) * RotZ(0) * TransZ(5): the z offset turns into -y.
  const DhChain chain(DhConvention::kModified, {{10.0, kPi / 2, 5.0, 0.0, 0.0}});
  const Eigen::Isometry3d t = chain.BaseFromFlange(std::vector<double>{0.0});
  EXPECT_TRUE(PosesNear(t, PoseFromAxes({1, 0, 0}, {0, 0, 1}, {0, -1, 0}, {10, -5, 0}), 1e-12));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-3, 3);
  for (int trial = 0; trial < 50; ++trial) {
    const DhJoint row{100 * u(rng), u(rng), 100 * u(rng), u(rng), 0.01 * u(rng)};
    const double q = u(rng);
    const DhChain one(DhConvention::kModified, {row});
    EXPECT_TRUE(
        PosesNear(one.BaseFromFlange(std::vector<double>{q}),
                  ElementaryModified(row.alpha_rad, row.a_mm,
                                     q + row.theta_offset_rad + row.joint_offset_rad, row.d_mm),
                  1e-9));
  }
}

TEST(KinematicsTest, ModifiedRewriteOfStandardChainIsEquivalent) {
  // Standard: prod RotZ(t_i) TransZ(d_i) TransX(a_i) RotX(al_i). TransX and RotX commute, so
  // regrouping gives modified rows (a_{i-1}, al_{i-1}, d_i) and a trailing TransX(a_n)RotX(al_n).
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 50; ++trial) {
    const int n = 1 + trial % 7;
    std::vector<DhJoint> standard(n), modified(n);
    for (int i = 0; i < n; ++i) {
      standard[i] = {500 * u(rng), 3 * u(rng), 500 * u(rng), 3 * u(rng), 0.05 * u(rng)};
    }
    for (int i = 0; i < n; ++i) {
      modified[i].a_mm = i == 0 ? 0.0 : standard[i - 1].a_mm;
      modified[i].alpha_rad = i == 0 ? 0.0 : standard[i - 1].alpha_rad;
      modified[i].d_mm = standard[i].d_mm;
      modified[i].theta_offset_rad = standard[i].theta_offset_rad;
      modified[i].joint_offset_rad = standard[i].joint_offset_rad;
    }
    const Eigen::Isometry3d base = RandomPose(rng), flange = RandomPose(rng);
    const Eigen::Isometry3d tail(
        Eigen::Translation3d(standard[n - 1].a_mm, 0, 0) *
        Eigen::AngleAxisd(standard[n - 1].alpha_rad, Eigen::Vector3d::UnitX()));
    const DhChain s(DhConvention::kStandard, standard, base, flange);
    const DhChain m(DhConvention::kModified, modified, base, tail * flange);
    std::vector<double> q(n);
    for (double& v : q) v = 4 * u(rng);
    EXPECT_TRUE(PosesNear(s.BaseFromFlange(q), m.BaseFromFlange(q), 1e-9)) << "trial " << trial;
  }
}

TEST(KinematicsTest, LinkPosesComposeToTheFlange) {
  DhChain chain = NominalUr5();
  std::mt19937 rng(5);
  chain.set_base_from_chain(RandomPose(rng));
  chain.set_chain_from_flange(RandomPose(rng));
  const std::vector<double> q = {0.3, -1.1, 0.7, 2.0, -0.4, 1.3};
  const std::vector<Eigen::Isometry3d> links = chain.LinkPoses(q);
  ASSERT_EQ(links.size(), 6u);
  Eigen::Isometry3d expected = chain.base_from_chain();
  for (int i = 0; i < 6; ++i) {
    const DhJoint& row = chain.joints()[i];
    expected = expected * ElementaryStandard(q[i], row.d_mm, row.a_mm, row.alpha_rad);
    EXPECT_TRUE(PosesNear(links[i], expected, 1e-6)) << "link " << i + 1;
  }
  EXPECT_TRUE(PosesNear(links.back() * chain.chain_from_flange(), chain.BaseFromFlange(q), 1e-12));
  // Link 1 of the nominal UR5 sits d1 above the base.
  EXPECT_TRUE(NominalUr5().LinkPoses(std::vector<double>(6, 0.0))[0].translation().isApprox(
      Eigen::Vector3d(0, 0, kD1)));
}

TEST(KinematicsTest, EmptyChainIsBaseTimesFlange) {
  std::mt19937 rng(9);
  const Eigen::Isometry3d base = RandomPose(rng), flange = RandomPose(rng);
  const DhChain chain(DhConvention::kStandard, {}, base, flange);
  EXPECT_TRUE(chain.LinkPoses({}).empty());
  EXPECT_TRUE(PosesNear(chain.BaseFromFlange({}), base * flange, 1e-12));
}

TEST(KinematicsTest, WrongJointCountNamesTheExpectedCount) {
  const DhChain ur5 = NominalUr5();
  try {
    ur5.BaseFromFlange(std::vector<double>(5, 0.0));
    FAIL() << "no exception for 5 joint values";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("got 5 joint values, expected 6"));
  }
  EXPECT_THROW(ur5.LinkPoses(std::vector<double>(7, 0.0)), InputError);
}

TEST(KinematicsTest, NonFiniteValuesAreRejected) {
  const DhChain ur5 = NominalUr5();
  std::vector<double> q(6, 0.0);
  q[2] = std::numeric_limits<double>::quiet_NaN();
  try {
    ur5.BaseFromFlange(q);
    FAIL() << "no exception for a NaN joint";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("joint value 3 of 6 is not finite"));
  }
  q[2] = std::numeric_limits<double>::infinity();
  EXPECT_THROW(ur5.BaseFromFlange(q), InputError);
  std::vector<DhJoint> rows(2);
  rows[1].d_mm = std::numeric_limits<double>::infinity();
  try {
    DhChain bad(DhConvention::kModified, rows);
    FAIL() << "no exception for an infinite d";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("joint 2 has a non-finite value"));
  }
}

/// True when a and b hold the very same bits (so also the same sign of zero).
bool SameBits(const QuaternionPose& a, const QuaternionPose& b) {
  return std::memcmp(a.rotation.coeffs().data(), b.rotation.coeffs().data(), 4 * sizeof(double)) ==
             0 &&
         std::memcmp(a.translation_mm.data(), b.translation_mm.data(), 3 * sizeof(double)) == 0;
}

bool SameBits(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return std::memcmp(a.matrix().data(), b.matrix().data(), 16 * sizeof(double)) == 0;
}

TEST(KinematicsTest, MountsAreStoredAsGivenWithTheirMatricesCached) {
  std::mt19937 rng(13);
  std::normal_distribution<double> n(0.0, 1.0);
  const std::vector<double> q = {0.3, -1.1, 0.7, 2.0, -0.4, 1.3};
  for (int trial = 0; trial < 200; ++trial) {
    // Any sign, -0, and a norm off 1 by less than 1e-9, as a file may hold them.
    const double off = 1.0 + 9e-10 * (2 * (trial % 2) - 1);
    const QuaternionPose base{
        Eigen::Quaterniond(Eigen::Vector4d{n(rng), n(rng), -0.0, n(rng)}.normalized() * off),
        100.0 * Eigen::Vector3d{n(rng), -0.0, n(rng)}};
    const QuaternionPose flange{
        Eigen::Quaterniond(-Eigen::Vector4d{n(rng), n(rng), n(rng), n(rng)}.normalized()),
        Draws<3>(n, rng)};
    const DhChain chain(DhConvention::kStandard, NominalUr5().joints(), base, flange);
    EXPECT_TRUE(SameBits(chain.base_from_chain_stored(), base)) << "trial " << trial;
    EXPECT_TRUE(SameBits(chain.chain_from_flange_stored(), flange)) << "trial " << trial;
    EXPECT_TRUE(SameBits(chain.base_from_chain(), base.ToIsometry())) << "trial " << trial;
    EXPECT_TRUE(SameBits(chain.chain_from_flange(), flange.ToIsometry())) << "trial " << trial;
    EXPECT_TRUE(SameBits(chain.BaseFromFlange(q), chain.LinkPoses(q).back() * flange.ToIsometry()));
    // Copies keep both forms.
    const DhChain copy = chain;
    const std::unique_ptr<KinematicModel> clone = chain.Clone();
    EXPECT_TRUE(SameBits(copy.base_from_chain_stored(), base));
    EXPECT_TRUE(SameBits(copy.chain_from_flange(), flange.ToIsometry()));
    EXPECT_TRUE(SameBits(clone->BaseFromFlange(q), chain.BaseFromFlange(q)));
    // Setters keep the cache in step: a QuaternionPose as given, a matrix converted once.
    DhChain set = NominalUr5();
    set.set_base_from_chain(base);
    set.set_chain_from_flange(flange);
    EXPECT_TRUE(SameBits(set.base_from_chain_stored(), base));
    EXPECT_TRUE(SameBits(set.base_from_chain(), base.ToIsometry()));
    EXPECT_TRUE(SameBits(set.chain_from_flange(), flange.ToIsometry()));
    EXPECT_TRUE(SameBits(set.BaseFromFlange(q), chain.BaseFromFlange(q)));
    const Eigen::Isometry3d matrix = RandomPose(rng);
    set.set_base_from_chain(matrix);
    EXPECT_TRUE(SameBits(set.base_from_chain_stored(), QuaternionPose::FromIsometry(matrix)));
    EXPECT_TRUE(SameBits(set.base_from_chain(), QuaternionPose::FromIsometry(matrix).ToIsometry()));
    EXPECT_TRUE(PosesNear(set.base_from_chain(), matrix, 1e-12));
    const DhChain from_matrices(DhConvention::kModified, {}, matrix, matrix.inverse());
    EXPECT_TRUE(SameBits(from_matrices.chain_from_flange_stored(),
                         QuaternionPose::FromIsometry(matrix.inverse())));
    EXPECT_TRUE(SameBits(from_matrices.chain_from_flange(),
                         QuaternionPose::FromIsometry(matrix.inverse()).ToIsometry()));
  }
}

TEST(KinematicsTest, BadMountsAreRejectedAndTheOldOnesKept) {
  DhChain chain = NominalUr5();
  const QuaternionPose kept{Eigen::Quaterniond(0.6, 0, 0.8, 0), Eigen::Vector3d(1, 2, 3)};
  chain.set_base_from_chain(kept);
  Eigen::Isometry3d scaled = Eigen::Isometry3d::Identity();
  scaled.linear() *= 1.001;
  Eigen::Isometry3d nan = Eigen::Isometry3d::Identity();
  nan.translation().y() = std::nan("");
  const struct {
    QuaternionPose pose;
    const char* problem;
  } stored[] = {
      {{Eigen::Quaterniond(1.001, 0, 0, 0), Eigen::Vector3d::Zero()}, "rotation has norm 1.001"},
      {{Eigen::Quaterniond(0, 0, 0, 0), Eigen::Vector3d::Zero()}, "rotation has norm 0"},
      {{Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, std::nan(""), 0)}, "non-finite"},
  };
  for (const auto& c : stored) {
    try {
      chain.set_base_from_chain(c.pose);
      ADD_FAILURE() << "accepted " << c.problem;
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr(c.problem));
      EXPECT_THAT(e.what(), HasSubstr("DH chain base_from_chain"));
    }
    EXPECT_THROW(DhChain(DhConvention::kStandard, {}, QuaternionPose(), c.pose), InputError);
  }
  for (const auto& [matrix, problem] :
       {std::pair{scaled, "not orthonormal"}, std::pair{nan, "non-finite"}}) {
    try {
      chain.set_chain_from_flange(matrix);
      ADD_FAILURE() << "accepted " << problem;
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr(problem));
      EXPECT_THAT(e.what(), HasSubstr("DH chain chain_from_flange"));
    }
    EXPECT_THROW(DhChain(DhConvention::kStandard, {}, matrix), InputError);
  }
  EXPECT_TRUE(SameBits(chain.base_from_chain_stored(), kept));
  EXPECT_TRUE(SameBits(chain.base_from_chain(), kept.ToIsometry()));
  EXPECT_TRUE(SameBits(chain.chain_from_flange_stored(), QuaternionPose()));
  EXPECT_TRUE(SameBits(chain.chain_from_flange(), Eigen::Isometry3d::Identity()));
}

TEST(KinematicsTest, CloneIsDeep) {
  DhChain chain = NominalUr5();
  const std::unique_ptr<KinematicModel> copy = chain.Clone();
  chain.mutable_joints()[0].d_mm = 1000.0;
  const std::vector<double> q(6, 0.0);
  EXPECT_EQ(copy->TypeName(), "dh");
  EXPECT_EQ(copy->NumJoints(), 6);
  EXPECT_TRUE(PosesNear(copy->BaseFromFlange(q), Ur5Reference(q), 1e-6));
  EXPECT_FALSE(PosesNear(chain.BaseFromFlange(q), Ur5Reference(q), 1e-6));
}

}  // namespace
}  // namespace lasercell

namespace lasercell {
namespace {

// Calibration parameter access: names, order and a round trip that keeps the mounts exactly.
TEST(DhParameters, VectorRoundTripKeepsMountsAndNominalZeros) {
  DhChain chain = NominalUr5();
  chain.mutable_joints()[1].joint_offset_rad = 0.002;
  chain.mutable_joints()[4].theta_offset_rad = 0.5;
  chain.set_chain_from_flange(Eigen::Isometry3d(Eigen::Translation3d(0, 0, 12.5)));
  std::vector<double> p = DhParameterVector(chain);
  ASSERT_EQ(p.size(), 24u);
  EXPECT_EQ(p[1], 0.002);
  EXPECT_EQ(p[6 + 1], -425.0);   // a_2
  EXPECT_EQ(p[12 + 0], 89.159);  // d_1
  EXPECT_EQ(DhParameterName(0, 6), "joint_offset_1");
  EXPECT_EQ(DhParameterName(7, 6), "a_2");
  EXPECT_EQ(DhParameterName(15, 6), "d_4");
  EXPECT_EQ(DhParameterName(23, 6), "alpha_6");
  p[2] = -0.001;
  p[12 + 3] += 0.25;
  const DhChain changed = WithDhParameters(chain, p);
  EXPECT_EQ(changed.joints()[2].joint_offset_rad, -0.001);
  EXPECT_EQ(changed.joints()[3].d_mm, 109.15 + 0.25);
  EXPECT_EQ(changed.joints()[4].theta_offset_rad, 0.5);
  EXPECT_EQ(changed.chain_from_flange_stored().translation_mm,
            chain.chain_from_flange_stored().translation_mm);
  EXPECT_EQ(DhParameterVector(changed), p);
}

TEST(DhParameters, WrongLengthAndIndexAreRejected) {
  const DhChain chain = NominalUr5();
  EXPECT_THAT([&] { WithDhParameters(chain, std::vector<double>(5, 0.0)); },
              ::testing::ThrowsMessage<InputError>(::testing::HasSubstr("expected 24")));
  EXPECT_THAT([] { DhParameterName(24, 6); },
              ::testing::ThrowsMessage<InputError>(::testing::HasSubstr("out of range")));
}

// The templated link transform (used with autodiff jets by calib) equals the chain's own.
TEST(DhParameters, TemplatedLinkTransformMatchesTheChain) {
  for (DhConvention convention : {DhConvention::kStandard, DhConvention::kModified}) {
    std::vector<DhJoint> rows(1);
    rows[0] = {12.0, 0.7, -30.0, 0.0, 0.0};
    const DhChain chain(convention, rows);
    const double theta = 0.9;
    Eigen::Matrix3d r;
    Eigen::Vector3d t;
    DhLinkRotationTranslation(convention, 12.0, 0.7, -30.0, theta, &r, &t);
    const Eigen::Isometry3d expected = chain.BaseFromFlange(std::vector<double>{theta});
    EXPECT_LT((r - expected.linear()).cwiseAbs().maxCoeff(), 1e-15);
    EXPECT_LT((t - expected.translation()).cwiseAbs().maxCoeff(), 1e-13);
  }
}

}  // namespace
}  // namespace lasercell
