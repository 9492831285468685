// The damped Gauss-Newton step of Levenberg-Marquardt with Marquardt's scaling, for the
// small dense problems that form J^T J themselves (the calibration routines):
//   (J^T J + lambda * diag(damping)) step = -J^T r,  solved by LDLT.
// `damping` is J^T J's diagonal with the caller's floor, which keeps a parameter the data do
// not move (a zero column) solvable; each caller states its floor where it forms `damping`.
// The step is not finite when the damped system has no solution at this lambda: callers test
// allFinite() (core/optim/levenberg_marquardt.h, LmStepStatus::kSolveFailed).
// Compiled once in damped_normal_step.cpp, for the two shapes the callers use: the LDLT
// it instantiates is seconds of compile time per file.
#pragma once

#include <Eigen/Core>

namespace facet {

// normal: J^T J (n x n, symmetric positive semi-definite); gradient: J^T r (n);
// damping: n entries > 0.
Eigen::VectorXd DampedNormalStep(const Eigen::MatrixXd& normal, const Eigen::VectorXd& gradient, double lambda,
                                 const Eigen::VectorXd& damping);
Eigen::Vector2d DampedNormalStep(const Eigen::Matrix2d& normal, const Eigen::Vector2d& gradient, double lambda,
                                 const Eigen::Vector2d& damping);

}  // namespace facet
