// The joint solve (the paper's equation): cameras and geometry from all constraints at once,
//   min  sum_j sum_i ||P_j v_i - m_ij||^2  (pins)  + vanishing-line residuals (segments)
//   s.t. g(v) = 0                          (project.constraints)
// over the free camera and primitive parameters. Vertices are written in primitive-local
// coordinates times the primitive's pose (core/mesh/mesh.h, LocalDefinition: v = R (C p) + t), so
// topology edits keep using the primitive parameterisation.
//
// Parameters (each block present only when free and used by a residual):
// - per calibrated image: focal (unless Image::focal_locked), principal point (unless
//   principal_point_locked), rotation (3, a small rotation applied on the left) and centre (3)
//   unless pose_locked, radial distortion k1, k2 (unless distortion_locked; Camera's model).
//   Images of one lens group (Image::lens_group > 0) have one focal length, one principal
//   point and one k1, k2 among those they free, started from the mean of their values;
// - per primitive: each unlocked shape parameter, rotation (unless rotation_locked) and
//   translation (unless translation_locked). A primitive attached on a box (attached_to)
//   takes its footprint and pose from its base, so only its own parameters from index 2 on
//   are free;
// - per free vertex (LocalDefinition::free, e.g. an E_split vertex the user marked free to
//   pin it to a roof ridge off its edge): its local offset (3). A vertex that is not free
//   stays on its definition. The rule is explicit: the solve never frees a vertex itself.
// Residuals, all in px so they share one scale:
// - a pin: projection of its vertex through the lens distortion minus the pin's pixel (2);
// - a segment of a line family: signed distance of each endpoint to the line through the
//   segment's midpoint and the family's vanishing point K R e_axis (2), which keeps the
//   camera's rotation tied to the user's lines. Segments are drawn on the distorted photo, so
//   with k != 0 (or k free) their endpoints are undistorted with the current intrinsics first
//   (Camera::UndistortPixel), derivatives with respect to f, c, k1, k2 included; an
//   edge-on-image-line constraint's two line points likewise;
// - a spatial constraint: g(v) made dimensionless (sines and cosines of angles, lengths over
//   the model size S = RMS spread of the used vertices at the start, a distance over its
//   value, image-line distances over the focal length; core/solve/joint_solve_internal.h lists
//   each kind) and enforced by an augmented Lagrangian on the interactive path: rows
//   sqrt(mu) c + lambda / sqrt(mu), mu starting at 1e6 (a relative error of 1e-3 weighs like
//   1 px); after each inner Levenberg-Marquardt run lambda += mu c, and mu grows tenfold
//   (up to 1e14) when max |c| fell by less than a factor 4; at most 12 outer rounds, ending
//   once max |c| <= constraint_tolerance and the cost the constraints still owe, sum
//   |lambda c|, is below 1e-10 of the observation cost; when only the latter fails, one last
//   round at mu = 1e14 with the (by then nearly exact) multipliers settles it in a step or
//   two. Each inner LM run stops once its model promises less than function_tolerance of
//   the cost and restarts from the damping of its last accepted step. The SLSQP polish
//   (NLopt) then makes them hold as hard equalities.
// Linear algebra: the damped normal equations (J^T J + lambda diag(J^T J)) delta = -J^T r. By
// default (kSchur) the primitive-side parameters are grouped (a primitive with the primitives
// attached to it and its free vertices, merged when a constraint couples them); no residual
// couples two groups, so each group's small dense block is eliminated on its own and the
// cameras are solved from the dense reduced camera system (Schur complement): the time per
// iteration grows linearly with the primitives. A group larger than 96 parameters (e.g. one
// coplanarity across many primitives) falls back to kSparseLdlt: a sparse matrix of fixed
// pattern factorised by a simplicial LDL^T whose AMD ordering and symbolic analysis are done
// once per solve.
// Gauge: world axes come from the calibrated rotations or a locked primitive rotation; the
// origin from a fixed point, a locked translation or a locked camera centre; the scale from a
// distance constraint or a locked dimension. When something is left free the solve still
// runs (LM damping picks the nearest solution) and the summary names it.
#pragma once

#include <string>
#include <vector>

#include "core/optim/solver_summary.h"
#include "core/scene/project.h"

namespace facet {

struct JointSolveOptions {
  int max_iterations = 100;  // LM iterations (the per-frame budget while dragging)
  double function_tolerance = 1e-14;
  double gradient_tolerance = 1e-14;
  double parameter_tolerance = 1e-14;
  double initial_lambda = 1e-4;
  // Start from the project's values (interactive path). When false and the problem has at
  // most 300 parameters, the geometry solve (core/solve/scene_solve.h, linear initialisation of
  // camera centres and dimensions) gives the start; initial_cost is then measured there.
  bool warm_start = true;
  bool refine_intrinsics = true;  // false keeps every camera's intrinsics (k too) whatever the locks
  bool use_segments = true;       // vanishing-line residuals on cameras with segments
  // Hard equality polish by NLopt SLSQP after LM, so that coplanar points end up coplanar to
  // ~1e-9 of the model size. Off on the per-frame path; on when a drag ends or on request.
  bool polish_constraints = false;
  double constraint_tolerance = 1e-9;  // relative to the model size
  // A constraint whose scale-free residual stays above this after the solve is reported as
  // not satisfied, and named in `conflicts`.
  double conflict_tolerance = 1e-6;
  // Diagnostics cost a dense SVD of the column-scaled Jacobian: on for a full solve, off per
  // frame. Above 600 parameters the analysis is skipped with a warning.
  bool compute_diagnostics = true;
  // Robust loss on the pins (issue 26: a pin clicked 47-75 px off its place pulled every
  // camera by degrees). After the least-squares solve, the pins' noise scale sigma is taken
  // from their own spread, median(|r_i|) / 1.1774 (the median of a 2D Gaussian residual's
  // norm is 1.1774 sigma), floored at robust_min_scale_px; then iteratively reweighted solves
  // weigh each pin's squared residual by w(|r|): 1 up to huber_scale * sigma (quadratic, so
  // noise-free and inlier-only scenes keep the least-squares optimum), Huber's c / |r| above,
  // and beyond outlier_scale * sigma a redescending tail (c / |r|) (t / |r|)^2, t that
  // threshold, whose pull on the model fades as 1 / |r|^2. Pins beyond outlier_scale * sigma
  // are flagged in the summary. Needs at least robust_min_pins pins.
  bool robust_pins = true;
  double robust_min_scale_px = 1.0;
  double huber_scale = 3.0;    // in units of sigma
  double outlier_scale = 5.0;  // in units of sigma, above huber_scale
  int robust_min_pins = 6;
  int max_robust_rounds = 8;  // reweighted solves after the first
  enum class LinearSolver { kSchur, kSparseLdlt };
  LinearSolver linear_solver = LinearSolver::kSchur;

  bool Check(std::string* error) const;
};

struct PinDiagnostic {
  Id pin_id = kNoId;
  double error_px = 0.0;  // NaN when the pin did not take part
  double weight = 1.0;    // the robust loss's weight on its squared residual (1: an inlier)
};
// A pin whose residual is far beyond the others' (JointSolveOptions::outlier_scale): most
// likely a click on the wrong place.
struct FlaggedPin {
  Id pin_id = kNoId;
  Id image_id = kNoId;
  double error_px = 0.0;  // distance from where the solved model puts its vertex, px
  std::string sentence;   // "pin 12 in 0003 is 47 px from where the model puts it"
};
struct ImageDiagnostic {
  Id image_id = kNoId;
  int num_pins = 0;
  double rms_px = 0.0;
  double max_px = 0.0;
};
struct ConstraintDiagnostic {
  Id constraint_id = kNoId;
  // In the constraint's natural unit: project units for coplanar/collinear/distance/fixed
  // point distances, degrees for parallel/perpendicular/axis, px for edge-on-image-line.
  double residual = 0.0;
  std::string unit;
  bool satisfied = false;  // within the tolerance
};

// The joint solve's summary: SolverSummary's fields (core/optim/solver_summary.h), with
// initial_cost and final_cost 0.5 * sum of squared observation residuals (px^2, pins and
// segments) at the start and at the result; with down-weighted pins final_cost is the robust
// objective (each pin's squared residual times its weight).
struct JointSolveSummary : SolverSummary {
  int num_residuals = 0;
  int num_parameters = 0;
  double reprojection_rms_px = 0.0;  // over the pins that took part
  double reprojection_max_px = 0.0;
  // Robust loss on the pins (JointSolveOptions::robust_pins): the noise scale sigma it used
  // (px; 0 when it did not run), the pins it gave a weight below 1, and those beyond the
  // outlier threshold, worst first (their sentences are also in warnings).
  double pin_scale_px = 0.0;
  int num_downweighted_pins = 0;
  std::vector<FlaggedPin> flagged_pins;
  // The solve converged to a degenerate model (WhySolvedModelDegenerate); termination is then
  // kFailed and the message names the size.
  bool degenerate = false;
  // Images whose unlocked distortion the solve took past any lens (WhyDistortionFolds,
  // core/geometry/camera_checks.h), or whose unlocked focal length it took beyond 25 image
  // diagonals (a 1,080 mm lens on full frame: pins that do not fix f): the solve ran again
  // with those held where they started, one sentence each (also first in warnings).
  std::vector<std::string> held_intrinsics;
  std::vector<PinDiagnostic> pins;                // project.pins order
  std::vector<ImageDiagnostic> images;            // calibrated images with pins
  std::vector<ConstraintDiagnostic> constraints;  // project.constraints order
  // Parameters the residuals do not determine (from the rank of the column-scaled Jacobian),
  // one sentence each: "the box 'house' depth is free: pin a vertex on its back face or add a
  // second image".
  std::vector<std::string> undetermined;
  // The degrees of freedom the residuals leave (pins, segments and spatial constraints
  // together): num_parameters minus the rank of that column-scaled Jacobian, gauge freedoms
  // (e.g. the scale without a known length) included; -1 when the diagnostics did not run.
  int degrees_of_freedom_left = -1;
  // Constraints that cannot hold together (their scale-free residuals stay above
  // conflict_tolerance after a solve that converged; not named when the iteration budget ran
  // out, e.g. per frame).
  std::vector<std::string> conflicts;
  bool polished = false;
};

// Solves and writes the result to *solved (cameras, primitive shapes and cached vertex
// positions). When the summary is not usable, *solved is an unchanged copy of `project`.
JointSolveSummary SolveJoint(const Project& project, const JointSolveOptions& options, Project* solved);

// Why a solved model is no answer though its solve converged (issue 14: degenerate geometry
// gives a named error, never a number that looks like an answer): CheckModelChange
// (core/solve/model_sanity.h) of `before` against `solved` -- a size at or below zero, shrunk
// to nothing (the model collapsing when nothing the pins see fixes its scale), or grown or
// moved a millionfold beyond its reach (cameras and model run off to infinity together) --
// with what likely caused it. Names the primitive and the size; "" when usable.
std::string WhySolvedModelDegenerate(const Project& before, const Project& solved);

// Whether the pins see the length of the edge (a, b): it varies with a shape parameter that a
// pin's vertex moves with. A known length on an edge they do not see (a box's depth when only
// its front face is pinned) says nothing about the size of what they see, so it cannot take
// the scale over from a kept dimension.
bool PinsSeeLength(const Project& project, const VertexRef& a, const VertexRef& b);

}  // namespace facet
