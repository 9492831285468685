// The cross-product (skew-symmetric) matrix of a 3-vector.
#pragma once

#include <Eigen/Core>

namespace facet::internal {

// [v]x: Skew(v) * w == v.cross(w).
inline Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d s;
  s << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return s;
}

}  // namespace facet::internal
