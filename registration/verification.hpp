#pragma once
// Hypothesis verification (Skotheim et al. 2012, IV-F):
//  - pose constraints: a supporting plane with allowed tilt of the model's "up" axis, where a
//    list of up axes describes the part's stable poses; optionally no sinking below the plane;
//  - the projection grid: scene and posed model are projected orthographically onto an M x N
//    grid perpendicular to the line of sight (viewpoint -> model centre); per cell the model
//    point nearest the sensor is kept (back faces culled); a cell is supported when a scene
//    point lies within support_distance_mm of it. support = supported / visible model cells.
// The same grid selects the scene points that overlap the posed model, the ICP source
// (Skotheim IV-G). Frames: scene points in `scene`; pose scene_from_model; units mm, rad.

#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <span>
#include <string>
#include <vector>

#include "registration/ppf_model.hpp"
#include "registration/viewpoint.hpp"

namespace lasercell::registration {

/// Constraints on plausible poses of a part lying on a support (table, conveyor, bin floor).
struct PoseConstraints {
  bool enabled = false;  ///< Off: every pose passes.
  Eigen::Vector3d plane_normal =
      Eigen::Vector3d::UnitZ();  ///< Support normal (scene, toward free space).
  double plane_offset_mm = 0.0;  ///< Support plane {p : n . p = offset}, mm.
  /// Model-frame axes that must point along plane_normal, one per stable pose; empty = any
  /// orientation. A single axis with max_tilt_rad is the "supporting plane + allowed tilt" case.
  std::vector<Eigen::Vector3d> up_in_model;
  double max_tilt_rad = 15.0 * std::numbers::pi / 180.0;  ///< Angular tolerance, rad.
  /// Posed model points may lie at most this far below the plane, mm; < 0 disables the test.
  double max_penetration_mm = -1.0;
  /// Throws OptionError naming the field when a value is out of range.
  void Check(const std::string& owner) const;
};

/// Options for VerifyPose.
struct VerificationOptions {
  int grid_rows = 48;  ///< M: cells across the model's projected extent (>= 2).
  int grid_cols = 48;  ///< N.
  /// A model cell is supported by a scene point within this distance, mm (> 0). LocalizeInCloud
  /// derives it from the sampling step unless set.
  double support_distance_mm = 3.0;
  double min_support = 0.25;           ///< Candidates with a lower support fraction are rejected.
  std::size_t min_visible_cells = 10;  ///< Fewer visible model cells: rejected (hidden pose).
  bool cull_back_faces = true;         ///< Ignore model points whose normal faces away.
  /// Scene points within this depth band of the model's cell are the ICP source, mm (> 0).
  double overlap_band_mm = 6.0;
  PoseConstraints constraints;  ///< Optional plausibility constraints.
  /// Throws OptionError naming the field when a value is out of range.
  void Check() const;
};

/// What the verification found for one pose.
struct VerificationResult {
  bool accepted = false;
  std::string rejection_reason;              ///< Empty when accepted.
  double support = 0.0;                      ///< supported_cells / visible_cells.
  std::size_t visible_cells = 0;             ///< Cells holding a (front-facing) model point.
  std::size_t supported_cells = 0;           ///< ... with a scene point within support distance.
  std::size_t occluded_cells = 0;            ///< ... unsupported, with scene in front of the model.
  std::size_t conflicting_cells = 0;         ///< ... unsupported, scene seen behind the model.
  std::size_t empty_cells = 0;               ///< ... unsupported, no scene point near the cell.
  double tilt_rad = 0.0;                     ///< Smallest angle to an allowed up axis (0 if none).
  double penetration_mm = 0.0;               ///< Deepest model point below the support plane.
  std::size_t overlapping_scene_points = 0;  ///< Scene points selected by the grid.
  std::string Summary() const;
};

/// Verifies `scene_from_model` against `scene_points`. When `overlap` is given it receives the
/// indices of the scene points overlapping the posed model (ascending; see overlap_band_mm).
VerificationResult VerifyPose(std::span<const Eigen::Vector3d> scene_points, const PpfModel& model,
                              const Eigen::Isometry3d& scene_from_model, const Viewpoint& viewpoint,
                              const VerificationOptions& options,
                              std::vector<std::uint32_t>* overlap = nullptr);

/// The constraint part of VerifyPose alone: true when the pose passes; fills tilt, penetration
/// and the reason when it does not.
bool CheckPoseConstraints(const PpfModel& model, const Eigen::Isometry3d& scene_from_model,
                          const PoseConstraints& constraints, VerificationResult* result);

}  // namespace lasercell::registration
