#pragma once
// Random vectors drawn in a defined order. C++ leaves the order in which a call's arguments are
// evaluated to the compiler, so Eigen::Vector3d(d(rng), d(rng), d(rng)) puts the same three
// draws into other coordinates with GCC than with clang: the same seed gives other data, and a
// seeded test or simulation is not reproducible across compilers. scripts/check-draw-order
// finds such expressions.
#include <Eigen/Core>

namespace lasercell {

/// N successive draws of `distribution` from `engine`, first draw in coordinate 0.
template <int N, class Distribution, class Engine>
Eigen::Matrix<double, N, 1> Draws(Distribution& distribution, Engine& engine) {
  Eigen::Matrix<double, N, 1> v;
  for (int i = 0; i < N; ++i) v[i] = distribution(engine);
  return v;
}

}  // namespace lasercell
