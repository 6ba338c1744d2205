#include "localize/job_report.hpp"

#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include "core/format.hpp"
#include "core/html_scene3d.hpp"

namespace lasercell::localize {
namespace {

std::string Triple(const Eigen::Vector3d& v, int digits = 2) {
  return FormatFixed(v.x(), digits) + ", " + FormatFixed(v.y(), digits) + ", " +
         FormatFixed(v.z(), digits);
}

// 1-sigma of the rotation (deg) and translation (mm) parts of a 6x6 covariance.
std::string SigmaText(const Matrix6d& cov) {
  Eigen::Vector3d r, t;
  for (int k = 0; k < 3; ++k) {
    r[k] = std::sqrt(std::max(0.0, cov(k, k))) * 180.0 / std::numbers::pi;
    t[k] = std::sqrt(std::max(0.0, cov(k + 3, k + 3)));
  }
  return Triple(t, 3) + " mm / " + Triple(r, 3) + " deg";
}

void AddInstances(const JobResult& result, report::HtmlReport* report) {
  const std::string& target = result.job.target_frame;
  report->AddHeading("Part instances in " + target);
  std::vector<std::vector<std::string>> rows, grasps;
  for (const PartInstance& inst : result.parts.instances) {
    rows.push_back({inst.frame, Triple(inst.target_from_part.translation()),
                    PoseToFileNotation(inst.target_from_part),
                    inst.covariance_valid ? SigmaText(inst.covariance) : "unavailable",
                    FormatFixed(inst.candidate.verification.support, 3),
                    inst.candidate.icp_run ? FormatFixed(inst.candidate.icp.rmse_mm, 3) : "-",
                    inst.graspable ? "yes" : "no: " + inst.not_graspable_reason,
                    inst.ambiguous ? inst.ambiguity_reason : "no"});
    for (const GraspPose& g : inst.grasps) {
      grasps.push_back({inst.frame + "." + g.name, Triple(g.target_from_grasp.translation()),
                        PoseToFileNotation(g.target_from_grasp),
                        FormatFixed(g.position_sigma_mm, 3), g.within_tolerance ? "yes" : "no"});
    }
  }
  if (rows.empty()) {
    report->AddWarning("no part instance was found");
  } else {
    report->AddTable({"instance", "position (mm)", target + "_from_part", "1-sigma (t / r)",
                      "support", "ICP RMSE (mm)", "graspable", "ambiguous"},
                     rows);
  }
  if (!grasps.empty()) {
    report->AddHeading("Grasp frames (gripper_tcp targets)");
    report->AddTable({"grasp", "position (mm)", target + "_from_grasp", "position 1-sigma (mm)",
                      "3-sigma within " + FormatFixed(result.job.grasp_tolerance_mm, 1) + " mm"},
                     grasps);
  }
  for (const PartSearch& s : result.parts.searches) {
    if (s.found < s.requested) {
      report->AddWarning(s.part + ": " + std::to_string(s.found) + " of " +
                         std::to_string(s.requested) + " found: " + s.message);
    }
  }
}

void AddModelsAndTimings(const JobResult& result, report::HtmlReport* report) {
  report->AddHeading("Part models");
  std::vector<std::vector<std::string>> rows;
  for (const PartModel& m : *result.models) {
    rows.push_back({m.part.name, m.part.model_path, m.source_format + " (" + m.source_unit + ")",
                    std::to_string(m.ppf.points().size()), FormatFixed(m.ppf.diameter_mm(), 1),
                    m.from_cache ? "cache" : "built", FormatFixed(m.load_ms, 1)});
  }
  report->AddTable({"part", "model", "format", "PPF points", "diameter (mm)", "source", "ms"},
                   rows);
  const JobTimings& t = result.timings;
  report->AddBars(
      "Time per stage",
      {"setup", "models", "profiles", "triangulation", "roi", "normals", "searches"},
      {t.setup_ms, t.models_ms, t.profiles_ms, t.triangulation_ms, result.parts.timings.roi_ms,
       result.parts.timings.normals_ms, result.parts.timings.searches_ms},
      "ms");
  for (const std::string& note : result.notes) report->AddParagraph("Note: " + note);
}

// The sweep (decimated), each posed part mesh, its grasp frames and the ROI.
report::Scene3d SceneOf(const JobResult& result) {
  report::Scene3d scene;
  scene.title = "Sweep and found parts in " + result.job.target_frame;
  report::Scene3dPoints sweep;
  sweep.name = "sweep (" + std::to_string(result.sweep.cloud.size()) + " points)";
  sweep.positions.reserve(result.sweep.cloud.size());
  for (const Eigen::Vector3d& p : result.sweep.cloud.positions)
    sweep.positions.push_back(p.cast<float>());
  sweep.max_points = 150000;
  scene.points.push_back(std::move(sweep));
  static constexpr std::array<std::array<float, 3>, 4> kColours = {
      {{0.85f, 0.45f, 0.15f}, {0.2f, 0.6f, 0.85f}, {0.3f, 0.75f, 0.3f}, {0.8f, 0.3f, 0.6f}}};
  std::size_t k = 0;
  for (const PartInstance& inst : result.parts.instances) {
    const PartModel* model = nullptr;
    for (const PartModel& m : *result.models) {
      if (m.part.name == inst.part) model = &m;
    }
    if (model != nullptr && !model->mesh.faces.empty()) {
      report::Scene3dMesh mesh;
      mesh.name = inst.frame + (inst.graspable ? "" : " (not graspable)");
      for (const Eigen::Vector3d& v : model->mesh.vertices.positions) {
        mesh.vertices.push_back(v.cast<float>());
      }
      mesh.faces = model->mesh.faces;
      mesh.world_from_mesh = inst.target_from_part;
      mesh.rgb = kColours[k++ % kColours.size()];
      mesh.opacity = 0.8f;
      scene.meshes.push_back(std::move(mesh));
    }
    for (const GraspPose& g : inst.grasps) {
      report::Scene3dFrame frame;
      frame.name = inst.frame + "." + g.name;
      frame.world_from_frame = g.target_from_grasp;
      frame.axis_length_mm = 40.0f;
      scene.frames.push_back(frame);
    }
  }
  if (result.job.use_roi) {
    report::Scene3dBox roi;
    roi.name = "region of interest";
    roi.min_mm = result.job.roi.min;
    roi.max_mm = result.job.roi.max;
    scene.boxes.push_back(roi);
  }
  return scene;
}

}  // namespace

report::HtmlReport JobReport(const JobResult& result) {
  report::HtmlReport report("lasercell job: " + result.job.file);
  report.AddKeyValues({{"job", result.job.file},
                       {"result", result.Summary()},
                       {"source", result.source},
                       {"sweep", result.sweep.Summary()},
                       {"laser plane", result.laser_plane_source},
                       {"target frame", result.job.target_frame}});
  report.Add3dView(SceneOf(result));
  AddInstances(result, &report);
  AddModelsAndTimings(result, &report);
  return report;
}

}  // namespace lasercell::localize
