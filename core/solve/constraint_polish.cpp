#include "core/solve/constraint_polish.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <string>
#include <vector>

#include <nlopt.hpp>

namespace facet {

namespace {

struct Context {
  const ConstraintPolishProblem* problem = nullptr;
  Eigen::VectorXd x;
  Eigen::VectorXd gradient;
  Eigen::VectorXd values;
  Eigen::MatrixXd jacobian;
  int evaluations = 0;
};

double Objective(unsigned n, const double* x, double* grad, void* data) {
  Context& ctx = *static_cast<Context*>(data);
  ctx.x = Eigen::Map<const Eigen::VectorXd>(x, n);
  ++ctx.evaluations;
  const double f = ctx.problem->objective(ctx.x, grad != nullptr ? &ctx.gradient : nullptr);
  if (grad != nullptr) Eigen::Map<Eigen::VectorXd>(grad, n) = ctx.gradient;
  return f;
}

void Constraints(unsigned m, double* result, unsigned n, const double* x, double* grad, void* data) {
  Context& ctx = *static_cast<Context*>(data);
  ctx.x = Eigen::Map<const Eigen::VectorXd>(x, n);
  ctx.problem->constraints(ctx.x, &ctx.values, grad != nullptr ? &ctx.jacobian : nullptr);
  Eigen::Map<Eigen::VectorXd>(result, m) = ctx.values;
  if (grad != nullptr) {
    // NLopt wants grad[i * n + j] = dc_i / dx_j: row-major.
    Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(grad, m, n) = ctx.jacobian;
  }
}

const char* ResultName(nlopt::result r) {
  switch (r) {
    case nlopt::SUCCESS: return "success";
    case nlopt::STOPVAL_REACHED: return "stop value reached";
    case nlopt::FTOL_REACHED: return "function tolerance reached";
    case nlopt::XTOL_REACHED: return "parameter tolerance reached";
    case nlopt::MAXEVAL_REACHED: return "evaluation budget used";
    case nlopt::MAXTIME_REACHED: return "time budget used";
    default: return "failure";
  }
}

double MaxViolation(const ConstraintPolishProblem& problem, const Eigen::VectorXd& x) {
  Eigen::VectorXd c;
  problem.constraints(x, &c, nullptr);
  return c.size() > 0 ? c.cwiseAbs().maxCoeff() : 0.0;
}

bool BudgetUsed(nlopt::result r) { return r == nlopt::MAXEVAL_REACHED || r == nlopt::MAXTIME_REACHED; }

}  // namespace

bool ConstraintPolishOptions::Check(std::string* error) const {
  auto fail = [&](const std::string& why) {
    if (error != nullptr) *error = why;
    return false;
  };
  if (!(constraint_tolerance > 0.0) || !std::isfinite(constraint_tolerance)) {
    return fail("constraint_tolerance must be positive and finite");
  }
  if (!(relative_x_tolerance >= 0.0)) return fail("relative_x_tolerance must be non-negative");
  if (max_evaluations < 1) return fail("max_evaluations must be at least 1");
  if (max_variables < 1) return fail("max_variables must be at least 1");
  return true;
}

ConstraintPolishSummary PolishConstraints(const ConstraintPolishProblem& problem,
                                          const ConstraintPolishOptions& options, Eigen::VectorXd* x) {
  const auto start = std::chrono::steady_clock::now();
  ConstraintPolishSummary summary;
  std::string error;
  if (!options.Check(&error)) {
    return internal::FailedSummary(summary, "polish: invalid options: " + error, start,
                                   SolverTermination::kInvalidInput);
  }
  if (problem.num_variables <= 0 || x == nullptr || x->size() != problem.num_variables || !problem.objective ||
      (problem.num_constraints > 0 && !problem.constraints)) {
    return internal::FailedSummary(summary, "polish: empty or inconsistent problem", start,
                                   SolverTermination::kInvalidInput);
  }
  if (problem.num_variables > options.max_variables) {
    return internal::FailedSummary(summary,
                                   "polish skipped: " + std::to_string(problem.num_variables) +
                                       " variables exceed the dense limit of " + std::to_string(options.max_variables),
                                   start, SolverTermination::kInvalidInput);
  }
  Context ctx;
  ctx.problem = &problem;
  ctx.gradient.setZero(problem.num_variables);
  ctx.values.setZero(problem.num_constraints);
  ctx.jacobian.setZero(problem.num_constraints, problem.num_variables);
  try {
    summary.initial_cost = problem.objective(*x, nullptr);
    summary.initial_max_violation = problem.num_constraints > 0 ? MaxViolation(problem, *x) : 0.0;
    nlopt::opt opt(nlopt::LD_SLSQP, static_cast<unsigned>(problem.num_variables));
    opt.set_min_objective(Objective, &ctx);
    if (problem.num_constraints > 0) {
      opt.add_equality_mconstraint(Constraints, &ctx,
                                   std::vector<double>(problem.num_constraints, options.constraint_tolerance));
    }
    opt.set_xtol_rel(options.relative_x_tolerance);
    opt.set_maxeval(options.max_evaluations);
    std::vector<double> values(x->data(), x->data() + x->size());
    double f = 0.0;
    const nlopt::result result = opt.optimize(values, f);
    const Eigen::VectorXd polished = Eigen::Map<const Eigen::VectorXd>(values.data(), problem.num_variables);
    summary.iterations = ctx.evaluations;
    if (!polished.allFinite())
      return internal::FailedSummary(summary, "polish: SLSQP returned a non-finite point", start);
    summary.final_cost = problem.objective(polished, nullptr);
    summary.final_max_violation = problem.num_constraints > 0 ? MaxViolation(problem, polished) : 0.0;
    summary.message = std::string("SLSQP: ") + ResultName(result);
    // Keep the polished point only when it is feasible and no worse a point to stand on.
    if (summary.final_max_violation <= std::max(options.constraint_tolerance, summary.initial_max_violation)) {
      *x = polished;
      const bool held = summary.final_max_violation <= options.constraint_tolerance;
      summary.termination = !held                ? SolverTermination::kFailed
                            : BudgetUsed(result) ? SolverTermination::kMaxIterations
                                                 : SolverTermination::kConverged;
    } else {
      summary.termination = SolverTermination::kFailed;
      summary.message += " (constraints not met; kept the start)";
    }
  } catch (const std::exception& e) {
    summary.iterations = ctx.evaluations;
    return internal::FailedSummary(summary, std::string("polish: SLSQP stopped: ") + e.what(), start);
  }
  summary.time_ms = internal::MsSince(start);
  return summary;
}

}  // namespace facet
