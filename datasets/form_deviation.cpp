#include "datasets/form_deviation.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/error.hpp"
#include "registration/kdtree.hpp"

namespace lasercell::datasets {

// Voronoi regions of the triangle (vertex, edge, face), tested in turn with the barycentric
// parameters of p's projection (Ericson 2005, Real-Time Collision Detection, sec. 5.1.5).
Eigen::Vector3d ClosestPointOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                       const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return a + ab * (d1 / (d1 - d3));
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return a + ac * (d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  }
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

MeshDeviation MeasureMeshDeviation(const TriangleMesh& part, const TriangleMesh& cad) {
  if (part.faces.empty() || cad.faces.empty()) {
    throw InputError("MeasureMeshDeviation: " + std::string(part.faces.empty() ? "part" : "CAD") +
                     " mesh has no faces");
  }
  const auto& v = cad.vertices.positions;
  // Triangles are found by their centroids: a triangle whose closest point to p is at distance
  // d has its centroid within d + (its largest centroid-to-vertex distance) of p.
  std::vector<Eigen::Vector3d> centroids;
  centroids.reserve(cad.faces.size());
  double reach = 0.0;
  for (const Eigen::Vector3i& f : cad.faces) {
    const Eigen::Vector3d g = (v[f[0]] + v[f[1]] + v[f[2]]) / 3.0;
    for (int k = 0; k < 3; ++k) reach = std::max(reach, (v[f[k]] - g).norm());
    centroids.push_back(g);
  }
  const registration::KdTree tree(std::move(centroids));
  const auto distance_to = [&](const Eigen::Vector3d& p, std::size_t face) {
    const Eigen::Vector3i& f = cad.faces[face];
    return (ClosestPointOnTriangle(p, v[f[0]], v[f[1]], v[f[2]]) - p).norm();
  };
  MeshDeviation out;
  double sum_sq = 0.0;
  std::vector<registration::Neighbor> near;
  for (const Eigen::Vector3d& p : part.vertices.positions) {
    registration::Neighbor nearest;
    tree.Nearest(p, &nearest);
    double d = distance_to(p, nearest.index);
    tree.RadiusSearch(p, d + reach, &near);
    for (const registration::Neighbor& n : near) d = std::min(d, distance_to(p, n.index));
    sum_sq += d * d;
    out.max_mm = std::max(out.max_mm, d);
    ++out.samples;
  }
  out.rms_mm = std::sqrt(sum_sq / static_cast<double>(out.samples));
  return out;
}

}  // namespace lasercell::datasets
