#include "core/estimators/fit_steps.h"

#include <cmath>
#include <utility>

#include "core/geometry/camera.h"
#include "core/geometry/hartley_normalization.h"

namespace facet {
namespace {

VpFitState StateOf(const VpCalibrationSummary& summary) {
  VpFitState state;
  state.focal_px = summary.focal_px;
  state.principal_point_px = summary.principal_point_px;
  state.vanishing_points = summary.vanishing_points;
  state.cost_px2 = summary.final_cost;
  return state;
}

// The fit with a budget of `iterations`.
VpCalibrationSummary RunVpFit(const VpFitSteps& steps, int iterations) {
  VpCalibrationOptions options = steps.options;
  options.max_joint_iterations = iterations;
  return CalibrateFromVanishingLines(steps.segments, options);
}

FundamentalSummary RunFundamentalFit(const FundamentalFitSteps& steps, int iterations) {
  FundamentalOptions options = steps.options;
  options.max_refine_iterations = iterations;
  return EstimateFundamentalMatrix(steps.uv1, steps.uv2, options);
}

constexpr double kDegree = 3.14159265358979323846 / 180.0;

}  // namespace

VpCalibrationOptions PerturbVpStart(const VpCalibrationSummary& answer, const VpCalibrationOptions& options,
                                    double perturbation) {
  VpCalibrationOptions moved = options;
  moved.warm_start = true;
  moved.warm_start_focal_px = answer.focal_px * (1.0 + perturbation);
  moved.warm_start_principal_point_px =
      answer.principal_point_px + perturbation * 0.25 * Eigen::Vector2d(options.width_px, -options.height_px);
  const Eigen::Vector3d axis = Eigen::Vector3d(1.0, 2.0, 3.0).normalized();
  moved.warm_start_rotation =
      RotationFromAngleAxis(perturbation * 20.0 * kDegree * axis) * answer.cam_from_world_rotation;
  return moved;
}

Eigen::Matrix3d PerturbFundamental(const Eigen::Matrix3d& F, const std::vector<Eigen::Vector2d>& uv1,
                                   const std::vector<Eigen::Vector2d>& uv2, double perturbation) {
  internal::OrthonormalFundamental o = internal::OrthonormalFundamental::FromF(F, internal::HartleyNormalization(uv1),
                                                                               internal::HartleyNormalization(uv2));
  const double angle = perturbation * 10.0 * kDegree;
  o.U = o.U * RotationFromAngleAxis(angle * Eigen::Vector3d(1.0, 2.0, 3.0).normalized());
  o.V = o.V * RotationFromAngleAxis(angle * Eigen::Vector3d(3.0, -1.0, 2.0).normalized());
  o.s *= 1.0 - perturbation;
  return NormalizeFundamental(o.F());
}

bool BeginVpFitSteps(const std::vector<Segment>& segments, const VpCalibrationOptions& options, double perturbation,
                     VpFitSteps* steps, VpCalibrationSummary* failure) {
  VpFitSteps begun;
  begun.segments = segments;
  begun.options = options;
  begun.perturbation = perturbation;
  // The refit without the flagged segments is a second fit on other data, not an iteration.
  begun.options.refit_without_outliers = false;
  begun.options.record_joint_trace = true;
  if (perturbation != 0.0) {
    const VpCalibrationSummary answer = CalibrateFromVanishingLines(segments, begun.options);
    if (!answer.IsUsable()) {
      if (failure != nullptr) *failure = answer;
      return false;
    }
    begun.options = PerturbVpStart(answer, begun.options, perturbation);
  }
  VpCalibrationSummary start = RunVpFit(begun, 0);
  if (!start.IsUsable()) {
    if (failure != nullptr) *failure = std::move(start);
    return false;
  }
  begun.path.push_back(StateOf(start));
  begun.summary = start;
  begun.start = std::move(start);
  *steps = std::move(begun);
  return true;
}

bool StepVpFit(VpFitSteps* steps, VpCalibrationSummary* failure) {
  if (steps->finished) return false;
  VpCalibrationSummary next = RunVpFit(*steps, steps->steps + 1);
  if (!next.IsUsable()) {
    if (failure != nullptr) *failure = std::move(next);
    return false;
  }
  ++steps->steps;
  steps->finished = next.termination != SolverTermination::kMaxIterations;
  steps->trace = next.joint_trace;
  steps->path.push_back(StateOf(next));
  steps->summary = std::move(next);
  return true;
}

void ResetVpFitSteps(VpFitSteps* steps) {
  steps->steps = 0;
  steps->finished = false;
  steps->trace.clear();
  steps->path.resize(1);
  steps->summary = steps->start;
}

bool BeginFundamentalFitSteps(const std::vector<Eigen::Vector2d>& uv1, const std::vector<Eigen::Vector2d>& uv2,
                              const FundamentalOptions& options, double perturbation, FundamentalFitSteps* steps,
                              FundamentalSummary* failure) {
  FundamentalFitSteps begun;
  begun.uv1 = uv1;
  begun.uv2 = uv2;
  begun.options = options;
  begun.perturbation = perturbation;
  begun.options.use_ransac = false;
  begun.options.refine = true;
  begun.options.record_refine_trace = true;
  if (perturbation != 0.0) {
    const FundamentalSummary answer = EstimateFundamentalMatrix(uv1, uv2, begun.options);
    if (!answer.IsUsable()) {
      if (failure != nullptr) *failure = answer;
      return false;
    }
    begun.options.warm_start = true;
    begun.options.warm_start_F = PerturbFundamental(answer.F, uv1, uv2, perturbation);
  }
  FundamentalSummary start = RunFundamentalFit(begun, 0);
  if (!start.IsUsable()) {
    if (failure != nullptr) *failure = std::move(start);
    return false;
  }
  begun.path.push_back(start.F);
  begun.summary = start;
  begun.start = std::move(start);
  *steps = std::move(begun);
  return true;
}

bool StepFundamentalFit(FundamentalFitSteps* steps, FundamentalSummary* failure) {
  if (steps->finished) return false;
  FundamentalSummary next = RunFundamentalFit(*steps, steps->steps + 1);
  if (!next.IsUsable()) {
    if (failure != nullptr) *failure = std::move(next);
    return false;
  }
  ++steps->steps;
  steps->finished = next.termination != SolverTermination::kMaxIterations;
  steps->trace = next.refine_trace;
  steps->path.push_back(next.F);
  steps->summary = std::move(next);
  return true;
}

void ResetFundamentalFitSteps(FundamentalFitSteps* steps) {
  steps->steps = 0;
  steps->finished = false;
  steps->trace.clear();
  steps->path.resize(1);
  steps->summary = steps->start;
}

}  // namespace facet
