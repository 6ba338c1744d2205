#include "registration/verification.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "core/error.hpp"

namespace lasercell::registration {

void PoseConstraints::Check(const std::string& owner) const {
  if (!enabled) return;
  if (!plane_normal.allFinite() || plane_normal.norm() < 1e-9) {
    throw OptionError(owner + ".constraints.plane_normal must be a finite non-zero vector");
  }
  if (!std::isfinite(plane_offset_mm))
    throw OptionError(owner + ".constraints.plane_offset_mm must be finite");
  for (std::size_t i = 0; i < up_in_model.size(); ++i) {
    if (!up_in_model[i].allFinite() || up_in_model[i].norm() < 1e-9) {
      throw OptionError(owner + ".constraints.up_in_model[" + std::to_string(i) +
                        "] must be a finite non-zero vector");
    }
  }
  if (!(max_tilt_rad >= 0.0 && max_tilt_rad <= std::numbers::pi)) {
    throw OptionError(owner + ".constraints.max_tilt_rad = " + std::to_string(max_tilt_rad) +
                      ": must be in [0, pi] rad");
  }
  if (!std::isfinite(max_penetration_mm))
    throw OptionError(owner + ".constraints.max_penetration_mm must be finite");
}

void VerificationOptions::Check() const {
  if (grid_rows < 2 || grid_cols < 2 || grid_rows > 4096 || grid_cols > 4096) {
    throw OptionError("VerificationOptions.grid_rows/grid_cols = " + std::to_string(grid_rows) +
                      "x" + std::to_string(grid_cols) +
                      ": the projection grid needs 2..4096 cells per side");
  }
  if (!(support_distance_mm > 0.0) || !std::isfinite(support_distance_mm)) {
    throw OptionError("VerificationOptions.support_distance_mm = " +
                      std::to_string(support_distance_mm) + ": must be a positive distance in mm");
  }
  if (!(min_support >= 0.0 && min_support <= 1.0)) {
    throw OptionError("VerificationOptions.min_support = " + std::to_string(min_support) +
                      ": must be a fraction in [0, 1]");
  }
  if (!(overlap_band_mm > 0.0) || !std::isfinite(overlap_band_mm)) {
    throw OptionError("VerificationOptions.overlap_band_mm = " + std::to_string(overlap_band_mm) +
                      ": must be > 0 mm");
  }
  constraints.Check("VerificationOptions");
}

std::string VerificationResult::Summary() const {
  std::ostringstream s;
  s << (accepted ? "accepted" : "rejected") << ": support " << support << " (" << supported_cells
    << "/" << visible_cells << " cells; occluded " << occluded_cells << ", conflicting "
    << conflicting_cells << ", empty " << empty_cells << ")";
  if (!accepted) s << ", " << rejection_reason;
  return s.str();
}

bool CheckPoseConstraints(const PpfModel& model, const Eigen::Isometry3d& scene_from_model,
                          const PoseConstraints& c, VerificationResult* result) {
  if (!c.enabled) return true;
  const Eigen::Vector3d up = c.plane_normal.normalized();
  result->tilt_rad = 0.0;
  if (!c.up_in_model.empty()) {
    result->tilt_rad = std::numeric_limits<double>::infinity();
    for (const Eigen::Vector3d& a : c.up_in_model) {
      const Eigen::Vector3d a_in_scene = scene_from_model.linear() * a.normalized();
      result->tilt_rad =
          std::min(result->tilt_rad, std::acos(std::clamp(a_in_scene.dot(up), -1.0, 1.0)));
    }
  }
  const Eigen::Isometry3d scene_from_centered = scene_from_model * model.model_from_centered();
  double lowest = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector3d& p : model.refinement_points())
    lowest = std::min(lowest, up.dot(scene_from_centered * p));
  result->penetration_mm = std::max(0.0, c.plane_offset_mm - lowest);
  if (result->tilt_rad > c.max_tilt_rad) {
    result->rejection_reason = "pose constraint: tilt " +
                               std::to_string(result->tilt_rad * 180.0 / std::numbers::pi) +
                               " deg from the nearest stable pose exceeds " +
                               std::to_string(c.max_tilt_rad * 180.0 / std::numbers::pi) + " deg";
    return false;
  }
  if (c.max_penetration_mm >= 0.0 && result->penetration_mm > c.max_penetration_mm) {
    result->rejection_reason =
        "pose constraint: model sinks " + std::to_string(result->penetration_mm) +
        " mm below the support plane (allowed " + std::to_string(c.max_penetration_mm) + " mm)";
    return false;
  }
  return true;
}

VerificationResult VerifyPose(std::span<const Eigen::Vector3d> scene_points, const PpfModel& model,
                              const Eigen::Isometry3d& scene_from_model, const Viewpoint& viewpoint,
                              const VerificationOptions& options,
                              std::vector<std::uint32_t>* overlap) {
  options.Check();
  viewpoint.Check("VerifyPose viewpoint");
  VerificationResult result;
  if (overlap) overlap->clear();
  const bool constraints_ok =
      CheckPoseConstraints(model, scene_from_model, options.constraints, &result);

  // Grid perpendicular to the line of sight through the model centre (Skotheim IV-F).
  const Eigen::Isometry3d scene_from_centered = scene_from_model * model.model_from_centered();
  const Eigen::Vector3d centre = scene_from_centered.translation();
  Eigen::Vector3d view = -viewpoint.TowardSensor(centre);
  if (view.squaredNorm() == 0.0) view = Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d e1 = view.unitOrthogonal();
  const Eigen::Vector3d e2 = view.cross(e1);
  double half = 0.0;
  for (const Eigen::Vector3d& p : model.refinement_points()) half = std::max(half, p.squaredNorm());
  half = std::sqrt(half) + 1e-6;
  const int rows = options.grid_rows, cols = options.grid_cols;
  const double inv_w = cols / (2.0 * half), inv_h = rows / (2.0 * half);
  auto cell_of = [&](const Eigen::Vector3d& d, int* row, int* col) {
    const double u = (d.dot(e1) + half) * inv_w, w = (d.dot(e2) + half) * inv_h;
    if (!(u >= 0.0 && u < cols && w >= 0.0 && w < rows)) return false;
    *col = static_cast<int>(u);
    *row = static_cast<int>(w);
    return true;
  };
  const std::size_t cells = static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols);

  // Model z-buffer: front-most front-facing model point per cell.
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::vector<double> model_depth(cells, kInf);
  std::vector<Eigen::Vector3d> model_point(cells);
  const auto& points = model.refinement_points();
  const auto& normals = model.refinement_normals();
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (options.cull_back_faces && (scene_from_centered.linear() * normals[i]).dot(view) >= 0.0)
      continue;
    const Eigen::Vector3d q = scene_from_centered * points[i];
    int r, c;
    if (!cell_of(q - centre, &r, &c)) continue;
    const std::size_t k = static_cast<std::size_t>(r) * cols + static_cast<std::size_t>(c);
    const double depth = (q - centre).dot(view);
    if (depth < model_depth[k]) {
      model_depth[k] = depth;
      model_point[k] = q;
    }
  }

  // Scene points bucketed by cell (counting sort), and the front-most scene depth per cell.
  std::vector<std::uint32_t> scene_index;
  std::vector<std::uint32_t> scene_cell;
  std::vector<double> scene_front(cells, kInf);
  for (std::size_t i = 0; i < scene_points.size(); ++i) {
    const Eigen::Vector3d d = scene_points[i] - centre;
    int r, c;
    if (!cell_of(d, &r, &c)) continue;
    const auto k = static_cast<std::uint32_t>(r * cols + c);
    scene_index.push_back(static_cast<std::uint32_t>(i));
    scene_cell.push_back(k);
    scene_front[k] = std::min(scene_front[k], d.dot(view));
  }
  std::vector<std::uint32_t> start(cells + 1, 0);
  for (std::uint32_t k : scene_cell) ++start[k + 1];
  for (std::size_t k = 0; k < cells; ++k) start[k + 1] += start[k];
  std::vector<std::uint32_t> bucket(scene_index.size());
  {
    std::vector<std::uint32_t> cursor(start.begin(), start.end() - 1);
    for (std::size_t m = 0; m < scene_index.size(); ++m)
      bucket[cursor[scene_cell[m]]++] = scene_index[m];
  }

  const double tol_sq = options.support_distance_mm * options.support_distance_mm;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const std::size_t k = static_cast<std::size_t>(r) * cols + static_cast<std::size_t>(c);
      if (model_depth[k] == kInf) continue;
      ++result.visible_cells;
      bool supported = false;
      // 3x3 cells: the matching scene point may sit across a cell border when the pose is coarse.
      for (int rr = std::max(0, r - 1); rr <= std::min(rows - 1, r + 1) && !supported; ++rr) {
        for (int cc = std::max(0, c - 1); cc <= std::min(cols - 1, c + 1) && !supported; ++cc) {
          const std::size_t kk = static_cast<std::size_t>(rr) * cols + static_cast<std::size_t>(cc);
          for (std::uint32_t m = start[kk]; m < start[kk + 1]; ++m) {
            if ((scene_points[bucket[m]] - model_point[k]).squaredNorm() <= tol_sq) {
              supported = true;
              break;
            }
          }
        }
      }
      if (supported)
        ++result.supported_cells;
      else if (scene_front[k] == kInf)
        ++result.empty_cells;
      else if (scene_front[k] < model_depth[k])
        ++result.occluded_cells;
      else
        ++result.conflicting_cells;
    }
  }
  if (overlap) {
    for (std::size_t m = 0; m < scene_index.size(); ++m) {
      const std::uint32_t k = scene_cell[m];
      if (model_depth[k] == kInf) continue;
      const double depth = (scene_points[scene_index[m]] - centre).dot(view);
      if (std::abs(depth - model_depth[k]) <= options.overlap_band_mm)
        overlap->push_back(scene_index[m]);
    }
  }
  result.overlapping_scene_points = overlap ? overlap->size() : 0;
  result.support = result.visible_cells > 0
                       ? static_cast<double>(result.supported_cells) / result.visible_cells
                       : 0.0;

  if (!constraints_ok) return result;  // reason already set
  if (result.visible_cells < options.min_visible_cells) {
    result.rejection_reason = "projection grid: only " + std::to_string(result.visible_cells) +
                              " visible model cells (minimum " +
                              std::to_string(options.min_visible_cells) + ")";
  } else if (result.support < options.min_support) {
    result.rejection_reason = "projection grid: support " + std::to_string(result.support) +
                              " below min_support " + std::to_string(options.min_support);
  } else {
    result.accepted = true;
  }
  return result;
}

}  // namespace lasercell::registration
