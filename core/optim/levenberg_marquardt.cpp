#include "core/optim/levenberg_marquardt.h"

namespace facet {

namespace {
bool PositiveFinite(double x) { return x > 0.0 && std::isfinite(x); }
}  // namespace

bool LmOptions::Check(std::string* error) const {
  auto fail = [&](const char* message) {
    if (error) *error = message;
    return false;
  };
  if (max_iterations < 0) return fail("max_iterations must not be negative");
  if (!PositiveFinite(initial_lambda)) return fail("initial_lambda must be positive and finite");
  if (schedule == LmSchedule::kFixedFactors) {
    if (!(lambda_decrease > 0.0 && lambda_decrease < 1.0)) return fail("lambda_decrease must lie in (0, 1)");
    if (!(lambda_increase > 1.0) || !std::isfinite(lambda_increase)) {
      return fail("lambda_increase must be finite and above 1");
    }
  }
  if (!stop_on_failed_solve && (schedule == LmSchedule::kFixedFactors || lambda_increase_on_failed_solve != 0.0) &&
      (!(lambda_increase_on_failed_solve > 1.0) || !std::isfinite(lambda_increase_on_failed_solve))) {
    return fail("lambda_increase_on_failed_solve must be finite and above 1");
  }
  if (max_trials_per_linearization < 0) return fail("max_trials_per_linearization must not be negative");
  if (!(min_lambda >= 0.0) || !(min_lambda < max_lambda)) return fail("min_lambda must lie in [0, max_lambda)");
  if (!(initial_lambda < max_lambda) || !(initial_lambda < max_lambda_on_failed_solve)) {
    return fail("initial_lambda must be below max_lambda and max_lambda_on_failed_solve");
  }
  if (!std::isfinite(min_gain_ratio) || min_gain_ratio < 0.0 || min_gain_ratio >= 1.0) {
    return fail("min_gain_ratio must lie in [0, 1)");
  }
  if (!(relative_decrease_tolerance >= 0.0) || !(min_step_squared_norm >= 0.0)) {
    return fail("the tolerances must not be negative");
  }
  return true;
}

LmOptions TenfoldLmOptions(int max_iterations) {
  LmOptions options;
  options.max_iterations = max_iterations;
  options.initial_lambda = 1e-4;
  options.lambda_decrease = 0.1;
  options.lambda_increase = 10.0;
  options.lambda_increase_on_failed_solve = 10.0;
  options.min_lambda = 1e-12;
  return options;
}

const char* LmTerminationName(LmTermination termination) {
  switch (termination) {
    case LmTermination::kConverged: return "converged";
    case LmTermination::kGradientConverged: return "gradient tolerance reached";
    case LmTermination::kNoDecrease: return "no step decreases the cost";
    case LmTermination::kMaxIterations: return "iteration limit reached";
    case LmTermination::kZeroCost: return "the residuals are zero";
    case LmTermination::kNonFiniteCost: return "the cost is not finite";
    case LmTermination::kLinearSolveFailed: return "the damped normal equations cannot be solved";
    case LmTermination::kStoppedByCallback: return "stopped by the callback";
  }
  return "?";
}

}  // namespace facet
