#include "core/point_cloud.hpp"

#include <cmath>

#include "core/error.hpp"

namespace lasercell {
namespace {

template <typename T>
void CheckSize(const std::vector<T>& attribute, std::size_t n, const char* name,
               const std::string& what) {
  if (!attribute.empty() && attribute.size() != n) {
    throw InputError(what + ": attribute '" + name + "' has " + std::to_string(attribute.size()) +
                     " values for " + std::to_string(n) +
                     " points; every attribute must be empty or one value per point");
  }
}

template <typename T>
void AppendAttribute(std::vector<T>& to, const std::vector<T>& from) {
  to.insert(to.end(), from.begin(), from.end());
}

template <typename T>
std::vector<T> Gather(const std::vector<T>& from, std::span<const std::size_t> indices) {
  if (from.empty()) return {};
  std::vector<T> out;
  out.reserve(indices.size());
  for (std::size_t i : indices) out.push_back(from[i]);
  return out;
}

}  // namespace

void PointCloud::Validate(const std::string& what) const {
  for (std::size_t i = 0; i < positions.size(); ++i) {
    if (!positions[i].allFinite()) {
      throw InputError(what + ": point " + std::to_string(i) +
                       " has a non-finite coordinate; remove NaN/inf points before use");
    }
  }
  ValidateAttributes(what);
}

void PointCloud::ValidateAttributes(const std::string& what) const {
  const std::size_t n = positions.size();
  CheckSize(normals, n, "normals", what);
  CheckSize(intensity, n, "intensity", what);
  CheckSize(profile, n, "profile", what);
  CheckSize(column, n, "column", what);
  CheckSize(timestamp_s, n, "timestamp", what);
  for (std::size_t i = 0; i < normals.size(); ++i) {
    if (!normals[i].allFinite()) {
      throw InputError(what + ": normal of point " + std::to_string(i) +
                       " is not finite; recompute normals or drop the point");
    }
  }
  if (grid_rows < 0 || grid_cols < 0) {
    throw InputError(what + ": negative grid size " + std::to_string(grid_rows) + "x" +
                     std::to_string(grid_cols));
  }
  if (grid_rows > 0 && grid_cols > 0) {
    for (std::size_t i = 0; i < profile.size(); ++i) {
      if (profile[i] < 0 || profile[i] >= grid_rows) {
        throw InputError(what + ": point " + std::to_string(i) + " has profile " +
                         std::to_string(profile[i]) + " outside the grid of " +
                         std::to_string(grid_rows) + " rows");
      }
    }
    for (std::size_t i = 0; i < column.size(); ++i) {
      if (column[i] < 0 || column[i] >= grid_cols) {
        throw InputError(what + ": point " + std::to_string(i) + " has column " +
                         std::to_string(column[i]) + " outside the grid of " +
                         std::to_string(grid_cols) + " columns");
      }
    }
  }
}

BoundingBox PointCloud::Bounds() const {
  BoundingBox box;
  for (const auto& p : positions) box.Extend(p);
  return box;
}

Eigen::Vector3d PointCloud::Centroid() const {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const auto& p : positions) sum += p;
  return positions.empty() ? sum : Eigen::Vector3d(sum / static_cast<double>(positions.size()));
}

void PointCloud::Transform(const Eigen::Isometry3d& target_from_source) {
  const Eigen::Matrix3d rotation = target_from_source.linear();
  for (auto& p : positions) p = target_from_source * p;
  for (auto& n : normals) n = rotation * n;
}

PointCloud PointCloud::Transformed(const Eigen::Isometry3d& target_from_source) const {
  PointCloud out = *this;
  out.Transform(target_from_source);
  return out;
}

PointCloud PointCloud::Subset(std::span<const std::size_t> indices) const {
  PointCloud out;
  out.positions = Gather(positions, indices);
  out.normals = Gather(normals, indices);
  out.intensity = Gather(intensity, indices);
  out.profile = Gather(profile, indices);
  out.column = Gather(column, indices);
  out.timestamp_s = Gather(timestamp_s, indices);
  out.grid_rows = grid_rows;
  out.grid_cols = grid_cols;
  return out;
}

void PointCloud::Append(const PointCloud& other) {
  if (other.empty()) return;
  if (empty()) {
    const auto rows = grid_rows, cols = grid_cols;
    *this = other;
    if (rows > 0) grid_rows = std::max(rows, other.grid_rows);
    if (cols > 0) grid_cols = std::max(cols, other.grid_cols);
    return;
  }
  if (HasNormals() != other.HasNormals() || HasIntensity() != other.HasIntensity() ||
      HasProfile() != other.HasProfile() || HasColumn() != other.HasColumn() ||
      HasTimestamps() != other.HasTimestamps()) {
    throw InputError("PointCloud::Append: clouds carry different attributes (" + FieldNames() +
                     " vs " + other.FieldNames() + ")");
  }
  AppendAttribute(positions, other.positions);
  AppendAttribute(normals, other.normals);
  AppendAttribute(intensity, other.intensity);
  AppendAttribute(profile, other.profile);
  AppendAttribute(column, other.column);
  AppendAttribute(timestamp_s, other.timestamp_s);
  grid_rows = std::max(grid_rows, other.grid_rows);
  grid_cols = std::max(grid_cols, other.grid_cols);
}

void PointCloud::Reserve(std::size_t n) {
  positions.reserve(n);
  if (HasNormals()) normals.reserve(n);
  if (HasIntensity()) intensity.reserve(n);
  if (HasProfile()) profile.reserve(n);
  if (HasColumn()) column.reserve(n);
  if (HasTimestamps()) timestamp_s.reserve(n);
}

std::string PointCloud::FieldNames() const {
  std::string names = "x y z";
  if (HasNormals()) names += " nx ny nz";
  if (HasIntensity()) names += " intensity";
  if (HasProfile()) names += " profile";
  if (HasColumn()) names += " column";
  if (HasTimestamps()) names += " timestamp";
  return names;
}

}  // namespace lasercell
