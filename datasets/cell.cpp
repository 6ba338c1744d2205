#include "datasets/cell.hpp"

#include <cmath>
#include <limits>
#include <numbers>

#include "core/error.hpp"
#include "datasets/geometry.hpp"
#include "datasets/rng.hpp"

namespace lasercell::datasets {

namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;
// Random streams of the simulator (see rng.hpp); placements use kPlacementStream + index.
constexpr std::uint64_t kPlacementStream = 0x5EA7'0000'0000ull;

void AddFloor(Scene& scene, const CellLayout& layout) {
  Material m;
  m.albedo = layout.albedo.floor;
  scene.Add(
      {"floor",
       MakeRectangle(Eigen::Isometry3d::Identity(), layout.floor_size_mm, layout.floor_size_mm),
       m});
}

void AddPallet(Scene& scene, const CellLayout& layout) {
  Material m;
  m.albedo = layout.albedo.pallet;
  scene.Add({"pallet", MakePallet(), m});
}

}  // namespace

std::vector<Eigen::Vector3d> SphereTargets::CentersInCell() const {
  std::vector<Eigen::Vector3d> centers;
  for (std::size_t i = 0; i < positions_xy_mm.size(); ++i) {
    centers.emplace_back(positions_xy_mm[i].x(), positions_xy_mm[i].y(),
                         kPalletHeightMm + stand_heights_mm[i]);
  }
  return centers;
}

void SphereTargets::Check(const std::string& what) const {
  if (!(radius_mm > 0) || radius_mm > 200) {
    throw OptionError(what + ".radius_mm must be in (0, 200] (got " + std::to_string(radius_mm) +
                      ")");
  }
  if (stand_heights_mm.size() != positions_xy_mm.size() || stand_heights_mm.size() < 3) {
    throw OptionError(what + ".stand_heights_mm and " + what +
                      ".positions_xy_mm must list the same number (>= 3) of spheres (got " +
                      std::to_string(stand_heights_mm.size()) + " and " +
                      std::to_string(positions_xy_mm.size()) + ")");
  }
  if (!radius_errors_mm.empty() && radius_errors_mm.size() != stand_heights_mm.size()) {
    throw OptionError(what + ".radius_errors_mm must be empty or list one error per sphere (got " +
                      std::to_string(radius_errors_mm.size()) + " for " +
                      std::to_string(stand_heights_mm.size()) + " spheres)");
  }
  for (std::size_t i = 0; i < radius_errors_mm.size(); ++i) {
    if (!(std::abs(radius_errors_mm[i]) <= 0.1 * radius_mm)) {
      throw OptionError(what + ".radius_errors_mm[" + std::to_string(i) +
                        "] must be within 10 % of radius_mm (got " +
                        std::to_string(radius_errors_mm[i]) + ")");
    }
  }
  for (std::size_t i = 0; i < stand_heights_mm.size(); ++i) {
    if (!(stand_heights_mm[i] > 0) || !std::isfinite(stand_heights_mm[i])) {
      throw OptionError(what + ".stand_heights_mm[" + std::to_string(i) +
                        "] must be positive (got " + std::to_string(stand_heights_mm[i]) + ")");
    }
    if (!positions_xy_mm[i].allFinite() || std::abs(positions_xy_mm[i].x()) > 600 - radius_mm ||
        std::abs(positions_xy_mm[i].y()) > 400 - radius_mm) {
      throw OptionError(what + ".positions_xy_mm[" + std::to_string(i) +
                        "] must stand on the pallet (|x| <= 600 - r, |y| <= 400 - r)");
    }
    for (std::size_t j = 0; j < i; ++j) {
      if ((positions_xy_mm[i] - positions_xy_mm[j]).norm() < 2.5 * radius_mm) {
        throw OptionError(what + ".positions_xy_mm[" + std::to_string(i) + "] and [" +
                          std::to_string(j) + "] are closer than 2.5 radii");
      }
    }
  }
  if (segments < 16) throw OptionError(what + ".segments must be >= 16");
}

void SeatPlacementOptions::Check(const std::string& what) const {
  if (!(max_shift_mm >= 0) || max_shift_mm > 300) {
    throw OptionError(what + ".max_shift_mm must be in [0, 300] (got " +
                      std::to_string(max_shift_mm) + ")");
  }
  if (!(max_tilt_deg >= 0) || max_tilt_deg > 60) {
    throw OptionError(what + ".max_tilt_deg must be in [0, 60] (got " +
                      std::to_string(max_tilt_deg) + ")");
  }
  if (!(max_yaw_deg >= 0) || max_yaw_deg > 180) {
    throw OptionError(what + ".max_yaw_deg must be in [0, 180] (got " +
                      std::to_string(max_yaw_deg) + ")");
  }
}

SeatPlacement DrawSeatPlacement(const SeatPlacementOptions& options, const ChairSeat& seat,
                                std::uint64_t seed, int index) {
  options.Check();
  Rng rng(StreamSeed(seed, kPlacementStream + static_cast<std::uint64_t>(index)));
  SeatPlacement p;
  p.shift_x_mm = rng.Uniform(-options.max_shift_mm, options.max_shift_mm);
  p.shift_y_mm = rng.Uniform(-options.max_shift_mm, options.max_shift_mm);
  p.tilt_x_rad = rng.Uniform(-options.max_tilt_deg, options.max_tilt_deg) * kDegToRad;
  p.tilt_y_rad = rng.Uniform(-options.max_tilt_deg, options.max_tilt_deg) * kDegToRad;
  p.yaw_rad = rng.Uniform(-options.max_yaw_deg, options.max_yaw_deg) * kDegToRad;
  const Eigen::Matrix3d rotation = (Eigen::AngleAxisd(p.tilt_y_rad, Eigen::Vector3d::UnitY()) *
                                    Eigen::AngleAxisd(p.tilt_x_rad, Eigen::Vector3d::UnitX()) *
                                    Eigen::AngleAxisd(p.yaw_rad, Eigen::Vector3d::UnitZ()))
                                       .toRotationMatrix();
  double min_z = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector3d& v : seat.part.mesh.vertices.positions) {
    min_z = std::min(min_z, (rotation * v).z());
  }
  p.cell_from_part.linear() = rotation;
  p.cell_from_part.translation() =
      Eigen::Vector3d(p.shift_x_mm, p.shift_y_mm, kPalletHeightMm - min_z);
  return p;
}

Scene MakeSeatScene(const CellLayout& layout, const ChairSeat& seat,
                    const Eigen::Isometry3d& cell_from_part) {
  Scene scene;
  AddFloor(scene, layout);
  AddPallet(scene, layout);
  MeshPart part = seat.part;
  part.Transform(cell_from_part);
  Material m;
  m.albedo = layout.albedo.seat;
  scene.Add({"seat", std::move(part), m});
  scene.Commit();
  return scene;
}

Scene MakePlaneScene(const CellLayout& layout, double height_mm, const Eigen::Vector2d& size_mm) {
  Scene scene;
  AddFloor(scene, layout);
  Material m;
  m.albedo = layout.albedo.white_plane;
  const double thickness = 10.0;
  scene.Add({"white_plane",
             MakeBox(Eigen::Isometry3d(Eigen::Translation3d(0, 0, height_mm - thickness / 2)),
                     {size_mm.x(), size_mm.y(), thickness}),
             m});
  scene.Commit();
  return scene;
}

Scene MakeSphereScene(const CellLayout& layout, const SphereTargets& spheres) {
  spheres.Check();
  Scene scene;
  AddFloor(scene, layout);
  AddPallet(scene, layout);
  const std::vector<Eigen::Vector3d> centers = spheres.CentersInCell();
  for (std::size_t i = 0; i < centers.size(); ++i) {
    const Eigen::Vector3d base(centers[i].x(), centers[i].y(), kPalletHeightMm);
    Material stand;
    stand.albedo = layout.albedo.stands;
    scene.Add({"stand_" + std::to_string(i),
               MakeCylinder(Eigen::Isometry3d(Eigen::Translation3d(base)), spheres.radius_mm,
                            spheres.stand_heights_mm[i], spheres.segments, false, false),
               stand});
    Material ball;
    ball.albedo = layout.albedo.spheres;
    scene.Add({"sphere_" + std::to_string(i),
               MakeHemisphere(Eigen::Isometry3d(Eigen::Translation3d(centers[i])),
                              spheres.RadiusOf(i), spheres.segments, spheres.segments / 4),
               ball});
  }
  scene.Commit();
  return scene;
}

Scene MakeChessboardScene(const CellLayout& layout, const Eigen::Isometry3d& cell_from_board,
                          const std::array<int, 2>& squares, double square_mm) {
  Scene scene;
  AddFloor(scene, layout);
  const double border = 20.0;
  const double thickness = 5.0;
  const Eigen::Vector3d size(squares[0] * square_mm + 2 * border,
                             squares[1] * square_mm + 2 * border, thickness);
  const Eigen::Vector3d center(squares[0] * square_mm / 2, squares[1] * square_mm / 2,
                               -thickness / 2);
  Material m;
  m.albedo = layout.albedo.chessboard_light;
  m.dark_albedo = layout.albedo.chessboard_dark;
  m.squares_x = squares[0];
  m.squares_y = squares[1];
  m.square_mm = square_mm;
  m.pattern_from_scene = cell_from_board.inverse();
  scene.Add({"chessboard", MakeBox(cell_from_board * Eigen::Translation3d(center), size), m});
  scene.Commit();
  return scene;
}

}  // namespace lasercell::datasets
