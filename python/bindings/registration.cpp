// lasercell.PpfModel and lasercell.localize_in_cloud: the PPF model (registration/ppf_model.hpp)
// built from a cloud or loaded from a .ppfm, and the seven localization steps of
// registration/localize_in_cloud.hpp on a scene. Options are dicts with the keys of the localize
// options file (README, "Localize options"), read by that file's reader; poses are 4x4 float64
// arrays scene_from_model, mm. Long calls release the GIL and take a progress callback.
#include <pybind11/stl.h>

#include <chrono>
#include <memory>
#include <string>

#include "core/error.hpp"
#include "docstrings.hpp"  // generated from the headers' /// comments
#include "python/bindings/bindings.hpp"
#include "registration/localization_json.hpp"
#include "registration/localize_in_cloud.hpp"
#include "registration/localize_options_io.hpp"
#include "registration/ppf_model.hpp"

namespace lasercell::python {
namespace {

using registration::LocalizationCandidate;
using registration::LocalizationResult;
using registration::PpfModel;
using ModelPtr = std::shared_ptr<PpfModel>;
using ResultPtr = std::shared_ptr<LocalizationResult>;

// PpfModelOptions from a dict of the options file's `model:` keys (None: the defaults).
registration::PpfModelOptions ModelOptions(const py::object& options) {
  if (options.is_none()) return {};
  py::dict wrapped;
  wrapped["model"] = options;
  return SettingsFromDict(wrapped, "options").model;
}

// The settings of `options`: a dict of options-file keys, a path to an options file, or None.
registration::LocalizeSettings Settings(const py::object& options) {
  if (py::isinstance<py::str>(options)) {
    return registration::ReadLocalizeOptions(options.cast<std::string>());
  }
  return SettingsFromDict(options, "options");
}

void BindModel(py::module_& m) {
  py::class_<PpfModel, ModelPtr>(m, "PpfModel", LC_DOC(registration_PpfModel) R"doc(

Build it once from a model cloud with normals (or load a .ppfm) and localize it in many scenes.
Stored geometry is in the model's centred frame: p_model = model_from_centered @ p_centered.)doc")
      .def_static(
          "build",
          [](const PointCloud& cloud, const py::object& options) {
            const registration::PpfModelOptions o = ModelOptions(options);
            py::gil_scoped_release release;
            return std::make_shared<PpfModel>(PpfModel::Build(cloud, o));
          },
          py::arg("cloud"), py::arg("options") = py::none(),
          "Builds from a cloud (normals estimated when absent). options: the `model:` keys of a "
          "localize options file, e.g. {'sampling_step_relative': 0.04}.")
      .def_static(
          "load",
          [](const std::string& path) {
            py::gil_scoped_release release;
            return std::make_shared<PpfModel>(PpfModel::Load(path));
          },
          py::arg("path"), "Reads a .ppfm; FileError/InputError naming the problem.")
      .def_static(
          "load_or_build",
          [](const std::string& path, const py::object& options) {
            const registration::PpfModelOptions o = ModelOptions(options);
            py::gil_scoped_release release;
            return std::make_shared<PpfModel>(registration::LoadOrBuildModel(path, o));
          },
          py::arg("path"), py::arg("options") = py::none(),
          "A .ppfm is loaded; a PLY mesh or cloud or a PCD cloud is built with options.")
      .def(
          "save",
          [](const PpfModel& model, const std::string& path) {
            py::gil_scoped_release release;
            model.Save(path);
          },
          py::arg("path"), "Writes a .ppfm atomically.")
      .def_property_readonly("diameter_mm", &PpfModel::diameter_mm,
                             LC_DOC(registration_PpfModel_diameter_mm))
      .def_property_readonly("sampling_step_mm", &PpfModel::sampling_step_mm,
                             LC_DOC(registration_PpfModel_sampling_step_mm))
      .def_property_readonly("distance_step_mm", &PpfModel::distance_step_mm,
                             LC_DOC(registration_PpfModel_distance_step_mm))
      .def_property_readonly("angle_step_rad", &PpfModel::angle_step_rad,
                             LC_DOC(registration_PpfModel_angle_step_rad))
      .def_property_readonly("pair_count", &PpfModel::pair_count,
                             LC_DOC(registration_PpfModel_pair_count))
      .def_property_readonly("key_count", &PpfModel::key_count,
                             LC_DOC(registration_PpfModel_key_count))
      .def_property_readonly(
          "points",
          [](const py::object& self) {
            return Vector3View(self.cast<const PpfModel&>().points(), self);
          },
          "(M, 3) sampled points, centred frame, mm (read-only view).")
      .def_property_readonly(
          "normals",
          [](const py::object& self) {
            return Vector3View(self.cast<const PpfModel&>().normals(), self);
          },
          "(M, 3) unit normals of points.")
      .def_property_readonly(
          "refinement_points",
          [](const py::object& self) {
            return Vector3View(self.cast<const PpfModel&>().refinement_points(), self);
          },
          "(R, 3) denser points for verification and ICP, centred frame, mm.")
      .def_property_readonly(
          "model_from_centered",
          [](const PpfModel& model) { return FromIsometry(model.model_from_centered()); },
          "4x4: " LC_DOC(registration_PpfModel_model_from_centered))
      .def_property_readonly(
          "principal_variances",
          [](const PpfModel& model) {
            const Eigen::Vector3d& v = model.principal_variances();
            return py::array_t<double>(3, v.data());
          },
          "(3,) variances of the sampled points along their principal axes, mm^2, descending.")
      .def("summary", &PpfModel::Summary, LC_DOC(registration_PpfModel_Summary))
      .def("__repr__",
           [](const PpfModel& model) { return "<lasercell.PpfModel " + model.Summary() + ">"; });
}

void BindCandidate(py::module_& m) {
  py::class_<LocalizationCandidate>(m, "LocalizationCandidate",
                                    LC_DOC(registration_LocalizationCandidate))
      .def_readonly("rank", &LocalizationCandidate::rank,
                    LC_DOC(registration_LocalizationCandidate_rank))
      .def_property_readonly(
          "scene_from_model",
          [](const LocalizationCandidate& c) { return FromIsometry(c.scene_from_model); },
          "4x4 float64, mm: the final pose.")
      .def_property_readonly(
          "coarse_scene_from_model",
          [](const LocalizationCandidate& c) { return FromIsometry(c.coarse_scene_from_model); },
          "4x4 float64: the pose from clustering, before ICP.")
      .def_property_readonly(
          "covariance", [](const LocalizationCandidate& c) { return FromMatrix(c.covariance); },
          "6x6 over [rotation vector (rad); translation (mm)], left perturbation in the scene "
          "frame; meaningful only when covariance_valid.")
      .def_readonly("covariance_valid", &LocalizationCandidate::covariance_valid,
                    LC_DOC(registration_LocalizationCandidate_covariance_valid))
      .def_readonly("votes", &LocalizationCandidate::votes,
                    LC_DOC(registration_LocalizationCandidate_votes))
      .def_readonly("score", &LocalizationCandidate::score,
                    LC_DOC(registration_LocalizationCandidate_score))
      .def_readonly("cluster_members", &LocalizationCandidate::cluster_members,
                    LC_DOC(registration_LocalizationCandidate_cluster_members))
      .def_property_readonly(
          "support", [](const LocalizationCandidate& c) { return c.verification.support; },
          "Fraction of the visible model cells with scene points nearby, after ICP.")
      .def_property_readonly(
          "coarse_support",
          [](const LocalizationCandidate& c) { return c.coarse_verification.support; },
          LC_DOC(registration_VerificationResult_support))
      .def_readonly("icp_run", &LocalizationCandidate::icp_run,
                    LC_DOC(registration_LocalizationCandidate_icp_run))
      .def_property_readonly(
          "icp_rmse_mm", [](const LocalizationCandidate& c) { return c.icp.rmse_mm; },
          LC_DOC(registration_IcpResult_rmse_mm))
      .def_property_readonly(
          "icp_iterations", [](const LocalizationCandidate& c) { return c.icp.iterations; },
          LC_DOC(registration_IcpResult_iterations))
      .def_readonly("rejection_reason", &LocalizationCandidate::rejection_reason,
                    LC_DOC(registration_LocalizationCandidate_rejection_reason))
      .def(
          "to_dict",
          [](const LocalizationCandidate& c) {
            return JsonToPython(registration::LocalizationCandidateJson(c));
          },
          "The candidate as the result file writes it.");
}

void BindResult(py::module_& m) {
  py::class_<LocalizationResult, ResultPtr>(m, "LocalizationResult",
                                            LC_DOC(registration_LocalizationResult))
      .def_readonly("found", &LocalizationResult::found,
                    LC_DOC(registration_LocalizationResult_found))
      .def_readonly("candidates", &LocalizationResult::candidates,
                    LC_DOC(registration_LocalizationResult_candidates))
      .def_readonly("rejected", &LocalizationResult::rejected,
                    LC_DOC(registration_LocalizationResult_rejected))
      .def_readonly("ambiguous", &LocalizationResult::ambiguous,
                    LC_DOC(registration_LocalizationResult_ambiguous))
      .def_readonly("ambiguity_reason", &LocalizationResult::ambiguity_reason,
                    LC_DOC(registration_LocalizationResult_ambiguity_reason))
      .def_readonly("message", &LocalizationResult::message,
                    LC_DOC(registration_LocalizationResult_message))
      .def_property_readonly(
          "timings_ms",
          [](const LocalizationResult& r) {
            return JsonToPython(registration::LocalizationTimingsJson(r.timings, 0.0));
          },
          "Wall time per stage, ms (model_build_or_load is 0 here).")
      .def_property_readonly(
          "counts",
          [](const LocalizationResult& r) {
            return JsonToPython(registration::LocalizationCountsJson(r));
          },
          "Points per stage, pairs, votes, hypotheses, clusters.")
      .def("summary", &LocalizationResult::Summary, LC_DOC(registration_LocalizationResult_Summary))
      .def(
          "to_dict",
          [](const LocalizationResult& r, const std::string& model, const std::string& scene,
             double model_ms) {
            return JsonToPython(registration::LocalizationResultJson(r, {model, scene}, model_ms));
          },
          py::arg("model") = "", py::arg("scene") = "", py::arg("model_ms") = 0.0,
          "The result file (format lasercell.localization) as a dict, as `lasercell localize "
          "--out` writes it.")
      .def("__repr__", [](const LocalizationResult& r) {
        return "<lasercell.LocalizationResult " + r.Summary() + ">";
      });
}

}  // namespace

void BindRegistration(py::module_& m) {
  BindModel(m);
  BindCandidate(m);
  BindResult(m);
  m.def(
      "localize_in_cloud",
      [](const PointCloud& scene, const py::object& model, const py::object& options,
         const py::object& progress) {
        registration::LocalizeSettings settings = Settings(options);
        settings.localize.progress = ToProgress(progress);
        ModelPtr ppf;
        const PointCloud* model_cloud = nullptr;
        if (py::isinstance<PpfModel>(model)) {
          ppf = model.cast<ModelPtr>();
        } else if (py::isinstance<PointCloud>(model)) {
          model_cloud = &model.cast<const PointCloud&>();
        } else {
          throw py::type_error("model: expected a lasercell.PpfModel or a lasercell.PointCloud");
        }
        py::gil_scoped_release release;
        if (ppf) {
          return std::make_shared<LocalizationResult>(
              registration::LocalizeInCloud(scene, *ppf, settings.localize));
        }
        return std::make_shared<LocalizationResult>(
            registration::LocalizeInCloud(scene, *model_cloud, settings.model, settings.localize));
      },
      py::arg("scene"), py::arg("model"), py::arg("options") = py::none(),
      py::arg("progress") = py::none(), R"doc(Localizes model in scene (PPF voting, clustering,
verification, ICP; Skotheim et al. 2012, section IV).

scene: a PointCloud (normals estimated toward the viewpoint when absent). model: a PpfModel, or
a PointCloud built into one with options['model']. options: a dict of localize options-file
keys (e.g. {'threads': 1, 'max_instances': 2, 'viewpoint_mm': [0, 0, 0]}) or the path of such a
file. progress(stage, fraction) is called after each stage. "Not found" is a result
(found == False), not an exception; bad options raise lasercell.OptionError naming the field.)doc");

  // For the binding-overhead benchmark (python/bench/bench_bindings.py): the C++ call alone,
  // timed in C++ around LocalizeInCloud with the same inputs, one run per call.
  m.def(
      "_time_localize_in_cloud_ms",
      [](const PointCloud& scene, const ModelPtr& model, const py::object& options) {
        const registration::LocalizeSettings settings = Settings(options);
        py::gil_scoped_release release;
        const auto start = std::chrono::steady_clock::now();
        const LocalizationResult result =
            registration::LocalizeInCloud(scene, *model, settings.localize);
        const auto stop = std::chrono::steady_clock::now();
        return std::chrono::duration<double, std::milli>(stop - start).count();
      },
      py::arg("scene"), py::arg("model"), py::arg("options") = py::none());
}

}  // namespace lasercell::python
