// SE(3) helpers against Eigen's AngleAxis (an independent implementation) and closed forms.

#include "core/se3.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/random.hpp"

namespace lasercell {
namespace {

constexpr double kPi = std::numbers::pi;

Eigen::Vector3d RandomAxis(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Draws<3>(n, rng).normalized();
}

/// Rotation matrices agree (sign-free, unlike quaternion coefficients).
double MatrixGap(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return (a.toRotationMatrix() - b.toRotationMatrix()).cwiseAbs().maxCoeff();
}

TEST(Se3Test, QuaternionFromRotationVectorMatchesAngleAxis) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> angle(0.0, kPi);
  for (int trial = 0; trial < 500; ++trial) {
    const Eigen::Vector3d axis = RandomAxis(rng);
    const double a = angle(rng);
    const Eigen::Quaterniond q = QuaternionFromRotationVector(a * axis);
    EXPECT_NEAR(q.norm(), 1.0, 1e-15);
    EXPECT_LT(MatrixGap(q, Eigen::Quaterniond(Eigen::AngleAxisd(a, axis))), 4e-15);
  }
  // Zero rotation is exactly the identity; tiny ones keep their direction on both sides of the
  // series switch (1e-8).
  const Eigen::Quaterniond identity = QuaternionFromRotationVector(Eigen::Vector3d::Zero());
  EXPECT_EQ(identity.coeffs(), Eigen::Quaterniond::Identity().coeffs());
  for (double a : {1e-15, 1e-10, 0.999e-8, 1.001e-8, 1e-6}) {
    const Eigen::Vector3d v = a * Eigen::Vector3d(0.6, 0.0, 0.8);
    const Eigen::Quaterniond q = QuaternionFromRotationVector(v);
    EXPECT_NEAR(q.x() / (0.5 * a), 0.6, 1e-12) << a;
    EXPECT_NEAR(q.z() / (0.5 * a), 0.8, 1e-12) << a;
    EXPECT_NEAR(q.w(), std::cos(0.5 * a), 1e-15) << a;
  }
}

TEST(Se3Test, RotationVectorRoundTrips) {
  std::mt19937 rng(2);
  std::vector<double> angles = {1e-14, 1e-12, 1e-9, 1e-6,       0.1,
                                1.0,   2.0,   3.0,  kPi - 1e-6, kPi - 1e-9};
  std::uniform_real_distribution<double> angle(0.0, kPi);
  for (int i = 0; i < 200; ++i) angles.push_back(angle(rng));
  for (double a : angles) {
    const Eigen::Vector3d v = a * RandomAxis(rng);
    const Eigen::Vector3d back = RotationVectorFromQuaternion(QuaternionFromRotationVector(v));
    EXPECT_LT((back - v).norm(), 1e-12 * std::max(1.0, a)) << "angle " << a;
    const Eigen::Vector3d from_matrix =
        RotationVectorFromMatrix(Eigen::AngleAxisd(a, v.normalized()).toRotationMatrix());
    EXPECT_LT((from_matrix - v).norm(), 1e-9) << "angle " << a;
  }
}

TEST(Se3Test, RotationVectorAngleStaysInZeroToPi) {
  // A rotation by pi + e equals one by pi - e about the opposite axis; q and -q are the same.
  const Eigen::Vector3d axis(0, 0.6, 0.8);
  const Eigen::Vector3d v =
      RotationVectorFromQuaternion(QuaternionFromRotationVector((kPi + 0.25) * axis));
  EXPECT_NEAR(v.norm(), kPi - 0.25, 1e-12);
  EXPECT_LT((v.normalized() + axis).norm(), 1e-12);
  const Eigen::Quaterniond q = QuaternionFromRotationVector(1.3 * axis);
  Eigen::Quaterniond minus_q;
  minus_q.coeffs() = -q.coeffs();
  EXPECT_LT((RotationVectorFromQuaternion(minus_q) - 1.3 * axis).norm(), 1e-14);
  // Exactly pi: angle pi about +-axis.
  const Eigen::Vector3d at_pi = RotationVectorFromQuaternion(Eigen::Quaterniond(0, 0, 0.6, 0.8));
  EXPECT_NEAR(at_pi.norm(), kPi, 1e-15);
  EXPECT_NEAR(std::abs(at_pi.normalized().dot(axis)), 1.0, 1e-15);
}

TEST(Se3Test, PoseParametrisationRoundTrip) {
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 100.0);
  for (int trial = 0; trial < 100; ++trial) {
    Vector6d v;
    v.head<3>() = 3.0 * (trial + 0.5) / 100.0 * RandomAxis(rng);
    v.tail<3>() << n(rng), n(rng), n(rng);
    const Eigen::Isometry3d pose = PoseFromRotationVectorTranslation(v);
    EXPECT_LT((RotationVectorTranslation(pose) - v).norm(), 1e-12);
    const Eigen::Isometry3d reference(
        Eigen::Translation3d(v.tail<3>()) *
        Eigen::AngleAxisd(v.head<3>().norm(), v.head<3>().normalized()));
    EXPECT_TRUE(pose.isApprox(reference, 1e-14));
  }
}

TEST(Se3Test, RotationDistanceIsSymmetricAndSignFree) {
  std::mt19937 rng(4);
  for (int trial = 0; trial < 100; ++trial) {
    const Eigen::Quaterniond a = QuaternionFromRotationVector(2.0 * RandomAxis(rng));
    const double angle = kPi * (trial + 0.5) / 100.0;
    const Eigen::Quaterniond b = a * Eigen::Quaterniond(Eigen::AngleAxisd(angle, RandomAxis(rng)));
    EXPECT_NEAR(RotationDistance(a, b), angle, 1e-12);
    EXPECT_EQ(RotationDistance(a, b), RotationDistance(b, a));
    Eigen::Quaterniond minus_b;
    minus_b.coeffs() = -b.coeffs();
    EXPECT_NEAR(RotationDistance(a, minus_b), angle, 1e-12);
    Eigen::Isometry3d pa = PoseFromQuaternion(a, Eigen::Vector3d(1, 2, 3));
    Eigen::Isometry3d pb = PoseFromQuaternion(b, Eigen::Vector3d(4, 6, 3));
    EXPECT_NEAR(RotationDistance(pa, pb), angle, 1e-9);
    EXPECT_NEAR(RotationDistance(pb, pa), angle, 1e-9);
    EXPECT_DOUBLE_EQ(TranslationDistance(pa, pb), 5.0);
  }
  EXPECT_EQ(RotationDistance(Eigen::Quaterniond::Identity(), Eigen::Quaterniond::Identity()), 0.0);
  // Small angles stay accurate (acos would lose them).
  const Eigen::Quaterniond tiny = QuaternionFromRotationVector(Eigen::Vector3d(1e-10, 0, 0));
  EXPECT_NEAR(RotationDistance(Eigen::Quaterniond::Identity(), tiny), 1e-10, 1e-22);
}

TEST(Se3Test, AverageQuaternionsIgnoresSignsAndUsesWeights) {
  const Eigen::Vector3d axis(0.0, 0.6, 0.8);
  std::mt19937 axis_rng(5);
  const Eigen::Quaterniond base = QuaternionFromRotationVector(0.7 * RandomAxis(axis_rng));
  const Eigen::Quaterniond q1 = base * QuaternionFromRotationVector(0.2 * axis);
  const Eigen::Quaterniond q2 = base * QuaternionFromRotationVector(0.6 * axis);
  Eigen::Quaterniond minus_q2;
  minus_q2.coeffs() = -q2.coeffs();
  const Eigen::Quaterniond midpoint = base * QuaternionFromRotationVector(0.4 * axis);
  // Two rotations, equal weights: the principal eigenvector is (q1 + q2)/|q1 + q2|, the slerp
  // midpoint, whatever sign q2 comes with.
  for (const auto& pair :
       {std::vector<Eigen::Quaterniond>{q1, q2}, std::vector<Eigen::Quaterniond>{q1, minus_q2}}) {
    const Eigen::Quaterniond mean = AverageQuaternions(pair);
    EXPECT_LT(RotationDistance(mean, midpoint), 1e-12);
    EXPECT_GT(mean.coeffs().dot(q1.coeffs()), 0.0);  // keeps the first input's sign
  }
  // A single quaternion comes back unchanged, even with w < 0.
  const Eigen::Quaterniond single = AverageQuaternions(std::vector<Eigen::Quaterniond>{minus_q2});
  EXPECT_LT((single.coeffs() - minus_q2.coeffs()).norm(), 1e-15);
  // Zero weight removes an input; a larger weight pulls towards its rotation.
  const std::vector<Eigen::Quaterniond> pair = {q1, minus_q2};
  EXPECT_LT(RotationDistance(AverageQuaternions(pair, std::vector<double>{0.0, 2.0}), q2), 1e-12);
  const Eigen::Quaterniond pulled = AverageQuaternions(pair, std::vector<double>{3.0, 1.0});
  EXPECT_LT(RotationDistance(pulled, q1), RotationDistance(pulled, q2));
  EXPECT_NEAR(RotationDistance(pulled, q1) + RotationDistance(pulled, q2), 0.4, 1e-12);
  // Many noisy copies of one rotation with random signs average back to it.
  std::mt19937 rng(6);
  std::normal_distribution<double> noise(0.0, 0.01);
  std::vector<Eigen::Quaterniond> cloud;
  for (int i = 0; i < 400; ++i) {
    Eigen::Quaterniond q = q1 * QuaternionFromRotationVector(Draws<3>(noise, rng));
    if (i % 2 == 1) q.coeffs() = -q.coeffs();
    cloud.push_back(q);
  }
  EXPECT_LT(RotationDistance(AverageQuaternions(cloud), q1), 3e-3);
}

TEST(Se3Test, AverageRejectsBadWeights) {
  const std::vector<Eigen::Quaterniond> qs(2, Eigen::Quaterniond::Identity());
  EXPECT_THROW(AverageQuaternions(std::vector<Eigen::Quaterniond>{}), InputError);
  EXPECT_THROW(AverageQuaternions(qs, std::vector<double>{1.0}), InputError);
  EXPECT_THROW(AverageQuaternions(qs, std::vector<double>{1.0, -1.0}), InputError);
  EXPECT_THROW(AverageQuaternions(qs, std::vector<double>{0.0, 0.0}), InputError);
  EXPECT_THROW(AverageQuaternions(qs, std::vector<double>{1.0, std::nan("")}), InputError);
  EXPECT_THROW(AveragePoses(std::vector<Eigen::Isometry3d>{}), InputError);
}

TEST(Se3Test, AveragePosesWeightsTranslations) {
  const Eigen::Isometry3d a =
      PoseFromRotationVector(Eigen::Vector3d(0, 0, 0.1), Eigen::Vector3d(0, 0, 0));
  const Eigen::Isometry3d b =
      PoseFromRotationVector(Eigen::Vector3d(0, 0, 0.3), Eigen::Vector3d(40, 0, 8));
  const Eigen::Isometry3d mean =
      AveragePoses(std::vector<Eigen::Isometry3d>{a, b}, std::vector<double>{3.0, 1.0});
  EXPECT_LT((mean.translation() - Eigen::Vector3d(10, 0, 2)).norm(), 1e-12);
  const Eigen::Isometry3d even = AveragePoses(std::vector<Eigen::Isometry3d>{a, b});
  EXPECT_NEAR(RotationVectorFromMatrix(even.linear()).z(), 0.2, 1e-12);
}

TEST(Se3Test, InterpolatePosesEndpointsAndMidpoint) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::Isometry3d a =
        PoseFromRotationVector(2.5 * RandomAxis(rng), Eigen::Vector3d(1, 2, 3));
    const double angle = 0.05 + 3.0 * trial / 50.0;
    const Eigen::Isometry3d b(a * Eigen::Translation3d(10, -20, 30) *
                              Eigen::AngleAxisd(angle, RandomAxis(rng)));
    EXPECT_TRUE(InterpolatePoses(a, b, 0.0).isApprox(a, 1e-14));
    EXPECT_TRUE(InterpolatePoses(a, b, 1.0).isApprox(b, 1e-14));
    const Eigen::Isometry3d mid = InterpolatePoses(a, b, 0.5);
    EXPECT_NEAR(RotationDistance(a, mid), angle / 2, 1e-9);
    EXPECT_NEAR(RotationDistance(mid, b), angle / 2, 1e-9);
    EXPECT_LT((mid.translation() - 0.5 * (a.translation() + b.translation())).norm(), 1e-12);
    const Eigen::Isometry3d quarter = InterpolatePoses(a, b, 0.25);
    EXPECT_NEAR(RotationDistance(a, quarter), angle / 4, 1e-9);
  }
}

TEST(Se3Test, OrthonormalizedFindsTheNearestRotation) {
  std::mt19937 rng(8);
  std::normal_distribution<double> n(0.0, 1e-4);
  for (int trial = 0; trial < 50; ++trial) {
    Eigen::Isometry3d pose =
        PoseFromRotationVector(2.0 * RandomAxis(rng), Eigen::Vector3d(5, 6, 7));
    const Eigen::Matrix3d rotation = pose.linear();
    Eigen::Matrix3d noise;
    noise << n(rng), n(rng), n(rng), n(rng), n(rng), n(rng), n(rng), n(rng), n(rng);
    pose.linear() += noise;
    const Eigen::Isometry3d fixed = Orthonormalized(pose);
    const Eigen::Matrix3d r = fixed.linear();
    EXPECT_LT((r.transpose() * r - Eigen::Matrix3d::Identity()).norm(), 1e-14);
    EXPECT_NEAR(r.determinant(), 1.0, 1e-14);
    EXPECT_LT((r - rotation).norm(), 1e-3);
    EXPECT_EQ(fixed.translation(), Eigen::Vector3d(5, 6, 7));
    // Nearest: closer to the perturbed matrix than the original rotation is.
    EXPECT_LE((r - pose.linear()).norm(), (rotation - pose.linear()).norm() + 1e-15);
    // Already orthonormal: unchanged.
    EXPECT_LT((Orthonormalized(fixed).linear() - r).norm(), 1e-14);
  }
  // A reflection is turned into a proper rotation (det +1), not kept.
  Eigen::Isometry3d mirrored = Eigen::Isometry3d::Identity();
  mirrored.linear() = Eigen::Vector3d(1, 1, -1).asDiagonal();
  EXPECT_NEAR(Orthonormalized(mirrored).linear().determinant(), 1.0, 1e-14);
}

TEST(Se3Test, SkewIsTheCrossProduct) {
  const Eigen::Vector3d v(1.5, -2.0, 0.25), w(-3.0, 0.5, 4.0);
  EXPECT_EQ(Skew(v) * w, v.cross(w));
  EXPECT_EQ(Skew(v).transpose(), -Skew(v));
}

TEST(Se3Test, CanonicalQuaternionHasThePositiveFirstNonzeroAndNoNegativeZero) {
  // Rotations by pi (R = 2 a a^T - I) have w == 0: the first nonzero of (w, x, y, z) decides.
  const double h = std::sqrt(0.5);
  Eigen::Matrix3d about_y_z;  // axis (0, -1, 1) / sqrt(2)
  about_y_z << -1, 0, 0, 0, 0, -1, 0, -1, 0;
  Eigen::Matrix3d about_x_z;  // axis (-0.6, 0, 0.8): Eigen gives x < 0, so the sign is flipped
  about_x_z << -0.28, 0, -0.96, 0, -1, 0, -0.96, 0, 0.28;
  const struct {
    Eigen::Matrix3d rotation;
    Eigen::Vector4d wxyz;
  } exact[] = {
      {Eigen::Matrix3d::Identity(), {1, 0, 0, 0}},
      {Eigen::Vector3d(1, -1, -1).asDiagonal(), {0, 1, 0, 0}},
      {Eigen::Vector3d(-1, 1, -1).asDiagonal(), {0, 0, 1, 0}},
      {Eigen::Vector3d(-1, -1, 1).asDiagonal(), {0, 0, 0, 1}},
      {about_y_z, {0, 0, h, -h}},
      {about_x_z, {0, 0.6, 0, -0.8}},
  };
  for (const auto& c : exact) {
    const Eigen::Quaterniond q = CanonicalQuaternion(c.rotation);
    const Eigen::Vector4d wxyz(q.w(), q.x(), q.y(), q.z());
    EXPECT_LT((wxyz - c.wxyz).cwiseAbs().maxCoeff(), 1e-15) << wxyz.transpose();
    for (int i = 0; i < 4; ++i) EXPECT_FALSE(wxyz[i] == 0 && std::signbit(wxyz[i])) << "-0";
  }
  std::mt19937 rng(21);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int trial = 0; trial < 1000; ++trial) {
    const Eigen::Quaterniond q = Eigen::Quaterniond{n(rng), n(rng), n(rng), n(rng)}.normalized();
    const Eigen::Quaterniond c = CanonicalQuaternion(q.toRotationMatrix());
    EXPECT_GT(c.w(), 0.0);
    EXPECT_NEAR(c.norm(), 1.0, 1e-15);
    EXPECT_LT(std::abs(std::abs(c.dot(q)) - 1.0), 1e-15);
    // Both signs of the input quaternion give the same matrix, hence the same result.
    EXPECT_EQ(c.coeffs(),
              CanonicalQuaternion(Eigen::Quaterniond(-q.coeffs()).toRotationMatrix()).coeffs());
  }
}

TEST(Se3Test, QuaternionPoseKeepsItsCoefficientsAndConvertsOnce) {
  // Default: identity.
  const QuaternionPose identity;
  EXPECT_EQ(identity.ToIsometry().matrix(), Eigen::Matrix4d::Identity());
  // Stored as given (any sign, -0, norm off 1 within the tolerance); only the matrix normalizes.
  const QuaternionPose given{Eigen::Quaterniond(-(0.6 + 5e-10), 0.0, -0.0, 0.8),
                             Eigen::Vector3d(0.1, -0.0, 1e-300)};
  EXPECT_TRUE(std::signbit(given.rotation.y()));
  EXPECT_EQ(given.ToIsometry().matrix(),
            PoseFromQuaternion(given.rotation, given.translation_mm).matrix());
  EXPECT_NO_THROW(CheckQuaternionPose(given, "pose"));
  // FromIsometry: canonical quaternion, translation as is; ToIsometry gives the matrix back to
  // rounding (which is why DhChain and StaticEdge store the quaternion, not the matrix).
  std::mt19937 rng(22);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int trial = 0; trial < 1000; ++trial) {
    const double angle = 3.0 * n(rng);
    const Eigen::Vector3d axis = RandomAxis(rng);
    const Eigen::Isometry3d pose = PoseFromRotationVector(angle * axis, 500.0 * Draws<3>(n, rng));
    const QuaternionPose stored = QuaternionPose::FromIsometry(pose);
    EXPECT_EQ(stored.rotation.coeffs(), CanonicalQuaternion(pose.linear()).coeffs());
    EXPECT_EQ(stored.translation_mm, pose.translation());
    const Eigen::Isometry3d back = stored.ToIsometry();
    EXPECT_EQ(back.translation(), pose.translation());
    EXPECT_LT((back.linear() - pose.linear()).cwiseAbs().maxCoeff(), 1e-14);
    EXPECT_LT(RotationDistance(QuaternionPose::FromIsometry(back).rotation, stored.rotation),
              1e-14);
  }
}

TEST(Se3Test, PoseChecksNameTheProblem) {
  const auto message = [](const auto& check) {
    try {
      check();
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  using ::testing::AllOf;
  using ::testing::HasSubstr;
  using ::testing::StartsWith;
  const Eigen::Vector3d t(1, 2, 3);
  EXPECT_THAT(message([&] {
                CheckQuaternionPose({Eigen::Quaterniond(1.001, 0, 0, 0), t}, "m");
              }),
              AllOf(StartsWith("m: rotation has norm 1.001"), HasSubstr("unit quaternion")));
  EXPECT_THAT(message([&] {
                CheckQuaternionPose({Eigen::Quaterniond(1 + 2e-6, 0, 0, 0), t}, "m");
              }),
              HasSubstr("unit quaternion"));
  EXPECT_NO_THROW(CheckQuaternionPose({Eigen::Quaterniond(1 + 9e-7, 0, 0, 0), t}, "m"));
  EXPECT_THAT(message([&] {
                CheckQuaternionPose({Eigen::Quaterniond(std::nan(""), 0, 0, 0), t}, "m");
              }),
              StartsWith("m has non-finite entries"));
  Eigen::Isometry3d scaled = Eigen::Isometry3d::Identity();
  scaled.linear() *= 1.001;
  Eigen::Isometry3d mirrored = Eigen::Isometry3d::Identity();
  mirrored.linear() = Eigen::Vector3d(1, 1, -1).asDiagonal();
  Eigen::Isometry3d infinite = Eigen::Isometry3d::Identity();
  infinite.translation().z() = std::numeric_limits<double>::infinity();
  EXPECT_THAT(message([&] { CheckRigidTransform(scaled, "m"); }),
              StartsWith("m has a rotation that is not orthonormal"));
  EXPECT_THAT(message([&] { CheckRigidTransform(mirrored, "m"); }), HasSubstr("not orthonormal"));
  EXPECT_THAT(message([&] { CheckRigidTransform(infinite, "m"); }),
              StartsWith("m has non-finite entries"));
  Eigen::Isometry3d almost = Eigen::Isometry3d::Identity();
  almost.linear()(0, 1) = 1e-12;
  EXPECT_NO_THROW(CheckRigidTransform(almost, "m"));
}

}  // namespace
}  // namespace lasercell

namespace lasercell {
namespace {

TEST(FixedXyzAngles, RoundTripAndMatchTheRobotConvention) {
  // R = Rz(c) Ry(b) Rx(a): a 90 degree c turns x into y.
  const Eigen::Matrix3d z90 = RotationFromFixedXyzDeg({0, 0, 90});
  EXPECT_TRUE((z90 * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY(), 1e-12));
  // x is applied first: Rx(90) then Rz(90) maps y to z, then z stays z.
  const Eigen::Matrix3d xz = RotationFromFixedXyzDeg({90, 0, 90});
  EXPECT_TRUE((xz * Eigen::Vector3d::UnitY()).isApprox(Eigen::Vector3d::UnitZ(), 1e-12));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> angle(-179.0, 179.0), tilt(-89.0, 89.0);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d abc{angle(rng), tilt(rng), angle(rng)};
    const Eigen::Vector3d back = FixedXyzDegFromRotation(RotationFromFixedXyzDeg(abc));
    EXPECT_TRUE(back.isApprox(abc, 1e-9)) << abc.transpose() << " -> " << back.transpose();
  }
  // Gimbal lock: the angles differ but the rotation is the same.
  for (const double b : {90.0, -90.0}) {
    const Eigen::Matrix3d r = RotationFromFixedXyzDeg({30, b, -50});
    const Eigen::Vector3d back = FixedXyzDegFromRotation(r);
    EXPECT_EQ(back.x(), 0.0);
    EXPECT_TRUE(RotationFromFixedXyzDeg(back).isApprox(r, 1e-9)) << back.transpose();
  }
}

}  // namespace
}  // namespace lasercell
