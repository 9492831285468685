#include "core/solve/constraint_polish.h"

#include <algorithm>
#include <cmath>
#include <exception>
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

}  // namespace

ConstraintPolishSummary PolishConstraints(const ConstraintPolishProblem& problem, const ConstraintPolishOptions& options,
                                          Eigen::VectorXd* x) {
  ConstraintPolishSummary summary;
  if (problem.num_variables <= 0 || x == nullptr || x->size() != problem.num_variables || !problem.objective ||
      (problem.num_constraints > 0 && !problem.constraints)) {
    summary.message = "polish: empty or inconsistent problem";
    return summary;
  }
  if (problem.num_variables > options.max_variables) {
    summary.message = "polish skipped: " + std::to_string(problem.num_variables) + " variables exceed the dense limit of " +
                      std::to_string(options.max_variables);
    return summary;
  }
  Context ctx;
  ctx.problem = &problem;
  ctx.gradient.setZero(problem.num_variables);
  ctx.values.setZero(problem.num_constraints);
  ctx.jacobian.setZero(problem.num_constraints, problem.num_variables);
  try {
    summary.initial_objective = problem.objective(*x, nullptr);
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
    summary.evaluations = ctx.evaluations;
    if (!polished.allFinite()) {
      summary.message = "polish: SLSQP returned a non-finite point";
      return summary;
    }
    summary.final_objective = problem.objective(polished, nullptr);
    summary.final_max_violation = problem.num_constraints > 0 ? MaxViolation(problem, polished) : 0.0;
    summary.message = std::string("SLSQP: ") + ResultName(result);
    // Keep the polished point only when it is feasible and no worse a point to stand on.
    if (summary.final_max_violation <= std::max(options.constraint_tolerance, summary.initial_max_violation)) {
      *x = polished;
      summary.success = summary.final_max_violation <= options.constraint_tolerance;
    } else {
      summary.message += " (constraints not met; kept the start)";
    }
  } catch (const std::exception& e) {
    summary.success = false;
    summary.evaluations = ctx.evaluations;
    summary.message = std::string("polish: SLSQP stopped: ") + e.what();
  }
  return summary;
}

}  // namespace facet
