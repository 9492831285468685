// Cameras for images that have pins but no line families: each such image is calibrated from
// its pins alone, by resection against the model, from two views, or by self-calibration of
// three or more views, so that a second photo takes part in the solve without drawing lines.
//
// Input: a Project (core/scene/project.h). "Calibrated" means Image::camera_calibrated at input
// (usually by vanishing points, core/estimators/calibrate_vp.h). A pin's vertex is "known" when it is
// pinned in a calibrated image: the current model places it (VertexInWorld, world units).
// Pixels follow core/geometry/conventions.h; cameras are cam_from_world with square pixels, zero skew.
//
// Paths, tried per uncalibrated image with pins, in this order:
// (a) Resection: 6 or more pins on known vertices (or 4 or more on one plane) calibrate the
//     image by DLT and Levenberg-Marquardt (core/estimators/calibrate_dlt.h): focal length, principal
//     point (per Image::principal_point_mode; held at the centre on the planar path), R, t in
//     the model's world frame. A pin whose reprojection error stays above
//     wrong_click_threshold_px is dropped and the camera refitted (one at a time, worst first,
//     while enough points remain); dropped pins are reported as wrong clicks. An image with a
//     known focal length (FocalMode::kFixed, fixed_focal_px > 0) keeps it exactly: resection
//     then solves only its pose (and the principal point its mode leaves free), a calibrated
//     PnP; with FocalMode::kPrior the focal length is refined under that Gaussian prior (weighed
//     with resection_pixel_noise_px). focal_px_by_image (EXIF) is not used here: resection
//     measures f, an EXIF value is only as good as the prior it would be. Where the pins
//     cannot fix f (the DLT or the plane fails, e.g. "no positive focal length", or gives a
//     focal length no lens has, refused by name by WhyNotACamera: f = 63,038 px was once
//     kept), core/solve/pin_resection.h takes over (issue 26): pins nearly on one plane
//     (thickness <= coplanar_thickness_ratio, e.g. 4 pins spread over two boxes whose solved
//     faces are not exactly coplanar) by the homography on their common plane refined on the
//     true points; then, with a focal length known from a calibrated image of the same lens
//     group (Image::lens_group), else focal_px_by_image (EXIF), else the image's fixed focal
//     length or prior, the pose alone from 4 or more pins, planar or not.
// (b) Two views: the images not resected, when exactly two are left; then each image still
//     uncalibrated (after (b) or (c), or alone) with the calibrated image, at input or
//     initialised here, it shares the most pinned vertices with. Correspondences are the
//     vertices pinned in both; 7 or more give F (core/estimators/two_view.h, RANSAC flags wrong
//     clicks). When the model places the shared vertices on one plane (thickness at most
//     coplanar_thickness_ratio of their extent: every pin on one face, where F is not unique),
//     4 or more give the plane's homography instead (core/estimators/homography_pose.h; RANSAC flags wrong
//     clicks from 6) and its decomposition; of the poses that pass cheirality (often two), the
//     one whose triangulated vertices best fit the model's positions (a similarity) is taken,
//     with a warning naming the misfits (two_view_plane is set in the report). The intrinsics
//     (a calibrated image's own; else focal_px_by_image, e.g. EXIF; else the image's
//     fixed_focal_px (FocalMode::kFixed) or focal_prior_px (kPrior); else
//     default_focal_factor x the larger image side; principal point at the centre unless
//     kFixed) give E (or decompose H) and the relative pose with the cheirality check. The
//     baseline is fixed as in "Gauge" below. Residual: the symmetric epipolar RMS of the pose.
// (c) Self-calibration: three or more images left are self-calibrated together
//     (core/estimators/self_calibration.h) from the tracks of their pinned vertices, with the known
//     focal lengths of (b) (not the guess) as single-image priors. When it initialises none
//     of them, the two that share the most vertices take (b), and the others pair with
//     calibrated images as above.
//
// Gauge (two views and self-calibration fix the reconstruction only up to a similarity):
// - (b) with a calibrated partner: that camera stays where it is, the other is placed
//   relative to it, and the baseline is scaled so that the triangulated vertices' RMS spread
//   about their centroid equals that of the model's positions for the same vertices.
// - Otherwise, MultiViewGauge::kAlignToModel (default): the similarity that best maps the
//   triangulated vertices onto the model's positions of the same vertices (Umeyama), so the
//   cameras face the model as it stands and the geometry solve starts close; it needs 3 or
//   more such vertices not on one line. kKeepFirstCamera, or when alignment is not possible:
//   the first image (project order) keeps its current pose, the scale is the spread ratio
//   above (1 when the model has no spread).
// The geometry solve (core/solve/scene_solve.h) then moves camera centres and the model together.
//
// When to call: after the geometry solve of the calibrated images. Resection and the gauge
// read the model's cached vertex positions, which are right only once solved; on a stale
// model resection fits a wrong camera (and may flag good pins as wrong clicks).
//
// Distortion: pins of a calibrated image are undistorted with its camera (Camera::k1, k2);
// an uncalibrated image is taken as a pinhole, and its initialised camera has k1 = k2 = 0.
//
// Degenerate input (too few pins, collinear or coincident pins, a failed F or pose) leaves
// that image uncalibrated with a message naming the count needed. *out is always a copy of
// the project in which only successfully initialised images changed (camera, width/height,
// camera_calibrated = true); locks (focal_locked, pose_locked) are never changed.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/estimators/homography_pose.h"
#include "core/estimators/self_calibration.h"
#include "core/estimators/two_view.h"
#include "core/geometry/camera.h"
#include "core/optim/solver_summary.h"
#include "core/scene/project.h"

namespace facet {

enum class MultiViewGauge { kAlignToModel, kKeepFirstCamera };

struct MultiViewInitOptions {
  // Resection (a).
  int max_resection_iterations = 100;
  // The clicks' assumed standard deviation (px): weighs an image's focal prior (kPrior)
  // against the reprojection residuals in resection.
  double resection_pixel_noise_px = 1.0;
  // A resection pin farther than this from its reprojection is a wrong click (also the
  // F RANSAC inlier threshold of (b) and the self-calibration's).
  double wrong_click_threshold_px = 3.0;
  // Focal length in px of uncalibrated images (the EXIF value, core/image/exif.h), by image id; it
  // takes precedence over the image's own focal mode.
  std::map<Id, double> focal_px_by_image;
  // Otherwise the two-view guess: this factor times the larger image side (a normal lens).
  double default_focal_factor = 1.2;
  MultiViewGauge gauge = MultiViewGauge::kAlignToModel;
  // Two views (b): the F estimation (its inlier threshold is set from wrong_click_threshold_px)
  // and the relative pose.
  FundamentalOptions fundamental;
  RelativePoseOptions relative_pose;
  // Two views of one plane (b): the shared vertices' model positions count as one plane when
  // their thickness is at most this fraction of their extent; then the homography (its inlier
  // threshold set from wrong_click_threshold_px) replaces F.
  double coplanar_thickness_ratio = 0.02;
  HomographyOptions homography;
  // Self-calibration (c) (its inlier threshold is set from wrong_click_threshold_px).
  SelfCalibrationOptions self_calibration;

  bool Check(std::string* error) const;
};

enum class MultiViewInitPath {
  kNone,               // not initialised (see the message), or no pins
  kAlreadyCalibrated,  // left as it was
  kResection,
  kTwoView,
  kSelfCalibration,
};
const char* MultiViewInitPathName(MultiViewInitPath path);  // "none", "calibrated", "resection", ...

// One image's outcome.
struct MultiViewImageReport {
  Id image_id = kNoId;
  std::string image_path;
  MultiViewInitPath path = MultiViewInitPath::kNone;
  bool initialized = false;     // its camera was set by this call
  int num_pins = 0;             // pins on existing vertices with finite pixels
  int num_known_pins = 0;       // of those, on vertices pinned in a calibrated image
  Id partner_image_id = kNoId;  // two views: the other image
  // Resection and self-calibration: reprojection RMS (px) over the pins used; two views: the
  // symmetric epipolar RMS (core/estimators/two_view.h) of the final relative pose.
  double residual_px = 0.0;
  double focal_px = 0.0;  // of the initialised camera
  // One-sigma focal uncertainty (px): resection from the DLT refinement, self-calibration from
  // its bundle adjustment; 0 for two views (the focal length is given or guessed there).
  double focal_std_px = 0.0;
  bool focal_guessed = false;    // two views: default_focal_factor; self-calibration: no prior
  bool two_view_plane = false;   // two views through the plane's homography (shared vertices on one face)
  std::vector<Id> flagged_pins;  // wrong clicks in this image, by pin id
  std::string message;           // one line: what was done, or why nothing could be
  std::vector<std::string> warnings;
};

// F of an initialised pair (two views), for epipolar display: uv_b^T F uv_a = 0.
struct MultiViewPairGeometry {
  Id image_a = kNoId;
  Id image_b = kNoId;
  Eigen::Matrix3d F = Eigen::Matrix3d::Zero();
  int num_correspondences = 0;
  int num_inliers = 0;
};

// SolverSummary's shape (core/optim/solver_summary.h) for a driver of several estimators:
// termination kConverged when the call ran (options valid; per-image results in `images`,
// which may all be "not initialised"), kInvalidInput otherwise; message: invalid options, or a
// one-line account. iterations and the costs are not used (each image's estimator reports
// its own in `images`).
struct MultiViewInitSummary : SolverSummary {
  std::vector<MultiViewImageReport> images;  // one per project image, project order
  std::vector<MultiViewPairGeometry> pairs;
  // User-facing lines for images that have pins but could not be initialised, e.g.
  // "image 'b.jpg': 4 pins on known vertices; resection needs 6, or 4 on one face".
  std::vector<std::string> messages;
  int num_initialized = 0;

  const MultiViewImageReport* Find(Id image_id) const;
};

// Leaves calibrated images alone; initialises each uncalibrated image with pins by the paths
// above. *out receives a copy of `project` with the initialised cameras (out may not alias
// project).
MultiViewInitSummary CalibrateImagesFromPins(const Project& project, const MultiViewInitOptions& options, Project* out);

// Epipolar geometry for teaching display.

// F with uv_b^T F uv_a = 0 from two cameras (image a's pixel to its line in image b):
// K_b^-T [t]x R K_a^-1 with R = R_b R_a^T, t = t_b - R t_a. Zero when the centres coincide.
Eigen::Matrix3d FundamentalFromCameras(const Camera& camera_a, const Camera& camera_b);

struct EpipolarLine {
  // l with l . (u, v, 1) = 0 for the pixels of the line in image b, scaled so that (l0, l1)
  // has unit norm (l . (u, v, 1) is then a signed distance in px). Zero when undefined (uv_a
  // is the epipole, or F is zero).
  Eigen::Vector3d line = Eigen::Vector3d::Zero();
  // The part of the line inside image b's rectangle [-0.5, w - 0.5] x [-0.5, h - 0.5]
  // (pixel edges, core/geometry/conventions.h); nullopt when the line misses it or is undefined.
  std::optional<std::pair<Eigen::Vector2d, Eigen::Vector2d>> segment_px;
};

// The epipoles of two cameras (pinhole part): in image a the image of b's centre, P_a (C_b, 1),
// in image b that of a's, homogeneous and unit norm (third coordinate 0: at infinity; negative:
// the other centre is behind the camera). F e_a = 0 and F^T e_b = 0 for
// F = FundamentalFromCameras(a, b): every epipolar line of image b passes through e_b.
// Zero when the centres coincide.
struct EpipolePair {
  Eigen::Vector3d in_a = Eigen::Vector3d::Zero();
  Eigen::Vector3d in_b = Eigen::Vector3d::Zero();
};
EpipolePair EpipolesOfCameras(const Camera& camera_a, const Camera& camera_b);

// The epipolar line in image b (width_b_px x height_b_px) of pixel uv_a_px of image a.
EpipolarLine EpipolarLineInImage(const Eigen::Matrix3d& F, const Eigen::Vector2d& uv_a_px, int width_b_px,
                                 int height_b_px);

}  // namespace facet
