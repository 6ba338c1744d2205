#pragma once
// LocalizeParts: the localization step of a job (Skotheim et al. 2012, section IV) for several
// parts and instances in one calibrated sweep expressed in the target frame (handling_base):
//   1. region of interest in the target frame (before anything per point),
//   2. normals from each point's neighbourhood, oriented along the point's own line of sight
//      (a moving sensor has no single viewpoint: each profile is seen from the camera centre
//      at its exposure, SweepResult::frame_from_sensor), fitted at one point per cell of the
//      finest verification cell of the parts (LocalizeOptions::verification_cell_relative;
//      nothing later reads more) from the dense sweep's neighbourhoods,
//   3. per part, per instance: registration::LocalizeInCloud (PPF, clustering, verification,
//      ICP) on the points not yet explained; the points an accepted instance explains (within
//      `explained_distance_relative` x its diameter of the posed model) are removed before the
//      next search, so they do not vote again and no part is reported twice,
//   4. poses target_from_<part> and grasps target_from_<grasp> = target_from_part *
//      part_from_grasp, with a 6x6 covariance (left perturbation in the target frame, [rotation
//      rad; translation mm]) that adds the ICP pose covariance, the covariance of the
//      calibrated edges that put the sweep into the target frame and the sensor's (laser
//      plane, and with its error modes the camera too, together with what they did to a
//      placement calibrated through them: laser_plane_uncertainty.hpp), first order,
//      independent,
//   5. graspability: accepted, not ambiguous (flat or symmetric parts are flagged, not posed
//      silently), ICP RMSE within max_rmse_factor x scan_noise_mm, and the grasp position's
//      3-sigma radius within grasp_tolerance_mm; otherwise the reason is given.
// Units mm, rad; timings ms.

#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

#include "core/point_cloud.hpp"
#include "core/progress.hpp"
#include "core/se3.hpp"
#include "localize/job.hpp"
#include "localize/laser_plane_uncertainty.hpp"
#include "localize/part_model.hpp"
#include "registration/localize_in_cloud.hpp"
#include "triangulation/sweep.hpp"

namespace lasercell::localize {

/// Options of LocalizeParts.
struct LocalizePartsOptions {
  bool use_roi = false;
  BoundingBox roi;  ///< In the target frame, mm.
  SupportPlane support;
  registration::LocalizeOptions localize;  ///< Base options of every search (max_instances,
                                           ///< viewpoint and normal handling are set here).
  double grasp_tolerance_mm = 10.0;        ///< > 0.
  double scan_noise_mm = 0.1;              ///< > 0.
  double max_rmse_factor = 5.0;            ///< >= 1.
  /// Scene points within this fraction of the part's diameter of an accepted instance's surface
  /// are removed before the next search, (0, 0.2].
  double explained_distance_relative = 0.02;
  /// Covariance of the target frame <- sensor placement (the calibrated edges on the path), left
  /// perturbation in the target frame; unset when unknown. Added to every pose covariance.
  std::optional<Matrix6d> placement_covariance;
  /// The calibrated laser plane's covariance (or the sensor's error modes with the
  /// placement's response to them) and the sweep's sensor poses; unset when unknown. Each pose
  /// then gains the sensor's share over the points its part explains (the scene must carry the
  /// `profile` attribute).
  std::optional<LaserPlaneUncertainty> laser_plane;
  int threads = 0;            ///< 0 = all cores.
  ProgressCallback progress;  ///< Called after each search ("<part> #k") with its fraction.
  /// Throws OptionError naming the field.
  void Check() const;
};

/// What the job asks for one part.
struct PartRequest {
  const PartModel* model = nullptr;  ///< Not owned; must outlive the call.
  int instances = 1;                 ///< >= 1.
};

/// A grasp frame of a found instance.
struct GraspPose {
  std::string name;                        ///< The part's grasp name.
  Eigen::Isometry3d target_from_grasp;     ///< The gripper_tcp target.
  Matrix6d covariance = Matrix6d::Zero();  ///< Left perturbation in the target frame.
  double position_sigma_mm = 0.0;  ///< sqrt of the largest eigenvalue of the position covariance.
  bool within_tolerance = false;   ///< 3 x position_sigma_mm <= grasp tolerance.
  /// The grasp's own fit (GraspFrame::refine_radius_mm > 0) decided the pose and its ICP term;
  /// false: the part's pose did (no radius, or the local fit was refused: local_note says why).
  bool refined_locally = false;
  std::size_t local_points = 0;  ///< Scan points of the local fit.
  double local_rmse_mm = 0.0;    ///< Its ICP RMSE.
  /// Translation of the grasp origin by the local fit against the part's pose, mm.
  double local_shift_mm = 0.0;
  std::string local_note;  ///< Why a requested local fit was not used ("" otherwise).
};

/// The terms `PartInstance::covariance` adds (same convention; zero when absent).
struct PoseCovarianceTerms {
  Matrix6d icp = Matrix6d::Zero();        ///< ICP normal equations x residual variance.
  Matrix6d placement = Matrix6d::Zero();  ///< Calibrated edges target <- sensor.
  /// Laser plane calibration; with the sensor's error modes, camera and plane together,
  /// including what they did to the placement (then `placement` holds only the placement's own
  /// noise, e.g. the touches).
  Matrix6d laser_plane = Matrix6d::Zero();
};

/// One found part instance.
struct PartInstance {
  std::string part;   ///< Part name.
  std::string frame;  ///< Instance frame, "<part>_<k>", k from 1 in order found.
  Eigen::Isometry3d target_from_part = Eigen::Isometry3d::Identity();
  Matrix6d covariance = Matrix6d::Zero();  ///< See the file comment.
  bool covariance_valid = false;           ///< False when ICP gave none.
  PoseCovarianceTerms covariance_terms;    ///< What `covariance` is made of.
  std::vector<GraspPose> grasps;
  bool graspable = false;            ///< Unambiguous, ICP fits, every grasp within the tolerance.
  std::string not_graspable_reason;  ///< Empty when graspable.
  bool ambiguous = false;            ///< Flat or symmetric: the pose is not determined.
  std::string ambiguity_reason;      ///< Why (empty when not ambiguous).
  registration::LocalizationCandidate candidate;  ///< Votes, support, ICP (pose in target).
  double search_ms = 0.0;                         ///< This search, all stages.
};

/// One part's searches.
struct PartSearch {
  std::string part;     ///< Part name.
  int requested = 0;    ///< Instances asked for.
  int found = 0;        ///< Instances found.
  std::string message;  ///< Why fewer than requested were found ("" when all were).
  registration::LocalizationTimings timings;  ///< Summed over this part's searches.
  /// Summed over this part's searches: the work that explains the timings.
  std::size_t sampled_points = 0;    ///< After the voxel grid.
  std::size_t reference_points = 0;  ///< PPF reference points.
  std::size_t scene_pairs = 0;       ///< Scene pairs looked up in the model table.
  std::size_t votes_cast = 0;        ///< Accumulator increments.
  /// Per found instance after LocalizeInCloud: the grasps' local fits, removing the explained
  /// points and the laser plane's covariance term, ms.
  double judgement_ms = 0.0;
  std::vector<registration::LocalizationCandidate> rejected;  ///< Of the last search.
};

/// Wall time of the stages before the searches, ms.
struct LocalizePartsTimings {
  double roi_ms = 0.0;
  double normals_ms = 0.0;
  double searches_ms = 0.0;
  double total_ms = 0.0;
};

/// Everything LocalizeParts found.
struct LocalizePartsResult {
  std::vector<PartInstance> instances;  ///< In the order found.
  std::vector<PartSearch> searches;     ///< One per requested part, in request order.
  std::size_t sweep_points = 0;         ///< In the scene given.
  std::size_t roi_points = 0;           ///< Inside the ROI.
  std::size_t normal_points = 0;        ///< Thinned, with a normal (searched).
  LocalizePartsTimings timings;
  /// Every requested instance found.
  bool AllFound() const;
};

/// Unit vectors from each point of `sweep` toward the camera centre of its profile (the cloud's
/// `profile` attribute indexes sweep.frame_from_sensor). Throws InputError when the cloud has no
/// profile attribute or a profile index has no pose.
std::vector<Eigen::Vector3d> LinesOfSight(const triangulation::SweepResult& sweep);

/// Localizes the requested parts in `scene` (target frame, mm) whose points see the sensor
/// along `line_of_sight` (one unit vector per point toward the sensor; empty = straight up,
/// +z). Throws InputError for an empty scene, an ROI holding no point, sizes that disagree or a
/// request without a model; OptionError for bad options.
LocalizePartsResult LocalizeParts(const PointCloud& scene,
                                  const std::vector<Eigen::Vector3d>& line_of_sight,
                                  const std::vector<PartRequest>& requests,
                                  const LocalizePartsOptions& options);

}  // namespace lasercell::localize
