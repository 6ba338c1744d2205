#pragma once
// A reference pose for a real scan without ground truth (the UWA scenes ship none): the pose a
// part's model settles at when every available point is used, with the checks that make it a
// reference rather than one method's output.
//   1. High-effort LocalizeInCloud: the model sampled finely, every raw model point kept for
//      refinement, every scene point a reference point, spread feature lookup, more peaks per
//      reference, ICP over all grid-selected scene points to tight tolerances.
//   2. Refinement rounds to a fixed point: re-select the scene points that overlap the posed
//      model with the projection grid (Skotheim IV-F/G), robust point-to-plane ICP over all of
//      them; the pose shift of each round is recorded and the last must be ~0.
//   3. Checks: seeded random starts about the model centre must return to the pose (a basin,
//      not an artefact of the start); other robust kernels from the pose must stay close; the
//      fraction of model points within 0.5 / 1 / 2 mm of a scene point.
// Poses are scene_from_model; units mm, rad. An independent implementation (OpenCV's PPF + ICP)
// is compared against the result by the tests, not here.

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/point_cloud.hpp"
#include "core/progress.hpp"
#include "registration/viewpoint.hpp"

namespace lasercell::registration {

/// Options of EstablishReferencePose.
struct ReferencePoseOptions {
  Viewpoint viewpoint;  ///< Sensor in the scene frame (UWA scans: the origin, the default).
  double model_sampling_relative = 0.025;  ///< PPF model voxel, fraction of the diameter (> 0).
  std::size_t reference_stride = 1;        ///< Every n-th scene point votes (>= 1; 1 = all).
  std::size_t peaks_per_reference = 5;     ///< Pose peaks per reference point (>= 1).
  int rounds = 3;                          ///< Re-selection + ICP rounds after the search (>= 1).
  int icp_iterations = 200;                ///< Iteration limit of every ICP (>= 1).
  double translation_tolerance_mm = 1e-5;  ///< ICP convergence (> 0).
  double rotation_tolerance_rad = 1e-7;    ///< ICP convergence (> 0).
  int random_starts = 20;                  ///< Seeded perturbed starts for the basin check (>= 0).
  double start_rotation_rad = 0.0523599;   ///< Their rotation about the model centre (3 deg).
  double start_translation_mm = 5.0;       ///< Their translation.
  double converged_rms_mm = 0.1;           ///< A start "returns" when it ends this close (RMS).
  std::uint64_t seed = 1;                  ///< Seed of the random starts.
  int threads = 0;                         ///< 0 = all cores, 1 = calling thread.
  ProgressCallback progress;               ///< "search", "rounds", "starts"; may be empty.
  /// Throws OptionError naming the field when a value is out of range.
  void Check() const;
};

/// One random start of the basin check.
struct ReferenceStart {
  double start_rms_mm = 0.0;  ///< RMS model-point offset of the start from the reference.
  double end_rms_mm = 0.0;    ///< ... of where the rounds ended.
};

/// Outcome of EstablishReferencePose. RMS distances are over the model's input points.
struct ReferencePose {
  bool found = false;   ///< The search found the part (else only `message` is meaningful).
  std::string message;  ///< Why not, when !found.
  Eigen::Isometry3d scene_from_model = Eigen::Isometry3d::Identity();
  double search_support = 0.0;           ///< Support of the high-effort search's instance.
  double search_rmse_mm = 0.0;           ///< Its point-to-plane ICP rmse.
  std::vector<double> round_shift_mm;    ///< RMS pose change of each refinement round.
  std::size_t icp_source_points = 0;     ///< Scene points of the last round.
  double icp_rmse_mm = 0.0;              ///< Last round's point-to-plane rmse.
  std::vector<ReferenceStart> starts;    ///< Basin check, in seed order.
  std::size_t starts_returned = 0;       ///< Starts that ended within converged_rms_mm.
  double huber_offset_mm = 0.0;          ///< Huber-kernel rounds from the pose: RMS offset.
  double geman_mcclure_offset_mm = 0.0;  ///< Geman-McClure rounds from the pose: RMS offset.
  /// Fraction of model points within 0.5 / 1 / 2 mm of a scene point.
  std::array<double, 3> within_fraction = {0.0, 0.0, 0.0};
  /// The comment block of a reference file: how the pose was obtained and checked.
  std::string Report() const;
};

/// Establishes the reference pose of `model` (cloud with normals, mm) in `scene` (see the file
/// comment). Throws InputError for an empty model or scene, OptionError for bad options.
ReferencePose EstablishReferencePose(const PointCloud& model, const PointCloud& scene,
                                     const ReferencePoseOptions& options = {});

/// The result as JSON: found (+ message), scene_from_model (json::Pose) and its 4x4 rows,
/// search {support, rmse_mm}, round_shift_mm, icp_source_points, icp_rmse_mm, starts
/// [{start_rms_mm, end_rms_mm}], starts_returned, huber_offset_mm, geman_mcclure_offset_mm,
/// within_fraction {0.5, 1, 2 mm}.
nlohmann::json ReferencePoseJson(const ReferencePose& reference);

/// RMS displacement of `points` between two poses, mm.
double PoseRmsDistanceMm(const std::vector<Eigen::Vector3d>& points, const Eigen::Isometry3d& a,
                         const Eigen::Isometry3d& b);

}  // namespace lasercell::registration
