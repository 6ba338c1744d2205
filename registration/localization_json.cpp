#include "registration/localization_json.hpp"

#include "core/io/file_util.hpp"
#include "core/io/point_cloud_io.hpp"
#include "core/json_io.hpp"

namespace lasercell::registration {

nlohmann::json LocalizationCandidateJson(const LocalizationCandidate& c) {
  nlohmann::json j;
  j["rank"] = c.rank;
  j["scene_from_model"] = json::Pose(c.scene_from_model);
  j["scene_from_model_matrix"] = json::MatrixRows(c.scene_from_model);
  // The fit's covariance of scene_from_model (left perturbation in the scene frame), or null.
  j["scene_from_model_covariance"] =
      c.covariance_valid ? json::Covariance(c.covariance) : nlohmann::json();
  j["votes"] = c.votes;
  j["score"] = c.score;
  j["support"] = c.verification.support;
  j["coarse_support"] = c.coarse_verification.support;
  if (c.icp_run) {
    j["icp"] = {{"rmse_mm", c.icp.rmse_mm},
                {"inliers", c.icp.inliers},
                {"iterations", c.icp.iterations},
                {"converged", c.icp.converged},
                {"termination", ToString(c.icp.termination)}};
  } else {
    j["icp"] = nullptr;
  }
  if (!c.rejection_reason.empty()) j["rejection_reason"] = c.rejection_reason;
  return j;
}

nlohmann::json LocalizationTimingsJson(const LocalizationTimings& t, double model_ms) {
  return {{"model_build_or_load", model_ms},
          {"preprocess", t.preprocess_ms},
          {"normals", t.normals_ms},
          {"subsample", t.subsample_ms},
          {"kdtree", t.kdtree_ms},
          {"matching", t.matching_ms},
          {"clustering", t.clustering_ms},
          {"verification", t.verification_ms},
          {"icp", t.icp_ms},
          {"total", t.total_ms}};
}

nlohmann::json LocalizationCountsJson(const LocalizationResult& r) {
  return {{"scene_points", r.scene_points},
          {"dropped_points", r.dropped_points},
          {"used_points", r.used_points},
          {"sampled_points", r.sampled_points},
          {"reference_points", r.reference_points},
          {"hypotheses", r.hypotheses},
          {"clusters", r.clusters}};
}

nlohmann::json LocalizationResultJson(const LocalizationResult& r,
                                      const LocalizationInputNames& inputs, double model_ms) {
  nlohmann::json j;
  j["format"] = "lasercell.localization";
  j["version"] = 1;
  j["model"] = inputs.model;
  j["scene"] = inputs.scene;
  j["found"] = r.found;
  if (!r.found) j["message"] = r.message;
  j["ambiguous"] = r.ambiguous;
  if (r.ambiguous) j["ambiguity_reason"] = r.ambiguity_reason;
  j["candidates"] = nlohmann::json::array();
  for (const auto& c : r.candidates) j["candidates"].push_back(LocalizationCandidateJson(c));
  j["rejected"] = nlohmann::json::array();
  for (const auto& c : r.rejected) j["rejected"].push_back(LocalizationCandidateJson(c));
  j["timings_ms"] = LocalizationTimingsJson(r.timings, model_ms);
  j["counts"] = LocalizationCountsJson(r);
  return j;
}

PpfModel LoadOrBuildModel(const std::string& path, const PpfModelOptions& options) {
  const std::string extension = io::LowerExtension(path);
  if (extension == ".ppfm") return PpfModel::Load(path);
  if (extension == ".ply") return PpfModel::Build(io::ReadPlyMesh(path), options);
  return PpfModel::Build(io::ReadPointCloud(path), options);
}

}  // namespace lasercell::registration
