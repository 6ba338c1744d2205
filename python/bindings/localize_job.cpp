// Localization jobs (localize/job.hpp, localize/job_run.hpp): lasercell.Job.load reads a job
// file (with its part files), lasercell.run_job runs it once on its profile file as
// `lasercell job run` does, and lasercell.JobRunner loads a job once and runs it on sweep after
// sweep. Results carry the part and grasp poses in the target frame (handling_base by default)
// as 4x4 arrays with 6x6 covariances, and the whole result file as a dict.
#include <pybind11/stl.h>

#include <memory>
#include <string>
#include <vector>

#include "docstrings.hpp"  // generated from the headers' /// comments
#include "localize/job.hpp"
#include "localize/job_run.hpp"
#include "python/bindings/bindings.hpp"

namespace lasercell::python {
namespace {

using localize::Job;
using localize::JobResult;
using localize::PartInstance;
using ResultPtr = std::shared_ptr<JobResult>;

localize::JobRunOptions RunOptions(int threads, bool load_meshes, const py::object& progress) {
  localize::JobRunOptions options;
  options.threads = threads;
  options.load_meshes = load_meshes;
  options.progress = ToProgress(progress);
  return options;
}

void BindJob(py::module_& m) {
  py::class_<Job>(m, "Job", LC_DOC(localize_Job))
      .def_static("load", &localize::ReadJobFile, py::arg("path"), LC_DOC(localize_ReadJobFile))
      .def_readonly("file", &Job::file, LC_DOC(localize_Job_file))
      .def_readonly("cell", &Job::cell, LC_DOC(localize_Job_cell))
      .def_readonly("camera", &Job::camera, LC_DOC(localize_Job_camera))
      .def_readonly("laser", &Job::laser, LC_DOC(localize_Job_laser))
      .def_readonly("profiles", &Job::profiles, LC_DOC(localize_Job_profiles))
      .def_readonly("target_frame", &Job::target_frame, LC_DOC(localize_Job_target_frame))
      .def_readonly("grasp_tolerance_mm", &Job::grasp_tolerance_mm,
                    LC_DOC(localize_Job_grasp_tolerance_mm))
      .def_property_readonly(
          "parts",
          [](const Job& job) {
            py::list parts;
            for (const localize::JobPart& p : job.parts) {
              parts.append(py::make_tuple(p.part.name, p.instances));
            }
            return parts;
          },
          "[(part name, instances to find)] in job order.")
      .def("__repr__", [](const Job& job) {
        return "<lasercell.Job " + job.file + ": " + std::to_string(job.parts.size()) +
               " part(s) in " + job.target_frame + ">";
      });
}

void BindInstance(py::module_& m) {
  py::class_<PartInstance>(m, "PartInstance", LC_DOC(localize_PartInstance))
      .def_readonly("part", &PartInstance::part, LC_DOC(localize_PartInstance_part))
      .def_readonly("frame", &PartInstance::frame, LC_DOC(localize_PartInstance_frame))
      .def_property_readonly(
          "target_from_part",
          [](const PartInstance& i) { return FromIsometry(i.target_from_part); }, "4x4, mm.")
      .def_property_readonly(
          "covariance", [](const PartInstance& i) { return FromMatrix(i.covariance); },
          "6x6 over [rotation vector (rad); translation (mm)]: the calibrated edges on the path "
          "and the fit; meaningful when covariance_valid.")
      .def_readonly("covariance_valid", &PartInstance::covariance_valid,
                    LC_DOC(localize_PartInstance_covariance_valid))
      .def_property_readonly(
          "grasps",
          [](const PartInstance& i) {
            py::dict grasps;
            for (const localize::GraspPose& g : i.grasps) {
              grasps[py::str(g.name)] = FromIsometry(g.target_from_grasp);
            }
            return grasps;
          },
          "{grasp name: 4x4 target_from_grasp} (the handling robot's gripper_tcp target).")
      .def_readonly("graspable", &PartInstance::graspable, LC_DOC(localize_PartInstance_graspable))
      .def_readonly("not_graspable_reason", &PartInstance::not_graspable_reason,
                    LC_DOC(localize_PartInstance_not_graspable_reason))
      .def_readonly("ambiguous", &PartInstance::ambiguous, LC_DOC(localize_PartInstance_ambiguous))
      .def_readonly("candidate", &PartInstance::candidate, LC_DOC(localize_PartInstance_candidate));
}

void BindResult(py::module_& m) {
  py::class_<JobResult, ResultPtr>(m, "JobResult", LC_DOC(localize_JobResult))
      .def_property_readonly(
          "instances", [](const JobResult& r) { return r.parts.instances; },
          "Found instances (PartInstance), in the order found.")
      .def_property_readonly(
          "all_found", [](const JobResult& r) { return r.parts.AllFound(); },
          "Every requested instance was found.")
      .def_property_readonly(
          "sweep",
          [](const ResultPtr& r) {
            return std::shared_ptr<triangulation::SweepResult>(r, &r->sweep);
          },
          "The sweep in the target frame (Sweep).")
      .def_readonly("notes", &JobResult::notes, LC_DOC(localize_JobResult_notes))
      .def("summary", &JobResult::Summary, LC_DOC(localize_JobResult_Summary))
      .def(
          "to_dict", [](const JobResult& r) { return JsonToPython(localize::JobResultJson(r)); },
          "The result file (format lasercell.localization_job) as a dict, as `lasercell job "
          "run --out` writes it (timings included).")
      .def(
          "cell_with_instances",
          [](const JobResult& r, const FrameGraph& cell) {
            return localize::CellWithInstances(cell, r);
          },
          py::arg("cell"), "A copy of cell with one static edge per found instance.")
      .def("__repr__",
           [](const JobResult& r) { return "<lasercell.JobResult " + r.Summary() + ">"; });
}

void BindRunner(py::module_& m) {
  py::class_<localize::JobRunner>(m, "JobRunner", LC_DOC(localize_JobRunner))
      .def(py::init([](const Job& job, int threads, bool load_meshes, const py::object& progress) {
             const localize::JobRunOptions options = RunOptions(threads, load_meshes, progress);
             py::gil_scoped_release release;
             return std::make_unique<localize::JobRunner>(job, options);
           }),
           py::arg("job"), py::arg("threads") = -1, py::arg("load_meshes") = false,
           py::arg("progress") = py::none())
      .def(
          "run",
          [](localize::JobRunner& runner, const triangulation::ProfileSet& profiles,
             const std::string& source_name) {
            py::gil_scoped_release release;
            return std::make_shared<JobResult>(runner.Run(profiles, source_name));
          },
          py::arg("profiles"), py::arg("source_name") = "python",
          "Localizes the job's parts in one sweep (a ProfileSet).")
      .def_property_readonly(
          "models",
          [](const localize::JobRunner& runner) {
            // Each shares the runner's models (read-only from Python: no setter is bound).
            const auto all =
                std::const_pointer_cast<std::vector<localize::PartModel>>(runner.shared_models());
            std::vector<std::shared_ptr<localize::PartModel>> models;
            for (localize::PartModel& model : *all) models.emplace_back(all, &model);
            return models;
          },
          "The loaded part models (PartModel), in job order.");
}

}  // namespace

void BindLocalizeJob(py::module_& m) {
  BindJob(m);
  BindInstance(m);
  BindResult(m);
  BindRunner(m);
  m.def(
      "run_job",
      [](const Job& job, int threads, bool load_meshes, const py::object& progress) {
        const localize::JobRunOptions options = RunOptions(threads, load_meshes, progress);
        py::gil_scoped_release release;
        return std::make_shared<JobResult>(localize::RunJob(job, options));
      },
      py::arg("job"), py::arg("threads") = -1, py::arg("load_meshes") = false,
      py::arg("progress") = py::none(),
      R"doc(Runs the job once on its profile file: profiles -> sweep in the target frame -> part
and grasp poses. threads >= 0 overrides the job's. progress(stage, fraction): "models",
"profiles", "triangulation", then the searches. Parts not found are in the result; a cell,
camera, laser plane, profile file or model that cannot be used raises FileError/InputError.)doc");
}

}  // namespace lasercell::python
