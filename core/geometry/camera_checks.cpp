#include "core/geometry/camera_checks.h"

#include <algorithm>
#include <cmath>

#include "core/util/format.h"

namespace facet {
namespace {

std::string Number(double value) { return internal::FormatNumber(value, 6); }

}  // namespace

std::string WhyNotACamera(double focal_px, const Eigen::Vector2d& principal_point_px, int width_px, int height_px) {
  if (!std::isfinite(focal_px) || !(focal_px > 0.0))
    return "the focal length is not a positive number (f = " + Number(focal_px) + " px)";
  if (!principal_point_px.allFinite()) return "the principal point is not finite";
  if (width_px <= 0 || height_px <= 0) return "the photo has no size";
  const double diagonal = std::hypot(static_cast<double>(width_px), static_cast<double>(height_px));
  const double ratio = focal_px / diagonal;
  if (ratio < kMinFocalPerDiagonal || ratio > kMaxFocalPerDiagonal)
    return "f = " + Number(focal_px) + " px is " + Number(ratio) + " image diagonals, outside any lens (" +
           Number(kMinFocalPerDiagonal) + " to " + Number(kMaxFocalPerDiagonal) + ")";
  const Eigen::Vector2d center(0.5 * (width_px - 1), 0.5 * (height_px - 1));
  const double offset = (principal_point_px - center).norm() / diagonal;
  if (offset > kMaxPrincipalPointOffsetPerDiagonal)
    return "the principal point (" + Number(principal_point_px.x()) + ", " + Number(principal_point_px.y()) +
           ") px is " + Number(offset) + " image diagonals from the centre (at most " +
           Number(kMaxPrincipalPointOffsetPerDiagonal) + ")";
  return {};
}

std::string WhyNotAFocalLength(double focal_px, int width_px, int height_px) {
  const Eigen::Vector2d center(0.5 * (width_px - 1), 0.5 * (height_px - 1));
  return WhyNotACamera(focal_px, center, width_px, height_px);
}

std::string WhyNotAFocalPrior(double prior_px, double prior_std_px, int width_px, int height_px) {
  const std::string focal = WhyNotAFocalLength(prior_px, width_px, height_px);
  if (!focal.empty()) return "the prior's value: " + focal;
  if (!std::isfinite(prior_std_px) || !(prior_std_px > 0.0))
    return "the prior's standard deviation is not a positive number (" + Number(prior_std_px) + " px)";
  if (prior_std_px < kMinFocalPriorRelativeStd * prior_px)
    return "the prior's standard deviation " + Number(prior_std_px) + " px is below " +
           Number(kMinFocalPriorRelativeStd) + " of its value " + Number(prior_px) +
           " px: give the focal length as known (fixed) instead";
  return {};
}

std::string WhyNotALineOnPhoto(const Eigen::Vector4d& points_px, int width_px, int height_px) {
  if (!points_px.allFinite()) return "its points are not finite";
  if (width_px <= 0 || height_px <= 0) return "the photo has no size";
  const Eigen::Vector2d a = points_px.head<2>(), b = points_px.tail<2>();
  if (a == b) return "its two points are the same";
  const double diagonal = std::hypot(static_cast<double>(width_px), static_cast<double>(height_px));
  const Eigen::Vector2d center(0.5 * (width_px - 1), 0.5 * (height_px - 1));
  const double offset = std::max((a - center).norm(), (b - center).norm()) / diagonal;
  if (!(offset <= kMaxHorizonOffsetPerDiagonal))
    return "a point is " + Number(offset) + " image diagonals from the photo's centre (at most " +
           Number(kMaxHorizonOffsetPerDiagonal) + ")";
  return {};
}

std::string WhyDistortionFolds(double k1, double k2, double focal_px, const Eigen::Vector2d& principal_point_px,
                               int width_px, int height_px) {
  if (k1 == 0.0 && k2 == 0.0) return {};
  if (!std::isfinite(k1) || !std::isfinite(k2)) return "the distortion is not finite";
  if (!(focal_px > 0.0) || !std::isfinite(focal_px)) return {};  // WhyNotACamera names that
  double corner = 0.0;
  for (const double u : {0.0, static_cast<double>(width_px)})
    for (const double v : {0.0, static_cast<double>(height_px)})
      corner = std::max(corner, (Eigen::Vector2d(u, v) - principal_point_px).norm() / focal_px);
  // d(r_d)/dr = 1 + 3 k1 s + 5 k2 s^2 with s = r^2: its first positive root is the peak.
  double peak_s = -1.0;
  if (k2 == 0.0) {
    if (k1 < 0.0) peak_s = -1.0 / (3.0 * k1);
  } else {
    const double disc = 9.0 * k1 * k1 - 20.0 * k2;
    if (disc >= 0.0) {
      const double q = std::sqrt(disc);
      for (const double root : {(-3.0 * k1 - q) / (10.0 * k2), (-3.0 * k1 + q) / (10.0 * k2)})
        if (root > 0.0 && (peak_s < 0.0 || root < peak_s)) peak_s = root;
    }
  }
  if (peak_s < 0.0) return {};
  const double peak_r = std::sqrt(peak_s);
  const double peak_distorted = peak_r * (1.0 + k1 * peak_s + k2 * peak_s * peak_s);
  if (peak_distorted >= corner) return {};
  return "the distortion k1 = " + Number(k1) + ", k2 = " + Number(k2) + " folds the photo: it bends rays back at " +
         Number(peak_distorted) + " of the focal length from the principal point, inside the farthest corner at " +
         Number(corner) + " (no lens does that)";
}

std::string WhyFocalIsUndetermined(double focal_px, double focal_std_px) {
  if (!std::isfinite(focal_std_px) || !(focal_std_px > 0.0) || !(focal_px > 0.0)) return {};
  if (focal_std_px <= kMaxFocalRelativeStd * focal_px) return {};
  return "the focal length is not determined by the data: f = " + Number(focal_px) + " +- " + Number(focal_std_px) +
         " px (a standard deviation over " + Number(100.0 * kMaxFocalRelativeStd) + " % of f)";
}

std::string WhyNotACalibrationMatrix(const Eigen::Matrix3d& k) {
  if (!k.allFinite()) return "K has a non-finite entry";
  if (k(1, 0) != 0.0 || k(2, 0) != 0.0 || k(2, 1) != 0.0) return "K is not upper triangular";
  if (!(k(2, 2) > 0.0)) return "K(2,2) must be positive, got " + Number(k(2, 2));
  if (!(k(0, 0) > 0.0) || !(k(1, 1) > 0.0))
    return "K's focal lengths must be positive, got " + Number(k(0, 0)) + " and " + Number(k(1, 1));
  return {};
}

}  // namespace facet
