// The Levenberg-Marquardt driver (core/optim/levenberg_marquardt.h) on its own: Rosenbrock's
// valley, a noise-free exponential fit, a rank-deficient problem, both damping schedules, the
// stop tests, the callback and LmOptions::Check.
#include <doctest/doctest.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "core/optim/levenberg_marquardt.h"
#include "core/util/eigen_decompositions.h"

namespace facet {
namespace {

// A dense problem with additive updates: residuals(x) and their Jacobian, Marquardt's
// scaling with a small floor so that a zero column stays solvable.
struct DenseProblem {
  std::function<Eigen::VectorXd(const Eigen::VectorXd&)> residuals;
  std::function<Eigen::MatrixXd(const Eigen::VectorXd&)> jacobian;
  Eigen::VectorXd x, candidate, gradient;
  Eigen::MatrixXd normal;
  int linearizations = 0;
  double gradient_tolerance = -1.0;  // < 0: no gradient test

  double Cost(const Eigen::VectorXd& at) const { return 0.5 * residuals(at).squaredNorm(); }
  bool Linearize() {
    ++linearizations;
    const Eigen::MatrixXd j = jacobian(x);
    normal = j.transpose() * j;
    gradient = j.transpose() * residuals(x);
    return gradient.lpNorm<Eigen::Infinity>() <= gradient_tolerance;
  }
  LmStepStatus Step(double lambda, LmTrial* trial) {
    Eigen::MatrixXd damped = normal;
    const Eigen::VectorXd damping = normal.diagonal().array() + 1e-12;
    damped.diagonal() += lambda * damping;
    const Eigen::VectorXd delta = damped.ldlt().solve(-gradient);
    if (!delta.allFinite()) return LmStepStatus::kSolveFailed;
    candidate = x + delta;
    trial->cost = Cost(candidate);
    trial->step_squared_norm = delta.squaredNorm();
    trial->predicted_decrease = 0.5 * delta.dot(lambda * damping.cwiseProduct(delta) - gradient);
    return LmStepStatus::kSolved;
  }
  void Accept() { x = candidate; }
};

DenseProblem Rosenbrock(double a, double b) {
  DenseProblem p;
  p.residuals = [=](const Eigen::VectorXd& x) {
    Eigen::VectorXd r(2);
    r << a - x(0), std::sqrt(b) * (x(1) - x(0) * x(0));
    return r;
  };
  p.jacobian = [=](const Eigen::VectorXd& x) {
    Eigen::MatrixXd j(2, 2);
    j << -1.0, 0.0, -2.0 * std::sqrt(b) * x(0), std::sqrt(b);
    return j;
  };
  p.x = Eigen::Vector2d(-1.2, 1.0);
  return p;
}

LmOptions TightOptions(LmSchedule schedule) {
  LmOptions o;
  o.schedule = schedule;
  o.max_iterations = 500;
  o.relative_decrease_tolerance = 0.0;
  o.min_step_squared_norm = 0.0;
  if (schedule == LmSchedule::kGainRatio) {
    o.count_every_trial = true;
    o.lambda_increase_on_failed_solve = 0.0;
    o.max_lambda = o.max_lambda_on_failed_solve = 1e32;
    o.min_lambda = 0.0;
  }
  return o;
}

TEST_CASE("Rosenbrock's valley: both schedules reach (a, a^2) to 1e-9 from the classic start") {
  for (LmSchedule schedule : {LmSchedule::kFixedFactors, LmSchedule::kGainRatio}) {
    CAPTURE(static_cast<int>(schedule));
    DenseProblem p = Rosenbrock(1.0, 100.0);
    const LmResult r = MinimizeLevenbergMarquardt(p.Cost(p.x), TightOptions(schedule), p);
    CHECK(p.x(0) == doctest::Approx(1.0).epsilon(1e-9));
    CHECK(p.x(1) == doctest::Approx(1.0).epsilon(1e-9));
    CHECK(r.final_cost == p.Cost(p.x));  // the state returned is the one whose cost is reported
    CHECK(r.final_cost < 1e-20);
    CHECK(r.initial_cost == doctest::Approx(12.1).epsilon(1e-12));  // 0.5 (2.2^2 + 100 (1 - 1.44)^2)
    CHECK(r.accepted_steps > 5);
    CHECK(r.iterations < 500);
    // It stops because the fit is exact or nothing lowers the cost any more.
    CHECK((r.termination == LmTermination::kZeroCost || r.termination == LmTermination::kNoDecrease ||
           r.termination == LmTermination::kConverged));
  }
}

TEST_CASE("A noise-free exponential decay y = A exp(-k t) + c is recovered to 1e-9") {
  const double true_a = 3.5, true_k = 0.7, true_c = -0.25;
  std::vector<double> t, y;
  for (int i = 0; i < 30; ++i) {
    t.push_back(0.2 * i);
    y.push_back(true_a * std::exp(-true_k * t.back()) + true_c);
  }
  for (LmSchedule schedule : {LmSchedule::kFixedFactors, LmSchedule::kGainRatio}) {
    DenseProblem p;
    p.residuals = [&](const Eigen::VectorXd& x) {
      Eigen::VectorXd r(t.size());
      for (size_t i = 0; i < t.size(); ++i) r(i) = x(0) * std::exp(-x(1) * t[i]) + x(2) - y[i];
      return r;
    };
    p.jacobian = [&](const Eigen::VectorXd& x) {
      Eigen::MatrixXd j(t.size(), 3);
      for (size_t i = 0; i < t.size(); ++i) {
        const double e = std::exp(-x(1) * t[i]);
        j.row(i) << e, -x(0) * t[i] * e, 1.0;
      }
      return j;
    };
    p.x = Eigen::Vector3d(1.0, 0.1, 0.0);
    MinimizeLevenbergMarquardt(p.Cost(p.x), TightOptions(schedule), p);
    CHECK(std::abs(p.x(0) - true_a) < 1e-9);
    CHECK(std::abs(p.x(1) - true_k) < 1e-9);
    CHECK(std::abs(p.x(2) - true_c) < 1e-9);
  }
}

TEST_CASE("A rank-deficient problem (only x0 + x1 is observed) converges to a minimiser without blowing up") {
  DenseProblem p;
  p.residuals = [](const Eigen::VectorXd& x) {
    Eigen::VectorXd r(2);
    r << x(0) + x(1) - 3.0, 2.0 * (x(0) + x(1)) - 6.0;
    return r;
  };
  p.jacobian = [](const Eigen::VectorXd&) {
    Eigen::MatrixXd j(2, 2);
    j << 1.0, 1.0, 2.0, 2.0;
    return j;
  };
  p.x = Eigen::Vector2d(10.0, -4.0);
  const LmResult r = MinimizeLevenbergMarquardt(p.Cost(p.x), TightOptions(LmSchedule::kFixedFactors), p);
  CHECK(p.x.allFinite());
  CHECK(std::abs(p.x(0) + p.x(1) - 3.0) < 1e-9);
  // The damped steps move along the observed direction only: the difference is kept.
  CHECK(std::abs((p.x(0) - p.x(1)) - 14.0) < 1e-6);
  CHECK(r.final_cost < 1e-18);
}

TEST_CASE("Stop tests: zero and non-finite start, iteration limit, gradient test, tolerances") {
  SUBCASE("a start that fits exactly is not touched") {
    DenseProblem p = Rosenbrock(1.0, 100.0);
    p.x = Eigen::Vector2d(1.0, 1.0);
    const LmResult r = MinimizeLevenbergMarquardt(p.Cost(p.x), LmOptions{}, p);
    CHECK(r.termination == LmTermination::kZeroCost);
    CHECK(r.iterations == 0);
    CHECK(p.linearizations == 0);
  }
  SUBCASE("a non-finite start is refused") {
    DenseProblem p = Rosenbrock(1.0, 100.0);
    const LmResult r = MinimizeLevenbergMarquardt(std::nan(""), LmOptions{}, p);
    CHECK(r.termination == LmTermination::kNonFiniteCost);
    CHECK(p.linearizations == 0);
  }
  SUBCASE("max_iterations counts linearisations, or trials with count_every_trial") {
    for (bool every_trial : {false, true}) {
      DenseProblem p = Rosenbrock(1.0, 100.0);
      LmOptions o;
      o.max_iterations = 3;
      o.count_every_trial = every_trial;
      const LmResult r = MinimizeLevenbergMarquardt(p.Cost(p.x), o, p);
      CHECK(r.termination == LmTermination::kMaxIterations);
      CHECK(r.iterations == 3);
      if (!every_trial) CHECK(p.linearizations == 3);
      if (every_trial) CHECK(p.linearizations <= 3);
    }
  }
  SUBCASE("the caller's gradient test ends the run at a linearisation") {
    DenseProblem p = Rosenbrock(1.0, 100.0);
    p.gradient_tolerance = 1e-3;
    const LmResult r = MinimizeLevenbergMarquardt(p.Cost(p.x), TightOptions(LmSchedule::kGainRatio), p);
    CHECK(r.termination == LmTermination::kGradientConverged);
    CHECK(p.gradient.lpNorm<Eigen::Infinity>() <= 1e-3);
  }
  SUBCASE("a loose relative-decrease tolerance stops early, as converged") {
    DenseProblem p = Rosenbrock(1.0, 100.0);
    LmOptions o;
    o.relative_decrease_tolerance = 0.5;
    const LmResult r = MinimizeLevenbergMarquardt(p.Cost(p.x), o, p);
    CHECK(r.termination == LmTermination::kConverged);
    CHECK(r.final_cost > 1e-6);
  }
}

TEST_CASE("A step the problem vetoes (+inf cost) is rejected and lambda grows until max_lambda") {
  struct Vetoing {
    int steps = 0;
    double last_lambda = 0.0;
    bool Linearize() { return false; }
    LmStepStatus Step(double lambda, LmTrial* trial) {
      ++steps;
      CHECK(lambda > last_lambda);
      last_lambda = lambda;
      trial->cost = std::numeric_limits<double>::infinity();
      return LmStepStatus::kSolved;
    }
    void Accept() { FAIL("no step may be accepted"); }
  } p;
  LmOptions o;
  o.initial_lambda = 1.0;
  o.lambda_increase = 10.0;
  o.max_lambda = 1e5;
  const LmResult r = MinimizeLevenbergMarquardt(1.0, o, p);
  CHECK(r.termination == LmTermination::kNoDecrease);
  CHECK(p.steps == 5);  // lambda 1, 10, ..., 1e4; the next, 1e5, is not tried
  CHECK(r.final_cost == 1.0);
}

TEST_CASE("max_trials_per_linearization stops after that many unaccepted trials in a row, failed solves included") {
  // Trials 1 and 2 fail to solve, 3 is accepted, then every trial is rejected: with a cap of
  // 4 the run ends after trials 4 to 7 (lambda 10 .. 1e4), far below max_lambda.
  struct Stubborn {
    int steps = 0;
    int linearizations = 0;
    bool Linearize() {
      ++linearizations;
      return false;
    }
    LmStepStatus Step(double, LmTrial* trial) {
      ++steps;
      if (steps <= 2) return LmStepStatus::kSolveFailed;
      trial->cost = steps == 3 ? 0.5 : 2.0;
      trial->step_squared_norm = 1.0;
      return LmStepStatus::kSolved;
    }
    void Accept() {}
  };
  for (int cap : {0, 4}) {
    CAPTURE(cap);
    Stubborn p;
    LmOptions o;
    o.initial_lambda = 1.0;
    o.lambda_increase = o.lambda_increase_on_failed_solve = 10.0;
    o.lambda_decrease = 0.1;
    o.max_lambda = 1e12;
    o.max_trials_per_linearization = cap;
    const LmResult r = MinimizeLevenbergMarquardt(1.0, o, p);
    CHECK(r.termination == LmTermination::kNoDecrease);
    CHECK(r.accepted_steps == 1);
    CHECK(r.final_cost == 0.5);
    CHECK(p.linearizations == 2);
    // Without a cap the rejections go on until lambda reaches max_lambda: 1e1 .. 1e11.
    CHECK(p.steps == (cap == 0 ? 3 + 11 : 3 + cap));
  }
  LmOptions bad;
  bad.max_trials_per_linearization = -1;
  std::string error;
  CHECK_FALSE(bad.Check(&error));
  CHECK(error.find("max_trials_per_linearization") != std::string::npos);
}

TEST_CASE("A damped system without a finite solution raises lambda, or stops when asked") {
  struct Failing {
    int steps = 0;
    bool Linearize() { return false; }
    LmStepStatus Step(double, LmTrial*) {
      ++steps;
      return LmStepStatus::kSolveFailed;
    }
    void Accept() {}
  };
  {
    Failing p;
    LmOptions o;
    o.initial_lambda = 1.0;
    o.lambda_increase_on_failed_solve = 10.0;
    o.max_lambda_on_failed_solve = 1e3;
    const LmResult r = MinimizeLevenbergMarquardt(1.0, o, p);
    CHECK(r.termination == LmTermination::kLinearSolveFailed);
    CHECK(p.steps == 3);
  }
  {
    Failing p;
    LmOptions o;
    o.stop_on_failed_solve = true;
    const LmResult r = MinimizeLevenbergMarquardt(1.0, o, p);
    CHECK(r.termination == LmTermination::kLinearSolveFailed);
    CHECK(p.steps == 1);
  }
}

TEST_CASE("The callback sees every trial and can stop the run; N single-iteration runs resume exactly") {
  DenseProblem p = Rosenbrock(1.0, 100.0);
  LmOptions o = TightOptions(LmSchedule::kFixedFactors);
  std::vector<LmIteration> seen;
  o.callback = [&](const LmIteration& it) {
    seen.push_back(it);
    return seen.size() < 7;
  };
  const LmResult r = MinimizeLevenbergMarquardt(p.Cost(p.x), o, p);
  CHECK(r.termination == LmTermination::kStoppedByCallback);
  REQUIRE(seen.size() == 7);
  int accepted = 0;
  for (const LmIteration& it : seen) {
    accepted += it.accepted;
    if (it.accepted) CHECK(it.cost == it.trial_cost);
    if (!it.accepted) CHECK(it.trial_cost >= it.cost);
  }
  CHECK(accepted == r.accepted_steps);
  CHECK(seen.back().cost == r.final_cost);

  // Stepping: one-iteration runs, each resuming from the last run's lambda, retrace one run.
  DenseProblem whole = Rosenbrock(1.0, 100.0), stepped = Rosenbrock(1.0, 100.0);
  LmOptions ten = TightOptions(LmSchedule::kFixedFactors);
  ten.max_iterations = 10;
  MinimizeLevenbergMarquardt(whole.Cost(whole.x), ten, whole);
  LmOptions one = ten;
  one.max_iterations = 1;
  for (int i = 0; i < 10; ++i) {
    const LmResult step = MinimizeLevenbergMarquardt(stepped.Cost(stepped.x), one, stepped);
    // The next linearisation starts from the damping this one ended with (after its
    // rejections, as the one run does).
    one.initial_lambda = step.final_lambda;
  }
  CHECK((stepped.x - whole.x).norm() < 1e-12);
}

TEST_CASE("LmOptions::Check names what is wrong") {
  std::string error;
  CHECK(LmOptions{}.Check(&error));
  LmOptions o;
  o.initial_lambda = 0.0;
  CHECK_FALSE(o.Check(&error));
  CHECK(error.find("initial_lambda") != std::string::npos);
  o = LmOptions{};
  o.lambda_decrease = 1.5;
  CHECK_FALSE(o.Check(&error));
  CHECK(error.find("lambda_decrease") != std::string::npos);
  o = LmOptions{};
  o.max_iterations = -1;
  CHECK_FALSE(o.Check(&error));
  o = LmOptions{};
  o.min_gain_ratio = 1.0;
  CHECK_FALSE(o.Check(&error));
  o = LmOptions{};
  o.schedule = LmSchedule::kGainRatio;
  o.lambda_increase_on_failed_solve = 0.0;  // the rejection rule: allowed for kGainRatio
  CHECK(o.Check(&error));
}

}  // namespace
}  // namespace facet
