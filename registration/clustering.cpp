#include "registration/clustering.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
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
  if (!(refinement_inlier_mm > 0.0) || !std::isfinite(refinement_inlier_mm)) {
    throw OptionError("PoseClusteringOptions.refinement_inlier_mm = " +
                      std::to_string(refinement_inlier_mm) + ": must be a positive distance in mm");
  }
  if (refinement_rounds < 1 || refinement_rounds > 10) {
    throw OptionError("PoseClusteringOptions.refinement_rounds = " +
                      std::to_string(refinement_rounds) + ": must be in [1, 10]");
  }
  if (refinement_min_members < 3)
    throw OptionError("PoseClusteringOptions.refinement_min_members must be >= 3");
  if (!(refinement_tangent_weight > 0.0 && refinement_tangent_weight <= 1.0)) {
    throw OptionError("PoseClusteringOptions.refinement_tangent_weight = " +
                      std::to_string(refinement_tangent_weight) + ": must be in (0, 1]");
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
      cluster.member_hypotheses.push_back(static_cast<std::uint32_t>(h.index));
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

namespace {

// Gauss-Newton on E = sum w_i r_i^T A_i r_i, r_i = pose * m_i - s_i, A_i = n_i n_i^T +
// tangent_weight (I - n_i n_i^T): each correspondence is trusted along the scene normal n_i and
// only weakly across it, where the two voxel grids put the paired samples up to a step apart.
// Left perturbation pose <- Exp(xi) pose, xi = (omega, v): d r / d xi = [-[q]x, I].
Eigen::Isometry3d AnisotropicFit(const std::vector<Eigen::Vector3d>& model,
                                 const std::vector<Eigen::Vector3d>& scene,
                                 const std::vector<Eigen::Vector3d>& normals,
                                 const std::vector<double>& weights, double tangent_weight,
                                 Eigen::Isometry3d pose) {
  for (int iteration = 0; iteration < 5; ++iteration) {
    Matrix6d h = Matrix6d::Zero();
    Vector6d g = Vector6d::Zero();
    for (std::size_t i = 0; i < model.size(); ++i) {
      const Eigen::Vector3d q = pose * model[i];
      const Eigen::Vector3d& n = normals[i];
      const Eigen::Matrix3d a =
          n * n.transpose() + tangent_weight * (Eigen::Matrix3d::Identity() - n * n.transpose());
      Eigen::Matrix<double, 3, 6> j;
      j << -Skew(q), Eigen::Matrix3d::Identity();
      h += weights[i] * j.transpose() * a * j;
      g += weights[i] * j.transpose() * a * (q - scene[i]);
    }
    const Eigen::LDLT<Matrix6d> ldlt(h);
    if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) break;
    const Vector6d xi = -ldlt.solve(g);
    if (!xi.allFinite()) break;
    pose = PoseFromRotationVectorTranslation(xi) * pose;
    if (xi.head<3>().norm() < 1e-9 && xi.tail<3>().norm() < 1e-6) break;
  }
  return pose;
}

}  // namespace

bool RefineClusterPose(std::span<const PoseHypothesis> hypotheses,
                       std::span<const Eigen::Vector3d> scene_points,
                       std::span<const Eigen::Vector3d> scene_normals,
                       std::span<const Eigen::Vector3d> model_points,
                       const PoseClusteringOptions& options, PoseCluster* cluster) {
  options.Check();
  const bool anisotropic = options.refinement_tangent_weight < 1.0;
  if (anisotropic && scene_normals.size() != scene_points.size()) {
    throw InputError("RefineClusterPose: " + std::to_string(scene_normals.size()) +
                     " scene normals for " + std::to_string(scene_points.size()) +
                     " scene points (refinement_tangent_weight < 1 needs one per point)");
  }
  std::vector<Eigen::Vector3d> model, scene, normals;
  std::vector<double> weights;
  Eigen::Isometry3d pose = cluster->scene_from_centered;
  bool refined = false;
  for (int round = 0; round < options.refinement_rounds; ++round) {
    model.clear();
    scene.clear();
    normals.clear();
    weights.clear();
    for (const std::uint32_t index : cluster->member_hypotheses) {
      if (index >= hypotheses.size()) throw InputError("RefineClusterPose: member out of range");
      const PoseHypothesis& h = hypotheses[index];
      if (h.model_reference >= model_points.size() || h.scene_reference >= scene_points.size())
        throw InputError("RefineClusterPose: a hypothesis indexes a point out of range");
      const Eigen::Vector3d& m = model_points[h.model_reference];
      const Eigen::Vector3d& s = scene_points[h.scene_reference];
      if ((pose * m - s).norm() >= options.refinement_inlier_mm) continue;
      model.push_back(m);
      scene.push_back(s);
      if (anisotropic) normals.push_back(scene_normals[h.scene_reference]);
      weights.push_back(h.votes);
    }
    if (model.size() < options.refinement_min_members) break;
    // Collinear model points leave the rotation about their line free: keep the pose.
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d& m : model) mean += m;
    mean /= static_cast<double>(model.size());
    Eigen::Matrix3d spread = Eigen::Matrix3d::Zero();
    for (const Eigen::Vector3d& m : model) spread += (m - mean) * (m - mean).transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(spread);
    if (!(es.eigenvalues()(1) > 1e-6 * es.eigenvalues()(2))) break;
    pose = HornRigidTransform(model, scene, weights);
    if (anisotropic) {
      pose =
          AnisotropicFit(model, scene, normals, weights, options.refinement_tangent_weight, pose);
    }
    cluster->fitted_members = model.size();
    refined = true;
  }
  if (refined) cluster->scene_from_centered = pose;
  return refined;
}

}  // namespace lasercell::registration
