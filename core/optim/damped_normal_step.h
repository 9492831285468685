// The damped Gauss-Newton step of Levenberg-Marquardt with Marquardt's scaling, for the
// small dense problems that form J^T J themselves (the calibration routines):
//   (J^T J + lambda * diag(damping)) step = -J^T r,  solved by LDLT.
// `damping` is J^T J's diagonal with the caller's floor, which keeps a parameter the data do
// not move (a zero column) solvable; each caller states its floor where it forms `damping`.
// The step is not finite when the damped system has no solution at this lambda: callers test
// allFinite() (core/optim/levenberg_marquardt.h, LmStepStatus::kSolveFailed).
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>

namespace facet {

// normal: J^T J (n x n, symmetric positive semi-definite); gradient: J^T r (n);
// damping: n entries > 0.
template <typename NormalMatrix, typename Gradient, typename Damping>
typename Gradient::PlainObject DampedNormalStep(const NormalMatrix& normal, const Gradient& gradient, double lambda,
                                                const Damping& damping) {
  typename NormalMatrix::PlainObject damped = normal;
  damped.diagonal() += lambda * damping;
  return damped.ldlt().solve(-gradient);
}

}  // namespace facet
