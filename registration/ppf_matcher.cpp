#include "registration/ppf_matcher.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.hpp"
#include "core/parallel.hpp"

namespace lasercell::registration {
namespace {

// Per-thread scratch: the accumulator over (model point, alpha bin), cleared per reference.
struct Voter {
  std::vector<std::uint32_t> accumulator;
  std::vector<Neighbor> hits;
  // PpfMatchOptions::unique_votes: per key, a bit per scene alpha bin already voted, and the keys
  // set for this reference (cleared before the next).
  std::vector<std::uint64_t> voted;
  std::vector<std::uint32_t> voted_keys;
};

// Sub-bin offset of an accumulator peak along alpha, in bins within [-0.5, 0.5]: the vertex of
// the parabola through (-1, left), (0, peak), (1, right), the alpha row being circular.
double AlphaOffset(const std::uint32_t* acc, std::uint32_t cell, std::size_t alpha_bins) {
  if (alpha_bins < 3) return 0.0;
  const std::size_t bin = cell % alpha_bins;
  const std::uint32_t* row = acc + (cell - bin);
  const double left = row[bin == 0 ? alpha_bins - 1 : bin - 1];
  const double right = row[bin + 1 == alpha_bins ? 0 : bin + 1];
  const double peak = row[bin];
  const double curvature = left - 2.0 * peak + right;
  if (!(curvature < 0.0)) return 0.0;  // flat: no vertex to prefer over the bin centre
  return std::clamp(0.5 * (left - right) / curvature, -0.5, 0.5);
}

// Bin of a continuous quantized value and its nearer neighbour (-1 when out of range).
struct BinPair {
  int bin;
  int neighbor;
};

BinPair NearBins(double value, int bins) {
  const int bin = std::clamp(static_cast<int>(value), 0, bins - 1);
  const double frac = value - bin;
  const int neighbor = frac < 0.5 ? bin - 1 : bin + 1;
  return {bin, (neighbor >= 0 && neighbor < bins) ? neighbor : -1};
}

// Keys to look up for one scene pair: the feature's own key, plus (with spreading) the keys of
// the nearer neighbouring bin in every dimension (2^4 combinations, Hinterstoisser 2016).
int SpreadFeatureKeys(const PpfModel& model, const PpfFeature& f, std::uint32_t keys[16]) {
  const double d = f.distance_mm / model.distance_step_mm();
  if (!(d < model.distance_bins())) return 0;
  const BinPair dims[4] = {NearBins(d, model.distance_bins()),
                           NearBins(f.angle_n1_d / model.angle_step_rad(), model.angle_bins()),
                           NearBins(f.angle_n2_d / model.angle_step_rad(), model.angle_bins()),
                           NearBins(f.angle_n1_n2 / model.angle_step_rad(), model.angle_bins())};
  int count = 0;
  for (int mask = 0; mask < 16; ++mask) {
    int b[4];
    bool valid = true;
    for (int k = 0; k < 4; ++k) {
      b[k] = (mask >> k) & 1 ? dims[k].neighbor : dims[k].bin;
      valid = valid && b[k] >= 0;
    }
    if (!valid) continue;
    keys[count++] = model.Key({b[0], b[1], b[2], b[3]});
  }
  return count;
}

// The accumulator's maxima of one scene reference point s_r = scene[r] as poses: the best
// peaks_per_reference cells (ties by lower cell index) with at least min_votes and
// peak_min_relative of the best, each turned into
//   scene_from_centered = T(s_r)^-1 R_x(alpha) T(m_r)   (Drost eq. 2-3),
// alpha at the bin centre or at the vertex of the parabola through the peak and its neighbours
// (options.interpolate_alpha). `rot_s` is RotationNormalToX of the reference's normal.
void AccumulatorPeaks(const std::uint32_t* acc, std::size_t cells, const PpfModel& model,
                      const PpfMatchOptions& options, const Eigen::Matrix3d& rot_s,
                      const Eigen::Vector3d& s_r, std::size_t r, std::vector<PoseHypothesis>* out) {
  const std::size_t alpha_bins = static_cast<std::size_t>(model.alpha_bins());
  const std::size_t keep = options.peaks_per_reference;
  std::uint32_t best_cell[16];
  std::uint32_t best_votes[16];
  std::size_t found = 0;
  const std::uint32_t floor_votes = options.min_votes;
  for (std::size_t cell = 0; cell < cells; ++cell) {
    const std::uint32_t v = acc[cell];
    if (v < floor_votes || (found == keep && v <= best_votes[found - 1])) continue;
    std::size_t pos = found < keep ? found++ : keep - 1;
    while (pos > 0 && best_votes[pos - 1] < v) {
      best_votes[pos] = best_votes[pos - 1];
      best_cell[pos] = best_cell[pos - 1];
      --pos;
    }
    best_votes[pos] = v;
    best_cell[pos] = static_cast<std::uint32_t>(cell);
  }
  for (std::size_t p = 0; p < found; ++p) {
    const std::uint32_t cell = best_cell[p];
    const double v = best_votes[p];
    if (v < options.peak_min_relative * best_votes[0]) break;
    PoseHypothesis h;
    h.votes = v;
    h.scene_reference = static_cast<std::uint32_t>(r);
    h.model_reference = static_cast<std::uint32_t>(cell / alpha_bins);
    h.alpha_bin = static_cast<std::int32_t>(cell % alpha_bins);
    const double alpha = (h.alpha_bin + 0.5 +
                          (options.interpolate_alpha ? AlphaOffset(acc, cell, alpha_bins) : 0.0)) *
                         model.alpha_step_rad();
    h.alpha_rad = alpha;
    const Eigen::Vector3d& m_r = model.points()[h.model_reference];
    const Eigen::Matrix3d rot =
        rot_s.transpose() * Eigen::AngleAxisd(alpha, Eigen::Vector3d::UnitX()).toRotationMatrix() *
        RotationNormalToX(model.normals()[h.model_reference]);
    h.scene_from_centered.linear() = rot;
    h.scene_from_centered.translation() = s_r - rot * m_r;
    out->push_back(h);
  }
}

}  // namespace

void PpfMatchOptions::Check() const {
  if (reference_stride < 1)
    throw OptionError("PpfMatchOptions.reference_stride must be >= 1 (1 = every scene point)");
  if (peaks_per_reference < 1 || peaks_per_reference > 16) {
    throw OptionError("PpfMatchOptions.peaks_per_reference = " +
                      std::to_string(peaks_per_reference) + ": must be in [1, 16]");
  }
  if (!(peak_min_relative >= 0.0 && peak_min_relative <= 1.0)) {
    throw OptionError("PpfMatchOptions.peak_min_relative = " + std::to_string(peak_min_relative) +
                      ": must be in [0, 1]");
  }
  if (min_votes < 1) throw OptionError("PpfMatchOptions.min_votes must be >= 1");
}

PpfMatchResult MatchPpf(const KdTree& scene_tree, std::span<const Eigen::Vector3d> scene_normals,
                        const PpfModel& model, const PpfMatchOptions& options) {
  options.Check();
  if (scene_normals.size() != scene_tree.size()) {
    throw InputError("MatchPpf: " + std::to_string(scene_normals.size()) + " scene normals for " +
                     std::to_string(scene_tree.size()) +
                     " scene points; give one unit normal per point");
  }
  PpfMatchResult result;
  const std::vector<Eigen::Vector3d>& scene = scene_tree.points();
  std::size_t stride = options.reference_stride;
  if (options.max_reference_points > 0)
    stride = std::max(
        stride, (scene.size() + options.max_reference_points - 1) / options.max_reference_points);
  const std::size_t refs = (scene.size() + stride - 1) / stride;
  result.reference_points = refs;
  if (refs == 0 || model.points().empty()) return result;

  const std::size_t alpha_bins = static_cast<std::size_t>(model.alpha_bins());
  const double radius = model.max_pair_distance_mm();
  std::vector<std::vector<PoseHypothesis>> per_reference(refs);
  std::vector<std::size_t> pairs_of(refs, 0), votes_of(refs, 0);
  const bool unique = options.unique_votes && alpha_bins <= 64;
  const std::size_t key_space = static_cast<std::size_t>(model.distance_bins()) *
                                model.angle_bins() * model.angle_bins() * model.angle_bins();
  WorkerLocal<Voter> voters([&] {
    Voter v;
    v.accumulator.assign(model.points().size() * alpha_bins, 0);
    if (unique) v.voted.assign(key_space, 0);
    return v;
  });
  const std::uint32_t spread_alpha = options.spread_alpha && alpha_bins > 1 ? 1 : 0;
  const std::size_t cap = options.max_entries_per_key;

  ParallelForChunks(options.threads, refs, 4, [&](std::size_t begin, std::size_t end) {
    Voter& voter = voters.local();
    std::uint32_t* acc = voter.accumulator.data();
    const std::size_t cells = voter.accumulator.size();
    for (std::size_t ref = begin; ref < end; ++ref) {
      const std::size_t r = ref * stride;
      const Eigen::Vector3d& s_r = scene[r];
      const Eigen::Vector3d& n_r = scene_normals[r];
      const Eigen::Matrix3d rot_s = RotationNormalToX(n_r);
      scene_tree.RadiusSearch(s_r, radius, &voter.hits);
      std::fill(acc, acc + cells, 0U);
      std::size_t pairs = 0, votes = 0;
      std::uint32_t keys[16];
      for (const Neighbor& hit : voter.hits) {
        if (hit.index == r) continue;
        const Eigen::Vector3d& s_i = scene[hit.index];
        const Eigen::Vector3d& n_i = scene_normals[hit.index];
        int key_count = 0;
        if (options.spread_features)
          key_count = SpreadFeatureKeys(model, ComputePpf(s_r, n_r, s_i, n_i), keys);
        else
          key_count = model.PairKey(s_r, n_r, s_i, n_i, &keys[0]) ? 1 : 0;
        if (key_count == 0) continue;
        ++pairs;
        // The plane angle (an atan2) only for a pair whose key holds model pairs.
        bool any = false;
        for (int k = 0; k < key_count && !any; ++k) any = !model.Lookup(keys[k]).empty();
        if (!any) continue;
        // alpha = phi_s - phi_m (Drost Sec. 3.5, alpha split into a scene and a model part), in
        // 16-bit turns so the wrap to [0, 2 pi) is the natural unsigned overflow.
        const std::uint16_t phi_s = PlaneAngleToTurn16(PairPlaneAngle(rot_s, s_r, s_i));
        // unique_votes: this pair's scene alpha bin as a bit (alpha_bins <= 64 when unique).
        const std::uint64_t phi_bit =
            unique ? std::uint64_t{1} << ((static_cast<std::uint32_t>(phi_s) * alpha_bins) >> 16)
                   : 0;
        for (int k = 0; k < key_count; ++k) {
          if (unique) {
            std::uint64_t& voted = voter.voted[keys[k]];
            if (voted & phi_bit) continue;  // the same votes were cast by an earlier pair
            if (voted == 0) voter.voted_keys.push_back(keys[k]);
            voted |= phi_bit;
          }
          const std::span<const PpfPairEntry> entries = model.Lookup(keys[k]);
          const std::size_t n = entries.size();
          // A flooded key votes with every step-th entry only (PpfMatchOptions::
          // max_entries_per_key); the offset turns with the pair count.
          const std::size_t step = cap > 0 && n > cap ? (n + cap - 1) / cap : 1;
          const std::size_t first = step > 1 ? pairs % step : 0;
          votes += ((n - first + step - 1) / step) << spread_alpha;
          for (std::size_t i = first; i < n; i += step) {
            const PpfPairEntry& e = entries[i];
            const std::uint32_t scaled = static_cast<std::uint16_t>(phi_s - e.plane_angle) *
                                         static_cast<std::uint32_t>(alpha_bins);
            const std::uint32_t bin = scaled >> 16;
            std::uint32_t* row = acc + static_cast<std::size_t>(e.reference) * alpha_bins;
            ++row[bin];
            if (spread_alpha) {
              // The nearer neighbouring alpha bin also gets a vote (upper or lower half of the
              // bin).
              const bool upper = (scaled >> 15) & 1U;
              ++row[upper ? (bin + 1 == alpha_bins ? 0 : bin + 1)
                          : (bin == 0 ? alpha_bins - 1 : bin - 1)];
            }
          }
        }
      }
      pairs_of[ref] = pairs;
      votes_of[ref] = votes;
      for (std::uint32_t key : voter.voted_keys) voter.voted[key] = 0;
      voter.voted_keys.clear();

      AccumulatorPeaks(acc, cells, model, options, rot_s, s_r, r, &per_reference[ref]);
    }
  });

  for (std::size_t ref = 0; ref < refs; ++ref) {
    result.scene_pairs += pairs_of[ref];
    result.votes_cast += votes_of[ref];
    result.hypotheses.insert(result.hypotheses.end(), per_reference[ref].begin(),
                             per_reference[ref].end());
  }
  return result;
}

}  // namespace lasercell::registration
