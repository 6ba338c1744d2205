#include "localize/part_model.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "core/io/file_util.hpp"
#include "core/io/mesh_io.hpp"
#include "core/provenance.hpp"
#include "localize/cad_import.hpp"
#include "registration/localize_options_io.hpp"

namespace lasercell::localize {
namespace {

// Bumped when the way surface points are made changes, so old cache files are not reused.
constexpr const char* kSamplingVersion = "lasercell part model 1";

double Frac(double x) { return x - std::floor(x); }

Eigen::AlignedBox3d BoundsOf(const std::vector<Eigen::Vector3d>& points) {
  Eigen::AlignedBox3d box;
  for (const Eigen::Vector3d& p : points) box.extend(p);
  return box;
}

void CheckGrasps(const PartDefinition& part, const Eigen::AlignedBox3d& bounds) {
  const double diameter = bounds.diagonal().norm();
  for (const GraspFrame& g : part.grasps) {
    const double outside = bounds.exteriorDistance(g.part_from_grasp.translation_mm);
    if (outside > 0.5 * diameter) {
      throw InputError((part.file.empty() ? "part " + part.name : part.file) + ": grasps." +
                       g.name + ".part_from_grasp lies " + std::to_string(outside) +
                       " mm outside the model (diameter " + std::to_string(diameter) +
                       " mm): is it in the part frame and in mm?");
    }
  }
}

// The model's oriented surface points and mesh, in the part frame, mm.
PointCloud SurfaceOf(const PartDefinition& part, PartModel* out) {
  if (!std::filesystem::is_regular_file(part.model_path)) {
    throw FileError(part.model_path, "model file of part '" + part.name + "' (" +
                                         (part.file.empty() ? "in memory" : part.file) +
                                         ") does not exist");
  }
  if (IsCadFile(part.model_path)) {
    CadModel cad = ReadCadModel(part.model_path, part.cad);
    out->source_format = cad.format;
    out->source_unit = cad.source_unit;
    out->mesh = std::move(cad.mesh);
    return std::move(cad.samples);
  }
  io::ReadReport report;
  TriangleMesh mesh = io::ReadMesh(part.model_path, &report);
  if (mesh.faces.empty()) {
    throw FileError(part.model_path,
                    "holds no triangles: the part model must be a surface mesh "
                    "(or a STEP/IGES solid)");
  }
  const double scale = UnitToMm(part.units, part.file + ": field 'units'");
  for (Eigen::Vector3d& p : mesh.vertices.positions) p *= scale;
  mesh.vertices.normals.clear();  // re-derived from the faces below
  out->source_format = report.format.substr(0, report.format.find(' '));
  out->source_unit = part.units;
  PointCloud samples = SampleMeshSurface(mesh, part.cad.sampling_step_mm);
  out->mesh = std::move(mesh);
  return samples;
}

}  // namespace

PointCloud SampleMeshSurface(const TriangleMesh& mesh, double step_mm, std::size_t max_points) {
  if (!(step_mm > 0.0)) throw OptionError("SampleMeshSurface: step_mm must be > 0");
  if (mesh.faces.empty()) throw InputError("SampleMeshSurface: the mesh has no faces");
  const auto& v = mesh.vertices.positions;
  double area = 0.0;
  for (const Eigen::Vector3i& f : mesh.faces) {
    for (int k = 0; k < 3; ++k) {
      if (f[k] < 0 || static_cast<std::size_t>(f[k]) >= v.size()) {
        throw InputError("SampleMeshSurface: a face refers to vertex " + std::to_string(f[k]) +
                         " of " + std::to_string(v.size()));
      }
    }
    area += 0.5 * (v[f[1]] - v[f[0]]).cross(v[f[2]] - v[f[0]]).norm();
  }
  if (!(area > 0.0)) throw InputError("SampleMeshSurface: the mesh has zero area");
  const double step = std::max(step_mm, std::sqrt(area / static_cast<double>(max_points)));
  const double per_mm2 = 1.0 / (step * step);
  PointCloud cloud;
  // R2 low-discrepancy sequence (plastic-number constants) folded onto each triangle with the
  // area-uniform map (1 - sqrt(u), sqrt(u)(1 - w), sqrt(u) w).
  constexpr double kA1 = 0.7548776662466927, kA2 = 0.5698402909980532;
  for (const Eigen::Vector3i& f : mesh.faces) {
    const Eigen::Vector3d &a = v[f[0]], &b = v[f[1]], &c = v[f[2]];
    const Eigen::Vector3d cross = (b - a).cross(c - a);
    const double face_area = 0.5 * cross.norm();
    if (!(face_area > 0.0)) continue;  // degenerate triangle: no surface
    const Eigen::Vector3d normal = cross.normalized();
    const auto n = static_cast<std::size_t>(std::ceil(face_area * per_mm2));
    for (std::size_t i = 0; i < n; ++i) {
      const double s = std::sqrt(Frac(0.5 + kA1 * static_cast<double>(i)));
      const double w = Frac(0.5 + kA2 * static_cast<double>(i));
      cloud.positions.push_back((1.0 - s) * a + s * (1.0 - w) * b + s * w * c);
      cloud.normals.push_back(normal);
    }
  }
  return cloud;
}

std::string PartModelDigest(const PartDefinition& part) {
  InputDigest digest;
  digest.Add(kSamplingVersion);
  digest.AddFile(part.model_path);
  digest.Add("\nunits " + part.units + "\ncad " + std::to_string(part.cad.sampling_step_mm) + " " +
             std::to_string(part.cad.linear_deflection_mm) + " " +
             std::to_string(part.cad.angular_deflection_rad) + "\n");
  registration::PpfModelOptions model = part.model_options;
  model.threads = 0;  // the table does not depend on it
  digest.Add(registration::PpfModelOptionsYaml(model, ""));
  return digest.Text();
}

std::string PartModelCacheFile(const PartDefinition& part, const std::string& digest,
                               const PartModelOptions& options) {
  if (!options.use_cache) return "";
  std::filesystem::path dir = options.cache_dir;
  if (dir.empty()) {
    const std::filesystem::path folder = std::filesystem::path(part.file).parent_path();
    dir = (folder.empty() ? std::filesystem::path(".") : folder) / ".lasercell-cache";
  }
  const std::string hex = digest.substr(digest.find(':') + 1);
  return (dir / (part.name + "-" + hex + ".ppfm")).string();
}

std::string PartModelSummary(const PartModel& m) {
  char buf[512];
  std::string out = "part " + m.part.name + (m.part.file.empty() ? "" : " (" + m.part.file + ")") +
                    "\nmodel " + m.part.model_path + ": " + m.source_format + ", unit " +
                    m.source_unit + "\n";
  std::snprintf(buf, sizeof buf,
                "surface points %zu; PPF model %zu points, %zu pairs; diameter %.2f mm; "
                "sampling step %.2f mm; refinement points %zu\n",
                m.surface_points, m.ppf.points().size(), m.ppf.pair_count(), m.ppf.diameter_mm(),
                m.ppf.sampling_step_mm(), m.ppf.refinement_points().size());
  out += buf;
  for (const GraspFrame& g : m.part.grasps) {
    out += "grasp " + g.name + ": part_from_grasp " + PoseToFileNotation(g.part_from_grasp) + "\n";
  }
  const FormDeviation& form = m.part.form_deviation;
  if (form.rms_mm > 0.0) {
    std::snprintf(buf, sizeof buf,
                  "form deviation from the model: %.3f mm RMS over %.0f mm (in the pose "
                  "covariance)\n",
                  form.rms_mm, form.correlation_mm);
    out += buf;
  } else {
    out += "form deviation from the model: none stated (the model is taken as exact)\n";
  }
  std::snprintf(buf, sizeof buf, "%s in %.1f ms; cache %s%s%s\n",
                m.from_cache ? "loaded from the cache" : "built", m.load_ms,
                m.cache_file.empty() ? "off" : m.cache_file.c_str(),
                m.cache_note.empty() ? "" : ": ", m.cache_note.c_str());
  return out + buf;
}

PartModel LoadPartModel(const PartDefinition& part, const PartModelOptions& options) {
  part.Check();
  const auto start = std::chrono::steady_clock::now();
  PartModel out;
  out.part = part;
  if (!std::filesystem::is_regular_file(part.model_path)) SurfaceOf(part, &out);  // throws
  out.digest = PartModelDigest(part);
  out.cache_file = PartModelCacheFile(part, out.digest, options);
  if (!out.cache_file.empty() && std::filesystem::is_regular_file(out.cache_file)) {
    try {
      out.ppf = registration::PpfModel::Load(out.cache_file);
      out.from_cache = true;
    } catch (const InputError& e) {
      out.cache_note = std::string("cache file unreadable, rebuilt: ") + e.what();
    }
  }
  if (!out.from_cache || options.load_mesh) {
    const PointCloud samples = SurfaceOf(part, &out);
    if (!out.from_cache) {
      out.surface_points = samples.size();
      registration::PpfModelOptions model_options = part.model_options;
      model_options.threads = options.threads;
      out.ppf = registration::PpfModel::Build(samples, model_options);
      if (!out.cache_file.empty() && options.write_cache) {
        try {
          std::filesystem::create_directories(std::filesystem::path(out.cache_file).parent_path());
          out.ppf.Save(out.cache_file);
        } catch (const std::exception& e) {
          out.cache_note = std::string("model not cached: ") + e.what();
        }
      }
    }
    out.bounds = BoundsOf(out.mesh.vertices.positions);
  }
  if (out.bounds.isEmpty()) {
    const Eigen::Isometry3d& m = out.ppf.model_from_centered();
    for (const Eigen::Vector3d& p : out.ppf.refinement_points()) out.bounds.extend(m * p);
  }
  CheckGrasps(part, out.bounds);
  out.load_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace lasercell::localize
