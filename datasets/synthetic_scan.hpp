#pragma once
// Synthetic single-view scans for registration tests and benchmarks: a model rendered at known
// poses into a real scan whose own instance of the model was cut out (UWA rs1 with the
// parasaurolophus removed), z-buffered from the scanner, with Gaussian noise along the line of
// sight. One implementation for the registration tests and `lasercell bench robustness`.
// Frames: the scene frame is the scanner's (sensor at the origin, looking down -z, rs1 lies at
// z ~ -600 mm); poses are scene_from_model. Units: mm. Seeded: the same seed and inputs give the
// same scan (std::mt19937_64 and the standard distributions, so bit-identical per standard
// library). Nothing here reads files except LoadRs1SyntheticData, which reads the paths it is
// given.

#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "core/point_cloud.hpp"

namespace lasercell::datasets {

/// Options for RenderSyntheticScan.
struct SyntheticScanOptions {
  /// Gaussian noise sigma added to the model's points along the line of sight, mm (>= 0).
  double noise_sigma_mm = 0.3;
  /// Noise sigma added to the clutter points along the line of sight, mm (>= 0). The clutter is
  /// usually a real scan that already carries the scanner's noise, hence 0.
  double clutter_noise_sigma_mm = 0.0;
  /// Seed of the generator used by the overload that takes no generator.
  std::uint64_t seed = 1;
  /// Z-buffer cell size at `zbuffer_reference_range_mm`, mm (> 0): the buffer is angular.
  double zbuffer_cell_mm = 0.8;
  /// Range at which a z-buffer cell is `zbuffer_cell_mm` wide, mm (> 0).
  double zbuffer_reference_range_mm = 600.0;
  /// Points within this range of the nearest point of their cell stay visible, mm (> 0).
  double zbuffer_depth_tolerance_mm = 2.0;
  /// Neighbours for re-estimating the model's normals from its noisy visible points (>= 3).
  std::size_t part_normal_neighbors = 12;
  /// Throws OptionError naming the field when a value is out of range.
  void Check() const;
};

/// A rendered scan.
struct SyntheticScan {
  /// Visible clutter points (normals kept) followed by visible model points (normals
  /// re-estimated, toward the origin; points without a valid fit dropped).
  PointCloud cloud;
  std::size_t clutter_points = 0;  ///< Visible clutter points (the first ones of `cloud`).
  std::size_t part_points = 0;     ///< Visible model points before normal estimation.
};

/// The real inputs of the rs1 scenes.
struct Rs1SyntheticData {
  PointCloud model;         ///< parasaurolophus_6700.ply as shipped (6700 points with normals).
  PointCloud part_surface;  ///< The model's mesh sampled at rs1's density (SampleMeshSurface).
  PointCloud clutter;       ///< rs1 with the real parasaurolophus cut out (unit normals).
  Eigen::Isometry3d reference_scene_from_model =
      Eigen::Isometry3d::Identity();  ///< Its pose in rs1.
};

/// Reads a 4x4 row-major pose (16 numbers; lines starting with '#' are comments). Throws
/// FileError when unreadable, InputError when it does not hold 16 numbers.
Eigen::Isometry3d ReadPoseFile(const std::string& path);

/// Writes `pose` as ReadPoseFile reads it, atomically: each line of `comment` as a '#' line,
/// then the 4x4 row-major matrix at 10 significant digits. Throws FileError when unwritable.
void WritePoseFile(const std::string& path, const Eigen::Isometry3d& pose,
                   const std::string& comment);

/// Uniform random points on a mesh surface, one per `area_per_point_mm2` on average (stochastic
/// rounding per face), normals interpolated from the (normalized) vertex normals, which the mesh
/// must have. Seeded by `seed`.
PointCloud SampleMeshSurface(const TriangleMesh& mesh, double area_per_point_mm2,
                             std::uint64_t seed);

/// `scene` without the points within `margin_mm` of `posed_model` (an instance cut out).
PointCloud CutOutModel(const PointCloud& scene, const PointCloud& posed_model, double margin_mm);

/// Perspective z-buffer from the origin: indices of the points that face the origin (normal
/// toward it) and lie within `depth_tolerance_mm` of the nearest front-facing point of their
/// angular cell (`cell_mm` wide at `reference_range_mm`). Normals must be present.
std::vector<std::size_t> VisibleFromOrigin(const PointCloud& cloud, double cell_mm,
                                           double depth_tolerance_mm,
                                           double reference_range_mm = 600.0);

/// Renders `part_surface` (model frame) at every pose of `scene_from_model` into `clutter`
/// (scene frame, unit normals): noise along the line of sight, occlusions resolved by the
/// z-buffer from the origin, the model's normals re-estimated from its noisy visible points. No
/// pose gives the clutter alone (a scene without the part). Draws from `rng`.
SyntheticScan RenderSyntheticScan(const PointCloud& clutter, const PointCloud& part_surface,
                                  const std::vector<Eigen::Isometry3d>& scene_from_model,
                                  const SyntheticScanOptions& options, std::mt19937_64& rng);

/// As above with a generator seeded by options.seed.
SyntheticScan RenderSyntheticScan(const PointCloud& clutter, const PointCloud& part_surface,
                                  const std::vector<Eigen::Isometry3d>& scene_from_model,
                                  const SyntheticScanOptions& options = {});

/// A uniformly random rotation (random unit quaternion) and a translation uniform in a cube of
/// +-half_mm.
Eigen::Isometry3d RandomPose(std::mt19937_64& rng, double half_mm);

/// A random placement in rs1's field of view of a model whose centroid (model frame) is
/// `model_centroid`: uniform random rotation, centroid uniform in x [-110, 70], y [-90, 90],
/// z [-640, -600] mm (rs1's footprint at its depth).
Eigen::Isometry3d RandomPlacementInRs1(const Eigen::Vector3d& model_centroid, std::mt19937_64& rng);

/// Loads the rs1 inputs: `uwa_dir`/parasaurolophus_6700.ply and `uwa_dir`/rs1_normals.bin.ply
/// (datasets/real/uwa) and the reference pose file (tests/registration/data/
/// rs1_parasaurolophus_reference.txt); samples the surface at 0.5 mm^2 per point (seed 99) and
/// cuts the instance out with an 8 mm margin. Throws FileError for a missing file.
Rs1SyntheticData LoadRs1SyntheticData(const std::string& uwa_dir,
                                      const std::string& reference_pose_file);

}  // namespace lasercell::datasets
