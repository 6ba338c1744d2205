#include "core/json_io.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/io/file_util.hpp"

namespace lasercell::json {
namespace {
constexpr double kRadToDeg = 180.0 / std::numbers::pi;
double SigmaOf(const Matrix6d& c, int k) { return std::sqrt(std::max(0.0, c(k, k))); }
}  // namespace

nlohmann::json Vector(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

nlohmann::json FiniteOrNull(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json();
}

nlohmann::json Pose(const Eigen::Isometry3d& pose) {
  const QuaternionPose q = QuaternionPose::FromIsometry(pose);
  return {{"translation_mm", Vector(q.translation_mm)},
          {"rotation_wxyz", {q.rotation.w(), q.rotation.x(), q.rotation.y(), q.rotation.z()}}};
}

nlohmann::json MatrixRows(const Eigen::Isometry3d& pose) {
  nlohmann::json rows = nlohmann::json::array();
  const Eigen::Matrix4d m = pose.matrix();
  for (int r = 0; r < 4; ++r) rows.push_back({m(r, 0), m(r, 1), m(r, 2), m(r, 3)});
  return rows;
}

nlohmann::json MatrixFlat(const Eigen::Isometry3d& pose) {
  nlohmann::json values = nlohmann::json::array();
  const Eigen::Matrix4d m = pose.matrix();
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) values.push_back(m(r, c));
  }
  return values;
}

nlohmann::json Sigma(const Matrix6d& c) {
  return {{"rotation_deg",
           {SigmaOf(c, 0) * kRadToDeg, SigmaOf(c, 1) * kRadToDeg, SigmaOf(c, 2) * kRadToDeg}},
          {"translation_mm", {SigmaOf(c, 3), SigmaOf(c, 4), SigmaOf(c, 5)}}};
}

nlohmann::json Covariance(const Matrix6d& c) {
  return {{"order", "rotation vector rad (3), translation mm (3); left perturbation"},
          {"matrix", Rows(c)},
          {"sigma_rotation_deg",
           {SigmaOf(c, 0) * kRadToDeg, SigmaOf(c, 1) * kRadToDeg, SigmaOf(c, 2) * kRadToDeg}},
          {"sigma_translation_mm", {SigmaOf(c, 3), SigmaOf(c, 4), SigmaOf(c, 5)}}};
}

nlohmann::json Rows(const Eigen::MatrixXd& m) {
  nlohmann::json rows = nlohmann::json::array();
  for (Eigen::Index i = 0; i < m.rows(); ++i) {
    nlohmann::json row = nlohmann::json::array();
    for (Eigen::Index j = 0; j < m.cols(); ++j) row.push_back(m(i, j));
    rows.push_back(std::move(row));
  }
  return rows;
}

nlohmann::json Provenance(const EdgeProvenance& p) {
  return {{"tool", p.tool},
          {"date", p.date},
          {"input_digest", p.input_digest},
          {"residual_summary", p.residual_summary}};
}

void WriteFile(const std::string& path, const nlohmann::json& j) {
  if (!path.empty()) io::WriteFileAtomically(path, j.dump(2) + "\n");
}

}  // namespace lasercell::json
