// Self-calibration of 3 or more views (core/estimators/self_calibration.h) on synthetic scenes: random
// points in a box seen by look-at cameras placed around it, tracks of their pixels with
// optional noise and wrong observations. Recovered cameras and points are compared with the
// truth after a similarity alignment (AlignSimilarity, core/estimators/projective_upgrade.h).
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "core/estimators/projective_bundle_adjustment.h"
#include "core/estimators/self_calibration.h"
#include "tests/synthetic_scene.h"

namespace facet {
namespace {

// Noise-free numerics after the bundle adjustment (relative).
constexpr double kExactTol = 1e-9;
// The linear absolute dual quadric with exact constraints, before any adjustment (relative).
constexpr double kLinearTol = 1e-6;

struct MultiViewScene {
  std::vector<Camera> cameras;
  std::vector<Eigen::Vector3d> points;
  std::vector<SelfCalibrationView> views;
  std::vector<Track> tracks;
};

struct MultiViewOptions {
  int num_views = 5;
  int num_points = 150;
  double noise_px = 0.0;
  std::vector<double> focal_px = {900.0};  // one per view, or one for all
  Eigen::Vector2d principal_point_offset_px = Eigen::Vector2d::Zero();
  double outlier_fraction = 0.0;  // tracks with one observation moved 20 to 60 px
  unsigned seed = 11;
};

MultiViewScene MakeMultiViewScene(const MultiViewOptions& o) {
  MultiViewScene s;
  std::mt19937 rng(o.seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::uniform_real_distribution<double> ux(-1.0, 5.0), uy(-1.0, 4.0), uz(0.0, 3.0), unit(0.0, 1.0);
  for (int v = 0; v < o.num_views; ++v) {
    testing::SyntheticSceneOptions c;
    c.focal_px = o.focal_px[std::min<size_t>(v, o.focal_px.size() - 1)];
    c.principal_point_offset_px = o.principal_point_offset_px;
    // On an arc of 150 degrees around the box, at varying heights and rolls.
    const double angle = -1.2 + 2.6 * v / std::max(1, o.num_views - 1);
    c.camera_center = Eigen::Vector3d(2.0 + 10.0 * std::cos(angle), 1.5 + 10.0 * std::sin(angle), 4.0 + 2.0 * (v % 3));
    c.look_at = {2.0 + 0.3 * (v % 2), 1.5, 1.2};
    c.roll_deg = 5.0 * std::sin(1.7 * v);
    s.cameras.push_back(testing::MakeLookAtCamera(c));
    s.views.push_back({c.width_px, c.height_px, 0.0});
  }
  while (static_cast<int>(s.points.size()) < o.num_points) {
    const Eigen::Vector3d x{ux(rng), uy(rng), uz(rng)};
    Track track;
    for (int v = 0; v < o.num_views; ++v) {
      const Camera& c = s.cameras[v];
      const Eigen::Vector2d uv = c.Project(x);
      if (c.CamFromWorld(x).z() <= 0 || uv.x() < 0 || uv.y() < 0 || uv.x() > c.width_px || uv.y() > c.height_px)
        continue;
      track.push_back({v, uv + o.noise_px * Eigen::Vector2d{noise(rng), noise(rng)}});
    }
    if (track.size() < 2) continue;
    if (unit(rng) < o.outlier_fraction) {
      const double angle = 2 * M_PI * unit(rng), distance = 20.0 + 40.0 * unit(rng);
      track[rng() % track.size()].uv_px += distance * Eigen::Vector2d(std::cos(angle), std::sin(angle));
    }
    s.points.push_back(x);
    s.tracks.push_back(track);
  }
  return s;
}

double RotationErrorDeg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a * b.transpose()).angle() * 180.0 / M_PI;
}

struct Errors {
  double max_focal_rel = 0.0;
  double max_rotation_deg = 0.0;  // relative rotations to view 0
  double structure_rel = 0.0;     // aligned points and centres, over the scene extent
};

Errors Compare(const MultiViewScene& s, const SelfCalibrationSummary& r) {
  Errors e;
  std::vector<Eigen::Vector3d> a, b;
  for (size_t v = 0; v < s.cameras.size(); ++v) {
    REQUIRE(r.registered[v]);
    e.max_focal_rel = std::max(e.max_focal_rel, std::abs(r.cameras[v].focal_px / s.cameras[v].focal_px - 1.0));
    const Eigen::Matrix3d rel_true =
        s.cameras[v].cam_from_world_rotation * s.cameras[0].cam_from_world_rotation.transpose();
    const Eigen::Matrix3d rel_est =
        r.cameras[v].cam_from_world_rotation * r.cameras[0].cam_from_world_rotation.transpose();
    e.max_rotation_deg = std::max(e.max_rotation_deg, RotationErrorDeg(rel_true, rel_est));
    a.push_back(r.cameras[v].CenterInWorld());
    b.push_back(s.cameras[v].CenterInWorld());
  }
  for (size_t t = 0; t < s.points.size(); ++t)
    if (r.triangulated[t]) {
      a.push_back(r.points[t]);
      b.push_back(s.points[t]);
    }
  Similarity3d sim;
  REQUIRE(AlignSimilarity(a, b, &sim));
  double extent = 0.0;
  for (size_t i = 0; i < a.size(); ++i) {
    e.structure_rel = std::max(e.structure_rel, (sim * a[i] - b[i]).norm());
    extent = std::max(extent, (b[i] - b[0]).norm());
  }
  e.structure_rel /= extent;
  return e;
}

TEST_CASE("noise-free, principal point at the centre: the linear quadric is exact and the adjustment keeps it") {
  const MultiViewScene s = MakeMultiViewScene({});
  SelfCalibrationOptions options;
  options.focal_weight = 0.0;  // only the exact constraints
  options.bundle_adjust = false;
  const SelfCalibrationSummary linear = SelfCalibrate(s.views, s.tracks, options);
  REQUIRE_MESSAGE(linear.IsUsable(), linear.message);
  const Errors linear_errors = Compare(s, linear);
  CAPTURE(linear.message);
  CAPTURE(linear_errors.max_focal_rel);
  CAPTURE(linear_errors.max_rotation_deg);
  CAPTURE(linear_errors.structure_rel);
  CHECK(linear.warnings.empty());
  CHECK(linear_errors.max_focal_rel < kLinearTol);
  CHECK(linear_errors.structure_rel < kLinearTol);

  options.bundle_adjust = true;
  const SelfCalibrationSummary full = SelfCalibrate(s.views, s.tracks, options);
  REQUIRE_MESSAGE(full.IsUsable(), full.message);
  const Errors e = Compare(s, full);
  CAPTURE(full.message);
  CAPTURE(e.max_focal_rel);
  CAPTURE(e.structure_rel);
  CHECK(e.max_focal_rel < kExactTol);
  CHECK(e.max_rotation_deg < kExactTol * 180 / M_PI);
  CHECK(e.structure_rel < kExactTol);
}

TEST_CASE("noise-free, principal point off-centre: the adjustment recovers focal and principal point exactly") {
  MultiViewOptions o;
  o.principal_point_offset_px = {12.0, -9.0};
  o.num_views = 6;
  const MultiViewScene s = MakeMultiViewScene(o);
  SelfCalibrationOptions options;
  options.principal_point_mode = PrincipalPointMode::kSolve;
  options.principal_point_prior_std = 0.0;  // the unbiased solve (a prior pulls towards the centre)
  const SelfCalibrationSummary r = SelfCalibrate(s.views, s.tracks, options);
  REQUIRE_MESSAGE(r.IsUsable(), r.message);
  const Errors e = Compare(s, r);
  const double linear_rel = std::abs(r.linear_focal_px[0] / s.cameras[0].focal_px - 1.0);
  const double pp_error = (r.cameras[0].principal_point_px - s.cameras[0].principal_point_px).norm();
  CAPTURE(r.message);
  CAPTURE(linear_rel);
  CAPTURE(e.max_focal_rel);
  CAPTURE(pp_error);
  CAPTURE(e.structure_rel);
  CHECK(linear_rel > 1e-6);  // the start (principal point assumed at the centre) is not the answer
  CHECK(linear_rel < 0.1);
  CHECK(e.max_focal_rel < kExactTol);
  CHECK(pp_error < kExactTol * s.cameras[0].focal_px);
  CHECK(e.structure_rel < kExactTol);
}

TEST_CASE("noise-free, one focal length per view (zoom): each is recovered") {
  MultiViewOptions o;
  o.num_views = 6;
  o.focal_px = {800.0, 950.0, 1100.0, 870.0, 1250.0, 1000.0};
  const MultiViewScene s = MakeMultiViewScene(o);
  SelfCalibrationOptions options;
  options.shared_focal_length = false;
  const SelfCalibrationSummary r = SelfCalibrate(s.views, s.tracks, options);
  REQUIRE_MESSAGE(r.IsUsable(), r.message);
  const Errors e = Compare(s, r);
  CAPTURE(r.message);
  CAPTURE(e.max_focal_rel);
  CHECK(e.max_focal_rel < kExactTol);
  CHECK(e.structure_rel < kExactTol);
}

TEST_CASE("with 0.5 px noise and 5 % wrong observations the focal length is within the noise") {
  MultiViewOptions o;
  o.num_views = 8;
  o.num_points = 300;
  o.noise_px = 0.5;
  o.outlier_fraction = 0.05;
  o.principal_point_offset_px = {12.0, -9.0};
  const MultiViewScene s = MakeMultiViewScene(o);
  for (PrincipalPointMode mode : {PrincipalPointMode::kImageCenter, PrincipalPointMode::kSolve}) {
    SelfCalibrationOptions options;
    options.principal_point_mode = mode;
    const SelfCalibrationSummary r = SelfCalibrate(s.views, s.tracks, options);
    REQUIRE_MESSAGE(r.IsUsable(), r.message);
    const Errors e = Compare(s, r);
    const double focal_error_px = std::abs(r.cameras[0].focal_px - s.cameras[0].focal_px);
    CAPTURE(static_cast<int>(mode));
    CAPTURE(r.message);
    CAPTURE(focal_error_px);
    CAPTURE(r.focal_std_px[0]);
    CAPTURE(e.max_rotation_deg);
    CAPTURE(e.structure_rel);
    // The residual is the noise once the outliers are gone.
    CHECK(r.reprojection_rms_px < 0.6);
    CHECK(r.reprojection_rms_px > 0.4);
    if (mode == PrincipalPointMode::kSolve) {
      // Unbiased model: within 4 sigma of the adjustment's own uncertainty.
      CHECK(r.focal_std_px[0] > 0);
      CHECK(focal_error_px < 4 * r.focal_std_px[0]);
    }
    // Either way within 1 % (the principal point held 15 px off costs a little).
    CHECK(focal_error_px < 0.01 * s.cameras[0].focal_px);
    // A principal point off by d px tilts each camera by about d / f; a relative rotation
    // carries two such tilts. The principal point is the least determined intrinsic (a few
    // px here when solved, 15 px when held at the centre).
    const double pp_error_px = (r.cameras[0].principal_point_px - s.cameras[0].principal_point_px).norm();
    CAPTURE(pp_error_px);
    CHECK(e.max_rotation_deg < 2.0 * pp_error_px / s.cameras[0].focal_px * 180.0 / M_PI + 0.1);
    CHECK(e.structure_rel < 0.01);
  }
}

TEST_CASE("the reported focal standard deviation matches the spread of the estimate over noise seeds") {
  // One geometry, fresh 0.5 px noise per seed: the adjustment's covariance predicts the spread
  // of the focal estimate over the seeds (the model is exact, so there is no bias to add).
  constexpr int kSeeds = 60;
  constexpr double kNoisePx = 0.5;
  // The sample standard deviation of 60 draws is itself uncertain by ~1 / sqrt(2 * 59) = 9 %.
  constexpr double kStdRelTol = 0.25;
  // 60 points (was 150): the claim is the ratio of reported to observed spread, which holds at
  // any count; 150 made this case 206 of the suite's 254 CPU-s under the sanitizers.
  MultiViewOptions o;
  o.num_views = 6;
  o.num_points = 60;
  const MultiViewScene s = MakeMultiViewScene(o);
  const double true_focal = s.cameras[0].focal_px;
  for (PrincipalPointMode mode : {PrincipalPointMode::kImageCenter, PrincipalPointMode::kSolve}) {
    SelfCalibrationOptions options;
    options.principal_point_mode = mode;
    std::vector<double> focal, reported;
    for (int seed = 0; seed < kSeeds; ++seed) {
      std::mt19937 rng(1000 + seed);
      std::normal_distribution<double> noise(0.0, kNoisePx);
      std::vector<Track> tracks = s.tracks;
      for (Track& t : tracks)
        for (auto& obs : t) obs.uv_px += Eigen::Vector2d{noise(rng), noise(rng)};
      const SelfCalibrationSummary r = SelfCalibrate(s.views, tracks, options);
      REQUIRE_MESSAGE(r.IsUsable(), r.message);
      focal.push_back(r.cameras[0].focal_px);
      reported.push_back(r.focal_std_px[0]);
    }
    double mean = 0.0, reported_rms = 0.0;
    for (int k = 0; k < kSeeds; ++k) {
      mean += focal[k] / kSeeds;
      reported_rms += reported[k] * reported[k] / kSeeds;
    }
    reported_rms = std::sqrt(reported_rms);
    double spread = 0.0;
    for (double f : focal) spread += (f - mean) * (f - mean) / (kSeeds - 1);
    spread = std::sqrt(spread);
    const double ratio = reported_rms / spread;
    const std::string mode_name = mode == PrincipalPointMode::kSolve ? "solved" : "at the centre";
    MESSAGE("principal point " << mode_name << ": focal over " << kSeeds << " seeds: mean " << mean << " px (truth "
                               << true_focal << "), observed std " << spread << " px, reported std " << reported_rms
                               << " px, ratio " << ratio);
    CHECK(spread > 0);
    CHECK(std::abs(ratio - 1.0) < kStdRelTol);
    // The mean is unbiased within the standard error of the mean (4 sigma).
    CHECK(std::abs(mean - true_focal) < 4.0 * spread / std::sqrt(static_cast<double>(kSeeds)));
  }
}

TEST_CASE("a single-image focal prior lets a long lens far from the default normalisation calibrate") {
  MultiViewOptions o;
  o.focal_px = {2600.0};
  o.noise_px = 0.3;
  o.num_views = 6;
  const MultiViewScene s = MakeMultiViewScene(o);
  std::vector<SelfCalibrationView> views = s.views;
  for (auto& v : views) v.focal_prior_px = 2300.0;  // the single-image estimate, 12 % low
  const SelfCalibrationSummary r = SelfCalibrate(views, s.tracks, SelfCalibrationOptions());
  REQUIRE_MESSAGE(r.IsUsable(), r.message);
  const double rel = std::abs(r.cameras[0].focal_px / s.cameras[0].focal_px - 1.0);
  CAPTURE(r.message);
  CAPTURE(rel);
  CAPTURE(r.focal_std_px[0]);
  CHECK(rel < 0.01);
}

TEST_CASE("projective bundle adjustment converges from perturbed cameras and points") {
  MultiViewOptions o;
  o.num_views = 5;
  const MultiViewScene s = MakeMultiViewScene(o);
  // A projective frame: the true cameras and points moved by an arbitrary homography H.
  Eigen::Matrix4d h;
  h << 1.0, 0.2, -0.1, 0.5, 0.1, 0.9, 0.3, -0.2, -0.2, 0.1, 1.1, 0.4, 0.05, -0.03, 0.02, 1.0;
  std::vector<Matrix34d> cameras;
  std::vector<Eigen::Matrix3d> pixel_from_normalised(s.cameras.size(), Eigen::Matrix3d::Identity());
  for (const Camera& c : s.cameras) cameras.push_back(c.ProjectionMatrix() * h.inverse());
  std::vector<Eigen::Vector4d> points;
  std::vector<ProjectiveBundleObservation> observations;
  for (size_t t = 0; t < s.tracks.size(); ++t) {
    points.push_back(h * s.points[t].homogeneous());
    for (const auto& obs : s.tracks[t]) observations.push_back({obs.view, static_cast<int>(t), obs.uv_px});
  }
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 1.0);
  for (auto& c : cameras) c += 1e-4 * c.norm() * Matrix34d::NullaryExpr([&] { return noise(rng); });
  for (auto& x : points) x += 1e-4 * x.norm() * Eigen::Vector4d::NullaryExpr([&] { return noise(rng); });
  const ProjectiveBundleSummary r = ProjectiveBundleAdjust(observations, pixel_from_normalised, {}, &cameras, &points);
  CAPTURE(r.message);
  REQUIRE(r.IsUsable());
  CHECK(r.initial_rms_px > 1.0);  // the start is not the answer (about 180 px off)
  CHECK(r.final_rms_px < kExactTol * s.cameras[0].focal_px);
  // The summary's costs are the squared pixel errors behind the RMS figures.
  CHECK(r.initial_cost == doctest::Approx(2.0 * observations.size() * r.initial_rms_px * r.initial_rms_px));
  CHECK(r.final_cost <= r.initial_cost);
  CHECK(r.iterations > 0);

  std::vector<ProjectiveBundleObservation> bad = observations;
  bad[0].point = -1;
  CHECK(ProjectiveBundleAdjust(bad, pixel_from_normalised, {}, &cameras, &points).termination ==
        SolverTermination::kInvalidInput);
}

// A closed ring of views around the box where each track reaches only three consecutive
// views (v, v + 1, v + 2 modulo the ring): no view shares a track with a view more than two
// steps away, so the reconstruction has to be grown view by view along the chain.
MultiViewScene MakeChainedRingScene(int num_views, int num_points, double noise_px, unsigned seed) {
  MultiViewScene s;
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::uniform_real_distribution<double> ux(-1.0, 5.0), uy(-1.0, 4.0), uz(0.0, 3.0);
  for (int v = 0; v < num_views; ++v) {
    testing::SyntheticSceneOptions c;
    c.focal_px = 900.0;
    c.principal_point_offset_px = Eigen::Vector2d::Zero();
    const double angle = 2 * M_PI * v / num_views;
    c.camera_center = Eigen::Vector3d(2.0 + 10.0 * std::cos(angle), 1.5 + 10.0 * std::sin(angle), 4.0 + 1.5 * (v % 3));
    c.look_at = {2.0 + 0.3 * (v % 2), 1.5, 1.2};
    c.roll_deg = 5.0 * std::sin(1.7 * v);
    s.cameras.push_back(testing::MakeLookAtCamera(c));
    s.views.push_back({c.width_px, c.height_px, 0.0});
  }
  while (static_cast<int>(s.points.size()) < num_points) {
    const Eigen::Vector3d x{ux(rng), uy(rng), uz(rng)};
    const int first = static_cast<int>(rng() % num_views);
    Track track;
    for (int k = 0; k < 3; ++k) {
      const int v = (first + k) % num_views;
      const Camera& c = s.cameras[v];
      const Eigen::Vector2d uv = c.Project(x);
      if (c.CamFromWorld(x).z() <= 0 || uv.x() < 0 || uv.y() < 0 || uv.x() > c.width_px || uv.y() > c.height_px)
        continue;
      track.push_back({v, uv + noise_px * Eigen::Vector2d{noise(rng), noise(rng)}});
    }
    if (track.size() < 2) continue;
    s.points.push_back(x);
    s.tracks.push_back(track);
  }
  return s;
}

TEST_CASE("a ring of 12 views whose tracks reach only neighbours registers view by view") {
  constexpr int kViews = 12;
  // With 0.5 px noise the focal length is within this many of its reported sigmas (measured:
  // 0.94 px off, sigma 1.91 px; noise-free 1e-13 px).
  constexpr double kSigmas = 3.0;
  for (double noise_px : {0.0, 0.5}) {
    const MultiViewScene s = MakeChainedRingScene(kViews, 600, noise_px, 23);
    // The chain: views two steps apart share tracks, three steps apart none.
    int far_shared = 0;
    for (const Track& t : s.tracks)
      for (const auto& a : t)
        for (const auto& b : t) {
          const int d = std::abs(a.view - b.view);
          far_shared += std::min(d, kViews - d) > 2;
        }
    REQUIRE(far_shared == 0);
    const SelfCalibrationSummary r = SelfCalibrate(s.views, s.tracks, SelfCalibrationOptions());
    CAPTURE(noise_px);
    CAPTURE(r.message);
    REQUIRE_MESSAGE(r.IsUsable(), r.message);
    for (const auto& w : r.warnings) MESSAGE("warning: " << w);
    const Errors e = Compare(s, r);  // requires every view registered
    const double focal_error_px = std::abs(r.cameras[0].focal_px - s.cameras[0].focal_px);
    const double linear_rel = std::abs(r.linear_focal_px[r.initial_view_a] / s.cameras[0].focal_px - 1.0);
    CAPTURE(focal_error_px);
    CAPTURE(r.focal_std_px[0]);
    CAPTURE(linear_rel);
    CAPTURE(e.max_rotation_deg);
    CAPTURE(e.structure_rel);
    MESSAGE("ring, noise " << noise_px << " px: " << r.message << "; focal error " << focal_error_px << " px, sigma "
                           << r.focal_std_px[0] << " px, linear " << linear_rel << " relative, " << r.time_ms << " ms");
    if (noise_px == 0.0) {
      CHECK(e.max_focal_rel < kExactTol);
      CHECK(e.max_rotation_deg < kExactTol * 180 / M_PI);
      CHECK(e.structure_rel < kExactTol);
    } else {
      CHECK(linear_rel > 1e-6);  // the adjustment's start is not the answer
      CHECK(r.focal_std_px[0] > 0);
      CHECK(focal_error_px < kSigmas * r.focal_std_px[0]);
      CHECK(r.reprojection_rms_px < 0.6);
      CHECK(e.structure_rel < 0.01);
    }
  }
}

TEST_CASE("bad input comes back as a message") {
  const MultiViewScene s = MakeMultiViewScene({});
  std::vector<SelfCalibrationView> two(s.views.begin(), s.views.begin() + 2);
  std::vector<Track> tracks_two;
  for (const Track& t : s.tracks) {
    Track kept;
    for (const auto& o : t)
      if (o.view < 2) kept.push_back(o);
    tracks_two.push_back(kept);
  }
  const SelfCalibrationSummary r2 = SelfCalibrate(two, tracks_two, {});
  CAPTURE(r2.message);
  CHECK_FALSE(r2.IsUsable());
  std::vector<Track> few(s.tracks.begin(), s.tracks.begin() + 5);
  const SelfCalibrationSummary r_few = SelfCalibrate(s.views, few, {});
  CAPTURE(r_few.message);
  CHECK_FALSE(r_few.IsUsable());
  std::vector<Track> bad = s.tracks;
  bad[0][0].view = 99;
  const SelfCalibrationSummary r_bad = SelfCalibrate(s.views, bad, {});
  CAPTURE(r_bad.message);
  CHECK_FALSE(r_bad.IsUsable());
}

}  // namespace
}  // namespace facet
