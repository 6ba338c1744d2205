#pragma once
// 3-D kd-tree over std::vector<Eigen::Vector3d> (nanoflann underneath, hidden in kdtree.cpp).
// Conventions: positions in mm; distances are reported SQUARED (mm^2), as in nanoflann and FLANN;
// the radius passed to RadiusSearch is NOT squared (mm). Queries are const and thread-safe.
// Results are deterministic: the same tree and query always give the same answer, in the same
// order (kNN hits nearest first, equal distances by lower index).

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace lasercell::registration {

/// One search hit: index into the tree's points and squared distance, mm^2.
struct Neighbor {
  std::uint32_t index = 0;
  double distance_sq = 0.0;
};

/// Static kd-tree that owns a copy of its points.
class KdTree {
 public:
  /// An empty tree (every search returns nothing).
  KdTree();
  /// Builds the tree over `points` (moved in). `leaf_size` trades build for query time.
  /// Throws InputError when there are more than 2^32-1 points or a point is not finite.
  explicit KdTree(std::vector<Eigen::Vector3d> points, int leaf_size = 10);
  ~KdTree();
  KdTree(KdTree&&) noexcept;
  KdTree& operator=(KdTree&&) noexcept;
  KdTree(const KdTree&) = delete;
  KdTree& operator=(const KdTree&) = delete;

  /// Number of points.
  std::size_t size() const { return points_.size(); }
  /// True when the tree holds no point.
  bool empty() const { return points_.empty(); }
  /// The points, in the order given at construction.
  const std::vector<Eigen::Vector3d>& points() const { return points_; }

  /// The k nearest points to `query`, nearest first, into `out` (cleared first); returns
  /// min(k, size()).
  std::size_t KNearest(const Eigen::Vector3d& query, std::size_t k,
                       std::vector<Neighbor>* out) const;
  /// The nearest point; false when the tree is empty.
  bool Nearest(const Eigen::Vector3d& query, Neighbor* out) const;
  /// Every point within `radius_mm` (inclusive) of `query` into `out` (cleared first). With
  /// `sorted`, nearest first; otherwise in the tree's (deterministic) traversal order.
  std::size_t RadiusSearch(const Eigen::Vector3d& query, double radius_mm,
                           std::vector<Neighbor>* out, bool sorted = false) const;

 private:
  struct Index;
  std::vector<Eigen::Vector3d> points_;
  std::unique_ptr<Index> index_;
};

}  // namespace lasercell::registration
