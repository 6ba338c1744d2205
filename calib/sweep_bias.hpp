#pragma once
// Does the kinematic model explain the sweeps? A right model leaves each sweep's residuals
// (point-to-sphere distances at the solution) centred on zero up to their own scatter; a model
// error (link lengths off, a wrong radius or centre) moves a whole sweep's points together and
// shows as per-sweep mean residuals larger than the within-sweep scatter explains. The
// statistic is one-way ANOVA's F over the sweeps:
//   F = [sum_k n_k m_k^2 / (K - 1)] / [sum_k (n_k rms_k^2 - n_k m_k^2) / (N - K)],
// with m_k, rms_k, n_k the mean, RMS and count of sweep k, K sweeps and N points. F ~ 1 for a
// right model with independent noise; the fit absorbs a little of the means, so slightly less.

#include <vector>

namespace lasercell::calib {

struct SweepResidual;

/// The F ratio above over sweeps with at least 2 points; 0 when fewer than 2 such sweeps or no
/// within-sweep scatter.
double SweepBiasRatio(const std::vector<SweepResidual>& sweeps);

/// Above this F the per-sweep means are twice (sqrt 4) what the within-sweep noise explains:
/// IdentifyRobot warns that the model misses something. Measured on the simulator's realistic
/// profile: 1.4-1.7 with the link lengths estimated or exact, 65 with 0.2 mm link-length errors
/// left to the joint offsets (BENCHMARKS.md, robot side on the realistic profile).
inline constexpr double kSweepBiasWarningRatio = 4.0;

}  // namespace lasercell::calib
