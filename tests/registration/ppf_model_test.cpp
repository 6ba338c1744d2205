#include "registration/ppf_model.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <random>

#include "core/error.hpp"
#include "core/random.hpp"
#include "registration/ppf_feature.hpp"
#include "registration_test_util.hpp"
#include "tests/cli_util.hpp"

namespace lasercell::registration {
namespace {

using ::testing::HasSubstr;

struct OrientedPoint {
  Eigen::Vector3d p, n;
};

OrientedPoint RandomOrientedPoint(std::mt19937_64& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  return {Draws<3>(g, rng) * 40.0, Draws<3>(g, rng).normalized()};
}

TEST(PpfFeatureTest, InvariantUnderRigidTransforms) {
  std::mt19937_64 rng(31);
  for (int trial = 0; trial < 500; ++trial) {
    const OrientedPoint a = RandomOrientedPoint(rng), b = RandomOrientedPoint(rng);
    const Eigen::Isometry3d t = test::RandomPose(rng, 500.0);
    const PpfFeature f = ComputePpf(a.p, a.n, b.p, b.n);
    const PpfFeature g = ComputePpf(t * a.p, t.linear() * a.n, t * b.p, t.linear() * b.n);
    EXPECT_NEAR(f.distance_mm, g.distance_mm, 1e-9);
    EXPECT_NEAR(f.angle_n1_d, g.angle_n1_d, 1e-7);
    EXPECT_NEAR(f.angle_n2_d, g.angle_n2_d, 1e-7);
    EXPECT_NEAR(f.angle_n1_n2, g.angle_n1_n2, 1e-7);
  }
  // The feature is not symmetric: swapping the points swaps and mirrors the d-angles.
  const PpfFeature f = ComputePpf({0, 0, 0}, {0, 0, 1}, {10, 0, 0}, {1, 0, 0});
  EXPECT_DOUBLE_EQ(f.distance_mm, 10.0);
  EXPECT_NEAR(f.angle_n1_d, std::numbers::pi / 2, 1e-12);
  EXPECT_NEAR(f.angle_n2_d, 0.0, 1e-12);
  EXPECT_NEAR(f.angle_n1_n2, std::numbers::pi / 2, 1e-12);
}

TEST(PpfFeatureTest, RotationNormalToXIsARotationMappingNToX) {
  std::mt19937_64 rng(32);
  std::vector<Eigen::Vector3d> normals = {Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitX(),
                                          Eigen::Vector3d::UnitY(),
                                          Eigen::Vector3d(-1, 1e-12, 0).normalized()};
  for (int i = 0; i < 200; ++i) normals.push_back(RandomOrientedPoint(rng).n);
  for (const auto& n : normals) {
    const Eigen::Matrix3d r = RotationNormalToX(n);
    EXPECT_TRUE((r * n).isApprox(Eigen::Vector3d::UnitX(), 1e-9)) << n.transpose();
    EXPECT_TRUE((r.transpose() * r).isApprox(Eigen::Matrix3d::Identity(), 1e-9));
    EXPECT_NEAR(r.determinant(), 1.0, 1e-9);
  }
}

// Drost eq. 2-3: with alpha = phi_s - phi_m, T(s_r)^-1 R_x(alpha) T(m_r) is the transform that
// moved the model pair onto the scene pair.
TEST(PpfFeatureTest, LocalCoordinatesRecoverThePose) {
  std::mt19937_64 rng(33);
  for (int trial = 0; trial < 200; ++trial) {
    const OrientedPoint m_r = RandomOrientedPoint(rng), m_i = RandomOrientedPoint(rng);
    const Eigen::Isometry3d scene_from_model = test::RandomPose(rng, 300.0);
    const Eigen::Vector3d s_r = scene_from_model * m_r.p, s_i = scene_from_model * m_i.p;
    const Eigen::Vector3d n_s = scene_from_model.linear() * m_r.n;
    const Eigen::Matrix3d rot_m = RotationNormalToX(m_r.n), rot_s = RotationNormalToX(n_s);
    const double alpha = PairPlaneAngle(rot_s, s_r, s_i) - PairPlaneAngle(rot_m, m_r.p, m_i.p);
    const Eigen::Matrix3d rot =
        rot_s.transpose() * Eigen::AngleAxisd(alpha, Eigen::Vector3d::UnitX()).toRotationMatrix() *
        rot_m;
    EXPECT_TRUE(rot.isApprox(scene_from_model.linear(), 1e-9));
    EXPECT_TRUE((s_r - rot * m_r.p).isApprox(scene_from_model.translation(), 1e-9));
  }
}

PointCloud BoxModel() { return test::BoxPoints({60, 40, 25}, 2.0); }

TEST(PpfModelTest, StoresEveryOrderedPairUnderItsKey) {
  PpfModelOptions options;
  options.sampling_step_relative = 0.08;
  const PpfModel model = PpfModel::Build(BoxModel(), options);
  const std::size_t n = model.points().size();
  ASSERT_GT(n, 50U);
  EXPECT_EQ(model.pair_count(), n * (n - 1));
  EXPECT_EQ(model.alpha_bins(), 30);
  EXPECT_EQ(model.angle_bins(), 15);
  EXPECT_NEAR(model.distance_step_mm(), 0.05 * model.diameter_mm(), 1e-12);
  // Centred at the centroid of the sampled points.
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : model.points()) mean += p;
  EXPECT_LT((mean / n).norm(), 1e-9);
  // Each pair is found under its own key with its plane angle (the table keeps duplicates: a
  // box has many identical features, PCL's table would keep one per key).
  std::size_t largest_bucket = 0;
  for (std::size_t r = 0; r < n; ++r) {
    const Eigen::Matrix3d rot = RotationNormalToX(model.normals()[r]);
    for (std::size_t i = 0; i < n; i += 7) {
      if (i == r) continue;
      std::uint32_t key = 0;
      ASSERT_TRUE(model.PairKey(model.points()[r], model.normals()[r], model.points()[i],
                                model.normals()[i], &key));
      const auto entries = model.Lookup(key);
      largest_bucket = std::max(largest_bucket, entries.size());
      const std::uint16_t phi =
          PlaneAngleToTurn16(PairPlaneAngle(rot, model.points()[r], model.points()[i]));
      const bool found = std::any_of(entries.begin(), entries.end(), [&](const PpfPairEntry& e) {
        return e.reference == r && e.plane_angle == phi;
      });
      ASSERT_TRUE(found) << "pair " << r << "," << i;
    }
  }
  EXPECT_GT(largest_bucket, 100U);
  // A key beyond the table is empty, not out of bounds.
  EXPECT_TRUE(model.Lookup(0xFFFFFFF0U).empty());
}

TEST(PpfModelTest, TheTableIsTheSameForAnyThreadCount) {
  PpfModelOptions options;
  options.sampling_step_relative = 0.06;
  options.threads = 1;
  const std::string one = PpfModel::Build(BoxModel(), options).Serialize();
  for (const int threads : {2, 3, 0}) {
    options.threads = threads;
    EXPECT_EQ(PpfModel::Build(BoxModel(), options).Serialize(), one) << threads << " threads";
  }
}

TEST(PpfModelTest, QuantizationAgreesWithAngleBins) {
  const PpfModel model = PpfModel::Build(BoxModel());
  std::mt19937_64 rng(34);
  int agree = 0, total = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const OrientedPoint a = RandomOrientedPoint(rng), b = RandomOrientedPoint(rng);
    std::uint32_t key = 0;
    PpfBins bins;
    const bool in = model.PairKey(a.p, a.n, b.p, b.n, &key);
    ASSERT_EQ(in, model.Quantize(ComputePpf(a.p, a.n, b.p, b.n), &bins));
    if (!in) continue;
    ++total;
    agree += key == model.Key(bins) ? 1 : 0;
  }
  EXPECT_GT(total, 1000);
  EXPECT_EQ(agree, total);  // cosine thresholds and acos bins agree away from exact borders
}

TEST(PpfModelTest, SerializeRoundTripAndFiles) {
  PpfModelOptions options;
  options.sampling_step_relative = 0.1;
  const PpfModel model = PpfModel::Build(BoxModel(), options);
  const std::string bytes = model.Serialize();
  const PpfModel loaded = PpfModel::Deserialize(bytes);
  EXPECT_EQ(loaded.Serialize(), bytes);
  EXPECT_EQ(loaded.points(), model.points());
  EXPECT_EQ(loaded.refinement_points(), model.refinement_points());
  EXPECT_TRUE(loaded.model_from_centered().isApprox(model.model_from_centered()));
  EXPECT_EQ(loaded.pair_count(), model.pair_count());
  std::uint32_t key = 0;
  ASSERT_TRUE(model.PairKey(model.points()[0], model.normals()[0], model.points()[5],
                            model.normals()[5], &key));
  ASSERT_EQ(loaded.Lookup(key).size(), model.Lookup(key).size());
  EXPECT_TRUE(std::equal(loaded.Lookup(key).begin(), loaded.Lookup(key).end(),
                         model.Lookup(key).begin(),
                         [](const PpfPairEntry& a, const PpfPairEntry& b) {
                           return a.reference == b.reference && a.plane_angle == b.plane_angle;
                         }));

  const ::lasercell::test::TestDir dir("ppf_model");
  const std::string path = dir.File("model.lcppf");
  model.Save(path);
  EXPECT_EQ(PpfModel::Load(path).Serialize(), bytes);
  std::filesystem::remove(path);
  EXPECT_THROW(PpfModel::Load(path), FileError);
}

TEST(PpfModelTest, DeserializeRejectsDamagedBytes) {
  PpfModelOptions options;
  options.sampling_step_relative = 0.15;
  const std::string bytes = PpfModel::Build(BoxModel(), options).Serialize();
  auto message_of = [](const std::string& b) {
    try {
      PpfModel::Deserialize(b, "model.lcppf");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  std::string flipped = bytes;
  flipped[bytes.size() / 2] ^= 0x40;
  EXPECT_THAT(message_of(flipped), HasSubstr("checksum"));
  EXPECT_THAT(message_of(bytes.substr(0, bytes.size() - 100)), HasSubstr("model.lcppf"));
  EXPECT_THAT(message_of("not a model at all"), HasSubstr("bad magic"));
  std::string version = bytes;
  version[8] = 9;
  EXPECT_THAT(message_of(version), HasSubstr("format version 9"));
  EXPECT_THAT(message_of(""), HasSubstr("bad magic"));
}

TEST(PpfModelTest, EstimatesNormalsWhenAbsent) {
  PointCloud cloud = BoxModel();
  cloud.normals.clear();
  PpfModelOptions options;
  options.normals.viewpoint = Viewpoint::AtPoint({0, 0, 500});
  const PpfModel model = PpfModel::Build(cloud, options);
  EXPECT_GT(model.points().size(), 10U);
  for (const auto& n : model.normals()) EXPECT_NEAR(n.norm(), 1.0, 1e-9);
}

// A closed cube (side 100 mm, centred at the origin), each face a 10 x 10 grid of quads wound
// counter-clockwise seen from outside.
TriangleMesh CubeMesh() {
  TriangleMesh mesh;
  const int n = 10;
  const double half = 50.0, step = 100.0 / n;
  for (int axis = 0; axis < 3; ++axis) {
    for (const double side : {-1.0, 1.0}) {
      Eigen::Vector3d normal = Eigen::Vector3d::Zero();
      normal[axis] = side;
      const Eigen::Vector3d u = Eigen::Vector3d::Unit((axis + 1) % 3);
      const Eigen::Vector3d v = normal.cross(u);  // u x v = normal: counter-clockwise outside
      const int base = static_cast<int>(mesh.vertices.size());
      for (int j = 0; j <= n; ++j) {
        for (int i = 0; i <= n; ++i) {
          mesh.vertices.positions.push_back(half * normal + (i * step - half) * u +
                                            (j * step - half) * v);
        }
      }
      for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
          const int a = base + j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
          mesh.faces.push_back({a, b, d});
          mesh.faces.push_back({a, d, c});
        }
      }
    }
  }
  return mesh;
}

TEST(PpfModelTest, AMeshWithoutNormalsGetsOutwardNormalsFromItsFaces) {
  const TriangleMesh cube = CubeMesh();
  // A viewpoint at the centre: PCA normals flipped toward it would all point inward.
  PpfModelOptions options;
  options.normals.viewpoint = Viewpoint::AtPoint({0, 0, 0});
  const PpfModel model = PpfModel::Build(cube, options);
  ASSERT_GT(model.points().size(), 10U);
  // points() are centred at the model's centroid, the cube's centre.
  for (std::size_t i = 0; i < model.points().size(); ++i) {
    EXPECT_GT(model.normals()[i].dot(model.points()[i]), 0.0) << "point " << i;
  }
  // The same vertices as a cloud take the PCA path and its viewpoint: inward.
  const PpfModel from_cloud = PpfModel::Build(cube.vertices, options);
  int inward = 0;
  for (std::size_t i = 0; i < from_cloud.points().size(); ++i) {
    inward += from_cloud.normals()[i].dot(from_cloud.points()[i]) < 0.0;
  }
  EXPECT_GT(inward, static_cast<int>(from_cloud.points().size()) / 2);
}

TEST(PpfModelTest, RejectsBadInputAndOptions) {
  EXPECT_THAT([] { PpfModel::Build(PointCloud{}); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("at least 3 points")));
  PointCloud zero_normals = BoxModel();
  for (auto& n : zero_normals.normals) n.setZero();
  EXPECT_THAT([&] { PpfModel::Build(zero_normals); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("normal")));

  auto expect_option_error = [](const PpfModelOptions& options, const char* field) {
    EXPECT_THAT([&] { options.Check(); }, ::testing::ThrowsMessage<OptionError>(HasSubstr(field)));
  };
  PpfModelOptions o;
  o.distance_step_mm = -1.0;
  expect_option_error(o, "distance_step_mm");
  o = {};
  o.distance_step_relative = 0.0;
  expect_option_error(o, "distance_step_relative");
  o = {};
  o.angle_step_rad = 0.0;
  expect_option_error(o, "angle_step_rad");
  o = {};
  o.angle_step_rad = 3.0;
  expect_option_error(o, "angle_step_rad");
  o = {};
  o.sampling_step_relative = 1.5;
  expect_option_error(o, "sampling_step_relative");
  o = {};
  o.max_model_points = 100000;
  expect_option_error(o, "max_model_points");
  // Too many points after sampling: the message says which step to change.
  o = {};
  o.sampling_step_mm = 0.5;
  EXPECT_THAT([&] { PpfModel::Build(BoxModel(), o); },
              ::testing::ThrowsMessage<OptionError>(HasSubstr("larger sampling step")));
}

}  // namespace
}  // namespace lasercell::registration
