#pragma once
// Laser-plane calibration: the light plane of a line laser, n . p + d = 0 in
// the `sensor` frame (= the camera frame of the laser sensor, calib/camera_model.hpp), with its
// covariance, by two methods:
//
//  (a) White plane at known heights. A matt white
//      plate is swept at k heights h_i. What a cell knows, and what is estimated:
//        known  - the plate's unit normal m in the sensor frame, pointing towards the sensor
//                 (from the fixture / the robot's orientation: e.g. the sensor looks down on a
//                 levelled plate), and the heights h_i along m (stage or gauge-block readings)
//                 relative to an arbitrary zero;
//        estimated (Ceres) - the laser plane (n, d) and D0, the distance from the sensor origin
//                 to the zero-height plate along m (the optical centre is not a mechanical
//                 point, so a cell cannot measure it). Plate i is then m . p = h_i - D0.
//      Each peak pixel's ray r from the camera model meets plate i at p = r (h_i - D0)/(m . r);
//      the residual is that point's distance from the laser plane, weighted to px of peak row.
//      Observability: with m known, the images of the k parallel stripe lines fix the laser
//      plane and D0 only for k >= 3 (for k = 2 a one-parameter family fits exactly), so D0 is
//      estimated for k >= 3 and must be given (HeightPlaneOptions::zero_distance_mm) for k = 2.
//      Of m's two tilt angles, the tilt towards the laser line's direction on the plate changes
//      how the stripe lines of different heights converge in the image and is estimated
//      (HeightPlaneOptions::estimate_plate_tilt); the tilt about the line cannot be observed
//      from stripe images at all (the line images then define only a 1-D projectivity per
//      column plane), so that part of m is an input.
//  (b) Laser stripe on a chessboard of unknown pose (Zhou & Zhang 2005): per image the board
//      pose from its inner corners (OpenCV findChessboardCornersSB + cornerSubPix, rays from the
//      camera model, PnP), the stripe peak per scan line inside the board region, the peaks'
//      rays intersected with the board plane, one plane fitted to the points of all images.
//
// Units mm, rad (angles in reports: _deg), px. The normal is oriented so that d <= 0 (it points
// from the sensor origin towards the plane); the point p0 = -d n is the plane's point nearest
// the sensor origin. Covariance: 4x4 over [n; d] (rank 3), from Ceres at the solution, scaled
// by the residuals' variance (reduced chi-square); for method (b) from the joint refinement of
// the plane and the board poses (corners and stripe pixels, each group weighted by the sigma its
// own residuals give), so it includes the board-pose uncertainty.

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "calib/board.hpp"
#include "calib/camera_model.hpp"
#include "calib/target_detection.hpp"
#include "core/frame_graph.hpp"
#include "core/image8.hpp"

namespace lasercell::calib {

/// Peaks of one white-plane sweep: (column, subpixel row) pixels of all its profiles.
struct HeightCapture {
  std::string name;                       ///< e.g. the profile file, for messages and reports.
  double height_mm = 0;                   ///< Height of the plate along the plate normal m.
  std::vector<Eigen::Vector2d> peaks_px;  ///< (column, row) of every valid peak.
};

/// Options of the white-plane method (a).
struct HeightPlaneOptions {
  /// Unit normal m of the white plate in the sensor frame, pointing towards the sensor (need
  /// not be exactly unit; it is normalized). Known input (see the header comment).
  Eigen::Vector3d plate_normal_in_sensor = -Eigen::Vector3d::UnitZ();
  /// Estimate the plate's tilt towards the laser line's direction on it (the one component of
  /// m's error the stripe images observe: it makes the lines of different heights converge).
  /// Default true; false keeps m exactly as given.
  bool estimate_plate_tilt = true;
  /// Distance (mm) from the sensor origin to the height-0 plate along m, when known; otherwise
  /// (nullopt) it is estimated, which needs >= 3 distinct heights.
  std::optional<double> zero_distance_mm;
  /// Per column and height, peaks farther than this from the column's median row are not on the
  /// plate (floor, plate edges) and are dropped, px. Default 2 px.
  double inlier_band_px = 2.0;
  /// The plate's stripe is the longest run of neighbouring columns whose mean rows differ by
  /// less than this (px); columns outside it see something else (floor, plate edge). Default 3.
  double max_row_step_px = 3.0;
  /// A height needs at least this many columns with plate peaks. Default 20.
  int min_columns = 20;
  /// A column/height cell needs at least this many peaks to count. Default 3.
  int min_peaks_per_column = 3;
  /// Below this median angle between the camera rays and the fitted laser plane the result is
  /// flagged ill-conditioned (deg). Default 2 deg.
  double min_triangulation_angle_deg = 2.0;
  /// Add the camera's own uncertainty (CameraModel::intrinsics_covariance) to the plane's
  /// covariance, propagated by refitting the plane through perturbed cameras
  /// (calib/camera_uncertainty.hpp; 2 refits per intrinsic). Default true; without a stored
  /// covariance the result says it was not included.
  bool include_camera_uncertainty = true;
  /// Throws OptionError naming the field.
  void Check() const;
};

/// One image of the stripe method (b), decoded, with the name its messages use.
struct StripeImage {
  std::string name;  ///< File name, for messages and reports.
  Image8 image;      ///< 1 (gray) or 3 (BGR, as OpenCV decodes) channels.
};

/// Decodes an image file's bytes (JPEG, PNG, ... through OpenCV imgcodecs); throws FileError
/// naming `name` when it cannot be decoded.
StripeImage DecodeStripeImage(const std::string& bytes, const std::string& name);

/// Options of the stripe-on-chessboard method (b).
struct StripeOptions {
  /// Laser colour channel: "green" (G - (R + B) / 2), "red" (R - (G + B) / 2) or "gray".
  std::string laser_color = "green";
  /// Minimum peak value of the laser channel (8-bit levels) above the scan line's median.
  double min_peak_contrast = 20.0;
  /// The board region searched for the stripe: the inner-corner grid grown by this many squares
  /// on every side (1 = the whole printed pattern). Default 0.8 keeps clear of its edge.
  double board_margin_squares = 0.8;
  /// Scan lines whose stripe profile has a second maximum above this fraction of the peak,
  /// farther than `max_stripe_width_px` from it, are ambiguous and skipped. Default 0.6.
  double ambiguity_ratio = 0.6;
  /// Widest plausible stripe (full width above half maximum), px. Default 15.
  int max_stripe_width_px = 15;
  /// An image needs at least this many stripe peaks on the board. Default 30.
  int min_peaks_per_image = 30;
  /// As HeightPlaneOptions::min_triangulation_angle_deg. Default 2 deg.
  double min_triangulation_angle_deg = 2.0;
  /// Refine the plane and all board poses jointly from corners and stripe pixels (Zhou & Zhang
  /// 2005), so the covariance includes the board-pose uncertainty. Default true; false keeps the
  /// plane fitted to the stripe points of the PnP boards (its covariance is then optimistic).
  bool joint_refinement = true;
  /// Plane-fit outliers: points farther than this many robust sigmas are dropped once. Default 4.
  double outlier_sigmas = 4.0;
  /// As HeightPlaneOptions::include_camera_uncertainty (the refits repeat the board poses and
  /// the joint refinement). Default true.
  bool include_camera_uncertainty = true;
  /// The board detector's options (calib/target_detection.hpp). Default: the detector's own,
  /// but a corner refinement half window of at most 5 px: the laser stripe crosses the board and
  /// a window the size of the squares takes in its edges (on the real stripe set the default
  /// window triples the corner RMS of the intrinsics fit, 0.27 -> 0.78 px).
  DetectionOptions board_detection = [] {
    DetectionOptions o;
    o.max_refine_half_window_px = 5;
    return o;
  }();
  /// Throws OptionError naming the field.
  void Check() const;
};

/// Per-height / per-image diagnostics.
struct LaserPlaneItem {
  std::string name;
  bool used = false;               ///< False when rejected (reason in `note`).
  std::string note;                ///< Why it was rejected, or how it was detected.
  int points = 0;                  ///< Observations used.
  double rms_mm = 0;               ///< RMS distance of its points from the fitted plane.
  double rms_px = 0;               ///< RMS residual in px of peak row (method a), or 0.
  double height_mm = 0;            ///< Method (a): plate height.
  double reprojection_rms_px = 0;  ///< Method (b): board corners' PnP reprojection RMS.
  bool scan_along_rows = false;    ///< Method (b): one peak per image row (vertical stripe).
  /// Leave-this-one-out refit: angle of the normal from the full fit (deg), change of d (mm),
  /// largest displacement of the plane over the observed points (mm); NaN when not possible.
  double loo_normal_change_deg = 0;
  double loo_offset_change_mm = 0;
  double loo_max_displacement_mm = 0;
  /// Method (a): the refit without this height held D0 and the plate tilt at the full fit's
  /// values (the remaining 2 heights cannot estimate them).
  bool loo_zero_distance_held = false;
};

/// One observation for plots: which item, the pixel, its 3-D point and its residual.
struct LaserPlaneResidual {
  int item = 0;
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();
  Eigen::Vector3d p_in_sensor = Eigen::Vector3d::Zero();
  double residual_mm = 0;  ///< Signed distance from the fitted plane.
};

/// The fitted laser plane and how good it is.
struct LaserPlaneResult {
  std::string method;       ///< "heights" or "stripe_chessboard".
  bool converged = false;   ///< The solver converged.
  std::string termination;  ///< Ceres termination message.
  int iterations = 0;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitY();   ///< Unit, oriented so offset <= 0.
  double offset_mm = 0;                                ///< d of n . p + d = 0.
  Eigen::Vector3d point_mm = Eigen::Vector3d::Zero();  ///< p0 = -d n.
  /// Over [n; d]: the fit's own (its residuals) plus camera_covariance.
  Eigen::Matrix4d covariance = Eigen::Matrix4d::Zero();
  double normal_sigma_deg = 0;  ///< 1 sigma of the normal's direction: sqrt(trace cov(n)).
  double offset_sigma_mm = 0;   ///< 1 sigma of d.
  /// The part of `covariance` the camera's intrinsics covariance causes (zero when not
  /// included): an error shared by every point measured with this camera and plane.
  Eigen::Matrix4d camera_covariance = Eigen::Matrix4d::Zero();
  bool camera_uncertainty_included = false;
  /// Why not, when not included ("" when included).
  std::string camera_uncertainty_note;
  /// `covariance` as independent error modes (core/frame_graph.hpp SensorErrorMode): the
  /// camera's principal axes with the plane refitted through each (when included), then the
  /// principal axes of the fit's own covariance.
  std::vector<SensorErrorMode> error_modes;
  double camera_normal_sigma_deg = 0;         ///< The camera's part of normal_sigma_deg.
  double camera_offset_sigma_mm = 0;          ///< The camera's part of offset_sigma_mm.
  double rms_mm = 0;                          ///< RMS point-to-plane residual of the used points.
  double rms_px = 0;                          ///< Method (a): RMS residual in px of peak row.
  int points = 0;                             ///< Observations used.
  double median_triangulation_angle_deg = 0;  ///< Median angle of the rays to the plane.
  bool ill_conditioned = false;            ///< True when the geometry cannot determine the plane.
  std::optional<double> zero_distance_mm;  ///< Method (a): D0 (estimated or given).
  double zero_distance_sigma_mm = 0;       ///< Method (a): 1 sigma of D0 (0 when given).
  double plate_tilt_deg = 0;               ///< Method (a): estimated tilt of m towards the line.
  double plate_tilt_sigma_deg = 0;         ///< Method (a): its 1 sigma (0 when not estimated).
  std::vector<LaserPlaneItem> items;
  std::vector<LaserPlaneResidual> residuals;  ///< Used observations (for reports).
  /// Leave-one-out over the items: largest normal change (deg) and offset change (mm); NaN
  /// when there are too few items to refit without one.
  double loo_max_normal_change_deg = 0;
  double loo_max_offset_change_mm = 0;
  std::vector<std::string> warnings;  ///< Ill-conditioned, no covariance, no convergence, ...

  /// One line: method, plane, sigmas, RMS, points, flags.
  std::string Summary() const;
  /// Why this plane must not be written to a cell: empty when it is usable, else the first
  /// warning (or the summary) of an ill-conditioned or not converged fit. The policy of
  /// `lasercell calibrate laser`, which refuses such a plane after writing its JSON and report.
  std::string RefusalReason() const;
};

/// Method (a). Throws InputError naming the problem for: fewer than 2 distinct heights ("planes
/// at one height only"), 2 heights without zero_distance_mm, a height without enough plate
/// peaks, a laser plane (nearly) parallel to the camera rays (the stripe does not move between
/// heights).
LaserPlaneResult CalibrateLaserPlaneFromHeights(const CameraModel& camera,
                                                const std::vector<HeightCapture>& captures,
                                                const HeightPlaneOptions& options = {});

/// What method (b) measures in one image: the board's inner corners and the stripe peaks.
struct StripeObservation {
  std::string name;                         ///< Image file, for messages and reports.
  std::vector<Eigen::Vector2d> corners_px;  ///< Inner corners, OpenCV order; empty: not found.
  std::vector<Eigen::Vector2d> stripe_px;   ///< (column, row) stripe peaks on the board.
  bool scan_along_rows = false;  ///< One peak per image row (a vertical stripe), else per column.
  std::string note;              ///< Why the board or stripe was not found, or how it was scanned.
};

/// Detects the board (calib::DetectTarget with options.board_detection) and the stripe (one peak
/// per scan line of the laser channel inside the board region; rows or columns, whichever gives
/// more peaks). Throws InputError when the image size differs from the camera's.
StripeObservation DetectStripe(const CameraModel& camera, const StripeImage& image,
                               const BoardSpec& board, const StripeOptions& options = {});

/// Method (b) from observations (board pose by PnP through the camera model, rays ∩ board
/// plane, one plane over all images). Same errors as CalibrateLaserPlaneFromStripes.
LaserPlaneResult CalibrateLaserPlaneFromStripeObservations(
    const CameraModel& camera, const std::vector<StripeObservation>& observations,
    const BoardSpec& board, const StripeOptions& options = {});

/// Method (b): DetectStripe on every image, then CalibrateLaserPlaneFromStripeObservations. Images
/// where the board or the stripe is not found are kept as unused items with the reason; throws
/// InputError when fewer than 2 images are usable (listing why each failed), when the images' size
/// differs from the camera's, or when the stripe points of all images lie in one plane through the
/// camera centre (laser plane parallel to the camera rays).
LaserPlaneResult CalibrateLaserPlaneFromStripes(const CameraModel& camera,
                                                const std::vector<StripeImage>& images,
                                                const BoardSpec& board,
                                                const StripeOptions& options = {});

}  // namespace lasercell::calib
