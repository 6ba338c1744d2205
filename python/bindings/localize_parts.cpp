// Localizing parts in a cloud a Python program already holds (localize/localize_parts.hpp,
// localize/part_model.hpp): lasercell.load_part_model turns a part file into its PPF model
// (cached as the job caches it), lasercell.localize_parts finds the requested parts and
// instances in a scene in the target frame with the job's judgement (grasp tolerance, RMSE
// gate, support plane, ambiguity), and lasercell.lines_of_sight gives a sweep's per-point
// directions toward the sensor.
#include "localize/localize_parts.hpp"

#include <pybind11/stl.h>

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "docstrings.hpp"  // generated from the headers' /// comments
#include "localize/job_run.hpp"
#include "localize/part_model.hpp"
#include "python/bindings/bindings.hpp"

namespace lasercell::python {
namespace {

using localize::LocalizePartsResult;
using localize::PartModel;
using ModelPtr = std::shared_ptr<PartModel>;
using ResultPtr = std::shared_ptr<LocalizePartsResult>;

void BindPartModel(py::module_& m) {
  py::class_<PartModel, ModelPtr>(m, "PartModel", LC_DOC(localize_PartModel))
      .def_readonly("part", &PartModel::part, LC_DOC(localize_PartModel_part))
      .def_property_readonly(
          "ppf",
          [](const ModelPtr& p) { return std::shared_ptr<registration::PpfModel>(p, &p->ppf); },
          "The PPF model (PpfModel).")
      .def_property_readonly(
          "mesh", [](const ModelPtr& p) { return std::shared_ptr<TriangleMesh>(p, &p->mesh); },
          "Part frame, mm (empty when not loaded).")
      .def_readonly("digest", &PartModel::digest, LC_DOC(localize_PartModel_digest))
      .def_readonly("cache_file", &PartModel::cache_file, LC_DOC(localize_PartModel_cache_file))
      .def_readonly("from_cache", &PartModel::from_cache, LC_DOC(localize_PartModel_from_cache))
      .def_readonly("cache_note", &PartModel::cache_note, LC_DOC(localize_PartModel_cache_note))
      .def_readonly("load_ms", &PartModel::load_ms, LC_DOC(localize_PartModel_load_ms))
      .def_readonly("surface_points", &PartModel::surface_points,
                    LC_DOC(localize_PartModel_surface_points))
      .def_readonly("source_format", &PartModel::source_format,
                    LC_DOC(localize_PartModel_source_format))
      .def_readonly("source_unit", &PartModel::source_unit, LC_DOC(localize_PartModel_source_unit))
      .def("summary", &localize::PartModelSummary, LC_DOC(localize_PartModelSummary))
      .def("__repr__", [](const PartModel& p) {
        return "<lasercell.PartModel " + p.part.name + (p.from_cache ? " (cached)>" : ">");
      });
  m.def(
      "load_part_model",
      [](const localize::PartDefinition& part, bool use_cache, const std::string& cache_dir,
         bool load_mesh, int threads) {
        localize::PartModelOptions options;
        options.use_cache = use_cache;
        options.write_cache = use_cache;
        options.cache_dir = cache_dir;
        options.load_mesh = load_mesh;
        options.threads = threads;
        py::gil_scoped_release release;
        return std::make_shared<PartModel>(localize::LoadPartModel(part, options));
      },
      py::arg("part"), py::arg("use_cache") = true, py::arg("cache_dir") = "",
      py::arg("load_mesh") = true, py::arg("threads") = 0, LC_DOC(localize_LoadPartModel) R"doc(

In Python: the model comes from the cache (<cache_dir>/<name>-<digest>.ppfm; "" = the part
file's folder + "/.lasercell-cache") when the model file, unit, sampling and options are
unchanged, as in a job; use_cache=False builds it and writes nothing.)doc");
}

void BindPartsResult(py::module_& m) {
  py::class_<localize::PartSearch>(m, "PartSearch", LC_DOC(localize_PartSearch))
      .def_readonly("part", &localize::PartSearch::part, LC_DOC(localize_PartSearch_part))
      .def_readonly("requested", &localize::PartSearch::requested,
                    LC_DOC(localize_PartSearch_requested))
      .def_readonly("found", &localize::PartSearch::found, LC_DOC(localize_PartSearch_found))
      .def_readonly("message", &localize::PartSearch::message, LC_DOC(localize_PartSearch_message))
      .def_readonly("rejected", &localize::PartSearch::rejected,
                    LC_DOC(localize_PartSearch_rejected))
      .def(
          "to_dict",
          [](const localize::PartSearch& s) { return JsonToPython(localize::PartSearchJson(s)); },
          LC_DOC(localize_PartSearchJson));
  py::class_<LocalizePartsResult, ResultPtr>(m, "LocalizePartsResult",
                                             LC_DOC(localize_LocalizePartsResult))
      .def_readonly("instances", &LocalizePartsResult::instances,
                    LC_DOC(localize_LocalizePartsResult_instances))
      .def_readonly("searches", &LocalizePartsResult::searches,
                    LC_DOC(localize_LocalizePartsResult_searches))
      .def_readonly("sweep_points", &LocalizePartsResult::sweep_points,
                    LC_DOC(localize_LocalizePartsResult_sweep_points))
      .def_readonly("roi_points", &LocalizePartsResult::roi_points,
                    LC_DOC(localize_LocalizePartsResult_roi_points))
      .def_readonly("normal_points", &LocalizePartsResult::normal_points,
                    LC_DOC(localize_LocalizePartsResult_normal_points))
      .def_property_readonly("all_found", &LocalizePartsResult::AllFound,
                             LC_DOC(localize_LocalizePartsResult_AllFound))
      .def_property_readonly(
          "timings_ms",
          [](const LocalizePartsResult& r) {
            py::dict t;
            t["roi"] = r.timings.roi_ms;
            t["normals"] = r.timings.normals_ms;
            t["searches"] = r.timings.searches_ms;
            t["total"] = r.timings.total_ms;
            return t;
          },
          "Wall time of the ROI, normals, searches and in total, ms.");
}

// (part model, instances) pairs from a list of PartModel or (PartModel, count) items; the
// models (their own or a JobRunner's) stay referenced by `keep` while the call runs.
std::vector<localize::PartRequest> Requests(const py::list& parts, std::vector<py::object>* keep) {
  std::vector<localize::PartRequest> requests;
  for (const py::handle& item : parts) {
    int instances = 1;
    py::object model = py::reinterpret_borrow<py::object>(item);
    if (py::isinstance<py::tuple>(item)) {
      const py::tuple pair = item.cast<py::tuple>();
      if (pair.size() != 2) ThrowInput("parts: a tuple must be (PartModel, instances)");
      model = pair[0];
      instances = pair[1].cast<int>();
    }
    if (!py::isinstance<PartModel>(model)) {
      throw py::type_error("parts: expected PartModel or (PartModel, instances) items");
    }
    if (instances < 1) ThrowInput("parts: instances must be >= 1");
    keep->push_back(model);
    requests.push_back({&model.cast<const PartModel&>(), instances});
  }
  if (requests.empty()) ThrowInput("parts: give at least one PartModel");
  return requests;
}

LocalizePartsResult LocalizeParts(const PointCloud& scene, const py::list& parts,
                                  const py::object& line_of_sight, const py::object& roi,
                                  const py::object& options, double grasp_tolerance_mm,
                                  double scan_noise_mm, double max_rmse_factor, int threads,
                                  const py::object& progress) {
  localize::LocalizePartsOptions o;
  if (!roi.is_none()) {
    if (!py::isinstance<py::sequence>(roi) || py::len(roi) != 2) {
      ThrowInput("roi: expected (min_xyz, max_xyz) in mm");
    }
    const py::sequence box = roi.cast<py::sequence>();
    o.use_roi = true;
    o.roi = BoundingBox{ToVector3(box[0], "roi[0]"), ToVector3(box[1], "roi[1]")};
  }
  o.localize = SettingsFromDict(options, "options").localize;
  o.grasp_tolerance_mm = grasp_tolerance_mm;
  o.scan_noise_mm = scan_noise_mm;
  o.max_rmse_factor = max_rmse_factor;
  o.threads = threads;
  o.progress = ToProgress(progress);
  std::vector<Eigen::Vector3d> sight;
  if (!line_of_sight.is_none()) sight = ToVector3Rows(line_of_sight, "line_of_sight");
  std::vector<py::object> keep;
  const std::vector<localize::PartRequest> requests = Requests(parts, &keep);
  py::gil_scoped_release release;
  return localize::LocalizeParts(scene, sight, requests, o);
}

}  // namespace

void BindLocalizeParts(py::module_& m) {
  BindPartModel(m);
  BindPartsResult(m);
  m.def(
      "localize_parts",
      [](const PointCloud& scene, const py::list& parts, const py::object& line_of_sight,
         const py::object& roi, const py::object& options, double grasp_tolerance_mm,
         double scan_noise_mm, double max_rmse_factor, int threads, const py::object& progress) {
        return std::make_shared<LocalizePartsResult>(
            LocalizeParts(scene, parts, line_of_sight, roi, options, grasp_tolerance_mm,
                          scan_noise_mm, max_rmse_factor, threads, progress));
      },
      py::arg("scene"), py::arg("parts"), py::arg("line_of_sight") = py::none(),
      py::arg("roi") = py::none(), py::arg("options") = py::none(),
      py::arg("grasp_tolerance_mm") = 10.0, py::arg("scan_noise_mm") = 0.1,
      py::arg("max_rmse_factor") = 5.0, py::arg("threads") = 0, py::arg("progress") = py::none(),
      LC_DOC(localize_LocalizeParts) R"doc(

In Python, as a job does after triangulation: each part's search (localize_in_cloud), instances in turn with the points an
accepted instance explains removed, then the job's judgement: grasp poses, graspable within
grasp_tolerance_mm, ICP RMSE gate max_rmse_factor x scan_noise_mm, ambiguity.

parts: PartModel items or (PartModel, instances) tuples. line_of_sight: (N, 3) unit vectors from
each point toward the sensor (lines_of_sight(sweep)); None = straight up (+z). roi: (min_xyz,
max_xyz) in the target frame. options: a dict of localize options-file keys. The pose
covariances hold the fit only: the calibrated edges and the laser plane are a job's (run_job).
InputError for an empty scene, an ROI holding no point or sizes that disagree.)doc");
  m.def(
      "lines_of_sight",
      [](const triangulation::SweepResult& sweep) {
        return RowsArray(localize::LinesOfSight(sweep));
      },
      py::arg("sweep"), LC_DOC(localize_LinesOfSight) " Returned as an (N, 3) array.");
}

}  // namespace lasercell::python
