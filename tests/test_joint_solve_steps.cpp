// The joint solve stepped one iteration at a time (core/solve/joint_solve_steps.h): N steps
// give the project of one solve with a budget of N iterations, the trace holds every trial's
// cost, damping and step norm, and Reset restores the start exactly.
#include <doctest/doctest.h>

#include <cmath>

#include <Eigen/Geometry>

#include "core/solve/joint_solve_steps.h"
#include "tests/synthetic_scene.h"

namespace facet {
namespace {

// The box scene with 0.5 px noise, its camera pose, focal length and box moved off the truth.
Project PerturbedStart() {
  testing::SyntheticSceneOptions o;
  o.noise_px = 0.5;
  Project p = testing::MakeBoxScene(o).project;
  Image& image = p.images[0];
  image.focal_locked = false;
  Camera& c = image.camera;
  const Eigen::Matrix3d r =
      Eigen::AngleAxisd(0.01, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix() * c.cam_from_world_rotation;
  c.SetPose(r, c.CenterInWorld() * 1.03);
  c.focal_px *= 1.03;
  p.primitives[0].shape.params(0) *= 1.05;
  p.primitives[0].shape.params(1) *= 0.95;
  RefreshAllPrimitives(&p);
  return p;
}

// Largest difference over the cameras' and primitives' values, relative to their size.
double MaxRelativeDifference(const Project& a, const Project& b) {
  double worst = 0.0;
  auto compare = [&](double x, double y) { worst = std::max(worst, std::abs(x - y) / std::max(1.0, std::abs(y))); };
  REQUIRE(a.images.size() == b.images.size());
  for (size_t i = 0; i < a.images.size(); ++i) {
    const Camera& x = a.images[i].camera;
    const Camera& y = b.images[i].camera;
    compare(x.focal_px, y.focal_px);
    for (int k = 0; k < 2; ++k) compare(x.principal_point_px(k), y.principal_point_px(k));
    for (int k = 0; k < 9; ++k) compare(x.cam_from_world_rotation(k), y.cam_from_world_rotation(k));
    for (int k = 0; k < 3; ++k) compare(x.cam_from_world_translation(k), y.cam_from_world_translation(k));
  }
  REQUIRE(a.primitives.size() == b.primitives.size());
  for (size_t i = 0; i < a.primitives.size(); ++i) {
    const PrimitiveShape& x = a.primitives[i].shape;
    const PrimitiveShape& y = b.primitives[i].shape;
    for (int k = 0; k < x.params.size(); ++k) compare(x.params(k), y.params(k));
    for (int k = 0; k < 3; ++k) compare(x.translation(k), y.translation(k));
    for (int k = 0; k < 3; ++k) compare(x.rotation(k), y.rotation(k));
  }
  return worst;
}

TEST_CASE("N steps equal one solve of N iterations; the trace is the solve's; Reset restores the start") {
  // The same arithmetic in the same order: equal to rounding (1e-12 relative).
  constexpr double kSameSolveRelative = 1e-12;
  const Project start = PerturbedStart();
  JointSolveOptions options;
  options.compute_diagnostics = false;
  JointSolveSteps steps = BeginJointSolveSteps(start, options);
  CHECK(steps.current == start);
  double previous_cost = std::numeric_limits<double>::infinity();
  for (int n = 1; n <= 50 && !steps.finished; ++n) {
    CAPTURE(n);
    REQUIRE(StepJointSolve(&steps));
    CHECK(steps.steps == n);
    JointSolveOptions budget = steps.options;
    budget.max_iterations = n;
    Project solved;
    std::vector<LmIteration> trace;
    const JointSolveSummary once = SolveJointTraced(start, budget, &solved, &trace);
    REQUIRE(once.IsUsable());
    CHECK(MaxRelativeDifference(steps.current, solved) <= kSameSolveRelative);
    CHECK(std::abs(steps.summary.final_cost - once.final_cost) <= kSameSolveRelative * once.final_cost);
    // One trial per step, numbered 1..n, the cost never rising (a step that found the
    // state converged tries no step and adds none).
    if (!steps.finished) {
      REQUIRE(steps.trace.size() == static_cast<size_t>(n));
      CHECK(steps.trace.back().iteration == n);
    }
    CHECK(trace.size() == steps.trace.size());
    CHECK(steps.trace.back().cost <= previous_cost);
    CHECK(steps.trace.back().lambda > 0.0);
    previous_cost = steps.trace.back().cost;
  }
  // The start was not already the answer: it took steps, which lowered the cost.
  CHECK(steps.steps >= 3);
  CHECK(steps.summary.final_cost < 0.5 * steps.summary.initial_cost);
  CHECK_FALSE(steps.current == start);
  // The full solve (polish off) is where the steps end.
  JointSolveOptions full = steps.options;
  Project converged;
  const JointSolveSummary all = SolveJoint(start, full, &converged);
  REQUIRE(all.IsUsable());
  CHECK(steps.finished);
  CHECK(steps.steps == all.iterations);
  CHECK(MaxRelativeDifference(steps.current, converged) <= kSameSolveRelative);
  CHECK_FALSE(StepJointSolve(&steps));  // nothing more to do

  ResetJointSolveSteps(&steps);
  CHECK(steps.current == start);
  CHECK(steps.steps == 0);
  CHECK(steps.trace.empty());
}

}  // namespace
}  // namespace facet
