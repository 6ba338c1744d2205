#pragma once
// Order statistics shared by the solvers' robust scales and the benchmarks' timings.

#include <vector>

namespace lasercell {

/// The element of rank n/2 (0-based) of the values: the median for odd n, the upper of the two
/// middle values for even n (always one of the data, as a robust scale wants). NaN when empty.
double Median(std::vector<double> values);

}  // namespace lasercell
