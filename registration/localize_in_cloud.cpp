#include "registration/localize_in_cloud.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <iomanip>
#include <limits>
#include <numeric>
#include <sstream>

#include "core/error.hpp"
#include "core/pose_covariance.hpp"
#include "core/se3.hpp"
#include "registration/internal/rank_candidates.hpp"

namespace lasercell::registration {
namespace {

using Clock = std::chrono::steady_clock;

double MillisecondsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

void CheckSizes(const PointCloud& scene) {
  const std::size_t n = scene.size();
  auto check = [&](std::size_t size, const char* name) {
    if (size != 0 && size != n) {
      throw InputError(std::string("LocalizeInCloud scene: attribute '") + name + "' has " +
                       std::to_string(size) + " values for " + std::to_string(n) +
                       " points; every attribute must be empty or one per point");
    }
  };
  check(scene.normals.size(), "normals");
  check(scene.intensity.size(), "intensity");
  check(scene.profile.size(), "profile");
  check(scene.column.size(), "column");
  check(scene.timestamp_s.size(), "timestamp");
}

// Drops points with a non-finite position or a non-finite/zero normal; renormalizes normals.
PointCloud CleanScene(const PointCloud& scene, std::size_t* dropped) {
  CheckSizes(scene);
  std::vector<std::size_t> keep;
  keep.reserve(scene.size());
  for (std::size_t i = 0; i < scene.size(); ++i) {
    if (!scene.positions[i].allFinite()) continue;
    if (scene.HasNormals() && !(scene.normals[i].allFinite() && scene.normals[i].norm() > 1e-12))
      continue;
    keep.push_back(i);
  }
  *dropped = scene.size() - keep.size();
  PointCloud out = keep.size() == scene.size() ? scene : scene.Subset(keep);
  for (Eigen::Vector3d& n : out.normals) n.normalize();
  return out;
}

// Evenly spaced subset of at most `limit` indices (deterministic thinning of the ICP source).
std::vector<Eigen::Vector3d> ThinnedPoints(const std::vector<Eigen::Vector3d>& points,
                                           const std::vector<std::uint32_t>& indices,
                                           std::size_t limit) {
  std::vector<Eigen::Vector3d> out;
  const std::size_t n = indices.size();
  const std::size_t m = std::min(n, limit);
  out.reserve(m);
  for (std::size_t k = 0; k < m; ++k) out.push_back(points[indices[k * n / m]]);
  return out;
}

double Deg(double rad) { return rad * 180.0 / std::numbers::pi; }

// What the verification and refinement steps share within one LocalizeInCloud call.
struct RefineContext {
  const PpfModel& model;
  const LocalizeOptions& options;              // with derived absolute values
  const std::vector<Eigen::Vector3d>& points;  // scene points for verification and ICP
  VerificationOptions refined;                 // verification after ICP
  LocalizationTimings* timings;
};

LocalizationCandidate CandidateFromCluster(const ClusteringResult& clustering, std::size_t index,
                                           const PpfModel& model) {
  const PoseCluster& cluster = clustering.clusters[index];
  LocalizationCandidate candidate;
  candidate.cluster = index;
  candidate.votes = cluster.seed_votes;
  candidate.score = cluster.score;
  candidate.cluster_members = cluster.members;
  candidate.coarse_scene_from_model =
      cluster.scene_from_centered * model.model_from_centered().inverse();
  candidate.scene_from_model = candidate.coarse_scene_from_model;
  return candidate;
}

// Skotheim IV-G, repeated: ICP on the scene points the projection grid selects around the current
// pose, then a new selection around the refined pose (so clutter picked up by a coarse pose drops
// out), then the final verification with the tighter support distance.
void Refine(const RefineContext& ctx, std::vector<std::uint32_t> overlap,
            LocalizationCandidate* candidate) {
  const PpfModel& model = ctx.model;
  const LocalizeOptions& options = ctx.options;
  int iterations = 0;
  for (int round = 0; round < options.icp_rounds; ++round) {
    auto t = Clock::now();
    if (round > 0) {
      VerifyPose(ctx.points, model, candidate->scene_from_model, options.viewpoint, ctx.refined,
                 &overlap);
      ctx.timings->verification_ms += MillisecondsSince(t);
      t = Clock::now();
    }
    const std::vector<Eigen::Vector3d> source =
        ThinnedPoints(ctx.points, overlap, options.max_icp_source_points);
    const Eigen::Isometry3d centered_from_scene =
        (candidate->scene_from_model * model.model_from_centered()).inverse();
    candidate->icp = AlignIcp(source, model.refinement_tree(), model.refinement_normals(),
                              centered_from_scene, options.icp);
    candidate->icp_run = true;
    iterations += candidate->icp.iterations;
    ctx.timings->icp_ms += MillisecondsSince(t);
    if (candidate->icp.termination == IcpTermination::kTooFewCorrespondences) break;
    candidate->scene_from_model =
        candidate->icp.target_from_source.inverse() * model.model_from_centered().inverse();
  }
  candidate->icp.iterations = iterations;
  // The pose is the inverse of ICP's target_from_source (times the exact model_from_centered,
  // on the right, which leaves a left perturbation in the scene frame as it is). A last round
  // that lost its correspondences left the pose of the round before: no covariance for it.
  if (candidate->icp.termination != IcpTermination::kTooFewCorrespondences) {
    candidate->covariance =
        InverseCovariance(candidate->icp.target_from_source, candidate->icp.covariance);
    candidate->covariance_valid = candidate->icp.covariance_valid;
  }
  const auto t = Clock::now();
  candidate->verification =
      VerifyPose(ctx.points, model, candidate->scene_from_model, options.viewpoint, ctx.refined);
  ctx.timings->verification_ms += MillisecondsSince(t);
}

// The dense scene kept for normals that are fitted later, at the voxel-grid points only
// (LocalizeOptions::scene_normals_at_samples).
struct DenseScene {
  bool pending = false;               // normals still to be fitted
  PointCloud cloud;                   // cleaned, cropped, filtered; every point
  std::vector<std::size_t> index_of;  // point of the thinned scene -> point of `cloud`
};

// Steps 1-2: clean, region of interest, small clusters (Skotheim IV-A), normals toward the
// sensor (IV-B). With `thin_cell_mm` > 0 a scene whose normals are estimated is thinned to one
// point per cell of that size, the most central one (the verification's cell: nothing later reads
// more). Its normals are then either left to MatchAndCluster, which fits them at the voxel-grid
// points only (*dense keeps what it needs), or fitted here at every thinned point.
PointCloud PreprocessScene(const PointCloud& scene_in, const LocalizeOptions& options,
                           double thin_cell_mm, LocalizationResult* result, DenseScene* dense) {
  auto t = Clock::now();
  PointCloud scene = CleanScene(scene_in, &result->dropped_points);
  if (options.use_roi) scene = CropBox(scene, options.roi, options.roi_from_scene);
  if (options.remove_small_clusters && !scene.empty())
    scene = scene.Subset(RemoveSmallClusters(scene, options.cluster_filter).kept);
  result->timings.preprocess_ms = MillisecondsSince(t);
  ReportProgress(options.progress, "preprocess", 1.0);

  t = Clock::now();
  if (!scene.empty()) {
    if ((!scene.HasNormals() || options.recompute_normals) && options.scene_normals_at_samples) {
      dense->pending = true;
      if (thin_cell_mm > 0.0) {
        dense->index_of =
            OnePerCellIndices(scene.positions, thin_cell_mm, CellPoint::kNearestCentre);
      } else {
        dense->index_of.resize(scene.size());
        std::iota(dense->index_of.begin(), dense->index_of.end(), std::size_t{0});
      }
      dense->cloud = std::move(scene);
      scene = dense->cloud.Subset(dense->index_of);
      scene.normals.clear();
    } else if (!scene.HasNormals() || options.recompute_normals) {
      CloudWithNormals fitted = WithNormalsAtCells(scene, thin_cell_mm, options.normals);
      result->dropped_points += fitted.dropped;
      scene = std::move(fitted.cloud);
    } else if (options.orient_normals) {
      OrientNormalsTowardViewpoint(&scene, options.viewpoint);
    }
  }
  result->timings.normals_ms = MillisecondsSince(t);
  ReportProgress(options.progress, "normals", 1.0);
  result->used_points = scene.size();
  return scene;
}

// The voxel grid of a scene without normals, with a normal fitted per voxel at the scene point
// nearest its centroid, from that point's neighbourhood in the dense scene; voxels whose fit
// fails are dropped. The fit's time is added to *normals_ms.
PointCloud SamplesWithNormals(const PointCloud& scene, const DenseScene& dense,
                              const VoxelGridOptions& voxel, const NormalOptions& options,
                              double* normals_ms) {
  std::vector<std::int32_t> voxel_of;
  PointCloud grid = VoxelGridDownsample(scene, voxel, &voxel_of);
  std::vector<double> best(grid.size(), std::numeric_limits<double>::infinity());
  std::vector<std::size_t> at(grid.size(), 0);
  for (std::size_t i = 0; i < scene.size(); ++i) {
    if (voxel_of[i] < 0) continue;
    const auto v = static_cast<std::size_t>(voxel_of[i]);
    const double d = (scene.positions[i] - grid.positions[v]).squaredNorm();
    if (d < best[v]) {
      best[v] = d;
      at[v] = dense.index_of[i];
    }
  }
  const auto t = Clock::now();
  const NormalEstimationResult fit = EstimateNormalsAt(dense.cloud, at, options);
  *normals_ms += MillisecondsSince(t);
  std::vector<std::size_t> keep;
  keep.reserve(grid.size());
  std::vector<Eigen::Vector3d> normals;
  normals.reserve(grid.size());
  for (std::size_t v = 0; v < grid.size(); ++v) {
    if (!fit.valid[v]) continue;
    keep.push_back(v);
    normals.push_back(fit.normals[v]);
  }
  PointCloud out = grid.Subset(keep);
  out.normals = std::move(normals);
  return out;
}

// Steps 3-5: voxel grid at the model's sampling step (IV-C), PPF voting (IV-D, Drost 2010),
// pose clustering (IV-E).
ClusteringResult MatchAndCluster(const PointCloud& scene, const DenseScene& dense,
                                 const PpfModel& model, const LocalizeOptions& options,
                                 LocalizationResult* result) {
  auto t = Clock::now();
  VoxelGridOptions voxel;
  voxel.voxel_size_mm = options.scene_sampling_step_mm > 0.0 ? options.scene_sampling_step_mm
                                                             : model.sampling_step_mm();
  voxel.normal_mode = options.scene_normal_mode == VoxelNormalMode::kNone
                          ? VoxelNormalMode::kAverage
                          : options.scene_normal_mode;
  voxel.normal_split_angle_rad = options.scene_normal_split_angle_rad;
  double fit_ms = 0.0;
  PointCloud sampled = dense.pending
                           ? SamplesWithNormals(scene, dense, voxel, options.normals, &fit_ms)
                           : VoxelGridDownsample(scene, voxel);
  result->sampled_points = sampled.size();
  result->timings.normals_ms += fit_ms;
  result->timings.subsample_ms = MillisecondsSince(t) - fit_ms;
  ReportProgress(options.progress, "subsample", 1.0);

  t = Clock::now();
  const KdTree scene_tree(std::move(sampled.positions));
  result->timings.kdtree_ms = MillisecondsSince(t);
  t = Clock::now();
  const PpfMatchResult match = MatchPpf(scene_tree, sampled.normals, model, options.matching);
  result->reference_points = match.reference_points;
  result->scene_pairs = match.scene_pairs;
  result->votes_cast = match.votes_cast;
  result->hypotheses = match.hypotheses.size();
  result->timings.matching_ms = MillisecondsSince(t);
  ReportProgress(options.progress, "matching", 1.0);

  t = Clock::now();
  ClusteringResult clustering = ClusterPoses(match.hypotheses, options.clustering);
  if (options.clustering.refine_poses) {
    for (PoseCluster& cluster : clustering.clusters) {
      RefineClusterPose(match.hypotheses, scene_tree.points(), sampled.normals, model.points(),
                        options.clustering, &cluster);
    }
  }
  result->clusters = clustering.clusters.size();
  result->timings.clustering_ms = MillisecondsSince(t);
  ReportProgress(options.progress, "clustering", 1.0);
  return clustering;
}

// A candidate that passed the coarse check, waiting for refinement.
struct Pending {
  LocalizationCandidate candidate;
  std::vector<std::uint32_t> overlap;
  bool primary;  // a kept cluster (not an alternative orientation)
};

// Step 6, for one batch: coarse verification (IV-F) of the next kept clusters until `batch_size`
// primaries passed, each followed by the orientations it suppressed at the same place with
// nearly its score (symmetric or ambiguous views: ICP and the final support decide between
// them, and the result says so). Candidates failing the coarse check go to result->rejected.
std::vector<Pending> CoarseBatch(const RefineContext& ctx, const ClusteringResult& clustering,
                                 std::size_t batch_size, std::size_t* next_cluster,
                                 std::size_t* examined, LocalizationResult* result) {
  const LocalizeOptions& options = ctx.options;
  auto examine = [&](std::size_t index, bool primary, std::vector<Pending>* batch) {
    Pending p{CandidateFromCluster(clustering, index, ctx.model), {}, primary};
    p.candidate.coarse_verification =
        VerifyPose(ctx.points, ctx.model, p.candidate.scene_from_model, options.viewpoint,
                   options.verification, &p.overlap);
    p.candidate.verification = p.candidate.coarse_verification;
    if (!p.candidate.coarse_verification.accepted) {
      p.candidate.rejection_reason =
          "before ICP: " + p.candidate.coarse_verification.rejection_reason;
      result->rejected.push_back(std::move(p.candidate));
      return false;
    }
    batch->push_back(std::move(p));
    return primary;
  };
  std::vector<Pending> batch;
  std::size_t primaries = 0;
  for (; *next_cluster < clustering.clusters.size() && primaries < batch_size; ++*next_cluster) {
    const std::size_t c = *next_cluster;
    if (clustering.clusters[c].suppressed_by >= 0) continue;
    if (*examined >= options.max_verified_clusters) break;
    ++*examined;
    primaries += examine(c, true, &batch) ? 1 : 0;
    std::size_t alternatives = 0;
    for (std::size_t a = c + 1; a < clustering.clusters.size() && alternatives < 2; ++a) {
      const PoseCluster& alt = clustering.clusters[a];
      if (alt.suppressed_by != static_cast<int>(c) ||
          alt.score < options.ambiguity_score_ratio * clustering.clusters[c].score)
        continue;
      examine(a, false, &batch);
      ++alternatives;
    }
  }
  return batch;
}

// Steps 6-7: coarse verification and ICP with the scene as source and the model as target
// (IV-G), then re-verification. Clusters are taken in batches of max_instances +
// extra_refined_candidates that pass the coarse check: the first max_instances of a batch are
// always refined, the others only when their coarse support is close to the best seen. Another
// batch follows while fewer than max_instances candidates pass the final check (up to
// max_verified_clusters clusters). Returns the refined candidates (accepted or not).
std::vector<LocalizationCandidate> VerifyAndRefine(const RefineContext& ctx,
                                                   const ClusteringResult& clustering,
                                                   LocalizationResult* result) {
  const LocalizeOptions& options = ctx.options;
  const std::size_t batch_size = options.max_instances + options.extra_refined_candidates;
  std::vector<LocalizationCandidate> refined;
  std::size_t next_cluster = 0, examined = 0, final_accepted = 0;
  double best_coarse_support = 0.0;
  while (final_accepted < options.max_instances) {
    const auto t = Clock::now();
    std::vector<Pending> batch =
        CoarseBatch(ctx, clustering, batch_size, &next_cluster, &examined, result);
    result->timings.verification_ms += MillisecondsSince(t);
    if (batch.empty()) break;
    for (const Pending& p : batch)
      best_coarse_support = std::max(best_coarse_support, p.candidate.coarse_verification.support);
    std::size_t primary_rank = 0;
    for (Pending& p : batch) {
      LocalizationCandidate& candidate = p.candidate;
      const bool always = p.primary && primary_rank++ < options.max_instances;
      if (!options.run_icp) {
        refined.push_back(std::move(candidate));
        continue;
      }
      if (!always && candidate.coarse_verification.support <
                         options.extra_refined_min_relative_support * best_coarse_support) {
        candidate.rejection_reason =
            "coarse support " + std::to_string(candidate.coarse_verification.support) +
            " far below the best " + std::to_string(best_coarse_support) + " (not refined)";
        result->rejected.push_back(std::move(candidate));
        continue;
      }
      Refine(ctx, std::move(p.overlap), &candidate);
      final_accepted += candidate.verification.accepted ? 1 : 0;
      refined.push_back(std::move(candidate));
    }
    if (!options.run_icp) break;
  }
  return refined;
}

}  // namespace

namespace internal {

// Ranking by support after refinement (ties: cluster score); one instance per place. A second
// orientation at the same place with nearly the winner's support makes the result ambiguous; so
// does a planar model, whatever the scene (rotations about its normal are unobservable).
void RankCandidates(std::vector<LocalizationCandidate> refined, const PpfModel& model,
                    const LocalizeOptions& options, LocalizationResult* result) {
  const Eigen::Vector3d& var = model.principal_variances();
  if (var(0) > 0.0 && var(2) / var(0) < options.planarity_ratio) {
    result->ambiguous = true;
    result->ambiguity_reason = "planar model (principal variance ratio " +
                               std::to_string(var(2) / var(0)) +
                               "): rotations about its normal are not observable";
  }
  std::stable_sort(refined.begin(), refined.end(),
                   [](const LocalizationCandidate& a, const LocalizationCandidate& b) {
                     if (a.verification.accepted != b.verification.accepted)
                       return a.verification.accepted;
                     if (a.verification.support != b.verification.support)
                       return a.verification.support > b.verification.support;
                     return a.score > b.score;
                   });
  const double same_place_mm = options.clustering.duplicate_radius_mm;
  for (LocalizationCandidate& candidate : refined) {
    if (!candidate.verification.accepted) {
      candidate.rejection_reason =
          (candidate.icp_run ? "after ICP: " : "") + candidate.verification.rejection_reason;
      result->rejected.push_back(std::move(candidate));
      continue;
    }
    LocalizationCandidate* same_place = nullptr;
    double shift_mm = 0.0;  // between the model centres of same_place and candidate
    for (LocalizationCandidate& kept : result->candidates) {
      shift_mm = TranslationDistance(kept.scene_from_model * model.model_from_centered(),
                                     candidate.scene_from_model * model.model_from_centered());
      if (shift_mm < same_place_mm) {
        same_place = &kept;
        break;
      }
    }
    if (same_place != nullptr) {
      const double turn =
          RotationDistance(same_place->scene_from_model, candidate.scene_from_model);
      // Converged to the same pose (model moved by less than the refined support distance):
      // one answer found twice, so keep the evidence of the stronger cluster, its coarse pose
      // included; the supports differ only by ICP's convergence tolerance.
      const double resolution_mm = options.refined_support_distance_relative * model.diameter_mm();
      if (candidate.score > same_place->score &&
          shift_mm + turn * 0.5 * model.diameter_mm() < resolution_mm) {
        std::swap(same_place->rank, candidate.rank);
        std::swap(*same_place, candidate);
      }
      if (!result->ambiguous && turn > options.clustering.rotation_threshold_rad &&
          candidate.verification.support >=
              options.ambiguity_score_ratio * same_place->verification.support) {
        result->ambiguous = true;
        result->ambiguity_reason = "two orientations " + std::to_string(Deg(turn)) +
                                   " deg apart at the same place have support " +
                                   std::to_string(same_place->verification.support) + " and " +
                                   std::to_string(candidate.verification.support);
      }
      candidate.rejection_reason =
          "duplicate of rank " + std::to_string(same_place->rank) + " (same place after ICP)";
      result->rejected.push_back(std::move(candidate));
      continue;
    }
    if (result->candidates.size() >= options.max_instances) {
      candidate.rejection_reason = "beyond max_instances";
      result->rejected.push_back(std::move(candidate));
      continue;
    }
    candidate.rank = static_cast<int>(result->candidates.size()) + 1;
    result->candidates.push_back(std::move(candidate));
  }
  result->found = !result->candidates.empty();
}

}  // namespace internal

namespace {

// Why nothing was found. The strongest candidate is the one with the highest cluster score,
// whatever stage rejected it: supports before and after ICP use different distances and cannot
// be compared.
std::string NotFoundMessage(const LocalizationResult& result, const ClusteringResult& clustering) {
  const LocalizationCandidate* strongest = nullptr;
  double runner_up = 0.0;
  for (const LocalizationCandidate& c : result.rejected) {
    if (strongest == nullptr || c.score > strongest->score ||
        (c.score == strongest->score && c.cluster < strongest->cluster)) {
      if (strongest != nullptr) runner_up = std::max(runner_up, strongest->score);
      strongest = &c;
    } else {
      runner_up = std::max(runner_up, c.score);
    }
  }
  if (clustering.clusters.empty())
    return "no pose hypotheses: no scene pair matched the model's features";
  if (strongest == nullptr) return "no cluster could be examined";
  std::ostringstream m;
  m << "no candidate passed verification (" << result.rejected.size()
    << " rejected); the strongest, cluster " << strongest->cluster << " (score "
    << strongest->score;
  if (runner_up > 0.0)
    m << ", " << std::setprecision(2) << std::fixed << strongest->score / runner_up << "x the next";
  m << std::setprecision(3) << std::fixed << ", coarse support "
    << strongest->coarse_verification.support;
  if (strongest->icp_run)
    m << ", support after ICP " << strongest->verification.support << ", ICP rmse "
      << strongest->icp.rmse_mm << " mm";
  m << "), was rejected: " << strongest->rejection_reason;
  return m.str();
}

}  // namespace

void LocalizeOptions::Check() const {
  viewpoint.Check("LocalizeOptions.viewpoint");
  if (use_roi && roi.Empty())
    throw OptionError("LocalizeOptions.roi is empty (min > max) while use_roi is set");
  if (remove_small_clusters) cluster_filter.Check();
  normals.Check();
  if (!(scene_sampling_step_mm >= 0.0) || !std::isfinite(scene_sampling_step_mm)) {
    throw OptionError(
        "LocalizeOptions.scene_sampling_step_mm = " + std::to_string(scene_sampling_step_mm) +
        ": must be >= 0 mm (0 = the model's sampling step)");
  }
  matching.Check();
  clustering.Check();
  verification.Check();
  icp.Check();
  auto non_negative = [](double v, const char* field) {
    if (!(v >= 0.0) || !std::isfinite(v))
      throw OptionError(std::string("LocalizeOptions.") + field + " = " + std::to_string(v) +
                        ": must be >= 0");
  };
  non_negative(cluster_radius_relative, "cluster_radius_relative");
  non_negative(cluster_refinement_inlier_steps, "cluster_refinement_inlier_steps");
  if (!(scene_normal_split_angle_rad >= 0.0 && scene_normal_split_angle_rad <= std::numbers::pi)) {
    throw OptionError("LocalizeOptions.scene_normal_split_angle_rad = " +
                      std::to_string(scene_normal_split_angle_rad) + ": must be in [0, pi] rad");
  }
  non_negative(support_distance_relative, "support_distance_relative");
  non_negative(icp_max_distance_relative, "icp_max_distance_relative");
  non_negative(icp_covariance_block_relative, "icp_covariance_block_relative");
  non_negative(verification_cell_relative, "verification_cell_relative");
  if (!(refined_support_distance_relative > 0.0) ||
      !std::isfinite(refined_support_distance_relative)) {
    throw OptionError("LocalizeOptions.refined_support_distance_relative = " +
                      std::to_string(refined_support_distance_relative) +
                      ": must be > 0 (fraction of the model diameter)");
  }
  if (!(refined_min_support >= 0.0 && refined_min_support <= 1.0)) {
    throw OptionError("LocalizeOptions.refined_min_support = " +
                      std::to_string(refined_min_support) + ": must be in [0, 1]");
  }
  if (max_verified_clusters < 1)
    throw OptionError("LocalizeOptions.max_verified_clusters must be >= 1");
  if (!(extra_refined_min_relative_support >= 0.0 && extra_refined_min_relative_support <= 1.0)) {
    throw OptionError("LocalizeOptions.extra_refined_min_relative_support = " +
                      std::to_string(extra_refined_min_relative_support) + ": must be in [0, 1]");
  }
  if (icp_rounds < 1 || icp_rounds > 10)
    throw OptionError("LocalizeOptions.icp_rounds = " + std::to_string(icp_rounds) +
                      ": must be in [1, 10]");
  if (max_icp_source_points < 10)
    throw OptionError("LocalizeOptions.max_icp_source_points must be >= 10");
  if (max_instances < 1) throw OptionError("LocalizeOptions.max_instances must be >= 1");
  if (!(ambiguity_score_ratio > 0.0 && ambiguity_score_ratio <= 1.0)) {
    throw OptionError("LocalizeOptions.ambiguity_score_ratio = " +
                      std::to_string(ambiguity_score_ratio) + ": must be in (0, 1]");
  }
  non_negative(planarity_ratio, "planarity_ratio");
}

std::string LocalizationResult::Summary() const {
  std::ostringstream s;
  if (!found) {
    s << "not found: " << message;
  } else {
    const LocalizationCandidate& best = candidates.front();
    s << "found " << candidates.size() << " instance(s); best support "
      << best.verification.support;
    if (best.icp_run)
      s << ", icp rmse " << best.icp.rmse_mm << " mm, " << best.icp.inliers << " inliers";
  }
  if (ambiguous) s << "; AMBIGUOUS: " << ambiguity_reason;
  s << "; " << timings.total_ms << " ms (match " << timings.matching_ms << ", icp "
    << timings.icp_ms << ")";
  return s.str();
}

LocalizeOptions DerivedLocalizeOptions(const LocalizeOptions& options_in, const PpfModel& model) {
  LocalizeOptions options = options_in;
  const double diameter = model.diameter_mm();
  if (options.cluster_radius_relative > 0.0) {
    options.clustering.translation_radius_mm = options.cluster_radius_relative * diameter;
    options.clustering.duplicate_radius_mm = options.cluster_radius_relative * diameter;
  }
  if (options.cluster_refinement_inlier_steps > 0.0) {
    options.clustering.refinement_inlier_mm =
        options.cluster_refinement_inlier_steps * model.sampling_step_mm();
  }
  if (options.support_distance_relative > 0.0)
    options.verification.support_distance_mm = options.support_distance_relative * diameter;
  if (options.icp_max_distance_relative > 0.0) {
    options.icp.max_correspondence_distance_mm = options.icp_max_distance_relative * diameter;
    options.verification.overlap_band_mm = options.icp.max_correspondence_distance_mm;
  }
  if (options.icp_covariance_block_relative > 0.0) {
    options.icp.covariance_block_mm = options.icp_covariance_block_relative * diameter;
  }
  options.matching.threads = options.normals.threads = options.icp.threads = options.threads;
  options.normals.viewpoint = options.viewpoint;
  return options;
}

LocalizationResult LocalizeInCloud(const PointCloud& scene_in, const PpfModel& model,
                                   const LocalizeOptions& options_in) {
  options_in.Check();
  const auto start = Clock::now();
  LocalizationResult result;
  result.scene_points = scene_in.size();
  if (scene_in.empty())
    throw InputError("LocalizeInCloud: the scene cloud is empty; nothing to search");
  if (model.points().empty())
    throw InputError("LocalizeInCloud: the PPF model is empty; build it from a model cloud");
  const LocalizeOptions options = DerivedLocalizeOptions(options_in, model);

  // Steps 1-2: preprocessing and normals.
  const double refined_support_mm = options.refined_support_distance_relative * model.diameter_mm();
  const double thin_cell_mm = options.verification_cell_relative * refined_support_mm;
  DenseScene dense;
  const PointCloud scene = PreprocessScene(scene_in, options, thin_cell_mm, &result, &dense);
  if (scene.size() < 3) {
    result.message = "fewer than 3 scene points left after cleaning, ROI and filters";
    result.timings.total_ms = MillisecondsSince(start);
    return result;
  }

  // Steps 3-5: subsampling, voting, clustering.
  const ClusteringResult clustering = MatchAndCluster(scene, dense, model, options, &result);
  dense = DenseScene{};  // not read again

  // Steps 6-7 verify and refine against the scene thinned to one point per cell of a fraction of
  // the refined support distance.
  auto t = Clock::now();
  std::vector<Eigen::Vector3d> thinned;
  const std::vector<Eigen::Vector3d>* check_points = &scene.positions;
  if (thin_cell_mm > 0.0) {
    for (std::size_t i : OnePerCellIndices(scene.positions, thin_cell_mm))
      thinned.push_back(scene.positions[i]);
    check_points = &thinned;
  }
  result.timings.verification_ms = MillisecondsSince(t);
  RefineContext ctx{model, options, *check_points, options.verification, &result.timings};
  ctx.refined.support_distance_mm = refined_support_mm;
  ctx.refined.min_support = options.refined_min_support;
  std::vector<LocalizationCandidate> refined = VerifyAndRefine(ctx, clustering, &result);
  ReportProgress(options.progress, "refinement", 1.0);

  internal::RankCandidates(std::move(refined), model, options, &result);
  if (!result.found) result.message = NotFoundMessage(result, clustering);
  result.timings.total_ms = MillisecondsSince(start);
  return result;
}

LocalizationResult LocalizeInCloud(const PointCloud& scene, const PointCloud& model_cloud,
                                   const PpfModelOptions& model_options,
                                   const LocalizeOptions& options) {
  return LocalizeInCloud(scene, PpfModel::Build(model_cloud, model_options), options);
}

}  // namespace lasercell::registration
