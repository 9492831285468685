#include "core/solve/joint_solve_steps.h"

namespace facet {

JointSolveSteps BeginJointSolveSteps(const Project& start, const JointSolveOptions& options) {
  JointSolveSteps steps;
  steps.start = start;
  steps.current = start;
  steps.options = options;
  steps.options.polish_constraints = false;  // not a Levenberg-Marquardt iteration
  return steps;
}

bool StepJointSolve(JointSolveSteps* steps, JointSolveSummary* failure) {
  if (steps->finished) return false;
  JointSolveOptions options = steps->options;
  options.max_iterations = steps->steps + 1;
  Project next;
  std::vector<LmIteration> trace;
  const JointSolveSummary summary = SolveJointTraced(steps->start, options, &next, &trace);
  if (!summary.IsUsable()) {
    if (failure != nullptr) *failure = summary;
    return false;
  }
  ++steps->steps;
  steps->current = std::move(next);
  steps->trace = std::move(trace);
  steps->summary = summary;
  steps->finished = summary.termination != SolverTermination::kMaxIterations;
  return true;
}

void ResetJointSolveSteps(JointSolveSteps* steps) {
  steps->steps = 0;
  steps->current = steps->start;
  steps->trace.clear();
  steps->summary = JointSolveSummary();
  steps->finished = false;
}

}  // namespace facet
