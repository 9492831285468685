// How the texture bake mixes the photos that see a texel: exposure gains fitted where photos
// overlap, and the weight of one view at one texel.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Core>

namespace facet {

// What two views saw of the same surface points: `count` points (texels) both see, and the
// sums of the colours (RGB, grey levels 0-255) each view sampled there.
struct ExposureOverlap {
  int view_a = 0;
  int view_b = 0;
  double count = 0.0;
  Eigen::Vector3d sum_a = Eigen::Vector3d::Zero();
  Eigen::Vector3d sum_b = Eigen::Vector3d::Zero();
};

// Per-view, per-channel gains g that level the photos' exposures (Brown and Lowe, "Automatic
// panoramic image stitching using invariant features", IJCV 2007, section 6): per channel,
// minimises sum over overlaps of count * (g_a mean_a - g_b mean_b)^2 / sigma_n^2 plus, per view,
// (its overlap count) * (1 - g)^2 / sigma_g^2, with sigma_n = 1 grey level (means over many
// texels are precise) and sigma_g = 0.5 (the prior only fixes the overall level: the levelled
// photos meet near their mean exposure). A view without overlaps keeps gain 1. Gains are
// clamped to [0.25, 4]. Returns view_count gains.
std::vector<Eigen::Vector3d> FitExposureGains(int view_count, const std::vector<ExposureOverlap>& overlaps);

// Feather: 0 on a view's visibility boundary, rising smoothly (smoothstep) to 1 at
// feather_px photo pixels from it; 1 everywhere when feather_px <= 0.
// (Inline, as ViewQuality: the bake weighs every view at every texel.)
inline double FeatherWeight(double boundary_distance_px, double feather_px) {
  if (!(feather_px > 0.0)) return 1.0;
  const double t = std::clamp(boundary_distance_px / feather_px, 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

// A view's preference at a texel before feathering: (resolution * frontality)^sharpness *
// centrality, where resolution = (focal_px / distance)^2 (photo pixels per square metre of a
// frontal surface), frontality = cos(angle between the face normal and the ray to the camera),
// and centrality = 1 - 0.5 (r / r_corner)^2 for the sample's distance r from the photo's
// centre (half weight in a corner, where lenses are softest). 0 when cos_angle <= 0.
inline double ViewQuality(double cos_angle, double focal_px, double distance, double radius_fraction,
                          double sharpness) {
  if (!(cos_angle > 0.0) || !(distance > 0.0)) return 0.0;
  const double resolution = (focal_px / distance) * (focal_px / distance);
  const double r = std::min(radius_fraction, 1.0);
  const double base = resolution * cos_angle;
  const double preference = sharpness == 2.0 ? base * base : std::pow(base, sharpness);
  return preference * (1.0 - 0.5 * r * r);
}

}  // namespace facet
