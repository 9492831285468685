// Single-image calibration from vanishing points (core/calibrate_vp.h) on synthetic box
// scenes: exact recovery without noise, accuracy within the noise, degenerate input.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Geometry>

#include "core/calibrate_vp.h"
#include "core/vanishing_point.h"
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
  REQUIRE(summary.success);
  CHECK(focal_error < relative);
  CHECK(pp_error < relative);
  CHECK(rotation_error < rotation_rad);
}

void CheckRotationRules(const Eigen::Matrix3d& r) {
  CAPTURE(r);
  CHECK(std::abs(r.determinant() - 1.0) < 1e-12);
  CHECK((r.transpose() * r - Eigen::Matrix3d::Identity()).norm() < 1e-12);
  CHECK(r(1, 2) < 0.0);              // world z up: negative camera-y component
  CHECK(r(2, 0) + r(2, 1) > 0.0);    // x + y towards the front
}

double Median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
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
    REQUIRE(summary.success);
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
      const Eigen::Vector3d camera_vp = (fitted.K() * fitted.cam_from_world_rotation.col(static_cast<int>(s.axis))).normalized();
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
    REQUIRE(fit.success);
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
  REQUIRE(clean_summary.success);
  double var_f = 0.0, var_cx = 0.0, var_cy = 0.0, var_rot = 0.0;
  const double h = 1e-4;  // px; the response is linear at this step and far above rounding
  for (size_t i = 0; i < clean.project.segments.size(); ++i) {
    for (int c = 0; c < 4; ++c) {
      std::vector<Segment> perturbed = clean.project.segments;
      (c < 2 ? perturbed[i].a_px : perturbed[i].b_px)(c % 2) += h;
      const VpCalibrationSummary s = CalibrateFromVanishingLines(perturbed, options);
      REQUIRE(s.success);
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
    const VpCalibrationSummary s = CalibrateFromVanishingLines(scene.project.segments, OptionsFor(scene, PrincipalPointMode::kSolve));
    CAPTURE(seed);
    INFO(s.message);
    REQUIRE(s.success);
    focal_errors.push_back(std::abs(s.focal_px - scene.true_camera.focal_px));
    pp_errors.push_back((s.principal_point_px - scene.true_camera.principal_point_px).norm());
    rotation_errors.push_back(
        RotationErrorRad(s.cam_from_world_rotation, ExpectedRotation(scene.true_camera.cam_from_world_rotation)));
    // The residuals measure the noise: endpoint noise projects onto the normal of the line
    // with sigma 0.5 px, and both endpoints share it (RMS of two equal distances).
    for (double r : s.segment_residuals_px) CHECK(r < 5 * kNoisePx);
  }
  const double median_f = Median(focal_errors), max_f = *std::max_element(focal_errors.begin(), focal_errors.end());
  const double median_pp = Median(pp_errors), max_pp = *std::max_element(pp_errors.begin(), pp_errors.end());
  const double median_rot = Median(rotation_errors),
               max_rot = *std::max_element(rotation_errors.begin(), rotation_errors.end());
  MESSAGE("over " << kSeeds << " seeds: focal median " << median_f << " px, max " << max_f << " px; principal point median "
                  << median_pp << " px, max " << max_pp << " px; rotation median " << median_rot * 180 / M_PI
                  << " deg, max " << max_rot * 180 / M_PI << " deg");
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
  REQUIRE(reference.success);
  for (double scale : {1e-3, 1e3}) {
    CAPTURE(scale);
    SyntheticSceneOptions o;
    o.scale = scale;
    const SyntheticScene scene = MakeBoxScene(o);
    const VpCalibrationSummary s =
        CalibrateFromVanishingLines(scene.project.segments, OptionsFor(scene, PrincipalPointMode::kSolve));
    REQUIRE(s.success);
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
  CHECK_FALSE(two.success);
  CHECK(two.message.find("undetermined") != std::string::npos);

  // Three points cannot place the principal point when one of them is at infinity.
  const VpCalibrationSummary solve =
      CalibrateFromVanishingLines(scene.project.segments, OptionsFor(scene, PrincipalPointMode::kSolve));
  INFO(solve.message);
  CHECK_FALSE(solve.success);
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
  CHECK_FALSE(s.success);
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
    CHECK_FALSE(s.success);
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

}  // namespace
}  // namespace facet
