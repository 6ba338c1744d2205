#include "registration/reference_pose.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <random>

#include "core/error.hpp"
#include "core/io/point_cloud_io.hpp"
#include "registration/localize_in_cloud.hpp"
#include "registration_test_util.hpp"
#include "tests/sanitizer_scale.hpp"
#include "tests/shared_data.hpp"

namespace lasercell::registration {
namespace {

using ::testing::HasSubstr;

TEST(ReferencePose, BadOptionsAndInputsNameTheField) {
  ReferencePoseOptions options;
  options.reference_stride = 0;
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<OptionError>(HasSubstr("reference_stride")));
  options = {};
  options.rounds = 0;
  EXPECT_THAT([&] { options.Check(); }, ::testing::ThrowsMessage<OptionError>(HasSubstr("rounds")));
  options = {};
  options.converged_rms_mm = 0.0;
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<OptionError>(HasSubstr("converged_rms_mm")));
  PointCloud model;
  model.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  PointCloud scene = model;
  EXPECT_THAT([&] { EstablishReferencePose(model, scene); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("no normals")));
  model.normals.assign(3, Eigen::Vector3d::UnitZ());
  EXPECT_THAT([&] { EstablishReferencePose(model, PointCloud{}); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("scene cloud is empty")));
}

// Simulation: the parasaurolophus surface (the mesh sampled at rs1's density, not the model's
// 6700 vertices the tool aligns) rendered at a seeded random placement into rs1's real clutter,
// 0.3 mm noise along the line of sight, z-buffered. With tens of thousands of overlapping points
// the noise moves the pose by ~0.01 mm; what remains is the mesh's flat facets against the
// model's vertex tangent planes: a sag of curvature x edge^2 / 8 = 0.2-0.4 mm at the ~4 mm edges
// and 5-10 mm radii of the neck, legs and crest. One view sees one side, so the sags pull the
// same way instead of cancelling: up to the largest, 0.4 mm. Bound 0.5 mm RMS over the model's
// points. The default LocalizeInCloud on the same scan (measured 0.351 mm; the reference 0.364)
// must not beat it by more than the spread between robust kernels at a pose (0.06 mm, below).
TEST(ReferencePose, RecoversAKnownPlacementInRealClutter) {
  LASERCELL_REQUIRE_UWA();
  std::mt19937_64 rng(417);
  const Eigen::Isometry3d truth = test::RandomPlacementInRs1(test::UwaModel()->Centroid(), rng);
  const PointCloud scan = test::SyntheticRs1Scan({truth}, 0.3, rng);
  ReferencePoseOptions options;
  options.reference_stride =
      lasercell::test::kSanitizerBuild ? 40 : 10;  // the search only finds the basin
  options.random_starts = lasercell::test::Draws(4);
  const ReferencePose ref = EstablishReferencePose(*test::UwaModel(), scan, options);
  ASSERT_TRUE(ref.found) << ref.message;
  const double error = PoseRmsDistanceMm(test::UwaModel()->positions, ref.scene_from_model, truth);
  EXPECT_LT(error, 0.5) << ref.Report();
  const LocalizationResult fast = LocalizeInCloud(scan, *test::UwaModel(), PpfModelOptions{});
  ASSERT_TRUE(fast.found) << fast.Summary();
  EXPECT_LE(error, PoseRmsDistanceMm(test::UwaModel()->positions,
                                     fast.candidates.front().scene_from_model, truth) +
                       0.06);
  ASSERT_EQ(ref.round_shift_mm.size(), 3u);
  EXPECT_LT(ref.round_shift_mm.back(), 0.01) << "not at a fixed point: " << ref.Report();
  EXPECT_EQ(ref.starts_returned, ref.starts.size()) << ref.Report();
  for (const ReferenceStart& s : ref.starts) EXPECT_GT(s.start_rms_mm, 3.0);
  EXPECT_GT(ref.within_fraction[2], ref.within_fraction[0]);
  EXPECT_THAT(ref.Report(), HasSubstr("random starts"));
  EXPECT_EQ(ReferencePoseJson(ref)["starts"].size(), ref.starts.size());
}

// Real data: the committed rs1 reference (tests/registration/data) was made by an earlier
// scratch version of this procedure; the tool must reproduce it. Bound: 0.06 mm RMS, the spread
// between robust kernels at the pose (Geman-McClure 0.056 mm from Tukey's), below which two
// poses are not distinguishable by this scan. Measured: 0.018 mm.
TEST(ReferencePose, ReproducesTheCommittedRs1Reference) {
  LASERCELL_REQUIRE_UWA();
  if (lasercell::test::kSanitizerBuild) {
    GTEST_SKIP() << "every scene point of rs1 votes: minutes under the sanitizer; the same code "
                    "runs there in RecoversAKnownPlacementInRealClutter";
  }
  ReferencePoseOptions options;
  options.random_starts = 2;
  const ReferencePose ref = EstablishReferencePose(*test::UwaModel(), *test::UwaScene(), options);
  ASSERT_TRUE(ref.found) << ref.message;
  EXPECT_LT(PoseRmsDistanceMm(test::UwaModel()->positions, ref.scene_from_model,
                              test::Rs1ReferencePose()),
            0.06)
      << ref.Report();
  EXPECT_EQ(ref.starts_returned, 2u) << ref.Report();
}

// Real data, second case: UWA rs22 with the 28k-point parasaurolophus_low_normals2
// (../shared/data/uwa). The committed reference was made by `lasercell reference-pose` (its
// comment lines say how it was checked; OpenCV's pose agrees within ~1 mm, see the CLI test).
// LocalizeInCloud at its defaults must find the part there within 1 mm RMS, as on rs1.
TEST(ReferencePose, LocalizeInCloudFindsTheParasaurolophusInRs22) {
  const std::string dir = shared_data::SharedDataSet("uwa");
  if (dir.empty()) LASERCELL_SHARED_DATA_ABSENT(shared_data::SharedDataMissing("uwa"));
  const PointCloud model = io::ReadPointCloud(dir + "/parasaurolophus_low_normals2.ply");
  const PointCloud scene = io::ReadPointCloud(dir + "/rs22_proc2.ply");
  const Eigen::Isometry3d reference =
      datasets::ReadPoseFile(std::string(LASERCELL_SOURCE_DIR) +
                             "/tests/registration/data/rs22_parasaurolophus_reference.txt");
  const LocalizationResult result = LocalizeInCloud(scene, model, PpfModelOptions{});
  ASSERT_TRUE(result.found) << result.Summary();
  EXPECT_LT(
      PoseRmsDistanceMm(model.positions, result.candidates.front().scene_from_model, reference),
      1.0)
      << result.Summary();
  EXPECT_LT(result.candidates.front().icp.rmse_mm, 0.6);  // the scanner's noise, as on rs1
}

}  // namespace
}  // namespace lasercell::registration
