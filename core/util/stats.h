// Small statistics over samples: the median and the root mean square.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

namespace facet::internal {

// The median (the mean of the two middle values for an even count); 0 for no values.
inline double Median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  const size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + mid, values.end());
  const double upper = values[mid];
  if (values.size() % 2) return upper;
  return 0.5 * (upper + *std::max_element(values.begin(), values.begin() + mid));
}

// sqrt(mean of squares); 0 for no values.
inline double RootMeanSquare(const std::vector<double>& values) {
  if (values.empty()) return 0.0;
  double sum = 0.0;
  for (double x : values) sum += x * x;
  return std::sqrt(sum / static_cast<double>(values.size()));
}

}  // namespace facet::internal
