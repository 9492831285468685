// Single-image calibration from known 3D points and their pixels (the paper's "known spatial
// points"): a linear estimate (normalised DLT with RQ decomposition, or a plane-to-image
// homography when the points are coplanar), then Levenberg-Marquardt on the reprojection error.
//
// Points: xyz in world units (any scale; the result's t is in the same units), uv_px in the
// OpenCV pixel convention (core/geometry/conventions.h). The camera is cam_from_world R, t with
// K = [[f, 0, cx], [0, f, cy], [0, 0, 1]] (square pixels, zero skew: our Camera model).
//
// Radial distortion (OpenCV's model, radial part only): for p_in_cam = (X, Y, Z), Z > 0,
//   x = X / Z, y = Y / Z, r^2 = x^2 + y^2, d = 1 + k1 r^2 + k2 r^4,
//   uv = (f x d + cx, f y d + cy).
// k1, k2 are estimated only in the refinement (the linear step is pinhole).
//
// Paths:
// - Non-planar (6 or more points not on one plane): Hartley-normalised DLT for P (3x4), RQ of
//   its left 3x3 into K R (K with positive diagonal, det R = +1), t = K^-1 p4. The RQ K is
//   general (fx, fy, skew); the refinement fits the square-pixel, zero-skew model starting
//   from f = (fx + fy) / 2, with the principal point free (unless fixed by the options).
// - Planar (4 or more points on one plane; detected from the SVD of the centred points): a
//   homography from the plane to the image; with one view, square pixels, zero skew and the
//   principal point given (image centre by default), the focal length follows from the two
//   orthogonality constraints on the homography's columns (Zhang 2000); R, t from K^-1 H,
//   orthonormalised. The principal point stays fixed in the refinement: one view of a plane
//   determines it only weakly. P, fx, fy, skew are then those of this first camera.
// - Known focal length (fixed_focal_px > 0): a calibrated-camera pose (PnP). The linear step
//   is the same (DLT, or the plane's homography without Zhang's focal constraints); its R is
//   kept, t is re-solved linearly with K held (each point's ray through R X + t), and the
//   refinement moves only R, t and what the principal point mode leaves free. Same point
//   counts as above; noise-free data give the pose exactly.
// - Focal prior (focal_prior_px, focal_prior_std_px > 0, fixed_focal_px = 0): the refinement
//   adds the residual (f - prior) * pixel_noise_px / prior_std, so the cost is a weighted sum
//   of squares with pixel noise pixel_noise_px; on the planar path a plane seen fronto-parallel
//   (Zhang's constraints give no f) starts from the prior instead of failing.
// Degenerate input (too few points, collinear points, non-finite values, a plane seen
// fronto-parallel so that f is undetermined) gives a summary that is not IsUsable() with a message. Nearly
// coplanar points on the non-planar path and points behind the camera give warnings.
// References: Hartley & Zisserman, Multiple View Geometry, 2nd ed., sections 4.4, 6.1, 7.1,
// A4.1 (RQ); Z. Zhang, "A flexible new technique for camera calibration", PAMI 2000.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/geometry/camera.h"
#include "core/geometry/intrinsics_modes.h"
#include "core/optim/solver_summary.h"

namespace facet {

struct PointCorrespondence {
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero();    // point in world
  Eigen::Vector2d uv_px = Eigen::Vector2d::Zero();  // its pixel in the image
};

struct DltCalibrationOptions {
  int width_px = 0;  // image size; the image centre is ((w - 1) / 2, (h - 1) / 2)
  int height_px = 0;
  bool refine = true;  // Levenberg-Marquardt after the linear step
  // Our Camera has one focal length and no skew; false is not supported by Camera and is
  // rejected by Check() (the RQ's fx, fy, skew are reported in any case).
  bool square_pixels_zero_skew = true;
  int radial_distortion_terms = 0;  // 0, 1 (k1) or 2 (k1, k2); needs refine
  // kSolve: free in the non-planar refinement; the planar path then uses the image centre.
  // kImageCenter / kFixed: held on both paths. The non-planar linear step estimates its own
  // principal point regardless (kept when refine is false); the refinement starts from the
  // held one.
  PrincipalPointMode principal_point_mode = PrincipalPointMode::kSolve;
  Eigen::Vector2d fixed_principal_point_px = Eigen::Vector2d::Zero();  // for kFixed
  int max_iterations = 100;
  // Focal length (px) known, e.g. Image::fixed_focal_px (FocalMode::kFixed): > 0 holds it
  // (pose only), 0 solves it. Needs refine for a non-planar DLT to use it (without refine the
  // linear camera is returned with the known f and the DLT's R, t re-solved with it).
  double fixed_focal_px = 0.0;
  // Gaussian prior on the focal length (FocalMode::kPrior), used when both are > 0 and the
  // focal length is not fixed. pixel_noise_px is the clicks' assumed standard deviation: it
  // weighs the prior against the reprojection residuals.
  double focal_prior_px = 0.0;
  double focal_prior_std_px = 0.0;
  double pixel_noise_px = 1.0;

  bool Check(std::string* error) const;
};

// SolverSummary: message says why it failed, or gives the result in one line; warnings: a
// usable result the user should know about; iterations, initial_cost, final_cost: the
// refinement's (linearisations; sum of squared reprojection residuals in px^2, plus the
// focal prior's residual squared), zero without refinement.
struct DltCalibrationSummary : SolverSummary {
  bool planar = false;            // which path was taken
  bool focal_fixed = false;       // fixed_focal_px was held (pose-only solve)
  bool focal_prior_used = false;  // the focal prior took part in the refinement
  Camera camera;                  // final camera (refined when options.refine)
  double k1 = 0.0;                // radial distortion, zero unless estimated
  double k2 = 0.0;
  // The linear step's projection matrix (pixels, world units), scaled to unit Frobenius norm
  // with det of its left 3x3 > 0; for the planar path K [R | t] of the first camera.
  Eigen::Matrix<double, 3, 4> P = Eigen::Matrix<double, 3, 4>::Zero();
  // Unconstrained intrinsics of the linear step (RQ of P): K = [[fx, skew, cx], [0, fy, cy], ...].
  double fx = 0.0, fy = 0.0, skew = 0.0;
  Eigen::Vector2d linear_principal_point_px = Eigen::Vector2d::Zero();
  double initial_rms_px = 0.0;       // reprojection RMS of the linear camera (pinhole)
  double reprojection_rms_px = 0.0;  // of the final camera (with distortion when estimated)
  std::vector<double> residuals_px;  // per input point (same order): final reprojection error
  // One-sigma uncertainties from the refinement's covariance (J^T J)^-1 scaled by the
  // residual variance per coordinate; zero without refinement, or for a fixed parameter.
  double focal_std_px = 0.0;
  Eigen::Vector2d principal_point_std_px = Eigen::Vector2d::Zero();
  double k1_std = 0.0;
};

DltCalibrationSummary CalibrateFromPoints(const std::vector<PointCorrespondence>& points,
                                          const DltCalibrationOptions& options);

}  // namespace facet
