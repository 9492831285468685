// The one Levenberg-Marquardt driver of core: the damping schedule, the acceptance of a step,
// the stop tests and the iteration callback. The problem's linear algebra is the caller's.
//
// Why the problem is callbacks rather than residuals and a Jacobian: Facet's problems reduce
// the normal equations by a Schur complement over thousands of point blocks, keep sparse
// blocks, parameterise rotations and unit vectors on manifolds (updates are not additive) and
// veto steps that put a vertex behind its camera. A generic dense J^T J would be orders of
// magnitude slower on the large ones. The problem supplies
//   bool Linearize();                          builds the normal equations at the current state;
//                                              returns true when the caller's gradient test
//                                              already says the state is a minimum;
//   LmStepStatus Step(double lambda, LmTrial*); solves the damped equations, forms the
//                                              candidate state and fills the trial;
//   void Accept();                             makes the candidate the current state.
//
// Two damping schedules, both in use (LmOptions::schedule):
//   kFixedFactors: lambda *= lambda_decrease after an accepted step, *= lambda_increase after
//     a rejected one (Marquardt 1963). Cheap and robust for the small calibration problems.
//   kGainRatio: Nielsen's rule (Madsen, Nielsen, Tingleff 2004, eq. 3.16): after a step with
//     gain ratio rho = actual / predicted decrease, lambda *= max(1/3, 1 - (2 rho - 1)^3);
//     after a rejection lambda *= nu, nu *= 2. Needs LmTrial::predicted_decrease; fewer
//     rejected trials on the scene solves, where a trial costs a full evaluation.
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <string>

namespace facet {

enum class LmSchedule { kFixedFactors, kGainRatio };

// What the driver reports after every trial step (accepted or not).
struct LmIteration {
  int iteration = 0;               // as counted by LmResult::iterations
  double cost = 0.0;               // the current (accepted) cost
  double trial_cost = 0.0;         // the trial's cost (+inf when it could not be evaluated)
  double lambda = 0.0;             // the damping the trial used
  double step_squared_norm = 0.0;  // in the problem's own (possibly scaled) coordinates
  bool accepted = false;
};

struct LmOptions {
  int max_iterations = 100;
  // Count every trial step as an iteration (the scene solves, as Ceres does), or every
  // linearisation with however many trials it took (the calibration problems).
  bool count_every_trial = false;
  LmSchedule schedule = LmSchedule::kFixedFactors;
  double initial_lambda = 1e-4;
  double lambda_decrease = 0.2;  // kFixedFactors: factor after an accepted step
  double lambda_increase = 5.0;  // kFixedFactors: factor after a rejected step
  // After a damped system without a finite solution: lambda *= this (kGainRatio: 0 means the
  // rejection rule, lambda *= nu), or stop at once.
  double lambda_increase_on_failed_solve = 10.0;
  bool stop_on_failed_solve = false;
  double min_lambda = 1e-12;  // lambda never drops below it after an accepted step
  double max_lambda = 1e16;   // rejections up to it: no damping lowers the cost
  double max_lambda_on_failed_solve = 1e16;
  // A cap on the trials at one linearisation instead of (or with) max_lambda: after this many
  // unaccepted trials in a row (failed solves included) the run stops as kNoDecrease. 0: no cap.
  int max_trials_per_linearization = 0;
  // kGainRatio: a step is accepted when it lowers the cost and rho exceeds this.
  double min_gain_ratio = 0.0;
  // An accepted step ends the run when it lowers the cost by at most this fraction of the
  // cost before it, or moves the state by at most sqrt(min_step_squared_norm).
  double relative_decrease_tolerance = 1e-14;
  double min_step_squared_norm = 1e-30;
  // Called after every trial; returning false stops the run (progress, stepping, budgets).
  std::function<bool(const LmIteration&)> callback;

  bool Check(std::string* error) const;
};

// Marquardt's schedule with factors of 10: lambda from 1e-4, x0.1 after an accepted step (not
// below 1e-12), x10 after a rejected step or a failed solve. The small dense calibration
// problems share it; each sets its own cap or trial limit and tolerances at the call.
LmOptions TenfoldLmOptions(int max_iterations);

enum class LmStepStatus {
  kSolved,          // the trial holds a candidate
  kSolveFailed,     // the damped system has no finite solution at this lambda
  kStepNegligible,  // the caller's own step test says the state has converged
};

struct LmTrial {
  double cost = std::numeric_limits<double>::infinity();  // +inf vetoes the step
  double step_squared_norm = 0.0;
  double predicted_decrease = 0.0;  // kGainRatio: decrease of the linear model
};

enum class LmTermination {
  kConverged,          // a negligible decrease or step, or the caller's step test
  kGradientConverged,  // the caller's gradient test at a linearisation
  kNoDecrease,         // no damping up to max_lambda (or max_trials_per_linearization) lowered the cost
  kMaxIterations,      // max_iterations reached (0 included)
  kZeroCost,           // the start or an accepted step fits exactly
  kNonFiniteCost,      // the start's cost is not finite: nothing was tried
  kLinearSolveFailed,  // no damping up to max_lambda_on_failed_solve gave a finite step
  kStoppedByCallback,
};
const char* LmTerminationName(LmTermination termination);

struct LmResult {
  int iterations = 0;
  int accepted_steps = 0;
  double initial_cost = 0.0;
  double final_cost = 0.0;
  double final_lambda = 0.0;  // the damping after the last accepted step (to resume from)
  LmTermination termination = LmTermination::kMaxIterations;
};

namespace internal {

struct LmSchedulerState {
  double lambda;
  double nu = 2.0;
};

inline void LmOnAccepted(const LmOptions& o, double rho, LmSchedulerState* s) {
  if (o.schedule == LmSchedule::kFixedFactors) {
    s->lambda *= o.lambda_decrease;
  } else {
    const double t = 2.0 * rho - 1.0;
    s->lambda *= std::max(1.0 / 3.0, 1.0 - t * t * t);
    s->nu = 2.0;
  }
  s->lambda = std::max(s->lambda, o.min_lambda);
}

inline void LmOnRejected(const LmOptions& o, bool failed_solve, LmSchedulerState* s) {
  if (o.schedule == LmSchedule::kFixedFactors) {
    s->lambda *= failed_solve ? o.lambda_increase_on_failed_solve : o.lambda_increase;
  } else if (failed_solve && o.lambda_increase_on_failed_solve > 0.0) {
    s->lambda *= o.lambda_increase_on_failed_solve;
  } else {
    s->lambda *= s->nu;
    s->nu *= 2.0;
  }
}

}  // namespace internal

// Minimises from the problem's current state, whose cost is `cost`. On return the problem's
// state is the best one found (the last accepted candidate).
template <typename Problem>
LmResult MinimizeLevenbergMarquardt(double cost, const LmOptions& options, Problem& problem) {
  LmResult result;
  result.initial_cost = cost;
  internal::LmSchedulerState schedule{options.initial_lambda};
  result.final_lambda = schedule.lambda;
  auto finish = [&](LmTermination termination) {
    result.termination = termination;
    result.final_cost = cost;
    return result;
  };
  bool need_linearization = true;
  int trials_at_linearization = 0;
  while (true) {
    if (need_linearization) {
      if (!std::isfinite(cost)) return finish(LmTermination::kNonFiniteCost);
      if (!(cost > 0.0)) return finish(LmTermination::kZeroCost);
      if (!options.count_every_trial && result.iterations >= options.max_iterations) {
        return finish(LmTermination::kMaxIterations);
      }
      if (problem.Linearize()) return finish(LmTermination::kGradientConverged);
      need_linearization = false;
      trials_at_linearization = 0;
      if (!options.count_every_trial) ++result.iterations;
    }
    if (options.count_every_trial) {
      if (result.iterations >= options.max_iterations) return finish(LmTermination::kMaxIterations);
      ++result.iterations;
    }
    LmTrial trial;
    const double lambda = schedule.lambda;
    const LmStepStatus status = problem.Step(lambda, &trial);
    if (status == LmStepStatus::kStepNegligible) return finish(LmTermination::kConverged);
    ++trials_at_linearization;
    bool accepted = false;
    bool converged = false;
    if (status == LmStepStatus::kSolveFailed) {
      if (options.stop_on_failed_solve) return finish(LmTermination::kLinearSolveFailed);
      internal::LmOnRejected(options, true, &schedule);
      if (!(schedule.lambda < options.max_lambda_on_failed_solve)) return finish(LmTermination::kLinearSolveFailed);
    } else {
      const double decrease = cost - trial.cost;
      const double rho = trial.predicted_decrease > 0.0 ? decrease / trial.predicted_decrease : -1.0;
      accepted = std::isfinite(trial.cost) && trial.cost < cost &&
                 (options.schedule == LmSchedule::kFixedFactors || rho > options.min_gain_ratio);
      if (accepted) {
        problem.Accept();
        converged = decrease <= options.relative_decrease_tolerance * cost ||
                    trial.step_squared_norm <= options.min_step_squared_norm;
        cost = trial.cost;
        ++result.accepted_steps;
        internal::LmOnAccepted(options, rho, &schedule);
        result.final_lambda = schedule.lambda;
        need_linearization = true;
      } else {
        internal::LmOnRejected(options, false, &schedule);
      }
    }
    if (options.callback) {
      LmIteration report{result.iterations, cost, trial.cost, lambda, trial.step_squared_norm, accepted};
      if (!options.callback(report)) return finish(LmTermination::kStoppedByCallback);
    }
    if (converged) return finish(!(cost > 0.0) ? LmTermination::kZeroCost : LmTermination::kConverged);
    if (!accepted && status == LmStepStatus::kSolved && !(schedule.lambda < options.max_lambda)) {
      return finish(LmTermination::kNoDecrease);
    }
    if (!accepted && options.max_trials_per_linearization > 0 &&
        trials_at_linearization >= options.max_trials_per_linearization) {
      return finish(LmTermination::kNoDecrease);
    }
  }
}

// The same driver for problems written as three lambdas (the bundle adjustments):
//   linearize(); step(lambda, &cost, &step_squared_norm) -> bool (false: no finite solution);
//   accept().
template <typename LinearizeFn, typename StepFn, typename AcceptFn>
LmResult MinimizeLevenbergMarquardt(double cost, const LmOptions& options, LinearizeFn&& linearize, StepFn&& step,
                                    AcceptFn&& accept) {
  struct Adapter {
    LinearizeFn& linearize;
    StepFn& step;
    AcceptFn& accept;
    bool Linearize() {
      linearize();
      return false;
    }
    LmStepStatus Step(double lambda, LmTrial* trial) {
      return step(lambda, &trial->cost, &trial->step_squared_norm) ? LmStepStatus::kSolved : LmStepStatus::kSolveFailed;
    }
    void Accept() { accept(); }
  } adapter{linearize, step, accept};
  return MinimizeLevenbergMarquardt(cost, options, adapter);
}

}  // namespace facet
