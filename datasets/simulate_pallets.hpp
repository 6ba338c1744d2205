#pragma once
// Pallet scenes (Skotheim et al., Fig. 4): the seat, the seat back and the armrest lying on the
// pallet (datasets/pallet_scene.hpp), each scene one linear sweep over the whole pallet, with
// truth. The back and the armrest are CAD solids (datasets/chair_parts.hpp) written as STEP;
// what the sensor sees is that STEP file read back at a fine tessellation, while a localization
// job samples the same file at its own step.
//
// Output folder (fields: datasets/SIMULATOR.md):
//   profiles/pallet_NNN.lcp       the sweep of scene NNN
//   records/linear_sweep.yaml     t0 and the velocity in the sensor frame (no truth)
//   models/back.step, models/armrest.step              the CAD parts (AP214, mm)
//   models/{seat,back,armrest}.part.yaml               part files (localize/part.hpp): model,
//                                 grasp frame; the CAD parts' with their stable poses
//   models/{seat,back,armrest,pallet}.{ply,stl}        rendered meshes (CAD parts: the fine
//                                 tessellation of the STEP file)
//   truth/cell.yaml               true frame graph with handling_base -> <part>_NNN per part
//   truth/captures.yaml           per scene: sweep, per part its stable pose, yaw, shift,
//                                 cell_from_part, handling_base_from_part, grasp frames in cell
//                                 and handling_base; then per part its stable poses and grasps
//   truth/sensor.yaml, truth/robots.yaml, truth/camera.cameramodel, truth/sim_config.yaml
// Same config, options and seed -> identical bytes for any thread count.

#include <string>

#include "core/progress.hpp"
#include "datasets/chair_parts.hpp"
#include "datasets/pallet_scene.hpp"
#include "datasets/sim_config.hpp"
#include "datasets/simulate.hpp"

namespace lasercell::datasets {

/// What SimulatePallets builds beyond the SimConfig.
struct PalletSimOptions {
  SeatBackOptions back;              ///< Seat back geometry.
  ArmrestOptions armrest;            ///< Armrest geometry.
  PalletPlacementOptions placement;  ///< Where the parts may lie.
  /// Length of the pallet scenes' linear sweep, mm: by default the whole 1200 mm pallet, so one
  /// sweep covers all three parts wherever they lie. Replaces SimConfig.sweep.length_mm (the
  /// written truth/sim_config.yaml holds the length used); 0 keeps the config's.
  double sweep_length_mm = 1200.0;
  /// Chord error of the rendered tessellation of the CAD parts, mm (ReadCadRenderMesh).
  double render_deflection_mm = 0.02;

  /// Throws OptionError naming `what` and the field.
  void Check(const std::string& what = "PalletSimOptions") const;
};

/// Writes `scenes` pallet scenes (pallet_000 ...) to `out_dir` (created if missing), with truth,
/// models and records. Scene i draws its placements from its own random stream, so it does not
/// depend on the number of scenes. The SimConfig's capture switches are ignored. Throws
/// OptionError for a bad config or options (naming the field), including parts that do not fit
/// the placement region or a sweep that sees nothing; FileError when a file cannot be written.
/// `threads` <= 0 uses all cores; output is identical for any value.
SimulationReport SimulatePallets(const SimConfig& config, int scenes, const std::string& out_dir,
                                 const PalletSimOptions& options = {},
                                 const ProgressCallback& progress = {}, int threads = 0);

}  // namespace lasercell::datasets
