#include "localize/job.hpp"

#include <cmath>
#include <filesystem>

#include "core/error.hpp"
#include "core/yaml_fields.hpp"

namespace lasercell::localize {
namespace {

std::string Resolve(const std::string& job_file, const std::string& path) {
  const std::filesystem::path p(path);
  if (p.is_absolute() || job_file.empty()) return path;
  return (std::filesystem::path(job_file).parent_path() / p).string();
}

void ReadSourceAndTrajectory(yaml::Fields& r, Job* job) {
  yaml::Fields source = r.Sub("source");
  if (!r.Has("source")) r.Fail("source", "is required: give {file: PROFILES.lcp}");
  source.ReadRequired("file", &job->profiles);
  source.Done();
  job->profiles = Resolve(job->file, job->profiles);

  if (!r.Has("trajectory")) {
    r.Fail("trajectory", "is required: give {linear: linear_sweep.yaml} or {robot: ROBOT}");
  }
  yaml::Fields t = r.Sub("trajectory");
  const bool linear = t.Read("linear", &job->linear_record);
  job->robot_trajectory = t.Has("robot");
  if (job->robot_trajectory) t.Read("robot", &job->robot);
  t.Known("robot");
  t.Done();
  if (linear == job->robot_trajectory) {
    r.Fail("trajectory", "must name exactly one of 'linear' (a linear-axis record) and 'robot'");
  }
  if (linear) job->linear_record = Resolve(job->file, job->linear_record);
}

void ReadGeometry(yaml::Fields& r, Job* job) {
  r.Read("target_frame", &job->target_frame);
  if (r.Has("roi")) {
    job->use_roi = true;
    yaml::Fields roi = r.Sub("roi");
    roi.ReadRequired("min_mm", &job->roi.min);
    roi.ReadRequired("max_mm", &job->roi.max);
    roi.Done();
    for (int k = 0; k < 3; ++k) {
      if (!(job->roi.max[k] > job->roi.min[k])) {
        roi.Fail("max_mm", "must exceed min_mm on every axis (the box is empty along " +
                               std::string(1, "xyz"[k]) + ")");
      }
    }
  }
  r.Known("roi");
  if (r.Has("support_plane")) {
    job->support.enabled = true;
    yaml::Fields s = r.Sub("support_plane");
    s.ReadRequired("normal", &job->support.normal);
    s.Read("offset_mm", &job->support.offset_mm);
    s.Read("max_penetration_mm", &job->support.max_penetration_mm);
    s.Done();
    if (std::abs(job->support.normal.norm() - 1.0) > 1e-6) {
      s.Fail("normal", "must be a unit vector (toward free space)");
    }
  }
  r.Known("support_plane");
}

void ReadParts(yaml::Fields& r, Job* job) {
  if (!r.Has("parts")) r.Fail("parts", "is required: list the parts to look for");
  std::vector<yaml::Fields> parts = r.List("parts");
  if (parts.empty()) r.Fail("parts", "is empty: list at least one {part: PART.yaml}");
  for (yaml::Fields& p : parts) {
    JobPart part;
    p.ReadRequired("part", &part.file);
    p.Read("instances", &part.instances);
    p.Done();
    if (part.instances < 1) p.Fail("instances", "must be >= 1");
    part.file = Resolve(job->file, part.file);
    part.part = ReadPartFile(part.file);
    for (const JobPart& other : job->parts) {
      if (other.part.name == part.part.name) {
        p.Fail("part", "names part '" + part.part.name + "' a second time (" + other.file +
                           "); give one entry with instances: N");
      }
    }
    job->parts.push_back(std::move(part));
  }
}

Job FromFields(yaml::Fields r, const std::string& path) {
  Job job;
  job.file = path;
  r.RequireFormat(kJobFormat, kJobFormatVersion, "is this a lasercell job file?");
  r.Known({"cell", "camera", "laser", "source", "trajectory", "target_frame", "roi",
           "support_plane", "parts", "grasp_tolerance_mm", "scan_noise_mm", "max_rmse_factor",
           "threads", "model_cache", "localize", "localize_options"});
  r.Done();  // a misspelt key is reported before the problems it causes
  r.ReadRequired("cell", &job.cell);
  job.cell = Resolve(path, job.cell);
  r.ReadRequired("camera", &job.camera);
  job.camera = Resolve(path, job.camera);
  r.Read("laser", &job.laser);
  ReadSourceAndTrajectory(r, &job);
  ReadGeometry(r, &job);
  r.Read("grasp_tolerance_mm", &job.grasp_tolerance_mm);
  r.Read("scan_noise_mm", &job.scan_noise_mm);
  r.Read("max_rmse_factor", &job.max_rmse_factor);
  r.Read("threads", &job.threads);
  if (r.Read("model_cache", &job.model_cache)) job.model_cache = Resolve(path, job.model_cache);
  if (r.Has("localize") && r.Has("localize_options")) {
    r.Fail("localize_options", "and 'localize' are both given; give one of them");
  }
  if (r.Has("localize")) job.settings = registration::LocalizeSettingsFromFields(r.Sub("localize"));
  std::string options_file;
  if (r.Read("localize_options", &options_file)) {
    job.settings = registration::ReadLocalizeOptions(Resolve(path, options_file));
  }
  ReadParts(r, &job);
  job.Check();
  return job;
}

}  // namespace

void Job::Check() const {
  const std::string where = file.empty() ? std::string("job") : file;
  const auto fail = [&](const std::string& field, const std::string& problem) {
    throw OptionError(where + ": field '" + field + "' " + problem);
  };
  if (cell.empty()) fail("cell", "is empty: name the cell.yaml");
  if (camera.empty()) fail("camera", "is empty: name the .cameramodel");
  if (profiles.empty()) fail("source.file", "is empty: name the profile file");
  if (target_frame.empty()) fail("target_frame", "is empty");
  if (parts.empty()) fail("parts", "is empty: list at least one part");
  if (!(grasp_tolerance_mm > 0.0)) fail("grasp_tolerance_mm", "must be > 0 (mm)");
  if (!(scan_noise_mm > 0.0)) fail("scan_noise_mm", "must be > 0 (mm)");
  if (!(max_rmse_factor >= 1.0)) fail("max_rmse_factor", "must be >= 1");
  if (threads < 0) fail("threads", "must be >= 0 (0 = all cores)");
  if (use_roi) {
    for (int k = 0; k < 3; ++k) {
      if (!(roi.max[k] > roi.min[k])) fail("roi", "is empty: max_mm must exceed min_mm");
    }
  }
  if (support.enabled && std::abs(support.normal.norm() - 1.0) > 1e-6) {
    fail("support_plane.normal", "must be a unit vector");
  }
  for (const JobPart& p : parts) {
    if (p.instances < 1) fail("parts", "instances of '" + p.part.name + "' must be >= 1");
  }
  try {
    settings.localize.Check();
    settings.model.Check();
  } catch (const OptionError& e) {
    throw OptionError(where + ": localize options: " + e.what());
  }
}

Job ParseJobFile(const std::string& text, const std::string& path) {
  return FromFields(yaml::Fields::Parse(text, path), path);
}

Job ReadJobFile(const std::string& path) { return FromFields(yaml::Fields::Load(path), path); }

}  // namespace lasercell::localize
