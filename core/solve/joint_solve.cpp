#include "core/solve/joint_solve.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <sstream>

#include <Eigen/SVD>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include "core/geometry/camera_checks.h"
#include "core/optim/levenberg_marquardt.h"
#include "core/solve/constraint_polish.h"
#include "core/solve/joint_solve_internal.h"
#include "core/solve/joint_solve_steps.h"
#include "core/solve/model_sanity.h"
#include "core/solve/scene_solve.h"
#include "core/solve/vertex_move.h"
#include "core/util/eigen_decompositions.h"
#include "core/util/format.h"

namespace facet {

bool JointSolveOptions::Check(std::string* error) const {
  auto fail = [&](const std::string& why) {
    if (error != nullptr) *error = why;
    return false;
  };
  if (max_iterations < 1) return fail("max_iterations must be at least 1");
  if (!(function_tolerance >= 0.0)) return fail("function_tolerance must be non-negative");
  if (!(gradient_tolerance >= 0.0)) return fail("gradient_tolerance must be non-negative");
  if (!(parameter_tolerance >= 0.0)) return fail("parameter_tolerance must be non-negative");
  if (!(initial_lambda > 0.0) || !std::isfinite(initial_lambda))
    return fail("initial_lambda must be positive and finite");
  if (!(constraint_tolerance > 0.0)) return fail("constraint_tolerance must be positive");
  if (!(conflict_tolerance > 0.0)) return fail("conflict_tolerance must be positive");
  if (!(robust_min_scale_px > 0.0) || !std::isfinite(robust_min_scale_px))
    return fail("robust_min_scale_px must be positive and finite");
  if (!(huber_scale > 0.0) || !std::isfinite(huber_scale)) return fail("huber_scale must be positive and finite");
  if (!(outlier_scale >= huber_scale) || !std::isfinite(outlier_scale))
    return fail("outlier_scale must be finite and at least huber_scale");
  if (robust_min_pins < 3) return fail("robust_min_pins must be at least 3");
  if (max_robust_rounds < 0) return fail("max_robust_rounds must be non-negative");
  return true;
}

namespace {

using namespace joint_solve_internal;

constexpr double kInitialConstraintWeight = 1e3;  // sqrt(mu): a relative error of 1e-3 weighs 1 px
constexpr double kMaxConstraintWeight = 1e7;
constexpr int kMaxOuterRounds = 12;
// The augmented Lagrangian ends when the constraints hold and the cost they still owe (sum
// |lambda c|) is below this fraction of the observation cost, or below the floor (px^2,
// invisible) for a noise-free scene whose cost is ~0.
constexpr double kCostGapTolerance = 1e-10;
constexpr double kCostGapFloorPx2 = 1e-20;
constexpr int kMaxDiagnosticParameters = 600;  // dense SVD above this costs too much for a full solve
constexpr double kRankTolerance = 1e-9;        // singular values below this times the largest are zero
constexpr int kMaxColdStartParameters = 300;   // the geometry solve's initialisation is dense
// A focal length the solve takes beyond this many image diagonals (f / d times 43.3 mm: a
// 1,080 mm lens on a full-frame camera) is no lens a photo for modelling was taken with, but
// pins that cannot fix f letting it run along the viewing direction (134,515 px after 100
// iterations from 19 pins on a shared lens, issue 26). It is held where it started.
constexpr double kMaxSolvedFocalPerDiagonal = 25.0;

// The damped normal equations (J^T J + lambda D) delta = -J^T r, D = diag(J^T J) floored.
class NormalEquations {
 public:
  virtual ~NormalEquations() = default;
  virtual bool Init(const JointProblem& problem) = 0;
  virtual void Assemble(const JointProblem& problem) = 0;
  virtual bool Solve(double lambda, Eigen::VectorXd* delta) = 0;
  const Eigen::VectorXd& gradient() const { return g_; }
  const Eigen::VectorXd& damping() const { return d_; }
  double HessianDiagonal(int k) const { return h_diag_(k); }

 protected:
  // Marquardt's scaling makes the step independent of the units of each parameter; a floor
  // keeps parameters no residual sees (zero columns) from making the system singular.
  void SetDamping() {
    const double max_diag = h_diag_.size() > 0 ? h_diag_.maxCoeff() : 0.0;
    const double floor = std::max(max_diag * 1e-14, std::numeric_limits<double>::min());
    d_ = h_diag_.cwiseMax(floor);
  }
  Eigen::VectorXd g_;
  Eigen::VectorXd d_;
  Eigen::VectorXd h_diag_;
};

// General sparsity: a fixed sparse pattern assembled through precomputed value indices and
// factorised by a simplicial LDL^T whose AMD ordering and symbolic analysis are done once.
class SparseEquations : public NormalEquations {
 public:
  bool Init(const JointProblem& problem) override {
    const int n = problem.num_parameters;
    std::vector<Eigen::Triplet<double>> triplets;
    for (int k = 0; k < n; ++k) triplets.emplace_back(k, k, 0.0);
    for (const ResidualBlock& b : problem.blocks) {
      for (size_t i = 0; i < b.cols.size(); ++i) {
        for (size_t j = 0; j <= i; ++j) {
          triplets.emplace_back(std::max(b.cols[i], b.cols[j]), std::min(b.cols[i], b.cols[j]), 0.0);
        }
      }
    }
    h_.resize(n, n);
    h_.setFromTriplets(triplets.begin(), triplets.end());
    h_.makeCompressed();
    auto index = [&](int row, int col) {
      const int* begin = h_.innerIndexPtr() + h_.outerIndexPtr()[col];
      const int* end = h_.innerIndexPtr() + h_.outerIndexPtr()[col + 1];
      return static_cast<int>(std::lower_bound(begin, end, row) - h_.innerIndexPtr());
    };
    diagonal_.resize(n);
    for (int k = 0; k < n; ++k) diagonal_[k] = index(k, k);
    block_index_.clear();
    for (const ResidualBlock& b : problem.blocks) {
      std::vector<int> idx;
      idx.reserve(b.cols.size() * (b.cols.size() + 1) / 2);
      for (size_t i = 0; i < b.cols.size(); ++i) {
        for (size_t j = 0; j <= i; ++j)
          idx.push_back(index(std::max(b.cols[i], b.cols[j]), std::min(b.cols[i], b.cols[j])));
      }
      block_index_.push_back(std::move(idx));
    }
    damped_ = h_;
    g_.setZero(n);
    d_.setZero(n);
    h_diag_.setZero(n);
    ldlt_.analyzePattern(damped_);
    return ldlt_.info() == Eigen::Success;
  }

  void Assemble(const JointProblem& problem) override {
    double* h = h_.valuePtr();
    std::fill(h, h + h_.nonZeros(), 0.0);
    g_.setZero();
    for (size_t bi = 0; bi < problem.blocks.size(); ++bi) {
      const ResidualBlock& b = problem.blocks[bi];
      const int* idx = block_index_[bi].data();
      const int m = static_cast<int>(b.cols.size());
      for (int i = 0; i < m; ++i) {
        const auto ci = b.jacobian.col(i);
        g_(b.cols[i]) += ci.dot(b.residual);
        for (int j = 0; j <= i; ++j) h[*idx++] += ci.dot(b.jacobian.col(j));
      }
    }
    for (size_t k = 0; k < diagonal_.size(); ++k) h_diag_(k) = h[diagonal_[k]];
    SetDamping();
  }

  bool Solve(double lambda, Eigen::VectorXd* delta) override {
    std::copy(h_.valuePtr(), h_.valuePtr() + h_.nonZeros(), damped_.valuePtr());
    double* v = damped_.valuePtr();
    for (size_t k = 0; k < diagonal_.size(); ++k) v[diagonal_[k]] += lambda * d_(k);
    ldlt_.factorize(damped_);
    if (ldlt_.info() != Eigen::Success) return false;
    *delta = ldlt_.solve(-g_);
    return delta->allFinite();
  }

 private:
  Eigen::SparseMatrix<double> h_;
  Eigen::SparseMatrix<double> damped_;
  std::vector<int> diagonal_;
  std::vector<std::vector<int>> block_index_;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> ldlt_;
};

// The bundle-adjustment structure: camera parameters (numbered first) against groups of
// primitive-side parameters (a primitive with its attached primitives and free vertices,
// merged when a constraint couples them). Each group's block of J^T J is dense and small and
// no block couples two groups, so they are eliminated one by one (Schur complement) into a
// dense reduced camera system. Cost per iteration ~ sum over groups of (group size)^3 plus
// (cameras seeing it x 9)^2 x group size, plus (9 x cameras)^3: linear in the primitives.
class SchurEquations : public NormalEquations {
 public:
  // The largest group this class accepts; beyond it SparseEquations is used.
  static constexpr int kMaxGroupSize = 96;

  bool Init(const JointProblem& problem) override {
    const int n = problem.num_parameters;
    nc_ = 0;
    // BuildJointProblem numbers the camera parameters first.
    for (const CameraBlock& c : problem.cameras) {
      if (c.focal_offset >= 0) nc_ = std::max(nc_, c.focal_offset + 1);
      if (c.principal_point_offset >= 0) nc_ = std::max(nc_, c.principal_point_offset + 2);
      if (c.center_offset >= 0) nc_ = std::max(nc_, c.center_offset + 3);
      if (c.distortion_offset >= 0) nc_ = std::max(nc_, c.distortion_offset + 2);
    }
    // Union-find over the primitive-side parameters [nc, n).
    std::vector<int> parent(n);
    for (int k = 0; k < n; ++k) parent[k] = k;
    auto find = [&](int k) {
      while (parent[k] != k) k = parent[k] = parent[parent[k]];
      return k;
    };
    for (const ResidualBlock& b : problem.blocks) {
      int first = -1;
      for (int c : b.cols) {
        if (c < nc_) continue;
        if (first < 0)
          first = c;
        else
          parent[find(c)] = find(first);
      }
    }
    group_of_.assign(n, -1);
    local_.assign(n, -1);
    std::vector<int> root_group(n, -1);
    groups_.clear();
    for (int k = nc_; k < n; ++k) {
      const int r = find(k);
      if (root_group[r] < 0) {
        root_group[r] = static_cast<int>(groups_.size());
        groups_.emplace_back();
      }
      Group& g = groups_[root_group[r]];
      group_of_[k] = root_group[r];
      local_[k] = static_cast<int>(g.params.size());
      g.params.push_back(k);
      if (static_cast<int>(g.params.size()) > kMaxGroupSize) return false;
    }
    // Camera rows of each group's W block.
    for (const ResidualBlock& b : problem.blocks) {
      for (int c : b.cols) {
        if (c >= nc_) continue;
        for (int p : b.cols) {
          if (p < nc_) continue;
          Group& g = groups_[group_of_[p]];
          if (std::find(g.camera_rows.begin(), g.camera_rows.end(), c) == g.camera_rows.end())
            g.camera_rows.push_back(c);
        }
      }
    }
    for (Group& g : groups_) {
      std::sort(g.camera_rows.begin(), g.camera_rows.end());
      const int ng = static_cast<int>(g.params.size());
      const int kg = static_cast<int>(g.camera_rows.size());
      g.v.setZero(ng, ng);
      g.w.setZero(kg, ng);
      g.y.setZero(ng, kg);
      g.wy.setZero(kg, kg);
      g.wg.setZero(kg);
      g.damped.setZero(ng, ng);
      g.rhs.setZero(ng);
      g.llt = Eigen::LLT<Eigen::MatrixXd>(ng);
    }
    u_.setZero(nc_, nc_);
    s_.setZero(nc_, nc_);
    s_llt_ = Eigen::LLT<Eigen::MatrixXd>(nc_);
    rhs_c_.setZero(nc_);
    dc_.setZero(nc_);
    auto camera_row = [&](const Group& g, int c) {
      return static_cast<int>(std::lower_bound(g.camera_rows.begin(), g.camera_rows.end(), c) - g.camera_rows.begin());
    };
    auto entry = [&](int a, int b) -> double* {
      if (a < nc_ && b < nc_) return &u_(std::max(a, b), std::min(a, b));
      if (a >= nc_ && b >= nc_) {
        Group& g = groups_[group_of_[a]];
        return &g.v(std::max(local_[a], local_[b]), std::min(local_[a], local_[b]));
      }
      const int c = std::min(a, b), p = std::max(a, b);
      Group& g = groups_[group_of_[p]];
      return &g.w(camera_row(g, c), local_[p]);
    };
    targets_.clear();
    for (const ResidualBlock& b : problem.blocks) {
      std::vector<double*> t;
      t.reserve(b.cols.size() * (b.cols.size() + 1) / 2);
      for (size_t i = 0; i < b.cols.size(); ++i) {
        for (size_t j = 0; j <= i; ++j) t.push_back(entry(b.cols[i], b.cols[j]));
      }
      targets_.push_back(std::move(t));
    }
    diagonal_.resize(n);
    for (int k = 0; k < n; ++k) diagonal_[k] = entry(k, k);
    g_.setZero(n);
    d_.setZero(n);
    h_diag_.setZero(n);
    return true;
  }

  void Assemble(const JointProblem& problem) override {
    u_.setZero();
    for (Group& g : groups_) {
      g.v.setZero();
      g.w.setZero();
    }
    g_.setZero();
    for (size_t bi = 0; bi < problem.blocks.size(); ++bi) {
      const ResidualBlock& b = problem.blocks[bi];
      double* const* t = targets_[bi].data();
      const int m = static_cast<int>(b.cols.size());
      for (int i = 0; i < m; ++i) {
        const auto ci = b.jacobian.col(i);
        g_(b.cols[i]) += ci.dot(b.residual);
        for (int j = 0; j <= i; ++j) **t++ += ci.dot(b.jacobian.col(j));
      }
    }
    for (size_t k = 0; k < diagonal_.size(); ++k) h_diag_(k) = *diagonal_[k];
    SetDamping();
  }

  bool Solve(double lambda, Eigen::VectorXd* delta) override {
    delta->resize(static_cast<Eigen::Index>(diagonal_.size()));
    s_ = u_;
    for (int k = 0; k < nc_; ++k) s_(k, k) += lambda * d_(k);
    rhs_c_ = -g_.head(nc_);
    for (Group& g : groups_) {
      const int ng = static_cast<int>(g.params.size());
      g.damped = g.v;
      for (int i = 0; i < ng; ++i) {
        g.damped(i, i) += lambda * d_(g.params[i]);
        g.rhs(i) = g_(g.params[i]);
      }
      g.llt.compute(g.damped);
      if (g.llt.info() != Eigen::Success) return false;
      g.llt.solveInPlace(g.rhs);  // V^-1 g_p
      if (g.camera_rows.empty()) continue;
      g.y = g.w.transpose();
      g.llt.solveInPlace(g.y);  // V^-1 W^T
      const int kg = static_cast<int>(g.camera_rows.size());
      g.wy.noalias() = g.w * g.y;
      g.wg.noalias() = g.w * g.rhs;
      for (int b = 0; b < kg; ++b) {
        const int rb = g.camera_rows[b];
        rhs_c_(rb) += g.wg(b);
        for (int a = b; a < kg; ++a) s_(g.camera_rows[a], rb) -= g.wy(a, b);
      }
    }
    if (nc_ > 0) {
      s_llt_.compute(s_);
      if (s_llt_.info() != Eigen::Success) return false;
      dc_ = rhs_c_;
      s_llt_.solveInPlace(dc_);
      delta->head(nc_) = dc_;
    }
    for (Group& g : groups_) {
      for (size_t a = 0; a < g.camera_rows.size(); ++a) g.wg(a) = dc_(g.camera_rows[a]);
      g.rhs.noalias() += g.y * g.wg;
      for (size_t i = 0; i < g.params.size(); ++i) (*delta)(g.params[i]) = -g.rhs(i);
    }
    return delta->allFinite();
  }

 private:
  struct Group {
    std::vector<int> params;       // parameter indices, in local order
    std::vector<int> camera_rows;  // camera parameters coupled to the group, sorted
    Eigen::MatrixXd v;             // J_p^T J_p (lower triangle)
    Eigen::MatrixXd w;             // J_c^T J_p over camera_rows
    Eigen::MatrixXd y;             // V^-1 W^T
    Eigen::MatrixXd wy;            // W V^-1 W^T
    Eigen::VectorXd wg;            // W V^-1 g_p
    Eigen::MatrixXd damped;
    Eigen::VectorXd rhs;
    Eigen::LLT<Eigen::MatrixXd> llt;
  };
  int nc_ = 0;
  std::vector<Group> groups_;
  std::vector<int> group_of_;
  std::vector<int> local_;
  std::vector<std::vector<double*>> targets_;
  std::vector<double*> diagonal_;
  Eigen::MatrixXd u_;  // J_c^T J_c (lower triangle)
  Eigen::MatrixXd s_;  // reduced camera system (lower triangle)
  Eigen::LLT<Eigen::MatrixXd> s_llt_;
  Eigen::VectorXd rhs_c_;
  Eigen::VectorXd dc_;
};

double TotalCost(const JointProblem& problem) {
  double cost = 0.0;
  for (const ResidualBlock& b : problem.blocks) cost += b.residual.squaredNorm();
  return 0.5 * cost;
}

double ObservationCost(const JointProblem& problem) {
  double cost = 0.0;
  for (const ResidualBlock& b : problem.blocks) {
    if (b.kind != BlockKind::kConstraint) cost += b.residual.squaredNorm();
  }
  return 0.5 * cost;
}

double MaxConstraintViolation(const JointProblem& problem) {
  double v = 0.0;
  for (const ResidualBlock& b : problem.blocks) {
    if (b.kind == BlockKind::kConstraint && b.raw.size() > 0) v = std::max(v, b.raw.cwiseAbs().maxCoeff());
  }
  return v;
}

bool StateIsFinite(const JointState& state) {
  for (const CameraState& c : state.cameras) {
    if (!std::isfinite(c.focal_px) || !c.principal_point_px.allFinite() || !c.cam_from_world_rotation.allFinite() ||
        !c.center_in_world.allFinite() || !std::isfinite(c.k1) || !std::isfinite(c.k2)) {
      return false;
    }
  }
  for (const PrimitiveState& p : state.primitives) {
    if (!p.params.allFinite() || !p.world_from_primitive.allFinite() || !p.translation.allFinite()) return false;
  }
  for (const Eigen::Vector3d& o : state.free_offsets) {
    if (!o.allFinite()) return false;
  }
  return true;
}

// What an inner LM run needs beyond the problem: the normal equations and the buffers of a
// trial, kept across the outer rounds.
struct LmWorkspace {
  NormalEquations* normal = nullptr;
  JointState trial;
  Eigen::VectorXd delta;
  int iterations = 0;  // over all rounds
  // The damping after the last accepted step: the next outer round starts from it, not from
  // the lambda that the rejections at the end of a converged run inflated.
  double accepted_lambda = 1e-4;
  // SolveJointTraced: every trial of every round, numbered over all rounds.
  std::vector<LmIteration>* trace = nullptr;
};

enum class LmStop { kConverged, kBudget, kFailed };

// The joint problem at fixed constraint weights and multipliers, for the LM driver
// (core/optim/levenberg_marquardt.h).
class JointLmProblem {
 public:
  JointLmProblem(const JointSolveOptions& options, int budget, double cost, JointProblem* problem, JointState* state,
                 LmWorkspace* workspace)
      : options_(options), budget_(budget), cost_(cost), problem_(problem), state_(state), workspace_(workspace) {}

  // False when the blocks hold a rejected trial's evaluation rather than the state's.
  bool evaluated_at_state() const { return evaluated_at_state_; }

  bool Linearize() {
    // The budget is tested before the linearisation: the last trial of a frame's budget must
    // not pay for an assembly nobody uses. Returning false here lets the driver stop on it.
    if (trials_ >= budget_) return false;
    NormalEquations& normal = *workspace_->normal;
    normal.Assemble(*problem_);
    // Gradient with unit-norm columns: in px, whatever the parameters' units.
    double max_gradient = 0.0;
    for (int k = 0; k < problem_->num_parameters; ++k) {
      const double h = normal.HessianDiagonal(k);
      if (h > 0.0) max_gradient = std::max(max_gradient, std::abs(normal.gradient()(k)) / std::sqrt(h));
    }
    return max_gradient <= options_.gradient_tolerance;
  }

  LmStepStatus Step(double lambda, LmTrial* trial) {
    ++trials_;
    NormalEquations& normal = *workspace_->normal;
    Eigen::VectorXd& delta = workspace_->delta;
    if (!normal.Solve(lambda, &delta)) return LmStepStatus::kSolveFailed;
    const Eigen::VectorXd& d = normal.damping();
    double scaled_step = 0.0;
    for (int k = 0; k < problem_->num_parameters; ++k) scaled_step += d(k) * delta(k) * delta(k);
    const double predicted = 0.5 * (lambda * scaled_step - normal.gradient().dot(delta));
    if (std::sqrt(scaled_step) <=
        options_.parameter_tolerance * (std::sqrt(2.0 * cost_) + options_.parameter_tolerance)) {
      return LmStepStatus::kStepNegligible;
    }
    // The model promises less than the cost's working precision: every further step would be
    // rounding noise, rejected one by one while lambda climbs to its cap.
    if (predicted <= options_.function_tolerance * cost_) return LmStepStatus::kStepNegligible;
    ApplyStep(*problem_, delta, *state_, &workspace_->trial);
    const bool ok = EvaluateBlocks(problem_, workspace_->trial, true);
    evaluated_at_state_ = false;
    trial_cost_ = ok ? TotalCost(*problem_) : std::numeric_limits<double>::infinity();
    trial->cost = trial_cost_;
    trial->step_squared_norm = scaled_step;
    trial->predicted_decrease = predicted;
    return LmStepStatus::kSolved;
  }

  void Accept() {
    std::swap(*state_, workspace_->trial);
    cost_ = trial_cost_;
    evaluated_at_state_ = true;
  }

 private:
  const JointSolveOptions& options_;
  const int budget_;
  double cost_;
  JointProblem* problem_;
  JointState* state_;
  LmWorkspace* workspace_;
  int trials_ = 0;
  double trial_cost_ = 0.0;
  bool evaluated_at_state_ = true;
};

// Levenberg-Marquardt on the current problem (its constraint weights and multipliers fixed)
// from *state, using at most `budget` iterations. The problem's blocks hold the evaluation at
// *state on return.
LmStop RunLevenbergMarquardt(const JointSolveOptions& options, int budget, JointProblem* problem, JointState* state,
                             LmWorkspace* workspace, std::string* why) {
  if (!EvaluateBlocks(problem, *state, true)) {
    *why = "a pinned vertex lies behind its camera";
    return LmStop::kFailed;
  }
  JointLmProblem lm_problem(options, budget, TotalCost(*problem), problem, state, workspace);
  LmOptions lm;
  lm.max_iterations = budget;
  lm.schedule = LmSchedule::kGainRatio;
  lm.initial_lambda = std::min(workspace->accepted_lambda, options.initial_lambda);
  lm.relative_decrease_tolerance = options.function_tolerance;
  // Rules that differ from the defaults: every trial counts against the budget (the drag
  // frame's 5 iterations are trials); a step is accepted only with rho > 1e-4 (a decrease that
  // small next to the model's prediction is not trusted); a factorisation failure says nothing
  // about the model's fit, so it raises lambda tenfold without touching nu, up to 1e32 before
  // the solve fails; lambda's floor is 1e-16, so that near the minimum the steps are
  // Gauss-Newton steps; the step tests are the caller's (Step's kStepNegligible: the relative
  // step and the predicted-decrease pre-check), hence no absolute step bound.
  lm.count_every_trial = true;
  lm.min_gain_ratio = 1e-4;
  lm.lambda_increase_on_failed_solve = 10.0;
  lm.max_lambda_on_failed_solve = 1e32;
  lm.min_lambda = 1e-16;
  lm.min_step_squared_norm = 0.0;
  if (workspace->trace != nullptr) {
    lm.callback = [workspace](const LmIteration& iteration) {
      LmIteration numbered = iteration;
      numbered.iteration += workspace->iterations;
      workspace->trace->push_back(numbered);
      return true;
    };
  }
  const LmResult result = MinimizeLevenbergMarquardt(TotalCost(*problem), lm, lm_problem);
  workspace->iterations += result.iterations;
  workspace->accepted_lambda = result.final_lambda;
  if (result.termination == LmTermination::kLinearSolveFailed) {
    *why = "the normal equations cannot be solved";
    return LmStop::kFailed;
  }
  if (!lm_problem.evaluated_at_state()) EvaluateBlocks(problem, *state, true);
  // Exact zero cost after the budget's last trial is still the budget (it is tested first).
  const bool budget_used = result.termination == LmTermination::kMaxIterations ||
                           (result.termination == LmTermination::kZeroCost && result.iterations >= budget);
  return budget_used ? LmStop::kBudget : LmStop::kConverged;
}

// Cold start: the geometry solve's linear initialisation (camera centres and dimensions
// with intrinsics and rotations held) gives the start, when the scene is small enough for
// its dense algebra; otherwise, or when it fails, the project's values are the start.
// Returns the project the solve starts from (`project` or *initialised), *problem and *state
// built from it.
const Project* ColdStart(const Project& project, const JointSolveOptions& options, const BuildOptions& build,
                         Project* initialised, JointProblem* problem, JointState* state) {
  if (options.warm_start || problem->num_parameters == 0 || problem->num_parameters > kMaxColdStartParameters) {
    return &project;
  }
  SceneSolveOptions scene_options;
  scene_options.warm_start = false;
  const SceneSolveSummary init = SolveScene(project, scene_options, initialised);
  if (init.IsUsable()) {
    *state = JointState();
    *problem = BuildJointProblem(*initialised, build, state);
    return initialised;
  }
  if (init.termination != SolverTermination::kNothingToSolve) {
    problem->warnings.push_back("cold start: the geometry solve gave no start (" + init.message +
                                "); started from the project's values");
  }
  return &project;
}

// The observation cost still to pay for the violation: sum |lambda_i c_i| with the updated
// multipliers lambda + mu c (first order). A violation within constraint_tolerance can still
// leave the cost far from its constrained minimum when a constraint fights the pins: a line
// pin 3 px off has lambda ~ 3 px x focal, so c = 5e-10 rad left 2e-6 of the cost.
double ConstraintCostGap(const JointProblem& problem, double mu) {
  double cost_gap = 0.0;
  for (const ResidualBlock& b : problem.blocks) {
    if (b.kind != BlockKind::kConstraint) continue;
    cost_gap += std::abs((problem.constraints[b.source].multiplier + mu * b.raw).dot(b.raw));
  }
  return cost_gap;
}

struct RoundsOutcome {
  bool failed = false;
  std::string why;  // when failed
  bool budget_used = false;
};

// The augmented Lagrangian's outer rounds (joint_solve.h gives the schedule): an inner LM run
// per round, then the multiplier update and a stiffer penalty when the violation did not drop
// enough; without constraints, one LM run.
RoundsOutcome RunOuterRounds(const JointSolveOptions& options, JointProblem* problem, JointState* state,
                             LmWorkspace* lm) {
  RoundsOutcome outcome;
  double previous_violation = std::numeric_limits<double>::infinity();
  const bool has_constraints = !problem->constraints.empty();
  bool final_round = false;
  for (int round = 0;; ++round) {
    const int budget = options.max_iterations - lm->iterations;
    if (budget <= 0) {
      outcome.budget_used = true;
      break;
    }
    const LmStop stop = RunLevenbergMarquardt(options, budget, problem, state, lm, &outcome.why);
    if (stop == LmStop::kFailed) {
      outcome.failed = true;
      return outcome;
    }
    if (stop == LmStop::kBudget) outcome.budget_used = true;
    if (!has_constraints || outcome.budget_used || final_round) break;
    const double violation = MaxConstraintViolation(*problem);
    const double mu = problem->constraint_weight * problem->constraint_weight;
    const double cost_gap = ConstraintCostGap(*problem, mu);
    const bool held = violation <= options.constraint_tolerance;
    if (held && cost_gap <= kCostGapTolerance * ObservationCost(*problem) + kCostGapFloorPx2) break;
    if (!held && round + 1 >= kMaxOuterRounds) break;
    // Multiplier update, then a stiffer penalty when the violation did not drop enough.
    for (const ResidualBlock& b : problem->blocks) {
      if (b.kind == BlockKind::kConstraint) problem->constraints[b.source].multiplier += mu * b.raw;
    }
    if (held) {
      // One last round at the stiffest penalty: the multipliers are nearly exact by now, so
      // it takes a step or two, and it resolves c to ~sqrt(2 eps cost) / weight where the
      // AL's rounds at a moderate weight stall (the merit's rounding hides smaller c).
      final_round = true;
      problem->constraint_weight = kMaxConstraintWeight;
      continue;
    }
    if (violation > 0.25 * previous_violation) {
      problem->constraint_weight = std::min(problem->constraint_weight * std::sqrt(10.0), kMaxConstraintWeight);
    }
    previous_violation = violation;
  }
  return outcome;
}

// The median of a 2D isotropic Gaussian residual's norm (a Rayleigh variable) over its
// per-axis sigma: sqrt(2 ln 2).
constexpr double kRayleighMedianOverSigma = 1.1774100225154747;
// Reweighted rounds stop once no pin's weight moved by more than this.
constexpr double kRobustWeightTolerance = 1e-3;

// The pins' noise scale (px) from their unweighted residuals at the problem's last
// evaluation, or 0 when there are too few pins for a spread to mean anything.
double RobustPinScale(const JointSolveOptions& options, const JointProblem& problem) {
  std::vector<double> norms;
  for (const ResidualBlock& b : problem.blocks) {
    if (b.kind == BlockKind::kPin) norms.push_back(b.raw.norm());
  }
  if (static_cast<int>(norms.size()) < options.robust_min_pins) return 0.0;
  const size_t mid = norms.size() / 2;
  std::nth_element(norms.begin(), norms.begin() + mid, norms.end());
  double median = norms[mid];
  if (norms.size() % 2 == 0) median = 0.5 * (median + *std::max_element(norms.begin(), norms.begin() + mid));
  return std::max(median / kRayleighMedianOverSigma, options.robust_min_scale_px);
}

// The robust loss's weight on a squared residual of norm e (JointSolveOptions::robust_pins).
double RobustPinWeight(const JointSolveOptions& options, double sigma, double e) {
  const double c = options.huber_scale * sigma;
  const double t = options.outlier_scale * sigma;
  if (!(e > c)) return 1.0;
  if (e <= t) return c / e;
  return (c / e) * (t / e) * (t / e);
}

// Sets every pin block's weight from its residual at the last evaluation; returns the largest
// change of a weight.
double UpdatePinWeights(const JointSolveOptions& options, double sigma, JointProblem* problem) {
  double change = 0.0;
  for (ResidualBlock& b : problem->blocks) {
    if (b.kind != BlockKind::kPin) continue;
    const double w = RobustPinWeight(options, sigma, b.raw.norm());
    change = std::max(change, std::abs(w - b.weight * b.weight));
    b.weight = std::sqrt(w);
  }
  return change;
}

// Iteratively reweighted solves from the least-squares result (the blocks evaluated at
// *state) until the weights settle, the budget runs out or max_robust_rounds. Returns the
// noise scale used (0: the loss did not run).
double RunRobustRounds(const JointSolveOptions& options, JointProblem* problem, JointState* state, LmWorkspace* lm,
                       RoundsOutcome* outcome) {
  if (!options.robust_pins) return 0.0;
  double sigma = RobustPinScale(options, *problem);
  if (sigma == 0.0) return 0.0;
  for (int round = 0; round < options.max_robust_rounds && !outcome->budget_used; ++round) {
    if (UpdatePinWeights(options, sigma, problem) <= kRobustWeightTolerance) break;
    *outcome = RunOuterRounds(options, problem, state, lm);
    if (outcome->failed) break;
    sigma = RobustPinScale(options, *problem);
  }
  return sigma;
}

// The constraints' values at the start (raw, per constraint block in block order), so that
// the result can be compared with the start on the same exact-penalty merit.
std::vector<Eigen::VectorXd> ConstraintValues(const JointProblem& problem) {
  std::vector<Eigen::VectorXd> values;
  for (const ResidualBlock& b : problem.blocks)
    if (b.kind == BlockKind::kConstraint) values.push_back(b.raw);
  return values;
}

// Where the solve started, on the merit the result is judged by.
struct StartPoint {
  double observation_cost = 0.0;
  std::vector<Eigen::VectorXd> constraint_values;  // ConstraintValues at the start
  // Per block, the unweighted squared norm of an observation block's residual (0 for a
  // constraint block), so that the start can be costed with the robust weights at the end.
  std::vector<double> observation_squared_norms;
};

StartPoint StartPointOf(const JointProblem& problem) {
  StartPoint start{ObservationCost(problem), ConstraintValues(problem), {}};
  for (const ResidualBlock& b : problem.blocks) {
    const bool observation = b.kind != BlockKind::kConstraint;
    start.observation_squared_norms.push_back(
        !observation ? 0.0 : (b.kind == BlockKind::kPin ? b.raw.squaredNorm() : b.residual.squaredNorm()));
  }
  return start;
}

// The start's observation cost under the blocks' current weights, so that it compares with
// the (weighted) result's.
StartPoint WeightedStart(const JointProblem& problem, StartPoint start) {
  double cost = 0.0;
  for (size_t i = 0; i < problem.blocks.size() && i < start.observation_squared_norms.size(); ++i) {
    const ResidualBlock& b = problem.blocks[i];
    cost += (b.kind == BlockKind::kPin ? b.weight * b.weight : 1.0) * start.observation_squared_norms[i];
  }
  start.observation_cost = 0.5 * cost;
  return start;
}

// The exact (L1) penalty merit obs + sum_i w_i |c_i| at the result and at the start, with
// w_i = 2 |lambda_i|, lambda_i = multiplier + mu c the final multiplier estimate (first order).
// With weights above the multipliers a constrained minimum is a local minimum of this merit
// (Han 1977), so a result that solved the problem is never above the start on it, while the
// observation cost alone can rise: a start that breaks a constraint (a drag preview, a
// geometry solve that ignores the constraints) buys pixels with the violation. Without
// constraints it is the observation cost.
void ExactPenaltyMerits(const JointProblem& problem, const StartPoint& start, double final_cost, double* at_start,
                        double* at_result) {
  const double mu = problem.constraint_weight * problem.constraint_weight;
  *at_start = start.observation_cost;
  *at_result = final_cost;
  size_t k = 0;
  for (const ResidualBlock& b : problem.blocks) {
    if (b.kind != BlockKind::kConstraint) continue;
    const Eigen::VectorXd weight = 2.0 * (problem.constraints[b.source].multiplier + mu * b.raw).cwiseAbs();
    if (k < start.constraint_values.size() && start.constraint_values[k].size() == weight.size())
      *at_start += weight.dot(start.constraint_values[k].cwiseAbs());
    *at_result += weight.dot(b.raw.cwiseAbs());
    ++k;
  }
}

// Why the solve's result must not be used, or "" when it may: non-finite values, a pinned
// vertex behind its camera (`evaluated` false), or a result above the start on the exact
// penalty merit (ExactPenaltyMerits).
std::string WhyResultUnusable(const JointProblem& problem, const JointState& state, bool evaluated, double final_cost,
                              const StartPoint& start) {
  if (!StateIsFinite(state) || !std::isfinite(final_cost)) {
    return "the solve diverged (non-finite values); the model is unchanged";
  }
  if (!evaluated) return "after the solve a pinned vertex lies behind its camera; the model is unchanged";
  double merit_start = 0.0, merit_result = 0.0;
  ExactPenaltyMerits(problem, start, final_cost, &merit_start, &merit_result);
  if (!(merit_result <= merit_start * (1.0 + 1e-9) + 1e-18)) {
    std::ostringstream text;
    text << "the solve increased the cost from " << merit_start << " to " << merit_result
         << " px^2 (pins and lines, with the constraints' violation at their multipliers); the model is unchanged";
    return text.str();
  }
  return "";
}

std::string Advice(const std::string& name) {
  if (name.find("free vertex") != std::string::npos) return "pin that vertex in a second image";
  if (name.rfind("the camera", 0) == 0) return "pin more vertices in that image, add segments, or lock it";
  if (name.find("rotation") != std::string::npos || name.find("position") != std::string::npos) {
    return "pin more of its vertices, add a constraint, or lock its pose";
  }
  return "pin a vertex that moves with it (e.g. on its back face) or add a second image, or lock it";
}

// Names the parameters the residuals do not determine, from the null space of the
// column-scaled dense Jacobian at the problem's last evaluation.
std::vector<std::string> UndeterminedParameters(const JointProblem& problem, int* null_space_dimension) {
  std::vector<std::string> out;
  const int n = problem.num_parameters;
  Eigen::MatrixXd j;
  Eigen::VectorXd r;
  DenseJacobian(problem, &j, &r);
  Eigen::VectorXd norms = j.colwise().norm().transpose();
  const double max_norm = norms.size() > 0 ? norms.maxCoeff() : 0.0;
  for (int k = 0; k < n; ++k) {
    if (norms(k) <= kRankTolerance * max_norm) {
      j.col(k).setZero();
    } else {
      j.col(k) /= norms(k);
    }
  }
  Eigen::MatrixXd padded = j;
  if (padded.rows() < n) {
    padded.conservativeResize(n, n);
    padded.bottomRows(n - j.rows()).setZero();
  }
  Eigen::BDCSVD<Eigen::MatrixXd> svd(padded, Eigen::ComputeThinV);
  const Eigen::VectorXd& sigma = svd.singularValues();
  const double largest = sigma.size() > 0 ? sigma(0) : 0.0;
  std::vector<int> null_columns;
  for (int s = 0; s < sigma.size(); ++s) {
    if (sigma(s) <= kRankTolerance * largest) null_columns.push_back(s);
  }
  const int null_dim = static_cast<int>(null_columns.size());
  *null_space_dimension = null_dim;
  if (null_dim == 0) return out;
  Eigen::MatrixXd null_space(n, null_dim);
  for (int i = 0; i < null_dim; ++i) null_space.col(i) = svd.matrixV().col(null_columns[i]);

  // Per object (a camera, a primitive, a free vertex: the part of the name before ": "), the
  // directions inside its own parameters that lie in the null space: moving that object
  // alone that way changes no residual.
  std::vector<std::pair<std::string, std::vector<int>>> owners;
  for (int k = 0; k < n; ++k) {
    const std::string& name = problem.parameter_names[k];
    const std::string owner = name.substr(0, name.find(": "));
    if (owners.empty() || owners.back().first != owner) owners.push_back({owner, {}});
    owners.back().second.push_back(k);
  }
  std::vector<double> freedom(n, 0.0);
  for (int k = 0; k < n; ++k) freedom[k] = null_space.row(k).squaredNorm();
  int alone = 0;
  std::vector<char> named(n, 0);
  for (const auto& [owner, params] : owners) {
    Eigen::MatrixXd restricted(params.size(), null_dim);
    for (size_t i = 0; i < params.size(); ++i) restricted.row(i) = null_space.row(params[i]);
    Eigen::JacobiSVD<Eigen::MatrixXd> own(restricted, Eigen::ComputeThinU);
    for (int d = 0; d < own.singularValues().size(); ++d) {
      if (own.singularValues()(d) < 0.95) continue;  // not a motion of this object alone
      ++alone;
      const Eigen::VectorXd u = own.matrixU().col(d);
      int dominant = 0;
      u.cwiseAbs().maxCoeff(&dominant);
      const std::string& first = problem.parameter_names[params[dominant]];
      if (std::abs(u(dominant)) > 0.9) {
        out.push_back(first + " is free: " + Advice(first));
        named[params[dominant]] = 1;
        continue;
      }
      std::string what;
      for (size_t i = 0; i < params.size(); ++i) {
        if (std::abs(u(i)) < 0.3) continue;
        const std::string& name = problem.parameter_names[params[i]];
        what += (what.empty() ? "" : ", ") + name.substr(name.find(": ") + 2);
        named[params[i]] = 1;
      }
      out.push_back(owner + ": a combination of " + what + " is free: " + Advice(first));
    }
  }
  if (null_dim > alone) {
    std::vector<int> order(n);
    for (int k = 0; k < n; ++k) order[k] = k;
    std::sort(order.begin(), order.end(), [&](int a, int b) { return freedom[a] > freedom[b]; });
    std::ostringstream text;
    text << null_dim - alone << " combined motion(s) of several objects leave every residual unchanged (e.g. the "
         << "scene's scale or position): add a distance or fixed-point constraint or lock a dimension; most involved: ";
    int listed = 0;
    for (int k : order) {
      if (named[k] || freedom[k] < 1e-6 || listed == 4) continue;
      text << (listed++ > 0 ? "; " : "") << problem.parameter_names[k];
    }
    out.push_back(text.str());
  }
  return out;
}

// Equality polish over the whole parameter vector, in column-scaled steps from `start`.
ConstraintPolishSummary Polish(const JointSolveOptions& options, JointProblem* problem, JointState* state,
                               const NormalEquations& normal) {
  const int n = problem->num_parameters;
  Eigen::VectorXd scale(n);
  for (int k = 0; k < n; ++k) {
    const double h = normal.HessianDiagonal(k);
    scale(k) = h > 0.0 ? std::sqrt(h) : 1.0;
  }
  int num_constraints = 0;
  for (const ConstraintTerm& t : problem->constraints) num_constraints += t.num_rows;
  const JointState start = *state;
  JointState trial = start;
  Eigen::VectorXd delta(n);
  const double weight = problem->constraint_weight;
  auto evaluate = [&](const Eigen::VectorXd& y) {
    delta = y.cwiseQuotient(scale);
    ApplyStep(*problem, delta, start, &trial);
    return EvaluateBlocks(problem, trial, true);
  };
  ConstraintPolishProblem pp;
  pp.num_variables = n;
  pp.num_constraints = num_constraints;
  pp.objective = [&](const Eigen::VectorXd& y, Eigen::VectorXd* gradient) {
    const bool ok = evaluate(y);
    if (gradient != nullptr) gradient->setZero(n);
    if (!ok) return std::numeric_limits<double>::infinity();
    double f = 0.0;
    for (const ResidualBlock& b : problem->blocks) {
      if (b.kind == BlockKind::kConstraint) continue;
      f += 0.5 * b.residual.squaredNorm();
      if (gradient != nullptr) {
        for (size_t c = 0; c < b.cols.size(); ++c) (*gradient)(b.cols[c]) += b.jacobian.col(c).dot(b.residual);
      }
    }
    if (gradient != nullptr) *gradient = gradient->cwiseQuotient(scale);
    return f;
  };
  pp.constraints = [&](const Eigen::VectorXd& y, Eigen::VectorXd* values, Eigen::MatrixXd* jacobian) {
    evaluate(y);
    values->setZero(num_constraints);
    if (jacobian != nullptr) jacobian->setZero(num_constraints, n);
    int row = 0;
    for (const ResidualBlock& b : problem->blocks) {
      if (b.kind != BlockKind::kConstraint) continue;
      values->segment(row, b.num_rows) = b.raw;
      if (jacobian != nullptr) {
        for (size_t c = 0; c < b.cols.size(); ++c) {
          jacobian->block(row, b.cols[c], b.num_rows, 1) += b.jacobian.col(c) / (weight * scale(b.cols[c]));
        }
      }
      row += b.num_rows;
    }
  };
  ConstraintPolishOptions po;
  po.constraint_tolerance = options.constraint_tolerance;
  Eigen::VectorXd y = Eigen::VectorXd::Zero(n);
  ConstraintPolishSummary s = PolishConstraints(pp, po, &y);
  if (s.IsUsable()) {
    ApplyStep(*problem, y.cwiseQuotient(scale), start, state);
  }
  EvaluateBlocks(problem, *state, true);
  return s;
}

// Conflicts are named only after a solve that ran to convergence: a per-frame solve that
// used its budget may simply not have enforced the constraints yet.
void FillDiagnostics(const Project& project, const JointSolveOptions& options, const JointProblem& problem,
                     bool name_conflicts, JointSolveSummary* summary) {
  summary->pins.clear();
  summary->flagged_pins.clear();
  summary->num_downweighted_pins = 0;
  for (const Pin& pin : project.pins) summary->pins.push_back({pin.id, std::numeric_limits<double>::quiet_NaN(), 1.0});
  std::map<int, ImageDiagnostic> per_camera;
  double sum_sq = 0.0, max_px = 0.0;
  int count = 0;
  for (const ResidualBlock& b : problem.blocks) {
    if (b.kind != BlockKind::kPin) continue;
    const double e = b.raw.norm();
    summary->pins[b.source].error_px = e;
    summary->pins[b.source].weight = b.weight * b.weight;
    if (b.weight < 1.0) ++summary->num_downweighted_pins;
    if (summary->pin_scale_px > 0.0 && e > options.outlier_scale * summary->pin_scale_px) {
      const Pin& pin = project.pins[b.source];
      FlaggedPin flagged{pin.id, pin.image_id, e, ""};
      const Image* image = project.FindImage(pin.image_id);
      const std::string photo = image != nullptr ? std::filesystem::path(image->path).stem().string()
                                                 : "image " + std::to_string(pin.image_id);
      flagged.sentence = "pin " + std::to_string(pin.id) + " in " + photo + " is " + internal::FormatNumber(e, 3) +
                         " px from where the model puts it";
      summary->flagged_pins.push_back(flagged);
    }
    ImageDiagnostic& d = per_camera[b.camera];
    d.image_id = project.images[problem.cameras[b.camera].image_index].id;
    ++d.num_pins;
    d.rms_px += e * e;
    d.max_px = std::max(d.max_px, e);
    sum_sq += e * e;
    max_px = std::max(max_px, e);
    ++count;
  }
  summary->images.clear();
  for (auto& [camera, d] : per_camera) {
    d.rms_px = std::sqrt(d.rms_px / d.num_pins);
    summary->images.push_back(d);
  }
  std::sort(summary->flagged_pins.begin(), summary->flagged_pins.end(),
            [](const FlaggedPin& a, const FlaggedPin& b) { return a.error_px > b.error_px; });
  summary->reprojection_rms_px = count > 0 ? std::sqrt(sum_sq / count) : 0.0;
  summary->reprojection_max_px = max_px;

  summary->constraints.clear();
  for (const Constraint& c : project.constraints) {
    ConstraintDiagnostic d;
    d.constraint_id = c.id;
    d.residual = std::numeric_limits<double>::quiet_NaN();
    summary->constraints.push_back(d);
  }
  summary->conflicts.clear();
  for (const ResidualBlock& b : problem.blocks) {
    if (b.kind != BlockKind::kConstraint) continue;
    const ConstraintTerm& term = problem.constraints[b.source];
    ConstraintDiagnostic& d = summary->constraints[term.constraint_index];
    d.residual = NaturalConstraintResidual(problem, term, b.raw, &d.unit);
    d.satisfied = b.raw.cwiseAbs().maxCoeff() <= options.conflict_tolerance;
    if (!d.satisfied && name_conflicts) {
      const Constraint& c = project.constraints[term.constraint_index];
      std::ostringstream text;
      text << "constraint " << c.id << " (" << ConstraintKindName(c.kind) << ") is not met: residual " << d.residual
           << " " << d.unit << "; it conflicts with other constraints or the pins";
      summary->conflicts.push_back(text.str());
    }
  }
}

}  // namespace

JointSolveSummary SolveJoint(const Project& project, const JointSolveOptions& options, Project* solved) {
  return SolveJointTraced(project, options, solved, nullptr);
}

JointSolveSummary SolveJointTraced(const Project& project, const JointSolveOptions& options, Project* solved,
                                   std::vector<LmIteration>* trace) {
  if (trace != nullptr) trace->clear();
  const auto t0 = std::chrono::steady_clock::now();
  JointSolveSummary summary;
  auto finish = [&](SolverTermination termination, const std::string& message) {
    summary.termination = termination;
    summary.message = message;
    summary.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return summary;
  };
  if (solved == nullptr) return finish(SolverTermination::kInvalidInput, "no output project given");
  *solved = project;
  std::string error;
  if (!options.Check(&error)) return finish(SolverTermination::kInvalidInput, "invalid options: " + error);

  BuildOptions build;
  build.refine_intrinsics = options.refine_intrinsics;
  build.use_segments = options.use_segments;
  JointState state;
  JointProblem problem = BuildJointProblem(project, build, &state);
  Project initialised;
  const Project* start = ColdStart(project, options, build, &initialised, &problem, &state);
  summary.warnings = problem.warnings;
  summary.num_parameters = problem.num_parameters;
  summary.num_residuals = problem.num_residuals;
  if (!StateIsFinite(state)) {
    return finish(SolverTermination::kInvalidInput, "a camera or primitive of the project has a non-finite value");
  }
  if (problem.blocks.empty())
    return finish(SolverTermination::kNothingToSolve, "no pins, segments or constraints to solve");
  if (problem.num_parameters == 0) {
    EvaluateBlocks(&problem, state, false);
    FillDiagnostics(project, options, problem, true, &summary);
    summary.initial_cost = summary.final_cost = ObservationCost(problem);
    return finish(SolverTermination::kNothingToSolve, "every parameter is locked");
  }
  problem.constraint_weight = kInitialConstraintWeight;

  if (!EvaluateBlocks(&problem, state, true)) {
    return finish(SolverTermination::kFailed,
                  "at the start a pinned vertex lies on or behind its camera; the model is unchanged");
  }
  summary.initial_cost = ObservationCost(problem);
  const StartPoint start_point = StartPointOf(problem);

  // The Schur complement on primitive groups, unless a constraint makes a group too large.
  SchurEquations schur;
  SparseEquations sparse;
  NormalEquations* normal_ptr = &schur;
  if (options.linear_solver != JointSolveOptions::LinearSolver::kSchur || !schur.Init(problem)) {
    normal_ptr = &sparse;
    if (!sparse.Init(problem))
      return finish(SolverTermination::kFailed, "the sparse normal equations could not be analysed");
  }
  NormalEquations& normal = *normal_ptr;
  LmWorkspace lm;
  lm.normal = &normal;
  lm.accepted_lambda = options.initial_lambda;
  lm.trial = state;
  lm.delta.resize(problem.num_parameters);
  lm.trace = trace;
  RoundsOutcome rounds = RunOuterRounds(options, &problem, &state, &lm);
  if (!rounds.failed) summary.pin_scale_px = RunRobustRounds(options, &problem, &state, &lm, &rounds);
  if (rounds.failed) {
    *solved = project;
    summary.iterations = lm.iterations;
    return finish(SolverTermination::kFailed, "the solve failed (" + rounds.why + "); the model is unchanged");
  }
  const bool budget_used = rounds.budget_used;
  summary.iterations = lm.iterations;
  EvaluateBlocks(&problem, state, true);
  normal.Assemble(problem);

  if (options.polish_constraints && !problem.constraints.empty()) {
    const ConstraintPolishSummary polish = Polish(options, &problem, &state, normal);
    summary.polished = polish.IsUsable();
    if (!polish.IsUsable()) summary.warnings.push_back("constraint polish: " + polish.message);
  }

  const bool evaluated = EvaluateBlocks(&problem, state, true);
  summary.final_cost = ObservationCost(problem);
  const std::string unusable =
      WhyResultUnusable(problem, state, evaluated, summary.final_cost, WeightedStart(problem, start_point));
  if (!unusable.empty()) {
    *solved = project;
    return finish(SolverTermination::kFailed, unusable);
  }

  FillDiagnostics(project, options, problem, !budget_used, &summary);
  for (const FlaggedPin& flagged : summary.flagged_pins) summary.warnings.push_back(flagged.sentence);
  if (options.compute_diagnostics) {
    if (problem.num_parameters <= kMaxDiagnosticParameters) {
      summary.undetermined = UndeterminedParameters(problem, &summary.degrees_of_freedom_left);
      summary.degrees_of_freedom_left += static_cast<int>(problem.held_parameters.size());
    } else {
      summary.warnings.push_back("undetermined parameters not analysed: " + std::to_string(problem.num_parameters) +
                                 " parameters exceed the dense limit of " + std::to_string(kMaxDiagnosticParameters));
    }
  }
  // Held shape parameters are undetermined too; they are named whether or not the rank
  // analysis ran, since no analysis is needed to see them.
  for (const JointProblem::HeldParameter& held : problem.held_parameters) {
    char value[32];
    std::snprintf(value, sizeof(value), "%.4g", held.value);
    summary.undetermined.push_back(held.name + " is free (seen by no pin, held at " + value +
                                   "): " + Advice(held.name));
  }
  if (start != &project) *solved = *start;
  WriteState(problem, state, solved);
  // Unlocked distortion, refined against few observations, can bend past any lens (k2 = -3
  // from 8 pins and a pinhole photo): no camera. The solve runs again with that distortion
  // held where it was, and says so; the image's lock setting is the user's and stays.
  Project held = project;
  std::vector<std::string> folded;
  for (const Image& image : solved->images) {
    const Image* old = project.FindImage(image.id);
    if (old == nullptr || (old->camera.k1 == image.camera.k1 && old->camera.k2 == image.camera.k2)) continue;
    const std::string folds = WhyDistortionFolds(image.camera.k1, image.camera.k2, image.camera.focal_px,
                                                 image.camera.principal_point_px, image.width_px, image.height_px);
    if (folds.empty()) continue;
    held.FindImage(image.id)->distortion_locked = true;
    folded.push_back("image '" + image.path + "': " + folds + "; its distortion was held at k1 = " +
                     internal::FormatNumber(old->camera.k1, 4) + ", k2 = " + internal::FormatNumber(old->camera.k2, 4) +
                     " (draw plumb lines to estimate it, or lock it)");
  }
  // A focal length that ran away (kMaxSolvedFocalPerDiagonal) is held the same way, for
  // every photo of its lens.
  for (const Image& image : solved->images) {
    const Image* old = project.FindImage(image.id);
    if (old == nullptr || old->focal_locked || old->camera.focal_px == image.camera.focal_px) continue;
    const double diagonal = std::hypot(static_cast<double>(image.width_px), static_cast<double>(image.height_px));
    const double start_per_diagonal = old->camera.focal_px / diagonal;
    const double per_diagonal = image.camera.focal_px / diagonal;
    const bool ran_away = !(per_diagonal >= kMinFocalPerDiagonal && per_diagonal <= kMaxSolvedFocalPerDiagonal);
    const bool start_was_a_lens =
        start_per_diagonal >= kMinFocalPerDiagonal && start_per_diagonal <= kMaxSolvedFocalPerDiagonal;
    if (!ran_away || !start_was_a_lens || held.FindImage(image.id)->focal_locked) continue;
    for (Image& same_lens : held.images) {
      if (same_lens.id == image.id || (image.lens_group > 0 && same_lens.lens_group == image.lens_group))
        same_lens.focal_locked = true;
    }
    folded.push_back("image '" + image.path + "': the solve took its focal length to " +
                     internal::FormatNumber(image.camera.focal_px, 6) + " px (" +
                     internal::FormatNumber(per_diagonal, 3) + " image diagonals, beyond any lens up to " +
                     internal::FormatNumber(kMaxSolvedFocalPerDiagonal, 3) +
                     "): the pins do not fix it; it was held at " + internal::FormatNumber(old->camera.focal_px, 6) +
                     " px (pin points at other depths, add a photo from another side, or give the focal length)");
  }
  if (!folded.empty()) {
    JointSolveSummary again = SolveJoint(held, options, solved);
    if (!again.IsUsable()) {
      *solved = project;
    } else {
      for (const Image& image : project.images) {
        Image* out = solved->FindImage(image.id);
        out->distortion_locked = image.distortion_locked;
        out->focal_locked = image.focal_locked;
      }
    }
    again.held_intrinsics = folded;
    again.warnings.insert(again.warnings.begin(), folded.begin(), folded.end());
    return again;
  }
  if (const std::string degenerate = WhySolvedModelDegenerate(project, *solved); !degenerate.empty()) {
    *solved = project;
    summary.undetermined.clear();
    summary.degenerate = true;
    return finish(SolverTermination::kFailed, degenerate + "; the model is unchanged");
  }
  std::ostringstream text;
  text << "RMS " << summary.reprojection_rms_px << " px over " << summary.pins.size() << " pins after "
       << summary.iterations << " iterations";
  if (summary.num_downweighted_pins > 0) {
    text << "; " << summary.num_downweighted_pins << " pin" << (summary.num_downweighted_pins == 1 ? "" : "s")
         << " down-weighted (noise scale " << internal::FormatNumber(summary.pin_scale_px, 3) << " px)";
  }
  return finish(budget_used ? SolverTermination::kMaxIterations : SolverTermination::kConverged, text.str());
}

std::string WhySolvedModelDegenerate(const Project& before, const Project& solved) {
  // A solve that shrinks a size a millionfold, to a millionth of the primitive's reach, has
  // found no dimension but the null direction of an unfixed scale (sizes of 1e-16 were seen
  // with 15.6 px pin RMS). One that grows a size or moves the model a million times its reach
  // has run its cameras and the model off towards infinity together (a box of 4 m became 4e8
  // m at 96 px RMS after a horizon that contradicted the line families; 7e4 m when the
  // iterations ran out sooner): no observation puts a model there.
  const ModelChangeCheck check = CheckModelChange(before, solved);
  switch (check.fault) {
    case ModelChangeFault::kNone: return "";
    case ModelChangeFault::kNonPositive:
      return "a size would be zero or negative: " + check.what + " (a size must stay above 0)";
    case ModelChangeFault::kCollapsed:
      return "the model collapsed: " + check.what +
             " (nothing the pins see fixes the scale, or the constraints contradict the pins)";
    case ModelChangeFault::kGrew:
    case ModelChangeFault::kRanAway:
      return "the model ran off to infinity: " + check.what +
             (check.scale_given ? " (the cameras and the pins disagree, e.g. a horizon or lines that contradict the photo)"
                                : " (nothing fixes the model's scale: set a known length on an edge the pins see, or "
                                  "lock a size you know)");
  }
  return "";
}

}  // namespace facet
