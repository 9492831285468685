// The geometry solve: min over free parameters of sum over pins of ||P_j v_i - m_ij||^2,
// where v_i is a primitive's mesh vertex written in primitive-local coordinates times the
// primitive's pose (Facade style) and P_j the camera of the pin's image. Free parameters:
// the centre of each calibrated camera whose pose is not locked (intrinsics and rotation come
// from calibration), and each primitive's unlocked shape parameters, rotation and
// translation. A locked dimension is a known length and fixes the scale.
// Levenberg-Marquardt on Eigen with analytic Jacobians, after a linear initialisation. The LM
// is dense: above 120 parameters the solve returns its start (the linear initialisation when
// cold, kMaxIterations, "refined by the joint solve") and core/solve/joint_solve.h's sparse LM,
// which UpdateModel runs next, refines it. The linear initialisation itself switches from a
// dense SVD to the Schur complement over primitive blocks above 300 unknowns.
#pragma once

#include <string>
#include <vector>

#include "core/optim/solver_summary.h"
#include "core/scene/project.h"

namespace facet {

struct SceneSolveOptions {
  int max_iterations = 100;
  double function_tolerance = 1e-14;  // relative decrease of the cost that stops the solve
  // max |J^T r| that stops the solve, with J's columns scaled to unit norm (so in px and
  // independent of the scene's units)
  double gradient_tolerance = 1e-14;
  // relative step size that stops the solve, measured with the same column scaling
  double parameter_tolerance = 1e-14;
  double initial_lambda = 1e-4;
  // Use the current parameter values as the start (interactive path). When false, a linear
  // initialisation computes camera centres and primitive dimensions first.
  bool warm_start = false;

  bool Check(std::string* error) const;
};

// The geometry solve's summary: SolverSummary's fields (core/optim/solver_summary.h), with
// initial_cost and final_cost 0.5 * sum of squared residuals (px^2), initial_cost at the
// project's values; warnings e.g. "the depth of box #3 is not determined by the pins".
struct SceneSolveSummary : SolverSummary {
  // Over the pins that took part: root mean square and maximum of the distance (px) between
  // the projected vertex and the pin.
  double reprojection_rms_px = 0.0;
  double reprojection_max_px = 0.0;
  int num_residuals = 0;  // 2 per pin that took part
  int num_parameters = 0;
  int num_skipped_pins = 0;                 // pins in uncalibrated images or naming missing objects
  bool linear_initialization_used = false;  // false for a warm start or when it fell back
  // Unlocked dimensions that no pin sees (a box's depth with only its front face pinned):
  // held at their current values rather than left without a start, one sentence each
  // naming the dimension, the value kept and the fix.
  std::vector<std::string> held_parameters;
  // Per pin, in project.pins order: reprojection error in px after the solve (NaN for pins
  // that did not take part).
  std::vector<double> pin_residuals_px;
};

// Solves and writes the result to *solved (which may alias nothing in `project`). When the
// summary is not usable, *solved is an unchanged copy of `project`.
SceneSolveSummary SolveScene(const Project& project, const SceneSolveOptions& options, Project* solved);

}  // namespace facet
