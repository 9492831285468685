// Small helpers the solvers share: the cross-product matrix, elapsed time for summaries, and
// the compact number format their messages use. Internal to core/*.cpp.
#pragma once

#include <chrono>
#include <cstdio>
#include <string>

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

// "%.<significant>g": short, exact enough for a message.
inline std::string FormatNumber(double x, int significant = 4) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*g", significant, x);
  return buffer;
}

}  // namespace facet::internal
