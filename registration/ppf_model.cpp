#include "registration/ppf_model.hpp"

#include <Eigen/Eigenvalues>
#include <array>
#include <cmath>
#include <sstream>
#include <string>

#include "core/error.hpp"
#include "core/parallel.hpp"

namespace lasercell::registration {
namespace {

// pair_key of an ordered model pair that has no feature (coincident points).
constexpr std::uint32_t kNoPair = 0xFFFFFFFFU;

constexpr std::size_t kMaxKeySpace = std::size_t{1} << 25;

double StepFrom(double absolute_mm, double relative, double diameter_mm) {
  return absolute_mm > 0.0 ? absolute_mm : relative * diameter_mm;
}

void CheckPositive(double value, const char* field, const char* meaning) {
  if (!(value > 0.0) || !std::isfinite(value)) {
    throw OptionError(std::string("PpfModelOptions.") + field + " = " + std::to_string(value) +
                      ": must be > 0 (" + meaning + ")");
  }
}

void CheckNonNegative(double value, const char* field, const char* meaning) {
  if (!(value >= 0.0) || !std::isfinite(value)) {
    throw OptionError(std::string("PpfModelOptions.") + field + " = " + std::to_string(value) +
                      ": must be >= 0 (" + meaning + ")");
  }
}

// Oriented, unit-normal copy of the model: normals as given (renormalized; UWA files carry
// unnormalized normals) or estimated. Points whose normal is zero are dropped.
PointCloud OrientedModel(const PointCloud& model, const PpfModelOptions& options) {
  if (!model.HasNormals()) return WithEstimatedNormals(model, options.normals);
  PointCloud out;
  out.Reserve(model.size());
  for (std::size_t i = 0; i < model.size(); ++i) {
    const double length = model.normals[i].norm();
    if (!(length > 1e-12)) continue;
    out.positions.push_back(model.positions[i]);
    out.normals.push_back(model.normals[i] / length);
  }
  return out;
}

}  // namespace

void PpfModelOptions::Check() const {
  CheckNonNegative(sampling_step_mm, "sampling_step_mm", "absolute voxel size in mm; 0 = relative");
  CheckNonNegative(distance_step_mm, "distance_step_mm",
                   "absolute distance step in mm; 0 = relative");
  if (sampling_step_mm == 0.0)
    CheckPositive(sampling_step_relative, "sampling_step_relative",
                  "fraction of the diameter, e.g. 0.04");
  if (distance_step_mm == 0.0)
    CheckPositive(distance_step_relative, "distance_step_relative",
                  "fraction of the diameter, e.g. 0.05");
  if (sampling_step_relative > 1.0) {
    throw OptionError(
        "PpfModelOptions.sampling_step_relative = " + std::to_string(sampling_step_relative) +
        ": must be <= 1 (fraction of the model diameter)");
  }
  CheckPositive(angle_step_rad, "angle_step_rad", "angle quantization in rad, e.g. pi/15");
  if (angle_step_rad > std::numbers::pi / 2.0 || angle_step_rad < std::numbers::pi / 180.0) {
    throw OptionError("PpfModelOptions.angle_step_rad = " + std::to_string(angle_step_rad) +
                      ": must be in [pi/180, pi/2] rad (Drost uses 2 pi / 30)");
  }
  CheckNonNegative(refinement_step_relative, "refinement_step_relative",
                   "fraction of the diameter; 0 keeps all points");
  if (max_model_points < 2 || max_model_points > 65535) {
    throw OptionError("PpfModelOptions.max_model_points = " + std::to_string(max_model_points) +
                      ": must be in [2, 65535]");
  }
  if (!(normal_split_angle_rad >= 0.0 && normal_split_angle_rad <= std::numbers::pi)) {
    throw OptionError("PpfModelOptions.normal_split_angle_rad = " +
                      std::to_string(normal_split_angle_rad) + ": must be in [0, pi] rad");
  }
  normals.Check();
}

double EstimateDiameter(std::span<const Eigen::Vector3d> points) {
  if (points.size() < 2) return 0.0;
  static const std::array<Eigen::Vector3d, 13> kDirections = {
      Eigen::Vector3d(1, 0, 0),  Eigen::Vector3d(0, 1, 0),  Eigen::Vector3d(0, 0, 1),
      Eigen::Vector3d(1, 1, 0),  Eigen::Vector3d(1, -1, 0), Eigen::Vector3d(1, 0, 1),
      Eigen::Vector3d(1, 0, -1), Eigen::Vector3d(0, 1, 1),  Eigen::Vector3d(0, 1, -1),
      Eigen::Vector3d(1, 1, 1),  Eigen::Vector3d(1, 1, -1), Eigen::Vector3d(1, -1, 1),
      Eigen::Vector3d(-1, 1, 1)};
  std::vector<Eigen::Vector3d> extremes;
  for (const Eigen::Vector3d& dir : kDirections) {
    std::size_t lo = 0, hi = 0;
    for (std::size_t i = 1; i < points.size(); ++i) {
      if (points[i].dot(dir) < points[lo].dot(dir)) lo = i;
      if (points[i].dot(dir) > points[hi].dot(dir)) hi = i;
    }
    extremes.push_back(points[lo]);
    extremes.push_back(points[hi]);
  }
  double best = 0.0;
  for (std::size_t i = 0; i < extremes.size(); ++i) {
    for (std::size_t j = i + 1; j < extremes.size(); ++j) {
      best = std::max(best, (extremes[i] - extremes[j]).squaredNorm());
    }
  }
  return std::sqrt(best);
}

PpfModel PpfModel::Build(const TriangleMesh& model, const PpfModelOptions& options) {
  if (model.faces.empty() || model.vertices.HasNormals()) return Build(model.vertices, options);
  return Build(WithMeshNormals(model), options);
}

PpfModel PpfModel::Build(const PointCloud& model_cloud, const PpfModelOptions& options) {
  options.Check();
  model_cloud.Validate("PPF model cloud");
  if (model_cloud.size() < 3) {
    throw InputError("PPF model cloud has " + std::to_string(model_cloud.size()) +
                     " points; a model needs at least 3 points with normals");
  }
  const PointCloud oriented = OrientedModel(model_cloud, options);
  if (oriented.size() < 3) {
    throw InputError("PPF model cloud: fewer than 3 points have a usable (non-zero) normal");
  }
  PpfModel model;
  model.diameter_mm_ = EstimateDiameter(oriented.positions);
  if (!(model.diameter_mm_ > 0.0)) throw InputError("PPF model cloud has no spatial extent");

  // Drost Sec. 3.2: subsample with tau_d relative to the diameter.
  model.sampling_step_mm_ =
      StepFrom(options.sampling_step_mm, options.sampling_step_relative, model.diameter_mm_);
  VoxelGridOptions voxel;
  voxel.voxel_size_mm = model.sampling_step_mm_;
  voxel.normal_mode = options.normal_mode == VoxelNormalMode::kNone ? VoxelNormalMode::kAverage
                                                                    : options.normal_mode;
  voxel.normal_split_angle_rad = options.normal_split_angle_rad;
  const PointCloud sampled = VoxelGridDownsample(oriented, voxel);
  if (sampled.size() > options.max_model_points) {
    throw OptionError("PpfModelOptions.sampling_step: the model subsampled at " +
                      std::to_string(model.sampling_step_mm_) + " mm has " +
                      std::to_string(sampled.size()) + " points, more than max_model_points = " +
                      std::to_string(options.max_model_points) + "; use a larger sampling step");
  }
  if (sampled.size() < 2) {
    throw OptionError("PpfModelOptions.sampling_step: the model subsampled at " +
                      std::to_string(model.sampling_step_mm_) +
                      " mm has fewer than 2 points; use a smaller step");
  }

  // Skotheim IV-E: the model is centred at its centroid, so pose translations cluster well.
  const Eigen::Vector3d centroid = sampled.Centroid();
  model.model_from_centered_ = Eigen::Translation3d(centroid);
  model.points_.reserve(sampled.size());
  for (const auto& p : sampled.positions) model.points_.push_back(p - centroid);
  model.normals_ = sampled.normals;

  PointCloud refinement = oriented;
  if (options.refinement_step_relative > 0.0) {
    VoxelGridOptions fine;
    fine.voxel_size_mm = options.refinement_step_relative * model.diameter_mm_;
    fine.normal_mode = VoxelNormalMode::kNearestPoint;
    refinement = VoxelGridDownsample(oriented, fine);
  }
  for (auto& p : refinement.positions) p -= centroid;
  model.refinement_normals_ = std::move(refinement.normals);
  model.refinement_tree_ = KdTree(std::move(refinement.positions));

  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : model.points_) cov.noalias() += p * p.transpose();
  cov /= static_cast<double>(model.points_.size());
  model.principal_variances_ =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvalues().reverse();

  // Quantization (Drost Sec. 3.2): distance step and angle step; alpha over a full turn.
  model.distance_step_mm_ =
      StepFrom(options.distance_step_mm, options.distance_step_relative, model.diameter_mm_);
  model.angle_step_rad_ = options.angle_step_rad;
  model.angle_bins_ = static_cast<int>(std::ceil(std::numbers::pi / options.angle_step_rad - 1e-9));
  model.alpha_bins_ =
      std::max(1, static_cast<int>(std::lround(2.0 * std::numbers::pi / options.angle_step_rad)));
  const std::size_t n = model.points_.size();
  double max_sq = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = i + 1; j < n; ++j)
      max_sq = std::max(max_sq, (model.points_[i] - model.points_[j]).squaredNorm());
  }
  model.max_pair_distance_mm_ = std::sqrt(max_sq);
  model.distance_bins_ =
      static_cast<int>(model.max_pair_distance_mm_ / model.distance_step_mm_) + 1;
  const std::size_t a = static_cast<std::size_t>(model.angle_bins_);
  const std::size_t key_space = static_cast<std::size_t>(model.distance_bins_) * a * a * a;
  if (key_space > kMaxKeySpace) {
    throw OptionError(
        "PpfModelOptions.distance_step / angle_step_rad: " + std::to_string(model.distance_bins_) +
        " distance bins x " + std::to_string(a) +
        "^3 angle bins exceed the 2^25 supported keys; "
        "use a larger distance or angle step");
  }

  // Every ordered pair (m_r, m_i), i != r: key and phi_m. Each reference writes its own row.
  model.ComputeQuantizationConstants();
  const std::size_t row = n - 1;
  std::vector<std::uint32_t> pair_key(n * row);
  std::vector<std::uint16_t> pair_angle(n * row);
  ParallelForChunks(options.threads, n, 16, [&](std::size_t begin, std::size_t end) {
    for (std::size_t r = begin; r < end; ++r) {
      const Eigen::Matrix3d rot = RotationNormalToX(model.normals_[r]);
      std::size_t slot = r * row;
      for (std::size_t i = 0; i < n; ++i) {
        if (i == r) continue;
        const bool in_range = model.PairKey(model.points_[r], model.normals_[r], model.points_[i],
                                            model.normals_[i], &pair_key[slot]);
        // Two faces' samples of one voxel (normal split) can share a position: no feature.
        const bool coincident = model.points_[r] == model.points_[i];
        LASERCELL_CHECK(in_range || coincident, "model pair beyond max_pair_distance");
        if (!in_range) pair_key[slot] = kNoPair;
        pair_angle[slot] =
            PlaneAngleToTurn16(PairPlaneAngle(rot, model.points_[r], model.points_[i]));
        ++slot;
      }
    }
  });

  // Counting sort by key (stable: pairs keep (reference, other) order within a key).
  std::vector<std::uint32_t> start(key_space + 1, 0);
  std::size_t pairs = 0;
  for (std::uint32_t k : pair_key) {
    if (k == kNoPair) continue;
    ++start[k + 1];
    ++pairs;
  }
  for (std::size_t k = 0; k < key_space; ++k) start[k + 1] += start[k];
  model.entries_.resize(pairs);
  std::vector<std::uint32_t> cursor(start.begin(), start.end() - 1);
  for (std::size_t p = 0; p < pair_key.size(); ++p) {
    if (pair_key[p] == kNoPair) continue;
    model.entries_[cursor[pair_key[p]]++] = {static_cast<std::uint16_t>(p / row), pair_angle[p]};
  }
  for (std::size_t k = 0; k < key_space; ++k) {
    if (start[k + 1] == start[k]) continue;
    model.keys_.push_back(static_cast<std::uint32_t>(k));
    model.offsets_.push_back(start[k]);
  }
  model.offsets_.push_back(static_cast<std::uint32_t>(model.entries_.size()));
  model.BuildDenseIndex();
  return model;
}

void PpfModel::ComputeQuantizationConstants() {
  inv_distance_step_ = 1.0 / distance_step_mm_;
  cos_thresholds_.clear();
  for (int k = 1; k < angle_bins_; ++k) cos_thresholds_.push_back(std::cos(k * angle_step_rad_));
}

void PpfModel::BuildDenseIndex() {
  ComputeQuantizationConstants();
  const std::size_t a = static_cast<std::size_t>(angle_bins_);
  const std::size_t key_space = static_cast<std::size_t>(distance_bins_) * a * a * a;
  dense_offsets_.assign(key_space + 1, 0);
  // dense_offsets_[k] = first entry of the first stored key >= k.
  std::size_t next = 0;
  for (std::size_t k = 0; k <= key_space; ++k) {
    while (next < keys_.size() && keys_[next] < k) ++next;
    dense_offsets_[k] =
        next < keys_.size() ? offsets_[next] : static_cast<std::uint32_t>(entries_.size());
  }
}

std::string PpfModel::Summary() const {
  std::ostringstream s;
  s << "PPF model: " << points_.size() << " points (" << refinement_points().size()
    << " for refinement), diameter " << diameter_mm_ << " mm, " << entries_.size() << " pairs in "
    << keys_.size() << " keys, sampling " << sampling_step_mm_ << " mm, distance step "
    << distance_step_mm_ << " mm, angle step " << angle_step_rad_ << " rad, " << alpha_bins_
    << " alpha bins";
  return s.str();
}

}  // namespace lasercell::registration
