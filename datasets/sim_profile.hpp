#pragma once
// Named simulator profiles: the base a SIM.yaml builds on (`profile: realistic`).
//
//  - ideal: the simulator's historical defaults (SimConfig{}): white Gaussian row noise on the
//    exact projection, no speckle, no reflections, exact timestamps and joints, exact DH
//    lengths, spheres exactly their nominal radius, the rendered seat is its CAD mesh. A
//    regression check: errors there are the algorithms' own.
//  - realistic: what a real cell adds, each effect at a level taken from a measurement or a
//    data sheet (the values and their sources are listed in datasets/SIMULATOR.md, "Profiles"):
//    laser speckle and specular multi-peak reflections on the seat's plastic and the cell,
//    random dropouts on top of those of dark and grazing surfaces, timestamp and encoder noise,
//    DH length errors of the vision robot, sphere radii off their nominal by a manufacturing
//    tolerance, noisier and blurrier camera images with detector-level corner noise as measured
//    on real views, and a seat whose CAD (a coarse tessellation) differs from the rendered part
//    (a fine tessellation of the same shell, warped). The accuracy benchmarks default to it.

#include <string>

#include "datasets/sim_config.hpp"

namespace lasercell::datasets {

enum class SimProfile { kIdeal, kRealistic };

/// "ideal" or "realistic"; throws OptionError listing the names otherwise.
SimProfile ParseSimProfile(const std::string& name);
/// The profile's name.
std::string SimProfileName(SimProfile profile);

/// The profile's configuration (SimConfig::profile set to its name).
SimConfig SimConfigForProfile(SimProfile profile);
/// Same, by name; throws OptionError for an unknown name.
SimConfig SimConfigForProfile(const std::string& name);

}  // namespace lasercell::datasets
