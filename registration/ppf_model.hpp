#pragma once
// The offline part of Drost et al. 2010 ("Model Globally, Match Locally", Sec. 3.2-3.3):
// a model point cloud with normals is subsampled, centred at its centroid (Skotheim IV-E), and
// every ordered pair of model points (m_r, m_i) is stored under its quantized feature F, with
// the pair's plane angle phi_m (ppf_feature.hpp) precomputed for the voting.
//
// Frames: the model's own frame is `model` (as given by the caller); all stored geometry is in
// `centered` (model frame shifted to the centroid of the sampled points): p_in_model =
// model_from_centered * p_in_centered. Units: mm and rad.
//
// The hash table keeps EVERY pair per key, as flat arrays (CSR): sorted unique keys, offsets,
// and entries grouped by key; a dense key -> offset index is rebuilt in memory for O(1) lookup.

#include <Eigen/Geometry>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/point_cloud.hpp"
#include "registration/filters.hpp"
#include "registration/kdtree.hpp"
#include "registration/normals.hpp"
#include "registration/ppf_feature.hpp"

namespace lasercell::registration {

/// Options for PpfModel::Build. Steps are relative to the model diameter unless the matching
/// absolute (_mm) value is > 0.
struct PpfModelOptions {
  /// Voxel size for subsampling the model, relative to the diameter (Drost: tau_d = 0.05).
  double sampling_step_relative = 0.04;
  /// Absolute voxel size, mm; overrides the relative value when > 0.
  double sampling_step_mm = 0.0;
  /// Feature distance quantization step, relative to the diameter (Drost default 0.05).
  double distance_step_relative = 0.05;
  /// Absolute distance step, mm; overrides the relative value when > 0.
  double distance_step_mm = 0.0;
  /// Feature angle quantization step, rad (Drost: n_angle = 30 -> 12 deg). The alpha
  /// accumulator uses round(2 pi / angle_step_rad) bins over a full turn.
  double angle_step_rad = std::numbers::pi / 15.0;
  /// Model geometry kept for verification and ICP: voxel size relative to the diameter;
  /// 0 keeps every input point.
  double refinement_step_relative = 0.005;
  /// Voxel normal handling when subsampling (see VoxelGridOptions).
  VoxelNormalMode normal_mode = VoxelNormalMode::kAverage;
  /// Subsampling keeps the faces of walls thinner than a voxel apart: normals more than this far
  /// apart in one voxel give separate model points (VoxelGridOptions::normal_split_angle_rad;
  /// 0 = one point per voxel). Facing-away faces (> 90 deg) average to a point inside the wall
  /// with a meaningless normal otherwise. In [0, pi].
  double normal_split_angle_rad = std::numbers::pi / 2.0;
  /// Subsampled models larger than this are refused (pairs grow quadratically); <= 65535.
  std::size_t max_model_points = 4000;
  /// Used only when the model cloud has no normals.
  NormalOptions normals;
  /// Worker threads for the pair table: 0 = all cores, 1 = calling thread.
  int threads = 0;
  /// Throws OptionError naming the field when a value is out of range.
  void Check() const;
};

/// One stored model pair: index of its reference point m_r (in points()) and its plane angle
/// phi_m as a fixed-point fraction of a turn (PlaneAngleToTurn16), so that alpha = phi_s - phi_m
/// wraps for free in 16-bit arithmetic.
struct PpfPairEntry {
  std::uint16_t reference = 0;
  std::uint16_t plane_angle = 0;
};

/// An angle in rad as a 16-bit fraction of a full turn (2 pi / 65536 = 9.6e-5 rad units).
inline std::uint16_t PlaneAngleToTurn16(double angle_rad) {
  const long units = std::lround(angle_rad * (65536.0 / (2.0 * std::numbers::pi)));
  return static_cast<std::uint16_t>(static_cast<unsigned long>(units) & 0xFFFFU);
}

/// Quantized feature cell (distance bin, three angle bins).
struct PpfBins {
  int distance = 0;
  int angle_n1_d = 0;
  int angle_n2_d = 0;
  int angle_n1_n2 = 0;
};

/// A PPF model: subsampled oriented points, refinement points and the pair table.
class PpfModel {
 public:
  /// Builds from a model cloud (normals used when present, else estimated with
  /// options.normals). Throws InputError for an empty/invalid cloud or zero normals, and
  /// OptionError naming the field for bad options or a table that would be too large.
  static PpfModel Build(const PointCloud& model, const PpfModelOptions& options = {});
  /// Builds from a CAD mesh: its vertex normals when it has them, else the normals of its faces
  /// (MeshVertexNormals: outward, the two sides of a thin shell kept apart, which a PCA fit on
  /// the vertices mixes). A mesh without faces is built as a cloud, as above.
  static PpfModel Build(const TriangleMesh& model, const PpfModelOptions& options = {});

  /// Versioned binary encoding (little-endian); Deserialize throws InputError naming `name`
  /// on a bad magic, unknown version, truncation or checksum mismatch.
  std::string Serialize() const;
  static PpfModel Deserialize(std::string_view bytes, const std::string& name = "PPF model");
  /// Writes Serialize() atomically to `path` (core/io/file_util.hpp).
  void Save(const std::string& path) const;
  /// Reads a file written by Save. Throws FileError/InputError.
  static PpfModel Load(const std::string& path);

  /// Sampled points used for the pair table, in `centered`.
  const std::vector<Eigen::Vector3d>& points() const { return points_; }
  /// Unit normals of points().
  const std::vector<Eigen::Vector3d>& normals() const { return normals_; }
  /// Denser points for verification and ICP (refinement_step_relative), in `centered`.
  const std::vector<Eigen::Vector3d>& refinement_points() const {
    return refinement_tree_.points();
  }
  /// Unit normals of refinement_points().
  const std::vector<Eigen::Vector3d>& refinement_normals() const { return refinement_normals_; }
  /// kd-tree over refinement_points() (rebuilt on load).
  const KdTree& refinement_tree() const { return refinement_tree_; }
  /// p_in_model = model_from_centered() * p_in_centered.
  const Eigen::Isometry3d& model_from_centered() const { return model_from_centered_; }

  /// Model diameter, mm: largest distance between extreme points of the input along 13
  /// directions (a tight lower bound of the true diameter, independent of the model's frame).
  double diameter_mm() const { return diameter_mm_; }
  /// Largest distance between two sampled points, mm: scene pairs beyond it cannot match.
  double max_pair_distance_mm() const { return max_pair_distance_mm_; }
  /// Voxel size the model was subsampled with, mm (scenes are subsampled the same way).
  double sampling_step_mm() const { return sampling_step_mm_; }
  /// Feature distance quantization step, mm.
  double distance_step_mm() const { return distance_step_mm_; }
  /// Feature angle quantization step, rad.
  double angle_step_rad() const { return angle_step_rad_; }
  /// Number of distance bins (max_pair_distance / distance_step + 1).
  int distance_bins() const { return distance_bins_; }
  /// Number of bins per feature angle over [0, pi].
  int angle_bins() const { return angle_bins_; }
  /// Bins of the alpha accumulator over [0, 2 pi).
  int alpha_bins() const { return alpha_bins_; }
  /// Width of an alpha bin, rad.
  double alpha_step_rad() const { return 2.0 * std::numbers::pi / alpha_bins_; }
  /// Variances of the sampled points along their principal axes, mm^2, descending.
  const Eigen::Vector3d& principal_variances() const { return principal_variances_; }

  /// Number of stored pairs (every ordered pair of sampled points).
  std::size_t pair_count() const { return entries_.size(); }
  /// Number of distinct keys in the table.
  std::size_t key_count() const { return keys_.size(); }

  /// Hash key of the oriented pair (p1, n1) -> (p2, n2) (Drost Sec. 3.2: quantized F). Angle
  /// bins are found by comparing cosines with precomputed thresholds (no acos): bin k holds
  /// angles in [k step, (k+1) step). Returns false for coincident points or a distance beyond
  /// the table. Build and matching both use this, so model and scene quantize identically.
  bool PairKey(const Eigen::Vector3d& p1, const Eigen::Vector3d& n1, const Eigen::Vector3d& p2,
               const Eigen::Vector3d& n2, std::uint32_t* key) const {
    const Eigen::Vector3d d = p2 - p1;
    const double distance_sq = d.squaredNorm();
    if (!(distance_sq > 0.0)) return false;
    const double distance = std::sqrt(distance_sq);
    const double distance_bin = distance * inv_distance_step_;
    if (!(distance_bin < distance_bins_)) return false;
    const double inv = 1.0 / distance;
    *key = Key({static_cast<int>(distance_bin), CosineBin(n1.dot(d) * inv),
                CosineBin(n2.dot(d) * inv), CosineBin(n1.dot(n2))});
    return true;
  }
  /// Quantizes a feature given as distance and angles (same bins as PairKey up to rounding at
  /// bin borders). Returns false when its distance is beyond the table.
  bool Quantize(const PpfFeature& f, PpfBins* bins) const {
    const double d = f.distance_mm * inv_distance_step_;
    if (!(d < distance_bins_)) return false;
    bins->distance = static_cast<int>(d);
    bins->angle_n1_d = AngleBin(f.angle_n1_d);
    bins->angle_n2_d = AngleBin(f.angle_n2_d);
    bins->angle_n1_n2 = AngleBin(f.angle_n1_n2);
    return true;
  }
  /// Hash key of a feature cell; bins must be in range.
  std::uint32_t Key(const PpfBins& b) const {
    const auto a = static_cast<std::uint32_t>(angle_bins_);
    return ((static_cast<std::uint32_t>(b.distance) * a +
             static_cast<std::uint32_t>(b.angle_n1_d)) *
                a +
            static_cast<std::uint32_t>(b.angle_n2_d)) *
               a +
           static_cast<std::uint32_t>(b.angle_n1_n2);
  }
  /// Every model pair stored under `key` (empty when none).
  std::span<const PpfPairEntry> Lookup(std::uint32_t key) const {
    if (key + 1 >= dense_offsets_.size()) return {};
    return {entries_.data() + dense_offsets_[key], entries_.data() + dense_offsets_[key + 1]};
  }
  /// Angle bin of an angle in [0, pi].
  int AngleBin(double angle) const {
    const int bin = static_cast<int>(angle / angle_step_rad_);
    return std::clamp(bin, 0, angle_bins_ - 1);
  }
  /// Angle bin of the angle whose cosine is `c`: the number of k >= 1 with cos(k step) >= c.
  int CosineBin(double c) const {
    int bin = 0;
    for (double threshold : cos_thresholds_) bin += c <= threshold ? 1 : 0;
    return bin;
  }

  /// One line: points, pairs, keys, steps.
  std::string Summary() const;

 private:
  friend class PpfModelCodec;
  void ComputeQuantizationConstants();
  void BuildDenseIndex();  // also computes the quantization constants

  std::vector<Eigen::Vector3d> points_;
  std::vector<Eigen::Vector3d> normals_;
  KdTree refinement_tree_;
  std::vector<Eigen::Vector3d> refinement_normals_;
  Eigen::Isometry3d model_from_centered_ = Eigen::Isometry3d::Identity();
  Eigen::Vector3d principal_variances_ = Eigen::Vector3d::Zero();
  double diameter_mm_ = 0.0;
  double max_pair_distance_mm_ = 0.0;
  double sampling_step_mm_ = 0.0;
  double distance_step_mm_ = 1.0;
  double angle_step_rad_ = std::numbers::pi / 15.0;
  int distance_bins_ = 0;
  int angle_bins_ = 0;
  int alpha_bins_ = 1;
  std::vector<std::uint32_t> keys_;     // sorted unique keys
  std::vector<std::uint32_t> offsets_;  // keys_.size() + 1, into entries_
  std::vector<PpfPairEntry> entries_;   // grouped by key, (reference, other) order within a key
  std::vector<std::uint32_t> dense_offsets_;  // key space + 1 (derived, not serialized)
  std::vector<double> cos_thresholds_;        // cos(k step), k = 1 .. angle_bins-1 (derived)
  double inv_distance_step_ = 1.0;            // derived
};

/// Diameter estimate used by PpfModel: largest distance between the extreme points along 13
/// fixed directions, mm (0 for fewer than two points).
double EstimateDiameter(std::span<const Eigen::Vector3d> points);

}  // namespace lasercell::registration
