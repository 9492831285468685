// Single-image calibration from vanishing points (core/estimators/calibrate_vp.h) on synthetic box
// scenes: exact recovery without noise, accuracy within the noise, degenerate input.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Geometry>

#include "core/estimators/calibrate_vp.h"
#include "core/estimators/vanishing_point.h"
#include "core/util/stats.h"
#include "tests/synthetic_scene.h"

namespace facet {
namespace {

using testing::MakeBoxScene;
using testing::SyntheticScene;
using testing::SyntheticSceneOptions;

// Noise-free data: the only error is rounding through a few SVDs and a Levenberg-Marquardt
// refinement that converges to the exact intersection.
constexpr double kNoiseFreeRelative = 1e-9;
constexpr double kNoiseFreeRotationRad = 1e-9;

VpCalibrationOptions OptionsFor(const SyntheticScene& scene, PrincipalPointMode mode) {
  VpCalibrationOptions options;
  options.width_px = scene.true_camera.width_px;
  options.height_px = scene.true_camera.height_px;
  options.principal_point_mode = mode;
  return options;
}

std::vector<Segment> SegmentsOfAxes(const SyntheticScene& scene, std::vector<Axis> axes) {
  std::vector<Segment> out;
  for (const Segment& s : scene.project.segments)
    if (std::find(axes.begin(), axes.end(), s.axis) != axes.end()) out.push_back(s);
  return out;
}

double RotationErrorRad(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a.transpose() * b).angle();
}

// Vanishing points fix each world axis up to sign. The calibration picks z up in the image,
// det = +1, and among (x, y) and (-x, -y) the one whose x + y points forward; the truth with
// the same rule applied is what the calibration must return.
Eigen::Matrix3d ExpectedRotation(const Eigen::Matrix3d& truth) {
  Eigen::Matrix3d r = truth;
  if (r(1, 2) > 0.0) r.col(2) *= -1.0, r.col(0) *= -1.0;
  if (r(2, 0) + r(2, 1) < 0.0) r.col(0) *= -1.0, r.col(1) *= -1.0;
  return r;
}

void CheckCameraNear(const VpCalibrationSummary& summary, const Camera& truth, double relative, double rotation_rad) {
  const Eigen::Matrix3d expected = ExpectedRotation(truth.cam_from_world_rotation);
  const double focal_error = std::abs(summary.focal_px - truth.focal_px) / truth.focal_px;
  const double pp_error = (summary.principal_point_px - truth.principal_point_px).norm() / truth.focal_px;
  const double rotation_error = RotationErrorRad(summary.cam_from_world_rotation, expected);
  INFO("message: " << summary.message);
  CAPTURE(summary.focal_px);
  CAPTURE(truth.focal_px);
  CAPTURE(summary.principal_point_px.transpose());
  CAPTURE(truth.principal_point_px.transpose());
  CAPTURE(focal_error);
  CAPTURE(pp_error);
  CAPTURE(rotation_error);
  REQUIRE(summary.IsUsable());
  CHECK(focal_error < relative);
  CHECK(pp_error < relative);
  CHECK(rotation_error < rotation_rad);
}

void CheckRotationRules(const Eigen::Matrix3d& r) {
  CAPTURE(r);
  CHECK(std::abs(r.determinant() - 1.0) < 1e-12);
  CHECK((r.transpose() * r - Eigen::Matrix3d::Identity()).norm() < 1e-12);
  CHECK(r(1, 2) < 0.0);            // world z up: negative camera-y component
  CHECK(r(2, 0) + r(2, 1) > 0.0);  // x + y towards the front
}

TEST_CASE("three vanishing points recover focal length, principal point and rotation exactly") {
  const SyntheticScene scene = MakeBoxScene();
  const Camera& truth = scene.true_camera;
  // The principal point is not the image centre, so the solve cannot succeed by returning
  // its natural starting guess.
  const Eigen::Vector2d image_center((truth.width_px - 1) / 2.0, (truth.height_px - 1) / 2.0);
  REQUIRE((truth.principal_point_px - image_center).norm() > 10.0);

  const VpCalibrationSummary summary =
      CalibrateFromVanishingLines(scene.project.segments, OptionsFor(scene, PrincipalPointMode::kSolve));
  CheckCameraNear(summary, truth, kNoiseFreeRelative, kNoiseFreeRotationRad);
  CheckRotationRules(summary.cam_from_world_rotation);
  CHECK((summary.principal_point_px - image_center).norm() > 10.0);
  CHECK(summary.warnings.empty());
  CHECK(summary.segments_per_axis == std::array<int, 3>{8, 8, 8});
  REQUIRE(summary.segment_residuals_px.size() == scene.project.segments.size());
  for (double r : summary.segment_residuals_px) CHECK(r < 1e-9);
  for (int a = 0; a < 3; ++a) {
    CHECK(std::abs(summary.vanishing_points[a].norm() - 1.0) < 1e-12);
    CHECK_FALSE(summary.vanishing_point_at_infinity[a]);
    // The fitted point is the projection of the world axis' point at infinity.
    const Eigen::Vector3d expected = (truth.K() * truth.cam_from_world_rotation.col(a)).normalized();
    CHECK(std::min((summary.vanishing_points[a] - expected).norm(), (summary.vanishing_points[a] + expected).norm()) <
          1e-9);
  }
  CHECK(summary.time_ms >= 0.0);
}

// Residual of one segment for a vanishing point given in pixels, from plain 2D geometry:
// the distance of endpoint a to the line through the midpoint towards the point.
double EndpointDistance(const Segment& s, const Eigen::Vector2d& vp) {
  const Eigen::Vector2d mid = 0.5 * (s.a_px + s.b_px);
  const Eigen::Vector2d dir = (vp - mid).normalized();
  const Eigen::Vector2d d = s.a_px - mid;
  return std::abs(d.x() * dir.y() - d.y() * dir.x());
}

double CostOfCamera(const std::vector<Segment>& segments, const Camera& camera) {
  double cost = 0.0;
  for (const Segment& s : segments) {
    const Eigen::Vector3d vp = camera.K() * camera.cam_from_world_rotation.col(static_cast<int>(s.axis));
    cost += std::pow(EndpointDistance(s, vp.head<2>() / vp.z()), 2);
  }
  return cost;
}

TEST_CASE("segment residuals are endpoint distances to the fitted camera's vanishing points") {
  SyntheticSceneOptions o;
  o.noise_px = 1.0;
  const SyntheticScene scene = MakeBoxScene(o);
  for (PrincipalPointMode mode : {PrincipalPointMode::kSolve, PrincipalPointMode::kFixed}) {
    VpCalibrationOptions options = OptionsFor(scene, mode);
    options.fixed_principal_point_px = scene.true_camera.principal_point_px;
    const VpCalibrationSummary summary = CalibrateFromVanishingLines(scene.project.segments, options);
    REQUIRE(summary.IsUsable());
    REQUIRE(summary.segment_residuals_px.size() == scene.project.segments.size());
    Camera fitted = scene.true_camera;
    fitted.focal_px = summary.focal_px;
    fitted.principal_point_px = summary.principal_point_px;
    fitted.cam_from_world_rotation = summary.cam_from_world_rotation;
    double sum_sq = 0.0;
    for (size_t i = 0; i < scene.project.segments.size(); ++i) {
      const Segment& s = scene.project.segments[i];
      const Eigen::Vector3d& vp = summary.vanishing_points[static_cast<int>(s.axis)];
      // The reported points are the fitted camera's: K R e_axis.
      const Eigen::Vector3d camera_vp =
          (fitted.K() * fitted.cam_from_world_rotation.col(static_cast<int>(s.axis))).normalized();
      CHECK(std::min((vp - camera_vp).norm(), (vp + camera_vp).norm()) < 1e-12);
      const double expected = EndpointDistance(s, vp.head<2>() / vp.z());
      CAPTURE(i);
      CHECK(std::abs(summary.segment_residuals_px[i] - expected) < 1e-9 * std::max(1.0, expected));
      sum_sq += expected * expected;
    }
    CHECK(std::abs(summary.rms_residual_px - std::sqrt(sum_sq / scene.project.segments.size())) < 1e-12);
    if (mode == PrincipalPointMode::kFixed) {
      // A least-squares fit over (f, R) explains the noisy segments at least as well as the
      // true camera does.
      CHECK(CostOfCamera(scene.project.segments, fitted) <= CostOfCamera(scene.project.segments, scene.true_camera));
    }
  }
}

// Fuzzing (tests/fuzz/fuzz_calibrate_lines): a family of exactly two segments gives a 2 x 3
// line matrix with two singular values, which were read into a fixed 3-vector: Eigen's size
// assert aborted `facet calibrate --lines` in a build with assertions, and without them the
// third value was read past the buffer. Two segments, the least the fit takes, give the
// crossing of their lines.
TEST_CASE("regression: a family of exactly two segments gives the crossing of their lines (fuzz_calibrate_lines)") {
  VanishingPointOptions options;
  options.conditioning_center_px = {511.5, 383.5};
  options.conditioning_scale_px = 512.0;
  // Two segments on lines through (900, 300): y = 300 + 0.1 (x - 900) and y = 300 - 0.2 (x - 900).
  const std::vector<Eigen::Vector4d> two = {{100.0, 220.0, 500.0, 260.0}, {100.0, 460.0, 500.0, 380.0}};
  const VanishingPointSummary fit = FitVanishingPoint(two, options);
  REQUIRE_MESSAGE(fit.IsUsable(), fit.message);
  const Eigen::Vector2d vp = fit.vp_px.head<2>() / fit.vp_px.z();
  const double tolerance_px = 1e-9 * 900.0;  // noise-free: exact up to rounding
  CHECK(std::abs(vp.x() - 900.0) < tolerance_px);
  CHECK(std::abs(vp.y() - 300.0) < tolerance_px);
  CHECK(fit.final_rms_px < 1e-9);
}

TEST_CASE("the vanishing point of a family minimises its segments' squared endpoint distances") {
  SyntheticSceneOptions o;
  o.noise_px = 1.0;
  const SyntheticScene scene = MakeBoxScene(o);
  VanishingPointOptions options;
  options.conditioning_center_px = {511.5, 383.5};
  options.conditioning_scale_px = 512.0;
  for (Axis axis : {Axis::kX, Axis::kY, Axis::kZ}) {
    const std::vector<Segment> family = SegmentsOfAxes(scene, {axis});
    std::vector<Eigen::Vector4d> raw;
    for (const Segment& s : family) raw.emplace_back(s.a_px.x(), s.a_px.y(), s.b_px.x(), s.b_px.y());
    const VanishingPointSummary fit = FitVanishingPoint(raw, options);
    REQUIRE(fit.IsUsable());
    CHECK(fit.final_rms_px <= fit.initial_rms_px);  // the refinement never makes it worse
    const Eigen::Vector2d center = fit.vp_px.head<2>() / fit.vp_px.z();
    double cost = 0.0;
    for (size_t i = 0; i < family.size(); ++i) {
      const double d = EndpointDistance(family[i], center);
      CHECK(std::abs(fit.residuals_px[i] - d) < 1e-9 * std::max(1.0, d));
      cost += d * d;
    }
    // Moving the point by a small fraction of its distance to the image, in any direction,
    // does not lower the cost.
    const double step = 1e-4 * (center - options.conditioning_center_px).norm();
    for (int k = 0; k < 8; ++k) {
      const Eigen::Vector2d moved = center + step * Eigen::Vector2d(std::cos(k * M_PI / 4), std::sin(k * M_PI / 4));
      double moved_cost = 0.0;
      for (const Segment& s : family) moved_cost += std::pow(EndpointDistance(s, moved), 2);
      CAPTURE(AxisName(axis));
      CAPTURE(k);
      CHECK(moved_cost >= cost * (1 - 1e-12));
    }
  }
}

TEST_CASE("0.5 px noise: errors stay within the first-order propagated noise") {
  // Each segment endpoint gets N(0, 0.5 px) per coordinate. The bounds come from a
  // first-order propagation of that noise through this calibration, computed below by finite
  // differences over all 112 endpoint coordinates of the scene (about 8.5 px of focal
  // length, 0.95 %, for this box; the principal-point prior vanishes for exact data, so this
  // is the sigma of the unregularised fit). Median |error| <= 1.5 sigma (the median of
  // |N(0, sigma)| is 0.67 sigma; 1.5 leaves room for the spread of a 25-sample median and for
  // non-linearity), max |error| <= 4.5 sigma over 25 seeds (a larger normal deviate has
  // probability ~2e-4 over all seeds).
  constexpr double kNoisePx = 0.5;
  constexpr int kSeeds = 25;

  // First-order standard deviations by finite differences of the calibration itself.
  SyntheticSceneOptions base;
  const SyntheticScene clean = MakeBoxScene(base);
  const VpCalibrationOptions options = OptionsFor(clean, PrincipalPointMode::kSolve);
  const VpCalibrationSummary clean_summary = CalibrateFromVanishingLines(clean.project.segments, options);
  REQUIRE(clean_summary.IsUsable());
  double var_f = 0.0, var_cx = 0.0, var_cy = 0.0, var_rot = 0.0;
  const double h = 1e-4;  // px; the response is linear at this step and far above rounding
  for (size_t i = 0; i < clean.project.segments.size(); ++i) {
    for (int c = 0; c < 4; ++c) {
      std::vector<Segment> perturbed = clean.project.segments;
      (c < 2 ? perturbed[i].a_px : perturbed[i].b_px)(c % 2) += h;
      const VpCalibrationSummary s = CalibrateFromVanishingLines(perturbed, options);
      REQUIRE(s.IsUsable());
      const double df = (s.focal_px - clean_summary.focal_px) / h;
      const Eigen::Vector2d dc = (s.principal_point_px - clean_summary.principal_point_px) / h;
      const double drot = RotationErrorRad(s.cam_from_world_rotation, clean_summary.cam_from_world_rotation) / h;
      var_f += df * df * kNoisePx * kNoisePx;
      var_cx += dc.x() * dc.x() * kNoisePx * kNoisePx;
      var_cy += dc.y() * dc.y() * kNoisePx * kNoisePx;
      var_rot += drot * drot * kNoisePx * kNoisePx;
    }
  }
  const double sigma_f = std::sqrt(var_f);
  const double sigma_pp = std::sqrt(var_cx + var_cy);  // of the 2D distance, RMS
  const double sigma_rot = std::sqrt(var_rot);
  MESSAGE("first-order sigma at 0.5 px: focal " << sigma_f << " px (" << 100 * sigma_f / base.focal_px
                                                << " %), principal point " << sigma_pp << " px, rotation "
                                                << sigma_rot * 180 / M_PI << " deg");

  std::vector<double> focal_errors, pp_errors, rotation_errors;
  for (int seed = 1; seed <= kSeeds; ++seed) {
    SyntheticSceneOptions o = base;
    o.noise_px = kNoisePx;
    o.seed = seed;
    const SyntheticScene scene = MakeBoxScene(o);
    const VpCalibrationSummary s =
        CalibrateFromVanishingLines(scene.project.segments, OptionsFor(scene, PrincipalPointMode::kSolve));
    CAPTURE(seed);
    INFO(s.message);
    REQUIRE(s.IsUsable());
    focal_errors.push_back(std::abs(s.focal_px - scene.true_camera.focal_px));
    pp_errors.push_back((s.principal_point_px - scene.true_camera.principal_point_px).norm());
    rotation_errors.push_back(
        RotationErrorRad(s.cam_from_world_rotation, ExpectedRotation(scene.true_camera.cam_from_world_rotation)));
    // The residuals measure the noise: endpoint noise projects onto the normal of the line
    // with sigma 0.5 px, and both endpoints share it (RMS of two equal distances).
    for (double r : s.segment_residuals_px) CHECK(r < 5 * kNoisePx);
  }
  const double median_f = internal::Median(focal_errors),
               max_f = *std::max_element(focal_errors.begin(), focal_errors.end());
  const double median_pp = internal::Median(pp_errors), max_pp = *std::max_element(pp_errors.begin(), pp_errors.end());
  const double median_rot = internal::Median(rotation_errors),
               max_rot = *std::max_element(rotation_errors.begin(), rotation_errors.end());
  MESSAGE("over " << kSeeds << " seeds: focal median " << median_f << " px, max " << max_f
                  << " px; principal point median " << median_pp << " px, max " << max_pp << " px; rotation median "
                  << median_rot * 180 / M_PI << " deg, max " << max_rot * 180 / M_PI << " deg");
  CHECK(median_f <= 1.5 * sigma_f);
  CHECK(max_f <= 4.5 * sigma_f);
  // The 2D principal-point distance is Rayleigh-like: median ~ 0.83 of its RMS, and its
  // tail decays like exp(-x^2 / 2), so 1.5 and 4.5 RMS play the same roles.
  CHECK(median_pp <= 1.5 * sigma_pp);
  CHECK(max_pp <= 4.5 * sigma_pp);
  CHECK(median_rot <= 1.5 * sigma_rot);
  CHECK(max_rot <= 4.5 * sigma_rot);
  // And the propagated noise itself is modest for this box (28 segments, 100-300 px long):
  // about 0.95 % of f; the 1.5 % bound flags a fit that loses accuracy.
  CHECK(sigma_f < 0.015 * base.focal_px);
}

TEST_CASE("two families with the principal point at the image centre or fixed") {
  SyntheticSceneOptions o;
  o.principal_point_offset_px = Eigen::Vector2d::Zero();
  const SyntheticScene centred = MakeBoxScene(o);
  const std::vector<std::vector<Axis>> pairs = {{Axis::kX, Axis::kY}, {Axis::kX, Axis::kZ}, {Axis::kY, Axis::kZ}};
  for (const auto& axes : pairs) {
    CAPTURE(AxisName(axes[0]));
    CAPTURE(AxisName(axes[1]));
    const std::vector<Segment> segments = SegmentsOfAxes(centred, axes);
    const VpCalibrationSummary s =
        CalibrateFromVanishingLines(segments, OptionsFor(centred, PrincipalPointMode::kImageCenter));
    CheckCameraNear(s, centred.true_camera, kNoiseFreeRelative, kNoiseFreeRotationRad);
    CheckRotationRules(s.cam_from_world_rotation);
    CHECK(s.segment_residuals_px.size() == segments.size());

    // kSolve cannot use two families: it falls back to the image centre and says so.
    const VpCalibrationSummary fallback =
        CalibrateFromVanishingLines(segments, OptionsFor(centred, PrincipalPointMode::kSolve));
    CheckCameraNear(fallback, centred.true_camera, kNoiseFreeRelative, kNoiseFreeRotationRad);
    CHECK(fallback.warnings.size() == 1);
  }

  // Off-centre principal point, given exactly.
  const SyntheticScene scene = MakeBoxScene();
  VpCalibrationOptions fixed = OptionsFor(scene, PrincipalPointMode::kFixed);
  fixed.fixed_principal_point_px = scene.true_camera.principal_point_px;
  const VpCalibrationSummary s = CalibrateFromVanishingLines(SegmentsOfAxes(scene, {Axis::kX, Axis::kZ}), fixed);
  CheckCameraNear(s, scene.true_camera, kNoiseFreeRelative, kNoiseFreeRotationRad);
  // Three families with the principal point given: f by least squares over three pairs.
  const VpCalibrationSummary three = CalibrateFromVanishingLines(scene.project.segments, fixed);
  CheckCameraNear(three, scene.true_camera, kNoiseFreeRelative, kNoiseFreeRotationRad);
}

TEST_CASE("the camera does not depend on the scale of the scene") {
  const SyntheticScene unit = MakeBoxScene();
  const VpCalibrationSummary reference =
      CalibrateFromVanishingLines(unit.project.segments, OptionsFor(unit, PrincipalPointMode::kSolve));
  REQUIRE(reference.IsUsable());
  for (double scale : {1e-3, 1e3}) {
    CAPTURE(scale);
    SyntheticSceneOptions o;
    o.scale = scale;
    const SyntheticScene scene = MakeBoxScene(o);
    const VpCalibrationSummary s =
        CalibrateFromVanishingLines(scene.project.segments, OptionsFor(scene, PrincipalPointMode::kSolve));
    REQUIRE(s.IsUsable());
    CHECK(std::abs(s.focal_px - reference.focal_px) < kNoiseFreeRelative * reference.focal_px);
    CHECK((s.principal_point_px - reference.principal_point_px).norm() < kNoiseFreeRelative * reference.focal_px);
    CHECK(RotationErrorRad(s.cam_from_world_rotation, reference.cam_from_world_rotation) < kNoiseFreeRotationRad);
    CheckCameraNear(s, scene.true_camera, kNoiseFreeRelative, kNoiseFreeRotationRad);
  }
}

TEST_CASE("a family parallel in the image: vanishing point at infinity") {
  // Zero pitch: the camera centre at the height it looks at, so vertical edges are parallel
  // in the image (the roll turns them but keeps them parallel).
  SyntheticSceneOptions o;
  o.camera_center.z() = 1.25;
  o.look_at.z() = 1.25;
  const SyntheticScene scene = MakeBoxScene(o);
  REQUIRE(std::abs(scene.true_camera.cam_from_world_rotation(2, 2)) < 1e-15);  // z axis in the image plane

  VpCalibrationOptions fixed = OptionsFor(scene, PrincipalPointMode::kFixed);
  fixed.fixed_principal_point_px = scene.true_camera.principal_point_px;
  const VpCalibrationSummary s = CalibrateFromVanishingLines(scene.project.segments, fixed);
  CheckCameraNear(s, scene.true_camera, kNoiseFreeRelative, kNoiseFreeRotationRad);
  CheckRotationRules(s.cam_from_world_rotation);
  CHECK(s.vanishing_point_at_infinity[2]);
  CHECK_FALSE(s.vanishing_point_at_infinity[0]);
  CHECK(std::abs(s.vanishing_points[2].z()) < 1e-9);
  for (double r : s.segment_residuals_px) CHECK(r < 1e-9);

  // The x and z families alone: z at infinity says nothing about f.
  const VpCalibrationSummary two = CalibrateFromVanishingLines(SegmentsOfAxes(scene, {Axis::kX, Axis::kZ}), fixed);
  CHECK_FALSE(two.IsUsable());
  CHECK(two.message.find("undetermined") != std::string::npos);

  // Three points cannot place the principal point when one of them is at infinity.
  const VpCalibrationSummary solve =
      CalibrateFromVanishingLines(scene.project.segments, OptionsFor(scene, PrincipalPointMode::kSolve));
  INFO(solve.message);
  CHECK_FALSE(solve.IsUsable());
  CHECK(solve.message.find("family z") != std::string::npos);
  CHECK(solve.message.find("parallel") != std::string::npos);
}

Segment MakeSegment(Axis axis, double x1, double y1, double x2, double y2) {
  Segment s;
  s.axis = axis;
  s.a_px = {x1, y1};
  s.b_px = {x2, y2};
  return s;
}

// Two segments of `axis` pointing at the pixel vp.
void AddPencil(Axis axis, const Eigen::Vector2d& vp, std::vector<Segment>* segments) {
  for (const Eigen::Vector2d& start : {Eigen::Vector2d(300, 200), Eigen::Vector2d(700, 600)}) {
    const Eigen::Vector2d dir = (vp - start).normalized();
    Segment s;
    s.axis = axis;
    s.a_px = start;
    s.b_px = start + 100.0 * dir;
    segments->push_back(s);
  }
}

void CheckFails(const std::vector<Segment>& segments, const VpCalibrationOptions& options,
                const std::vector<std::string>& words) {
  const VpCalibrationSummary s = CalibrateFromVanishingLines(segments, options);
  INFO("message: " << s.message);
  CHECK_FALSE(s.IsUsable());
  CHECK_FALSE(s.IsUsable());
  CHECK_FALSE(s.message.empty());
  for (const std::string& word : words) CHECK(s.message.find(word) != std::string::npos);
}

TEST_CASE("degenerate input fails with a message naming the problem") {
  const SyntheticScene scene = MakeBoxScene();
  const VpCalibrationOptions options = OptionsFor(scene, PrincipalPointMode::kSolve);

  SUBCASE("no segments or a single family") {
    CheckFails({}, options, {"two line families"});
    CheckFails(SegmentsOfAxes(scene, {Axis::kY}), options, {"two line families", "only y"});
  }
  SUBCASE("a family with one segment") {
    std::vector<Segment> segments = SegmentsOfAxes(scene, {Axis::kX, Axis::kZ});
    segments.push_back(SegmentsOfAxes(scene, {Axis::kY}).front());
    CheckFails(segments, options, {"family y", "1 segment"});
  }
  SUBCASE("a zero-length segment") {
    std::vector<Segment> segments = scene.project.segments;
    segments[5].b_px = segments[5].a_px;
    CheckFails(segments, options, {std::string("family ") + AxisName(segments[5].axis), "segment 5", "zero length"});
  }
  SUBCASE("a non-finite coordinate") {
    std::vector<Segment> segments = scene.project.segments;
    segments[2].a_px.x() = std::nan("");
    CheckFails(segments, options, {"segment 2", "non-finite"});
  }
  SUBCASE("all segments of a family on one line") {
    std::vector<Segment> segments = SegmentsOfAxes(scene, {Axis::kX, Axis::kY});
    segments.push_back(MakeSegment(Axis::kZ, 100, 100, 110, 300));
    segments.push_back(MakeSegment(Axis::kZ, 115, 400, 120, 500));  // on the same line
    CheckFails(segments, options, {"family z", "one line"});
  }
  SUBCASE("obtuse vanishing-point triangle") {
    std::vector<Segment> segments;
    AddPencil(Axis::kX, {-2000, 300}, &segments);
    AddPencil(Axis::kY, {3000, 300}, &segments);
    AddPencil(Axis::kZ, {500, 200}, &segments);  // between them: obtuse angle at z
    CheckFails(segments, options, {"f^2", "obtuse"});
  }
  SUBCASE("two families whose vanishing points lie on the same side of the principal point") {
    std::vector<Segment> segments;
    AddPencil(Axis::kX, {3000, 300}, &segments);
    AddPencil(Axis::kY, {4000, 500}, &segments);
    CheckFails(segments, OptionsFor(scene, PrincipalPointMode::kImageCenter), {"f^2"});
  }
  SUBCASE("three vanishing points on one line") {
    std::vector<Segment> segments;
    AddPencil(Axis::kX, {-2000, 300}, &segments);
    AddPencil(Axis::kY, {3000, 300}, &segments);
    AddPencil(Axis::kZ, {6000, 300}, &segments);
    const VpCalibrationSummary s = CalibrateFromVanishingLines(segments, options);
    INFO(s.message);
    CHECK_FALSE(s.IsUsable());
    CHECK_FALSE(s.message.empty());
  }
  SUBCASE("bad options") {
    VpCalibrationOptions bad = options;
    bad.width_px = 0;
    CheckFails(scene.project.segments, bad, {"image size"});
    bad = options;
    bad.principal_point_mode = PrincipalPointMode::kFixed;
    bad.fixed_principal_point_px = {std::nan(""), 0.0};
    CheckFails(scene.project.segments, bad, {"principal point"});
  }
}

TEST_CASE("an unfinished drawing is incomplete, not failed; broken input is not incomplete") {
  const SyntheticScene scene = MakeBoxScene();
  const VpCalibrationOptions options = OptionsFor(scene, PrincipalPointMode::kSolve);
  auto incomplete = [&](const std::vector<Segment>& segments) {
    const VpCalibrationSummary s = CalibrateFromVanishingLines(segments, options);
    INFO(s.message);
    CHECK_FALSE(s.IsUsable());
    return s.incomplete;
  };
  // What the user sees while drawing: nothing yet, the first line, one finished family.
  CHECK(incomplete({}));
  CHECK(incomplete({SegmentsOfAxes(scene, {Axis::kY}).front()}));
  CHECK(incomplete(SegmentsOfAxes(scene, {Axis::kY})));
  std::vector<Segment> one_more = SegmentsOfAxes(scene, {Axis::kX, Axis::kZ});
  one_more.push_back(SegmentsOfAxes(scene, {Axis::kY}).front());
  CHECK(incomplete(one_more));
  // Broken input and a geometric failure are real failures.
  std::vector<Segment> zero = scene.project.segments;
  zero[5].b_px = zero[5].a_px;
  CHECK_FALSE(incomplete(zero));
  std::vector<Segment> obtuse;
  AddPencil(Axis::kX, {-2000, 300}, &obtuse);
  AddPencil(Axis::kY, {3000, 300}, &obtuse);
  AddPencil(Axis::kZ, {500, 200}, &obtuse);
  CHECK_FALSE(incomplete(obtuse));
  // Complete and usable: not incomplete.
  const VpCalibrationSummary full = CalibrateFromVanishingLines(scene.project.segments, options);
  REQUIRE(full.IsUsable());
  CHECK_FALSE(full.incomplete);
}

// A warm start well away from the truth: focal length +12 %, principal point 25 px off, the
// rotation turned by about 4 degrees. The fit must walk from there to the answer.
VpCalibrationOptions WarmStartAway(VpCalibrationOptions options, const Camera& truth) {
  options.warm_start = true;
  options.warm_start_focal_px = 1.12 * truth.focal_px;
  options.warm_start_principal_point_px = truth.principal_point_px + Eigen::Vector2d(20.0, -15.0);
  options.warm_start_rotation =
      Eigen::AngleAxisd(0.07, Eigen::Vector3d(1.0, 2.0, -1.0).normalized()).toRotationMatrix() *
      truth.cam_from_world_rotation;
  return options;
}

void CheckStartIsNotTheAnswer(const VpCalibrationOptions& options, const Camera& truth) {
  CHECK(std::abs(options.warm_start_focal_px - truth.focal_px) > 0.1 * truth.focal_px);
  CHECK(RotationErrorRad(options.warm_start_rotation, truth.cam_from_world_rotation) > 0.05);
}

// Two points of the camera's horizon (the image of the plane orthogonal to world z), at the
// left and right image borders.
Eigen::Vector4d HorizonOf(const Camera& camera) {
  const Eigen::Vector3d line = camera.K().inverse().transpose() * camera.cam_from_world_rotation.col(2);
  const double x2 = camera.width_px - 1.0;
  return Eigen::Vector4d(0.0, -line.z() / line.y(), x2, -(line.x() * x2 + line.z()) / line.y());
}

TEST_CASE("every mode recovers the noise-free camera from a start away from it") {
  const SyntheticScene scene = MakeBoxScene();
  SyntheticSceneOptions centred_options;
  centred_options.principal_point_offset_px = Eigen::Vector2d::Zero();
  const SyntheticScene centred = MakeBoxScene(centred_options);

  struct Mode {
    std::string name;
    const SyntheticScene* scene;
    std::vector<Axis> axes;
    PrincipalPointMode pp_mode;
    bool fixed_focal, focal_prior, horizon;
  };
  const std::vector<Mode> modes = {
      {"3 VPs, principal point solved",
       &scene,
       {Axis::kX, Axis::kY, Axis::kZ},
       PrincipalPointMode::kSolve,
       false,
       false,
       false},
      {"3 VPs, principal point fixed",
       &scene,
       {Axis::kX, Axis::kY, Axis::kZ},
       PrincipalPointMode::kFixed,
       false,
       false,
       false},
      {"3 VPs, image centre",
       &centred,
       {Axis::kX, Axis::kY, Axis::kZ},
       PrincipalPointMode::kImageCenter,
       false,
       false,
       false},
      {"3 VPs, fixed focal length, principal point solved",
       &scene,
       {Axis::kX, Axis::kY, Axis::kZ},
       PrincipalPointMode::kSolve,
       true,
       false,
       false},
      {"3 VPs, focal prior", &scene, {Axis::kX, Axis::kY, Axis::kZ}, PrincipalPointMode::kSolve, false, true, false},
      {"2 VPs + principal point", &scene, {Axis::kX, Axis::kZ}, PrincipalPointMode::kFixed, false, false, false},
      {"2 VPs + principal point + focal prior",
       &scene,
       {Axis::kY, Axis::kZ},
       PrincipalPointMode::kFixed,
       false,
       true,
       false},
      {"2 VPs + fixed focal length", &scene, {Axis::kX, Axis::kY}, PrincipalPointMode::kFixed, true, false, false},
      {"2 VPs + horizon", &scene, {Axis::kX, Axis::kY}, PrincipalPointMode::kFixed, false, false, true},
      {"1 VP + fixed focal length + horizon", &scene, {Axis::kX}, PrincipalPointMode::kFixed, true, false, true},
      {"1 VP + focal prior + horizon", &scene, {Axis::kY}, PrincipalPointMode::kFixed, false, true, true},
  };
  for (const Mode& m : modes) {
    CAPTURE(m.name);
    const Camera& cam = m.scene->true_camera;
    VpCalibrationOptions options = OptionsFor(*m.scene, m.pp_mode);
    options.fixed_principal_point_px = cam.principal_point_px;
    if (m.fixed_focal) options.fixed_focal_px = cam.focal_px;
    if (m.focal_prior) {
      // Exact data outweigh any prior; with one family the prior is the only focal data.
      options.focal_prior_px = m.axes.size() == 1 ? cam.focal_px : 1.05 * cam.focal_px;
      options.focal_prior_std_px = 0.02 * cam.focal_px;
    }
    if (m.horizon) {
      options.use_horizon = true;
      options.horizon_px = HorizonOf(cam);
    }
    const std::vector<Segment> segments = SegmentsOfAxes(*m.scene, m.axes);
    const VpCalibrationSummary closed = CalibrateFromVanishingLines(segments, options);
    CheckCameraNear(closed, cam, kNoiseFreeRelative, kNoiseFreeRotationRad);
    CheckRotationRules(closed.cam_from_world_rotation);

    const VpCalibrationOptions warm = WarmStartAway(options, cam);
    CheckStartIsNotTheAnswer(warm, cam);
    const VpCalibrationSummary s = CalibrateFromVanishingLines(segments, warm);
    CheckCameraNear(s, cam, kNoiseFreeRelative, kNoiseFreeRotationRad);
    CHECK(s.iterations > 0);
    CHECK(s.outlier_segments.empty());
    if (m.focal_prior && m.axes.size() == 1)
      CHECK(s.focal_std_px == options.focal_prior_std_px);  // the segments say nothing about f
    else
      CHECK(s.focal_std_px < kNoiseFreeRelative * cam.focal_px);
    if (m.horizon) CHECK(s.horizon_residual_px < 1e-9);
  }
}

TEST_CASE("a principal point outside the image (cropped photo)") {
  SyntheticSceneOptions o;
  o.principal_point_offset_px = {640.0, -20.0};  // x = 1151.5 in a 1024 px wide image
  const SyntheticScene scene = MakeBoxScene(o);
  const Camera& truth = scene.true_camera;
  REQUIRE(truth.principal_point_px.x() > truth.width_px);
  VpCalibrationOptions fixed = OptionsFor(scene, PrincipalPointMode::kFixed);
  fixed.fixed_principal_point_px = truth.principal_point_px;
  CheckCameraNear(CalibrateFromVanishingLines(scene.project.segments, fixed), truth, kNoiseFreeRelative,
                  kNoiseFreeRotationRad);
  CheckCameraNear(CalibrateFromVanishingLines(SegmentsOfAxes(scene, {Axis::kX, Axis::kZ}), fixed), truth,
                  kNoiseFreeRelative, kNoiseFreeRotationRad);
  // Solved: exact data override the prior at the image centre, 640 px away.
  const VpCalibrationSummary solved =
      CalibrateFromVanishingLines(scene.project.segments, OptionsFor(scene, PrincipalPointMode::kSolve));
  CheckCameraNear(solved, truth, kNoiseFreeRelative, kNoiseFreeRotationRad);
  bool warned = false;
  for (const std::string& w : solved.warnings) warned = warned || w.find("outside the image") != std::string::npos;
  CHECK(warned);
}

// Monte Carlo over 200 seeds of 0.5 px endpoint noise: every error within 4.5 of its own
// focal_std_px (a larger normal deviate has probability 7e-6 per draw, 0.4 % over the 600
// draws; 4 would fail 4 % of the time, and the focal error is slightly skewed by the
// non-linearity), and the spread of the
// errors within a factor 1.5 of the mean reported std (200 samples give the empirical std to
// about 5 %; the factor leaves room for the linearisation). The same for the vanishing
// directions' angular std.
TEST_CASE("0.5 px noise: focal_std_px and the vanishing-direction std match the errors") {
  constexpr double kNoisePx = 0.5;
  constexpr int kSeeds = 200;
  struct Case {
    std::string name;
    PrincipalPointMode mode;
    std::vector<Axis> axes;
  };
  for (const Case& c :
       {Case{"3 VPs, principal point solved", PrincipalPointMode::kSolve, {Axis::kX, Axis::kY, Axis::kZ}},
        Case{"3 VPs, principal point fixed", PrincipalPointMode::kFixed, {Axis::kX, Axis::kY, Axis::kZ}},
        Case{"2 VPs, principal point fixed", PrincipalPointMode::kFixed, {Axis::kX, Axis::kZ}}}) {
    CAPTURE(c.name);
    double sum_sq_error = 0.0, sum_std = 0.0, max_z = 0.0;
    std::array<double, 3> sum_sq_angle{}, sum_angle_std{};
    for (int seed = 1; seed <= kSeeds; ++seed) {
      SyntheticSceneOptions o;
      o.noise_px = kNoisePx;
      o.seed = seed;
      const SyntheticScene scene = MakeBoxScene(o);
      VpCalibrationOptions options = OptionsFor(scene, c.mode);
      options.fixed_principal_point_px = scene.true_camera.principal_point_px;
      const VpCalibrationSummary s = CalibrateFromVanishingLines(SegmentsOfAxes(scene, c.axes), options);
      CAPTURE(seed);
      REQUIRE(s.IsUsable());
      REQUIRE(s.focal_std_px > 0.0);
      const double error = s.focal_px - scene.true_camera.focal_px;
      max_z = std::max(max_z, std::abs(error) / s.focal_std_px);
      CHECK(std::abs(error) < 4.5 * s.focal_std_px);
      sum_sq_error += error * error;
      sum_std += s.focal_std_px;
      const Eigen::Matrix3d expected = ExpectedRotation(scene.true_camera.cam_from_world_rotation);
      for (Axis axis : c.axes) {
        const int a = static_cast<int>(axis);
        const double angle = std::acos(std::clamp(s.cam_from_world_rotation.col(a).dot(expected.col(a)), -1.0, 1.0));
        sum_sq_angle[a] += angle * angle;
        sum_angle_std[a] += s.vanishing_direction_std_deg[a] * M_PI / 180.0;
      }
    }
    const double empirical = std::sqrt(sum_sq_error / kSeeds), reported = sum_std / kSeeds;
    MESSAGE(c.name << ": focal error RMS " << empirical << " px, mean focal_std_px " << reported
                   << " px, largest |error| / std " << max_z);
    CHECK(empirical < 1.5 * reported);
    CHECK(empirical > reported / 1.5);
    for (Axis axis : c.axes) {
      const int a = static_cast<int>(axis);
      const double angle_empirical = std::sqrt(sum_sq_angle[a] / kSeeds), angle_reported = sum_angle_std[a] / kSeeds;
      CAPTURE(AxisName(axis));
      CAPTURE(angle_empirical);
      CAPTURE(angle_reported);
      CHECK(angle_empirical < 1.5 * angle_reported);
      CHECK(angle_empirical > angle_reported / 1.5);
    }
  }
}

TEST_CASE("a focal prior combines with the data as independent Gaussians") {
  // Posterior std = 1 / sqrt(1 / data_std^2 + 1 / prior_std^2), to first order.
  SyntheticSceneOptions o;
  o.noise_px = 0.5;
  const SyntheticScene scene = MakeBoxScene(o);
  VpCalibrationOptions options = OptionsFor(scene, PrincipalPointMode::kFixed);
  options.fixed_principal_point_px = scene.true_camera.principal_point_px;
  const std::vector<Segment> segments = SegmentsOfAxes(scene, {Axis::kX, Axis::kZ});
  const VpCalibrationSummary data_only = CalibrateFromVanishingLines(segments, options);
  REQUIRE(data_only.IsUsable());
  options.focal_prior_px = scene.true_camera.focal_px;
  options.focal_prior_std_px = data_only.focal_std_px;  // equal weights: std / sqrt(2)
  const VpCalibrationSummary with_prior = CalibrateFromVanishingLines(segments, options);
  REQUIRE(with_prior.IsUsable());
  CAPTURE(data_only.focal_std_px);
  CAPTURE(with_prior.focal_std_px);
  CHECK(std::abs(with_prior.focal_std_px - data_only.focal_std_px / std::sqrt(2.0)) < 0.1 * data_only.focal_std_px);
  // And the estimate lies between the data's and the prior's (half way, to first order).
  const double expected = 0.5 * (data_only.focal_px + options.focal_prior_px);
  CHECK(std::abs(with_prior.focal_px - expected) < 0.1 * std::abs(data_only.focal_px - options.focal_prior_px) + 1e-6);

  // A fixed focal length is not solved: zero std, the value kept exactly.
  VpCalibrationOptions fixed = OptionsFor(scene, PrincipalPointMode::kSolve);
  fixed.fixed_focal_px = 1.03 * scene.true_camera.focal_px;
  const VpCalibrationSummary s = CalibrateFromVanishingLines(scene.project.segments, fixed);
  REQUIRE(s.IsUsable());
  CHECK(s.focal_px == fixed.fixed_focal_px);
  CHECK(s.focal_std_px == 0.0);
  CHECK(s.principal_point_std_px.x() > 0.0);
}

TEST_CASE("a wrong segment is flagged, and the refit without it recovers the camera") {
  SyntheticSceneOptions o;
  o.noise_px = 0.3;
  const SyntheticScene scene = MakeBoxScene(o);
  std::vector<Segment> segments = scene.project.segments;
  constexpr int kWrong = 9;
  // Rotate the segment about its midpoint by 3 degrees: its endpoints move ~5-8 px off.
  const Eigen::Vector2d mid = 0.5 * (segments[kWrong].a_px + segments[kWrong].b_px);
  const Eigen::Rotation2Dd turn(3.0 * M_PI / 180.0);
  segments[kWrong].a_px = mid + turn * (segments[kWrong].a_px - mid);
  segments[kWrong].b_px = mid + turn * (segments[kWrong].b_px - mid);

  VpCalibrationOptions options = OptionsFor(scene, PrincipalPointMode::kSolve);
  options.refit_without_outliers = false;
  const VpCalibrationSummary plain = CalibrateFromVanishingLines(segments, options);
  options.refit_without_outliers = true;
  const VpCalibrationSummary refit = CalibrateFromVanishingLines(segments, options);
  const VpCalibrationSummary clean = CalibrateFromVanishingLines(scene.project.segments, options);
  REQUIRE(plain.IsUsable());
  REQUIRE(refit.IsUsable());
  REQUIRE(clean.IsUsable());
  CAPTURE(plain.segment_residuals_px[kWrong]);
  CAPTURE(plain.outlier_threshold_px);
  // Without the refit the wrong segment drags the camera, and a neighbour may cross the
  // threshold too; the wrong one has the largest residual.
  REQUIRE_FALSE(plain.outlier_segments.empty());
  CHECK(std::max_element(plain.segment_residuals_px.begin(), plain.segment_residuals_px.end()) -
            plain.segment_residuals_px.begin() ==
        kWrong);
  CHECK(plain.segment_is_outlier[kWrong]);
  CHECK(refit.outlier_segments == std::vector<int>{kWrong});
  CHECK(refit.segment_is_outlier.size() == segments.size());
  CHECK(refit.segment_is_outlier[kWrong]);
  CHECK_FALSE(plain.refitted_without_outliers);
  CHECK(refit.refitted_without_outliers);
  CHECK(clean.outlier_segments.empty());
  // The threshold is max(3 * 1.4826 * median |r|, 1 px): the 0.3 px noise puts it at the floor.
  CHECK(refit.outlier_threshold_px == doctest::Approx(1.0));
  // The refit is the fit of the data without the wrong segment.
  std::vector<Segment> without = segments;
  without.erase(without.begin() + kWrong);
  const VpCalibrationSummary reference = CalibrateFromVanishingLines(without, options);
  REQUIRE(reference.IsUsable());
  CAPTURE(refit.focal_px);
  CAPTURE(reference.focal_px);
  CAPTURE(plain.focal_px);
  // Equal up to the weight of the principal-point prior, which follows the noise estimate of
  // the free vanishing points (the wrong segment raises it a little): within 5 % of a sigma.
  CHECK(std::abs(refit.focal_px - reference.focal_px) < 0.05 * reference.focal_std_px);
  CHECK(std::abs(refit.focal_px - scene.true_camera.focal_px) < std::abs(plain.focal_px - scene.true_camera.focal_px));
  bool warned = false;
  for (const std::string& w : refit.warnings) warned = warned || w.find("outlier") != std::string::npos;
  CHECK(warned);
}

TEST_CASE("degeneracy figures: angle spread, distance to the principal point, triangle angle") {
  const SyntheticScene scene = MakeBoxScene();
  const VpCalibrationSummary s =
      CalibrateFromVanishingLines(scene.project.segments, OptionsFor(scene, PrincipalPointMode::kSolve));
  REQUIRE(s.IsUsable());
  const Camera& truth = scene.true_camera;
  std::array<Eigen::Vector2d, 3> vps;
  for (int a = 0; a < 3; ++a) {
    const Eigen::Vector3d v = truth.K() * truth.cam_from_world_rotation.col(a);
    vps[a] = v.head<2>() / v.z();
    CHECK(std::abs(s.vanishing_point_to_principal_point_px[a] - (vps[a] - truth.principal_point_px).norm()) <
          1e-6 * (vps[a] - truth.principal_point_px).norm());
    // Largest pairwise angle between the family's segments, by brute force.
    double largest = 0.0;
    const std::vector<Segment> family = SegmentsOfAxes(scene, {static_cast<Axis>(a)});
    for (const Segment& p : family)
      for (const Segment& q : family) {
        const Eigen::Vector2d u = (p.b_px - p.a_px).normalized(), w = (q.b_px - q.a_px).normalized();
        largest = std::max(largest, std::acos(std::min(1.0, std::abs(u.dot(w)))) * 180.0 / M_PI);
      }
    CAPTURE(a);
    CHECK(std::abs(s.family_angle_spread_deg[a] - largest) < 1e-9);
  }
  CHECK(s.min_family_angle_spread_deg ==
        *std::min_element(s.family_angle_spread_deg.begin(), s.family_angle_spread_deg.end()));
  CHECK(s.min_vanishing_point_to_principal_point_px ==
        *std::min_element(s.vanishing_point_to_principal_point_px.begin(),
                          s.vanishing_point_to_principal_point_px.end()));
  // The triangle of the true vanishing points is acute, its orthocentre the principal point.
  double largest_angle = 0.0;
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector2d u = (vps[(i + 1) % 3] - vps[i]).normalized(), w = (vps[(i + 2) % 3] - vps[i]).normalized();
    largest_angle = std::max(largest_angle, std::acos(u.dot(w)) * 180.0 / M_PI);
  }
  CHECK(largest_angle < 90.0);
  CHECK(std::abs(s.vanishing_point_triangle_max_angle_deg - largest_angle) < 1e-6);

  // Nearly parallel segments in a family: the spread is small and a warning quotes it.
  std::vector<Segment> segments = SegmentsOfAxes(scene, {Axis::kX, Axis::kY});
  segments.push_back(MakeSegment(Axis::kZ, 100, 100, 101, 400));
  segments.push_back(MakeSegment(Axis::kZ, 300, 100, 301.5, 400));
  VpCalibrationOptions centre = OptionsFor(scene, PrincipalPointMode::kImageCenter);
  const VpCalibrationSummary narrow = CalibrateFromVanishingLines(segments, centre);
  INFO(narrow.message);
  REQUIRE(narrow.IsUsable());
  CHECK(narrow.family_angle_spread_deg[2] < 0.2);
  bool warned = false;
  for (const std::string& w : narrow.warnings) warned = warned || w.find("nearly parallel") != std::string::npos;
  CHECK(warned);
}

TEST_CASE("one family with the horizon: the modes it needs and refuses") {
  const SyntheticScene scene = MakeBoxScene();
  VpCalibrationOptions options = OptionsFor(scene, PrincipalPointMode::kFixed);
  options.fixed_principal_point_px = scene.true_camera.principal_point_px;
  options.use_horizon = true;
  options.horizon_px = HorizonOf(scene.true_camera);
  // Without a known focal length.
  CheckFails(SegmentsOfAxes(scene, {Axis::kX}), options, {"known focal length"});
  // The vertical family leaves the heading free.
  options.fixed_focal_px = scene.true_camera.focal_px;
  CheckFails(SegmentsOfAxes(scene, {Axis::kZ}), options, {"horizontal"});
  // kSolve falls back to the image centre with one family.
  options.principal_point_mode = PrincipalPointMode::kSolve;
  const VpCalibrationSummary s = CalibrateFromVanishingLines(SegmentsOfAxes(scene, {Axis::kX}), options);
  REQUIRE(s.IsUsable());
  CHECK(s.warnings.size() >= 1);
  CHECK((s.principal_point_px - Eigen::Vector2d(511.5, 383.5)).norm() < 1e-12);
  // Bad option combinations.
  VpCalibrationOptions both = options;
  both.focal_prior_px = 900.0;
  both.focal_prior_std_px = 10.0;
  CheckFails(scene.project.segments, both, {"not both"});
  VpCalibrationOptions flat = options;
  flat.horizon_px = Eigen::Vector4d(5.0, 5.0, 5.0, 5.0);
  CheckFails(scene.project.segments, flat, {"horizon"});
}

}  // namespace
}  // namespace facet
