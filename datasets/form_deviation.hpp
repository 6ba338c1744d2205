#pragma once
// How far a part's surface lies from its CAD model, as an inspection of the part against its
// CAD measures it: the distance of every vertex of the part's mesh to the nearest point of the
// CAD mesh. The simulator states it in the part file it writes (localize::FormDeviation): the
// localizer then knows the model is not the part and by how much, as a user would from the
// part's inspection report. Units mm.

#include <cstddef>

#include "core/point_cloud.hpp"

namespace lasercell::datasets {

/// Deviation statistics of a part against its CAD.
struct MeshDeviation {
  double rms_mm = 0.0;      ///< RMS distance of the part's vertices to the CAD surface.
  double max_mm = 0.0;      ///< Largest of them.
  std::size_t samples = 0;  ///< Part vertices measured.
};

/// Distances of the vertices of `part` to the surface of `cad` (both in the part frame).
/// InputError when either mesh has no faces.
MeshDeviation MeasureMeshDeviation(const TriangleMesh& part, const TriangleMesh& cad);

/// The closest point of triangle (a, b, c) to p.
Eigen::Vector3d ClosestPointOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                       const Eigen::Vector3d& b, const Eigen::Vector3d& c);

}  // namespace lasercell::datasets
