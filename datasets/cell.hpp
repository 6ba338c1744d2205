#pragma once
// The simulated work cell: where things stand and the scenes the simulator renders.
//
// Frame `cell`: floor at z = 0, +z up; the pallet's footprint is centred on the origin with its
// long side along +x. The handling robot (Nachi SC15F stand-in) stands on the floor facing the
// pallet; the vision robot (UR5) stands on a pedestal beside it. Part poses and hole centres are
// reported in `handling_base`. Units mm, rad.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "datasets/chair_seat.hpp"
#include "datasets/scene.hpp"

namespace lasercell::datasets {

/// Diffuse reflectances of the cell's surfaces at 660 nm.
struct CellAlbedo {
  double floor = 0.35;             ///< Grey concrete.
  double pallet = 0.55;            ///< Raw pine.
  double seat = 0.08;              ///< Black polypropylene (the seed's dark plastic).
  double white_plane = 0.90;       ///< Matte white calibration plane.
  double spheres = 0.75;           ///< Matte painted calibration spheres.
  double stands = 0.45;            ///< Sphere stands (anodized aluminium).
  double chessboard_light = 0.85;  ///< Light squares and border of the chessboard plate.
  double chessboard_dark = 0.04;   ///< Dark squares.
};

/// Placement of the cell's fixed items.
struct CellLayout {
  Eigen::Isometry3d cell_from_vision_base = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d cell_from_handling_base = Eigen::Isometry3d::Identity();
  double floor_size_mm = 4000.0;  ///< Edge of the square floor.
  CellAlbedo albedo;
};

/// The four calibration half spheres on cylindrical stands of different heights
/// (Skotheim et al., calibration step 3), standing on the pallet's top deck.
struct SphereTargets {
  double radius_mm = 25.0;                                    ///< Sphere (and stand) radius.
  std::vector<double> stand_heights_mm = {40, 80, 120, 160};  ///< Stand height above the deck.
  std::vector<Eigen::Vector2d> positions_xy_mm = {
      {-250, -140}, {230, -160}, {260, 150}, {-220, 170}};  ///< Stand axes in cell xy.
  int segments = 128;                                       ///< Tessellation around.
  /// Manufacturing error of each sphere's radius (true radius = radius_mm + error), mm; empty:
  /// every sphere has exactly radius_mm. The stands keep radius_mm. Records state radius_mm
  /// (the nominal, as printed on the drawing); only the truth knows the errors.
  std::vector<double> radius_errors_mm;

  /// True radius of sphere i, mm.
  double RadiusOf(std::size_t i) const {
    return radius_mm + (i < radius_errors_mm.size() ? radius_errors_mm[i] : 0.0);
  }
  /// Sphere centres in the cell frame (the stand top's centre).
  std::vector<Eigen::Vector3d> CentersInCell() const;
  /// Throws OptionError naming `what` and the field.
  void Check(const std::string& what = "spheres") const;
};

/// Seat placement drawn like Skotheim et al.'s Table I experiment.
struct SeatPlacementOptions {
  double max_shift_mm = 100.0;  ///< Uniform shift in cell x and y, +-.
  double max_tilt_deg = 25.0;   ///< Uniform tilts about cell x and y, +-.
  double max_yaw_deg = 180.0;   ///< Uniform rotation about the vertical, +-.

  /// Throws OptionError naming `what` and the field.
  void Check(const std::string& what = "seats") const;
};

/// One drawn placement.
struct SeatPlacement {
  double shift_x_mm = 0, shift_y_mm = 0;  ///< Drawn shifts.
  double tilt_x_rad = 0, tilt_y_rad = 0;  ///< Drawn tilts.
  double yaw_rad = 0;                     ///< Drawn yaw.
  /// cell_from_part = Translation(shift_x, shift_y, lift) * RotY(tilt_y) * RotX(tilt_x) *
  /// RotZ(yaw), with `lift` so that the seat's lowest vertex touches the pallet's top deck.
  Eigen::Isometry3d cell_from_part = Eigen::Isometry3d::Identity();
};

/// Draws placement `index` from its own random stream of `seed` (independent of the others).
SeatPlacement DrawSeatPlacement(const SeatPlacementOptions& options, const ChairSeat& seat,
                                std::uint64_t seed, int index);

/// Builders of the scenes the simulator renders (all committed).
Scene MakeSeatScene(const CellLayout& layout, const ChairSeat& seat,
                    const Eigen::Isometry3d& cell_from_part);
/// A matte white plate (800 x 600 mm by default) whose top face lies at `height_mm`.
Scene MakePlaneScene(const CellLayout& layout, double height_mm,
                     const Eigen::Vector2d& size_mm = {800, 600});
Scene MakeSphereScene(const CellLayout& layout, const SphereTargets& spheres);
/// Chessboard plate: `squares` (x, y) of `square_mm`, 5 mm thick, a 20 mm light border;
/// `cell_from_board` places the target frame of camera_images.hpp (origin at the pattern's outer
/// corner, pattern in its xy plane at z = 0, +z out of the printed face).
Scene MakeChessboardScene(const CellLayout& layout, const Eigen::Isometry3d& cell_from_board,
                          const std::array<int, 2>& squares, double square_mm);

}  // namespace lasercell::datasets
