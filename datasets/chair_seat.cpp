#include "datasets/chair_seat.hpp"

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "core/error.hpp"

namespace lasercell::datasets {

namespace {

constexpr double kPi = std::numbers::pi;

double SignedPow(double v, double e) { return std::copysign(std::pow(std::abs(v), e), v); }

// Height of the shell's outer (upper) surface at (x, y).
double TopZ(const ChairSeatOptions& o, double x, double y) {
  const double u = x / o.half_length_x_mm;
  const double v = y / o.half_width_y_mm;
  const double e = o.outline_exponent;
  const double rho = std::pow(std::pow(std::abs(u), e) + std::pow(std::abs(v), e), 1.0 / e);
  const double front = std::max(0.0, (u - 0.35) / 0.65);
  // Dome, rolled front edge, lifted sides; all smooth inside the outline.
  return o.thickness_mm + o.front_roll_mm + o.crown_mm * (1.0 - rho * rho) -
         o.front_roll_mm * front * front + o.side_lift_mm * v * v * v * v;
}

}  // namespace

void ChairSeatOptions::Check(const std::string& what) const {
  const auto positive = [&](double v, const char* field) {
    if (!(v > 0) || !std::isfinite(v)) {
      throw OptionError(what + "." + field + " must be a positive number (got " +
                        std::to_string(v) + ")");
    }
  };
  positive(half_length_x_mm, "half_length_x_mm");
  positive(half_width_y_mm, "half_width_y_mm");
  positive(outline_exponent, "outline_exponent");
  positive(thickness_mm, "thickness_mm");
  positive(boss_radius_mm, "boss_radius_mm");
  positive(boss_height_mm, "boss_height_mm");
  positive(hole_diameter_mm, "hole_diameter_mm");
  if (!(crown_mm >= 0) || !(front_roll_mm >= 0) || !(side_lift_mm >= 0)) {
    throw OptionError(what + ".crown_mm, front_roll_mm and side_lift_mm must be >= 0");
  }
  if (hole_diameter_mm / 2 >= boss_radius_mm - 1.0) {
    throw OptionError(what + ".hole_diameter_mm = " + std::to_string(hole_diameter_mm) +
                      " leaves no wall inside boss_radius_mm = " + std::to_string(boss_radius_mm));
  }
  const double room = std::min(half_length_x_mm, half_width_y_mm) * 0.6;
  if (std::abs(boss_offset_x_mm) + boss_radius_mm > room) {
    throw OptionError(what + ".boss_offset_x_mm/boss_radius_mm put the boss too close to the rim");
  }
  if (angular_steps < 16 || radial_steps < 2) {
    throw OptionError(what + ".angular_steps must be >= 16 and radial_steps >= 2");
  }
}

ChairSeat MakeChairSeat(const ChairSeatOptions& o) {
  o.Check();
  ChairSeat seat;
  MeshPart& m = seat.part;
  const int na = o.angular_steps;
  const int nr = o.radial_steps;
  const Eigen::Vector2d boss_c(o.boss_offset_x_mm, 0.0);
  const double rh = o.hole_diameter_mm / 2;
  const double rb = o.boss_radius_mm;
  const double boss_top_z = TopZ(o, boss_c.x(), boss_c.y()) + o.boss_height_mm;

  const std::int32_t top_patch = m.AddPatch({});
  const std::int32_t bottom_patch = m.AddPatch({});
  const std::int32_t rim_patch = m.AddPatch({});
  AnalyticSurface cyl;
  cyl.kind = AnalyticSurface::Kind::kCylinder;
  cyl.point = Eigen::Vector3d(boss_c.x(), boss_c.y(), 0.0);
  cyl.axis = Eigen::Vector3d::UnitZ();
  cyl.radius = rb;
  const std::int32_t boss_wall_patch = m.AddPatch(cyl);
  cyl.radius = rh;
  const std::int32_t hole_patch = m.AddPatch(cyl);
  AnalyticSurface top_plane;
  top_plane.kind = AnalyticSurface::Kind::kPlane;
  top_plane.point = Eigen::Vector3d(boss_c.x(), boss_c.y(), boss_top_z);
  top_plane.axis = Eigen::Vector3d::UnitZ();
  const std::int32_t boss_top_patch = m.AddPatch(top_plane);

  // Outline point at angle theta (superellipse), and the circle of radius r about the boss.
  const auto outline = [&](double theta) {
    const double e = 2.0 / o.outline_exponent;
    return Eigen::Vector2d(o.half_length_x_mm * SignedPow(std::cos(theta), e),
                           o.half_width_y_mm * SignedPow(std::sin(theta), e));
  };
  const auto circle = [&](double r, double theta) {
    return Eigen::Vector2d(boss_c + r * Eigen::Vector2d(std::cos(theta), std::sin(theta)));
  };
  // Grid from a circle of radius r0 about the boss (s = 0) to the outline (s = 1), at height
  // z(x, y) = TopZ + dz. Radial spacing is finer near both ends (cosine spacing).
  const auto grid = [&](double r0, double dz) {
    std::vector<std::vector<std::int32_t>> g(nr + 1, std::vector<std::int32_t>(na));
    for (int k = 0; k <= nr; ++k) {
      const double s = 0.5 - 0.5 * std::cos(kPi * k / nr);
      for (int j = 0; j < na; ++j) {
        const double theta = 2 * kPi * j / na;
        const Eigen::Vector2d xy = (1 - s) * circle(r0, theta) + s * outline(theta);
        g[k][j] = m.AddVertex({xy.x(), xy.y(), TopZ(o, xy.x(), xy.y()) + dz});
      }
    }
    return g;
  };
  const auto top = grid(rb, 0.0);
  const auto bottom = grid(rh, -o.thickness_mm);
  for (int k = 0; k < nr; ++k) {
    for (int j = 0; j < na; ++j) {
      const int jn = (j + 1) % na;
      m.AddFace(top[k][j], top[k + 1][j], top[k + 1][jn], top_patch);
      m.AddFace(top[k][j], top[k + 1][jn], top[k][jn], top_patch);
      m.AddFace(bottom[k][j], bottom[k + 1][jn], bottom[k + 1][j], bottom_patch);
      m.AddFace(bottom[k][j], bottom[k][jn], bottom[k + 1][jn], bottom_patch);
    }
  }
  // Rim wall between the outer rings.
  for (int j = 0; j < na; ++j) {
    const int jn = (j + 1) % na;
    m.AddFace(bottom[nr][j], bottom[nr][jn], top[nr][jn], rim_patch);
    m.AddFace(bottom[nr][j], top[nr][jn], top[nr][j], rim_patch);
  }
  // Boss wall: from the top surface's inner ring up to the boss top; boss top annulus; hole wall
  // down to the bottom surface's inner ring. The boss rings share the grid's angular steps.
  std::vector<std::int32_t> boss_outer(na), boss_inner(na);
  for (int j = 0; j < na; ++j) {
    const double theta = 2 * kPi * j / na;
    const Eigen::Vector2d po = circle(rb, theta);
    const Eigen::Vector2d pi = circle(rh, theta);
    boss_outer[j] = m.AddVertex({po.x(), po.y(), boss_top_z});
    boss_inner[j] = m.AddVertex({pi.x(), pi.y(), boss_top_z});
  }
  for (int j = 0; j < na; ++j) {
    const int jn = (j + 1) % na;
    m.AddFace(top[0][j], top[0][jn], boss_outer[jn], boss_wall_patch);
    m.AddFace(top[0][j], boss_outer[jn], boss_outer[j], boss_wall_patch);
    m.AddFace(boss_inner[j], boss_outer[j], boss_outer[jn], boss_top_patch);
    m.AddFace(boss_inner[j], boss_outer[jn], boss_inner[jn], boss_top_patch);
    m.AddFace(bottom[0][j], boss_inner[j], boss_inner[jn], hole_patch);
    m.AddFace(bottom[0][j], boss_inner[jn], bottom[0][jn], hole_patch);
  }
  m.CheckConsistent();
  seat.hole_center_in_part = Eigen::Vector3d(boss_c.x(), boss_c.y(), boss_top_z);
  seat.hole_axis_in_part = Eigen::Vector3d::UnitZ();
  seat.boss_radius_mm = o.boss_radius_mm;
  return seat;
}

void SeatRenderOptions::Check(const std::string& what) const {
  if (angular_steps != 0 && angular_steps < 16) {
    throw OptionError(what + ".angular_steps must be 0 (the CAD's) or >= 16 (got " +
                      std::to_string(angular_steps) + ")");
  }
  if (radial_steps != 0 && radial_steps < 2) {
    throw OptionError(what + ".radial_steps must be 0 (the CAD's) or >= 2 (got " +
                      std::to_string(radial_steps) + ")");
  }
  if (!(std::abs(warp_mm) <= 5.0)) {
    throw OptionError(what + ".warp_mm must be within +-5 mm (got " + std::to_string(warp_mm) +
                      ")");
  }
}

ChairSeat MakeRenderedChairSeat(const ChairSeatOptions& cad, const SeatRenderOptions& render) {
  render.Check();
  ChairSeatOptions o = cad;
  if (render.angular_steps > 0) o.angular_steps = render.angular_steps;
  if (render.radial_steps > 0) o.radial_steps = render.radial_steps;
  ChairSeat seat = MakeChairSeat(o);
  if (render.warp_mm != 0.0) {
    const double scale = render.warp_mm / (o.half_length_x_mm * o.half_length_x_mm);
    for (Eigen::Vector3d& v : seat.part.mesh.vertices.positions) {
      const double dx = v.x() - o.boss_offset_x_mm;
      v.z() += scale * (dx * dx - v.y() * v.y());
    }
  }
  return seat;
}

}  // namespace lasercell::datasets
