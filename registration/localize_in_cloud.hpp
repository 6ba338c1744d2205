#pragma once
// LocalizeInCloud: the seven localization steps of Skotheim et al. 2012 (section IV) over one
// scene:
//   1. region of interest + removal of small connected components (filters.hpp),
//   2. normals (PCA, toward the sensor) when the scene has none (normals.hpp): the scene is first
//      thinned to one point per verification cell (below), the finest set any later step reads,
//      and the normals are fitted at those points from their neighbourhoods in the dense scene,
//   3. voxel-grid subsampling at the model's sampling step (filters.hpp),
//   4. Drost PPF voting (ppf_matcher.hpp),
//   5. pose clustering (clustering.hpp),
//   6. verification: pose constraints + projection grid (verification.hpp), against the scene
//      thinned to one point per cell of half the refined support distance,
//   7. ICP, scene as source and model as target, on the grid-selected scene points (icp.hpp).
// Frames: the scene's frame is `scene`, the model's `model`; poses are scene_from_model.
// Units: mm, rad; timings in milliseconds (names end in _ms).
// Outcomes such as "no part in the scene" are reported (found = false), never thrown; invalid
// input or options throw InputError / OptionError naming the field.

#include <Eigen/Geometry>
#include <cstddef>
#include <numbers>
#include <string>
#include <vector>

#include "core/point_cloud.hpp"
#include "core/progress.hpp"
#include "registration/clustering.hpp"
#include "registration/filters.hpp"
#include "registration/icp.hpp"
#include "registration/normals.hpp"
#include "registration/ppf_matcher.hpp"
#include "registration/ppf_model.hpp"
#include "registration/verification.hpp"
#include "registration/viewpoint.hpp"

namespace lasercell::registration {

/// Options for LocalizeInCloud. Fields ending in _relative are fractions of the model diameter
/// and, when > 0, override the absolute value of the stage option they name.
struct LocalizeOptions {
  Viewpoint viewpoint;  ///< Sensor, in the scene frame (normal orientation, projection grid).
  int threads = 0;      ///< Overrides the threads of every stage: 0 = all cores, 1 = one thread.
  /// Called from the calling thread after each stage ("preprocess", "normals", "subsample",
  /// "matching", "clustering", "refinement") with fraction 1; may be empty.
  ProgressCallback progress;

  // Step 1: region of interest and small-cluster removal.
  bool use_roi = false;                                              ///< Crop to `roi` first.
  BoundingBox roi;                                                   ///< Box in the roi frame, mm.
  Eigen::Isometry3d roi_from_scene = Eigen::Isometry3d::Identity();  ///< Frame of the box.
  bool remove_small_clusters = false;   ///< Connected-component filter.
  ClusterFilterOptions cluster_filter;  ///< Its parameters.

  // Step 2: normals.
  bool recompute_normals = false;  ///< Estimate normals even when the scene has them.
  bool orient_normals = true;      ///< Flip given scene normals to face the viewpoint.
  NormalOptions normals;           ///< For estimation (viewpoint and threads are overridden).
  /// A scene whose normals are estimated gets them only where they are read: at its voxel-grid
  /// points (step 3), one fit per voxel at the scene point nearest the voxel's centroid, from
  /// that point's neighbourhood in the dense scene (Drost's voting reads no other normal;
  /// verification and ICP use the model's). false: a fit at every point of the verification
  /// thinning, averaged per voxel and split by scene_normal_split_angle_rad, which keeps apart
  /// the two faces of a wall thinner than a voxel when a sweep sees both; ~25x the fits.
  bool scene_normals_at_samples = true;

  // Step 3: subsampling.
  double scene_sampling_step_mm = 0.0;  ///< Scene voxel size, mm; 0 = the model's sampling step.
  /// Normals of the subsampled scene: voxel mean (default) or carried from the dense point
  /// nearest the voxel centroid, as the seed does.
  VoxelNormalMode scene_normal_mode = VoxelNormalMode::kAverage;
  /// Scene voxels split by normal as the model's are (PpfModelOptions::normal_split_angle_rad),
  /// rad in [0, pi]; 0 = one point per voxel.
  double scene_normal_split_angle_rad = std::numbers::pi / 2.0;

  // Steps 4-5: voting and clustering.
  PpfMatchOptions matching;
  PoseClusteringOptions clustering;
  double cluster_radius_relative =
      0.1;  ///< -> clustering.translation_radius_mm and duplicate_radius_mm.
  /// -> clustering.refinement_inlier_mm, in model sampling steps (0: keep the absolute value).
  /// A correct correspondence pairs points of one surface patch sampled on two voxel grids, so
  /// it is off by up to about one step; 1.5 steps also admits the average pose's own error.
  double cluster_refinement_inlier_steps = 1.5;

  // Step 6: verification (coarse pose, before ICP) and after ICP.
  VerificationOptions verification;
  double support_distance_relative = 0.02;  ///< -> verification.support_distance_mm (coarse).
  double refined_support_distance_relative = 0.008;  ///< Support distance after ICP (> 0).
  double refined_min_support = 0.4;                  ///< Minimum support after ICP, fraction.
  std::size_t max_verified_clusters = 12;  ///< Kept clusters examined at most, best score first.
  /// The scene used for verification and as ICP source keeps one point per cubic cell whose edge
  /// is this fraction of the refined support distance (0 = every point). Dense scans carry far
  /// more points than the support test needs; thinning in space (not by index, which leaves
  /// gaps along the rows of an organized scan) keeps a point within sqrt(3) x this fraction of
  /// the support distance of every dropped one (0.87 x at 0.5), so a model cell lying on the scan
  /// stays supported wherever the cells fall. >= 0.
  double verification_cell_relative = 0.5;

  // Step 7: ICP.
  bool run_icp = true;
  IcpOptions icp;
  double icp_max_distance_relative =
      0.03;  ///< -> icp.max_correspondence_distance_mm and overlap band.
  /// -> icp.covariance_block_mm (0: keep the absolute value). Neighbouring scene points share
  /// local errors (the model's facets against the real surface, a scan's ripple), so the pose
  /// covariance groups their residuals in cubes of this side (icp.hpp, cluster-robust
  /// sandwich): about 3x the length over which errors are shared, yet small enough that a part
  /// leaves dozens of groups (a 0.05 x diameter grid over a part seen from one side gives
  /// ~50-100). >= 0.
  double icp_covariance_block_relative = 0.05;
  /// ICP rounds; each round after the first re-selects the overlapping scene points around the
  /// refined pose (clutter selected by a coarse pose drops out). In [1, 10].
  int icp_rounds = 2;
  std::size_t max_icp_source_points =
      1500;  ///< Grid-selected scene points are thinned to this (>= 10).
  std::size_t extra_refined_candidates = 2;  ///< Refine max_instances + this many candidates...
  /// ... but the extra ones only with coarse support >= this fraction of the best coarse support.
  double extra_refined_min_relative_support = 0.5;

  // Output.
  std::size_t max_instances = 1;  ///< Instances reported at most (>= 1).
  /// Ambiguity: orientations suppressed by a kept cluster at the same place with at least this
  /// fraction of its score are refined too (at most 2 per cluster); if one ends with at least this
  /// fraction of the winner's support after ICP, the result is flagged ambiguous. In (0, 1].
  double ambiguity_score_ratio = 0.9;
  /// Ambiguity: model principal variances min/max below this flag a planar model.
  double planarity_ratio = 1e-3;

  /// Throws OptionError naming the field for any value out of range (stages included).
  void Check() const;
};

/// One candidate pose and the evidence for it.
struct LocalizationCandidate {
  int rank = 0;  ///< 1 = best; 0 for rejected candidates.
  Eigen::Isometry3d scene_from_model = Eigen::Isometry3d::Identity();         ///< Final pose.
  Eigen::Isometry3d coarse_scene_from_model = Eigen::Isometry3d::Identity();  ///< From clustering.
  double votes = 0.0;                      ///< Votes of the cluster's best hypothesis.
  double score = 0.0;                      ///< Cluster score (sum of member votes).
  std::size_t cluster_members = 0;         ///< Hypotheses in the cluster.
  std::size_t cluster = 0;                 ///< Index into the (score-ordered) clustering output.
  VerificationResult coarse_verification;  ///< Before ICP.
  VerificationResult verification;         ///< After ICP (the coarse one when ICP did not run).
  bool icp_run = false;                    ///< ICP refined the pose (LocalizeOptions::icp).
  IcpResult icp;  ///< Last ICP round (iterations summed over rounds); valid when icp_run.
  /// Covariance of scene_from_model over [rotation vector (rad); translation (mm)], left
  /// perturbation in the scene frame (scene_from_model_true = Exp(xi) * scene_from_model): the
  /// last ICP round's covariance of model_from_scene, inverted (InverseCovariance,
  /// core/pose_covariance.hpp). It holds the fit's share only (see icp.hpp for the estimator and
  /// what it assumes). Finite; meaningful only when covariance_valid.
  Matrix6d covariance = Matrix6d::Identity() * kIcpUnobservableVariance;
  /// True when ICP ran and its covariance is valid (IcpResult::covariance_valid).
  bool covariance_valid = false;
  std::string rejection_reason;  ///< Why it was rejected; empty for ranked candidates.
};

/// Wall time per stage, milliseconds.
struct LocalizationTimings {
  double preprocess_ms = 0.0;  ///< Cleaning, ROI, cluster filter.
  double normals_ms = 0.0;     ///< Normal estimation or orientation.
  double subsample_ms = 0.0;   ///< Voxel grid.
  double kdtree_ms = 0.0;      ///< Scene kd-tree.
  double matching_ms = 0.0;    ///< PPF voting.
  double clustering_ms = 0.0;
  double verification_ms = 0.0;  ///< Both verification passes.
  double icp_ms = 0.0;
  double total_ms = 0.0;
};

/// Everything LocalizeInCloud found.
struct LocalizationResult {
  bool found = false;                             ///< At least one candidate accepted.
  std::vector<LocalizationCandidate> candidates;  ///< Accepted, best first, <= max_instances.
  std::vector<LocalizationCandidate> rejected;    ///< Examined and rejected, with reasons.
  bool ambiguous = false;                         ///< Planar/symmetric: see ambiguity_reason.
  std::string ambiguity_reason;                   ///< Why (empty when not ambiguous).
  std::string message;                            ///< Why nothing was found (when !found).
  LocalizationTimings timings;
  std::size_t scene_points = 0;    ///< Input points.
  std::size_t dropped_points = 0;  ///< Non-finite positions/normals or zero normals.
  std::size_t used_points = 0;     ///< After ROI, filters, normals (and thinning when estimated).
  std::size_t sampled_points = 0;  ///< After the voxel grid.
  std::size_t reference_points = 0;
  std::size_t scene_pairs = 0;  ///< Scene pairs looked up in the model table.
  std::size_t votes_cast = 0;   ///< Accumulator increments.
  std::size_t hypotheses = 0;
  std::size_t clusters = 0;
  /// One line: found, best pose support/rmse, timings.
  std::string Summary() const;
};

/// The options with every `*_relative` field turned into its absolute stage option (fractions of
/// the model's diameter or sampling step) and the thread count passed to the stages: what
/// LocalizeInCloud runs with, for callers that run a stage themselves (a grasp's local ICP).
LocalizeOptions DerivedLocalizeOptions(const LocalizeOptions& options, const PpfModel& model);

/// Localizes `model` in `scene` (see the file comment). Throws InputError for an empty scene or
/// attribute sizes that disagree, OptionError for bad options.
LocalizationResult LocalizeInCloud(const PointCloud& scene, const PpfModel& model,
                                   const LocalizeOptions& options = {});

/// Convenience: builds the model from `model_cloud` first (model build time not in timings).
LocalizationResult LocalizeInCloud(const PointCloud& scene, const PointCloud& model_cloud,
                                   const PpfModelOptions& model_options,
                                   const LocalizeOptions& options = {});

}  // namespace lasercell::registration
