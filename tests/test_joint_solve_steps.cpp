// The joint solve stepped one iteration at a time (core/solve/joint_solve_steps.h): N steps
// give the project of one solve with a budget of N iterations, the trace holds every trial's
// cost, damping and step norm, and Reset restores the start exactly. The lesson's start,
// PerturbForSteps: moves exactly the free values by the stated amounts, and the steps lead
// back to the answer.
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

TEST_CASE("PerturbForSteps moves the free values by the stated amounts and keeps the locked ones") {
  // Rotations and centres go through SetPose and back: rounding only.
  constexpr double kRounding = 1e-12;
  testing::SyntheticSceneOptions o;
  Project p = testing::MakeBoxScene(o).project;
  p.images[0].focal_locked = false;
  Primitive& box = p.primitives[0];
  box.param_locked = {false, true, false, false};
  box.translation_locked = false;
  box.rotation_locked = true;
  RefreshAllPrimitives(&p);
  CHECK(PerturbForSteps(p, 0.0) == p);
  constexpr double kAmount = 0.05;
  const Project q = PerturbForSteps(p, kAmount);
  const Camera& before = p.images[0].camera;
  const Camera& after = q.images[0].camera;
  // The turn: amount x 20 degrees.
  const Eigen::AngleAxisd turn(before.cam_from_world_rotation.transpose() * after.cam_from_world_rotation);
  CHECK(std::abs(turn.angle() - kAmount * 20.0 * M_PI / 180.0) < kRounding);
  // The centre: amount x its distance to the model's centre (the box's centre here).
  Eigen::AlignedBox3d bounds;
  for (VertexId v = 0; v < box.mesh.VertexIdEnd(); ++v)
    if (box.mesh.IsVertex(v)) bounds.extend(box.mesh.vertex(v).position);
  const double distance = (before.CenterInWorld() - bounds.center()).norm();
  CHECK(std::abs((after.CenterInWorld() - before.CenterInWorld()).norm() - kAmount * distance) <
        kRounding * distance);
  CHECK(after.focal_px == before.focal_px * (1.0 + kAmount));
  CHECK(after.principal_point_px == before.principal_point_px);  // locked
  const PrimitiveShape& a = q.primitives[0].shape;
  CHECK(a.params(0) == box.shape.params(0) * (1.0 + kAmount));
  CHECK(a.params(1) == box.shape.params(1));  // locked
  CHECK(a.params(2) == box.shape.params(2) * (1.0 + kAmount));
  CHECK(std::abs((a.translation - box.shape.translation).norm() - kAmount * bounds.diagonal().norm()) <
        kRounding * bounds.diagonal().norm());
  CHECK(a.rotation == box.shape.rotation);  // locked
  // The cached vertices follow the new shape.
  const Primitive& moved = q.primitives[0];
  CHECK((moved.mesh.vertex(7).position - box.mesh.vertex(7).position).norm() > 0.01);
  // Locked pose: the camera stays.
  p.images[0].pose_locked = true;
  p.images[0].focal_locked = true;
  CHECK(PerturbForSteps(p, kAmount).images[0].camera == before);
}

TEST_CASE("from the perturbed start the steps lead back to the answer") {
  // Noise-free pins and segments: the answer fits them to rounding.
  constexpr double kFitPx = 1e-6;
  const Project truth = testing::MakeBoxScene().project;
  const Project start = PerturbForSteps(truth, 0.05);
  JointSolveSteps steps = BeginJointSolveSteps(start, SolveStepsOptions());
  for (int n = 0; n < 60 && !steps.finished; ++n) REQUIRE(StepJointSolve(&steps));
  CHECK(steps.finished);
  CHECK(steps.steps >= 3);  // the start was not the answer
  CHECK(steps.summary.initial_cost > 1.0);
  CHECK(steps.summary.reprojection_max_px < kFitPx);
}

}  // namespace
}  // namespace facet
