#pragma once
// The pallet scene of Skotheim et al.'s Fig. 4: a chair seat, a seat back and an armrest lying
// side by side on the EUR pallet, seen in one linear sweep.
//
// Each part lies in one of its stable poses on the deck (part_rest.hpp, the deck taken as the
// plane z = kPalletHeightMm), turned by a random yaw about the vertical and shifted to a random
// position: cell_from_part = T(x, y, deck) * RotZ(yaw) * plane_from_part(stable pose). Positions
// are drawn so that every footprint (the convex hull of the posed mesh seen from above) stays
// inside the placement region, the footprints keep min_gap_mm apart, and every contact vertex
// rests on a deck board rather than over a gap between boards. Units mm, rad; frame `cell`.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "datasets/cell.hpp"
#include "datasets/chair_parts.hpp"
#include "datasets/geometry.hpp"
#include "datasets/part_rest.hpp"
#include "datasets/scene.hpp"

namespace lasercell::datasets {

/// A part ready for the pallet scene: what the sensor sees of it and how it can lie.
struct PalletPart {
  std::string name;      ///< "seat", "back", "armrest": the instance frames are <name>_<scene>.
  MeshPart geometry;     ///< Rendered surface in the part frame (closed, outward), mm.
  double albedo = 0.08;  ///< Diffuse reflectance at 660 nm.
  std::vector<PartGrasp> grasps;          ///< Grasp frames in the part frame.
  std::vector<RestingPose> stable_poses;  ///< At least one.
  /// Per stable pose: the footprint (counter-clockwise convex hull of the posed mesh in the
  /// plane's xy) and the contact points' xy, both in the plane frame before yaw and shift.
  std::vector<std::vector<Eigen::Vector2d>> footprints, contacts_xy;
};

/// Builds a PalletPart from its rendered geometry: checks that the mesh is closed and outward
/// (InternalError naming the part otherwise: the renderer would see into it and its centre of
/// mass would be wrong) and settles it from each start orientation (SettleOnPlane).
PalletPart MakePalletPart(const std::string& name, MeshPart geometry, double albedo,
                          std::vector<PartGrasp> grasps,
                          const std::vector<Eigen::Matrix3d>& start_orientations);

/// Where the parts may go.
struct PalletPlacementOptions {
  /// Half extents of the placement region on the deck, centred on the pallet (cell xy), mm: the
  /// default is the pallet less 20 mm in x, and in y the +-290 mm the sensor's field covers at
  /// the deck (the 45 deg fan and the camera's view at the default stand-off).
  Eigen::Vector2d region_half_size_mm = {580.0, 290.0};
  double min_gap_mm = 15.0;   ///< Smallest distance between two footprints (>= 0).
  int max_attempts = 100000;  ///< Placement draws before giving up (>= 1).
  /// Keep every contact vertex on a deck board (at least this far from a board's edge, mm);
  /// negative: allow contacts over the gaps between boards.
  double board_support_margin_mm = 2.0;

  /// Throws OptionError naming `what` and the field.
  void Check(const std::string& what = "PalletPlacementOptions") const;
};

/// Where one part of a scene lies.
struct PalletPlacement {
  std::string part;                                       ///< PalletPart::name.
  std::string frame;                                      ///< Instance frame, e.g. "back_003".
  int stable_pose = 0;                                    ///< Index into stable_poses.
  double yaw_rad = 0;                                     ///< Rotation about cell z.
  Eigen::Vector2d shift_xy_mm = Eigen::Vector2d::Zero();  ///< Translation in cell xy.
  Eigen::Isometry3d cell_from_part = Eigen::Isometry3d::Identity();  ///< The pose.
  std::vector<Eigen::Vector2d> footprint;  ///< Posed footprint in cell xy (ccw).
};

/// Draws scene `index` from its own random stream of `seed`: every part in order (largest
/// footprint first gives the best odds), a stable pose, yaw and shift each. Frames are
/// "<part>_<index, 3 digits>". Throws OptionError naming the options when no placement is found
/// within max_attempts (the parts do not fit the region).
std::vector<PalletPlacement> DrawPalletPlacements(const PalletPlacementOptions& options,
                                                  const std::vector<PalletPart>& parts,
                                                  std::uint64_t seed, int index);

/// The committed scene: floor, pallet and every placed part (objects named by their frames).
Scene MakePalletScene(const CellLayout& layout, const std::vector<PalletPart>& parts,
                      const std::vector<PalletPlacement>& placements);

}  // namespace lasercell::datasets
