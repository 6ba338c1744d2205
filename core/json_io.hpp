#pragma once
// The one JSON writer for what every result file holds: poses in the file notation
// {translation_mm, rotation_wxyz} (the cell.yaml notation, QuaternionPose), 6x6 pose
// covariances, 1-sigma summaries and edge provenance. Result files are JSON (nlohmann), written
// atomically with a trailing newline.
//
// Covariance convention (as the frame graph's edges): [rotation vector (rad, 3); translation
// (mm, 3)], left perturbation.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <nlohmann/json.hpp>
#include <string>

#include "core/frame_graph.hpp"
#include "core/se3.hpp"

namespace lasercell::json {

/// [x, y, z].
nlohmann::json Vector(const Eigen::Vector3d& v);
/// A number, or null when it is not finite (JSON has no NaN).
nlohmann::json FiniteOrNull(double v);
/// {translation_mm: [x, y, z], rotation_wxyz: [w, x, y, z]}: the pose as cell.yaml holds it.
nlohmann::json Pose(const Eigen::Isometry3d& pose);
/// The 4x4 homogeneous matrix as 4 rows (row-major), translation in mm.
nlohmann::json MatrixRows(const Eigen::Isometry3d& pose);
/// The 4x4 homogeneous matrix as 16 numbers, row-major.
nlohmann::json MatrixFlat(const Eigen::Isometry3d& pose);
/// {rotation_deg: [3], translation_mm: [3]}: 1-sigma per axis of a 6x6 pose covariance.
nlohmann::json Sigma(const Matrix6d& covariance);
/// {order, matrix (6 rows), sigma_rotation_deg, sigma_translation_mm} of a 6x6 pose covariance.
nlohmann::json Covariance(const Matrix6d& covariance);
/// A dense matrix as a list of rows.
nlohmann::json Rows(const Eigen::MatrixXd& m);
/// {tool, date, input_digest, residual_summary}.
nlohmann::json Provenance(const EdgeProvenance& provenance);

/// Writes j.dump(2) + "\n" to `path` atomically (nothing when `path` is empty).
void WriteFile(const std::string& path, const nlohmann::json& j);

}  // namespace lasercell::json
