#include "datasets/geometry.hpp"

#include <cmath>
#include <numbers>

#include "core/error.hpp"

namespace lasercell::datasets {

namespace {
constexpr double kPi = std::numbers::pi;
}  // namespace

double AnalyticSurface::SignedDistance(const Eigen::Vector3d& p) const {
  switch (kind) {
    case Kind::kPlane:
      return (p - point).dot(axis);
    case Kind::kSphere:
      return (p - point).norm() - radius;
    case Kind::kCylinder: {
      const Eigen::Vector3d r = p - point;
      return (r - r.dot(axis) * axis).norm() - radius;
    }
    case Kind::kNone:
      break;
  }
  return 0.0;
}

AnalyticSurface AnalyticSurface::Transformed(const Eigen::Isometry3d& to_from_this) const {
  AnalyticSurface s = *this;
  s.point = to_from_this * point;
  s.axis = (to_from_this.linear() * axis).normalized();
  return s;
}

void MeshPart::Append(const MeshPart& other) {
  const auto v0 = static_cast<std::int32_t>(mesh.vertices.positions.size());
  const auto p0 = static_cast<std::int32_t>(patches.size());
  mesh.vertices.positions.insert(mesh.vertices.positions.end(),
                                 other.mesh.vertices.positions.begin(),
                                 other.mesh.vertices.positions.end());
  for (const Eigen::Vector3i& f : other.mesh.faces) {
    mesh.faces.push_back(f + Eigen::Vector3i::Constant(v0));
  }
  for (std::int32_t p : other.face_patch) face_patch.push_back(p + p0);
  patches.insert(patches.end(), other.patches.begin(), other.patches.end());
}

void MeshPart::Transform(const Eigen::Isometry3d& to_from_this) {
  for (Eigen::Vector3d& p : mesh.vertices.positions) p = to_from_this * p;
  for (AnalyticSurface& s : patches) s = s.Transformed(to_from_this);
}

std::int32_t MeshPart::AddPatch(const AnalyticSurface& surface) {
  patches.push_back(surface);
  return static_cast<std::int32_t>(patches.size() - 1);
}

std::int32_t MeshPart::AddVertex(const Eigen::Vector3d& p) {
  mesh.vertices.positions.push_back(p);
  return static_cast<std::int32_t>(mesh.vertices.positions.size() - 1);
}

void MeshPart::AddFace(std::int32_t a, std::int32_t b, std::int32_t c, std::int32_t patch) {
  mesh.faces.emplace_back(a, b, c);
  face_patch.push_back(patch);
}

void MeshPart::CheckConsistent() const {
  LASERCELL_CHECK(face_patch.size() == mesh.faces.size(), "one patch per face");
  const auto nv = static_cast<int>(mesh.vertices.positions.size());
  for (const Eigen::Vector3i& f : mesh.faces) {
    LASERCELL_CHECK(f.minCoeff() >= 0 && f.maxCoeff() < nv, "face index in range");
  }
  for (std::int32_t p : face_patch) {
    LASERCELL_CHECK(p >= 0 && p < static_cast<std::int32_t>(patches.size()), "patch in range");
  }
}

namespace {

AnalyticSurface Plane(const Eigen::Vector3d& point, const Eigen::Vector3d& normal) {
  AnalyticSurface s;
  s.kind = AnalyticSurface::Kind::kPlane;
  s.point = point;
  s.axis = normal.normalized();
  return s;
}

// Adds quad a-b-c-d (counter-clockwise seen from outside) as two triangles.
void AddQuad(MeshPart& m, std::int32_t a, std::int32_t b, std::int32_t c, std::int32_t d,
             std::int32_t patch) {
  m.AddFace(a, b, c, patch);
  m.AddFace(a, c, d, patch);
}

}  // namespace

MeshPart MakeBox(const Eigen::Isometry3d& frame_from_box, const Eigen::Vector3d& size_mm) {
  LASERCELL_CHECK((size_mm.array() > 0).all(), "box size must be positive");
  MeshPart m;
  const Eigen::Vector3d h = 0.5 * size_mm;
  // Each face gets its own 4 vertices so faces stay independent patches.
  for (int axis = 0; axis < 3; ++axis) {
    for (int sign : {-1, 1}) {
      Eigen::Vector3d n = Eigen::Vector3d::Zero();
      n[axis] = sign;
      const int u = (axis + 1) % 3;
      const int v = (axis + 2) % 3;
      Eigen::Vector3d du = Eigen::Vector3d::Zero();
      Eigen::Vector3d dv = Eigen::Vector3d::Zero();
      du[u] = h[u];
      dv[v] = h[v];
      const Eigen::Vector3d c = n.cwiseProduct(h);
      const std::int32_t patch = m.AddPatch(Plane(c, n));
      // (du x dv) is +n for sign > 0; flip the winding for the negative face.
      const std::int32_t a = m.AddVertex(c - du - dv);
      const std::int32_t b = m.AddVertex(c + du - dv);
      const std::int32_t cc = m.AddVertex(c + du + dv);
      const std::int32_t d = m.AddVertex(c - du + dv);
      if (sign > 0) {
        AddQuad(m, a, b, cc, d, patch);
      } else {
        AddQuad(m, a, d, cc, b, patch);
      }
    }
  }
  m.Transform(frame_from_box);
  return m;
}

MeshPart MakeRectangle(const Eigen::Isometry3d& frame_from_rect, double size_x_mm,
                       double size_y_mm) {
  LASERCELL_CHECK(size_x_mm > 0 && size_y_mm > 0, "rectangle size must be positive");
  MeshPart m;
  const double hx = 0.5 * size_x_mm;
  const double hy = 0.5 * size_y_mm;
  const std::int32_t patch = m.AddPatch(Plane(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ()));
  const std::int32_t a = m.AddVertex({-hx, -hy, 0});
  const std::int32_t b = m.AddVertex({hx, -hy, 0});
  const std::int32_t c = m.AddVertex({hx, hy, 0});
  const std::int32_t d = m.AddVertex({-hx, hy, 0});
  AddQuad(m, a, b, c, d, patch);
  m.Transform(frame_from_rect);
  return m;
}

MeshPart MakeCylinder(const Eigen::Isometry3d& frame_from_cylinder, double radius_mm,
                      double height_mm, int segments, bool bottom_cap, bool top_cap) {
  LASERCELL_CHECK(radius_mm > 0 && height_mm > 0 && segments >= 3, "cylinder parameters");
  MeshPart m;
  AnalyticSurface wall;
  wall.kind = AnalyticSurface::Kind::kCylinder;
  wall.radius = radius_mm;
  const std::int32_t wall_patch = m.AddPatch(wall);
  std::vector<std::int32_t> bottom(segments), top(segments);
  for (int i = 0; i < segments; ++i) {
    const double a = 2 * kPi * i / segments;
    const Eigen::Vector3d r(radius_mm * std::cos(a), radius_mm * std::sin(a), 0.0);
    bottom[i] = m.AddVertex(r);
    top[i] = m.AddVertex(r + Eigen::Vector3d(0, 0, height_mm));
  }
  for (int i = 0; i < segments; ++i) {
    const int j = (i + 1) % segments;
    AddQuad(m, bottom[i], bottom[j], top[j], top[i], wall_patch);
  }
  if (bottom_cap) {
    const std::int32_t patch =
        m.AddPatch(Plane(Eigen::Vector3d::Zero(), -Eigen::Vector3d::UnitZ()));
    const std::int32_t c = m.AddVertex(Eigen::Vector3d::Zero());
    for (int i = 0; i < segments; ++i) m.AddFace(c, bottom[(i + 1) % segments], bottom[i], patch);
  }
  if (top_cap) {
    const Eigen::Vector3d tc(0, 0, height_mm);
    const std::int32_t patch = m.AddPatch(Plane(tc, Eigen::Vector3d::UnitZ()));
    const std::int32_t c = m.AddVertex(tc);
    for (int i = 0; i < segments; ++i) m.AddFace(c, top[i], top[(i + 1) % segments], patch);
  }
  m.Transform(frame_from_cylinder);
  return m;
}

namespace {

// Sphere zone between polar angles [theta0, theta1] (0 = +z pole) as rings x segments.
MeshPart SphereZone(double radius_mm, int segments, int rings, double theta1) {
  LASERCELL_CHECK(radius_mm > 0 && segments >= 3 && rings >= 1, "sphere parameters");
  MeshPart m;
  AnalyticSurface s;
  s.kind = AnalyticSurface::Kind::kSphere;
  s.radius = radius_mm;
  const std::int32_t patch = m.AddPatch(s);
  const std::int32_t pole = m.AddVertex(Eigen::Vector3d(0, 0, radius_mm));
  std::vector<std::vector<std::int32_t>> ring(rings);
  for (int r = 0; r < rings; ++r) {
    const double theta = theta1 * (r + 1) / rings;
    ring[r].resize(segments);
    for (int i = 0; i < segments; ++i) {
      const double phi = 2 * kPi * i / segments;
      ring[r][i] = m.AddVertex(radius_mm * Eigen::Vector3d(std::sin(theta) * std::cos(phi),
                                                           std::sin(theta) * std::sin(phi),
                                                           std::cos(theta)));
    }
  }
  for (int i = 0; i < segments; ++i)
    m.AddFace(pole, ring[0][i], ring[0][(i + 1) % segments], patch);
  for (int r = 0; r + 1 < rings; ++r) {
    for (int i = 0; i < segments; ++i) {
      const int j = (i + 1) % segments;
      AddQuad(m, ring[r][i], ring[r + 1][i], ring[r + 1][j], ring[r][j], patch);
    }
  }
  return m;
}

}  // namespace

MeshPart MakeHemisphere(const Eigen::Isometry3d& frame_from_sphere, double radius_mm, int segments,
                        int rings) {
  MeshPart m = SphereZone(radius_mm, segments, rings, kPi / 2);
  m.Transform(frame_from_sphere);
  return m;
}

MeshPart MakeSphere(const Eigen::Isometry3d& frame_from_sphere, double radius_mm, int segments,
                    int rings) {
  // Upper half, then the mirrored lower half sharing nothing but the analytic patch.
  MeshPart upper = SphereZone(radius_mm, segments, rings, kPi / 2);
  MeshPart lower = upper;
  for (Eigen::Vector3d& p : lower.mesh.vertices.positions) p.z() = -p.z();
  for (Eigen::Vector3i& f : lower.mesh.faces) std::swap(f[1], f[2]);
  upper.Append(lower);
  upper.Transform(frame_from_sphere);
  return upper;
}

MeshPart MakePallet() {
  // EUR pallet (EN 13698-1): 1200 x 800 x 144 mm; 22 mm deck boards, 78 mm blocks.
  MeshPart m;
  const double board = 22.0;
  const double block = 78.0;
  const auto box = [&](double cx, double cy, double cz, double sx, double sy, double sz) {
    m.Append(MakeBox(Eigen::Isometry3d(Eigen::Translation3d(cx, cy, cz)), {sx, sy, sz}));
  };
  // Bottom boards along x (3), blocks (3 x 3), stringer boards along x (3), top boards (5).
  for (double y : {-335.0, 0.0, 335.0}) box(0, y, board / 2, 1200, 100, board);
  for (double x : {-545.0, 0.0, 545.0}) {
    for (double y : {-335.0, 0.0, 335.0}) box(x, y, board + block / 2, 110, 100, block);
  }
  for (double x : {-545.0, 0.0, 545.0}) box(x, 0, board + block + board / 2, 110, 800, board);
  const double top_z = 2 * board + block + board / 2;
  for (const Eigen::Vector2d& y : PalletDeckBoards()) {
    box(0, (y[0] + y[1]) / 2, top_z, 1200, y[1] - y[0], board);
  }
  return m;
}

std::vector<Eigen::Vector2d> PalletDeckBoards() {
  const double widths[5] = {100, 145, 100, 145, 100};
  const double ys[5] = {-350, -177.5, 0, 177.5, 350};
  std::vector<Eigen::Vector2d> boards;
  for (int i = 0; i < 5; ++i) boards.emplace_back(ys[i] - widths[i] / 2, ys[i] + widths[i] / 2);
  return boards;
}

}  // namespace lasercell::datasets
