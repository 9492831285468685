// Elapsed wall time for solver summaries.
#pragma once

#include <chrono>

namespace facet::internal {

inline double MsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace facet::internal
