#include "core/stats.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace lasercell {

double Median(std::vector<double> values) {
  if (values.empty()) return std::nan("");
  const auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  return *mid;
}

}  // namespace lasercell
