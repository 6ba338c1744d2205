#include "datasets/sim_profile.hpp"

#include "core/error.hpp"

namespace lasercell::datasets {

SimProfile ParseSimProfile(const std::string& name) {
  if (name == "ideal") return SimProfile::kIdeal;
  if (name == "realistic") return SimProfile::kRealistic;
  throw OptionError("unknown simulation profile '" + name + "' (use ideal or realistic)");
}

std::string SimProfileName(SimProfile profile) {
  return profile == SimProfile::kIdeal ? "ideal" : "realistic";
}

SimConfig SimConfigForProfile(SimProfile profile) {
  SimConfig c;
  c.profile = SimProfileName(profile);
  if (profile == SimProfile::kIdeal) return c;
  // Laser: speckle of a matt plastic or metal surface, spatially correlated along the line
  // (Goodman, "Speckle Phenomena in Optics": pixel-averaged contrast ~0.3); specular ghosts
  // from the floor, the pallet and the seat's plastic; random peak losses on top of those of
  // dark and grazing surfaces (min_intensity with the speckled intensity).
  c.render.speckle_sigma_px = 0.08;
  c.render.speckle_correlation_px = 3.0;
  c.render.speckle_intensity_sigma = 0.3;
  c.render.reflection_probability = 0.3;
  c.render.reflection_intensity = 0.3;
  c.render.reflective_objects = {"floor", "pallet", "seat"};
  c.render.dropout_probability = 0.01;
  // Timing: exposure jitter 20 us (the default), timestamp noise of a software-stamped stream
  // 50 us, encoder noise 2e-5 rad (one count of an 18-bit absolute encoder is 2.4e-5 rad).
  c.timing.timestamp_noise_s = 50e-6;
  c.timing.joint_noise_rad = 2e-5;
  // The vision robot: joint offsets N(0, 0.1 deg) (the default) and DH length errors N(0, 0.2
  // mm) per a_i and d_i (a factory-calibrated arm's residual).
  c.dh_length_sigma_mm = 0.2;
  // Calibration spheres turned to +-0.05 mm on the radius; touches N(0, 0.05 mm) per axis.
  c.sphere_radius_tolerance_mm = 0.05;
  c.touches.sigma_mm = 0.05;
  // Camera images: more read noise and blur than the ideal renderer (detected corners 0.03 px
  // RMS off); synthesized detections carry 0.15 px per coordinate, the real views' level (0.18 px
  // RMS reprojection after intrinsics, lens-model and board errors included).
  c.images.noise_sigma = 4.0;
  c.images.blur_sigma_px = 1.0;
  c.corner_sigma_px = 0.15;
  // The seat: the user's CAD is a coarse tessellation; the part the sensor sees is a fine
  // tessellation of the same shell with a 0.5 mm saddle warp (a moulded part).
  c.seat_shape.angular_steps = 96;
  c.seat_shape.radial_steps = 20;
  c.seat_render.angular_steps = 384;
  c.seat_render.radial_steps = 80;
  c.seat_render.warp_mm = 0.5;
  return c;
}

SimConfig SimConfigForProfile(const std::string& name) {
  return SimConfigForProfile(ParseSimProfile(name));
}

}  // namespace lasercell::datasets
