#pragma once
// The online part of Drost et al. 2010 (Sec. 3.3-3.4): every n-th scene point is a reference
// point s_r; it is paired with every scene point s_i within the model's largest pair distance
// (kd-tree radius search); each pair's feature looks up all model pairs (m_r, m_i) with the same
// quantized feature, and each of those votes for the local coordinate (m_r, alpha) in a
// per-reference accumulator. Accumulator maxima become pose hypotheses
//   scene_from_centered = T(s_r)^-1 R_x(alpha) T(m_r)   (Drost eq. 2-3).
// Frames: scene points in `scene`, model in `centered` (see ppf_model.hpp). Units mm, rad.
// Multi-threaded over reference points; hypotheses are stored per reference point and merged
// in reference order, so the output is identical for any thread count.

#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "registration/kdtree.hpp"
#include "registration/ppf_model.hpp"

namespace lasercell::registration {

/// Options for MatchPpf.
struct PpfMatchOptions {
  /// Every n-th sampled scene point is used as a reference point (Drost: 1/5 of the points).
  std::size_t reference_stride = 5;
  /// At most this many reference points (0 = no cap): the stride becomes
  /// max(reference_stride, ceil(points / max_reference_points)). Voting costs reference points x
  /// neighbours within the model diameter x model pairs per feature, so a scene much larger than
  /// the model (a room-size Kinect view around a carton) would otherwise take seconds while adding
  /// few references on the part. Deterministic: the stride depends only on the scene size.
  std::size_t max_reference_points = 1000;
  /// Accumulator maxima kept per reference point (several peaks, as in Drost Sec. 3.4), 1..16.
  std::size_t peaks_per_reference = 3;
  /// Secondary peaks are kept only with at least this fraction of the reference's best votes.
  double peak_min_relative = 0.75;
  /// Peaks with fewer votes are not kept (>= 1).
  std::uint32_t min_votes = 3;
  /// Also look up the nearer neighbouring bin of each feature dimension (2^4 keys per pair;
  /// robustness to noise at quantization borders, Hinterstoisser et al. 2016). Slower.
  bool spread_features = false;
  /// Also vote for the nearer neighbouring alpha bin (alpha quantization robustness). Doubles
  /// the voting time; on the UWA data it made no difference to the success rate.
  bool spread_alpha = false;
  /// Model entries voted per looked-up key at most (0 = all, the default). A smooth or flat part
  /// floods a few keys with its coplanar pairs (the seat: up to 24,000 entries under one key,
  /// 1,560 per lookup on average); they cast nearly every vote and take nearly all the voting
  /// time. A key holding n > cap entries votes with every s-th entry only, s = ceil(n / cap),
  /// starting at the scene pair's own offset (its count mod s, so the many pairs of a reference
  /// use every entry): a feature weighs at most `cap` votes, in the spirit of inverse-frequency
  /// weighting. Measured (`lasercell bench speed`, BENCHMARKS.md): at 16-64 the seat, rs1, rs22
  /// and milk keep their poses and the seat's voting is ~20x faster; but the armrest of the
  /// pallet scene, a thin shell whose evidence lies in its flooded keys, is lost at every cap
  /// tried (32-256; weighting the kept votes by s, an unbiased estimate of the full vote, loses
  /// it too), hence off by default: set it per job for parts it is measured on.
  std::size_t max_entries_per_key = 0;
  /// One vote per (feature key, scene plane-angle bin) per reference point (Hinterstoisser et al.
  /// 2016, Sec. 3.3): a second scene pair of the same reference with the same key and a scene
  /// angle phi_s in the same alpha bin would cast the very same votes again, so it is skipped.
  /// Flat regions, whose many coplanar pairs share a few keys, no longer outvote the part's
  /// distinctive pairs, and their repeated votes are not cast at all. Needs alpha_bins <= 64
  /// (one bit per bin); a finer alpha quantization votes every pair.
  bool unique_votes = false;
  /// Place each peak's alpha between bin centres by a parabola through the peak cell and its two
  /// alpha neighbours (vertex of the quadratic through three equally spaced samples, clamped to
  /// the peak's bin), instead of at the bin centre: the accumulator row is a histogram of the
  /// continuous alphas, so its vertex estimates their mode to a fraction of the step.
  bool interpolate_alpha = true;
  /// Worker threads: 0 = all cores, 1 = calling thread only.
  int threads = 0;
  /// Throws OptionError naming the field when a value is out of range.
  void Check() const;
};

/// One accumulator peak turned into a pose.
struct PoseHypothesis {
  Eigen::Isometry3d scene_from_centered = Eigen::Isometry3d::Identity();  ///< Model pose.
  double votes = 0.0;                 ///< Accumulator value at the peak.
  std::uint32_t scene_reference = 0;  ///< Index of s_r in the sampled scene.
  std::uint32_t model_reference = 0;  ///< Index of m_r in PpfModel::points().
  std::int32_t alpha_bin = 0;         ///< Alpha bin of the peak.
  double alpha_rad = 0.0;  ///< Alpha used for the pose (bin centre, or interpolated), rad.
};

/// Hypotheses and counters from MatchPpf.
struct PpfMatchResult {
  std::vector<PoseHypothesis> hypotheses;  ///< Reference order, best peak first per reference.
  std::size_t reference_points = 0;        ///< Scene reference points used.
  std::size_t scene_pairs = 0;             ///< Scene pairs whose feature was looked up.
  std::size_t votes_cast = 0;              ///< Total accumulator increments.
};

/// Drost voting. `scene_tree` holds the sampled scene points; `scene_normals` their unit normals
/// (same order). Throws InputError on mismatched sizes, OptionError on bad options.
PpfMatchResult MatchPpf(const KdTree& scene_tree, std::span<const Eigen::Vector3d> scene_normals,
                        const PpfModel& model, const PpfMatchOptions& options = {});

}  // namespace lasercell::registration
