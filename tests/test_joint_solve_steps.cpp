// The joint solve stepped one iteration at a time (core/solve/joint_solve_steps.h): N steps
// give the project of one solve with a budget of N iterations, the trace holds every trial's
// cost, damping and step norm, and Reset restores the start exactly. The lesson's start,
// PerturbForSteps: moves exactly the free values by the stated amounts, and the steps lead
// back to the answer. The same stepping of the vanishing-point fit and of the two-view
// refinement of F (core/estimators/fit_steps.h): N steps = the fit with a budget of N, the
// trace a prefix of the unbudgeted fit's, Reset exact; from the perturbed start (the fit's
// answer moved by the stated amounts) the same, and the steps lead back to the answer.
#include <doctest/doctest.h>

#include <cmath>
#include <random>

#include <Eigen/Geometry>

#include "core/estimators/fit_steps.h"
#include "core/geometry/camera.h"
#include "core/geometry/hartley_normalization.h"
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
  CHECK(std::abs((after.CenterInWorld() - before.CenterInWorld()).norm() - kAmount * distance) < kRounding * distance);
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

// --- The vanishing-point fit and the two-view refinement ---

// The same arithmetic in the same order: equal to rounding.
constexpr double kSameFitRelative = 1e-12;

double Relative(double a, double b) { return std::abs(a - b) / std::max(1.0, std::abs(b)); }

// The box scene's segments with 0.5 px noise; the principal point held at the image centre
// while the true one is 15 px off it, so that the orthogonal directions cannot meet the
// families' own vanishing points and the fit has some iterations to show.
std::vector<Segment> NoisySegments(VpCalibrationOptions* options) {
  testing::SyntheticSceneOptions o;
  o.noise_px = 0.5;
  const testing::SyntheticScene scene = testing::MakeBoxScene(o);
  options->width_px = o.width_px;
  options->height_px = o.height_px;
  options->principal_point_mode = PrincipalPointMode::kImageCenter;
  return scene.project.segments;
}

// Reset gives the start back exactly, and stepping again repeats the first step exactly.
void CheckResetRestores(VpFitSteps* steps, const VpFitState& start, const VpFitState& first) {
  ResetVpFitSteps(steps);
  CHECK(steps->steps == 0);
  CHECK(steps->trace.empty());
  REQUIRE(steps->path.size() == 1);
  CHECK(steps->summary.focal_px == start.focal_px);
  CHECK(steps->summary.principal_point_px == start.principal_point_px);
  CHECK(steps->summary.final_cost == start.cost_px2);
  for (int a = 0; a < 3; ++a) CHECK(steps->path[0].vanishing_points[a] == start.vanishing_points[a]);
  REQUIRE(StepVpFit(steps));
  CHECK(steps->path[1].focal_px == first.focal_px);
  CHECK(steps->path[1].cost_px2 == first.cost_px2);
}

// The state after steps.steps steps is the fit from `from` with that budget: f, principal
// point, rotation, vanishing points, residuals and cost.
void CheckStepIsBudgetedFit(const VpFitSteps& steps, const std::vector<Segment>& segments,
                            const VpCalibrationOptions& from) {
  VpCalibrationOptions budget = from;
  budget.max_joint_iterations = steps.steps;
  const VpCalibrationSummary once = CalibrateFromVanishingLines(segments, budget);
  REQUIRE(once.IsUsable());
  CHECK(Relative(steps.summary.focal_px, once.focal_px) <= kSameFitRelative);
  CHECK((steps.summary.principal_point_px - once.principal_point_px).norm() <= kSameFitRelative * once.focal_px);
  CHECK((steps.summary.cam_from_world_rotation - once.cam_from_world_rotation).norm() <= kSameFitRelative);
  for (int a = 0; a < 3; ++a)
    CHECK((steps.path.back().vanishing_points[a] - once.vanishing_points[a]).norm() <= kSameFitRelative);
  for (size_t i = 0; i < segments.size(); ++i)
    CHECK(std::abs(steps.summary.segment_residuals_px[i] - once.segment_residuals_px[i]) <= kSameFitRelative);
  CHECK(Relative(steps.summary.final_cost, once.final_cost) <= kSameFitRelative);
}

TEST_CASE(
    "vanishing-point fit: N steps equal the fit with N iterations; the trace is the fit's; Reset restores the start") {
  VpCalibrationOptions options;
  const std::vector<Segment> segments = NoisySegments(&options);
  VpFitSteps steps;
  REQUIRE(BeginVpFitSteps(segments, options, 0.0, &steps));
  REQUIRE(steps.path.size() == 1);
  // The unbudgeted fit (one round, as stepped), for the trace and the end.
  VpCalibrationOptions full = steps.options;
  const VpCalibrationSummary all = CalibrateFromVanishingLines(segments, full);
  REQUIRE(all.IsUsable());
  // The start is the fit's own initial estimate: the cost its first trial started from.
  REQUIRE_FALSE(all.joint_trace.empty());
  const double px2 = all.conditioning_scale_px * all.conditioning_scale_px;
  CHECK(Relative(steps.path[0].cost_px2, all.initial_cost) <= kSameFitRelative);
  const VpFitState start = steps.path[0];
  VpFitState first;
  for (int n = 1; n <= 100 && !steps.finished; ++n) {
    CAPTURE(n);
    REQUIRE(StepVpFit(&steps));
    if (n == 1) first = steps.path[1];
    CheckStepIsBudgetedFit(steps, segments, steps.options);
    // The budgeted fit's trials are the unbudgeted fit's first ones.
    REQUIRE(steps.trace.size() <= all.joint_trace.size());
    for (size_t i = 0; i < steps.trace.size(); ++i) {
      CHECK(Relative(steps.trace[i].trial_cost * px2, all.joint_trace[i].trial_cost * px2) <= kSameFitRelative);
      CHECK(steps.trace[i].lambda == all.joint_trace[i].lambda);
    }
    CHECK(steps.trace.back().iteration == n);
    CHECK(steps.path.size() == static_cast<size_t>(n + 1));
    CHECK(steps.path[n].cost_px2 <= steps.path[n - 1].cost_px2);
  }
  // The start was not the answer, and the steps end at the unbudgeted fit.
  CHECK(steps.finished);
  CHECK(steps.steps >= 3);
  CHECK(steps.summary.final_cost < 0.5 * start.cost_px2);
  CHECK(steps.trace.size() == all.joint_trace.size());
  CHECK(Relative(steps.summary.focal_px, all.focal_px) <= kSameFitRelative);
  CHECK_FALSE(StepVpFit(&steps));

  CheckResetRestores(&steps, start, first);
}

// 30 points seen by two cameras, 1 px noise.
void NoisyPair(std::vector<Eigen::Vector2d>* uv1, std::vector<Eigen::Vector2d>* uv2) {
  testing::SyntheticSceneOptions o1;
  testing::SyntheticSceneOptions o2 = o1;
  o2.focal_px = 1100;
  o2.camera_center = {11.0, 2.0, 3.5};
  o2.look_at = {1.5, 1.0, 1.2};
  o2.roll_deg = -4.0;
  const Camera c1 = testing::MakeLookAtCamera(o1), c2 = testing::MakeLookAtCamera(o2);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> ux(-1.0, 5.0), uy(-1.0, 4.0), uz(0.0, 3.0);
  std::normal_distribution<double> noise(0.0, 1.0);
  while (uv1->size() < 30) {
    const double x = ux(rng), y = uy(rng), z = uz(rng);
    const Eigen::Vector3d p(x, y, z);
    const double n1 = noise(rng), n2 = noise(rng), n3 = noise(rng), n4 = noise(rng);
    uv1->push_back(c1.Project(p) + Eigen::Vector2d(n1, n2));
    uv2->push_back(c2.Project(p) + Eigen::Vector2d(n3, n4));
  }
}

// Reset gives the start F back exactly.
void CheckResetRestores(FundamentalFitSteps* steps, const Eigen::Matrix3d& start) {
  ResetFundamentalFitSteps(steps);
  CHECK(steps->steps == 0);
  CHECK(steps->trace.empty());
  REQUIRE(steps->path.size() == 1);
  CHECK(steps->summary.F == start);
  CHECK(steps->summary.final_cost == steps->start.final_cost);
}

// The state after steps.steps steps is the refinement from `from` with that budget.
void CheckStepIsBudgetedRefinement(const FundamentalFitSteps& steps, const std::vector<Eigen::Vector2d>& uv1,
                                   const std::vector<Eigen::Vector2d>& uv2, const FundamentalOptions& from) {
  FundamentalOptions budget = from;
  budget.max_refine_iterations = steps.steps;
  const FundamentalSummary once = EstimateFundamentalMatrix(uv1, uv2, budget);
  REQUIRE(once.IsUsable());
  CHECK((steps.summary.F - once.F).norm() <= kSameFitRelative);  // unit Frobenius norm
  CHECK(Relative(steps.summary.final_cost, once.final_cost) <= kSameFitRelative);
}

TEST_CASE("two-view refinement: N steps equal the refinement with N iterations; Reset restores the linear start") {
  std::vector<Eigen::Vector2d> uv1, uv2;
  NoisyPair(&uv1, &uv2);
  FundamentalFitSteps steps;
  REQUIRE(BeginFundamentalFitSteps(uv1, uv2, FundamentalOptions(), 0.0, &steps));
  const FundamentalSummary all = EstimateFundamentalMatrix(uv1, uv2, steps.options);
  REQUIRE(all.IsUsable());
  // The start is the linear estimate the refinement starts from.
  CHECK(Relative(steps.summary.symmetric_epipolar_rms_px, all.initial_symmetric_epipolar_rms_px) <= kSameFitRelative);
  const Eigen::Matrix3d start = steps.path[0];
  for (int n = 1; n <= 100 && !steps.finished; ++n) {
    CAPTURE(n);
    REQUIRE(StepFundamentalFit(&steps));
    CheckStepIsBudgetedRefinement(steps, uv1, uv2, steps.options);
    REQUIRE(steps.trace.size() <= all.refine_trace.size());
    for (size_t i = 0; i < steps.trace.size(); ++i) {
      CHECK(Relative(steps.trace[i].trial_cost, all.refine_trace[i].trial_cost) <= kSameFitRelative);
      CHECK(steps.trace[i].lambda == all.refine_trace[i].lambda);
    }
    CHECK(steps.path.size() == static_cast<size_t>(n + 1));
  }
  CHECK(steps.finished);
  CHECK(steps.steps >= 2);
  CHECK(steps.summary.final_cost < steps.start.final_cost);
  CHECK((steps.summary.F - all.F).norm() <= kSameFitRelative);
  CHECK_FALSE(StepFundamentalFit(&steps));

  CheckResetRestores(&steps, start);
}

// The lessons' amount (the app's default).
constexpr double kLessonAmount = 0.2;
constexpr double kDegree = 3.14159265358979323846 / 180.0;

TEST_CASE(
    "vanishing-point fit from the perturbed start: N steps equal the fit with N iterations from it; back to "
    "the answer; Reset exact") {
  VpCalibrationOptions options;
  const std::vector<Segment> segments = NoisySegments(&options);
  options.principal_point_mode = PrincipalPointMode::kSolve;  // the principal point moves too
  options.refit_without_outliers = false;
  options.record_joint_trace = true;
  const VpCalibrationSummary answer = CalibrateFromVanishingLines(segments, options);
  REQUIRE(answer.IsUsable());
  // The stated start, built here from the header's words.
  VpCalibrationOptions from = options;
  from.warm_start = true;
  from.warm_start_focal_px = answer.focal_px * (1.0 + kLessonAmount);
  from.warm_start_principal_point_px =
      answer.principal_point_px + kLessonAmount * 0.25 * Eigen::Vector2d(options.width_px, -options.height_px);
  from.warm_start_rotation =
      RotationFromAngleAxis(kLessonAmount * 20.0 * kDegree * Eigen::Vector3d(1.0, 2.0, 3.0).normalized()) *
      answer.cam_from_world_rotation;

  VpFitSteps steps;
  REQUIRE(BeginVpFitSteps(segments, options, kLessonAmount, &steps));
  REQUIRE(steps.path.size() == 1);
  const VpFitState start = steps.path[0];
  CHECK(Relative(start.focal_px, from.warm_start_focal_px) <= kSameFitRelative);
  CHECK((start.principal_point_px - from.warm_start_principal_point_px).norm() <= kSameFitRelative * start.focal_px);
  // Far enough off to show: the cost at least 10 times the answer's.
  CHECK(start.cost_px2 > 10.0 * answer.final_cost);
  VpFitState first;
  for (int n = 1; n <= 100 && !steps.finished; ++n) {
    CAPTURE(n);
    REQUIRE(StepVpFit(&steps));
    if (n == 1) first = steps.path[1];
    CheckStepIsBudgetedFit(steps, segments, from);
    CHECK(steps.path[n].cost_px2 <= steps.path[n - 1].cost_px2);
  }
  // Back to the answer: the same minimum, to the fit's own stopping tolerance.
  constexpr double kSameAnswerRelative = 1e-6;
  CHECK(steps.finished);
  CHECK(steps.steps >= 3);
  CHECK(Relative(steps.summary.focal_px, answer.focal_px) <= kSameAnswerRelative);
  CHECK((steps.summary.principal_point_px - answer.principal_point_px).norm() <= kSameAnswerRelative * answer.focal_px);
  CHECK((steps.summary.cam_from_world_rotation - answer.cam_from_world_rotation).norm() <= kSameAnswerRelative);
  CHECK(Relative(steps.summary.final_cost, answer.final_cost) <= kSameAnswerRelative);
  MESSAGE("vp from the perturbed start: ", steps.steps, " steps, cost ", start.cost_px2, " -> ",
          steps.summary.final_cost, " px^2 (answer ", answer.final_cost, "), f ", start.focal_px, " -> ",
          steps.summary.focal_px, " px (answer ", answer.focal_px, ")");

  CheckResetRestores(&steps, start, first);
}

TEST_CASE(
    "two-view refinement from the perturbed start: N steps equal the refinement with N iterations from it; "
    "back to the answer; Reset exact") {
  std::vector<Eigen::Vector2d> uv1, uv2;
  NoisyPair(&uv1, &uv2);
  FundamentalOptions options;
  options.use_ransac = false;
  options.record_refine_trace = true;
  const FundamentalSummary answer = EstimateFundamentalMatrix(uv1, uv2, options);
  REQUIRE(answer.IsUsable());
  // The stated start, in F's orthonormal representation.
  internal::OrthonormalFundamental o = internal::OrthonormalFundamental::FromF(
      answer.F, internal::HartleyNormalization(uv1), internal::HartleyNormalization(uv2));
  const double angle = kLessonAmount * 10.0 * kDegree;
  o.U = o.U * RotationFromAngleAxis(angle * Eigen::Vector3d(1.0, 2.0, 3.0).normalized());
  o.V = o.V * RotationFromAngleAxis(angle * Eigen::Vector3d(3.0, -1.0, 2.0).normalized());
  o.s *= 1.0 - kLessonAmount;
  FundamentalOptions from = options;
  from.warm_start = true;
  from.warm_start_F = o.F();

  FundamentalFitSteps steps;
  REQUIRE(BeginFundamentalFitSteps(uv1, uv2, FundamentalOptions(), kLessonAmount, &steps));
  REQUIRE(steps.path.size() == 1);
  const Eigen::Matrix3d start = steps.path[0];
  CHECK((start - NormalizeFundamental(o.F())).norm() <= kSameFitRelative);
  CHECK(steps.summary.symmetric_epipolar_rms_px > 10.0 * answer.symmetric_epipolar_rms_px);
  for (int n = 1; n <= 100 && !steps.finished; ++n) {
    CAPTURE(n);
    REQUIRE(StepFundamentalFit(&steps));
    CheckStepIsBudgetedRefinement(steps, uv1, uv2, from);
  }
  constexpr double kSameAnswer = 1e-6;  // unit Frobenius norm; the refinement's stopping tolerance
  CHECK(steps.finished);
  CHECK(steps.steps >= 3);
  CHECK((steps.summary.F - answer.F).norm() <= kSameAnswer);
  CHECK(Relative(steps.summary.final_cost, answer.final_cost) <= kSameAnswer);
  MESSAGE("two views from the perturbed start: ", steps.steps, " steps, RMS ", steps.start.symmetric_epipolar_rms_px,
          " -> ", steps.summary.symmetric_epipolar_rms_px, " px (answer ", answer.symmetric_epipolar_rms_px, ")");

  CheckResetRestores(&steps, start);
}

}  // namespace
}  // namespace facet
