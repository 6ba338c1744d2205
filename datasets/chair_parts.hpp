#pragma once
// The other two parts of the reference cell (Skotheim et al., Sec. I and Fig. 4: seat, seat back
// and armrest on a pallet) as CAD solids: boxes and cylinders combined by union and difference
// (localize/cad_export.hpp), written as STEP so the simulator exercises the CAD import path. Like
// the seat (chair_seat.hpp) each part has a gripping hole in a boss for the 3-finger concentric
// gripper, and no symmetry that would make a pose ambiguous.
//
// Conventions: millimetres and radians, everything in the part's own frame. A grasp frame
// `part_from_grasp` has its origin at the centre of the hole's opening, +z along the hole axis
// pointing out of the material (the gripper approaches along -z), +x along the part's +x.
//
// Seat back (frame "back", as mounted on a chair): x across the width, y up the backrest, z out
// of its rear face. A centre panel (z from 0 = front face to thickness) with two side wings bent
// towards the front (-z), a lumbar ridge across the rear, and two mounting bosses on the rear
// near the bottom edge: the larger holds the gripping hole. The wings differ in width, bend and
// height (the right one is shorter, clear of the panel's top and bottom edges): a back with
// mirror-image wings would look the same turned 180 deg about its normal but for the small
// ridge and bosses, and its extruded panel would let a fit slide along y. It lies on the pallet
// front face down, on the wings' outer edges, bosses up.
//
// Armrest (frame "armrest", as mounted): x forward along the bar, z up the post, y outwards. A
// vertical post (bottom at z = 0) carrying a horizontal bar with a pad on top, the bar running
// mostly forward of the post (an L); a boss on the post's outer (+y) face near its bottom holds
// the gripping hole, through boss and post along y, and a roof-shaped rib above it slopes
// across x. It lies on the pallet on its inner side (the pad's and the post's -y faces), boss
// up.
//
// Sloped faces: the sweep's laser plane is vertical, so vertical walls are lit at grazing
// incidence or not at all, and a part made of upright boxes lying flat shows mostly level faces
// that leave ICP free to slide along them. The 45 deg ridge (back, across y) and rib (armrest,
// across x) give the fit a face it can see in each of those directions.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "datasets/chair_seat.hpp"
#include "datasets/geometry.hpp"
#include "localize/cad_export.hpp"
#include "localize/part.hpp"

namespace lasercell::datasets {

/// A named grasp frame of a part (see the file comment for its axes).
struct PartGrasp {
  std::string name;                                                   ///< e.g. "boss_hole".
  Eigen::Isometry3d part_from_grasp = Eigen::Isometry3d::Identity();  ///< mm.
  double hole_diameter_mm = 0;  ///< Diameter of the hole the fingers grip inside.
  double hole_depth_mm = 0;     ///< Depth of the hole below the grasp origin (along -z).
};

/// A part of the simulated cell built as a CAD solid.
struct CadChairPart {
  std::string name;               ///< "back" or "armrest": file and frame prefix.
  localize::CadSolid solid;       ///< In the part frame, mm.
  std::vector<PartGrasp> grasps;  ///< At least one.
  /// Voxel size of the part's PPF model in its part file, mm; 0 keeps the library's relative
  /// default (Skotheim et al. IV-C: 20 mm for seat and back, 10 mm for the armrest).
  double ppf_sampling_step_mm = 0.0;
  /// Orientations to lay the part down from (cell_from_part rotations, z up), one per stable
  /// pose it is meant to rest in; the pallet scene settles each onto the deck (part_rest.hpp).
  std::vector<Eigen::Matrix3d> rest_orientations;
};

/// Shape of the seat back, mm and deg (frame: see the file comment).
struct SeatBackOptions {
  double panel_width_mm = 220.0;       ///< Width of the flat centre panel along x.
  double height_mm = 340.0;            ///< Height of the panel (and the left wing) along y.
  double thickness_mm = 12.0;          ///< Thickness of the panel and the wings.
  double left_wing_width_mm = 90.0;    ///< Width of the left (-x) wing, along the wing.
  double left_wing_angle_deg = 20.0;   ///< Bend of the left wing towards the front (-z), (0, 60].
  double right_wing_width_mm = 70.0;   ///< Width of the right (+x) wing, along the wing.
  double right_wing_angle_deg = 32.0;  ///< Bend of the right wing towards the front, (0, 60].
  /// Extent of the right wing along y, [from, to], inside [0, height_mm].
  Eigen::Vector2d right_wing_y_mm = {30.0, 300.0};
  /// Lumbar ridge across the rear: a square bar along x turned 45 deg about x, its axis on the
  /// rear face (a roof of two 45 deg slopes, 2 x ridge_depth_mm wide): centre height along y.
  double ridge_center_y_mm = 240;
  double ridge_depth_mm = 10.0;  ///< Rise of the ridge's apex above the rear face (< thickness).
  /// Gripping boss on the rear face: axis position (x, y), radius, rise above the rear face.
  Eigen::Vector2d grip_boss_xy_mm = {-50.0, 85.0};
  double grip_boss_radius_mm = 24.0;    ///< Radius of the gripping boss.
  double grip_boss_height_mm = 30.0;    ///< Rise of the gripping boss above the rear face.
  double grip_hole_diameter_mm = 27.0;  ///< Gripping hole (the seat's 27 mm, Skotheim Sec. I).
  double grip_hole_depth_mm = 25.0;     ///< Blind hole depth from the boss top.
  /// Second, smaller mounting boss: axis position (x, y), radius, rise, hole.
  Eigen::Vector2d mount_boss_xy_mm = {65.0, 55.0};
  double mount_boss_radius_mm = 14.0;    ///< Radius of the mounting boss.
  double mount_boss_height_mm = 20.0;    ///< Rise of the mounting boss above the rear face.
  double mount_hole_diameter_mm = 10.0;  ///< Mounting hole diameter.
  double mount_hole_depth_mm = 15.0;     ///< Mounting hole depth from the boss top.

  /// Throws OptionError naming `what` and the field when a value is out of range or the
  /// features do not fit on the panel.
  void Check(const std::string& what = "SeatBackOptions") const;
};

/// Shape of the armrest, mm (frame: see the file comment).
struct ArmrestOptions {
  double post_width_x_mm = 50.0;   ///< Post extent along x (from x = 0).
  double post_height_mm = 220.0;   ///< Post height along z (from z = 0; it runs into the bar).
  double bar_length_mm = 270.0;    ///< Bar length along x.
  double bar_back_mm = 40.0;       ///< How far the bar reaches behind the post (-x).
  double bar_width_y_mm = 50.0;    ///< Bar width along y (from y = 0).
  double bar_thickness_mm = 25.0;  ///< Bar thickness along z.
  double post_inset_mm = 5.0;      ///< The post is this much narrower than the bar on each side.
  double pad_length_mm = 245.0;    ///< Pad length along x.
  double pad_front_inset_mm = 15;  ///< The pad ends this far behind the bar's front end.
  double pad_overhang_mm = 5.0;    ///< The pad is this much wider than the bar on each side.
  double pad_thickness_mm = 15.0;  ///< Pad rise above the bar's top.
  double boss_center_z_mm = 40.0;  ///< Gripping boss axis height on the post's outer face.
  double boss_radius_mm = 22.0;    ///< Gripping boss radius (must fit on the post's face).
  double boss_height_mm = 12.0;    ///< Boss rise above the post's outer face.
  double hole_diameter_mm = 20.0;  ///< Gripping hole through boss and post.
  /// Rib on the post's outer face: a square bar along z turned 45 deg about z, its axis on the
  /// face (a roof of two 45 deg slopes across x): rise of its apex above the face.
  double rib_depth_mm = 10.0;
  double rib_center_z_mm = 140.0;  ///< Centre of the rib along z.
  double rib_length_mm = 120.0;    ///< Rib length along z.

  /// Throws OptionError naming `what` and the field when a value is out of range or the
  /// features do not fit.
  void Check(const std::string& what = "ArmrestOptions") const;
};

/// Builds the seat back ("back"; grasp "boss_hole"). Check()s the options.
CadChairPart MakeSeatBack(const SeatBackOptions& options = {});
/// Builds the armrest ("armrest"; grasp "post_hole"). Check()s the options.
CadChairPart MakeArmrest(const ArmrestOptions& options = {});

/// The seat's grasp ("hole"): origin at the centre of the hole's opening, z along the hole axis
/// out of the boss (the rotation taking +z to that axis), as in the seat's part file.
PartGrasp SeatHoleGrasp(const ChairSeat& seat);

/// The seat's part file (localize/part.hpp): model "seat.stl" in mm beside the part file, grasp
/// "hole" (SeatHoleGrasp); no stable poses (the seat scenes tilt it by up to 25 deg). `seat` is
/// the CAD; when the part the sensor sees (`rendered`) differs from it, the file states the
/// form deviation an inspection of it against the CAD would report: the RMS distance of its
/// mesh's vertices from the CAD surface (MeasureMeshDeviation), rounded up to 0.01 mm, and the
/// default correlation length (the simulator does not measure one).
localize::PartDefinition SeatPartDefinition(const ChairSeat& seat,
                                            const ChairSeat* rendered = nullptr);

/// A CAD part's part file: model "<name>.step" beside the part file (no units: the STEP file
/// carries them), its grasps, and the up axis of each rest orientation as a stable pose (the
/// default 30 deg of tilt covers the settling, part_rest.hpp).
localize::PartDefinition CadPartDefinition(const CadChairPart& part);

/// The rendered geometry of a CAD part: its file read back by localize::ReadCadModel at a fine
/// tessellation (chord error `linear_deflection_mm`, 0.05 rad between neighbouring normals), as
/// one free-form patch (the renderer intersects its triangles in double precision). This is
/// deliberately not the sampling a localization job builds its model from (1 mm samples of the
/// same file), so a test of the job does not match the renderer's own points. Throws what
/// ReadCadModel throws.
MeshPart ReadCadRenderMesh(const std::string& path, double linear_deflection_mm = 0.02);

/// True when `p_in_part` lies inside `solid` evaluated as its constructive definition (each
/// primitive added or subtracted in order), exactly. Points on an added primitive's boundary
/// count as inside it, points on a subtracted one's as removed.
bool SolidContains(const localize::CadSolid& solid, const Eigen::Vector3d& p_in_part);

}  // namespace lasercell::datasets
