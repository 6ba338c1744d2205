#pragma once
// Pose clustering exactly as Skotheim et al. 2012, IV-E: hypotheses are
// (t, q) pairs; greedily, the highest-voted unassigned hypothesis seeds a cluster that takes every
// unassigned hypothesis within a fixed translation radius (kd-tree over translations) whose
// rotation distance theta = 2 acos(|<q1, q2>|) to the seed is below a threshold; the cluster
// score is the sum of its votes; at most max_clusters clusters are formed. Then, among clusters
// close in translation but different in orientation, only the best-scoring one is kept. The
// cluster pose is the vote-weighted average of its members (core/se3.hpp AveragePoses).
// Poses are scene_from_centered (the model centred at its centroid, so t is the model centre).
//
// RefineClusterPose then re-estimates a cluster's pose from its members' point correspondences:
// every hypothesis pairs a scene reference point s_r with a model reference point m_r (Drost et
// al. 2010, Sec. 3.3), and a vote-weighted closed-form rigid fit (Horn/Umeyama) of the m_r onto
// the s_r no longer carries each hypothesis's rotation error times the lever arm |m_r| into the
// translation, as the average does. Members whose correspondence lies farther than an inlier
// distance from the current pose are left out; a few rounds shrink from the average to the fit.
// Each round's closed-form fit is followed by a Gauss-Newton fit that trusts a correspondence
// along the scene normal more than across it (the two voxel grids put paired samples up to a
// step apart across the surface, far less along its normal). The fit uses the votes' own
// correspondences only (no search in the scene).

#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <span>
#include <vector>

#include "registration/ppf_matcher.hpp"

namespace lasercell::registration {

/// Options for ClusterPoses.
struct PoseClusteringOptions {
  /// Translation radius for cluster membership, mm (> 0). LocalizeInCloud derives it from the
  /// model (0.1 x diameter) unless set.
  double translation_radius_mm = 10.0;
  /// Maximum rotation distance theta to the seed, rad (in (0, pi]). 24 deg = two angle steps.
  double rotation_threshold_rad = 2.0 * std::numbers::pi / 15.0;
  /// Stop after this many clusters (>= 1).
  std::size_t max_clusters = 32;
  /// Clusters whose centres are closer than this keep only the best orientation, mm; 0 disables
  /// the suppression; negative is invalid. LocalizeInCloud derives it (0.1 x diameter) unless set.
  double duplicate_radius_mm = 10.0;
  /// Re-estimate each cluster's pose from its members' correspondences (RefineClusterPose).
  bool refine_poses = true;
  /// Its inlier distance, mm (> 0); LocalizeInCloud derives it from the model's sampling step
  /// (LocalizeOptions::cluster_refinement_inlier_steps) unless that is 0.
  double refinement_inlier_mm = 30.0;
  int refinement_rounds = 3;               ///< Fit rounds, in [1, 10].
  std::size_t refinement_min_members = 6;  ///< Fewer inliers keep the average pose (>= 3).
  /// Weight of a correspondence's offset across the scene normal relative to along it, in
  /// (0, 1]; 1 = plain point-to-point fit. The paired samples sit on one surface patch but on two
  /// voxel grids: across the normal they are up to a step apart (sigma ~ step / sqrt(6)), along it
  /// only by curvature and noise; 0.1 ~ (along / across sigma)^2 for a 3 mm vs 9 mm spread.
  double refinement_tangent_weight = 0.1;
  /// Throws OptionError naming the field when a value is out of range.
  void Check() const;
};

/// One cluster of hypotheses.
struct PoseCluster {
  Eigen::Isometry3d scene_from_centered = Eigen::Isometry3d::Identity();  ///< Weighted mean pose.
  double score = 0.0;                                                     ///< Sum of member votes.
  double seed_votes = 0.0;                       ///< Votes of the seed (the best member).
  std::size_t members = 0;                       ///< Hypotheses in the cluster.
  std::size_t seed = 0;                          ///< Index of the seed hypothesis.
  std::vector<std::uint32_t> member_hypotheses;  ///< Indices of its members (seed first).
  std::size_t fitted_members = 0;  ///< Members in RefineClusterPose's last fit (0: not refined).
  /// -1 when kept; otherwise index (into ClusteringResult::clusters) of the better cluster
  /// that suppressed it as a different orientation at the same place.
  int suppressed_by = -1;
};

/// Clusters in score order (best first). Suppressed clusters are reported, not dropped.
struct ClusteringResult {
  std::vector<PoseCluster> clusters;  ///< All clusters formed, best score first.
  std::size_t kept = 0;               ///< Clusters with suppressed_by == -1.
};

/// Skotheim IV-E clustering. Deterministic: ties in votes are broken by hypothesis index.
ClusteringResult ClusterPoses(std::span<const PoseHypothesis> hypotheses,
                              const PoseClusteringOptions& options);

/// RefineClusterPose (header): `scene_points` (and `scene_normals`, one per point, needed when
/// options.refinement_tangent_weight < 1) are the points the hypotheses' scene_reference indexes,
/// `model_points` the centred model points their model_reference indexes. Each of
/// options.refinement_rounds keeps the members whose |pose * m_r - s_r| is below
/// options.refinement_inlier_mm and fits them (Horn, then the normal-weighted fit); the cluster
/// keeps its pose when fewer than refinement_min_members are inliers or the inliers' model points
/// are nearly collinear (rotation about their line unobservable). Returns true when refined.
/// InputError for an index out of range or missing normals; OptionError for bad options.
bool RefineClusterPose(std::span<const PoseHypothesis> hypotheses,
                       std::span<const Eigen::Vector3d> scene_points,
                       std::span<const Eigen::Vector3d> scene_normals,
                       std::span<const Eigen::Vector3d> model_points,
                       const PoseClusteringOptions& options, PoseCluster* cluster);

/// theta = 2 acos(|<q1, q2>|), rad in [0, pi] (Skotheim IV-E).
double QuaternionDistance(const Eigen::Quaterniond& q1, const Eigen::Quaterniond& q2);

}  // namespace lasercell::registration
