#pragma once
// The result file of a localization (format `lasercell.localization`, version 1) and where the
// PPF model of a localization comes from (a prebuilt .ppfm, or built from a mesh or cloud).
//
// Poses are in the file notation of every lasercell file, {translation_mm, rotation_wxyz}
// (core/json_io.hpp, as cell.yaml holds them); each candidate also carries the same pose as a
// 4x4 homogeneous matrix, 4 rows, mm ("scene_from_model_matrix").

#include <nlohmann/json.hpp>
#include <string>

#include "registration/localize_in_cloud.hpp"
#include "registration/ppf_model.hpp"

namespace lasercell::registration {

/// Names of the inputs as the result file records them (paths, usually).
struct LocalizationInputNames {
  std::string model;  ///< The model file (mesh, cloud or .ppfm).
  std::string scene;  ///< The scene cloud.
};

/// One candidate: rank, scene_from_model {translation_mm, rotation_wxyz},
/// scene_from_model_matrix (4 rows), scene_from_model_covariance (json::Covariance: order,
/// 6 rows, sigma_rotation_deg, sigma_translation_mm; null unless covariance_valid), votes, score,
/// support, coarse_support, icp (or null) and rejection_reason when rejected.
nlohmann::json LocalizationCandidateJson(const LocalizationCandidate& candidate);

/// The result file's timings_ms: model_build_or_load = `model_ms`, then the stages of
/// LocalizationTimings, ms.
nlohmann::json LocalizationTimingsJson(const LocalizationTimings& timings, double model_ms);
/// The result file's counts: points per stage, hypotheses, clusters.
nlohmann::json LocalizationCountsJson(const LocalizationResult& result);

/// The result file: format, version, model, scene, found (+ message), ambiguous (+ reason),
/// candidates, rejected, timings_ms (model_build_or_load = `model_ms`, then the stages of
/// LocalizationTimings) and counts.
nlohmann::json LocalizationResultJson(const LocalizationResult& result,
                                      const LocalizationInputNames& inputs, double model_ms);

/// The model of a localization: a prebuilt .ppfm (PpfModel::Load; `options` unused), or a model
/// built with `options` from a PLY (a mesh: vertex normals from its faces, PpfModel::Build; or a
/// cloud) or a PCD cloud (normals estimated when absent). Throws FileError for unreadable files.
PpfModel LoadOrBuildModel(const std::string& path, const PpfModelOptions& options);

}  // namespace lasercell::registration
