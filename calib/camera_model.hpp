#pragma once
// A calibrated camera: a mrcal lens model (any model mrcal can project with gradients:
// LENSMODEL_PINHOLE, LENSMODEL_OPENCV4/5/8/12, LENSMODEL_STEREOGRAPHIC,
// LENSMODEL_SPLINED_STEREOGRAPHIC_..., ...), its intrinsics vector in mrcal's order (fx fy cx cy,
// then the distortion parameters) and the imager size.
//
// Conventions (mrcal/OpenCV): camera frame +x along image columns, +y along rows, +z the optical
// axis, origin at the projection centre; pixel coordinates put the centre of the top-left pixel
// at (0, 0). Units: mm for points, px for pixels. In lasercell the `sensor` frame is the camera
// frame of the laser sensor.
//
// Files: mrcal's .cameramodel text (a Python-dict literal that mrcal's tools and
// mrcal_read_cameramodel_file read), written atomically with every number printed to round-trip
// exactly, preceded by a `# lasercell-cameramodel v1` comment line. A model that carries its
// intrinsics covariance stores it under the key 'lasercell_intrinsics_covariance' (row-major
// list of NumIntrinsics()^2 numbers); mrcal's readers (C and Python) ignore keys they do not
// know, and a file without the key reads as a model without a covariance.

extern "C" {
#include <mrcal/mrcal.h>  // C library without extern "C" guards
}

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace lasercell::calib {

class CameraModel {
 public:
  /// Throws InputError when the lens model name is not a configured mrcal model, when the
  /// intrinsics vector has the wrong length for it, when a value is not finite or when the
  /// imager size is not positive.
  CameraModel(std::string lensmodel, std::vector<double> intrinsics, int width_px, int height_px);

  /// mrcal's configured model name, e.g. "LENSMODEL_OPENCV8" or
  /// "LENSMODEL_SPLINED_STEREOGRAPHIC_order=3_Nx=16_Ny=12_fov_x_deg=100".
  const std::string& lensmodel() const { return lensmodel_; }
  /// fx fy cx cy then distortion, in mrcal's order for the model.
  const std::vector<double>& intrinsics() const { return intrinsics_; }
  int width_px() const { return width_px_; }    ///< Imager width, px.
  int height_px() const { return height_px_; }  ///< Imager height, px.
  /// Number of intrinsics for this model.
  int NumIntrinsics() const { return static_cast<int>(intrinsics_.size()); }
  /// True when mrcal provides gradients for the model (everything but CAHVORE).
  bool HasGradients() const;
  /// Covariance of intrinsics() (NumIntrinsics() square; px^2 for fx fy cx cy, the distortion
  /// terms' own units) from the calibration that made the model, marginal over the board poses;
  /// empty when unknown (a model mrcal wrote, or a calibration whose covariance was not
  /// computable). Calibrations downstream of the camera propagate it
  /// (calib/camera_uncertainty.hpp).
  const Eigen::MatrixXd& intrinsics_covariance() const { return intrinsics_covariance_; }
  /// Sets it (an empty matrix clears it). Throws InputError unless it is NumIntrinsics() square,
  /// finite, symmetric (to 1e-6 of its largest entry; stored symmetrized) with a non-negative
  /// diagonal.
  void SetIntrinsicsCovariance(const Eigen::MatrixXd& covariance);

  /// Pixel of a point in the camera frame (mrcal_project). Points behind a pinhole-like camera
  /// give undefined values, as in mrcal; check z > 0 before calling when that matters.
  Eigen::Vector2d Project(const Eigen::Vector3d& p_in_camera) const;
  /// Projection with optional gradients: dq_dp is 2x3, dq_dintrinsics is 2 x NumIntrinsics()
  /// (dense, as mrcal_project reports it). Either pointer may be null.
  Eigen::Vector2d Project(const Eigen::Vector3d& p_in_camera, Eigen::Matrix<double, 2, 3>* dq_dp,
                          Eigen::Matrix<double, 2, Eigen::Dynamic>* dq_dintrinsics) const;
  /// Projection through this lens model evaluated at other intrinsics (NumIntrinsics() values),
  /// for solvers: dq_dintrinsics is a row-major 2 x NumIntrinsics() array. Pointers may be null.
  Eigen::Vector2d ProjectWithIntrinsics(const double* intrinsics,
                                        const Eigen::Vector3d& p_in_camera,
                                        Eigen::Matrix<double, 2, 3>* dq_dp,
                                        double* dq_dintrinsics_row_major) const;
  /// mrcal's parsed lens model, for code that calls mrcal directly.
  const mrcal_lensmodel_t& mrcal_lensmodel() const { return lens_; }
  /// Unit ray direction (camera frame) of a pixel (mrcal_unproject). Throws InternalError when
  /// mrcal's iterative unprojection fails.
  Eigen::Vector3d Unproject(const Eigen::Vector2d& pixel) const;
  /// Unit rays of many pixels in one mrcal call (faster than one by one).
  std::vector<Eigen::Vector3d> UnprojectMany(const std::vector<Eigen::Vector2d>& pixels) const;
  /// True when 0 <= u <= width-1 and 0 <= v <= height-1.
  bool InImage(const Eigen::Vector2d& pixel) const;

 private:
  std::string lensmodel_;
  mrcal_lensmodel_t lens_{};
  std::vector<double> intrinsics_;
  Eigen::MatrixXd intrinsics_covariance_;
  int width_px_ = 0;
  int height_px_ = 0;
};

/// Whether a lens model inverts over a region of the imager: pixels on a grid x grid lattice
/// over the region (its edges and corners included) are unprojected and projected back; a ray
/// that is not finite, or a round trip off by more than tolerance_px, means the model has no
/// ray there (its distortion turns back before that radius: high-order terms that cancel where
/// the boards were and diverge beyond). A fold that keeps the round trip exact still reverses
/// the pixel -> ray map, which the orientation of neighbouring rays shows.
struct LensInversionCheck {
  int pixels = 0;          ///< Grid pixels checked.
  int without_ray = 0;     ///< Of those, no ray that projects back.
  int cells = 0;           ///< Grid cells checked.
  int reversed_cells = 0;  ///< Cells whose rays are in reversed order.
  double worst_px = 0;     ///< Largest round-trip error (inf: no finite ray).
  Eigen::Vector2d first_bad_px = Eigen::Vector2d::Zero();  ///< First pixel without a ray.
  /// OPENCV models: distance from the principal point (px along x) at which the radial
  /// distortion r * (1 + k1 r^2 + ...) / (1 + k4 r^2 + ...) stops increasing or its denominator
  /// reaches zero inside the imager (0: it does not; checked for the whole imager only). A
  /// rational model can fold on a ring a pixel wide that a grid steps over (a pole of the
  /// denominator nearly cancelled by a zero of the numerator); this finds it analytically.
  double radial_fold_px = 0;
  bool ok() const { return without_ray == 0 && reversed_cells == 0 && radial_fold_px == 0; }
  /// Fraction of the checked pixels without a ray.
  double FractionWithoutRay() const { return pixels > 0 ? double(without_ray) / pixels : 0.0; }
  /// "" when ok(), else what failed, in words.
  std::string Describe() const;
};

/// Checks the pixels of `region_px` (clipped to the imager, [-0.5, width - 0.5] x [-0.5,
/// height - 0.5]: pixel centres are integers; empty or absent: the whole imager).
/// Throws InputError when grid < 2 or tolerance_px is not positive.
LensInversionCheck CheckLensInversion(const CameraModel& model,
                                      const Eigen::AlignedBox2d& region_px = {}, int grid = 129,
                                      double tolerance_px = 0.01);

/// CheckLensInversion where a calibration's corners pinned the model down: inside the convex
/// hull of `observed_px` (only pixels inside it, and grid cells whose pixels are all inside it,
/// count; the grid spans the corners' bounding box). Fewer than three corners: nothing checked.
LensInversionCheck CheckLensInversionWithin(const CameraModel& model,
                                            const std::vector<Eigen::Vector2d>& observed_px,
                                            int grid = 129, double tolerance_px = 0.01);

/// CheckLensInversion over the whole imager, described ("" when the model inverts everywhere).
std::string LensInversionProblem(const CameraModel& model, int grid = 129,
                                 double tolerance_px = 0.01);

/// The .cameramodel text for a model (extrinsics rt_cam_ref = 0: the camera is its own reference),
/// with `comment` (may be multi-line; each line is prefixed with "# ") after the version line.
std::string CameraModelText(const CameraModel& model, const std::string& comment = "");
/// Parses .cameramodel text with mrcal's reader; throws FileError(name, ...) when mrcal cannot
/// read it. Extrinsics are ignored (lasercell keeps poses in the frame graph).
CameraModel ParseCameraModel(const std::string& text, const std::string& name);
/// Reads a .cameramodel file (any mrcal-written or lasercell-written model).
CameraModel LoadCameraModel(const std::string& path);
/// Writes a .cameramodel file atomically (temp file + rename).
void SaveCameraModel(const std::string& path, const CameraModel& model,
                     const std::string& comment = "");

}  // namespace lasercell::calib
