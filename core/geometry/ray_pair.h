// The closest points of two rays, e.g. the rays from two cameras' centres through the pins of
// one vertex (teach mode's epipolar overlay in 3D, issue 15): their midpoint is the
// triangulated point and their distance, the ray gap, says how far the two pins disagree.
#pragma once

#include <Eigen/Core>

namespace facet {

struct RayPairClosestPoints {
  bool valid = false;  // false when the rays are parallel (or a direction is zero)
  // Signed distances from each origin along its unit direction; negative: behind the origin.
  double s = 0.0, t = 0.0;
  Eigen::Vector3d on_a = Eigen::Vector3d::Zero();  // origin_a + s * unit(direction_a)
  Eigen::Vector3d on_b = Eigen::Vector3d::Zero();  // origin_b + t * unit(direction_b)
  Eigen::Vector3d midpoint = Eigen::Vector3d::Zero();
  double gap = 0.0;  // |on_a - on_b|, in the origins' units
};

// The points of the two lines origin + r * direction (any non-zero direction lengths) that are
// nearest each other. Lines, not half-lines: s or t < 0 says a point lies behind its origin
// (the caller decides; a camera cannot see it). Parallel when the sine of the angle between
// the directions is below 1e-12.
RayPairClosestPoints ClosestPointsOfRays(const Eigen::Vector3d& origin_a, const Eigen::Vector3d& direction_a,
                                         const Eigen::Vector3d& origin_b, const Eigen::Vector3d& direction_b);

}  // namespace facet
