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
// Radial distortion coefficients (k1, k2 on the normalised radius) of any lens are within a
// few units (a fisheye's k1 ~ -0.5 at r = 1); 100 leaves room for long lenses, whose small
// radii make k large, and refuses numbers that overflow the projection (k1 = 1e308).
inline constexpr double kMaxDistortionCoefficient = 100.0;
// A focal prior's standard deviation below this fraction of its value is a fixed focal length
// in disguise whose weight (pixel noise / std) swamps every other residual: give it as fixed.
inline constexpr double kMinFocalPriorRelativeStd = 1e-6;
// A horizon (or any line the user gives on the photo) this many image diagonals from the
// photo's centre is the image of a camera looking within ~0.005 deg of straight up or down
// at the longest lens (f = 100 d): further, it carries no information, only overflow.
inline constexpr double kMaxHorizonOffsetPerDiagonal = 1e4;

// Empty when a focal length and principal point (px) make a camera for a width x height
// photo; else one sentence saying why not, with the numbers and the bound.
std::string WhyNotACamera(double focal_px, const Eigen::Vector2d& principal_point_px, int width_px, int height_px);

// Empty when a known focal length (px) is a lens for a width x height photo (the range of
// WhyNotACamera); else one sentence with the number and the bound. For values given by the
// user (a fixed focal length, a prior's value) before anything is computed with them.
std::string WhyNotAFocalLength(double focal_px, int width_px, int height_px);

// Empty when a Gaussian focal prior (value and standard deviation, px) can weigh a
// calibration of a width x height photo: its value a focal length as above, its std finite,
// positive and at least kMinFocalPriorRelativeStd of the value; else one sentence.
std::string WhyNotAFocalPrior(double prior_px, double prior_std_px, int width_px, int height_px);

// Empty when a line given by two points (x1, y1, x2, y2, px) on a width x height photo is
// usable: finite, two distinct points, within kMaxHorizonOffsetPerDiagonal diagonals of the
// centre; else one sentence.
std::string WhyNotALineOnPhoto(const Eigen::Vector4d& points_px, int width_px, int height_px);

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
