// Single-image calibration from vanishing points of user-drawn line families (the paper's
// "three orthogonal vanishing points"). Each vanishing point is fitted by least squares over
// all segments of its family (2 or more); the focal length and principal point follow from
// the orthocentre construction with three vanishing points, or the focal length alone from
// two with the principal point given; the rotation from the vanishing directions (with one
// horizontal family, from it and the horizon). That closed form (or a warm start) then
// starts a joint maximum-likelihood fit of focal length, principal point and rotation to all
// segments (each residual the distance of a segment's endpoints to the line through its
// midpoint and the camera's vanishing point), which keeps the three directions orthogonal.
// Optional Gaussian priors: the principal point at the image centre (when solved) and the
// focal length (e.g. from EXIF, core/image/exif.h). Segments whose residual is far above the
// robust noise level are flagged, and the fit is repeated without them. The summary carries
// first-order standard deviations from the fit's covariance and degeneracy figures.
// Reference: Hartley & Zisserman, Multiple View Geometry, 2nd ed., sections 8.6 and 8.8.
#pragma once

#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/geometry/intrinsics_modes.h"
#include "core/geometry/segment.h"
#include "core/optim/levenberg_marquardt.h"
#include "core/optim/solver_summary.h"

namespace facet {

struct VpCalibrationOptions {
  int width_px = 0;  // image size (principal point "center" is (w - 1) / 2, (h - 1) / 2)
  int height_px = 0;
  // kSolve needs three families; with fewer, kSolve falls back to kImageCenter and says so in
  // the warnings. A fixed principal point may lie outside the image (cropped photos).
  PrincipalPointMode principal_point_mode = PrincipalPointMode::kSolve;
  Eigen::Vector2d fixed_principal_point_px = Eigen::Vector2d::Zero();  // for kFixed
  // kSolve only: standard deviation in px of a Gaussian prior on the principal point at the
  // image centre (manufacturing puts the optical axis within a few percent of the sensor
  // size from its centre). 0 gives the default, 2.5 % of the larger image side (16 px at
  // 640 x 480); a negative value turns the prior off.
  double principal_point_prior_std_px = 0.0;

  // Focal length: a value > 0 in fixed_focal_px is a known lens (not solved). Otherwise a
  // prior focal_prior_px > 0 with focal_prior_std_px > 0 (e.g. from the photo's EXIF, see
  // core/image/exif.h) is added to the fit as one Gaussian residual. Both may not be set at once.
  double fixed_focal_px = 0.0;
  double focal_prior_px = 0.0;
  double focal_prior_std_px = 0.0;

  // The horizon, two distinct points (x1, y1, x2, y2) in px on the image of the horizontal
  // plane at infinity (a level horizon at row v is (0, v, w - 1, v)). It fixes the vertical
  // direction, which makes one horizontal family (x or y) with a known focal length (fixed
  // or prior) enough for the rotation. With more families it is one more observation.
  bool use_horizon = false;
  Eigen::Vector4d horizon_px = Eigen::Vector4d::Zero();

  // Warm start: begin the joint fit at this camera instead of the closed form (e.g. the
  // previous result while the user drags a segment). The principal point is used only when
  // it is solved, the focal length only when it is not fixed; the rotation's column signs
  // do not matter.
  bool warm_start = false;
  double warm_start_focal_px = 0.0;
  Eigen::Vector2d warm_start_principal_point_px = Eigen::Vector2d::Zero();
  Eigen::Matrix3d warm_start_rotation = Eigen::Matrix3d::Identity();  // cam_from_world

  // Outliers: a segment whose residual exceeds max(outlier_threshold_sigmas * 1.4826 *
  // median |residual|, outlier_floor_px) is flagged (1.4826 * median |r| estimates the
  // noise sigma robustly; the floor keeps near-exact data from flagging rounding).
  double outlier_threshold_sigmas = 3.0;
  double outlier_floor_px = 1.0;
  // Fit once more without the flagged segments (a family keeps at least its 2 best
  // segments); residuals are still reported for every segment.
  bool refit_without_outliers = true;

  // The joint fit's budget of Levenberg-Marquardt iterations (linearisations, each with its
  // trials) per round. Teach mode steps the fit by running it with 0, 1, 2, ...
  // (core/estimators/fit_steps.h), so that each shown state is the fit's own iterate.
  int max_joint_iterations = 100;
  // Fill VpCalibrationSummary::joint_trace.
  bool record_joint_trace = false;

  bool Check(std::string* error) const;
};

// SolverSummary: message says why it failed, or gives the result in one line; warnings: a
// usable result the user should know about; iterations: accepted steps of the joint fit
// (all its rounds); initial_cost / final_cost: its sum of squared residuals (segments,
// horizon and prior rows) in px^2, at the start of the first round and at the end of the last.
struct VpCalibrationSummary : SolverSummary {
  double focal_px = 0.0;
  Eigen::Vector2d principal_point_px = Eigen::Vector2d::Zero();
  // Columns: world x, y, z axes in the camera frame (core/geometry/conventions.h: z up). The world
  // z axis points up in the image; x and y point towards their vanishing points' side in
  // front of the camera; det = +1.
  Eigen::Matrix3d cam_from_world_rotation = Eigen::Matrix3d::Identity();
  // Homogeneous vanishing point per axis (x, y, z) of the fitted camera (K R e_axis), unit
  // norm, third coordinate >= 0; zero when the family is absent.
  std::array<Eigen::Vector3d, 3> vanishing_points{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                                                  Eigen::Vector3d::Zero()};
  // A family whose segments are parallel in the image (within ~1e-5 rad at the camera).
  std::array<bool, 3> vanishing_point_at_infinity = {false, false, false};
  // Each family's vanishing point fitted on its own, over all its segments (outliers
  // included), before the joint fit ties the three to one camera (FitVanishingPoint,
  // core/estimators/vanishing_point.h): the points of the three-point construction
  // (closed_form_*), in the same form as vanishing_points; zero when the family is absent.
  // Their covariance in px^2 (VanishingPointSummary::point_covariance_px2): NaN for a family
  // of 2 segments or a point at infinity.
  std::array<Eigen::Vector3d, 3> family_vanishing_points{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                                                         Eigen::Vector3d::Zero()};
  std::array<Eigen::Matrix2d, 3> family_vanishing_point_covariance_px2{
      Eigen::Matrix2d::Zero(), Eigen::Matrix2d::Zero(), Eigen::Matrix2d::Zero()};
  // RMS over a family's segments of segment_residuals_px; zero when the family is absent.
  std::array<double, 3> vanishing_point_rms_px = {0.0, 0.0, 0.0};
  // Largest deviation from 90 deg between two fitted vanishing directions before the
  // rotation is made orthonormal (zero by construction with three points and kSolve).
  double max_orthogonality_error_deg = 0.0;
  // The three-point closed form (kSolve with three families) before the joint fit of the
  // camera to all segments; zero when it gave no real focal length.
  double closed_form_focal_px = 0.0;
  Eigen::Vector2d closed_form_principal_point_px = Eigen::Vector2d::Zero();

  // Uncertainty of the joint fit, first order: covariance = (J_d^T J_d / sigma^2 + J_p^T J_p)^-1
  // at the solution, i.e. sigma^2 (J^T J)^-1 with the segment (and horizon) rows J_d at the
  // noise sigma their residuals show and the prior rows J_p (principal point, focal length)
  // in units of their own std. sigma^2 = sum of squared segment and horizon residuals /
  // degrees_of_freedom, degrees_of_freedom = those residuals + prior residuals - parameters.
  // focal_std_px is 0 with a fixed focal length, the prior's std when the segments cannot
  // fix f (one family, or no two finite vanishing points; f is then the prior's value);
  // principal_point_std_px is 0 unless the
  // principal point is solved; all are NaN (with a warning) when degrees_of_freedom <= 0 or
  // the fit leaves a parameter undetermined.
  double focal_std_px = 0.0;
  Eigen::Vector2d principal_point_std_px = Eigen::Vector2d::Zero();
  double residual_sigma_px = 0.0;  // sigma above, in px
  int degrees_of_freedom = 0;
  // Per axis: RMS angle in degrees by which the vanishing direction R e_axis in the camera
  // frame is uncertain (sqrt of the trace of its 2x2 tangent covariance); 0 when absent.
  std::array<double, 3> vanishing_direction_std_deg = {0.0, 0.0, 0.0};

  // Degeneracy figures (the warnings quote them when they pass the thresholds in the .cpp).
  // Per axis: the largest angle in degrees between two segments of the family in the image
  // (near 0: parallel segments, the vanishing point is poorly fixed or at infinity); 0 when
  // absent. The minimum over present families.
  std::array<double, 3> family_angle_spread_deg = {0.0, 0.0, 0.0};
  double min_family_angle_spread_deg = 0.0;
  // Per axis: distance in px of the vanishing point from the principal point (+infinity at
  // infinity, 0 when absent); near 0 the focal length is unconstrained by that point.
  std::array<double, 3> vanishing_point_to_principal_point_px = {0.0, 0.0, 0.0};
  double min_vanishing_point_to_principal_point_px = 0.0;  // over present families
  // Largest angle in degrees of the triangle of the three independently fitted vanishing
  // points (>= 90: obtuse, no real camera; near 90: one point near infinity, f and the
  // principal point poorly fixed). 0 unless three finite points were fitted.
  double vanishing_point_triangle_max_angle_deg = 0.0;

  // Outliers (see VpCalibrationOptions): the threshold used and the flagged input indices,
  // ascending. segment_is_outlier has one entry per input segment.
  double outlier_threshold_px = 0.0;
  std::vector<int> outlier_segments;
  std::vector<bool> segment_is_outlier;
  bool refitted_without_outliers = false;
  // Distance in px of the horizon's two points from the fitted camera's horizon (RMS);
  // 0 without a horizon.
  double horizon_residual_px = 0.0;
  double rms_residual_px = 0.0;  // RMS of segment_residuals_px
  std::array<int, 3> segments_per_axis = {0, 0, 0};
  // Not IsUsable() only because the drawing is not finished: a family with 1 segment, or
  // fewer families than the mode needs (kInvalidInput). More lines will calibrate, so the app
  // shows this as progress, not as a failure; the message says what is missing.
  bool incomplete = false;
  // Per input segment (same order): distance in px of its endpoints to the line through its
  // midpoint and its family's vanishing point (RMS of the two).
  std::vector<double> segment_residuals_px;
  // With VpCalibrationOptions::record_joint_trace: every trial of the joint fit, its rounds in
  // order (LmIteration::iteration counts within a round); cost and step in conditioned units
  // (the cost times conditioning_scale_px^2 is px^2).
  std::vector<LmIteration> joint_trace;
  double conditioning_scale_px = 0.0;  // max(width, height) / 2
};

// Calibrates from the segments of one image (their `axis` names the family). Modes: three
// families (principal point solved, centred or fixed); two families with the principal
// point centred or fixed; one horizontal family with the horizon and a known focal length;
// each with the focal length solved, fixed or under a prior. Degenerate input (a family
// with fewer than 2 segments, parallel or coincident segments where a finite vanishing
// point is needed, two families meeting at one vanishing point, an obtuse vanishing-point
// triangle, too few families for the mode) and a result that is no camera
// (core/geometry/camera_checks.h: a focal length outside any lens or left undetermined by the
// lines, a principal point far off the image) give a summary that is not IsUsable()
// (kInvalidInput or kFailed) and a message that says which.
VpCalibrationSummary CalibrateFromVanishingLines(const std::vector<Segment>& segments,
                                                 const VpCalibrationOptions& options);

}  // namespace facet
