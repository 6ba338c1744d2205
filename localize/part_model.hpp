#pragma once
// A part ready to be looked for: its CAD or mesh model turned into oriented surface points and a
// PPF model (registration/ppf_model.hpp), with the tessellated mesh for reports.
//
// Surface points: CAD (STEP/IGES) through ReadCadModel (exact normals from the B-rep); meshes
// (STL/OBJ/PLY, scaled from the part's unit to mm) sampled on every triangle, area-uniform at
// `cad.sampling_step_mm` spacing (ceil(area / step^2) points per triangle on a low-discrepancy
// sequence, so the result is deterministic), each with its face normal (outward when the mesh
// winds counter-clockwise seen from outside, as STL requires). The PPF model is built from these
// points with the part's model options.
//
// Cache: a built model is written as `<cache_dir>/<name>-<digest>.ppfm`, the digest (FNV-1a 64)
// over the model file's bytes, the unit, the sampling and the model options, so an edit of any
// of them builds anew and an unchanged part loads in milliseconds. Default cache_dir: the part
// file's folder + "/.lasercell-cache".

#include <Eigen/Geometry>
#include <string>

#include "core/point_cloud.hpp"
#include "localize/part.hpp"
#include "registration/ppf_model.hpp"

namespace lasercell::localize {

/// Options of LoadPartModel.
struct PartModelOptions {
  bool use_cache = true;    ///< Load a cached model when its digest matches; write one when built.
  bool write_cache = true;  ///< With use_cache: write a built model to the cache.
  std::string cache_dir;    ///< "" = the part file's folder + "/.lasercell-cache".
  /// Read the model file for the mesh even when the PPF model comes from the cache (reports).
  bool load_mesh = true;
  int threads = 0;  ///< Model build threads (0 = all cores).
};

/// A loaded part.
struct PartModel {
  PartDefinition part;  ///< The part file.
  registration::PpfModel ppf;
  TriangleMesh mesh;        ///< Part frame, mm (empty when not loaded).
  std::string digest;       ///< "fnv1a64:..." of the model inputs (see the file comment).
  std::string cache_file;   ///< Where the model is cached ("" when caching is off).
  bool from_cache = false;  ///< The PPF model was loaded, not built.
  /// Why the cache was not used or not written, e.g. a read-only folder ("" when it was).
  std::string cache_note;
  double load_ms = 0.0;            ///< Reading the model file, sampling and building or loading.
  std::size_t surface_points = 0;  ///< Oriented points sampled (0 when loaded from the cache).
  std::string source_format;       ///< "step", "iges", "stl", "obj", "ply".
  std::string source_unit;         ///< Unit of the model file ("mm", "inch", ...).
  Eigen::AlignedBox3d bounds;      ///< Of the model in the part frame, mm.
};

/// Oriented points on the surface of `mesh` (see the file comment), at most ~`max_points`
/// (the step grows when the area needs more). Throws InputError for a mesh without faces, a face
/// index out of range or a total area of zero.
PointCloud SampleMeshSurface(const TriangleMesh& mesh, double step_mm,
                             std::size_t max_points = 2000000);

/// The digest of what determines the PPF model of `part` (FileError when the model file cannot
/// be read).
std::string PartModelDigest(const PartDefinition& part);

/// The cache file of `part` under `options` ("" when caching is off).
std::string PartModelCacheFile(const PartDefinition& part, const std::string& digest,
                               const PartModelOptions& options);

/// Several lines: part, model file, format and unit, surface points, PPF model points,
/// diameter, sampling step, grasps, load time and cache state.
std::string PartModelSummary(const PartModel& model);

/// Loads a part's model (see the file comment). Throws FileError naming the model file when it
/// does not exist or cannot be read, InputError when it holds no triangles or surfaces, and
/// InputError naming the part file and the grasp when a grasp frame lies farther than half the
/// model's diameter outside the model's bounding box (a frame in the wrong unit or frame).
PartModel LoadPartModel(const PartDefinition& part, const PartModelOptions& options = {});

}  // namespace lasercell::localize
