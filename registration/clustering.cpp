#include "registration/clustering.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

#include "core/error.hpp"
#include "core/se3.hpp"
#include "registration/kdtree.hpp"

namespace lasercell::registration {

void PoseClusteringOptions::Check() const {
  if (!(translation_radius_mm > 0.0) || !std::isfinite(translation_radius_mm)) {
    throw OptionError(
        "PoseClusteringOptions.translation_radius_mm = " + std::to_string(translation_radius_mm) +
        ": must be a positive distance in mm");
  }
  if (!(rotation_threshold_rad > 0.0 && rotation_threshold_rad <= std::numbers::pi)) {
    throw OptionError("PoseClusteringOptions.rotation_threshold_rad = " +
                      std::to_string(rotation_threshold_rad) + ": must be in (0, pi] rad");
  }
  if (max_clusters < 1) throw OptionError("PoseClusteringOptions.max_clusters must be >= 1");
  if (!(duplicate_radius_mm >= 0.0) || !std::isfinite(duplicate_radius_mm)) {
    throw OptionError(
        "PoseClusteringOptions.duplicate_radius_mm = " + std::to_string(duplicate_radius_mm) +
        ": must be >= 0 mm (0 disables the suppression)");
  }
}

double QuaternionDistance(const Eigen::Quaterniond& q1, const Eigen::Quaterniond& q2) {
  return 2.0 * std::acos(std::min(1.0, std::abs(q1.coeffs().dot(q2.coeffs()))));
}

ClusteringResult ClusterPoses(std::span<const PoseHypothesis> hypotheses,
                              const PoseClusteringOptions& options) {
  options.Check();
  ClusteringResult result;
  const std::size_t n = hypotheses.size();
  if (n == 0) return result;

  std::vector<Eigen::Vector3d> translations(n);
  std::vector<Eigen::Quaterniond> rotations(n);
  for (std::size_t i = 0; i < n; ++i) {
    translations[i] = hypotheses[i].scene_from_centered.translation();
    rotations[i] = Eigen::Quaterniond(hypotheses[i].scene_from_centered.linear()).normalized();
  }
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return hypotheses[a].votes > hypotheses[b].votes;
  });

  const KdTree tree(translations);
  std::vector<bool> assigned(n, false);
  std::vector<Neighbor> hits;
  std::vector<Eigen::Isometry3d> member_poses;
  std::vector<double> member_votes;
  for (std::size_t seed : order) {
    if (result.clusters.size() >= options.max_clusters) break;
    if (assigned[seed]) continue;
    // Neighbours in translation (fixed radius), then the rotation test against the seed.
    tree.RadiusSearch(translations[seed], options.translation_radius_mm, &hits, /*sorted=*/true);
    PoseCluster cluster;
    cluster.seed = seed;
    cluster.seed_votes = hypotheses[seed].votes;
    member_poses.clear();
    member_votes.clear();
    for (const Neighbor& h : hits) {
      if (assigned[h.index]) continue;
      if (h.index != seed &&
          QuaternionDistance(rotations[seed], rotations[h.index]) >= options.rotation_threshold_rad)
        continue;
      assigned[h.index] = true;
      cluster.score += hypotheses[h.index].votes;
      ++cluster.members;
      member_poses.push_back(hypotheses[h.index].scene_from_centered);
      member_votes.push_back(hypotheses[h.index].votes);
    }
    cluster.scene_from_centered = AveragePoses(member_poses, member_votes);
    result.clusters.push_back(cluster);
  }

  std::stable_sort(result.clusters.begin(), result.clusters.end(),
                   [](const PoseCluster& a, const PoseCluster& b) { return a.score > b.score; });
  // Among clusters close in translation keep only the best orientation (Skotheim IV-E).
  for (std::size_t i = 0; i < result.clusters.size(); ++i) {
    PoseCluster& c = result.clusters[i];
    for (std::size_t j = 0; j < i && options.duplicate_radius_mm > 0.0; ++j) {
      const PoseCluster& better = result.clusters[j];
      if (better.suppressed_by >= 0) continue;
      if ((better.scene_from_centered.translation() - c.scene_from_centered.translation()).norm() <
          options.duplicate_radius_mm) {
        c.suppressed_by = static_cast<int>(j);
        break;
      }
    }
    if (c.suppressed_by < 0) ++result.kept;
  }
  return result;
}

}  // namespace lasercell::registration
