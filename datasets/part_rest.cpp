#include "datasets/part_rest.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <utility>

#include "core/error.hpp"

namespace lasercell::datasets {

namespace {

// Vertices closer than this to the plane touch it (after a pivot the new contact is at ~1e-12).
constexpr double kContactMm = 1e-6;

double Cross2(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

// Bit pattern of a position, so identical copies of a vertex weld and nothing else does.
std::array<std::uint64_t, 3> Key(const Eigen::Vector3d& p) {
  std::array<std::uint64_t, 3> k{};
  for (int i = 0; i < 3; ++i) {
    const double v = p[i] == 0.0 ? 0.0 : p[i];  // -0 and +0 weld
    std::memcpy(&k[i], &v, sizeof(double));
  }
  return k;
}

// Distance from p to the segment [a, b].
double SegmentDistance(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                       const Eigen::Vector2d& p) {
  const Eigen::Vector2d ab = b - a;
  const double len2 = ab.squaredNorm();
  const double s = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (a + s * ab - p).norm();
}

// The pivot of a part whose centre of mass projects to g outside the support hull: the hull
// feature nearest g, as a point and a horizontal unit direction towards g in which it tips.
struct Pivot {
  Eigen::Vector2d point;
  Eigen::Vector2d toward;
};

Pivot NearestFeature(const std::vector<Eigen::Vector2d>& hull, const Eigen::Vector2d& g) {
  Pivot best{hull.front(), Eigen::Vector2d::UnitX()};
  double best_d = std::numeric_limits<double>::infinity();
  const std::size_t n = hull.size();
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d& a = hull[i];
    const Eigen::Vector2d& b = hull[(i + 1) % n];
    if (n == 1 && i > 0) break;
    const Eigen::Vector2d ab = b - a;
    const double len2 = ab.squaredNorm();
    const double s = len2 > 0 ? std::clamp((g - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    const Eigen::Vector2d q = a + s * ab;
    const double d = (g - q).norm();
    if (d < best_d) {
      best_d = d;
      best.point = q;
      // Tip perpendicular to an edge when g faces its interior, else towards g from the vertex.
      if (len2 > 0 && s > 0 && s < 1) {
        Eigen::Vector2d normal(ab.y(), -ab.x());
        if (normal.dot(g - a) < 0) normal = -normal;
        best.toward = normal.normalized();
      } else {
        best.toward = d > 0 ? Eigen::Vector2d((g - q) / d) : Eigen::Vector2d::UnitX();
      }
    }
  }
  return best;
}

}  // namespace

MeshSolidCheck CheckMeshSolid(const TriangleMesh& mesh) {
  MeshSolidCheck out;
  const auto& p = mesh.vertices.positions;
  std::map<std::array<std::uint64_t, 3>, int> ids;
  std::vector<int> weld(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) {
    weld[i] = ids.emplace(Key(p[i]), static_cast<int>(ids.size())).first->second;
  }
  // Directed edge counts per undirected edge: (a < b) -> {uses a->b, uses b->a}.
  std::map<std::pair<int, int>, std::array<int, 2>> edges;
  double volume6 = 0;
  Eigen::Vector3d moment24 = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3i& f : mesh.faces) {
    for (int k = 0; k < 3; ++k) {
      const int a = weld[f[k]], b = weld[f[(k + 1) % 3]];
      if (a == b) continue;
      auto& e = edges[{std::min(a, b), std::max(a, b)}];
      ++e[a < b ? 0 : 1];
    }
    // Signed tetrahedra with the origin: volume and first moment (divergence theorem).
    const Eigen::Vector3d& v0 = p[f[0]];
    const Eigen::Vector3d& v1 = p[f[1]];
    const Eigen::Vector3d& v2 = p[f[2]];
    const double det = v0.dot(v1.cross(v2));
    volume6 += det;
    moment24 += det * (v0 + v1 + v2);
  }
  for (const auto& [key, uses] : edges) {
    const int total = uses[0] + uses[1];
    if (total == 1) {
      ++out.boundary_edges;
    } else if (total != 2 || uses[0] != 1) {
      ++out.inconsistent_edges;
    }
  }
  out.volume_mm3 = volume6 / 6.0;
  if (volume6 != 0) out.center_of_mass = moment24 / (4.0 * volume6);
  return out;
}

std::vector<Eigen::Vector2d> ConvexHull2d(std::vector<Eigen::Vector2d> pts) {
  std::sort(pts.begin(), pts.end(), [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  pts.erase(std::unique(pts.begin(), pts.end()), pts.end());
  if (pts.size() < 3) return pts;
  std::vector<Eigen::Vector2d> hull(2 * pts.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {  // lower chain
    while (k >= 2 && Cross2(hull[k - 1] - hull[k - 2], pts[i] - hull[k - 2]) <= 0) --k;
    hull[k++] = pts[i];
  }
  for (std::size_t i = pts.size() - 1, lower = k + 1; i-- > 0;) {  // upper chain
    while (k >= lower && Cross2(hull[k - 1] - hull[k - 2], pts[i] - hull[k - 2]) <= 0) --k;
    hull[k++] = pts[i];
  }
  hull.resize(k - 1);
  return hull;
}

double SignedDistanceInside(const std::vector<Eigen::Vector2d>& hull, const Eigen::Vector2d& p) {
  if (hull.empty()) return -std::numeric_limits<double>::infinity();
  if (hull.size() < 3) {
    return -(hull.size() == 1 ? (hull[0] - p).norm() : SegmentDistance(hull[0], hull[1], p));
  }
  double inside = std::numeric_limits<double>::infinity();
  bool outside = false;
  double outside_d = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < hull.size(); ++i) {
    const Eigen::Vector2d& a = hull[i];
    const Eigen::Vector2d& b = hull[(i + 1) % hull.size()];
    const double side = Cross2(b - a, p - a) / (b - a).norm();  // > 0: left, inside
    inside = std::min(inside, side);
    if (side < 0) outside = true;
    outside_d = std::min(outside_d, SegmentDistance(a, b, p));
  }
  return outside ? -outside_d : inside;
}

bool ConvexPolygonsCloserThan(const std::vector<Eigen::Vector2d>& a,
                              const std::vector<Eigen::Vector2d>& b, double gap_mm) {
  // The largest separation along any edge normal bounds the true distance from below, so this
  // errs on the side of "closer" (conservative for placing parts apart).
  const auto separated = [&](const std::vector<Eigen::Vector2d>& p,
                             const std::vector<Eigen::Vector2d>& q) {
    for (std::size_t i = 0; i < p.size(); ++i) {
      const Eigen::Vector2d e = p[(i + 1) % p.size()] - p[i];
      if (e.squaredNorm() == 0) continue;
      const Eigen::Vector2d n = Eigen::Vector2d(e.y(), -e.x()).normalized();  // outward (ccw)
      const double p_max = n.dot(p[i]);
      double q_min = std::numeric_limits<double>::infinity();
      for (const Eigen::Vector2d& v : q) q_min = std::min(q_min, n.dot(v));
      if (q_min - p_max >= gap_mm) return true;
    }
    return false;
  };
  return !(separated(a, b) || separated(b, a));
}

RestingPose SettleOnPlane(const std::vector<Eigen::Vector3d>& vertices, const Eigen::Vector3d& com,
                          const Eigen::Matrix3d& start, double contact_tolerance_mm) {
  if (vertices.size() < 3) throw InputError("SettleOnPlane: a part needs at least 3 vertices");
  if (!(contact_tolerance_mm > 0)) {
    throw InputError("SettleOnPlane: contact_tolerance_mm must be positive, got " +
                     std::to_string(contact_tolerance_mm));
  }
  RestingPose rest;
  Eigen::Matrix3d rotation = start;
  std::vector<Eigen::Vector3d> rotated(vertices.size());
  for (int step = 0; step <= 100; ++step) {
    double z_min = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < vertices.size(); ++i) {
      rotated[i] = rotation * vertices[i];
      z_min = std::min(z_min, rotated[i].z());
    }
    // Exact contacts (the pivot) and the support within the tolerance (the rest test).
    std::vector<Eigen::Vector2d> exact, support;
    std::vector<std::size_t> support_ids;
    for (std::size_t i = 0; i < vertices.size(); ++i) {
      const double h = rotated[i].z() - z_min;
      if (h < kContactMm) exact.push_back(rotated[i].head<2>());
      if (h <= contact_tolerance_mm) {
        support.push_back(rotated[i].head<2>());
        support_ids.push_back(i);
      }
    }
    const Eigen::Vector2d g = (rotation * com).head<2>();
    const std::vector<Eigen::Vector2d> support_hull = ConvexHull2d(support);
    const double margin = SignedDistanceInside(support_hull, g);
    if (support_hull.size() >= 3 && margin > 0) {
      rest.plane_from_part.linear() = rotation;
      rest.plane_from_part.translation() = Eigen::Vector3d(0, 0, -z_min);
      for (const Eigen::Vector2d& h : support_hull) {
        for (std::size_t k = 0; k < support.size(); ++k) {
          if (support[k] == h) {
            rest.contacts_in_part.push_back(vertices[support_ids[k]]);
            break;
          }
        }
      }
      rest.stability_margin_mm = margin;
      rest.pivots = step;
      return rest;
    }
    const std::vector<Eigen::Vector2d> hull = ConvexHull2d(exact);
    // Tip about the nearest support feature towards g: about the horizontal axis a = z x d
    // through the pivot, a point at horizontal offset u along d and height w above the plane
    // comes down to w cos(theta) - u sin(theta); the first vertex with u > 0 to reach the plane
    // stops the fall at theta = atan2(w, u).
    const Pivot pivot = NearestFeature(hull, g);
    const Eigen::Vector3d d(pivot.toward.x(), pivot.toward.y(), 0.0);
    const Eigen::Vector3d origin(pivot.point.x(), pivot.point.y(), z_min);
    double theta = std::numeric_limits<double>::infinity();
    for (const Eigen::Vector3d& p : rotated) {
      const double u = (p - origin).dot(d);
      if (u > kContactMm) theta = std::min(theta, std::atan2(p.z() - z_min, u));
    }
    LASERCELL_CHECK(std::isfinite(theta), "SettleOnPlane: no vertex beyond the pivot");
    const Eigen::Vector3d axis = Eigen::Vector3d::UnitZ().cross(d);
    rotation = Eigen::AngleAxisd(theta, axis).toRotationMatrix() * rotation;
  }
  throw InternalError("SettleOnPlane: the part did not come to rest within 100 pivots");
}

}  // namespace lasercell::datasets
