#include "core/solve/scene_solve.h"

#include <algorithm>
#include <cassert>
#include <chrono>
#include <cmath>
#include <limits>
#include <utility>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "core/geometry/camera.h"
#include "core/optim/levenberg_marquardt.h"
#include "core/solve/scene_solve_internal.h"
#include "core/util/eigen_decompositions.h"

namespace facet {

bool SceneSolveOptions::Check(std::string* error) const {
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
  return true;
}

namespace {

using scene_solve_internal::SceneProblem;
using scene_solve_internal::SceneState;

double Cost(const Eigen::VectorXd& residuals) { return 0.5 * residuals.squaredNorm(); }

// The current parameter values in the order of the parameter vector (rotations as
// angle-axis), for the relative step test.
void ParameterValues(const SceneProblem& problem, const SceneState& state, Eigen::VectorXd* values) {
  values->resize(problem.num_parameters);
  for (size_t c = 0; c < problem.cameras.size(); ++c) {
    const int off = problem.cameras[c].center_offset;
    if (off >= 0) values->segment<3>(off) = state.camera_centers[c];
  }
  for (size_t b = 0; b < problem.primitives.size(); ++b) {
    const auto& block = problem.primitives[b];
    for (int k = 0; k < kMaxPrimitiveParams; ++k) {
      if (block.param_offset[k] >= 0) (*values)(block.param_offset[k]) = state.primitive_params[b](k);
    }
    if (block.rotation_offset >= 0) {
      values->segment<3>(block.rotation_offset) = AngleAxisFromRotation(state.primitive_rotations[b]);
    }
    if (block.translation_offset >= 0) values->segment<3>(block.translation_offset) = state.primitive_translations[b];
  }
}

bool StateIsFinite(const SceneState& state) {
  auto finite = [](const auto& items) {
    return std::all_of(items.begin(), items.end(), [](const auto& x) { return x.allFinite(); });
  };
  return finite(state.camera_centers) && finite(state.primitive_params) && finite(state.primitive_rotations) &&
         finite(state.primitive_translations);
}

// How the geometry solve's LM ended, in the summary's terms.
struct SceneLmOutcome {
  SolverTermination termination = SolverTermination::kFailed;
  std::string message;
  int iterations = 0;
};

// The geometry solve's least squares for the LM driver (core/optim/levenberg_marquardt.h),
// with Marquardt's scaling: the damping term is lambda * diag(J^T J), taking the running
// maximum of each diagonal entry (More 1978) so a column that shrinks for a while cannot make
// the step blow up. With this scaling the iterates do not depend on the units of the
// parameters, and neither do the gradient and step tests, which are measured in the same
// scaled coordinates.
class SceneLmProblem {
 public:
  SceneLmProblem(const SceneProblem& problem, const SceneSolveOptions& options, SceneState* state)
      : problem_(problem), options_(options), state_(state) {
    num_behind_ = scene_solve_internal::EvaluateScene(problem_, *state_, &residuals_, &jacobian_);
    max_diagonal_ = Eigen::VectorXd::Zero(problem_.num_parameters);
  }
  double cost() const { return Cost(residuals_); }
  // True when the run ended on the relative step test (Step returned kStepNegligible).
  bool step_negligible() const { return step_negligible_; }

  bool Linearize() {
    normal_.noalias() = jacobian_.transpose() * jacobian_;
    gradient_.noalias() = jacobian_.transpose() * residuals_;
    max_diagonal_ = max_diagonal_.cwiseMax(normal_.diagonal());
    // A parameter no pin moves has a zero column; a tiny floor keeps the system solvable
    // and its step zero (its gradient is zero).
    const double floor = std::max(1e-12 * max_diagonal_.maxCoeff(), std::numeric_limits<double>::min());
    damping_ = max_diagonal_.cwiseMax(floor);
    scale_ = damping_.cwiseSqrt();
    const double scaled_gradient = (gradient_.array() / scale_.array()).abs().maxCoeff();
    return scaled_gradient <= options_.gradient_tolerance;
  }

  LmStepStatus Step(double lambda, LmTrial* trial) {
    damped_ = normal_;
    damped_.diagonal() += lambda * damping_;
    delta_ = damped_.ldlt().solve(-gradient_);
    if (!delta_.allFinite()) return LmStepStatus::kSolveFailed;
    ParameterValues(problem_, *state_, &values_);
    const double step_norm = (delta_.array() * scale_.array()).matrix().norm();
    const double value_norm = (values_.array() * scale_.array()).matrix().norm();
    if (step_norm <= options_.parameter_tolerance * (value_norm + options_.parameter_tolerance)) {
      step_negligible_ = true;
      return LmStepStatus::kStepNegligible;
    }
    trial_state_ = *state_;
    scene_solve_internal::ApplySceneStep(problem_, delta_, &trial_state_);
    trial_behind_ = scene_solve_internal::EvaluateScene(problem_, trial_state_, &trial_residuals_, &trial_jacobian_);
    const double trial_cost = Cost(trial_residuals_);
    // A trial that puts more pinned vertices behind their cameras is vetoed, whatever its cost.
    const bool valid = std::isfinite(trial_cost) && trial_jacobian_.allFinite() && trial_behind_ <= num_behind_;
    trial->cost = valid ? trial_cost : std::numeric_limits<double>::infinity();
    trial->step_squared_norm = step_norm * step_norm;
    // Decrease of the linear model: -g.d - 0.5 d.JtJ.d = 0.5 d.(lambda D d - g).
    trial->predicted_decrease = 0.5 * delta_.dot(lambda * damping_.cwiseProduct(delta_) - gradient_);
    return LmStepStatus::kSolved;
  }

  void Accept() {
    std::swap(*state_, trial_state_);
    std::swap(residuals_, trial_residuals_);
    std::swap(jacobian_, trial_jacobian_);
    num_behind_ = trial_behind_;
  }

 private:
  const SceneProblem& problem_;
  const SceneSolveOptions& options_;
  SceneState* state_;
  SceneState trial_state_;
  Eigen::VectorXd residuals_, trial_residuals_, gradient_, delta_, values_;
  Eigen::MatrixXd jacobian_, trial_jacobian_, normal_, damped_;
  Eigen::VectorXd max_diagonal_, scale_, damping_;
  int num_behind_ = 0;
  int trial_behind_ = 0;
  bool step_negligible_ = false;
};

SceneLmOutcome RunLevenbergMarquardt(const SceneProblem& problem, const SceneSolveOptions& options, SceneState* state) {
  SceneLmProblem lm_problem(problem, options, state);
  LmOptions lm;
  lm.max_iterations = options.max_iterations;
  lm.schedule = LmSchedule::kGainRatio;
  lm.initial_lambda = options.initial_lambda;
  lm.relative_decrease_tolerance = options.function_tolerance;
  // Rules that differ from the defaults: every trial counts as an iteration (the budget is
  // in evaluations, as in Ceres); a damped system without a finite solution raises lambda as
  // a rejection does (nu); lambda has no floor and may climb to 1e32 (the running-max
  // scaling keeps it scale-free, so no fixed bound is meaningful below that); the step test
  // is the caller's relative one (kStepNegligible), hence no absolute step bound.
  lm.count_every_trial = true;
  lm.lambda_increase_on_failed_solve = 0.0;
  lm.min_lambda = 0.0;
  lm.max_lambda = 1e32;
  lm.max_lambda_on_failed_solve = 1e32;
  lm.min_step_squared_norm = 0.0;
  const LmResult result = MinimizeLevenbergMarquardt(lm_problem.cost(), lm, lm_problem);
  SceneLmOutcome outcome;
  outcome.iterations = result.iterations;
  auto ended = [&](SolverTermination termination, std::string message) {
    outcome.termination = termination;
    outcome.message = std::move(message);
    return outcome;
  };
  switch (result.termination) {
    case LmTermination::kConverged:
      return ended(SolverTermination::kConverged,
                   lm_problem.step_negligible() ? "parameter tolerance reached" : "function tolerance reached");
    case LmTermination::kGradientConverged: return ended(SolverTermination::kConverged, "gradient tolerance reached");
    case LmTermination::kZeroCost: return ended(SolverTermination::kConverged, "the residuals are zero");
    case LmTermination::kNoDecrease: return ended(SolverTermination::kConverged, "no step decreases the cost any more");
    case LmTermination::kMaxIterations: return ended(SolverTermination::kMaxIterations, "iteration limit reached");
    case LmTermination::kLinearSolveFailed:
      return ended(SolverTermination::kFailed, "the normal equations cannot be solved");
    case LmTermination::kNonFiniteCost:
      return ended(SolverTermination::kFailed, "the reprojection is not finite at the start");
    case LmTermination::kStoppedByCallback: break;  // no callback
  }
  return ended(SolverTermination::kFailed, "the solve stopped unexpectedly");
}

// Why the project cannot be solved as given (a non-finite pin, invalid intrinsics or
// rotation, a non-finite camera position or primitive parameter), or "".
std::string InvalidInputMessage(const Project& project, const SceneProblem& problem, const SceneState& state) {
  for (const auto& obs : problem.observations) {
    if (!obs.uv_px.allFinite()) {
      return "pin #" + std::to_string(project.pins[obs.pin_index].id) + " has a non-finite pixel position";
    }
  }
  for (const auto& cam : problem.cameras) {
    if (!(cam.focal_px > 0.0) || !std::isfinite(cam.focal_px) || !cam.principal_point_px.allFinite() ||
        !cam.cam_from_world_rotation.allFinite()) {
      return "the camera of image #" + std::to_string(project.images[cam.image_index].id) +
             " has invalid intrinsics or rotation";
    }
  }
  if (!StateIsFinite(state)) return "a camera position or primitive parameter is not finite";
  return "";
}

// The pins' reprojection errors at `state` into the summary (per pin, RMS, max); returns the
// cost there.
double RecordResiduals(const SceneProblem& problem, const SceneState& state, SceneSolveSummary* summary) {
  Eigen::VectorXd residuals;
  scene_solve_internal::EvaluateScene(problem, state, &residuals, nullptr);
  double sum_sq = 0.0, max_px = 0.0;
  for (size_t o = 0; o < problem.observations.size(); ++o) {
    const double e = residuals.segment<2>(2 * o).norm();
    summary->pin_residuals_px[problem.observations[o].pin_index] = e;
    sum_sq += e * e;
    max_px = std::max(max_px, e);
  }
  const size_t num = problem.observations.size();
  summary->reprojection_rms_px = num > 0 ? std::sqrt(sum_sq / num) : 0.0;
  summary->reprojection_max_px = max_px;
  return Cost(residuals);
}

// A warning per pin whose vertex lies behind its image's camera in the solved project.
void AddBehindCameraWarnings(const Project& project, const SceneProblem& problem, const Project& solved,
                             std::vector<std::string>* warnings) {
  for (const auto& obs : problem.observations) {
    const Primitive& primitive = solved.primitives[problem.primitives[obs.primitive].primitive_index];
    const Image& image = solved.images[problem.cameras[obs.camera].image_index];
    if (image.camera.CamFromWorld(primitive.mesh.vertex(solved.pins[obs.pin_index].vertex.vertex).position).z() <=
        0.0) {
      warnings->push_back("pin #" + std::to_string(project.pins[obs.pin_index].id) +
                          ": the vertex lies behind the camera of its image");
    }
  }
}

}  // namespace

// Above this many parameters the geometry solve's dense LM would cost more than a frame
// (~n^2 x residuals flops per iteration): it then gives its start and the joint solve refines.
constexpr int kMaxDenseParameters = 120;

SceneSolveSummary SolveScene(const Project& project, const SceneSolveOptions& options, Project* solved) {
  assert(solved != nullptr && solved != &project);
  const auto start = std::chrono::steady_clock::now();
  SceneSolveSummary summary;
  auto finish = [&](SolverTermination termination, std::string message) {
    summary.termination = termination;
    summary.message = std::move(message);
    if (!summary.IsUsable()) *solved = project;
    summary.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return summary;
  };
  summary.pin_residuals_px.assign(project.pins.size(), std::numeric_limits<double>::quiet_NaN());

  std::string error;
  if (!options.Check(&error)) return finish(SolverTermination::kInvalidInput, "invalid options: " + error);

  SceneState state;
  const SceneProblem problem = scene_solve_internal::BuildSceneProblem(project, &state);
  summary.warnings = problem.warnings;
  summary.held_parameters = problem.held_parameters;
  summary.num_skipped_pins = problem.num_skipped_pins;
  summary.num_residuals = 2 * static_cast<int>(problem.observations.size());
  summary.num_parameters = problem.num_parameters;

  const std::string invalid = InvalidInputMessage(project, problem, state);
  if (!invalid.empty()) return finish(SolverTermination::kInvalidInput, invalid);
  auto record_residuals = [&](const SceneState& s) { return RecordResiduals(problem, s, &summary); };
  if (problem.observations.empty()) {
    *solved = project;
    return finish(SolverTermination::kNothingToSolve, "no pins in calibrated images");
  }
  summary.initial_cost = summary.final_cost = record_residuals(state);
  if (problem.num_parameters == 0) {
    *solved = project;
    return finish(SolverTermination::kNothingToSolve,
                  "nothing is free: every camera pose and primitive parameter that the pins touch is locked");
  }
  // A cold start replaces the current values, so only its result has to be finite: a camera
  // that was just calibrated still sits at the origin, often on a primitive's corner.
  std::string why;
  if (!options.warm_start) {
    if (scene_solve_internal::LinearInitialization(problem, &state, &why)) {
      summary.linear_initialization_used = true;
    } else {
      summary.warnings.push_back("linear initialisation not used (" + why + "); starting from the current values");
    }
  }
  if (!std::isfinite(summary.initial_cost) && !std::isfinite(record_residuals(state))) {
    // Said as the cause a user can act on: with a linear start this could not happen, so the
    // pins are too few to give one (a new photo's camera still sits on the model's corner).
    if (!why.empty()) {
      return finish(SolverTermination::kFailed,
                    "no start yet: the pins do not fix the cameras and the model (" + why +
                        "), and the current camera sits in the plane of a pinned vertex; pin more vertices "
                        "(the four corners of one face place a new box)");
    }
    return finish(SolverTermination::kFailed,
                  "the reprojection is not finite at the start: a pinned vertex lies in the plane of its camera");
  }

  // This LM and the rank analysis below are dense (n^2 work per residual): above
  // kMaxDenseParameters the geometry solve stops at its start (the linear initialisation on a
  // cold start) and leaves the refinement to the joint solve's sparse LM, which UpdateModel
  // runs next (core/solve/model_update.h) and which is exact on the same residuals.
  if (problem.num_parameters > kMaxDenseParameters) {
    if (!StateIsFinite(state)) return finish(SolverTermination::kFailed, "the linear start is not finite");
    summary.final_cost = record_residuals(state);
    if (!std::isfinite(summary.final_cost))
      return finish(SolverTermination::kFailed, "the reprojection is not finite at the linear start");
    *solved = project;
    scene_solve_internal::WriteSceneState(problem, state, solved);
    return finish(SolverTermination::kMaxIterations,
                  std::string(summary.linear_initialization_used ? "linear start only" : "start kept") + ": " +
                      std::to_string(problem.num_parameters) + " parameters are refined by the joint solve");
  }
  const auto lm = RunLevenbergMarquardt(problem, options, &state);
  summary.iterations = lm.iterations;
  if (lm.termination == SolverTermination::kFailed) return finish(lm.termination, lm.message);
  if (!StateIsFinite(state)) {
    return finish(SolverTermination::kFailed, "the solve diverged: a parameter is no longer finite");
  }
  const double final_cost = record_residuals(state);
  if (!std::isfinite(final_cost)) {
    summary.pin_residuals_px.assign(project.pins.size(), std::numeric_limits<double>::quiet_NaN());
    return finish(SolverTermination::kFailed, "the solve diverged: the reprojection is not finite");
  }
  summary.final_cost = final_cost;

  *solved = project;
  scene_solve_internal::WriteSceneState(problem, state, solved);
  for (const auto& w : scene_solve_internal::UndeterminedParameterWarnings(project, problem, state)) {
    summary.warnings.push_back(w);
  }
  AddBehindCameraWarnings(project, problem, *solved, &summary.warnings);
  return finish(lm.termination, lm.message);
}

}  // namespace facet
