// The vanishing-point fit (core/estimators/calibrate_vp.h) and the two-view refinement of F
// (core/estimators/two_view.h) one Levenberg-Marquardt iteration at a time, for teaching
// (issue 15), in the pattern of the joint solve's steps (core/solve/joint_solve_steps.h): step
// k re-runs the fit from its own initial estimate with a budget of k iterations, so the k-th
// state is the fit's own k-th iterate (same parameterisation, damping schedule and stop tests:
// the fit's code, not a copy), and the trace holds every trial so far. k steps cost
// k (k + 1) / 2 iterations of a fit that takes well under a millisecond each.
//
// What is stepped is the fit's Levenberg-Marquardt part alone:
//   - vanishing points: the joint maximum-likelihood fit of (f, principal point, R) to all
//     segments with the orthogonality of the three directions built in, one round (no refit
//     without outliers), from the closed form;
//   - two views: the refinement of F on the symmetric epipolar distance over the given
//     matches (the caller passes the inliers of a full estimate: RANSAC is not an iteration
//     of the refinement), from the normalised 8-point estimate.
//
// Both fits' own starts are already close to their answers on real photos (the Leuven
// sample's two-view refinement goes from 1.343 to 1.342 px RMS), so stepping them shows
// nothing. With a perturbation `amount` > 0 the steps start instead from the fit's answer
// moved off it the same way every time (no randomness: the same lecture on every machine),
// handed to the fit as its warm start, so that step k is still the fit's own k-th iterate:
//   - vanishing points: a solved focal length scaled by 1 + amount, a solved principal point
//     moved by amount x (width, -height) / 4 (5 % of each side at 0.2, two standard deviations
//     of the fit's default prior), the rotation turned by amount x 20 degrees (4 at 0.2, as
//     PerturbForSteps turns the joint solve's cameras) about the fixed axis (1, 2, 3);
//   - two views: F in its own parameterisation (core/estimators/two_view.h's orthonormal
//     representation on the points' Hartley normalisations), U turned by amount x 10 degrees
//     about (1, 2, 3), V by the same angle about (3, -1, 2), and s = sigma2 / sigma1 scaled by
//     1 - amount.
// The answer moved from is the unbudgeted fit from the fit's own start.
#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>

#include "core/estimators/calibrate_vp.h"
#include "core/estimators/two_view.h"

namespace facet {

// --- Vanishing points ---

// The fit's state after a step (or at the start), in px.
struct VpFitState {
  double focal_px = 0.0;
  Eigen::Vector2d principal_point_px = Eigen::Vector2d::Zero();
  // Homogeneous, unit norm, third coordinate >= 0; zero for an absent family.
  std::array<Eigen::Vector3d, 3> vanishing_points{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                                                  Eigen::Vector3d::Zero()};
  double cost_px2 = 0.0;  // the fit's sum of squared residuals (segments, horizon, priors)
};

struct VpFitSteps {
  std::vector<Segment> segments;
  double perturbation = 0.0;     // the start's amount (0: the fit's own start)
  VpCalibrationOptions options;  // as given, one round, the trace on; the budget set per step
  int steps = 0;
  VpCalibrationSummary start;      // the fit with 0 iterations
  VpCalibrationSummary summary;    // of the current state (start until the first step)
  std::vector<LmIteration> trace;  // every trial up to the current step (cost conditioned)
  std::vector<VpFitState> path;    // the start and the state after each step: steps + 1 entries
  bool finished = false;           // the last step's fit stopped before its budget
};

// The start: the fit with a budget of 0 (its closed form, or the warm start the options
// give; with perturbation > 0 the fit's answer moved off it as above). False (with *failure)
// when the calibration itself fails there.
bool BeginVpFitSteps(const std::vector<Segment>& segments, const VpCalibrationOptions& options, double perturbation,
                     VpFitSteps* steps, VpCalibrationSummary* failure = nullptr);
// The warm start `perturbation` away from `answer` (a usable fit with `options`).
VpCalibrationOptions PerturbVpStart(const VpCalibrationSummary& answer, const VpCalibrationOptions& options,
                                    double perturbation);
// One iteration more. False, with *steps unchanged, when finished or when the fit fails.
bool StepVpFit(VpFitSteps* steps, VpCalibrationSummary* failure = nullptr);
// Back to the start, exactly.
void ResetVpFitSteps(VpFitSteps* steps);

// --- Two views ---

struct FundamentalFitSteps {
  std::vector<Eigen::Vector2d> uv1, uv2;
  double perturbation = 0.0;   // the start's amount (0: the linear estimate)
  FundamentalOptions options;  // as given, without RANSAC, the trace on; the budget set per step
  int steps = 0;
  FundamentalSummary start;    // the refinement with 0 iterations: the linear or perturbed estimate
  FundamentalSummary summary;  // of the current state (start until the first step)
  std::vector<LmIteration> trace;
  // F after 0, 1, ... steps (unit Frobenius norm, largest entry positive): steps + 1 entries.
  std::vector<Eigen::Matrix3d> path;
  bool finished = false;
};

bool BeginFundamentalFitSteps(const std::vector<Eigen::Vector2d>& uv1, const std::vector<Eigen::Vector2d>& uv2,
                              const FundamentalOptions& options, double perturbation, FundamentalFitSteps* steps,
                              FundamentalSummary* failure = nullptr);
// F moved `perturbation` off `F` as above (unit Frobenius norm, largest entry positive).
Eigen::Matrix3d PerturbFundamental(const Eigen::Matrix3d& F, const std::vector<Eigen::Vector2d>& uv1,
                                   const std::vector<Eigen::Vector2d>& uv2, double perturbation);
bool StepFundamentalFit(FundamentalFitSteps* steps, FundamentalSummary* failure = nullptr);
void ResetFundamentalFitSteps(FundamentalFitSteps* steps);

}  // namespace facet
