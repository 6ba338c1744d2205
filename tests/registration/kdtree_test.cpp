#include "registration/kdtree.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <random>

#include "core/error.hpp"
#include "core/random.hpp"

namespace lasercell::registration {
namespace {

std::vector<Eigen::Vector3d> RandomPoints(std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-50.0, 50.0);
  std::vector<Eigen::Vector3d> points(n);
  for (auto& p : points) p = Draws<3>(u, rng);
  return points;
}

// Brute force reference: all (distance_sq, index) sorted by distance then index.
std::vector<Neighbor> BruteForce(const std::vector<Eigen::Vector3d>& points,
                                 const Eigen::Vector3d& q) {
  std::vector<Neighbor> all;
  for (std::size_t i = 0; i < points.size(); ++i)
    all.push_back({static_cast<std::uint32_t>(i), (points[i] - q).squaredNorm()});
  std::sort(all.begin(), all.end(), [](const Neighbor& a, const Neighbor& b) {
    return a.distance_sq < b.distance_sq || (a.distance_sq == b.distance_sq && a.index < b.index);
  });
  return all;
}

TEST(KdTreeTest, KNearestMatchesBruteForce) {
  const auto points = RandomPoints(2000, 1);
  const KdTree tree(points);
  const auto queries = RandomPoints(100, 2);
  std::vector<Neighbor> hits;
  for (std::size_t k : {1, 5, 20}) {
    for (const auto& q : queries) {
      ASSERT_EQ(tree.KNearest(q, k, &hits), k);
      const auto expected = BruteForce(points, q);
      for (std::size_t i = 0; i < k; ++i) {
        EXPECT_EQ(hits[i].index, expected[i].index);
        EXPECT_DOUBLE_EQ(hits[i].distance_sq, expected[i].distance_sq);
      }
    }
  }
}

TEST(KdTreeTest, NearestMatchesBruteForce) {
  const auto points = RandomPoints(500, 3);
  const KdTree tree(points);
  for (const auto& q : RandomPoints(200, 4)) {
    Neighbor nn;
    ASSERT_TRUE(tree.Nearest(q, &nn));
    EXPECT_EQ(nn.index, BruteForce(points, q).front().index);
  }
}

TEST(KdTreeTest, RadiusSearchMatchesBruteForceAndIsInclusive) {
  const auto points = RandomPoints(3000, 5);
  const KdTree tree(points);
  std::vector<Neighbor> hits;
  for (const auto& q : RandomPoints(50, 6)) {
    for (double radius : {0.0, 3.0, 12.5, 40.0}) {
      tree.RadiusSearch(q, radius, &hits, /*sorted=*/true);
      std::vector<Neighbor> expected;
      for (const Neighbor& n : BruteForce(points, q)) {
        if (n.distance_sq <= radius * radius) expected.push_back(n);
      }
      ASSERT_EQ(hits.size(), expected.size()) << "radius " << radius;
      for (std::size_t i = 0; i < hits.size(); ++i) EXPECT_EQ(hits[i].index, expected[i].index);
    }
  }
  // A point at exactly the radius is found.
  const KdTree line(std::vector<Eigen::Vector3d>{{0, 0, 0}, {2, 0, 0}, {4, 0, 0}});
  EXPECT_EQ(line.RadiusSearch({0, 0, 0}, 2.0, &hits), 2U);
}

TEST(KdTreeTest, UnsortedRadiusSearchIsDeterministic) {
  const auto points = RandomPoints(1000, 7);
  const KdTree a(points), b(points);
  std::vector<Neighbor> ha, hb;
  a.RadiusSearch({1, 2, 3}, 20.0, &ha);
  b.RadiusSearch({1, 2, 3}, 20.0, &hb);
  ASSERT_EQ(ha.size(), hb.size());
  for (std::size_t i = 0; i < ha.size(); ++i) EXPECT_EQ(ha[i].index, hb[i].index);
}

TEST(KdTreeTest, EmptyTreeAndSmallK) {
  const KdTree empty;
  std::vector<Neighbor> hits;
  Neighbor nn;
  EXPECT_FALSE(empty.Nearest({0, 0, 0}, &nn));
  EXPECT_EQ(empty.KNearest({0, 0, 0}, 3, &hits), 0U);
  EXPECT_EQ(empty.RadiusSearch({0, 0, 0}, 10.0, &hits), 0U);
  const KdTree two(std::vector<Eigen::Vector3d>{{0, 0, 0}, {1, 0, 0}});
  EXPECT_EQ(two.KNearest({0, 0, 0}, 10, &hits), 2U);  // k larger than the tree
  EXPECT_EQ(two.KNearest({0, 0, 0}, 0, &hits), 0U);
}

TEST(KdTreeTest, SurvivesMove) {
  auto points = RandomPoints(100, 8);
  const Eigen::Vector3d target = points[42];
  KdTree original(points);
  KdTree moved(std::move(original));
  KdTree assigned;
  assigned = std::move(moved);
  Neighbor nn;
  ASSERT_TRUE(assigned.Nearest(target, &nn));
  EXPECT_EQ(nn.index, 42U);
  EXPECT_EQ(nn.distance_sq, 0.0);
}

TEST(KdTreeTest, RejectsNonFinitePoints) {
  std::vector<Eigen::Vector3d> points = {{0, 0, 0},
                                         {std::numeric_limits<double>::quiet_NaN(), 0, 0}};
  try {
    KdTree tree(points);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("point 1"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace lasercell::registration
