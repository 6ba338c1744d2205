#include "calib/sweep_bias.hpp"

#include "calib/joint_identification.hpp"

namespace lasercell::calib {

double SweepBiasRatio(const std::vector<SweepResidual>& sweeps) {
  double between = 0, within = 0, points = 0;
  int groups = 0;
  for (const SweepResidual& s : sweeps) {
    if (s.points < 2) continue;
    const double n = static_cast<double>(s.points);
    between += n * s.mean_mm * s.mean_mm;
    within += n * (s.rms_mm * s.rms_mm - s.mean_mm * s.mean_mm);
    points += n;
    ++groups;
  }
  if (groups < 2 || !(within > 0) || points <= groups) return 0;
  return (between / (groups - 1)) / (within / (points - groups));
}

}  // namespace lasercell::calib
