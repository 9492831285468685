// Hartley's normalisation of 2-D points, which conditions the DLTs of F and H.
#pragma once

#include <cmath>
#include <vector>

#include <Eigen/Core>

namespace facet::internal {

// The similarity that moves the points' centroid to the origin and their mean distance from it
// to sqrt(2); identity scale when all points coincide.
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

}  // namespace facet::internal
