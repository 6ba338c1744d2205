// The localize options file reaches every field of LocalizeOptions and PpfModelOptions.
#include "registration/localize_options_io.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <string>

#include "core/error.hpp"

namespace lasercell::registration {
namespace {

// Every key of the file, each with a value that differs from its default.
constexpr const char* kEveryKey = R"(format: lasercell.localize_options
version: 1
threads: 3
max_instances: 4
view_direction: [0, 1, -1]
roi:
  min_mm: [-1, -2, -3]
  max_mm: [4, 5, 6]
  roi_from_scene: {translation_mm: [10, 20, 30], rotation_wxyz: [0, 0, 0, 1]}
remove_small_clusters: true
cluster_filter: {radius_mm: 3.5, min_cluster_size: 77, use_grid_when_organized: false, grid_window: 2}
recompute_normals: true
scene_normals_at_samples: false
orient_normals: false
normals: {k: 17, radius_mm: 1.5, use_grid_when_organized: false, grid_window: 3,
          grid_max_distance_mm: 2.5, min_neighbors: 5}
scene_sampling_step_mm: 1.25
scene_normal_mode: nearest_point
scene_normal_split_angle_rad: 1.25
model:
  sampling_step_relative: 0.03
  sampling_step_mm: 2.5
  distance_step_relative: 0.06
  distance_step_mm: 3.5
  angle_step_rad: 0.25
  refinement_step_relative: 0.007
  normal_mode: nearest_point
  normal_split_angle_rad: 2.5
  max_model_points: 3000
  normals: {k: 9, radius_mm: 0.5, use_grid_when_organized: false, grid_window: 4,
            grid_max_distance_mm: 1.5, min_neighbors: 4}
matching: {reference_stride: 7, max_reference_points: 900, peaks_per_reference: 4,
           peak_min_relative: 0.6, min_votes: 5, spread_features: true, spread_alpha: true,
           unique_votes: true,
           max_entries_per_key: 77}
clustering: {translation_radius_mm: 12, rotation_threshold_rad: 0.3, max_clusters: 20,
             duplicate_radius_mm: 8, refine_poses: false, refinement_inlier_mm: 22,
             refinement_rounds: 4, refinement_min_members: 9, refinement_tangent_weight: 0.3}
cluster_radius_relative: 0.15
cluster_refinement_inlier_steps: 2.25
verification:
  grid_rows: 30
  grid_cols: 31
  support_distance_mm: 2.5
  min_support: 0.35
  min_visible_cells: 12
  cull_back_faces: false
  overlap_band_mm: 5.5
  constraints:
    enabled: true
    plane_normal: [0, 0, -1]
    plane_offset_mm: 12.5
    up_in_model: [[0, 0, 1], [1, 0, 0]]
    max_tilt_rad: 0.2
    max_penetration_mm: 3
support_distance_relative: 0.03
refined_support_distance_relative: 0.009
refined_min_support: 0.45
max_verified_clusters: 9
verification_cell_relative: 0.4
run_icp: false
icp: {metric: point_to_point, kernel: huber, kernel_scale_mm: 0.7, min_kernel_scale_mm: 0.3,
      max_correspondence_distance_mm: 9, max_iterations: 25, translation_tolerance_mm: 0.002,
      rotation_tolerance_rad: 0.00002, min_correspondences: 8, covariance_block_mm: 7.5,
      max_normal_angle_rad: 0.6}
icp_max_distance_relative: 0.04
icp_covariance_block_relative: 0.03
icp_rounds: 3
max_icp_source_points: 1200
extra_refined_candidates: 3
extra_refined_min_relative_support: 0.6
ambiguity_score_ratio: 0.8
planarity_ratio: 0.002
)";

TEST(ReadLocalizeOptions, EveryKeyReachesItsField) {
  const LocalizeSettings s = ParseLocalizeOptions(kEveryKey, "every.yaml");
  const LocalizeOptions& o = s.localize;
  EXPECT_EQ(o.threads, 3);
  EXPECT_EQ(o.max_instances, 4u);
  EXPECT_EQ(o.viewpoint.kind, Viewpoint::Kind::kDirection);
  EXPECT_EQ(o.viewpoint.direction, Eigen::Vector3d(0, 1, -1));
  EXPECT_TRUE(o.use_roi);
  EXPECT_EQ(o.roi.min, Eigen::Vector3d(-1, -2, -3));
  EXPECT_EQ(o.roi.max, Eigen::Vector3d(4, 5, 6));
  EXPECT_TRUE(o.roi_from_scene.translation().isApprox(Eigen::Vector3d(10, 20, 30)));
  EXPECT_TRUE(o.roi_from_scene.linear().isApprox(
      Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ()).toRotationMatrix(), 1e-12));
  EXPECT_TRUE(o.remove_small_clusters);
  EXPECT_EQ(o.cluster_filter.radius_mm, 3.5);
  EXPECT_EQ(o.cluster_filter.min_cluster_size, 77u);
  EXPECT_FALSE(o.cluster_filter.use_grid_when_organized);
  EXPECT_EQ(o.cluster_filter.grid_window, 2);
  EXPECT_TRUE(o.recompute_normals);
  EXPECT_FALSE(o.scene_normals_at_samples);
  EXPECT_FALSE(o.orient_normals);
  EXPECT_EQ(o.normals.k, 17u);
  EXPECT_EQ(o.normals.radius_mm, 1.5);
  EXPECT_FALSE(o.normals.use_grid_when_organized);
  EXPECT_EQ(o.normals.grid_window, 3);
  EXPECT_EQ(o.normals.grid_max_distance_mm, 2.5);
  EXPECT_EQ(o.normals.min_neighbors, 5u);
  EXPECT_EQ(o.scene_sampling_step_mm, 1.25);
  EXPECT_EQ(o.scene_normal_mode, VoxelNormalMode::kNearestPoint);
  EXPECT_EQ(o.scene_normal_split_angle_rad, 1.25);

  const PpfModelOptions& m = s.model;
  EXPECT_EQ(m.sampling_step_relative, 0.03);
  EXPECT_EQ(m.sampling_step_mm, 2.5);
  EXPECT_EQ(m.distance_step_relative, 0.06);
  EXPECT_EQ(m.distance_step_mm, 3.5);
  EXPECT_EQ(m.angle_step_rad, 0.25);
  EXPECT_EQ(m.refinement_step_relative, 0.007);
  EXPECT_EQ(m.normal_mode, VoxelNormalMode::kNearestPoint);
  EXPECT_EQ(m.normal_split_angle_rad, 2.5);
  EXPECT_EQ(m.max_model_points, 3000u);
  EXPECT_EQ(m.normals.k, 9u);
  EXPECT_EQ(m.normals.radius_mm, 0.5);
  EXPECT_FALSE(m.normals.use_grid_when_organized);
  EXPECT_EQ(m.normals.grid_window, 4);
  EXPECT_EQ(m.normals.grid_max_distance_mm, 1.5);
  EXPECT_EQ(m.normals.min_neighbors, 4u);

  EXPECT_EQ(o.matching.reference_stride, 7u);
  EXPECT_EQ(o.matching.max_reference_points, 900u);
  EXPECT_EQ(o.matching.peaks_per_reference, 4u);
  EXPECT_EQ(o.matching.peak_min_relative, 0.6);
  EXPECT_EQ(o.matching.min_votes, 5u);
  EXPECT_TRUE(o.matching.spread_features);
  EXPECT_TRUE(o.matching.spread_alpha);
  EXPECT_EQ(o.matching.max_entries_per_key, 77u);
  EXPECT_TRUE(o.matching.unique_votes);
  EXPECT_EQ(o.clustering.translation_radius_mm, 12);
  EXPECT_EQ(o.clustering.rotation_threshold_rad, 0.3);
  EXPECT_EQ(o.clustering.max_clusters, 20u);
  EXPECT_EQ(o.clustering.duplicate_radius_mm, 8);
  EXPECT_FALSE(o.clustering.refine_poses);
  EXPECT_EQ(o.clustering.refinement_inlier_mm, 22);
  EXPECT_EQ(o.clustering.refinement_rounds, 4);
  EXPECT_EQ(o.clustering.refinement_min_members, 9u);
  EXPECT_EQ(o.clustering.refinement_tangent_weight, 0.3);
  EXPECT_EQ(o.cluster_radius_relative, 0.15);
  EXPECT_EQ(o.cluster_refinement_inlier_steps, 2.25);

  const VerificationOptions& v = o.verification;
  EXPECT_EQ(v.grid_rows, 30);
  EXPECT_EQ(v.grid_cols, 31);
  EXPECT_EQ(v.support_distance_mm, 2.5);
  EXPECT_EQ(v.min_support, 0.35);
  EXPECT_EQ(v.min_visible_cells, 12u);
  EXPECT_FALSE(v.cull_back_faces);
  EXPECT_EQ(v.overlap_band_mm, 5.5);
  EXPECT_TRUE(v.constraints.enabled);
  EXPECT_EQ(v.constraints.plane_normal, Eigen::Vector3d(0, 0, -1));
  EXPECT_EQ(v.constraints.plane_offset_mm, 12.5);
  ASSERT_EQ(v.constraints.up_in_model.size(), 2u);
  EXPECT_EQ(v.constraints.up_in_model[0], Eigen::Vector3d(0, 0, 1));
  EXPECT_EQ(v.constraints.up_in_model[1], Eigen::Vector3d(1, 0, 0));
  EXPECT_EQ(v.constraints.max_tilt_rad, 0.2);
  EXPECT_EQ(v.constraints.max_penetration_mm, 3);
  EXPECT_EQ(o.support_distance_relative, 0.03);
  EXPECT_EQ(o.refined_support_distance_relative, 0.009);
  EXPECT_EQ(o.refined_min_support, 0.45);
  EXPECT_EQ(o.max_verified_clusters, 9u);
  EXPECT_EQ(o.verification_cell_relative, 0.4);

  EXPECT_FALSE(o.run_icp);
  EXPECT_EQ(o.icp.metric, IcpMetric::kPointToPoint);
  EXPECT_EQ(o.icp.kernel, RobustKernel::kHuber);
  EXPECT_EQ(o.icp.kernel_scale_mm, 0.7);
  EXPECT_EQ(o.icp.min_kernel_scale_mm, 0.3);
  EXPECT_EQ(o.icp.max_correspondence_distance_mm, 9);
  EXPECT_EQ(o.icp.max_iterations, 25);
  EXPECT_EQ(o.icp.translation_tolerance_mm, 0.002);
  EXPECT_EQ(o.icp.rotation_tolerance_rad, 0.00002);
  EXPECT_EQ(o.icp.min_correspondences, 8u);
  EXPECT_EQ(o.icp.covariance_block_mm, 7.5);
  EXPECT_EQ(o.icp.max_normal_angle_rad, 0.6);
  EXPECT_EQ(o.icp_max_distance_relative, 0.04);
  EXPECT_EQ(o.icp_covariance_block_relative, 0.03);
  EXPECT_EQ(o.icp_rounds, 3);
  EXPECT_EQ(o.max_icp_source_points, 1200u);
  EXPECT_EQ(o.extra_refined_candidates, 3u);
  EXPECT_EQ(o.extra_refined_min_relative_support, 0.6);
  EXPECT_EQ(o.ambiguity_score_ratio, 0.8);
  EXPECT_EQ(o.planarity_ratio, 0.002);

  // The values are in range: the checks of the structs pass.
  EXPECT_NO_THROW(o.Check());
  EXPECT_NO_THROW(m.Check());
}

TEST(ReadLocalizeOptions, AnEmptyFileKeepsTheDefaults) {
  const LocalizeSettings s = ParseLocalizeOptions("", "empty.yaml");
  const LocalizeOptions d;
  EXPECT_FALSE(s.localize.use_roi);
  EXPECT_EQ(s.localize.icp_rounds, d.icp_rounds);
  EXPECT_EQ(s.localize.verification.grid_rows, d.verification.grid_rows);
  EXPECT_FALSE(s.localize.verification.constraints.enabled);
  EXPECT_EQ(s.localize.icp.kernel, d.icp.kernel);
  EXPECT_EQ(s.model.angle_step_rad, PpfModelOptions().angle_step_rad);
  EXPECT_EQ(s.localize.viewpoint.kind, Viewpoint::Kind::kPoint);
}

TEST(ReadLocalizeOptions, ViewpointAtAPoint) {
  const LocalizeSettings s = ParseLocalizeOptions("viewpoint_mm: [1, 2, 3]\n", "v.yaml");
  EXPECT_EQ(s.localize.viewpoint.kind, Viewpoint::Kind::kPoint);
  EXPECT_EQ(s.localize.viewpoint.position, Eigen::Vector3d(1, 2, 3));
}

std::string ErrorOf(const std::string& text) {
  try {
    ParseLocalizeOptions(text, "opts.yaml");
  } catch (const OptionError& e) {
    return e.what();
  }
  return "";
}

TEST(ReadLocalizeOptions, AnUnknownKeyIsAnErrorNamingIt) {
  EXPECT_NE(ErrorOf("icp_roundz: 2\n").find("icp_roundz"), std::string::npos);
  EXPECT_NE(ErrorOf("icp: {kernal: huber}\n").find("icp.kernal"), std::string::npos);
  EXPECT_NE(ErrorOf("verification: {constraints: {enable: true}}\n")
                .find("verification.constraints.enable"),
            std::string::npos);
  EXPECT_NE(ErrorOf("model: {normals: {kk: 3}}\n").find("model.normals.kk"), std::string::npos);
  EXPECT_NE(ErrorOf("roi: {min_mm: [0, 0, 0], max_mm: [1, 1, 1], frame: x}\n").find("roi.frame"),
            std::string::npos);
  EXPECT_NE(ErrorOf("icp_roundz: 2\n").find("opts.yaml"), std::string::npos);
}

TEST(ReadLocalizeOptions, BadValuesNameTheField) {
  std::string m = ErrorOf("icp: {kernel: cauchy}\n");
  EXPECT_NE(m.find("icp.kernel"), std::string::npos) << m;
  EXPECT_NE(m.find("geman_mcclure"), std::string::npos) << m;
  m = ErrorOf("scene_normal_mode: mean\n");
  EXPECT_NE(m.find("scene_normal_mode"), std::string::npos) << m;
  m = ErrorOf(
      "roi: {min_mm: [0, 0, 0], max_mm: [1, 1, 1], "
      "roi_from_scene: {translation_mm: [0, 0, 0], rotation_wxyz: [1, 0, 0, 0.1]}}\n");
  EXPECT_NE(m.find("roi.roi_from_scene.rotation_wxyz"), std::string::npos) << m;
  EXPECT_NE(m.find("unit quaternion"), std::string::npos) << m;
  m = ErrorOf("verification: {constraints: {up_in_model: [[0, 0]]}}\n");
  EXPECT_NE(m.find("verification.constraints.up_in_model[0]"), std::string::npos) << m;
  m = ErrorOf("viewpoint_mm: [0, 0, 0]\nview_direction: [0, 0, -1]\n");
  EXPECT_NE(m.find("view_direction"), std::string::npos) << m;
  m = ErrorOf("format: lasercell.cell\n");
  EXPECT_NE(m.find("format"), std::string::npos) << m;
  m = ErrorOf("matching: {reference_stride: many}\n");
  EXPECT_NE(m.find("matching.reference_stride"), std::string::npos) << m;
}

}  // namespace
}  // namespace lasercell::registration
