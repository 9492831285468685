// The Levenberg-Marquardt iteration shared by the bundle adjustments of self-calibration
// (core/estimators/self_calibration.cpp, metric; core/estimators/projective_bundle_adjustment.cpp, projective): the damping
// schedule, the acceptance of a step and the termination, with the problem's linear algebra
// left to callbacks. Internal to core/.
//
// Why callbacks rather than residuals and a Jacobian: both adjustments reduce the normal
// equations to the camera block by the Schur complement over thousands of 3x3 point blocks
// and parameterise on manifolds (rotations, unit-norm projective cameras and points); a
// generic dense J^T J over all points would be orders of magnitude slower, and the updates
// are not additive. The problem supplies:
//   linearize()                          builds the normal equations at the current state;
//   step(lambda, &cost, &step_sq) -> bool solves them with Marquardt damping lambda (scaled by
//                                        the diagonal), forms the candidate state, returns its
//                                        cost and the squared norm of the step; false when the
//                                        damped system has no finite solution;
//   accept()                             makes the candidate the current state.
// A step is accepted when its cost is finite and lower; then lambda /= 5 (not below 1e-12),
// else lambda *= 5 (10 after a non-finite solve) until it reaches 1e16. The iteration stops
// when an accepted step lowers the cost by at most relative_decrease_tolerance times the new
// cost or moves by at most min_step_squared_norm, when no damping gives a lower cost, when
// the cost is 0 or not finite, or after max_iterations linearisations.
#pragma once

#include <algorithm>
#include <cmath>

namespace facet::internal {

struct LmOptions {
  int max_iterations = 100;
  double initial_lambda = 1e-4;
  double relative_decrease_tolerance = 1e-14;
  double min_step_squared_norm = 1e-30;
};

enum class LmTermination {
  kConverged,      // the last accepted step changed the cost or the state negligibly
  kNoDecrease,     // no damping lowered the cost: a (local) minimum to working precision
  kMaxIterations,  // max_iterations reached (0 included)
  kZeroCost,       // the start or an accepted step fits exactly
  kNonFiniteCost,  // the start's cost is not finite: nothing was tried
};

struct LmResult {
  int iterations = 0;  // linearisations, the last (non-improving) one included
  double initial_cost = 0.0;
  double final_cost = 0.0;
  LmTermination termination = LmTermination::kMaxIterations;
};

template <typename Linearize, typename Step, typename Accept>
LmResult MinimizeLevenbergMarquardt(double cost, const LmOptions& options, Linearize&& linearize, Step&& step,
                                    Accept&& accept) {
  LmResult result;
  result.initial_cost = cost;
  double lambda = options.initial_lambda;
  result.termination = LmTermination::kMaxIterations;
  for (int it = 0; it < options.max_iterations; ++it) {
    if (!std::isfinite(cost)) {
      result.termination = LmTermination::kNonFiniteCost;
      break;
    }
    if (!(cost > 0)) {
      result.termination = LmTermination::kZeroCost;
      break;
    }
    linearize();
    bool improved = false;
    result.termination = LmTermination::kNoDecrease;
    while (lambda < 1e16) {
      double cost_new = 0.0, step_sq = 0.0;
      if (!step(lambda, &cost_new, &step_sq)) {
        lambda *= 10;
        continue;
      }
      if (std::isfinite(cost_new) && cost_new < cost) {
        const double decrease = cost - cost_new;
        accept();
        cost = cost_new;
        lambda = std::max(lambda / 5, 1e-12);
        improved = decrease > options.relative_decrease_tolerance * cost && step_sq > options.min_step_squared_norm;
        result.termination = improved ? LmTermination::kMaxIterations : LmTermination::kConverged;
        break;
      }
      lambda *= 5;
    }
    ++result.iterations;
    if (!improved) break;
  }
  if (result.termination == LmTermination::kMaxIterations && !(cost > 0) && std::isfinite(cost))
    result.termination = LmTermination::kZeroCost;
  result.final_cost = cost;
  return result;
}

}  // namespace facet::internal
