#include "core/estimators/fit_steps.h"

#include <utility>

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

}  // namespace

bool BeginVpFitSteps(const std::vector<Segment>& segments, const VpCalibrationOptions& options, VpFitSteps* steps,
                     VpCalibrationSummary* failure) {
  VpFitSteps begun;
  begun.segments = segments;
  begun.options = options;
  // The refit without the flagged segments is a second fit on other data, not an iteration.
  begun.options.refit_without_outliers = false;
  begun.options.record_joint_trace = true;
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
                              const FundamentalOptions& options, FundamentalFitSteps* steps,
                              FundamentalSummary* failure) {
  FundamentalFitSteps begun;
  begun.uv1 = uv1;
  begun.uv2 = uv2;
  begun.options = options;
  begun.options.use_ransac = false;
  begun.options.refine = true;
  begun.options.record_refine_trace = true;
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
