#pragma once
// Pose clustering exactly as Skotheim et al. 2012, IV-E: hypotheses are
// (t, q) pairs; greedily, the highest-voted unassigned hypothesis seeds a cluster that takes every
// unassigned hypothesis within a fixed translation radius (kd-tree over translations) whose
// rotation distance theta = 2 acos(|<q1, q2>|) to the seed is below a threshold; the cluster
// score is the sum of its votes; at most max_clusters clusters are formed. Then, among clusters
// close in translation but different in orientation, only the best-scoring one is kept. The
// cluster pose is the vote-weighted average of its members (core/se3.hpp AveragePoses).
// Poses are scene_from_centered (the model centred at its centroid, so t is the model centre).

#include <Eigen/Geometry>
#include <cstddef>
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
  /// Throws OptionError naming the field when a value is out of range.
  void Check() const;
};

/// One cluster of hypotheses.
struct PoseCluster {
  Eigen::Isometry3d scene_from_centered = Eigen::Isometry3d::Identity();  ///< Weighted mean pose.
  double score = 0.0;                                                     ///< Sum of member votes.
  double seed_votes = 0.0;  ///< Votes of the seed (the best member).
  std::size_t members = 0;  ///< Hypotheses in the cluster.
  std::size_t seed = 0;     ///< Index of the seed hypothesis.
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

/// theta = 2 acos(|<q1, q2>|), rad in [0, pi] (Skotheim IV-E).
double QuaternionDistance(const Eigen::Quaterniond& q1, const Eigen::Quaterniond& q2);

}  // namespace lasercell::registration
