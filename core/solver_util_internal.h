// Small helpers the solvers share: the cross-product matrix, elapsed time for summaries, the
// early-failure return, and the compact number format their messages use. Internal to core/*.cpp.
#pragma once

#include <chrono>
#include <cstdio>
#include <string>
#include <utility>

#include <Eigen/Core>

namespace facet::internal {

// [v]x: Skew(v) * w == v.cross(w).
inline Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d s;
  s << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return s;
}

inline double MsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

// The early return of a solver that could not run: success = false, the message, and the time
// so far, on the summary as filled in up to then.
template <typename Summary>
Summary FailedSummary(Summary summary, std::string message, std::chrono::steady_clock::time_point start) {
  summary.success = false;
  summary.message = std::move(message);
  summary.time_ms = MsSince(start);
  return summary;
}

// "%.<significant>g": short, exact enough for a message.
inline std::string FormatNumber(double x, int significant = 4) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*g", significant, x);
  return buffer;
}

}  // namespace facet::internal
