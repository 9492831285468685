// Self-calibration of 3 or more uncalibrated views from point tracks: a projective
// reconstruction, the absolute dual quadric under zero skew, square pixels and a principal
// point near the image centre (started from single-image intrinsics when known), then a metric
// bundle adjustment of focal lengths, poses and points.
//
// Conventions (core/geometry/conventions.h): pixels uv_px in the OpenCV convention; cameras
// cam_from_world, K = [[f, 0, cx], [0, f, cy], [0, 0, 1]] (square pixels, zero skew). The
// result is a Euclidean frame up to a global similarity, fixed here so that camera 0 of the
// initial pair is at the origin with R = I and the points' RMS distance from their centroid
// is 1.
//
// Steps:
// 1. Projective reconstruction, in image coordinates normalised by N_i (the prior K_i when
//    given, else f = w + h at the image centre), grown view by view: F of the pair of views
//    sharing the most tracks that a homography does not explain (core/estimators/two_view.h, RANSAC;
//    a pair taken from one centre fixes nothing), canonical cameras, triangulation; every
//    further view, the one seeing the most reconstructed points first, is resected by DLT on
//    the triangulated tracks it sees (points whitened, MSAC over 6-point samples, then refitted
//    on the inliers), new tracks are triangulated, and a projective bundle adjustment runs
//    each time projective_bundle_every_views views have joined. When views remain out (views
//    linked to the rest only by two-view tracks cannot be resected), starts from pairs of the
//    views left out are tried too and the attempt registering the most views is kept. The
//    frame is then normalised (points centred, unit RMS) for conditioning.
// 2. The absolute dual quadric Q (4x4 symmetric, rank 3): with w*_i = P_i Q P_i^T in the
//    normalised coordinates, the linear equations of Pollefeys et al. (IJCV 2004, "Visual
//    modeling with a hand-held camera", 5.3): w*_12 = 0 (zero skew), w*_11 = w*_22 (square
//    pixels), w*_13 = w*_23 = 0 (principal point at the normalisation's centre), and weakly
//    w*_11 = w*_33, w*_22 = w*_33 (focal length near the normalisation's), each weighted by
//    its option and by 1 / w*_33 of the previous round (iteratively reweighted). Rank 3 is
//    enforced by zeroing the eigenvalue of smallest magnitude; the rectifying homography H
//    (Q = H diag(1, 1, 1, 0) H^T) upgrades the cameras, which RQ splits into K, R, t.
// 3. Bundle adjustment (Levenberg-Marquardt on the reprojection error in px) of per-view
//    rotations and translations, the points, one shared focal length or one per view, and
//    optionally a principal point (under a weak prior at the image centre by default). The
//    normal equations are reduced to the camera block by the Schur complement over the 3x3
//    point blocks (core/optim/schur_step.h); the camera block is solved densely (fine for the
//    few tens of views a user clicks in, any number of points). Between rounds the inliers
//    are decided again on the adjusted cameras: observations flagged in the rough early
//    stages come back when they fit.
//
// Degenerate input (fewer than 3 views with tracks, too few tracks, no pair with a usable F,
// fewer than 3 views registered) gives an unusable summary with a message; views that cannot be
// resected are left out when at least 3 remain, flagged in `registered` and named in a
// warning with the number of reconstructed points they see.
// Critical motions (pure translation, rotation about the optical axes, all optical axes
// through one point with varying focal lengths) leave the focal length undetermined: the
// summary reports its standard deviation from the bundle adjustment's covariance.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/estimators/projective_upgrade.h"
#include "core/geometry/camera.h"
#include "core/geometry/intrinsics_modes.h"
#include "core/optim/solver_summary.h"

namespace facet {

struct TrackObservation {
  int view = 0;
  Eigen::Vector2d uv_px = Eigen::Vector2d::Zero();
};

// One scene point's pixels, at most one per view.
using Track = std::vector<TrackObservation>;

struct SelfCalibrationView {
  int width_px = 0;
  int height_px = 0;
  // Single-image focal length (e.g. from vanishing points or EXIF); 0 when unknown.
  double focal_prior_px = 0.0;
};

struct SelfCalibrationOptions {
  // One focal length for all views (one camera, fixed zoom) or one per view.
  bool shared_focal_length = true;
  // kImageCenter: held at each image's centre; kSolve: one principal point shared by all
  // views (shared_focal_length) or one per view, estimated in the bundle adjustment; kFixed:
  // fixed_principal_point_px for every view.
  PrincipalPointMode principal_point_mode = PrincipalPointMode::kImageCenter;
  Eigen::Vector2d fixed_principal_point_px = Eigen::Vector2d::Zero();
  // kSolve: a Gaussian prior of the principal point at the image centre, its standard
  // deviation as a fraction of the image's larger side (0: none, the unbiased solve). Views
  // that turn about nearly one axis leave the principal point and the focal length coupled
  // and weakly determined (on a 115-degree arc of the Middlebury ring the free principal
  // point drifts 240 px); real lenses keep it within a few percent of the centre.
  double principal_point_prior_std = 0.025;
  // Weights of the linear absolute-dual-quadric equations (normalised coordinates; Pollefeys
  // et al. use 1 / 0.01, 1 / 0.2, 1 / 0.1 and 1 / 9 for a focal length known within a factor
  // of 3). With a focal prior in every view its weight is raised to prior_focal_weight.
  double skew_weight = 100.0;
  double aspect_weight = 5.0;
  double principal_point_weight = 10.0;
  double focal_weight = 1.0 / 9.0;
  double prior_focal_weight = 1.0;
  int quadric_reweighting_rounds = 3;
  // A projective bundle adjustment of all registered views before the quadric
  // (core/estimators/projective_bundle_adjustment.h).
  bool projective_bundle_adjust = true;
  int max_projective_bundle_iterations = 50;
  // During the incremental registration, a projective bundle adjustment each time this many
  // views have been resected (0: only the final one). On the Middlebury ring it halves the
  // largest rotation error of 13 views (5.7 to 2.8 degrees).
  int projective_bundle_every_views = 3;
  // Observations farther than this from their reprojection are dropped (resection, after the
  // linear upgrade and between bundle adjustment rounds).
  double inlier_threshold_px = 3.0;
  bool bundle_adjust = true;
  int max_bundle_iterations = 100;
  int bundle_rounds = 2;  // bundle adjustment, drop outliers, again
  unsigned seed = 1;      // RANSAC of the initial pair

  bool Check(std::string* error) const;
};

// iterations: of the metric bundle adjustment, over its rounds; initial_cost / final_cost: the
// sum of squared reprojection errors (px^2) of the metric cameras right after the linear
// upgrade and at the end.
struct SelfCalibrationSummary : SolverSummary {
  std::vector<Camera> cameras;                   // per view; meaningful where registered
  std::vector<bool> registered;                  // per view
  std::vector<Eigen::Vector3d> points;           // per track, world
  std::vector<bool> triangulated;                // per track: reconstructed and kept
  int initial_view_a = -1, initial_view_b = -1;  // the pair of step 1
  // Focal lengths from the linear absolute dual quadric (per view; before the adjustment).
  std::vector<double> linear_focal_px;
  // One-sigma focal length uncertainty (px) from the adjustment's covariance, per view.
  std::vector<double> focal_std_px;
  Eigen::Matrix4d metric_from_projective = Eigen::Matrix4d::Identity();  // the rectifying H^-1 (normalised frame)
  double projective_rms_px = 0.0;    // reprojection RMS of the projective reconstruction
  double linear_rms_px = 0.0;        // of the metric cameras right after the upgrade
  double reprojection_rms_px = 0.0;  // final
  int num_observations = 0;          // used in the final adjustment
};

SelfCalibrationSummary SelfCalibrate(const std::vector<SelfCalibrationView>& views, const std::vector<Track>& tracks,
                                     const SelfCalibrationOptions& options);

// The metric bundle adjustment of step 3 on its own, for a known start.
struct BundleAdjustmentOptions {
  bool shared_focal_length = true;
  bool refine_principal_point = false;  // shared as the focal length is
  // A Gaussian prior on a refined principal point, centred on the image centre
  // ((width_px - 1) / 2, (height_px - 1) / 2; of camera 0 when shared), with this standard
  // deviation (px; 0: none). It enters the cost in the units of the pixel residuals,
  // weighted by (observation_std_px / principal_point_prior_std_px)^2, so observation_std_px
  // is the pixel noise the residuals are assumed to have.
  double principal_point_prior_std_px = 0.0;
  double observation_std_px = 1.0;
  int max_iterations = 100;

  bool Check(std::string* error) const;
};

struct BundleObservation {
  int view = 0;
  int point = 0;
  Eigen::Vector2d uv_px = Eigen::Vector2d::Zero();
};

// initial_cost / final_cost: the minimised sum of squared reprojection errors (px^2) plus the
// principal-point prior's term.
struct BundleAdjustmentSummary : SolverSummary {
  double initial_rms_px = 0.0;  // reprojection RMS, without the prior
  double final_rms_px = 0.0;
  std::vector<double> focal_std_px;  // per camera
};

// Adjusts cameras and points in place to minimise the squared reprojection error of the
// observations (every view and point index in range). A shared focal length or principal
// point starts from camera 0's.
BundleAdjustmentSummary BundleAdjust(const std::vector<BundleObservation>& observations,
                                     const BundleAdjustmentOptions& options, std::vector<Camera>* cameras,
                                     std::vector<Eigen::Vector3d>* points);

}  // namespace facet
