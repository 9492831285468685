// Resection paths for a photo's pins on vertices the model places (issue 26: later cameras
// from pins), beyond the DLT and the exact-plane homography of core/estimators/calibrate_dlt.h:
// - nearly planar pins (4 or 5 on a common plane spread over several boxes, whose solved
//   model puts them a little off one plane): the homography of the points projected onto
//   their best plane gives the start (Zhang's focal length, the principal point held), then
//   f, R, t are refined on the true points, so a noise-free scene is recovered exactly;
// - a known focal length (a shared lens, EXIF, the image's fixed focal or prior), planar or
//   not, 4 or more pins: the pose alone. Start: the depths along the pins' rays that best
//   keep the model's distances between the points (Gauss-Newton from equal depths), then the
//   rigid alignment of the rays' points onto the model's (Umeyama); refined on the pixels.
// Every result is checked as a camera (core/geometry/camera_checks.h: focal length within
// kMinFocalPerDiagonal..kMaxFocalPerDiagonal image diagonals, points in front) and refused by
// name otherwise.
//
// Units: points in world units, pixels in the OpenCV convention (core/geometry/conventions.h),
// the camera a pinhole (k1 = k2 = 0), square pixels, zero skew.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/geometry/camera.h"

namespace facet {

struct PinResectionInput {
  std::vector<Eigen::Vector3d> points;  // the pinned vertices in world, as the model places them
  std::vector<Eigen::Vector2d> pixels;  // the pins, same order
  int width_px = 0;
  int height_px = 0;
  Eigen::Vector2d principal_point_px = Eigen::Vector2d::Zero();  // held
  int max_iterations = 100;
};

struct PinResectionResult {
  bool ok = false;
  std::string message;  // why not, or what was done in one line
  Camera camera;
  double rms_px = 0.0;
  std::vector<double> residuals_px;  // per point
};

// Thickness of the points (smallest singular value of the centred points over the largest),
// 0 for fewer than 3 points.
double PointsThicknessRatio(const std::vector<Eigen::Vector3d>& points);

// Why the pins cannot fix a camera however it is solved: fewer than 4, or their pixels or
// their points (nearly) on one line; "" when they are well spread.
std::string WhyPinsNotSpread(const PinResectionInput& input);

// Focal length, R and t from nearly planar points (4 or more; see the header).
PinResectionResult ResectNearlyPlanar(const PinResectionInput& input);

// R and t with the focal length held at focal_px (4 or more points, planar or not).
PinResectionResult ResectWithKnownFocal(const PinResectionInput& input, double focal_px);

// "" when `camera` is a camera for the photo (WhyNotACamera) with every point in front of it;
// else one sentence with the numbers.
std::string WhyResectedCameraRefused(const Camera& camera, const std::vector<Eigen::Vector3d>& points, int width_px,
                                     int height_px);

}  // namespace facet
