// Equality-constrained polish by NLopt's SLSQP: min f(x) s.t. c(x) = 0, started from a point
// that nearly satisfies c (the joint solve's Levenberg-Marquardt result), so that the
// constraints end up holding to a tight tolerance. NLopt stays inside constraint_polish.cpp.
//
// x: num_variables values, preferably scaled so that a unit change in each matters about
// equally (SLSQP is not scale invariant). f and c come with their gradients; c has
// num_constraints rows and its Jacobian is num_constraints x num_variables.
// Dense quasi-Newton: meant for up to a few hundred variables.
#pragma once

#include <functional>
#include <string>

#include <Eigen/Core>

#include "core/optim/solver_summary.h"

namespace facet {

struct ConstraintPolishProblem {
  int num_variables = 0;
  int num_constraints = 0;
  // Returns f(x); fills *gradient (num_variables) when it is not null.
  std::function<double(const Eigen::VectorXd& x, Eigen::VectorXd* gradient)> objective;
  // Fills *values (num_constraints) and, when not null, *jacobian.
  std::function<void(const Eigen::VectorXd& x, Eigen::VectorXd* values, Eigen::MatrixXd* jacobian)> constraints;
};

struct ConstraintPolishOptions {
  double constraint_tolerance = 1e-10;  // |c_i| accepted by SLSQP
  double relative_x_tolerance = 1e-12;
  int max_evaluations = 200;
  int max_variables = 400;  // larger problems are refused (dense SLSQP)

  bool Check(std::string* error) const;
};

// SolverSummary's fields (core/optim/solver_summary.h): IsUsable() when x changed and the
// constraints hold within the tolerance (kMaxIterations when SLSQP used its evaluation or time
// budget to get there); kFailed when SLSQP failed or ended infeasible; kInvalidInput when the
// problem or the options were refused (message says why). initial_cost and final_cost are
// f(x) at the start and at SLSQP's point; iterations counts SLSQP's objective evaluations.
struct ConstraintPolishSummary : SolverSummary {
  double initial_max_violation = 0.0;  // max |c_i|
  double final_max_violation = 0.0;
};

// Polishes *x in place; on failure *x is left unchanged. Never throws.
ConstraintPolishSummary PolishConstraints(const ConstraintPolishProblem& problem,
                                          const ConstraintPolishOptions& options, Eigen::VectorXd* x);

}  // namespace facet
