#include "registration/kdtree.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <nanoflann.hpp>
#include <string>

#include "core/error.hpp"

namespace lasercell::registration {
namespace {

// nanoflann's dataset interface over the owned points.
// Holds the buffer pointer (not the vector), so moving the owning KdTree keeps it valid.
struct PointsAdaptor {
  const Eigen::Vector3d* data = nullptr;
  std::size_t count = 0;
  std::size_t kdtree_get_point_count() const { return count; }
  double kdtree_get_pt(std::size_t i, std::size_t dim) const { return data[i][dim]; }
  template <typename Box>
  bool kdtree_get_bbox(Box& /*box*/) const {
    return false;
  }
};

using NanoTree = nanoflann::KDTreeSingleIndexAdaptor<
    nanoflann::L2_Simple_Adaptor<double, PointsAdaptor, double, std::uint32_t>, PointsAdaptor, 3,
    std::uint32_t>;

// Result set writing straight into a Neighbor vector (avoids nanoflann's pair vector).
class RadiusCollector {
 public:
  RadiusCollector(double radius_sq, std::vector<Neighbor>* out)
      : radius_sq_(radius_sq), out_(out) {}
  std::size_t size() const { return out_->size(); }
  bool full() const { return true; }
  bool addPoint(double distance_sq, std::uint32_t index) {
    if (distance_sq <= radius_sq_) out_->push_back({index, distance_sq});
    return true;
  }
  // nanoflann keeps a point only when strictly nearer than worstDist(): make the radius inclusive.
  double worstDist() const {
    return std::nextafter(radius_sq_, std::numeric_limits<double>::max());
  }

 private:
  double radius_sq_;
  std::vector<Neighbor>* out_;
};

// k-nearest result set writing into a Neighbor array, ordered by (distance, index) so that
// ties are deterministic.
class KnnCollector {
 public:
  KnnCollector(std::size_t capacity, Neighbor* out) : capacity_(capacity), out_(out) {}
  std::size_t size() const { return count_; }
  bool full() const { return count_ == capacity_; }
  bool addPoint(double distance_sq, std::uint32_t index) {
    std::size_t i = count_;
    while (i > 0 && (out_[i - 1].distance_sq > distance_sq ||
                     (out_[i - 1].distance_sq == distance_sq && out_[i - 1].index > index))) {
      if (i < capacity_) out_[i] = out_[i - 1];
      --i;
    }
    if (i < capacity_) out_[i] = {index, distance_sq};
    if (count_ < capacity_) ++count_;
    return true;
  }
  double worstDist() const {
    return full() ? out_[capacity_ - 1].distance_sq : std::numeric_limits<double>::max();
  }

 private:
  std::size_t capacity_;
  std::size_t count_ = 0;
  Neighbor* out_;
};

bool NearerFirst(const Neighbor& a, const Neighbor& b) {
  return a.distance_sq < b.distance_sq || (a.distance_sq == b.distance_sq && a.index < b.index);
}

}  // namespace

struct KdTree::Index {
  PointsAdaptor adaptor;
  NanoTree tree;
  Index(const std::vector<Eigen::Vector3d>& points, int leaf_size)
      : adaptor{points.data(), points.size()},
        tree(3, adaptor,
             nanoflann::KDTreeSingleIndexAdaptorParams(static_cast<std::size_t>(leaf_size))) {
    tree.buildIndex();
  }
};

KdTree::KdTree() = default;
KdTree::~KdTree() = default;
KdTree::KdTree(KdTree&&) noexcept = default;
KdTree& KdTree::operator=(KdTree&&) noexcept = default;

KdTree::KdTree(std::vector<Eigen::Vector3d> points, int leaf_size) : points_(std::move(points)) {
  if (points_.size() >= std::numeric_limits<std::uint32_t>::max()) {
    throw InputError("KdTree: " + std::to_string(points_.size()) +
                     " points exceed the 2^32-1 supported; subsample the cloud first");
  }
  if (leaf_size < 1) throw OptionError("KdTree: leaf_size must be >= 1");
  for (std::size_t i = 0; i < points_.size(); ++i) {
    if (!points_[i].allFinite()) {
      throw InputError("KdTree: point " + std::to_string(i) +
                       " is not finite; drop NaN/inf points before building a tree");
    }
  }
  // The index keeps a pointer to points_'s buffer, which survives moves of KdTree.
  if (!points_.empty()) index_ = std::make_unique<Index>(points_, leaf_size);
}

std::size_t KdTree::KNearest(const Eigen::Vector3d& query, std::size_t k,
                             std::vector<Neighbor>* out) const {
  out->clear();
  if (!index_ || k == 0) return 0;
  k = std::min(k, points_.size());
  out->resize(k);
  KnnCollector result(k, out->data());
  index_->tree.findNeighbors(result, query.data(), nanoflann::SearchParams());
  out->resize(result.size());
  return out->size();
}

bool KdTree::Nearest(const Eigen::Vector3d& query, Neighbor* out) const {
  if (!index_) return false;
  KnnCollector result(1, out);
  index_->tree.findNeighbors(result, query.data(), nanoflann::SearchParams());
  return result.size() == 1;
}

std::size_t KdTree::RadiusSearch(const Eigen::Vector3d& query, double radius_mm,
                                 std::vector<Neighbor>* out, bool sorted) const {
  out->clear();
  if (!index_ || !(radius_mm >= 0.0)) return 0;
  RadiusCollector collector(radius_mm * radius_mm, out);
  index_->tree.findNeighbors(collector, query.data(), nanoflann::SearchParams(32, 0.0F, false));
  if (sorted) std::sort(out->begin(), out->end(), NearerFirst);
  return out->size();
}

}  // namespace lasercell::registration
