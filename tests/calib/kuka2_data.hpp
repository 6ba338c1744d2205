#pragma once
// The real kuka2 eye-in-hand set for the tests: calib::LoadKuka2Set (calib/kuka2_set.hpp, the
// loader `lasercell bench calibration` uses too) on the shared originals, with the board
// searched at half resolution (search_downscale 2: the SB search takes 1.8 s for the 28 images
// instead of 6.7 s at full resolution, measured; too slow for a unit test run once per test
// process) and refined at full resolution (the same corners as the full-resolution search: the
// bench's kuka2 numbers equal these tests'). Computed once per test process (detection is the
// slow part).
#include <cstdio>
#include <memory>
#include <string>

#include "calib/kuka2_set.hpp"
#include "calib/target_detection.hpp"
#include "tests/shared_data.hpp"

namespace lasercell::calib::realdata {

using Kuka2 = Kuka2Set;

/// The prepared set, or nullptr when it is absent (then SKIP with Kuka2Missing()).
inline const Kuka2* LoadKuka2() {
  static const std::unique_ptr<Kuka2> data = []() -> std::unique_ptr<Kuka2> {
    const std::string dir = lasercell::shared_data::SharedDataSet("handeye_kuka2");
    if (dir.empty()) return nullptr;
    DetectionOptions options;
    options.search_downscale = 2;
    auto k = std::make_unique<Kuka2>(LoadKuka2Set(dir, options));
    if (k->camera) {
      const std::vector<double>& intr = k->camera->intrinsics();
      std::printf(
          "kuka2 stand-in intrinsics: calibrateCamera RMS %.3f px, fx %.2f fy %.2f cx "
          "%.2f cy %.2f\n",
          k->calibration_rms_px, intr[0], intr[1], intr[2], intr[3]);
    }
    return k;
  }();
  return data.get();
}

inline std::string Kuka2Missing() {
  return lasercell::shared_data::SharedDataMissing("handeye_kuka2");
}

}  // namespace lasercell::calib::realdata
