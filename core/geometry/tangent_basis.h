// A basis of the plane tangent to the unit sphere at a point: the two directions in which a
// unit vector (a vanishing direction) is updated by a least-squares step.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace facet::internal {

// Two orthonormal vectors spanning the plane orthogonal to the unit vector v.
inline Eigen::Matrix<double, 3, 2> TangentBasis(const Eigen::Vector3d& v) {
  Eigen::Index smallest;
  v.cwiseAbs().minCoeff(&smallest);
  const Eigen::Vector3d e1 = v.cross(Eigen::Vector3d::Unit(smallest)).normalized();
  Eigen::Matrix<double, 3, 2> basis;
  basis.col(0) = e1;
  basis.col(1) = v.cross(e1);
  return basis;
}

}  // namespace facet::internal
