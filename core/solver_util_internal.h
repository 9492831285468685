// Small helpers the solvers share: the cross-product matrix, Hartley's normalisation, elapsed
// time for summaries, the early-failure return, and the compact number format their messages
// use. Internal to core/*.cpp.
#pragma once

#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

namespace facet::internal {

// [v]x: Skew(v) * w == v.cross(w).
inline Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d s;
  s << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return s;
}

// Hartley's normalisation of 2-D points (the DLTs of F and H): the similarity that moves their
// centroid to the origin and their mean distance from it to sqrt(2); identity scale when all
// points coincide.
inline Eigen::Matrix3d HartleyNormalization(const std::vector<Eigen::Vector2d>& points) {
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  for (const auto& p : points) centroid += p;
  centroid /= static_cast<double>(points.size());
  double mean_distance = 0.0;
  for (const auto& p : points) mean_distance += (p - centroid).norm();
  mean_distance /= static_cast<double>(points.size());
  const double scale = mean_distance > 0 ? std::sqrt(2.0) / mean_distance : 1.0;
  Eigen::Matrix3d t = Eigen::Matrix3d::Identity();
  t(0, 0) = t(1, 1) = scale;
  t(0, 2) = -scale * centroid.x();
  t(1, 2) = -scale * centroid.y();
  return t;
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
