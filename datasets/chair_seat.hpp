#pragma once
// A parametric office-chair seat: a curved shell (rounded-square outline, domed, with a rolled
// front edge that breaks the symmetry) and a central cylindrical boss holding the 27 mm hole the
// handling robot's 3-finger gripper grips inside (Skotheim et al., Sec. I). The seat is modelled
// lying upside down, underside (with the boss) up, as it lies on the pallet to be gripped.
//
// Part frame ("seat"): origin at the centre of the outline, +z up through the boss side, +x
// towards the front edge; the shell's lowest points lie near z = 0. Units mm. The mesh is closed
// (watertight) and consistently oriented (outward normals).

#include <Eigen/Core>
#include <string>

#include "datasets/geometry.hpp"

namespace lasercell::datasets {

/// Shape parameters of the seat, mm.
struct ChairSeatOptions {
  double half_length_x_mm = 225.0;  ///< Half the outline length front-back.
  double half_width_y_mm = 225.0;   ///< Half the outline width.
  double outline_exponent = 4.0;    ///< Superellipse exponent of the outline (2 = ellipse).
  double crown_mm = 35.0;           ///< Dome rise of the shell from rim to centre.
  double front_roll_mm = 28.0;      ///< Extra drop of the front edge (the "waterfall").
  double side_lift_mm = 12.0;       ///< Extra rise of the side edges (bucket shape).
  double thickness_mm = 8.0;        ///< Shell thickness (vertical).
  double boss_offset_x_mm = -30.0;  ///< Boss axis position along x.
  double boss_radius_mm = 32.0;     ///< Boss outer radius.
  double boss_height_mm = 45.0;     ///< Boss top above the shell surface at the boss axis.
  double hole_diameter_mm = 27.0;   ///< Diameter of the gripping hole through the boss.
  int angular_steps = 192;          ///< Mesh resolution around the boss.
  int radial_steps = 40;            ///< Mesh resolution from the boss to the rim.

  /// Throws OptionError naming the field when a value is out of range.
  void Check(const std::string& what = "ChairSeatOptions") const;
};

/// The seat mesh in the part frame and its grasp reference.
struct ChairSeat {
  MeshPart part;                        ///< Closed mesh with patches (cylinders for boss and hole).
  Eigen::Vector3d hole_center_in_part;  ///< Centre of the hole's opening at the boss top, mm.
  Eigen::Vector3d hole_axis_in_part;    ///< Unit axis of the hole, pointing out of the boss.
  double boss_radius_mm = 0.0;          ///< Outer radius of the boss holding the hole.
};

/// Builds the seat.
ChairSeat MakeChairSeat(const ChairSeatOptions& options = {});

/// The physical seat the sensor sees, against its CAD model (ChairSeatOptions, what the user's
/// models/seat.stl holds): a moulded part is not its CAD. Defaults reproduce the CAD exactly.
struct SeatRenderOptions {
  int angular_steps = 0;  ///< Tessellation of the rendered seat around the boss; 0: the CAD's.
  int radial_steps = 0;   ///< Tessellation from the boss to the rim; 0: the CAD's.
  /// Saddle warp of the moulded shell, mm: every vertex moves along the part's z by
  /// warp_mm * ((x - boss_offset_x)^2 - y^2) / half_length_x^2 (a "potato chip" about the boss
  /// axis: zero value and zero slope at the hole, so the grasp frame keeps its place, and
  /// +-warp_mm near the rim's x and y extremes). |warp_mm| <= 5.
  double warp_mm = 0.0;

  /// Throws OptionError naming `what` and the field.
  void Check(const std::string& what = "SeatRenderOptions") const;
};

/// The seat as rendered: MakeChairSeat at the render tessellation, then warped. The hole's
/// centre and axis are those of the CAD (the warp vanishes there to first order).
ChairSeat MakeRenderedChairSeat(const ChairSeatOptions& cad, const SeatRenderOptions& render);

}  // namespace lasercell::datasets
