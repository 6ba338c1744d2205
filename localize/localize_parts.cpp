#include "localize/localize_parts.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "core/error.hpp"
#include "core/format.hpp"
#include "core/pose_covariance.hpp"
#include "registration/filters.hpp"
#include "registration/icp.hpp"
#include "registration/kdtree.hpp"
#include "registration/normals.hpp"

namespace lasercell::localize {
namespace {

using Clock = std::chrono::steady_clock;

double MsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// The ICP pose covariance of a candidate (scene_from_model, left perturbation in the scene);
// false when ICP gave none.
bool IcpPoseCovariance(const registration::LocalizationCandidate& candidate, Matrix6d* out) {
  if (!candidate.icp_run || !candidate.covariance_valid) return false;
  *out = candidate.covariance;
  return true;
}

// Verification constraints of one part: the job's support plane and the part's stable poses
// (without a plane, the stable axes must point along the target frame's +z).
registration::PoseConstraints ConstraintsFor(const PartDefinition& part,
                                             const SupportPlane& support) {
  registration::PoseConstraints c;
  if (!support.enabled && part.stable_up_in_part.empty()) return c;
  c.enabled = true;
  c.plane_normal = support.enabled ? support.normal : Eigen::Vector3d::UnitZ();
  c.plane_offset_mm = support.enabled ? support.offset_mm : 0.0;
  c.max_penetration_mm = support.enabled ? support.max_penetration_mm : -1.0;
  c.up_in_model = part.stable_up_in_part;
  c.max_tilt_rad = part.max_tilt_rad;
  return c;
}

// Removes from *scene the points within `distance` of the posed model's refinement points; when
// `explained` is given it receives them.
void RemoveExplained(const registration::PpfModel& model, const Eigen::Isometry3d& scene_from_model,
                     double distance, PointCloud* scene, PointCloud* explained) {
  std::vector<Eigen::Vector3d> posed;
  posed.reserve(model.refinement_points().size());
  const Eigen::Isometry3d scene_from_centered = scene_from_model * model.model_from_centered();
  for (const Eigen::Vector3d& p : model.refinement_points())
    posed.push_back(scene_from_centered * p);
  // Only points inside the posed model's box grown by `distance` can be explained: the box
  // test spares the nearest-neighbour query for the rest of the sweep (most of it).
  Eigen::AlignedBox3d box;
  for (const Eigen::Vector3d& p : posed) box.extend(p);
  box.min().array() -= distance;
  box.max().array() += distance;
  const registration::KdTree tree(std::move(posed));
  std::vector<std::size_t> keep, near;
  keep.reserve(scene->size());
  registration::Neighbor nearest;
  const double d_sq = distance * distance;
  for (std::size_t i = 0; i < scene->size(); ++i) {
    if (box.contains(scene->positions[i]) && tree.Nearest(scene->positions[i], &nearest) &&
        nearest.distance_sq <= d_sq) {
      near.push_back(i);
    } else {
      keep.push_back(i);
    }
  }
  if (explained != nullptr) *explained = scene->Subset(near);
  *scene = scene->Subset(keep);
}

// The laser plane's share of an instance's pose covariance, from the points it explains.
Matrix6d LaserPlaneTerm(const LaserPlaneUncertainty& plane, const PointCloud& explained) {
  if (explained.size() < 6) return Matrix6d::Zero();
  return LaserPlanePoseCovariance(plane, explained.positions, explained.normals, explained.profile);
}

// A grasp's own fit: ICP over the model's refinement points and the scan points within
// `radius` of the grasp origin, from the part's pose, the scan's normals given so that a scan
// point is not paired with a model point on a face at another angle (IcpOptions::
// max_normal_angle_rad: a feature's rim seen from above, paired with its unseen wall, would
// claim a sideways constraint the scan does not hold). Refused (note set) when either side has
// too few points, ICP gives no valid covariance (the region does not fix the pose), or the
// fit moves the grasp farther than the part's ICP correspondence distance (it slid).
struct LocalFit {
  bool used = false;
  Eigen::Isometry3d target_from_part = Eigen::Isometry3d::Identity();
  Matrix6d covariance = Matrix6d::Zero();
  std::size_t points = 0;
  double rmse_mm = 0.0, shift_mm = 0.0;
  std::string note;
};

LocalFit FitAroundGrasp(const PartModel& model, const PointCloud& scene,
                        const Eigen::Isometry3d& target_from_part, const GraspFrame& grasp,
                        const registration::IcpOptions& icp) {
  LocalFit fit;
  const registration::PpfModel& ppf = model.ppf;
  const double r_sq = grasp.refine_radius_mm * grasp.refine_radius_mm;
  const Eigen::Vector3d origin_in_part = grasp.part_from_grasp.ToIsometry().translation();
  const Eigen::Vector3d origin_centered = ppf.model_from_centered().inverse() * origin_in_part;
  std::vector<Eigen::Vector3d> target, normals;
  for (std::size_t i = 0; i < ppf.refinement_points().size(); ++i) {
    if ((ppf.refinement_points()[i] - origin_centered).squaredNorm() > r_sq) continue;
    target.push_back(ppf.refinement_points()[i]);
    normals.push_back(ppf.refinement_normals()[i]);
  }
  const Eigen::Vector3d origin_in_target = target_from_part * origin_in_part;
  const bool with_normals = scene.normals.size() == scene.positions.size();
  std::vector<Eigen::Vector3d> source, source_normals;
  for (std::size_t i = 0; i < scene.positions.size(); ++i) {
    if ((scene.positions[i] - origin_in_target).squaredNorm() > r_sq) continue;
    source.push_back(scene.positions[i]);
    if (with_normals) source_normals.push_back(scene.normals[i]);
  }
  constexpr std::size_t kMaxSource = 6000, kMinPoints = 50;
  if (source.size() > kMaxSource) {  // every k-th point: deterministic, spread over the region
    std::vector<Eigen::Vector3d> thinned, thinned_normals;
    const double step = static_cast<double>(source.size()) / kMaxSource;
    for (std::size_t k = 0; k < kMaxSource; ++k) {
      const auto i = static_cast<std::size_t>(k * step);
      thinned.push_back(source[i]);
      if (with_normals) thinned_normals.push_back(source_normals[i]);
    }
    source = std::move(thinned);
    source_normals = std::move(thinned_normals);
  }
  fit.points = source.size();
  if (target.size() < kMinPoints || source.size() < kMinPoints) {
    fit.note = "local fit refused: " + std::to_string(target.size()) + " model and " +
               std::to_string(source.size()) + " scan points within " +
               FormatFixed(grasp.refine_radius_mm, 1) + " mm of the grasp (need " +
               std::to_string(kMinPoints) + " each)";
    return fit;
  }
  const registration::KdTree tree(std::move(target));
  const Eigen::Isometry3d centered_from_target =
      (target_from_part * ppf.model_from_centered()).inverse();
  const registration::IcpResult r =
      registration::AlignIcp(source, tree, normals, centered_from_target, icp, source_normals);
  fit.rmse_mm = r.rmse_mm;
  fit.target_from_part = r.target_from_source.inverse() * ppf.model_from_centered().inverse();
  fit.shift_mm = (fit.target_from_part * origin_in_part - origin_in_target).norm();
  if (r.termination == registration::IcpTermination::kTooFewCorrespondences ||
      !r.covariance_valid) {
    fit.note = "local fit refused: the region around the grasp does not fix the pose (" +
               r.Summary() + ")";
  } else if (fit.shift_mm > icp.max_correspondence_distance_mm) {
    fit.note = "local fit refused: it moved the grasp " + FormatFixed(fit.shift_mm, 2) +
               " mm, beyond the ICP correspondence distance " +
               FormatFixed(icp.max_correspondence_distance_mm, 2) + " mm";
  } else {
    fit.used = true;
    fit.covariance = InverseCovariance(r.target_from_source, r.covariance);
  }
  return fit;
}

// Grasp poses and the graspability verdict of an instance; local_fits[i] is grasp i's own fit.
void JudgeInstance(const PartModel& model, const LocalizePartsOptions& options,
                   const std::vector<LocalFit>& local_fits, PartInstance* inst) {
  const double rmse = inst->candidate.icp_run ? inst->candidate.icp.rmse_mm : -1.0;
  std::string reason;
  if (inst->ambiguous) reason = "ambiguous: " + inst->ambiguity_reason;
  if (reason.empty() && !inst->candidate.icp_run) reason = "ICP did not run: pose not refined";
  if (reason.empty() && rmse > options.max_rmse_factor * options.scan_noise_mm) {
    reason = "ICP RMSE " + std::to_string(rmse) + " mm is " +
             std::to_string(rmse / options.scan_noise_mm) + " x the scan noise (" +
             std::to_string(options.scan_noise_mm) + " mm): the model does not fit the scan";
  }
  if (reason.empty() && !inst->covariance_valid) reason = "pose covariance unavailable";
  for (std::size_t gi = 0; gi < model.part.grasps.size(); ++gi) {
    const GraspFrame& g = model.part.grasps[gi];
    const LocalFit& local = local_fits[gi];
    GraspPose grasp;
    grasp.name = g.name;
    const Eigen::Isometry3d part_from_grasp = g.part_from_grasp.ToIsometry();
    grasp.refined_locally = local.used;
    grasp.local_points = local.points;
    grasp.local_rmse_mm = local.rmse_mm;
    grasp.local_shift_mm = local.shift_mm;
    grasp.local_note = local.note;
    // The local fit replaces the ICP term; the calibration terms are shared by every point.
    const Matrix6d covariance = local.used
                                    ? Matrix6d(local.covariance + inst->covariance_terms.placement +
                                               inst->covariance_terms.laser_plane)
                                    : inst->covariance;
    grasp.target_from_grasp =
        (local.used ? local.target_from_part : inst->target_from_part) * part_from_grasp;
    // Left perturbations in the target frame carry over unchanged to a pose right-multiplied
    // by a fixed transform; the grasp origin's position covariance follows from the lever arm.
    grasp.covariance = covariance;
    const Eigen::Vector3d lever = grasp.target_from_grasp.translation();
    Eigen::Matrix<double, 3, 6> j;  // d(position) / d[rotation; translation]
    j.leftCols<3>() = -Skew(lever);
    j.rightCols<3>().setIdentity();
    const Eigen::Matrix3d position_cov = j * covariance * j.transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(position_cov);
    grasp.position_sigma_mm = std::sqrt(std::max(0.0, eig.eigenvalues().maxCoeff()));
    grasp.within_tolerance =
        inst->covariance_valid && 3.0 * grasp.position_sigma_mm <= options.grasp_tolerance_mm;
    if (reason.empty() && !grasp.within_tolerance) {
      reason = "grasp '" + g.name + "': 3-sigma position error " +
               std::to_string(3.0 * grasp.position_sigma_mm) + " mm exceeds the tolerance " +
               std::to_string(options.grasp_tolerance_mm) + " mm";
    }
    inst->grasps.push_back(grasp);
  }
  inst->graspable = reason.empty();
  inst->not_graspable_reason = reason;
}

// Scene points (with lines of sight) inside the ROI.
PointCloud CropScene(const PointCloud& scene, const std::vector<Eigen::Vector3d>& line_of_sight,
                     const LocalizePartsOptions& options, std::vector<Eigen::Vector3d>* sight) {
  if (!options.use_roi) {
    *sight = line_of_sight;
    return scene;
  }
  const std::vector<std::size_t> inside = registration::CropBoxIndices(scene, options.roi);
  if (inside.empty()) {
    throw InputError(
        "region of interest [" + std::to_string(options.roi.min.x()) + ", " +
        std::to_string(options.roi.min.y()) + ", " + std::to_string(options.roi.min.z()) +
        "] .. [" + std::to_string(options.roi.max.x()) + ", " +
        std::to_string(options.roi.max.y()) + ", " + std::to_string(options.roi.max.z()) +
        "] mm holds none of the " + std::to_string(scene.size()) +
        " sweep points: check the job's roi (target frame, mm)");
  }
  sight->clear();
  if (!line_of_sight.empty()) {
    for (std::size_t i : inside) sight->push_back(line_of_sight[i]);
  }
  return scene.Subset(inside);
}

// The scene with normals oriented along each point's line of sight; *view_direction gets the
// mean direction sensor -> scene (the verification grid's line of sight). With `thin_cell_mm` > 0
// the scene is first thinned to one point per cell of that size (the one nearest the cell's
// centre), the finest verification cell of the parts searched (nothing after this reads more), and
// normals are fitted at those points only, each from its neighbourhood in the dense sweep.
PointCloud WithNormals(const PointCloud& scene, const std::vector<Eigen::Vector3d>& sight,
                       const LocalizePartsOptions& options, double thin_cell_mm,
                       Eigen::Vector3d* view_direction) {
  registration::NormalOptions normal_options = options.localize.normals;
  normal_options.threads = options.threads;
  normal_options.viewpoint = registration::Viewpoint::AlongDirection(-Eigen::Vector3d::UnitZ());
  registration::CloudWithNormals fitted =
      registration::WithNormalsAtCells(scene, thin_cell_mm, normal_options, sight);
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (std::size_t i : fitted.kept) mean += sight.empty() ? Eigen::Vector3d::UnitZ() : sight[i];
  *view_direction = mean.norm() > 0 ? Eigen::Vector3d(-mean.normalized())
                                    : Eigen::Vector3d(-Eigen::Vector3d::UnitZ());
  return std::move(fitted.cloud);
}

// The finest verification cell of the requested parts, mm (0: one of them verifies on every
// point, so nothing is thinned).
double FinestVerificationCell(const std::vector<PartRequest>& requests,
                              const registration::LocalizeOptions& options) {
  double cell = std::numeric_limits<double>::infinity();
  for (const PartRequest& r : requests) {
    cell =
        std::min(cell, options.verification_cell_relative *
                           options.refined_support_distance_relative * r.model->ppf.diameter_mm());
  }
  return std::isfinite(cell) ? cell : 0.0;
}

}  // namespace

void LocalizePartsOptions::Check() const {
  const auto fail = [](const std::string& field, const std::string& problem) {
    throw OptionError("LocalizePartsOptions." + field + " " + problem);
  };
  if (!(grasp_tolerance_mm > 0.0)) fail("grasp_tolerance_mm", "must be > 0 (mm)");
  if (!(scan_noise_mm > 0.0)) fail("scan_noise_mm", "must be > 0 (mm)");
  if (!(max_rmse_factor >= 1.0)) fail("max_rmse_factor", "must be >= 1");
  if (!(explained_distance_relative > 0.0 && explained_distance_relative <= 0.2)) {
    fail("explained_distance_relative", "must be in (0, 0.2]");
  }
  if (use_roi && roi.Empty()) fail("roi", "is empty: max must exceed min on every axis");
  if (placement_covariance && !placement_covariance->allFinite()) {
    fail("placement_covariance", "must be finite");
  }
  if (laser_plane) laser_plane->Check();
  localize.Check();
}

bool LocalizePartsResult::AllFound() const {
  for (const PartSearch& s : searches) {
    if (s.found < s.requested) return false;
  }
  return true;
}

std::vector<Eigen::Vector3d> LinesOfSight(const triangulation::SweepResult& sweep) {
  const PointCloud& cloud = sweep.cloud;
  if (!cloud.HasProfile()) throw InputError("LinesOfSight: the sweep cloud has no profile index");
  std::vector<Eigen::Vector3d> sight(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const auto profile = static_cast<std::size_t>(cloud.profile[i]);
    if (profile >= sweep.frame_from_sensor.size()) {
      throw InputError("LinesOfSight: point " + std::to_string(i) + " belongs to profile " +
                       std::to_string(profile) + " but the sweep has " +
                       std::to_string(sweep.frame_from_sensor.size()) + " sensor poses");
    }
    const Eigen::Vector3d d = sweep.frame_from_sensor[profile].translation() - cloud.positions[i];
    const double n = d.norm();
    sight[i] = n > 0 ? Eigen::Vector3d(d / n) : Eigen::Vector3d::UnitZ();
  }
  return sight;
}

LocalizePartsResult LocalizeParts(const PointCloud& scene,
                                  const std::vector<Eigen::Vector3d>& line_of_sight,
                                  const std::vector<PartRequest>& requests,
                                  const LocalizePartsOptions& options) {
  options.Check();
  const auto start = Clock::now();
  if (scene.empty()) throw InputError("LocalizeParts: the sweep holds no points");
  if (!line_of_sight.empty() && line_of_sight.size() != scene.size()) {
    throw InputError("LocalizeParts: " + std::to_string(line_of_sight.size()) +
                     " lines of sight for " + std::to_string(scene.size()) + " points");
  }
  if (options.laser_plane && !scene.HasProfile()) {
    throw InputError(
        "LocalizeParts: the laser plane's uncertainty needs each point's profile, but the "
        "scene has no profile attribute");
  }
  for (const PartRequest& r : requests) {
    if (r.model == nullptr) throw InputError("LocalizeParts: a part request has no model");
    if (r.instances < 1) throw InputError("LocalizeParts: instances must be >= 1");
  }
  LocalizePartsResult result;
  result.sweep_points = scene.size();
  std::vector<Eigen::Vector3d> sight;
  const PointCloud cropped = CropScene(scene, line_of_sight, options, &sight);
  result.roi_points = cropped.size();
  result.timings.roi_ms = MsSince(start);
  const auto normals_start = Clock::now();
  Eigen::Vector3d view_direction;
  PointCloud remaining = WithNormals(
      cropped, sight, options, FinestVerificationCell(requests, options.localize), &view_direction);
  result.normal_points = remaining.size();
  result.timings.normals_ms = MsSince(normals_start);

  const auto searches_start = Clock::now();
  std::size_t total_searches = 0, done = 0;
  for (const PartRequest& r : requests) total_searches += static_cast<std::size_t>(r.instances);
  for (const PartRequest& request : requests) {
    const PartModel& model = *request.model;
    PartSearch search;
    search.part = model.part.name;
    search.requested = request.instances;
    registration::LocalizeOptions lo = options.localize;
    lo.threads = options.threads;
    lo.max_instances = 1;
    lo.use_roi = false;
    lo.recompute_normals = false;
    lo.orient_normals = false;  // oriented along each point's own line of sight above
    lo.viewpoint = registration::Viewpoint::AlongDirection(view_direction);
    lo.verification.constraints = ConstraintsFor(model.part, options.support);
    if (model.part.form_deviation.rms_mm > 0.0) {  // the part file's inspection wins
      lo.icp.model_error_sigma_mm = model.part.form_deviation.rms_mm;
      lo.icp.model_error_length_mm = model.part.form_deviation.correlation_mm;
    }
    for (int k = 0; k < request.instances; ++k) {
      const auto search_start = Clock::now();
      if (remaining.size() < 10) {
        search.message = "only " + std::to_string(remaining.size()) +
                         " unexplained scene points left after " + std::to_string(search.found) +
                         " instance(s)";
        break;
      }
      const registration::LocalizationResult found =
          registration::LocalizeInCloud(remaining, model.ppf, lo);
      search.timings.total_ms += found.timings.total_ms;
      search.timings.normals_ms += found.timings.normals_ms;
      search.timings.subsample_ms += found.timings.subsample_ms;
      search.timings.matching_ms += found.timings.matching_ms;
      search.timings.clustering_ms += found.timings.clustering_ms;
      search.timings.verification_ms += found.timings.verification_ms;
      search.timings.icp_ms += found.timings.icp_ms;
      search.timings.preprocess_ms += found.timings.preprocess_ms;
      search.timings.kdtree_ms += found.timings.kdtree_ms;
      search.sampled_points += found.sampled_points;
      search.reference_points += found.reference_points;
      search.scene_pairs += found.scene_pairs;
      search.votes_cast += found.votes_cast;
      search.rejected = found.rejected;
      if (options.progress) {
        options.progress(search.part + " #" + std::to_string(k + 1),
                         static_cast<double>(++done) / static_cast<double>(total_searches));
      }
      if (!found.found) {
        search.message = found.message.empty() ? "not found" : found.message;
        break;
      }
      PartInstance inst;
      inst.part = model.part.name;
      inst.frame = model.part.name + "_" + std::to_string(search.found + 1);
      inst.candidate = found.candidates.front();
      inst.target_from_part = inst.candidate.scene_from_model;
      inst.ambiguous = found.ambiguous;
      inst.ambiguity_reason = found.ambiguity_reason;
      if (model.part.symmetry.kind != PartSymmetry::Kind::kNone) {
        inst.ambiguous = true;
        inst.ambiguity_reason =
            "the part file declares a symmetry: the rotation about its axis "
            "is not determined by the scan";
      }
      inst.covariance_valid = IcpPoseCovariance(inst.candidate, &inst.covariance_terms.icp);
      // The grasps' own fits use the part's ICP settings as LocalizeInCloud scales them.
      const registration::IcpOptions local_icp =
          registration::DerivedLocalizeOptions(lo, model.ppf).icp;
      std::vector<LocalFit> local_fits;
      for (const GraspFrame& g : model.part.grasps) {
        local_fits.push_back(
            g.refine_radius_mm > 0 && inst.candidate.icp_run
                ? FitAroundGrasp(model, remaining, inst.target_from_part, g, local_icp)
                : LocalFit{});
      }
      // The explained points leave the scene for the searches that follow and feed the laser
      // plane's term; after the last search without that term nobody reads them.
      const bool searches_follow = k + 1 < request.instances || &request != &requests.back();
      PointCloud explained;
      if (searches_follow || options.laser_plane) {
        RemoveExplained(model.ppf, inst.target_from_part,
                        options.explained_distance_relative * model.ppf.diameter_mm(), &remaining,
                        options.laser_plane ? &explained : nullptr);
      }
      if (options.placement_covariance) {
        inst.covariance_terms.placement = *options.placement_covariance;
      }
      if (options.laser_plane) {
        inst.covariance_terms.laser_plane = LaserPlaneTerm(*options.laser_plane, explained);
      }
      if (inst.covariance_valid) {
        inst.covariance = inst.covariance_terms.icp + inst.covariance_terms.placement +
                          inst.covariance_terms.laser_plane;
      }
      JudgeInstance(model, options, local_fits, &inst);
      inst.search_ms = MsSince(search_start);
      search.judgement_ms += inst.search_ms - found.timings.total_ms;
      result.instances.push_back(std::move(inst));
      ++search.found;
    }
    result.searches.push_back(std::move(search));
  }
  result.timings.searches_ms = MsSince(searches_start);
  result.timings.total_ms = MsSince(start);
  return result;
}

}  // namespace lasercell::localize
