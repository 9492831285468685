// Calibration from known 3D points (core/estimators/calibrate_dlt.h) and its JSON adapter
// (core/io/calibrate_points_io.h) on synthetic cameras with known K, R, t.
#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/estimators/calibrate_dlt.h"
#include "core/io/calibrate_points_io.h"
#include "tests/synthetic_scene.h"

namespace facet {
namespace {

using testing::MakeLookAtCamera;
using testing::SyntheticSceneOptions;

// Noise-free recovery: the linear step and the refinement are exact up to rounding.
constexpr double kExactRelative = 1e-9;

Eigen::Vector2d ProjectDistorted(const Camera& camera, double k1, double k2, const Eigen::Vector3d& p_in_world) {
  const Eigen::Vector3d p = camera.CamFromWorld(p_in_world);
  const double x = p.x() / p.z(), y = p.y() / p.z();
  const double r2 = x * x + y * y;
  const double d = 1.0 + k1 * r2 + k2 * r2 * r2;
  return {camera.focal_px * x * d + camera.principal_point_px.x(),
          camera.focal_px * y * d + camera.principal_point_px.y()};
}

struct SceneSpec {
  int num_points = 40;
  bool planar = false;
  double noise_px = 0.0;
  double k1 = 0.0;
  double k2 = 0.0;
  double scale = 1.0;
  double extent = 1.0;  // multiplies the size of the volume or plane
  unsigned seed = 1;
};

// The default synthetic camera and points inside its image (a 4 x 4 x 3 volume around the
// look-at point, or a tilted 4 x 3 plane through it, so the plane's frame is not the world's;
// extent 3 fills the image).
std::vector<PointCorrespondence> MakePoints(const Camera& camera, const SceneSpec& spec,
                                            const SyntheticSceneOptions& scene) {
  std::mt19937 rng(spec.seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  std::normal_distribution<double> noise(0.0, 1.0);
  const Eigen::Vector3d center = scene.look_at * spec.scale;
  const Eigen::Vector3d plane_u = Eigen::Vector3d(1.0, 0.2, 0.3).normalized();
  const Eigen::Vector3d plane_v = plane_u.cross(Eigen::Vector3d(0.1, -0.3, 1.0)).normalized();
  std::vector<PointCorrespondence> points;
  while (static_cast<int>(points.size()) < spec.num_points) {
    Eigen::Vector3d xyz;
    if (spec.planar) {
      const double along_u = 2.0 * uniform(rng), along_v = 1.5 * uniform(rng);
      xyz = center + spec.scale * spec.extent * (along_u * plane_u + along_v * plane_v);
    } else {
      xyz = center +
            spec.scale * spec.extent * Eigen::Vector3d{2.0 * uniform(rng), 2.0 * uniform(rng), 1.5 * uniform(rng)};
    }
    const Eigen::Vector2d uv = ProjectDistorted(camera, spec.k1, spec.k2, xyz);
    if (camera.CamFromWorld(xyz).z() <= 0.0 || uv.x() < 0 || uv.y() < 0 || uv.x() > camera.width_px - 1 ||
        uv.y() > camera.height_px - 1)
      continue;
    PointCorrespondence c;
    c.xyz = xyz;
    c.uv_px = uv + spec.noise_px * Eigen::Vector2d{noise(rng), noise(rng)};
    points.push_back(c);
  }
  return points;
}

SyntheticSceneOptions DefaultScene(double scale = 1.0) {
  SyntheticSceneOptions o;
  o.scale = scale;
  return o;
}

double RotationErrorDeg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return AngleAxisFromRotation(a * b.transpose()).norm() * 180.0 / M_PI;
}

DltCalibrationOptions OptionsFor(const Camera& camera) {
  DltCalibrationOptions options;
  options.width_px = camera.width_px;
  options.height_px = camera.height_px;
  return options;
}

void CheckCameraExact(const Camera& got, const Camera& want) {
  CAPTURE(got.focal_px);
  CAPTURE(want.focal_px);
  CHECK(std::abs(got.focal_px - want.focal_px) <= kExactRelative * want.focal_px);
  CHECK((got.principal_point_px - want.principal_point_px).norm() <= kExactRelative * want.focal_px);
  const double rotation_error = (got.cam_from_world_rotation - want.cam_from_world_rotation).norm();
  CAPTURE(rotation_error);
  CHECK(rotation_error <= kExactRelative);
  const double t_error = (got.cam_from_world_translation - want.cam_from_world_translation).norm();
  CAPTURE(t_error);
  CHECK(t_error <= kExactRelative * want.cam_from_world_translation.norm());
}

}  // namespace

TEST_CASE("DLT: noise-free non-planar points give K, R, t exactly, from the linear step alone too") {
  const Camera truth = MakeLookAtCamera(DefaultScene());
  const auto points = MakePoints(truth, {}, DefaultScene());
  DltCalibrationOptions options = OptionsFor(truth);

  options.refine = false;
  const DltCalibrationSummary linear = CalibrateFromPoints(points, options);
  REQUIRE_MESSAGE(linear.IsUsable(), linear.message);
  CHECK_FALSE(linear.planar);
  CAPTURE(linear.fx);
  CAPTURE(linear.fy);
  CAPTURE(linear.skew);
  CHECK(std::abs(linear.fx - truth.focal_px) <= kExactRelative * truth.focal_px);
  CHECK(std::abs(linear.fy - truth.focal_px) <= kExactRelative * truth.focal_px);
  CHECK(std::abs(linear.skew) <= kExactRelative * truth.focal_px);
  CHECK((linear.linear_principal_point_px - truth.principal_point_px).norm() <= kExactRelative * truth.focal_px);
  CheckCameraExact(linear.camera, truth);
  // P equals K [R | t] up to scale.
  const Eigen::Matrix<double, 3, 4> p_true = truth.ProjectionMatrix() / truth.ProjectionMatrix().norm();
  CHECK((linear.P - p_true).norm() <= kExactRelative);
  CHECK(linear.initial_rms_px <= 1e-6);
  CHECK(linear.iterations == 0);

  options.refine = true;
  const DltCalibrationSummary refined = CalibrateFromPoints(points, options);
  REQUIRE_MESSAGE(refined.IsUsable(), refined.message);
  CheckCameraExact(refined.camera, truth);
  CHECK(refined.reprojection_rms_px <= 1e-6);
  CHECK(refined.residuals_px.size() == points.size());
  CHECK(refined.warnings.empty());
  MESSAGE("noise-free DLT: f error " << std::abs(refined.camera.focal_px - truth.focal_px) << " px, time "
                                     << refined.time_ms << " ms");
}

TEST_CASE("DLT: exactly 6 points suffice") {
  const Camera truth = MakeLookAtCamera(DefaultScene());
  SceneSpec spec;
  spec.num_points = 6;
  spec.seed = 7;
  const auto points = MakePoints(truth, spec, DefaultScene());
  const DltCalibrationSummary s = CalibrateFromPoints(points, OptionsFor(truth));
  REQUIRE_MESSAGE(s.IsUsable(), s.message);
  CheckCameraExact(s.camera, truth);
}

TEST_CASE("DLT: with 0.5 px noise the errors match the fit's covariance over 40 seeds") {
  // Each seed: |f - f_true| <= 4 sigma (sigma from the covariance, per seed); over the seeds
  // the observed spread of f agrees with the mean predicted sigma within the sampling error
  // of 40 draws (a factor 0.6..1.6 is far outside its ~11 % standard error).
  constexpr double kNoisePx = 0.5;
  constexpr int kSeeds = 40;
  const Camera truth = MakeLookAtCamera(DefaultScene());
  // Extent 1: the points fill the image's middle third (f weakly determined); 3: all of it.
  for (const double extent : {1.0, 3.0}) {
    double sum_sq_error = 0.0, sum_sigma = 0.0, max_rotation_deg = 0.0, sum_sq_start_error = 0.0;
    for (int seed = 1; seed <= kSeeds; ++seed) {
      SceneSpec spec;
      spec.noise_px = kNoisePx;
      spec.extent = extent;
      spec.seed = seed;
      const auto points = MakePoints(truth, spec, DefaultScene());
      const DltCalibrationSummary s = CalibrateFromPoints(points, OptionsFor(truth));
      REQUIRE_MESSAGE(s.IsUsable(), s.message);
      const double f_error = s.camera.focal_px - truth.focal_px;
      CAPTURE(seed);
      CAPTURE(f_error);
      CAPTURE(s.focal_std_px);
      REQUIRE(s.focal_std_px > 0.0);
      CHECK(std::abs(f_error) <= 4.0 * s.focal_std_px);
      CHECK((s.camera.principal_point_px - truth.principal_point_px).cwiseAbs().maxCoeff() <=
            4.0 * s.principal_point_std_px.maxCoeff());
      // The refinement starts from f = (fx + fy) / 2 of the linear step and moves off it (the
      // linear camera's own RMS is lower: it has fx, fy and skew free).
      const double start_f = 0.5 * (s.fx + s.fy);
      CAPTURE(start_f);
      CHECK(std::abs(s.camera.focal_px - start_f) > 1e-6 * truth.focal_px);
      CHECK(s.iterations >= 1);
      sum_sq_start_error += (start_f - truth.focal_px) * (start_f - truth.focal_px);
      // RMS of the 2D residual: sigma * sqrt(2 (2n - p) / 2n) with p = 9 parameters.
      const double expected_rms = kNoisePx * std::sqrt(2.0 * (2.0 * points.size() - 9) / (2.0 * points.size()));
      CAPTURE(s.reprojection_rms_px);
      CHECK(std::abs(s.reprojection_rms_px - expected_rms) <= 0.25 * expected_rms);
      sum_sq_error += f_error * f_error;
      sum_sigma += s.focal_std_px;
      max_rotation_deg =
          std::max(max_rotation_deg, RotationErrorDeg(s.camera.cam_from_world_rotation, truth.cam_from_world_rotation));
    }
    const double observed = std::sqrt(sum_sq_error / kSeeds), predicted = sum_sigma / kSeeds;
    MESSAGE("DLT 0.5 px noise, 40 points, extent " << extent << ": f error RMS over seeds " << observed
                                                   << " px, predicted sigma " << predicted << " px, max rotation error "
                                                   << max_rotation_deg << " deg; linear start f error RMS "
                                                   << std::sqrt(sum_sq_start_error / kSeeds) << " px");
    CHECK(observed < std::sqrt(sum_sq_start_error / kSeeds));
    CHECK(observed >= 0.6 * predicted);
    CHECK(observed <= 1.6 * predicted);
  }
}

TEST_CASE("Planar: noise-free points on a tilted plane give K, R, t exactly") {
  SUBCASE("principal point at the image centre (the default)") {
    SyntheticSceneOptions scene = DefaultScene();
    scene.principal_point_offset_px = {0.0, 0.0};
    const Camera truth = MakeLookAtCamera(scene);
    SceneSpec spec;
    spec.planar = true;
    spec.num_points = 30;
    const auto points = MakePoints(truth, spec, scene);
    DltCalibrationOptions options = OptionsFor(truth);
    options.refine = false;
    const DltCalibrationSummary linear = CalibrateFromPoints(points, options);
    REQUIRE_MESSAGE(linear.IsUsable(), linear.message);
    CHECK(linear.planar);
    CheckCameraExact(linear.camera, truth);
    options.refine = true;
    const DltCalibrationSummary s = CalibrateFromPoints(points, options);
    REQUIRE_MESSAGE(s.IsUsable(), s.message);
    CheckCameraExact(s.camera, truth);
  }
  SUBCASE("principal point given off-centre") {
    const Camera truth = MakeLookAtCamera(DefaultScene());
    SceneSpec spec;
    spec.planar = true;
    spec.num_points = 4;
    const auto points = MakePoints(truth, spec, DefaultScene());
    DltCalibrationOptions options = OptionsFor(truth);
    options.principal_point_mode = PrincipalPointMode::kFixed;
    options.fixed_principal_point_px = truth.principal_point_px;
    const DltCalibrationSummary s = CalibrateFromPoints(points, options);
    REQUIRE_MESSAGE(s.IsUsable(), s.message);
    CHECK(s.planar);
    CheckCameraExact(s.camera, truth);
  }
}

TEST_CASE("Planar: with 0.5 px noise the errors match the fit's covariance over 40 seeds") {
  constexpr double kNoisePx = 0.5;
  constexpr int kSeeds = 40;
  SyntheticSceneOptions scene = DefaultScene();
  scene.principal_point_offset_px = {0.0, 0.0};
  const Camera truth = MakeLookAtCamera(scene);
  double sum_sq_error = 0.0, sum_sigma = 0.0;
  for (int seed = 1; seed <= kSeeds; ++seed) {
    SceneSpec spec;
    spec.planar = true;
    spec.noise_px = kNoisePx;
    spec.seed = seed;
    const auto points = MakePoints(truth, spec, scene);
    const DltCalibrationSummary s = CalibrateFromPoints(points, OptionsFor(truth));
    REQUIRE_MESSAGE(s.IsUsable(), s.message);
    const double f_error = s.camera.focal_px - truth.focal_px;
    CAPTURE(seed);
    CAPTURE(f_error);
    CAPTURE(s.focal_std_px);
    REQUIRE(s.focal_std_px > 0.0);
    CHECK(std::abs(f_error) <= 4.0 * s.focal_std_px);
    CHECK(s.initial_rms_px > s.reprojection_rms_px);
    sum_sq_error += f_error * f_error;
    sum_sigma += s.focal_std_px;
  }
  const double observed = std::sqrt(sum_sq_error / kSeeds), predicted = sum_sigma / kSeeds;
  MESSAGE("planar 0.5 px noise, 40 points: f error RMS over seeds " << observed << " px, predicted sigma " << predicted
                                                                    << " px");
  CHECK(observed >= 0.6 * predicted);
  CHECK(observed <= 1.6 * predicted);
}

TEST_CASE("Distortion: k1 = -0.2 is recovered and the RMS falls to the noise level; a pinhole fit cannot") {
  constexpr double kNoisePx = 0.5;
  constexpr double kTrueK1 = -0.2;
  for (const bool planar : {false, true}) {
    SyntheticSceneOptions scene = DefaultScene();
    if (planar) scene.principal_point_offset_px = {0.0, 0.0};
    const Camera truth = MakeLookAtCamera(scene);
    SceneSpec spec;
    spec.planar = planar;
    spec.num_points = 80;
    spec.extent = 3.0;
    spec.noise_px = kNoisePx;
    spec.k1 = kTrueK1;
    spec.seed = 3;
    const auto points = MakePoints(truth, spec, scene);
    DltCalibrationOptions options = OptionsFor(truth);
    CAPTURE(planar);

    const DltCalibrationSummary pinhole = CalibrateFromPoints(points, options);
    REQUIRE_MESSAGE(pinhole.IsUsable(), pinhole.message);
    options.radial_distortion_terms = 1;
    const DltCalibrationSummary one = CalibrateFromPoints(points, options);
    REQUIRE_MESSAGE(one.IsUsable(), one.message);
    options.radial_distortion_terms = 2;
    const DltCalibrationSummary two = CalibrateFromPoints(points, options);
    REQUIRE_MESSAGE(two.IsUsable(), two.message);

    const double noise_rms = kNoisePx * std::sqrt(2.0);  // RMS of a 2D residual
    CAPTURE(pinhole.reprojection_rms_px);
    CAPTURE(one.reprojection_rms_px);
    CAPTURE(two.reprojection_rms_px);
    CAPTURE(one.k1);
    CAPTURE(one.k1_std);
    CAPTURE(one.camera.focal_px);
    // The start of the distortion fit (k1 = 0, the linear camera) is far from the answer.
    CHECK(one.initial_rms_px > 5.0 * noise_rms);
    CHECK(pinhole.reprojection_rms_px > 3.0 * noise_rms);
    CHECK(one.reprojection_rms_px <= 1.1 * noise_rms);
    CHECK(two.reprojection_rms_px <= 1.1 * noise_rms);
    // k1 within 4 sigma of its covariance, and that sigma small: 0.01 absolute.
    CHECK(std::abs(one.k1 - kTrueK1) <= 4.0 * one.k1_std);
    CHECK(one.k1_std <= 0.01);
    CHECK(std::abs(one.camera.focal_px - truth.focal_px) <= 4.0 * one.focal_std_px);
    const std::string label = planar ? "planar" : "non-planar";
    MESSAGE(label << " k1 = -0.2, 0.5 px noise: k1 = " << one.k1 << " +- " << one.k1_std << ", RMS pinhole "
                  << pinhole.reprojection_rms_px << " px, k1 " << one.reprojection_rms_px << " px, k1+k2 "
                  << two.reprojection_rms_px << " px; f error " << one.camera.focal_px - truth.focal_px << " px");
  }
}

TEST_CASE("Distortion: noise-free k1, k2 are recovered exactly from a pinhole start") {
  // The linear step is pinhole, so the refinement starts away from the answer (checked) and
  // must converge to it: this exercises the Levenberg-Marquardt loop and its Jacobian.
  constexpr double kTrueK1 = -0.2, kTrueK2 = 0.05;
  for (const bool planar : {false, true}) {
    SyntheticSceneOptions scene = DefaultScene();
    if (planar) scene.principal_point_offset_px = {0.0, 0.0};
    const Camera truth = MakeLookAtCamera(scene);
    SceneSpec spec;
    spec.planar = planar;
    spec.num_points = 60;
    spec.extent = 3.0;
    spec.k1 = kTrueK1;
    spec.k2 = kTrueK2;
    const auto points = MakePoints(truth, spec, scene);
    DltCalibrationOptions options = OptionsFor(truth);
    options.radial_distortion_terms = 2;
    const DltCalibrationSummary s = CalibrateFromPoints(points, options);
    REQUIRE_MESSAGE(s.IsUsable(), s.message);
    CAPTURE(planar);
    CAPTURE(s.initial_rms_px);
    CAPTURE(s.reprojection_rms_px);
    CAPTURE(s.iterations);
    CAPTURE(s.k1);
    CAPTURE(s.k2);
    CHECK(s.initial_rms_px > 1.0);
    CHECK(s.reprojection_rms_px <= 1e-6);
    CHECK(std::abs(s.k1 - kTrueK1) <= kExactRelative);
    CHECK(std::abs(s.k2 - kTrueK2) <= kExactRelative);
    const std::string label = planar ? "planar" : "non-planar";
    MESSAGE(label << std::string(" noise-free k1, k2: errors ") << s.k1 - kTrueK1 << ", " << s.k2 - kTrueK2
                  << ", f error " << s.camera.focal_px - truth.focal_px << " px, " << s.iterations
                  << " iterations from RMS " << s.initial_rms_px << " px");
    CheckCameraExact(s.camera, truth);
  }
}

TEST_CASE("DLT: a principal point held at the image centre is kept, and exact when true") {
  SyntheticSceneOptions scene = DefaultScene();
  scene.principal_point_offset_px = {0.0, 0.0};
  const Camera truth = MakeLookAtCamera(scene);
  SceneSpec spec;
  spec.noise_px = 0.0;
  const auto points = MakePoints(truth, spec, scene);
  DltCalibrationOptions options = OptionsFor(truth);
  options.principal_point_mode = PrincipalPointMode::kImageCenter;
  const DltCalibrationSummary s = CalibrateFromPoints(points, options);
  REQUIRE_MESSAGE(s.IsUsable(), s.message);
  CHECK(s.camera.principal_point_px == Eigen::Vector2d((truth.width_px - 1) / 2.0, (truth.height_px - 1) / 2.0));
  CHECK(s.principal_point_std_px == Eigen::Vector2d::Zero());
  CheckCameraExact(s.camera, truth);
}

TEST_CASE("DLT: scaling the 3D points by 1e-3 and 1e3 gives the same K and a scaled t") {
  // The problem is invariant to the world scale; with the same pixel noise the solutions agree
  // up to the solver's convergence tolerance.
  constexpr double kSameRelative = 1e-7;
  for (const bool planar : {false, true}) {
    std::vector<DltCalibrationSummary> results;
    for (const double scale : {1.0, 1e-3, 1e3}) {
      SyntheticSceneOptions scene = DefaultScene(scale);
      scene.principal_point_offset_px = planar ? Eigen::Vector2d(0.0, 0.0) : Eigen::Vector2d(12.0, -9.0);
      const Camera truth = MakeLookAtCamera(scene);
      SceneSpec spec;
      spec.planar = planar;
      spec.noise_px = 0.5;
      spec.scale = scale;
      const auto points = MakePoints(truth, spec, scene);
      DltCalibrationOptions options = OptionsFor(truth);
      options.radial_distortion_terms = 1;
      const DltCalibrationSummary s = CalibrateFromPoints(points, options);
      REQUIRE_MESSAGE(s.IsUsable(), s.message);
      results.push_back(s);
      const double t_ratio =
          s.camera.cam_from_world_translation.norm() / (results[0].camera.cam_from_world_translation.norm() * scale);
      CAPTURE(planar);
      CAPTURE(scale);
      CAPTURE(s.camera.focal_px);
      CAPTURE(results[0].camera.focal_px);
      CHECK(std::abs(s.camera.focal_px - results[0].camera.focal_px) <= kSameRelative * results[0].camera.focal_px);
      CHECK((s.camera.principal_point_px - results[0].camera.principal_point_px).norm() <=
            kSameRelative * results[0].camera.focal_px);
      CHECK(std::abs(s.k1 - results[0].k1) <= kSameRelative);
      CHECK(std::abs(t_ratio - 1.0) <= kSameRelative);
    }
  }
}

TEST_CASE("Degenerate input gives a clear error") {
  const Camera truth = MakeLookAtCamera(DefaultScene());
  const auto points = MakePoints(truth, {}, DefaultScene());
  const DltCalibrationOptions options = OptionsFor(truth);
  auto expect_failure = [&](const std::vector<PointCorrespondence>& input, const DltCalibrationOptions& o,
                            const std::string& needle) {
    const DltCalibrationSummary s = CalibrateFromPoints(input, o);
    CAPTURE(s.message);
    CHECK_FALSE(s.IsUsable());
    CHECK_FALSE(s.IsUsable());
    CHECK(s.message.find(needle) != std::string::npos);
  };
  expect_failure({points.begin(), points.begin() + 3}, options, "got 3");
  expect_failure({points.begin(), points.begin() + 5}, options, "6 or more");
  {
    auto bad = points;
    bad[4].uv_px.x() = std::nan("");
    expect_failure(bad, options, "point 4");
  }
  {
    std::vector<PointCorrespondence> line;
    for (int i = 0; i < 10; ++i) {
      PointCorrespondence c;
      c.xyz = Eigen::Vector3d(2.0, 1.5, 1.0) + 0.3 * i * Eigen::Vector3d(1.0, 0.5, 0.2);
      c.uv_px = truth.Project(c.xyz);
      line.push_back(c);
    }
    expect_failure(line, options, "one line");
  }
  {
    // Four coplanar points, three of them on one line: no homography.
    std::vector<PointCorrespondence> plane;
    for (const Eigen::Vector3d xyz :
         {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(2, 0, 0), Eigen::Vector3d(0, 1, 0)}) {
      PointCorrespondence c;
      c.xyz = xyz;
      c.uv_px = truth.Project(xyz);
      plane.push_back(c);
    }
    expect_failure(plane, options, "homography");
  }
  {
    // A plane seen exactly fronto-parallel: the focal length is not observable.
    SyntheticSceneOptions scene = DefaultScene();
    scene.principal_point_offset_px = {0.0, 0.0};
    Camera frontal = MakeLookAtCamera(scene);
    frontal.SetPose(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.0, 0.0, -10.0));
    std::vector<PointCorrespondence> plane;
    for (int i = 0; i < 5; ++i)
      for (int j = 0; j < 4; ++j) {
        PointCorrespondence c;
        c.xyz = Eigen::Vector3d(i - 2.0, j - 1.5, 0.0);
        c.uv_px = frontal.Project(c.xyz);
        plane.push_back(c);
      }
    expect_failure(plane, options, "fronto-parallel");
  }
  {
    DltCalibrationOptions o = options;
    o.width_px = 0;
    expect_failure(points, o, "image size");
    o = options;
    o.refine = false;
    o.radial_distortion_terms = 1;
    expect_failure(points, o, "refine");
    o = options;
    o.square_pixels_zero_skew = false;
    expect_failure(points, o, "square pixels");
  }
}

TEST_CASE("Warnings: nearly coplanar points, a point behind the camera") {
  const Camera truth = MakeLookAtCamera(DefaultScene());
  {
    SceneSpec spec;
    spec.planar = true;
    spec.num_points = 30;
    auto points = MakePoints(truth, spec, DefaultScene());
    // Lift points off the plane by up to 0.5 % of its extent, keeping their exact pixels.
    for (size_t i = 0; i < points.size(); ++i) {
      points[i].xyz.z() += 0.01 * ((i % 3) - 1.0);
      points[i].uv_px = truth.Project(points[i].xyz);
    }
    const DltCalibrationSummary s = CalibrateFromPoints(points, OptionsFor(truth));
    REQUIRE_MESSAGE(s.IsUsable(), s.message);
    CHECK_FALSE(s.planar);
    REQUIRE(!s.warnings.empty());
    CHECK(s.warnings[0].find("nearly coplanar") != std::string::npos);
  }
  {
    auto points = MakePoints(truth, {}, DefaultScene());
    // A point behind the camera still projects (through the centre) to a pixel.
    PointCorrespondence behind;
    behind.xyz = truth.CenterInWorld() - 3.0 * (Eigen::Vector3d(2.0, 1.5, 1.0) - truth.CenterInWorld());
    behind.uv_px = truth.Project(behind.xyz);
    points.push_back(behind);
    const DltCalibrationSummary s = CalibrateFromPoints(points, OptionsFor(truth));
    REQUIRE_MESSAGE(s.IsUsable(), s.message);
    bool warned = false;
    for (const auto& w : s.warnings) warned = warned || w.find("behind the camera") != std::string::npos;
    CHECK(warned);
  }
}

TEST_CASE("JSON adapter: round trip and malformed input") {
  const Camera truth = MakeLookAtCamera(DefaultScene());
  SceneSpec spec;
  spec.k1 = -0.1;
  const auto points = MakePoints(truth, spec, DefaultScene());
  nlohmann::json doc;
  doc["image_size"] = {truth.width_px, truth.height_px};
  doc["distortion"] = 1;
  doc["points"] = nlohmann::json::array();
  for (const auto& p : points)
    doc["points"].push_back({{"xyz", {p.xyz.x(), p.xyz.y(), p.xyz.z()}}, {"uv", {p.uv_px.x(), p.uv_px.y()}}});
  const CalibrateIoResult result = CalibratePointsJson(doc.dump());
  REQUIRE_MESSAGE(result.ok(), result.error);
  const nlohmann::json out = nlohmann::json::parse(result.json);
  Eigen::Matrix3d k, r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      k(i, j) = out["K"][i][j].get<double>();
      r(i, j) = out["R"][i][j].get<double>();
    }
  const Eigen::Vector3d t(out["t"][0].get<double>(), out["t"][1].get<double>(), out["t"][2].get<double>());
  CHECK((k - truth.K()).norm() <= kExactRelative * truth.focal_px);
  CHECK((r - truth.cam_from_world_rotation).norm() <= kExactRelative);
  CHECK((t - truth.cam_from_world_translation).norm() <= kExactRelative * truth.cam_from_world_translation.norm());
  CHECK(std::abs(out["focal_px"].get<double>() - truth.focal_px) <= kExactRelative * truth.focal_px);
  CHECK(std::abs(out["distortion"][0].get<double>() - spec.k1) <= 1e-9);
  CHECK(out["distortion"][1].get<double>() == 0.0);
  CHECK(out["residuals_px"].size() == points.size());
  CHECK(out["reprojection_rms_px"].get<double>() <= 1e-6);
  CHECK(out["warnings"].is_array());
  CHECK(out["principal_point"].size() == 2);
  CHECK(out["focal_fixed"].get<bool>() == false);

  // A known focal length, off the truth by 5 %: held exactly (the pose then absorbs it).
  nlohmann::json known = doc;
  known["focal_px"] = 1.05 * truth.focal_px;
  const CalibrateIoResult held = CalibratePointsJson(known.dump());
  REQUIRE_MESSAGE(held.ok(), held.error);
  const nlohmann::json held_out = nlohmann::json::parse(held.json);
  CHECK(held_out["focal_px"].get<double>() == 1.05 * truth.focal_px);
  CHECK(held_out["focal_fixed"].get<bool>());
  CHECK(held_out["focal_std_px"].get<double>() == 0.0);

  auto expect_error = [](const std::string& text, const std::string& needle) {
    const CalibrateIoResult r = CalibratePointsJson(text);
    CAPTURE(text);
    CAPTURE(r.error);
    CHECK_FALSE(r.ok());
    CHECK(r.error.find(needle) != std::string::npos);
  };
  expect_error("{not json", "malformed JSON");
  {
    nlohmann::json bad_focal = doc;
    bad_focal["focal_px"] = -3.0;
    expect_error(bad_focal.dump(), "\"focal_px\" must be a positive number");
  }
  expect_error("[]", "JSON object");
  expect_error(R"({"points": []})", "image_size");
  expect_error(R"({"image_size": [640], "points": []})", "image_size");
  expect_error(R"({"image_size": [640, 480]})", "missing \"points\"");
  expect_error(R"({"image_size": [640, 480], "points": {}})", "must be an array");
  expect_error(R"({"image_size": [640, 480], "points": [{"xyz": [1, 2], "uv": [1, 2]}]})", "points[0]: \"xyz\"");
  expect_error(R"({"image_size": [640, 480], "points": [{"xyz": [1, 2, 3]}]})", "points[0]: \"uv\"");
  expect_error(R"({"image_size": [640, 480], "points": [{"xyz": [1, 2, "3"], "uv": [1, 2]}]})", "\"xyz\"");
  expect_error(R"({"image_size": [640, 480], "points": [1]})", "points[0] must be an object");
  nlohmann::json bad = doc;
  bad["distortion"] = 3;
  expect_error(bad.dump(), "\"distortion\"");
  bad = doc;
  bad["points"] = nlohmann::json::array({doc["points"][0], doc["points"][1], doc["points"][2]});
  expect_error(bad.dump(), "calibration failed");
  bad = doc;
  bad["principal_point"] = "middle";
  expect_error(bad.dump(), "\"principal_point\"");
  {
    // A fixed principal point is held: the result keeps it exactly.
    nlohmann::json fixed = doc;
    fixed["principal_point"] = {500.0, 400.0};
    const CalibrateIoResult r = CalibratePointsJson(fixed.dump());
    REQUIRE_MESSAGE(r.ok(), r.error);
    const nlohmann::json o = nlohmann::json::parse(r.json);
    CHECK(o["principal_point"][0].get<double>() == 500.0);
    CHECK(o["principal_point"][1].get<double>() == 400.0);
    CHECK(o["reprojection_rms_px"].get<double>() > 0.1);
  }
  const CalibrateIoResult missing = CalibratePointsFile("/nonexistent/points.json");
  CHECK_FALSE(missing.ok());
  CHECK(missing.error.find("cannot open") != std::string::npos);
}

// Issue 25: a known focal length of 1e-300, 1e200 or 1e308 px crashed `calibrate --points`
// (SIGSEGV in the SVD of the pose's translation). Refused where it enters, named, with the
// range of camera_checks.h; on both paths (points in a volume and on a plane).
TEST_CASE("JSON adapter: a known focal length outside any lens is refused by name") {
  const Camera truth = MakeLookAtCamera(DefaultScene());
  const auto volume = MakePoints(truth, {}, DefaultScene());
  SceneSpec planar;
  planar.planar = true;
  const auto plane = MakePoints(truth, planar, DefaultScene());
  for (const auto* points : {&volume, &plane}) {
    nlohmann::json doc;
    doc["image_size"] = {truth.width_px, truth.height_px};
    doc["points"] = nlohmann::json::array();
    for (const auto& p : *points)
      doc["points"].push_back({{"xyz", {p.xyz.x(), p.xyz.y(), p.xyz.z()}}, {"uv", {p.uv_px.x(), p.uv_px.y()}}});
    const double diagonal = std::hypot(truth.width_px, truth.height_px);
    for (const double focal_px : {1e-300, 1e-5, 0.01 * diagonal, 101.0 * diagonal, 1e200, 1e308}) {
      nlohmann::json bad = doc;
      bad["focal_px"] = focal_px;
      const CalibrateIoResult r = CalibratePointsJson(bad.dump());
      CAPTURE(focal_px);
      CAPTURE(r.error);
      CHECK_FALSE(r.ok());
      CHECK(r.json.empty());
      CHECK(r.error.find("\"focal_px\"") != std::string::npos);
      CHECK(r.error.find("image diagonals") != std::string::npos);
    }
    // The true focal length is a lens: the refusal is of the number, not of the points.
    nlohmann::json edge = doc;
    edge["focal_px"] = truth.focal_px;
    const CalibrateIoResult fine = CalibratePointsJson(edge.dump());
    CHECK_MESSAGE(fine.ok(), fine.error);
  }
}

// The same numbers reaching the estimator without the adapter: its Check() refuses them, and
// the pose's linear algebra refuses non-finite rays instead of handing them to the SVD.
TEST_CASE("known focal length: options outside any lens fail Check, the solve returns a message") {
  const Camera truth = MakeLookAtCamera(DefaultScene());
  const auto points = MakePoints(truth, {}, DefaultScene());
  for (const double focal_px : {1e-300, 1e200, 1e308}) {
    DltCalibrationOptions options = OptionsFor(truth);
    options.fixed_focal_px = focal_px;
    std::string error;
    CHECK_FALSE(options.Check(&error));
    CHECK(error.find("fixed_focal_px") != std::string::npos);
    const DltCalibrationSummary s = CalibrateFromPoints(points, options);
    CAPTURE(focal_px);
    CHECK_FALSE(s.IsUsable());
    CHECK(s.termination == SolverTermination::kInvalidInput);
  }
  DltCalibrationOptions prior = OptionsFor(truth);
  prior.focal_prior_px = truth.focal_px;
  prior.focal_prior_std_px = 1e-300;
  std::string error;
  CHECK_FALSE(prior.Check(&error));
  CHECK(error.find("standard deviation") != std::string::npos);
}

// ---- Known focal length (a calibrated camera's pose) and the focal prior ----

// Pose errors of a camera against the truth: rotation (deg) and |t - t_true| / |t_true|.
std::pair<double, double> PoseErrors(const Camera& got, const Camera& want) {
  return {RotationErrorDeg(got.cam_from_world_rotation, want.cam_from_world_rotation),
          (got.cam_from_world_translation - want.cam_from_world_translation).norm() /
              want.cam_from_world_translation.norm()};
}

// A 5 x 4 grid on the plane through the look-at point facing the camera (fronto-parallel):
// one view of it does not determine the focal length.
std::vector<PointCorrespondence> FrontoParallelGrid(const Camera& camera, const SyntheticSceneOptions& scene) {
  const Eigen::Matrix3d& r = camera.cam_from_world_rotation;
  std::vector<PointCorrespondence> points;
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 4; ++j) {
      PointCorrespondence c;
      c.xyz = scene.look_at + (i - 2.0) * 0.8 * r.row(0).transpose() + (j - 1.5) * 0.8 * r.row(1).transpose();
      c.uv_px = camera.Project(c.xyz);
      points.push_back(c);
    }
  return points;
}

TEST_CASE("Known focal: noise-free pose exact from 6 and 40 points, and on a tilted plane") {
  SyntheticSceneOptions scene = DefaultScene();
  const Camera truth = MakeLookAtCamera(scene);
  for (const int num_points : {40, 6}) {
    CAPTURE(num_points);
    SceneSpec spec;
    spec.num_points = num_points;
    spec.seed = 7;
    const auto points = MakePoints(truth, spec, scene);
    DltCalibrationOptions options = OptionsFor(truth);
    options.fixed_focal_px = truth.focal_px;
    const DltCalibrationSummary s = CalibrateFromPoints(points, options);
    REQUIRE_MESSAGE(s.IsUsable(), s.message);
    CHECK(s.focal_fixed);
    CHECK_FALSE(s.planar);
    CHECK(s.camera.focal_px == truth.focal_px);  // held, not refitted
    CHECK(s.focal_std_px == 0.0);
    CheckCameraExact(s.camera, truth);
    CHECK(s.message.find("focal length known") != std::string::npos);
  }
  // The plane: the principal point held where it truly is.
  SceneSpec spec;
  spec.planar = true;
  spec.num_points = 4;
  const auto points = MakePoints(truth, spec, scene);
  DltCalibrationOptions options = OptionsFor(truth);
  options.fixed_focal_px = truth.focal_px;
  options.principal_point_mode = PrincipalPointMode::kFixed;
  options.fixed_principal_point_px = truth.principal_point_px;
  const DltCalibrationSummary s = CalibrateFromPoints(points, options);
  REQUIRE_MESSAGE(s.IsUsable(), s.message);
  CHECK(s.planar);
  CheckCameraExact(s.camera, truth);
}

TEST_CASE("Known focal: a fronto-parallel plane the free DLT refuses gives the exact pose; a prior starts it") {
  SyntheticSceneOptions scene = DefaultScene();
  scene.principal_point_offset_px = {0.0, 0.0};
  const Camera truth = MakeLookAtCamera(scene);
  const auto points = FrontoParallelGrid(truth, scene);
  DltCalibrationOptions options = OptionsFor(truth);
  const DltCalibrationSummary free_focal = CalibrateFromPoints(points, options);
  CAPTURE(free_focal.message);
  CHECK_FALSE(free_focal.IsUsable());
  CHECK(free_focal.message.find("undetermined") != std::string::npos);

  options.fixed_focal_px = truth.focal_px;
  const DltCalibrationSummary fixed = CalibrateFromPoints(points, options);
  REQUIRE_MESSAGE(fixed.IsUsable(), fixed.message);
  CHECK(fixed.planar);
  CheckCameraExact(fixed.camera, truth);

  // A prior 10 % off with a wide std: the plane says nothing of f, so f stays near the prior,
  // but the camera is usable (a warning says where f came from).
  options.fixed_focal_px = 0.0;
  options.focal_prior_px = 1.1 * truth.focal_px;
  options.focal_prior_std_px = 200.0;
  const DltCalibrationSummary with_prior = CalibrateFromPoints(points, options);
  REQUIRE_MESSAGE(with_prior.IsUsable(), with_prior.message);
  CHECK(with_prior.focal_prior_used);
  CHECK_FALSE(with_prior.warnings.empty());
  CAPTURE(with_prior.camera.focal_px);
  CHECK(std::abs(with_prior.camera.focal_px - options.focal_prior_px) < 0.05 * truth.focal_px);
}

TEST_CASE("Known focal with 0.5 px noise: pose errors below the free-focal DLT's over 40 seeds") {
  // Extent 1 (points in the image's middle third, f weakly determined): with f free, its error
  // trades against the camera's distance along the axis; holding the true f removes that.
  // Both hold the true principal point, so the comparison is about f alone.
  // Measured as the RMS over seeds of the rotation error (deg) and the relative t error.
  constexpr double kNoisePx = 0.5;
  constexpr int kSeeds = 40;
  const SyntheticSceneOptions scene = DefaultScene();
  const Camera truth = MakeLookAtCamera(scene);
  for (const bool planar : {false, true}) {
    CAPTURE(planar);
    double sq_rot_free = 0.0, sq_t_free = 0.0, sq_rot_fixed = 0.0, sq_t_fixed = 0.0, sq_rms_fixed = 0.0;
    int moved = 0;
    for (int seed = 1; seed <= kSeeds; ++seed) {
      SceneSpec spec;
      spec.noise_px = kNoisePx;
      spec.planar = planar;
      spec.seed = seed;
      const auto points = MakePoints(truth, spec, scene);
      DltCalibrationOptions options = OptionsFor(truth);
      options.principal_point_mode = PrincipalPointMode::kFixed;  // both hold the true one
      options.fixed_principal_point_px = truth.principal_point_px;
      const DltCalibrationSummary free_focal = CalibrateFromPoints(points, options);
      options.fixed_focal_px = truth.focal_px;
      const DltCalibrationSummary fixed = CalibrateFromPoints(points, options);
      REQUIRE_MESSAGE(free_focal.IsUsable(), free_focal.message);
      REQUIRE_MESSAGE(fixed.IsUsable(), fixed.message);
      CHECK(fixed.camera.focal_px == truth.focal_px);
      const auto [rot_free, t_free] = PoseErrors(free_focal.camera, truth);
      const auto [rot_fixed, t_fixed] = PoseErrors(fixed.camera, truth);
      sq_rot_free += rot_free * rot_free;
      sq_t_free += t_free * t_free;
      sq_rot_fixed += rot_fixed * rot_fixed;
      sq_t_fixed += t_fixed * t_fixed;
      sq_rms_fixed += fixed.reprojection_rms_px * fixed.reprojection_rms_px;
      if (fixed.iterations >= 1) ++moved;  // the refinement moved off the linear start
    }
    const double rot_free = std::sqrt(sq_rot_free / kSeeds), t_free = std::sqrt(sq_t_free / kSeeds);
    const double rot_fixed = std::sqrt(sq_rot_fixed / kSeeds), t_fixed = std::sqrt(sq_t_fixed / kSeeds);
    const double rms_fixed = std::sqrt(sq_rms_fixed / kSeeds);
    MESSAGE(std::string(planar ? "plane" : "volume")
            << ", 0.5 px, 40 seeds: rotation error RMS free f " << rot_free << " deg, known f " << rot_fixed
            << " deg; t error RMS free f " << t_free << ", known f " << t_fixed << "; known-f reprojection RMS "
            << rms_fixed << " px");
    CHECK(moved == kSeeds);
    // The position improves several-fold; the rotation hardly depends on f (it follows from the
    // directions between points), so it only has to stay as good.
    CHECK(t_fixed < 0.5 * t_free);
    CHECK(rot_fixed < 1.1 * rot_free);
    // 2-D residual RMS of a right model: about sqrt(2) sigma.
    CHECK(rms_fixed < 1.5 * std::sqrt(2.0) * kNoisePx);
  }
}

TEST_CASE("Focal prior with 0.5 px noise: the focal error shrinks toward the prior's weight") {
  // A true-centred prior of std 5 px against the points' own ~sigma_f: the posterior std is
  // below both, and the observed error RMS over 40 seeds follows it.
  constexpr double kNoisePx = 0.5;
  constexpr int kSeeds = 40;
  const SyntheticSceneOptions scene = DefaultScene();
  const Camera truth = MakeLookAtCamera(scene);
  double sq_free = 0.0, sq_prior = 0.0, sum_std_prior = 0.0;
  for (int seed = 1; seed <= kSeeds; ++seed) {
    SceneSpec spec;
    spec.noise_px = kNoisePx;
    spec.seed = seed;
    const auto points = MakePoints(truth, spec, scene);
    DltCalibrationOptions options = OptionsFor(truth);
    const DltCalibrationSummary free_focal = CalibrateFromPoints(points, options);
    options.focal_prior_px = truth.focal_px;
    options.focal_prior_std_px = 5.0;
    options.pixel_noise_px = kNoisePx;
    const DltCalibrationSummary prior = CalibrateFromPoints(points, options);
    REQUIRE_MESSAGE(prior.IsUsable(), prior.message);
    CHECK(prior.focal_prior_used);
    CHECK(prior.focal_std_px < free_focal.focal_std_px);
    sq_free += std::pow(free_focal.camera.focal_px - truth.focal_px, 2);
    sq_prior += std::pow(prior.camera.focal_px - truth.focal_px, 2);
    sum_std_prior += prior.focal_std_px;
  }
  const double rms_free = std::sqrt(sq_free / kSeeds), rms_prior = std::sqrt(sq_prior / kSeeds);
  MESSAGE("focal prior 5 px, 0.5 px noise: f error RMS free " << rms_free << " px, with prior " << rms_prior
                                                              << " px (mean predicted std " << sum_std_prior / kSeeds
                                                              << " px)");
  CHECK(rms_prior < rms_free);
  CHECK(rms_prior < 5.0);
}

TEST_CASE("Known focal and prior: invalid values are rejected") {
  const Camera truth = MakeLookAtCamera(DefaultScene());
  const auto points = MakePoints(truth, {}, DefaultScene());
  for (const int which : {0, 1, 2}) {
    DltCalibrationOptions options = OptionsFor(truth);
    if (which == 0) options.fixed_focal_px = -1.0;
    if (which == 1) options.focal_prior_std_px = std::nan("");
    if (which == 2) options.pixel_noise_px = 0.0;
    const DltCalibrationSummary s = CalibrateFromPoints(points, options);
    CAPTURE(s.message);
    CHECK_FALSE(s.IsUsable());
    CHECK(s.message.find("invalid options") == 0);
  }
}

}  // namespace facet
