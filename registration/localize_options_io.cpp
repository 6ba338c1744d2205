#include "registration/localize_options_io.hpp"

#include <cmath>
#include <cstdio>
#include <string_view>
#include <utility>
#include <vector>

#include "core/frame_graph.hpp"  // FormatDouble
#include "core/se3.hpp"
#include "core/yaml_fields.hpp"

namespace lasercell::registration {
namespace {

// An enum field spelled as one of `names` (the YAML text of each value).
template <typename E, std::size_t N>
void ReadEnum(yaml::Fields& f, const char* key, const std::pair<std::string_view, E> (&names)[N],
              E* out) {
  std::string text;
  if (!f.Read(key, &text)) return;
  std::string known;
  for (const auto& [name, value] : names) {
    if (text == name) {
      *out = value;
      return;
    }
    known += (known.empty() ? "" : ", ") + std::string(name);
  }
  f.Fail(key, "is '" + text + "'; expected one of: " + known);
}

// A pose {translation_mm: [x, y, z], rotation_wxyz: [w, x, y, z]}, the quaternion of unit norm
// (within kUnitQuaternionTolerance, as in cell.yaml).
void ReadPose(yaml::Fields& f, const char* key, Eigen::Isometry3d* out) {
  if (!f.Has(key)) return;
  yaml::Fields p = f.Sub(key);
  QuaternionPose pose;
  Eigen::Vector4d q;
  p.ReadRequired("translation_mm", &pose.translation_mm);
  p.ReadRequired("rotation_wxyz", &q);
  p.Done();
  if (!(std::abs(q.norm() - 1.0) <= kUnitQuaternionTolerance)) {
    char buf[48];
    std::snprintf(buf, sizeof buf, "%.12g", q.norm());
    p.Fail("rotation_wxyz", std::string("has norm ") + buf +
                                "; expected a unit quaternion (norm within 1e-9 of 1), w first");
  }
  pose.rotation = Eigen::Quaterniond(q[0], q[1], q[2], q[3]);
  *out = pose.ToIsometry();
}

// A list of [x, y, z] directions.
void ReadDirections(yaml::Fields& f, const char* key, std::vector<Eigen::Vector3d>* out) {
  if (!f.Has(key)) {
    f.Known(key);
    return;
  }
  f.Known(key);
  const YAML::Node list = f.node()[key];
  if (!list.IsSequence()) f.Fail(key, "must be a list of [x, y, z] directions");
  std::vector<Eigen::Vector3d> axes;
  for (std::size_t i = 0; i < list.size(); ++i) {
    const std::string item = std::string(key) + "[" + std::to_string(i) + "]";
    const YAML::Node v = list[i];
    if (!v.IsSequence() || v.size() != 3) f.Fail(item, "must be a list of 3 numbers [x, y, z]");
    Eigen::Vector3d axis;
    for (int k = 0; k < 3; ++k) {
      try {
        axis[k] = v[static_cast<std::size_t>(k)].as<double>();
      } catch (const YAML::Exception&) {
        f.Fail(item, "must be a list of 3 numbers [x, y, z]");
      }
    }
    axes.push_back(axis);
  }
  *out = std::move(axes);
}

void ReadNormals(yaml::Fields& f, const char* key, NormalOptions* o) {
  yaml::Fields s = f.Sub(key);
  s.Read("k", &o->k);
  s.Read("radius_mm", &o->radius_mm);
  s.Read("use_grid_when_organized", &o->use_grid_when_organized);
  s.Read("grid_window", &o->grid_window);
  s.Read("grid_max_distance_mm", &o->grid_max_distance_mm);
  s.Read("min_neighbors", &o->min_neighbors);
  s.Done();
}

constexpr std::pair<std::string_view, VoxelNormalMode> kNormalModes[] = {
    {"average", VoxelNormalMode::kAverage},
    {"nearest_point", VoxelNormalMode::kNearestPoint},
    {"none", VoxelNormalMode::kNone}};
constexpr std::pair<std::string_view, IcpMetric> kIcpMetrics[] = {
    {"point_to_plane", IcpMetric::kPointToPlane}, {"point_to_point", IcpMetric::kPointToPoint}};
constexpr std::pair<std::string_view, RobustKernel> kKernels[] = {
    {"none", RobustKernel::kNone},
    {"huber", RobustKernel::kHuber},
    {"tukey", RobustKernel::kTukey},
    {"geman_mcclure", RobustKernel::kGemanMcClure}};

void ReadModel(yaml::Fields& f, PpfModelOptions* m) {
  yaml::Fields s = f.Sub("model");
  ReadPpfModelOptionFields(s, m);
}

// Steps 1-3: region of interest, small clusters, normals, subsampling.
void ReadPreprocessing(yaml::Fields& r, LocalizeOptions* o) {
  if (r.Has("roi")) {
    o->use_roi = true;
    yaml::Fields roi = r.Sub("roi");
    roi.ReadRequired("min_mm", &o->roi.min);
    roi.ReadRequired("max_mm", &o->roi.max);
    ReadPose(roi, "roi_from_scene", &o->roi_from_scene);
    roi.Done();
  }
  r.Read("remove_small_clusters", &o->remove_small_clusters);
  yaml::Fields cf = r.Sub("cluster_filter");
  cf.Read("radius_mm", &o->cluster_filter.radius_mm);
  cf.Read("min_cluster_size", &o->cluster_filter.min_cluster_size);
  cf.Read("use_grid_when_organized", &o->cluster_filter.use_grid_when_organized);
  cf.Read("grid_window", &o->cluster_filter.grid_window);
  cf.Done();
  r.Read("recompute_normals", &o->recompute_normals);
  r.Read("scene_normals_at_samples", &o->scene_normals_at_samples);
  r.Read("orient_normals", &o->orient_normals);
  ReadNormals(r, "normals", &o->normals);
  r.Read("scene_sampling_step_mm", &o->scene_sampling_step_mm);
  ReadEnum(r, "scene_normal_mode", kNormalModes, &o->scene_normal_mode);
  r.Read("scene_normal_split_angle_rad", &o->scene_normal_split_angle_rad);
}

// Steps 4-5: voting and clustering.
void ReadMatching(yaml::Fields& r, LocalizeOptions* o) {
  yaml::Fields s = r.Sub("matching");
  s.Read("reference_stride", &o->matching.reference_stride);
  s.Read("max_reference_points", &o->matching.max_reference_points);
  s.Read("peaks_per_reference", &o->matching.peaks_per_reference);
  s.Read("peak_min_relative", &o->matching.peak_min_relative);
  s.Read("min_votes", &o->matching.min_votes);
  s.Read("spread_features", &o->matching.spread_features);
  s.Read("spread_alpha", &o->matching.spread_alpha);
  s.Read("interpolate_alpha", &o->matching.interpolate_alpha);
  s.Read("max_entries_per_key", &o->matching.max_entries_per_key);
  s.Read("unique_votes", &o->matching.unique_votes);
  s.Done();
  yaml::Fields c = r.Sub("clustering");
  c.Read("translation_radius_mm", &o->clustering.translation_radius_mm);
  c.Read("rotation_threshold_rad", &o->clustering.rotation_threshold_rad);
  c.Read("max_clusters", &o->clustering.max_clusters);
  c.Read("duplicate_radius_mm", &o->clustering.duplicate_radius_mm);
  c.Read("refine_poses", &o->clustering.refine_poses);
  c.Read("refinement_inlier_mm", &o->clustering.refinement_inlier_mm);
  c.Read("refinement_rounds", &o->clustering.refinement_rounds);
  c.Read("refinement_min_members", &o->clustering.refinement_min_members);
  c.Read("refinement_tangent_weight", &o->clustering.refinement_tangent_weight);
  c.Done();
  r.Read("cluster_radius_relative", &o->cluster_radius_relative);
  r.Read("cluster_refinement_inlier_steps", &o->cluster_refinement_inlier_steps);
}

// Step 6: verification and its pose constraints.
void ReadVerification(yaml::Fields& r, LocalizeOptions* o) {
  VerificationOptions& v = o->verification;
  yaml::Fields s = r.Sub("verification");
  s.Read("grid_rows", &v.grid_rows);
  s.Read("grid_cols", &v.grid_cols);
  s.Read("support_distance_mm", &v.support_distance_mm);
  s.Read("min_support", &v.min_support);
  s.Read("min_visible_cells", &v.min_visible_cells);
  s.Read("cull_back_faces", &v.cull_back_faces);
  s.Read("overlap_band_mm", &v.overlap_band_mm);
  yaml::Fields c = s.Sub("constraints");
  c.Read("enabled", &v.constraints.enabled);
  c.Read("plane_normal", &v.constraints.plane_normal);
  c.Read("plane_offset_mm", &v.constraints.plane_offset_mm);
  ReadDirections(c, "up_in_model", &v.constraints.up_in_model);
  c.Read("max_tilt_rad", &v.constraints.max_tilt_rad);
  c.Read("max_penetration_mm", &v.constraints.max_penetration_mm);
  c.Done();
  s.Done();
  r.Read("support_distance_relative", &o->support_distance_relative);
  r.Read("refined_support_distance_relative", &o->refined_support_distance_relative);
  r.Read("refined_min_support", &o->refined_min_support);
  r.Read("max_verified_clusters", &o->max_verified_clusters);
  r.Read("verification_cell_relative", &o->verification_cell_relative);
}

// Step 7: ICP.
void ReadIcp(yaml::Fields& r, LocalizeOptions* o) {
  r.Read("run_icp", &o->run_icp);
  IcpOptions& i = o->icp;
  yaml::Fields s = r.Sub("icp");
  ReadEnum(s, "metric", kIcpMetrics, &i.metric);
  ReadEnum(s, "kernel", kKernels, &i.kernel);
  s.Read("kernel_scale_mm", &i.kernel_scale_mm);
  s.Read("min_kernel_scale_mm", &i.min_kernel_scale_mm);
  s.Read("max_correspondence_distance_mm", &i.max_correspondence_distance_mm);
  s.Read("max_iterations", &i.max_iterations);
  s.Read("translation_tolerance_mm", &i.translation_tolerance_mm);
  s.Read("rotation_tolerance_rad", &i.rotation_tolerance_rad);
  s.Read("min_correspondences", &i.min_correspondences);
  s.Read("covariance_block_mm", &i.covariance_block_mm);
  s.Read("max_normal_angle_rad", &i.max_normal_angle_rad);
  s.Read("model_error_sigma_mm", &i.model_error_sigma_mm);
  s.Read("model_error_length_mm", &i.model_error_length_mm);
  s.Done();
  r.Read("icp_max_distance_relative", &o->icp_max_distance_relative);
  r.Read("icp_covariance_block_relative", &o->icp_covariance_block_relative);
  r.Read("icp_rounds", &o->icp_rounds);
  r.Read("max_icp_source_points", &o->max_icp_source_points);
  r.Read("extra_refined_candidates", &o->extra_refined_candidates);
  r.Read("extra_refined_min_relative_support", &o->extra_refined_min_relative_support);
}

}  // namespace

VoxelNormalMode ParseVoxelNormalMode(const std::string& name, const std::string& field) {
  std::string known;
  for (const auto& [mode_name, mode] : kNormalModes) {
    if (name == mode_name) return mode;
    known += (known.empty() ? "" : ", ") + std::string(mode_name);
  }
  throw OptionError(field + ": is '" + name + "'; expected one of: " + known);
}

void ReadPpfModelOptionFields(yaml::Fields& s, PpfModelOptions* m) {
  s.Read("sampling_step_relative", &m->sampling_step_relative);
  s.Read("sampling_step_mm", &m->sampling_step_mm);
  s.Read("distance_step_relative", &m->distance_step_relative);
  s.Read("distance_step_mm", &m->distance_step_mm);
  s.Read("angle_step_rad", &m->angle_step_rad);
  s.Read("refinement_step_relative", &m->refinement_step_relative);
  ReadEnum(s, "normal_mode", kNormalModes, &m->normal_mode);
  s.Read("normal_split_angle_rad", &m->normal_split_angle_rad);
  s.Read("max_model_points", &m->max_model_points);
  ReadNormals(s, "normals", &m->normals);
  s.Done();
}

std::string PpfModelOptionsYaml(const PpfModelOptions& m, const std::string& indent) {
  std::string normal_mode;
  for (const auto& [name, value] : kNormalModes) {
    if (value == m.normal_mode) normal_mode = name;
  }
  const auto line = [&](const char* key, const std::string& value) {
    return indent + key + ": " + value + "\n";
  };
  const auto num = [](double v) { return FormatDouble(v); };
  return line("sampling_step_relative", num(m.sampling_step_relative)) +
         line("sampling_step_mm", num(m.sampling_step_mm)) +
         line("distance_step_relative", num(m.distance_step_relative)) +
         line("distance_step_mm", num(m.distance_step_mm)) +
         line("angle_step_rad", num(m.angle_step_rad)) +
         line("refinement_step_relative", num(m.refinement_step_relative)) +
         line("normal_mode", normal_mode) +
         line("normal_split_angle_rad", num(m.normal_split_angle_rad)) +
         line("max_model_points", std::to_string(m.max_model_points)) + indent + "normals:\n" +
         line("  k", std::to_string(m.normals.k)) + line("  radius_mm", num(m.normals.radius_mm)) +
         line("  use_grid_when_organized", m.normals.use_grid_when_organized ? "true" : "false") +
         line("  grid_window", std::to_string(m.normals.grid_window)) +
         line("  grid_max_distance_mm", num(m.normals.grid_max_distance_mm)) +
         line("  min_neighbors", std::to_string(m.normals.min_neighbors));
}

LocalizeSettings LocalizeSettingsFromFields(yaml::Fields r) {
  LocalizeSettings settings;
  LocalizeOptions& o = settings.localize;
  r.ExpectFormat("lasercell.localize_options", 1);
  r.Read("threads", &o.threads);
  r.Read("max_instances", &o.max_instances);
  Eigen::Vector3d v;
  const bool at_point = r.Read("viewpoint_mm", &v);
  if (at_point) o.viewpoint = Viewpoint::AtPoint(v);
  if (r.Read("view_direction", &v)) {
    if (at_point) r.Fail("view_direction", "and viewpoint_mm are both set; give one of them");
    o.viewpoint = Viewpoint::AlongDirection(v);
  }
  if (r.Has("model")) ReadModel(r, &settings.model);
  r.Known("model");
  ReadPreprocessing(r, &o);
  ReadMatching(r, &o);
  ReadVerification(r, &o);
  ReadIcp(r, &o);
  r.Read("ambiguity_score_ratio", &o.ambiguity_score_ratio);
  r.Read("planarity_ratio", &o.planarity_ratio);
  r.Done();
  return settings;
}

LocalizeSettings ParseLocalizeOptions(const std::string& text, const std::string& name) {
  return LocalizeSettingsFromFields(yaml::Fields::Parse(text, name));
}

LocalizeSettings ReadLocalizeOptions(const std::string& path) {
  return LocalizeSettingsFromFields(yaml::Fields::Load(path));
}

}  // namespace lasercell::registration
