// The vanishing point's covariance (core/estimators/vanishing_point.h), which teach mode draws
// as the point's uncertainty ellipse: over many noisy draws of one family it matches the
// spread of the fitted points, and the calibration passes each family's free fit through.
#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Dense>

#include "core/estimators/calibrate_vp.h"
#include "core/estimators/vanishing_point.h"
#include "tests/synthetic_scene.h"

namespace facet {
namespace {

// Segments of 80-200 px at random places in a 1024 x 768 image, all pointing at vp_px, with
// Gaussian noise of noise_px on each endpoint.
std::vector<Eigen::Vector4d> NoisyFamily(const Eigen::Vector2d& vp_px, int count, double noise_px, std::mt19937* rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::vector<Eigen::Vector4d> out;
  for (int i = 0; i < count; ++i) {
    const double x = 100.0 + 824.0 * unit(*rng);
    const double y = 100.0 + 568.0 * unit(*rng);
    const Eigen::Vector2d a(x, y);
    const double length = 80.0 + 120.0 * unit(*rng);
    const Eigen::Vector2d b = a + length * (vp_px - a).normalized();
    Eigen::Vector4d s(a.x(), a.y(), b.x(), b.y());
    for (int k = 0; k < 4; ++k) {
      const double e = gauss(*rng);
      s(k) += noise_px * e;
    }
    out.push_back(s);
  }
  return out;
}

TEST_CASE("the covariance of a fitted vanishing point matches the spread of the fits") {
  // 1000 draws: the sample covariance's trace is within ~5 % (1 sigma) of its expectation;
  // the first-order covariance of a point 1.5 image widths out is good to a few percent.
  constexpr int kDraws = 1000;
  constexpr double kTraceRatioTolerance = 0.15;
  // Each draw scales its covariance by its own sigma^2 estimate with nu = n - 2 = 6 degrees
  // of freedom, so the squared Mahalanobis distance has mean 2 nu / (nu - 2) = 3, not 2.
  constexpr int kSegments = 8;
  constexpr double kNu = kSegments - 2;
  constexpr double kExpectedMahalanobis = 2.0 * kNu / (kNu - 2.0);
  constexpr double kMahalanobisTolerance = 0.15;
  const Eigen::Vector2d true_vp(1800.0, 250.0);
  VanishingPointOptions options;
  options.conditioning_center_px = Eigen::Vector2d(511.5, 383.5);
  options.conditioning_scale_px = 512.0;
  std::mt19937 rng(21);
  std::vector<Eigen::Vector2d> points;
  Eigen::Matrix2d mean_reported = Eigen::Matrix2d::Zero();
  double mahalanobis = 0.0;
  for (int d = 0; d < kDraws; ++d) {
    const VanishingPointSummary fit = FitVanishingPoint(NoisyFamily(true_vp, kSegments, 0.5, &rng), options);
    REQUIRE(fit.IsUsable());
    REQUIRE(fit.point_covariance_px2.allFinite());
    const Eigen::Vector2d p = fit.vp_px.head<2>() / fit.vp_px.z();
    points.push_back(p);
    mean_reported += fit.point_covariance_px2 / kDraws;
    mahalanobis += (p - true_vp).dot(fit.point_covariance_px2.inverse() * (p - true_vp)) / kDraws;
  }
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& p : points) mean += p / kDraws;
  Eigen::Matrix2d observed = Eigen::Matrix2d::Zero();
  for (const auto& p : points) observed += (p - mean) * (p - mean).transpose() / (kDraws - 1);
  CAPTURE(observed);
  CAPTURE(mean_reported);
  CAPTURE(mahalanobis);
  CHECK(std::abs(mean_reported.trace() / observed.trace() - 1.0) < kTraceRatioTolerance);
  CHECK(std::abs(mahalanobis / kExpectedMahalanobis - 1.0) < kMahalanobisTolerance);
  // The ellipse is elongated along the direction to the image, as the spread is.
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> reported(mean_reported), seen(observed);
  CHECK(std::abs(reported.eigenvectors().col(1).dot(seen.eigenvectors().col(1))) > 0.99);
}

TEST_CASE("no covariance without redundancy: two segments, or a point at infinity in px") {
  VanishingPointOptions options;
  options.conditioning_center_px = Eigen::Vector2d(511.5, 383.5);
  options.conditioning_scale_px = 512.0;
  const std::vector<Eigen::Vector4d> two = {{100, 100, 200, 150}, {100, 400, 200, 380}};
  const VanishingPointSummary fit = FitVanishingPoint(two, options);
  REQUIRE(fit.IsUsable());
  CHECK(std::isnan(fit.point_covariance_px2(0, 0)));
  CHECK(std::isnan(fit.vp_conditioned_covariance(0, 0)));
  const std::vector<Eigen::Vector4d> parallel = {{100, 100, 300, 100}, {100, 200, 300, 200}, {100, 400, 300, 400}};
  const VanishingPointSummary at_infinity = FitVanishingPoint(parallel, options);
  REQUIRE(at_infinity.IsUsable());
  CHECK(std::isnan(at_infinity.point_covariance_px2(0, 0)));
}

TEST_CASE("the calibration reports each family's own fit and its covariance") {
  testing::SyntheticSceneOptions scene_options;
  scene_options.noise_px = 0.5;
  const testing::SyntheticScene scene = testing::MakeBoxScene(scene_options);
  VpCalibrationOptions options;
  options.width_px = scene.true_camera.width_px;
  options.height_px = scene.true_camera.height_px;
  const VpCalibrationSummary calibration = CalibrateFromVanishingLines(scene.project.segments, options);
  REQUIRE(calibration.IsUsable());
  VanishingPointOptions vp_options;
  vp_options.conditioning_center_px = Eigen::Vector2d((options.width_px - 1) / 2.0, (options.height_px - 1) / 2.0);
  vp_options.conditioning_scale_px = std::max(options.width_px, options.height_px) / 2.0;
  for (int a = 0; a < 3; ++a) {
    std::vector<Eigen::Vector4d> family;
    for (const Segment& s : scene.project.segments)
      if (static_cast<int>(s.axis) == a) family.emplace_back(s.a_px.x(), s.a_px.y(), s.b_px.x(), s.b_px.y());
    const VanishingPointSummary own = FitVanishingPoint(family, vp_options);
    REQUIRE(own.IsUsable());
    CHECK((calibration.family_vanishing_points[a] - own.vp_px).norm() < 1e-12);
    CHECK((calibration.family_vanishing_point_covariance_px2[a] - own.point_covariance_px2).norm() <=
          1e-12 * own.point_covariance_px2.norm());
    // Noisy: the free point is not the fitted camera's (which ties the three together).
    CHECK((calibration.family_vanishing_points[a] - calibration.vanishing_points[a]).norm() > 0.0);
  }
}

}  // namespace
}  // namespace facet
