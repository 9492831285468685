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
#include "core/solve/scene_solve_internal.h"

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
  if (!(initial_lambda > 0.0) || !std::isfinite(initial_lambda)) return fail("initial_lambda must be positive and finite");
  return true;
}

const char* SolveTerminationName(SolveTermination termination) {
  switch (termination) {
    case SolveTermination::kConverged: return "converged";
    case SolveTermination::kMaxIterations: return "max iterations";
    case SolveTermination::kNothingToSolve: return "nothing to solve";
    case SolveTermination::kFailed: return "failed";
    case SolveTermination::kInvalidInput: return "invalid input";
  }
  return "?";
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

struct LmResult {
  SolveTermination termination = SolveTermination::kFailed;
  std::string message;
  int iterations = 0;
};

// Levenberg-Marquardt with Marquardt's scaling: the damping term is lambda * diag(J^T J),
// taking the running maximum of each diagonal entry (More 1978) so a column that shrinks
// for a while cannot make the step blow up. With this scaling the iterates do not depend on
// the units of the parameters, and neither do the gradient and step tests, which are
// measured in the same scaled coordinates. Lambda follows Nielsen's rule.
LmResult RunLevenbergMarquardt(const SceneProblem& problem, const SceneSolveOptions& options, SceneState* state) {
  const int n = problem.num_parameters;
  LmResult result;
  Eigen::VectorXd residuals, trial_residuals, gradient, delta, values;
  Eigen::MatrixXd jacobian, trial_jacobian, normal, damped;
  Eigen::VectorXd max_diagonal = Eigen::VectorXd::Zero(n), scale(n), damping(n);
  int num_behind = scene_solve_internal::EvaluateScene(problem, *state, &residuals, &jacobian);
  double cost = Cost(residuals);
  double lambda = options.initial_lambda;
  double nu = 2.0;
  constexpr double kMaxLambda = 1e32;
  SceneState trial;
  auto stop = [&](SolveTermination termination, std::string message) {
    result.termination = termination;
    result.message = std::move(message);
    return result;
  };

  bool need_normal = true;
  while (true) {
    if (need_normal) {
      normal.noalias() = jacobian.transpose() * jacobian;
      gradient.noalias() = jacobian.transpose() * residuals;
      max_diagonal = max_diagonal.cwiseMax(normal.diagonal());
      // A parameter no pin moves has a zero column; a tiny floor keeps the system solvable
      // and its step zero (its gradient is zero).
      const double floor = std::max(1e-12 * max_diagonal.maxCoeff(), std::numeric_limits<double>::min());
      damping = max_diagonal.cwiseMax(floor);
      scale = damping.cwiseSqrt();
      need_normal = false;
      if (cost == 0.0) return stop(SolveTermination::kConverged, "the residuals are zero");
      const double scaled_gradient = (gradient.array() / scale.array()).abs().maxCoeff();
      if (scaled_gradient <= options.gradient_tolerance) {
        return stop(SolveTermination::kConverged, "gradient tolerance reached");
      }
    }
    if (result.iterations >= options.max_iterations) {
      return stop(SolveTermination::kMaxIterations, "iteration limit reached");
    }
    ++result.iterations;

    damped = normal;
    damped.diagonal() += lambda * damping;
    delta = damped.ldlt().solve(-gradient);
    if (!delta.allFinite()) {
      lambda *= nu;
      nu *= 2.0;
      if (lambda > kMaxLambda) return stop(SolveTermination::kFailed, "the normal equations cannot be solved");
      continue;
    }
    ParameterValues(problem, *state, &values);
    const double step_norm = (delta.array() * scale.array()).matrix().norm();
    const double value_norm = (values.array() * scale.array()).matrix().norm();
    if (step_norm <= options.parameter_tolerance * (value_norm + options.parameter_tolerance)) {
      return stop(SolveTermination::kConverged, "parameter tolerance reached");
    }

    trial = *state;
    scene_solve_internal::ApplySceneStep(problem, delta, &trial);
    const int trial_behind = scene_solve_internal::EvaluateScene(problem, trial, &trial_residuals, &trial_jacobian);
    const double trial_cost = Cost(trial_residuals);
    // Decrease of the linear model: -g.d - 0.5 d.JtJ.d = 0.5 d.(lambda D d - g).
    const double predicted = 0.5 * delta.dot(lambda * damping.cwiseProduct(delta) - gradient);
    const bool valid = std::isfinite(trial_cost) && trial_jacobian.allFinite() && trial_behind <= num_behind;
    if (valid && trial_cost < cost && predicted > 0.0) {
      const double rho = (cost - trial_cost) / predicted;
      const double relative_decrease = (cost - trial_cost) / cost;
      std::swap(*state, trial);
      std::swap(residuals, trial_residuals);
      std::swap(jacobian, trial_jacobian);
      cost = trial_cost;
      num_behind = trial_behind;
      const double t = 2.0 * rho - 1.0;
      lambda *= std::max(1.0 / 3.0, 1.0 - t * t * t);
      nu = 2.0;
      need_normal = true;
      if (relative_decrease <= options.function_tolerance) {
        return stop(SolveTermination::kConverged, "function tolerance reached");
      }
    } else {
      lambda *= nu;
      nu *= 2.0;
      if (lambda > kMaxLambda) {
        return stop(SolveTermination::kConverged, "no step decreases the cost any more");
      }
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
  auto finish = [&](SolveTermination termination, std::string message) {
    summary.termination = termination;
    summary.message = std::move(message);
    if (!summary.IsUsable()) *solved = project;
    summary.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return summary;
  };
  summary.pin_residuals_px.assign(project.pins.size(), std::numeric_limits<double>::quiet_NaN());

  std::string error;
  if (!options.Check(&error)) return finish(SolveTermination::kInvalidInput, "invalid options: " + error);

  SceneState state;
  const SceneProblem problem = scene_solve_internal::BuildSceneProblem(project, &state);
  summary.warnings = problem.warnings;
  summary.num_skipped_pins = problem.num_skipped_pins;
  summary.num_residuals = 2 * static_cast<int>(problem.observations.size());
  summary.num_parameters = problem.num_parameters;

  for (const auto& obs : problem.observations) {
    if (!obs.uv_px.allFinite()) {
      return finish(SolveTermination::kInvalidInput,
                    "pin #" + std::to_string(project.pins[obs.pin_index].id) + " has a non-finite pixel position");
    }
  }
  for (const auto& cam : problem.cameras) {
    if (!(cam.focal_px > 0.0) || !std::isfinite(cam.focal_px) || !cam.principal_point_px.allFinite() ||
        !cam.cam_from_world_rotation.allFinite()) {
      return finish(SolveTermination::kInvalidInput,
                    "the camera of image #" + std::to_string(project.images[cam.image_index].id) +
                        " has invalid intrinsics or rotation");
    }
  }
  if (!StateIsFinite(state)) {
    return finish(SolveTermination::kInvalidInput, "a camera position or primitive parameter is not finite");
  }

  Eigen::VectorXd residuals;
  auto record_residuals = [&](const SceneState& s) {
    scene_solve_internal::EvaluateScene(problem, s, &residuals, nullptr);
    double sum_sq = 0.0, max_px = 0.0;
    for (size_t o = 0; o < problem.observations.size(); ++o) {
      const double e = residuals.segment<2>(2 * o).norm();
      summary.pin_residuals_px[problem.observations[o].pin_index] = e;
      sum_sq += e * e;
      max_px = std::max(max_px, e);
    }
    const size_t num = problem.observations.size();
    summary.reprojection_rms_px = num > 0 ? std::sqrt(sum_sq / num) : 0.0;
    summary.reprojection_max_px = max_px;
    return Cost(residuals);
  };

  if (problem.observations.empty()) {
    *solved = project;
    return finish(SolveTermination::kNothingToSolve, "no pins in calibrated images");
  }
  summary.initial_cost = summary.final_cost = record_residuals(state);
  if (problem.num_parameters == 0) {
    *solved = project;
    return finish(SolveTermination::kNothingToSolve,
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
    return finish(SolveTermination::kFailed,
                  std::string("the reprojection is not finite at the start: a pinned vertex lies in the plane of its camera") +
                      (why.empty() ? "" : ", and the linear initialisation found no start (" + why + ")"));
  }

  // This LM and the rank analysis below are dense (n^2 work per residual): above
  // kMaxDenseParameters the geometry solve stops at its start (the linear initialisation on a
  // cold start) and leaves the refinement to the joint solve's sparse LM, which UpdateModel
  // runs next (core/solve/model_update.h) and which is exact on the same residuals.
  if (problem.num_parameters > kMaxDenseParameters) {
    if (!StateIsFinite(state)) return finish(SolveTermination::kFailed, "the linear start is not finite");
    summary.final_cost = record_residuals(state);
    if (!std::isfinite(summary.final_cost))
      return finish(SolveTermination::kFailed, "the reprojection is not finite at the linear start");
    *solved = project;
    scene_solve_internal::WriteSceneState(problem, state, solved);
    return finish(SolveTermination::kMaxIterations,
                  std::string(summary.linear_initialization_used ? "linear start only" : "start kept") + ": " +
                      std::to_string(problem.num_parameters) + " parameters are refined by the joint solve");
  }
  const auto lm = RunLevenbergMarquardt(problem, options, &state);
  summary.iterations = lm.iterations;
  if (lm.termination == SolveTermination::kFailed) return finish(lm.termination, lm.message);
  if (!StateIsFinite(state)) {
    return finish(SolveTermination::kFailed, "the solve diverged: a parameter is no longer finite");
  }
  const double final_cost = record_residuals(state);
  if (!std::isfinite(final_cost)) {
    summary.pin_residuals_px.assign(project.pins.size(), std::numeric_limits<double>::quiet_NaN());
    return finish(SolveTermination::kFailed, "the solve diverged: the reprojection is not finite");
  }
  summary.final_cost = final_cost;

  *solved = project;
  scene_solve_internal::WriteSceneState(problem, state, solved);
  for (const auto& w : scene_solve_internal::UndeterminedParameterWarnings(project, problem, state)) {
    summary.warnings.push_back(w);
  }
  for (const auto& obs : problem.observations) {
    const Primitive& primitive = solved->primitives[problem.primitives[obs.primitive].primitive_index];
    const Image& image = solved->images[problem.cameras[obs.camera].image_index];
    if (image.camera.CamFromWorld(primitive.mesh.vertex(solved->pins[obs.pin_index].vertex.vertex).position).z() <= 0.0) {
      summary.warnings.push_back("pin #" + std::to_string(project.pins[obs.pin_index].id) +
                                 ": the vertex lies behind the camera of its image");
    }
  }
  return finish(lm.termination, lm.message);
}

}  // namespace facet
