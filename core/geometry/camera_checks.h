// What Facet accepts as a camera: one definition for the estimators, the solves and the
// command line. A result that fails it is a failure (its summary is not IsUsable(), the CLI
// exits 1, the app shows the message as an error), never printed as an answer.
#pragma once

#include <string>

#include <Eigen/Core>

namespace facet {

// Bounds on the focal length f, in image diagonals d: f / d times 43.3 mm is the lens on a
// full-frame camera, so 0.02 d is a 0.9 mm lens and 100 d a 4.3 m one, beyond any pinhole
// photo (fisheyes are not pinhole cameras).
inline constexpr double kMinFocalPerDiagonal = 0.02;
inline constexpr double kMaxFocalPerDiagonal = 100.0;
// Cropping moves the principal point off the image, but not this many diagonals from its centre.
inline constexpr double kMaxPrincipalPointOffsetPerDiagonal = 10.0;
// An estimated focal length whose standard deviation exceeds this fraction of it is not
// determined by the data (the York Urban photos with the weakest lines reach ~0.2).
inline constexpr double kMaxFocalRelativeStd = 0.5;

// Empty when a focal length and principal point (px) make a camera for a width x height
// photo; else one sentence saying why not, with the numbers and the bound.
std::string WhyNotACamera(double focal_px, const Eigen::Vector2d& principal_point_px, int width_px, int height_px);

// Empty unless an estimated focal length's standard deviation (0 or NaN: not estimated, no
// check) says the data leave it undetermined; then one sentence with both numbers.
std::string WhyFocalIsUndetermined(double focal_px, double focal_std_px);

// Empty when the radial distortion (k1, k2 on the normalised radius r, core/geometry/camera.h)
// maps the photo one to one; else one sentence with the numbers. The distorted radius
// r (1 + k1 r^2 + k2 r^4) must keep growing until it reaches the photo's farthest corner
// (from the principal point, over f): past its peak, points fold back onto nearer pixels and
// the corners are images of no ray, which no lens does (k1 = 0.32, k2 = -3.0 at f = 892 px
// on a 1024 x 768 photo peaks at 0.45 of the corner's 0.72).
std::string WhyDistortionFolds(double k1, double k2, double focal_px, const Eigen::Vector2d& principal_point_px,
                               int width_px, int height_px);

// Empty when K, given by the user with no photo size, is a calibration matrix: finite, upper
// triangular, positive focal lengths and K(2,2); else why not.
std::string WhyNotACalibrationMatrix(const Eigen::Matrix3d& k);

}  // namespace facet
