#include "core/geometry/ray_pair.h"

#include <Eigen/Geometry>

namespace facet {

RayPairClosestPoints ClosestPointsOfRays(const Eigen::Vector3d& origin_a, const Eigen::Vector3d& direction_a,
                                         const Eigen::Vector3d& origin_b, const Eigen::Vector3d& direction_b) {
  RayPairClosestPoints out;
  const double na = direction_a.norm(), nb = direction_b.norm();
  if (!(na > 0.0) || !(nb > 0.0)) return out;
  const Eigen::Vector3d u = direction_a / na, v = direction_b / nb;
  // With unit directions the normal equations of min |a + s u - b - t v|^2 have determinant
  // 1 - (u.v)^2 = sin^2 of the angle between the rays.
  const double b = u.dot(v);
  const double det = 1.0 - b * b;
  constexpr double kMinSine = 1e-12;
  if (!(det > kMinSine * kMinSine)) return out;
  const Eigen::Vector3d w = origin_a - origin_b;
  const double d = u.dot(w), e = v.dot(w);
  out.s = (b * e - d) / det;
  out.t = (e - b * d) / det;
  out.on_a = origin_a + out.s * u;
  out.on_b = origin_b + out.t * v;
  out.midpoint = 0.5 * (out.on_a + out.on_b);
  out.gap = (out.on_a - out.on_b).norm();
  out.valid = true;
  return out;
}

}  // namespace facet
