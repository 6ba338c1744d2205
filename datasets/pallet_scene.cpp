#include "datasets/pallet_scene.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <utility>

#include "core/error.hpp"
#include "datasets/rng.hpp"

namespace lasercell::datasets {

namespace {

// Random stream of pallet scene `index` (rng.hpp StreamSeed): kPalletStream + index.
constexpr std::uint64_t kPalletStream = 0x9A11'E700'0000ull;
// Draws per part before the whole scene is drawn again (a crowded start blocks later parts).
constexpr int kDrawsPerPart = 64;
constexpr double kPalletHalfX = 600.0;

std::vector<Eigen::Vector2d> Posed(const std::vector<Eigen::Vector2d>& pts, double yaw,
                                   const Eigen::Vector2d& shift) {
  const Eigen::Rotation2Dd r(yaw);
  std::vector<Eigen::Vector2d> out;
  out.reserve(pts.size());
  for (const Eigen::Vector2d& p : pts) out.push_back(r * p + shift);
  return out;
}

bool OnBoards(const std::vector<Eigen::Vector2d>& contacts, double margin) {
  if (margin < 0) return true;
  static const std::vector<Eigen::Vector2d> boards = PalletDeckBoards();
  for (const Eigen::Vector2d& c : contacts) {
    if (std::abs(c.x()) > kPalletHalfX - margin) return false;
    bool on = false;
    for (const Eigen::Vector2d& b : boards)
      on = on || (c.y() >= b[0] + margin && c.y() <= b[1] - margin);
    if (!on) return false;
  }
  return true;
}

// One draw of part `part`: stable pose, yaw, then a shift that keeps its footprint in the region.
// Returns false when the footprint at that yaw does not fit the region.
bool DrawOne(const PalletPlacementOptions& o, const PalletPart& part, Rng& rng,
             PalletPlacement& out, std::vector<Eigen::Vector2d>& contacts) {
  const int n = static_cast<int>(part.stable_poses.size());
  out.stable_pose = std::min(n - 1, static_cast<int>(rng.Uniform() * n));
  out.yaw_rad = rng.Uniform(-std::numbers::pi, std::numbers::pi);
  const std::vector<Eigen::Vector2d> turned =
      Posed(part.footprints[out.stable_pose], out.yaw_rad, Eigen::Vector2d::Zero());
  Eigen::Vector2d lo = turned.front(), hi = turned.front();
  for (const Eigen::Vector2d& p : turned) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const Eigen::Vector2d shift_lo = -o.region_half_size_mm - lo;
  const Eigen::Vector2d shift_hi = o.region_half_size_mm - hi;
  const double sx = rng.Uniform(), sy = rng.Uniform();
  if ((shift_hi.array() < shift_lo.array()).any()) return false;
  out.shift_xy_mm = Eigen::Vector2d(shift_lo.x() + sx * (shift_hi.x() - shift_lo.x()),
                                    shift_lo.y() + sy * (shift_hi.y() - shift_lo.y()));
  out.footprint = Posed(turned, 0.0, out.shift_xy_mm);
  contacts = Posed(part.contacts_xy[out.stable_pose], out.yaw_rad, out.shift_xy_mm);
  return true;
}

}  // namespace

PalletPart MakePalletPart(const std::string& name, MeshPart geometry, double albedo,
                          std::vector<PartGrasp> grasps,
                          const std::vector<Eigen::Matrix3d>& start_orientations) {
  const MeshSolidCheck check = CheckMeshSolid(geometry.mesh);
  if (!check.ClosedAndOutward()) {
    throw InternalError("pallet part '" + name +
                        "': the rendered mesh is not closed and outward (" +
                        std::to_string(check.boundary_edges) + " boundary and " +
                        std::to_string(check.inconsistent_edges) + " inconsistent edges, volume " +
                        std::to_string(check.volume_mm3) + " mm^3)");
  }
  if (start_orientations.empty()) {
    throw InputError("pallet part '" + name + "' has no start orientation to rest in");
  }
  PalletPart part;
  part.name = name;
  part.albedo = albedo;
  part.grasps = std::move(grasps);
  const std::vector<Eigen::Vector3d>& v = geometry.mesh.vertices.positions;
  for (const Eigen::Matrix3d& start : start_orientations) {
    RestingPose rest = SettleOnPlane(v, check.center_of_mass, start);
    std::vector<Eigen::Vector2d> xy;
    xy.reserve(v.size());
    for (const Eigen::Vector3d& p : v) xy.push_back((rest.plane_from_part * p).head<2>());
    part.footprints.push_back(ConvexHull2d(std::move(xy)));
    std::vector<Eigen::Vector2d> contacts;
    for (const Eigen::Vector3d& c : rest.contacts_in_part) {
      contacts.push_back((rest.plane_from_part * c).head<2>());
    }
    part.contacts_xy.push_back(std::move(contacts));
    part.stable_poses.push_back(std::move(rest));
  }
  part.geometry = std::move(geometry);
  return part;
}

void PalletPlacementOptions::Check(const std::string& what) const {
  if (!region_half_size_mm.allFinite() || !(region_half_size_mm.x() > 0) ||
      !(region_half_size_mm.y() > 0) || region_half_size_mm.x() > 600 ||
      region_half_size_mm.y() > 400) {
    throw OptionError(what +
                      ".region_half_size_mm must be positive and inside the 1200 x 800 mm "
                      "pallet (x <= 600, y <= 400)");
  }
  if (!(min_gap_mm >= 0) || !std::isfinite(min_gap_mm)) {
    throw OptionError(what + ".min_gap_mm must be >= 0 (mm), got " + std::to_string(min_gap_mm));
  }
  if (max_attempts < 1) {
    throw OptionError(what + ".max_attempts must be >= 1, got " + std::to_string(max_attempts));
  }
  if (!std::isfinite(board_support_margin_mm) || board_support_margin_mm > 40) {
    throw OptionError(what + ".board_support_margin_mm must be finite and <= 40 mm");
  }
}

std::vector<PalletPlacement> DrawPalletPlacements(const PalletPlacementOptions& options,
                                                  const std::vector<PalletPart>& parts,
                                                  std::uint64_t seed, int index) {
  options.Check();
  for (const PalletPart& p : parts) {
    LASERCELL_CHECK(!p.stable_poses.empty() && p.footprints.size() == p.stable_poses.size() &&
                        p.contacts_xy.size() == p.stable_poses.size(),
                    "pallet part without stable poses");
  }
  Rng rng(StreamSeed(seed, kPalletStream + static_cast<std::uint64_t>(index)));
  char suffix[16];
  std::snprintf(suffix, sizeof(suffix), "_%03d", index);
  int attempts = 0;
  while (attempts < options.max_attempts) {
    std::vector<PalletPlacement> placed;
    for (const PalletPart& part : parts) {
      bool done = false;
      for (int k = 0; k < kDrawsPerPart && attempts < options.max_attempts && !done; ++k) {
        ++attempts;
        PalletPlacement p;
        std::vector<Eigen::Vector2d> contacts;
        if (!DrawOne(options, part, rng, p, contacts)) continue;
        if (!OnBoards(contacts, options.board_support_margin_mm)) continue;
        bool clear = true;
        for (const PalletPlacement& q : placed) {
          clear = clear && !ConvexPolygonsCloserThan(p.footprint, q.footprint, options.min_gap_mm);
        }
        if (!clear) continue;
        p.part = part.name;
        p.frame = part.name + suffix;
        const Eigen::Isometry3d plane_from_part = part.stable_poses[p.stable_pose].plane_from_part;
        p.cell_from_part =
            Eigen::Translation3d(p.shift_xy_mm.x(), p.shift_xy_mm.y(), kPalletHeightMm) *
            Eigen::AngleAxisd(p.yaw_rad, Eigen::Vector3d::UnitZ()) * plane_from_part;
        placed.push_back(std::move(p));
        done = true;
      }
      if (!done) break;
    }
    if (placed.size() == parts.size()) return placed;
  }
  throw OptionError("pallet scene " + std::to_string(index) + ": no placement of the " +
                    std::to_string(parts.size()) + " parts within " +
                    std::to_string(options.max_attempts) +
                    " draws keeps them apart inside the region; enlarge "
                    "PalletPlacementOptions.region_half_size_mm or lower min_gap_mm");
}

Scene MakePalletScene(const CellLayout& layout, const std::vector<PalletPart>& parts,
                      const std::vector<PalletPlacement>& placements) {
  Scene scene;
  Material floor;
  floor.albedo = layout.albedo.floor;
  scene.Add(
      {"floor",
       MakeRectangle(Eigen::Isometry3d::Identity(), layout.floor_size_mm, layout.floor_size_mm),
       floor});
  Material pallet;
  pallet.albedo = layout.albedo.pallet;
  scene.Add({"pallet", MakePallet(), pallet});
  for (const PalletPlacement& placement : placements) {
    const auto it = std::find_if(parts.begin(), parts.end(),
                                 [&](const PalletPart& p) { return p.name == placement.part; });
    if (it == parts.end()) {
      throw InputError("MakePalletScene: placement '" + placement.frame + "' names part '" +
                       placement.part + "', which is not among the parts");
    }
    MeshPart geometry = it->geometry;
    geometry.Transform(placement.cell_from_part);
    Material m;
    m.albedo = it->albedo;
    scene.Add({placement.frame, std::move(geometry), m});
  }
  scene.Commit();
  return scene;
}

}  // namespace lasercell::datasets
