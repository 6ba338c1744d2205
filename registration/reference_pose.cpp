#include "registration/reference_pose.hpp"

#include <cmath>
#include <cstdio>
#include <random>
#include <sstream>

#include "core/error.hpp"
#include "core/format.hpp"
#include "core/json_io.hpp"
#include "core/random.hpp"
#include "registration/icp.hpp"
#include "registration/kdtree.hpp"
#include "registration/localize_in_cloud.hpp"
#include "registration/ppf_model.hpp"
#include "registration/verification.hpp"

namespace lasercell::registration {
namespace {

/// The stages' options: LocalizeInCloud at high effort, as LocalizeInCloud derives them.
LocalizeOptions SearchOptions(const ReferencePoseOptions& options, const PpfModel& model) {
  LocalizeOptions o;
  o.viewpoint = options.viewpoint;
  o.threads = options.threads;
  o.matching.reference_stride = options.reference_stride;
  o.matching.max_reference_points = 0;
  o.matching.peaks_per_reference = options.peaks_per_reference;
  o.matching.spread_features = true;
  o.max_icp_source_points = 1u << 30;  // every grid-selected scene point
  o.icp.max_iterations = options.icp_iterations;
  o.icp.translation_tolerance_mm = options.translation_tolerance_mm;
  o.icp.rotation_tolerance_rad = options.rotation_tolerance_rad;
  o.max_instances = 1;
  return DerivedLocalizeOptions(o, model);
}

/// What the refinement rounds need besides the pose.
struct RoundContext {
  const PpfModel& model;
  const std::vector<Eigen::Vector3d>& scene;
  VerificationOptions verification;  ///< Refined support distance; its grid selects the source.
  IcpOptions icp;
  Viewpoint viewpoint;
};

/// One round: grid-selected overlap at `pose`, robust point-to-plane ICP over all of it.
Eigen::Isometry3d Round(const RoundContext& ctx, const Eigen::Isometry3d& pose, IcpResult* icp_out,
                        std::size_t* source_count) {
  std::vector<std::uint32_t> overlap;
  VerifyPose(ctx.scene, ctx.model, pose, ctx.viewpoint, ctx.verification, &overlap);
  std::vector<Eigen::Vector3d> source;
  source.reserve(overlap.size());
  for (const std::uint32_t i : overlap) source.push_back(ctx.scene[i]);
  if (source_count != nullptr) *source_count = source.size();
  const Eigen::Isometry3d centered_from_scene = (pose * ctx.model.model_from_centered()).inverse();
  const IcpResult icp = AlignIcp(source, ctx.model.refinement_tree(),
                                 ctx.model.refinement_normals(), centered_from_scene, ctx.icp);
  if (icp_out != nullptr) *icp_out = icp;
  if (icp.termination == IcpTermination::kTooFewCorrespondences) return pose;
  return icp.target_from_source.inverse() * ctx.model.model_from_centered().inverse();
}

/// `rounds` rounds from `pose`; the RMS shift of each is appended to *shifts when given.
Eigen::Isometry3d Rounds(const RoundContext& ctx, Eigen::Isometry3d pose, int rounds,
                         const std::vector<Eigen::Vector3d>& model_points,
                         std::vector<double>* shifts, IcpResult* last, std::size_t* source) {
  for (int r = 0; r < rounds; ++r) {
    const Eigen::Isometry3d next = Round(ctx, pose, last, source);
    if (shifts != nullptr) shifts->push_back(PoseRmsDistanceMm(model_points, pose, next));
    pose = next;
  }
  return pose;
}

/// A rotation of exactly `angle` about a random axis through `centre` and a translation of
/// exactly `shift` mm in a random direction, applied to `pose` (in the scene frame).
Eigen::Isometry3d Perturbed(const Eigen::Isometry3d& pose, const Eigen::Vector3d& centre,
                            double angle, double shift, std::mt19937_64& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  const Eigen::Vector3d axis = Draws<3>(g, rng).normalized();
  const Eigen::Vector3d dir = Draws<3>(g, rng).normalized();
  const Eigen::Vector3d c = pose * centre;
  Eigen::Isometry3d delta = Eigen::Isometry3d::Identity();
  delta.linear() = Eigen::AngleAxisd(angle, axis).toRotationMatrix();
  delta.translation() = c - delta.linear() * c + shift * dir;
  return delta * pose;
}

void CheckSceneAndModel(const PointCloud& model, const PointCloud& scene) {
  if (model.empty()) throw InputError("EstablishReferencePose: the model cloud is empty");
  if (!model.HasNormals())
    throw InputError(
        "EstablishReferencePose: the model cloud has no normals; give a mesh or a "
        "cloud with normals");
  if (scene.empty()) throw InputError("EstablishReferencePose: the scene cloud is empty");
}

}  // namespace

void ReferencePoseOptions::Check() const {
  viewpoint.Check("ReferencePoseOptions.viewpoint");
  if (!(model_sampling_relative > 0.0))
    throw OptionError("ReferencePoseOptions.model_sampling_relative must be > 0");
  if (reference_stride < 1) throw OptionError("ReferencePoseOptions.reference_stride must be >= 1");
  if (peaks_per_reference < 1)
    throw OptionError("ReferencePoseOptions.peaks_per_reference must be >= 1");
  if (rounds < 1) throw OptionError("ReferencePoseOptions.rounds must be >= 1");
  if (icp_iterations < 1) throw OptionError("ReferencePoseOptions.icp_iterations must be >= 1");
  if (!(translation_tolerance_mm > 0.0) || !(rotation_tolerance_rad > 0.0))
    throw OptionError(
        "ReferencePoseOptions.translation_tolerance_mm / rotation_tolerance_rad "
        "must be > 0");
  if (random_starts < 0) throw OptionError("ReferencePoseOptions.random_starts must be >= 0");
  if (!(start_rotation_rad >= 0.0) || !(start_translation_mm >= 0.0))
    throw OptionError(
        "ReferencePoseOptions.start_rotation_rad / start_translation_mm must be >= 0");
  if (!(converged_rms_mm > 0.0))
    throw OptionError("ReferencePoseOptions.converged_rms_mm must be > 0");
  if (threads < 0) throw OptionError("ReferencePoseOptions.threads must be >= 0");
}

double PoseRmsDistanceMm(const std::vector<Eigen::Vector3d>& points, const Eigen::Isometry3d& a,
                         const Eigen::Isometry3d& b) {
  if (points.empty()) return 0.0;
  double sum = 0.0;
  for (const auto& p : points) sum += (a * p - b * p).squaredNorm();
  return std::sqrt(sum / static_cast<double>(points.size()));
}

ReferencePose EstablishReferencePose(const PointCloud& model_cloud, const PointCloud& scene,
                                     const ReferencePoseOptions& options) {
  options.Check();
  CheckSceneAndModel(model_cloud, scene);
  ReferencePose out;
  PpfModelOptions model_options;
  model_options.sampling_step_relative = options.model_sampling_relative;
  model_options.refinement_step_relative = 1e-6;  // keep every input point for refinement
  model_options.threads = options.threads;
  const PpfModel model = PpfModel::Build(model_cloud, model_options);
  const LocalizeOptions search = SearchOptions(options, model);

  // Step 1: the high-effort search.
  const LocalizationResult found = LocalizeInCloud(scene, model, search);
  ReportProgress(options.progress, "search", 1.0);
  if (!found.found) {
    out.message = "the high-effort search found no instance: " + found.message;
    return out;
  }
  out.found = true;
  out.search_support = found.candidates[0].verification.support;
  out.search_rmse_mm = found.candidates[0].icp.rmse_mm;

  // Step 2: refinement rounds over the whole scene, to the fixed point.
  RoundContext ctx{model, scene.positions, search.verification, search.icp, search.viewpoint};
  ctx.verification.support_distance_mm =
      search.refined_support_distance_relative * model.diameter_mm();
  const std::vector<Eigen::Vector3d>& points = model_cloud.positions;
  IcpResult last;
  out.scene_from_model = Rounds(ctx, found.candidates[0].scene_from_model, options.rounds, points,
                                &out.round_shift_mm, &last, &out.icp_source_points);
  out.icp_rmse_mm = last.rmse_mm;
  ReportProgress(options.progress, "rounds", 1.0);

  // Step 3: the checks.
  std::mt19937_64 rng(options.seed);
  const Eigen::Vector3d centre = model_cloud.Centroid();
  for (int s = 0; s < options.random_starts; ++s) {
    const Eigen::Isometry3d start =
        Perturbed(out.scene_from_model, centre, options.start_rotation_rad,
                  options.start_translation_mm, rng);
    const Eigen::Isometry3d end =
        Rounds(ctx, start, options.rounds, points, nullptr, nullptr, nullptr);
    ReferenceStart r{PoseRmsDistanceMm(points, start, out.scene_from_model),
                     PoseRmsDistanceMm(points, end, out.scene_from_model)};
    out.starts_returned += r.end_rms_mm <= options.converged_rms_mm ? 1 : 0;
    out.starts.push_back(r);
    ReportProgress(options.progress, "starts",
                   static_cast<double>(s + 1) / static_cast<double>(options.random_starts));
  }
  for (const RobustKernel kernel : {RobustKernel::kHuber, RobustKernel::kGemanMcClure}) {
    RoundContext other = ctx;
    other.icp.kernel = kernel;
    const Eigen::Isometry3d end =
        Rounds(other, out.scene_from_model, options.rounds, points, nullptr, nullptr, nullptr);
    (kernel == RobustKernel::kHuber ? out.huber_offset_mm : out.geman_mcclure_offset_mm) =
        PoseRmsDistanceMm(points, end, out.scene_from_model);
  }
  const KdTree scene_tree(scene.positions);
  const std::array<double, 3> radii = {0.5, 1.0, 2.0};
  for (const auto& p : points) {
    Neighbor nn;
    scene_tree.Nearest(out.scene_from_model * p, &nn);
    for (std::size_t k = 0; k < radii.size(); ++k)
      out.within_fraction[k] += nn.distance_sq <= radii[k] * radii[k] ? 1.0 : 0.0;
  }
  for (double& f : out.within_fraction) f /= static_cast<double>(points.size());
  return out;
}

nlohmann::json ReferencePoseJson(const ReferencePose& r) {
  nlohmann::json j;
  j["found"] = r.found;
  if (!r.found) {
    j["message"] = r.message;
    return j;
  }
  j["scene_from_model"] = json::Pose(r.scene_from_model);
  j["scene_from_model_matrix"] = json::MatrixRows(r.scene_from_model);
  j["search"] = {{"support", r.search_support}, {"rmse_mm", r.search_rmse_mm}};
  j["round_shift_mm"] = r.round_shift_mm;
  j["icp_source_points"] = r.icp_source_points;
  j["icp_rmse_mm"] = r.icp_rmse_mm;
  nlohmann::json starts = nlohmann::json::array();
  for (const auto& s : r.starts)
    starts.push_back({{"start_rms_mm", s.start_rms_mm}, {"end_rms_mm", s.end_rms_mm}});
  j["starts"] = std::move(starts);
  j["starts_returned"] = r.starts_returned;
  j["huber_offset_mm"] = r.huber_offset_mm;
  j["geman_mcclure_offset_mm"] = r.geman_mcclure_offset_mm;
  j["within_fraction"] = {{"0.5_mm", r.within_fraction[0]},
                          {"1_mm", r.within_fraction[1]},
                          {"2_mm", r.within_fraction[2]}};
  return j;
}

std::string ReferencePose::Report() const {
  if (!found) return "no reference: " + message + "\n";
  std::ostringstream s;
  s << "1. High-effort LocalizeInCloud (every scene point a reference point, spread lookup, every\n"
       "   model point kept for refinement): support "
    << FormatFixed(search_support, 3) << ", point-to-plane rmse " << FormatFixed(search_rmse_mm, 3)
    << " mm.\n2. " << round_shift_mm.size()
    << " rounds of projection-grid re-selection + robust point-to-plane ICP over all "
    << icp_source_points << " overlapping scene points; RMS shift per round (mm):";
  for (const double d : round_shift_mm) s << " " << FormatSignificant(d, 3);
  s << "; last rmse " << FormatFixed(icp_rmse_mm, 3) << " mm.\n3. Checks: " << starts_returned
    << " of " << starts.size() << " random starts";
  if (!starts.empty()) {
    double lo = starts[0].start_rms_mm, hi = lo;
    for (const auto& r : starts) {
      lo = std::min(lo, r.start_rms_mm);
      hi = std::max(hi, r.start_rms_mm);
    }
    s << " (" << FormatFixed(lo, 1) << "-" << FormatFixed(hi, 1) << " mm RMS from the pose)";
  }
  s << " return to it; Huber kernel " << FormatSignificant(huber_offset_mm, 2)
    << " mm, Geman-McClure " << FormatSignificant(geman_mcclure_offset_mm, 2)
    << " mm away; model points within 0.5 / 1 / 2 mm of the scene: "
    << FormatFixed(100.0 * within_fraction[0], 1) << " / "
    << FormatFixed(100.0 * within_fraction[1], 1) << " / "
    << FormatFixed(100.0 * within_fraction[2], 1) << " %.\n";
  return s.str();
}

}  // namespace lasercell::registration
