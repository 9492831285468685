// The joint solve (core/solve/joint_solve.h) one Levenberg-Marquardt iteration at a time, for
// teaching (issue 15): step k shows the project after the solve's first k iterations (trials,
// as JointSolveOptions::max_iterations counts them) from the same start, with every trial's
// cost, damping and step norm so far. Each step re-runs the solve from the start with a budget
// of k, so the k-th state is exactly the solve's own k-th iterate, the damping schedule and the
// constraints' multipliers included, not a resumed copy that could drift from it; k steps cost
// k (k + 1) / 2 iterations, nothing for the tens of iterations a lesson steps through.
#pragma once

#include <vector>

#include "core/optim/levenberg_marquardt.h"
#include "core/solve/joint_solve.h"

namespace facet {

// SolveJoint, also filling *trace (when not null) with every trial of every round in order,
// numbered over all rounds (LmIteration::iteration 1, 2, ...).
JointSolveSummary SolveJointTraced(const Project& project, const JointSolveOptions& options, Project* solved,
                                   std::vector<LmIteration>* trace);

struct JointSolveSteps {
  Project start;
  JointSolveOptions options;  // as given, without the SLSQP polish; max_iterations set per step
  int steps = 0;
  Project current;                 // start until the first step
  JointSolveSummary summary;       // of the last step (termination kInvalidInput before any)
  std::vector<LmIteration> trace;  // every trial up to the current step
  // The last step's solve stopped before its budget (converged, or nothing to solve): further
  // steps would give the same state.
  bool finished = false;
};

JointSolveSteps BeginJointSolveSteps(const Project& start, const JointSolveOptions& options);

// One iteration more. False, with *steps unchanged, when finished or when the solve fails
// (the message is then in a returned summary's copy: steps->summary keeps the last good one).
bool StepJointSolve(JointSolveSteps* steps, JointSolveSummary* failure = nullptr);

// Back to the start, exactly (steps, trace and summary cleared).
void ResetJointSolveSteps(JointSolveSteps* steps);

// The options the app's Solver steps window steps with (and its tests solve with): the
// interactive defaults, without the rank diagnostics (a dense SVD per step that the window
// does not show).
JointSolveOptions SolveStepsOptions();

// A start for a lesson (the Solver steps window): a converged project shows nothing when
// stepped, so the free parameters are moved off the answer by a relative `amount`, the same
// way every time: each free primitive dimension scaled by 1 + amount (even indices) or
// 1 - amount (odd), each free primitive translation moved by amount x the model's size (the
// diagonal of its vertices' bounding box) along a fixed direction, a free primitive rotation
// turned by amount x 20 degrees about z; each calibrated camera whose pose is free turned by
// amount x 20 degrees (0.05: 1 degree) about a fixed axis and its centre moved by amount x its
// distance to the model's centre; a free focal length scaled by 1 + amount. Alternate images
// and primitives go the opposite way. Locked values are kept; amount 0 returns the project.
// Cached vertex positions are refreshed.
Project PerturbForSteps(const Project& project, double amount);

}  // namespace facet
