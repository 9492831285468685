// Cameras for images with pins but no line families (core/solve/multiview_init.h) on synthetic
// scenes: MakeBoxScene's box (plus up to three more boxes for more vertices) seen by several
// look-at cameras, every visible vertex pinned in every image. Resection against a calibrated
// image, two views with a known focal length, self-calibration of three, the refusals, the
// epipolar display helper, and the model update that follows.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "core/estimators/two_view.h"
#include "core/scene/project.h"
#include "core/solve/model_update.h"
#include "core/solve/multiview_init.h"
#include "tests/synthetic_scene.h"

namespace facet {
namespace {

using testing::MakeBoxScene;
using testing::MakeLookAtCamera;
using testing::SyntheticSceneOptions;

// Noise-free numerics: relative (focal length, translation), radians (rotation).
constexpr double kExactTol = 1e-9;

struct ViewSpec {
  Eigen::Vector3d center;
  Eigen::Vector3d look_at;
  double roll_deg = 0.0;
};

// View 0 is MakeBoxScene's default camera; the others circle the boxes.
const std::vector<ViewSpec> kViews = {
    {{9.0, -7.0, 5.0}, {2.0, 1.5, 1.0}, 3.0},
    {{-5.0, -8.0, 4.5}, {2.0, 1.5, 1.2}, -2.0},
    {{12.0, 6.0, 6.0}, {2.5, 1.5, 0.8}, 4.0},
    {{-4.0, 9.0, 7.0}, {1.5, 1.8, 1.0}, -3.0},
};

struct SceneSpec {
  int num_views = 2;
  bool first_calibrated = true;  // image 0 keeps MakeBoxScene's true camera and its segments
  int extra_boxes = 0;           // 0 to 3
  double noise_px = 0.0;
  Eigen::Vector2d principal_point_offset_px = {12.0, -9.0};
  double scale = 1.0;
  unsigned seed = 1;
};

struct Scene {
  Project project;
  std::vector<Camera> truth;  // per image, project order
  std::vector<Id> box_ids;
};

bool Visible(const Camera& camera, const Eigen::Vector3d& x) {
  const Eigen::Vector2d uv = camera.Project(x);
  return camera.CamFromWorld(x).z() > 0 && uv.x() >= 0 && uv.y() >= 0 && uv.x() <= camera.width_px &&
         uv.y() <= camera.height_px;
}

Scene MakeScene(const SceneSpec& spec) {
  SyntheticSceneOptions o;
  o.principal_point_offset_px = spec.principal_point_offset_px;
  o.scale = spec.scale;
  o.noise_px = spec.noise_px;
  o.seed = spec.seed;
  Scene s;
  auto base = MakeBoxScene(o);
  s.project = base.project;
  s.truth.push_back(base.true_camera);
  s.box_ids.push_back(base.box_id);
  Project& p = s.project;

  const std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> extra = {
      {{1.0, 1.2, 1.5}, {5.5, 0.5, 0.0}}, {{1.5, 1.0, 2.0}, {-2.5, 1.0, 0.0}}, {{2.0, 1.0, 1.0}, {1.0, 4.5, 0.0}}};
  for (int b = 0; b < spec.extra_boxes; ++b) {
    PrimitiveShape shape = MakeBox(kNoId, extra[b].first * spec.scale);
    shape.translation = extra[b].second * spec.scale;
    Id id = kNoId;
    REQUIRE(AddPrimitiveToProject(&p, shape, "box" + std::to_string(b + 1), &id, nullptr));
    s.box_ids.push_back(id);
  }

  std::mt19937 rng(spec.seed + 1000);
  std::normal_distribution<double> noise(0.0, 1.0);
  auto pin_all = [&](Id image_id, const Camera& camera, size_t first_box) {
    for (size_t b = first_box; b < s.box_ids.size(); ++b)
      for (VertexId v = 0; v < 8; ++v) {
        const VertexRef ref{s.box_ids[b], v};
        const Eigen::Vector3d x = VertexInWorld(p, ref);
        if (!Visible(camera, x)) continue;
        Pin pin;
        pin.id = p.NewId();
        pin.image_id = image_id;
        pin.vertex = ref;
        const double noise_u = noise(rng), noise_v = noise(rng);
        pin.uv_px = camera.Project(x) + spec.noise_px * Eigen::Vector2d(noise_u, noise_v);
        p.pins.push_back(pin);
      }
  };
  pin_all(p.images[0].id, base.true_camera, 1);
  if (!spec.first_calibrated) {
    p.segments.clear();
    p.images[0].camera = Camera();
    p.images[0].camera_calibrated = false;
  }
  for (int k = 1; k < spec.num_views; ++k) {
    SyntheticSceneOptions c = o;
    c.camera_center = kViews[k].center;
    c.look_at = kViews[k].look_at;
    c.roll_deg = kViews[k].roll_deg;
    const Camera camera = MakeLookAtCamera(c);
    Image image;
    image.id = p.NewId();
    image.path = "view" + std::to_string(k) + ".png";
    image.width_px = o.width_px;
    image.height_px = o.height_px;
    p.images.push_back(image);
    s.truth.push_back(camera);
    pin_all(image.id, camera, 0);
  }
  return s;
}

// The usual multi-view set-up: every image uncalibrated (no line families), box 0 plus
// extra_boxes more, principal points at the centre (two views and self-calibration assume it).
SceneSpec UncalibratedSpec(int num_views = 2, int extra_boxes = 3) {
  SceneSpec spec;
  spec.num_views = num_views;
  spec.first_calibrated = false;
  spec.extra_boxes = extra_boxes;
  spec.principal_point_offset_px = Eigen::Vector2d::Zero();
  return spec;
}

// The same scene with Gaussian pin noise drawn from seed (the noise loops).
SceneSpec WithNoise(SceneSpec spec, double noise_px, unsigned seed) {
  spec.noise_px = noise_px;
  spec.seed = seed;
  return spec;
}

int PinsIn(const Project& p, Id image_id) {
  return static_cast<int>(
      std::count_if(p.pins.begin(), p.pins.end(), [&](const Pin& pin) { return pin.image_id == image_id; }));
}

// Keeps only the pins of image_id on the given corners of box 0 (other images untouched).
void KeepCorners(Scene* s, Id image_id, const std::vector<int>& corners) {
  auto& pins = s->project.pins;
  pins.erase(std::remove_if(pins.begin(), pins.end(),
                            [&](const Pin& pin) {
                              if (pin.image_id != image_id) return false;
                              if (pin.vertex.primitive_id != s->box_ids[0]) return true;
                              return std::find(corners.begin(), corners.end(), static_cast<int>(pin.vertex.vertex)) ==
                                     corners.end();
                            }),
             pins.end());
}

double RotationErrorRad(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a * b.transpose()).angle();
}

double AngleRad(const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return std::atan2(a.cross(b).norm(), a.dot(b)); }

struct CameraErrors {
  double focal_rel = 0.0;
  double principal_point_px = 0.0;
  double rotation_rad = 0.0;
  double translation_rel = 0.0;  // |t - t_true| / |t_true|
};

CameraErrors Compare(const Camera& estimate, const Camera& truth) {
  CameraErrors e;
  e.focal_rel = std::abs(estimate.focal_px / truth.focal_px - 1.0);
  e.principal_point_px = (estimate.principal_point_px - truth.principal_point_px).norm();
  e.rotation_rad = RotationErrorRad(estimate.cam_from_world_rotation, truth.cam_from_world_rotation);
  e.translation_rel = (estimate.cam_from_world_translation - truth.cam_from_world_translation).norm() /
                      truth.cam_from_world_translation.norm();
  return e;
}

// Noise-free: focal length, rotation and translation of a camera exact.
void CheckCameraExact(const CameraErrors& e) {
  CAPTURE(e.focal_rel);
  CAPTURE(e.rotation_rad);
  CAPTURE(e.translation_rel);
  CHECK(e.focal_rel < kExactTol);
  CHECK(e.rotation_rad < kExactTol);
  CHECK(e.translation_rel < kExactTol);
}

// Relative pose cam_b_from_cam_a of two cameras: rotation and unit translation.
std::pair<Eigen::Matrix3d, Eigen::Vector3d> Relative(const Camera& a, const Camera& b) {
  const Eigen::Matrix3d r = b.cam_from_world_rotation * a.cam_from_world_rotation.transpose();
  const Eigen::Vector3d t = b.cam_from_world_translation - r * a.cam_from_world_translation;
  return {r, t.normalized()};
}

// Errors of an estimated relative pose (a, b) against the true one: rotation angle and the
// angle between the baseline directions (rad).
std::pair<double, double> RelativePoseErrors(const Camera& true_a, const Camera& true_b, const Camera& a,
                                             const Camera& b) {
  const auto [r_true, t_true] = Relative(true_a, true_b);
  const auto [r_est, t_est] = Relative(a, b);
  return {RotationErrorRad(r_est, r_true), AngleRad(t_est, t_true)};
}

std::string Messages(const MultiViewInitSummary& s) {
  std::string out = s.message;
  for (const auto& r : s.images)
    out += "\n  " + r.image_path + " [" + MultiViewInitPathName(r.path) + "]: " + r.message;
  for (const auto& m : s.messages) out += "\n  ! " + m;
  return out;
}

// Only image `index` may differ between the two projects.
bool OnlyImageChanged(const Project& before, const Project& after, size_t index) {
  Project a = before, b = after;
  a.images[index] = b.images[index];
  return a == b;
}

TEST_CASE("resection: 8 and 6 non-coplanar pins on known corners recover K, R, t exactly, at three scales") {
  for (const double scale : {1.0, 1e-3, 1e3}) {
    for (const int num_pins : {8, 6}) {
      CAPTURE(scale);
      CAPTURE(num_pins);
      SceneSpec spec;
      spec.scale = scale;
      Scene s = MakeScene(spec);
      const Id image_id = s.project.images[1].id;
      if (num_pins == 6) KeepCorners(&s, image_id, {0, 1, 2, 4, 5, 7});
      REQUIRE(PinsIn(s.project, image_id) == num_pins);
      // The start is not the answer: the image is uncalibrated, its camera the default.
      REQUIRE_FALSE(s.project.images[1].camera_calibrated);
      REQUIRE(Compare(s.project.images[1].camera, s.truth[1]).rotation_rad > 0.1);

      Project out;
      const MultiViewInitSummary summary = CalibrateImagesFromPins(s.project, {}, &out);
      INFO(Messages(summary));
      REQUIRE(summary.IsUsable());
      const MultiViewImageReport& report = summary.images[1];
      REQUIRE(report.path == MultiViewInitPath::kResection);
      CHECK(report.initialized);
      CHECK(report.num_known_pins == num_pins);
      CHECK(report.flagged_pins.empty());
      CHECK(summary.images[0].path == MultiViewInitPath::kAlreadyCalibrated);
      CHECK(out.images[1].camera_calibrated);
      CHECK(out.images[1].camera.width_px == out.images[1].width_px);
      const CameraErrors e = Compare(out.images[1].camera, s.truth[1]);
      MESSAGE("resection scale " << scale << ", " << num_pins << " pins: focal " << e.focal_rel << ", pp "
                                 << e.principal_point_px << " px, rotation " << e.rotation_rad << " rad, t "
                                 << e.translation_rel << ", RMS " << report.residual_px << " px, " << summary.time_ms
                                 << " ms");
      CheckCameraExact(e);
      CHECK(e.principal_point_px / s.truth[1].focal_px < kExactTol);
      CHECK(report.residual_px < kExactTol * s.truth[1].focal_px);
      CHECK(OnlyImageChanged(s.project, out, 1));
    }
  }
}

TEST_CASE("resection: 4 pins on one face take the planar path (principal point at the centre)") {
  SceneSpec spec;
  spec.principal_point_offset_px = Eigen::Vector2d::Zero();  // one view of a plane cannot fix it
  Scene s = MakeScene(spec);
  const Id image_id = s.project.images[1].id;
  KeepCorners(&s, image_id, {4, 5, 6, 7});  // the top face
  Project out;
  const MultiViewInitSummary summary = CalibrateImagesFromPins(s.project, {}, &out);
  INFO(Messages(summary));
  REQUIRE(summary.images[1].path == MultiViewInitPath::kResection);
  CHECK(summary.images[1].message.find("planar") != std::string::npos);
  const CameraErrors e = Compare(out.images[1].camera, s.truth[1]);
  CheckCameraExact(e);
  CHECK(e.principal_point_px / s.truth[1].focal_px < kExactTol);
}

TEST_CASE("resection: a wrong click is flagged and dropped, the camera stays exact") {
  Scene s = MakeScene({});
  const Id image_id = s.project.images[1].id;
  Pin* wrong = nullptr;
  for (Pin& pin : s.project.pins)
    if (pin.image_id == image_id && pin.vertex.vertex == 3) wrong = &pin;
  REQUIRE(wrong != nullptr);
  wrong->uv_px += Eigen::Vector2d(30.0, -25.0);
  const Id wrong_id = wrong->id;
  Project out;
  const MultiViewInitSummary summary = CalibrateImagesFromPins(s.project, {}, &out);
  INFO(Messages(summary));
  const MultiViewImageReport& report = summary.images[1];
  REQUIRE(report.path == MultiViewInitPath::kResection);
  REQUIRE(report.flagged_pins.size() == 1);
  CHECK(report.flagged_pins[0] == wrong_id);
  const CameraErrors e = Compare(out.images[1].camera, s.truth[1]);
  CheckCameraExact(e);
}

TEST_CASE("resection with 0.5 px noise: within the noise") {
  // 4 boxes' visible corners in image 1. The fitted camera's prediction at the data points has
  // an RMS error of sigma sqrt(p / n) (least squares with p = 9 parameters, n points, 2
  // coordinates each, sum of squared prediction errors ~ sigma^2 p); bound at twice that. The
  // noise is on the pins only: the model's vertices are exact. The
  // focal length within 4 of the refinement's own standard deviations, which must be small.
  constexpr double kNoisePx = 0.5;
  constexpr int kParameters = 9;
  for (unsigned seed = 1; seed <= 5; ++seed) {
    CAPTURE(seed);
    SceneSpec spec = WithNoise({}, kNoisePx, seed);
    spec.extra_boxes = 3;
    Scene s = MakeScene(spec);
    Project out;
    const MultiViewInitSummary summary = CalibrateImagesFromPins(s.project, {}, &out);
    INFO(Messages(summary));
    const MultiViewImageReport& report = summary.images[1];
    REQUIRE(report.path == MultiViewInitPath::kResection);
    const int n = report.num_known_pins;
    const Camera& camera = out.images[1].camera;
    double sum_sq = 0.0;
    for (const Primitive& primitive : s.project.primitives)
      for (VertexId v = 0; v < 8; ++v) {
        const Eigen::Vector3d x = VertexInWorld(s.project, {primitive.id, v});
        if (!Visible(s.truth[1], x)) continue;
        sum_sq += (camera.Project(x) - s.truth[1].Project(x)).squaredNorm();
      }
    const double prediction_rms_px = std::sqrt(sum_sq / n);
    const double bound_px = 2.0 * kNoisePx * std::sqrt(static_cast<double>(kParameters) / n);
    const double focal_error_px = std::abs(camera.focal_px - s.truth[1].focal_px);
    MESSAGE("seed " << seed << ": " << n << " pins, RMS " << report.residual_px << " px, prediction RMS "
                    << prediction_rms_px << " px (bound " << bound_px << "), focal error " << focal_error_px
                    << " px (std " << report.focal_std_px << " px), flagged " << report.flagged_pins.size());
    CHECK(n >= 20);
    CHECK(report.flagged_pins.empty());
    CHECK(prediction_rms_px < bound_px);
    // The residual is a 2-D distance: its RMS is about sqrt(2) sigma.
    CHECK(report.residual_px < 1.5 * std::sqrt(2.0) * kNoisePx);
    CHECK(report.focal_std_px > 0.0);
    CHECK(report.focal_std_px < 0.02 * camera.focal_px);
    CHECK(focal_error_px < 4.0 * report.focal_std_px);
  }
}

MultiViewInitOptions KnownFocal(const Scene& s) {
  MultiViewInitOptions options;
  for (size_t i = 0; i < s.project.images.size(); ++i)
    options.focal_px_by_image[s.project.images[i].id] = s.truth[i].focal_px;
  return options;
}

TEST_CASE("two views, known focal length, noise-free: relative pose exact, aligned to the model") {
  const SceneSpec spec = UncalibratedSpec();
  Scene s = MakeScene(spec);
  REQUIRE(PinsIn(s.project, s.project.images[0].id) >= 10);
  REQUIRE(PinsIn(s.project, s.project.images[1].id) >= 10);
  Project out;
  const MultiViewInitSummary summary = CalibrateImagesFromPins(s.project, KnownFocal(s), &out);
  INFO(Messages(summary));
  REQUIRE(summary.IsUsable());
  for (int i : {0, 1}) {
    const MultiViewImageReport& report = summary.images[i];
    REQUIRE(report.path == MultiViewInitPath::kTwoView);
    CHECK(report.partner_image_id == s.project.images[1 - i].id);
    CHECK_FALSE(report.focal_guessed);
    CHECK(report.flagged_pins.empty());
    CHECK(report.residual_px < kExactTol * s.truth[i].focal_px);
  }
  REQUIRE(summary.pairs.size() == 1);
  const auto [rotation_error, direction_error] =
      RelativePoseErrors(s.truth[0], s.truth[1], out.images[0].camera, out.images[1].camera);
  // The model is the truth, so the alignment gauge puts both cameras at their true poses.
  const CameraErrors e0 = Compare(out.images[0].camera, s.truth[0]);
  const CameraErrors e1 = Compare(out.images[1].camera, s.truth[1]);
  MESSAGE("two views noise-free: rotation " << rotation_error << " rad, direction " << direction_error
                                            << " rad; absolute t " << e0.translation_rel << ", " << e1.translation_rel
                                            << "; " << summary.time_ms << " ms");
  CHECK(rotation_error < kExactTol);
  CHECK(direction_error < kExactTol);
  CHECK(e0.rotation_rad < kExactTol);
  CHECK(e1.rotation_rad < kExactTol);
  CHECK(e0.translation_rel < kExactTol);
  CHECK(e1.translation_rel < kExactTol);
  CHECK(out.images[0].camera_calibrated);
  CHECK(out.images[1].camera_calibrated);
}

TEST_CASE("two views take the focal length from the image's focal mode (fixed, or the prior's value)") {
  for (const FocalMode mode : {FocalMode::kFixed, FocalMode::kPrior}) {
    CAPTURE(FocalModeName(mode));
    Scene s = MakeScene(UncalibratedSpec());
    for (size_t i = 0; i < 2; ++i) {
      Image& image = s.project.images[i];
      image.focal_mode = mode;
      (mode == FocalMode::kFixed ? image.fixed_focal_px : image.focal_prior_px) = s.truth[i].focal_px;
      image.focal_prior_std_px = 50.0;
    }
    Project out;
    const MultiViewInitSummary summary = CalibrateImagesFromPins(s.project, {}, &out);
    INFO(Messages(summary));
    REQUIRE(summary.images[1].path == MultiViewInitPath::kTwoView);
    CHECK_FALSE(summary.images[1].focal_guessed);
    const auto [rotation_error, direction_error] =
        RelativePoseErrors(s.truth[0], s.truth[1], out.images[0].camera, out.images[1].camera);
    CHECK(std::abs(out.images[1].camera.focal_px / s.truth[1].focal_px - 1.0) < kExactTol);
    CHECK(rotation_error < kExactTol);
    CHECK(direction_error < kExactTol);
  }
}

TEST_CASE("two views of one face: the plane's homography gives both cameras where F cannot") {
  // Both uncalibrated images pin only the 4 corners of box 0's y = 0 face (corners 0, 1, 4, 5),
  // which both cameras see: F is not unique, the homography path places them exactly.
  Scene s = MakeScene(UncalibratedSpec(2, 0));
  for (int i : {0, 1}) KeepCorners(&s, s.project.images[i].id, {0, 1, 4, 5});
  REQUIRE(PinsIn(s.project, s.project.images[0].id) == 4);
  REQUIRE(PinsIn(s.project, s.project.images[1].id) == 4);
  Project out;
  const MultiViewInitSummary summary = CalibrateImagesFromPins(s.project, KnownFocal(s), &out);
  INFO(Messages(summary));
  for (int i : {0, 1}) {
    CAPTURE(i);
    const MultiViewImageReport& report = summary.images[i];
    REQUIRE(report.path == MultiViewInitPath::kTwoView);
    CHECK(report.two_view_plane);
    CHECK(report.message.find("one plane") != std::string::npos);
    CHECK(report.residual_px < kExactTol * s.truth[i].focal_px);
    // The start is not the answer: the uncalibrated camera is the default one.
    CHECK(Compare(s.project.images[i].camera, s.truth[i]).rotation_rad > 0.1);
    const CameraErrors e = Compare(out.images[i].camera, s.truth[i]);
    std::string warnings;
    for (const auto& w : report.warnings) warnings += "; " + w;
    MESSAGE("one face, view " << i << ": rotation " << e.rotation_rad << " rad, t " << e.translation_rel << warnings);
    CHECK(e.rotation_rad < kExactTol);
    CHECK(e.translation_rel < kExactTol);
  }
  const auto [rotation_error, direction_error] =
      RelativePoseErrors(s.truth[0], s.truth[1], out.images[0].camera, out.images[1].camera);
  CHECK(rotation_error < kExactTol);
  CHECK(direction_error < kExactTol);
  // The pair's F, for display, is that of the placed cameras: the true matches lie on its lines.
  REQUIRE(summary.pairs.size() == 1);
  const Eigen::Matrix3d F = summary.pairs[0].F;
  for (VertexId v : {0, 2, 3, 6}) {
    const Eigen::Vector3d x = VertexInWorld(s.project, {s.box_ids[0], v});
    const EpipolarLine line = EpipolarLineInImage(F, s.truth[0].Project(x), 1024, 768);
    CHECK(std::abs(line.line.dot(s.truth[1].Project(x).homogeneous())) < 1e-6);
  }
}

TEST_CASE("two views of one face, ambiguous pair: the model's positions pick the true pose") {
  // Image 1 is re-shot from above image 0 (a short vertical baseline); both pin the y = 0 face.
  // Two decompositions of the homography then pass cheirality; only the true one fits the
  // face's shape, and the model's positions pick it.
  Scene s = MakeScene(UncalibratedSpec(2, 0));
  SyntheticSceneOptions above;
  above.principal_point_offset_px = Eigen::Vector2d::Zero();
  above.camera_center = {9.0, -7.0, 7.0};
  s.truth[1] = MakeLookAtCamera(above);
  for (Pin& pin : s.project.pins)
    if (pin.image_id == s.project.images[1].id) pin.uv_px = s.truth[1].Project(VertexInWorld(s.project, pin.vertex));
  for (int i : {0, 1}) KeepCorners(&s, s.project.images[i].id, {0, 1, 4, 5});
  REQUIRE(PinsIn(s.project, s.project.images[1].id) == 4);
  Project out;
  const MultiViewInitSummary summary = CalibrateImagesFromPins(s.project, KnownFocal(s), &out);
  INFO(Messages(summary));
  for (int i : {0, 1}) {
    CAPTURE(i);
    const MultiViewImageReport& report = summary.images[i];
    REQUIRE(report.path == MultiViewInitPath::kTwoView);
    CHECK(report.two_view_plane);
    std::string warnings;
    for (const auto& w : report.warnings) warnings += "; " + w;
    const CameraErrors e = Compare(out.images[i].camera, s.truth[i]);
    MESSAGE("one face, short baseline, view " << i << ": rotation " << e.rotation_rad << " rad, t " << e.translation_rel
                                              << warnings);
    CHECK(warnings.find("the model's vertices chose one") != std::string::npos);
    CHECK(e.rotation_rad < kExactTol);
    CHECK(e.translation_rel < kExactTol);
  }
}

TEST_CASE("resection keeps a known focal length exactly (FocalMode::kFixed), noise-free and with noise") {
  SUBCASE("noise-free: the pose exact, f the given one") {
    Scene s = MakeScene({});
    Image& image = s.project.images[1];
    image.focal_mode = FocalMode::kFixed;
    image.fixed_focal_px = s.truth[1].focal_px;
    Project out;
    const MultiViewInitSummary summary = CalibrateImagesFromPins(s.project, {}, &out);
    INFO(Messages(summary));
    const MultiViewImageReport& report = summary.images[1];
    REQUIRE(report.path == MultiViewInitPath::kResection);
    CHECK(report.message.find("known, held") != std::string::npos);
    CHECK(out.images[1].camera.focal_px == image.fixed_focal_px);
    CHECK(report.focal_std_px == 0.0);
    const CameraErrors e = Compare(out.images[1].camera, s.truth[1]);
    CAPTURE(e.rotation_rad);
    CAPTURE(e.translation_rel);
    CHECK(e.principal_point_px / s.truth[1].focal_px < kExactTol);
    CHECK(e.rotation_rad < kExactTol);
    CHECK(e.translation_rel < kExactTol);
  }
  SUBCASE("0.5 px noise, 8 pins: f held, the camera position closer than with f free") {
    // Over 10 seeds, the RMS of the relative t error with the true f held is below the one
    // with f solved (f trades against the distance along the axis).
    constexpr double kNoisePx = 0.5;
    double sq_fixed = 0.0, sq_free = 0.0;
    for (unsigned seed = 1; seed <= 10; ++seed) {
      CAPTURE(seed);
      Scene s = MakeScene(WithNoise({}, kNoisePx, seed));
      Project out_free, out_fixed;
      const MultiViewInitSummary free_focal = CalibrateImagesFromPins(s.project, {}, &out_free);
      s.project.images[1].focal_mode = FocalMode::kFixed;
      s.project.images[1].fixed_focal_px = s.truth[1].focal_px;
      const MultiViewInitSummary fixed = CalibrateImagesFromPins(s.project, {}, &out_fixed);
      INFO(Messages(fixed));
      REQUIRE(free_focal.images[1].path == MultiViewInitPath::kResection);
      REQUIRE(fixed.images[1].path == MultiViewInitPath::kResection);
      CHECK(out_fixed.images[1].camera.focal_px == s.truth[1].focal_px);
      sq_free += std::pow(Compare(out_free.images[1].camera, s.truth[1]).translation_rel, 2);
      sq_fixed += std::pow(Compare(out_fixed.images[1].camera, s.truth[1]).translation_rel, 2);
    }
    MESSAGE("resection 0.5 px, 8 pins, 10 seeds: t error RMS with f free "
            << std::sqrt(sq_free / 10) << ", with f known " << std::sqrt(sq_fixed / 10));
    CHECK(sq_fixed < sq_free);
  }
}

TEST_CASE("two views, keep-first-camera gauge: image 0 stays where it was") {
  Scene s = MakeScene(UncalibratedSpec());
  Camera placed;
  placed.SetPose(RotationFromAngleAxis(Eigen::Vector3d(0.2, -0.1, 0.3)), Eigen::Vector3d(1.0, 2.0, 3.0));
  s.project.images[0].camera = placed;
  MultiViewInitOptions options = KnownFocal(s);
  options.gauge = MultiViewGauge::kKeepFirstCamera;
  Project out;
  const MultiViewInitSummary summary = CalibrateImagesFromPins(s.project, options, &out);
  INFO(Messages(summary));
  REQUIRE(summary.images[1].path == MultiViewInitPath::kTwoView);
  const Camera& c0 = out.images[0].camera;
  CHECK(RotationErrorRad(c0.cam_from_world_rotation, placed.cam_from_world_rotation) < kExactTol);
  CHECK((c0.CenterInWorld() - placed.CenterInWorld()).norm() < kExactTol);
  const auto [rotation_error, direction_error] = RelativePoseErrors(s.truth[0], s.truth[1], c0, out.images[1].camera);
  CHECK(rotation_error < kExactTol);
  CHECK(direction_error < kExactTol);
  // The baseline is scaled to the model: the true model spread gives the true baseline.
  const double baseline = (out.images[1].camera.CenterInWorld() - c0.CenterInWorld()).norm();
  const double true_baseline = (s.truth[1].CenterInWorld() - s.truth[0].CenterInWorld()).norm();
  CAPTURE(baseline);
  CAPTURE(true_baseline);
  CHECK(std::abs(baseline / true_baseline - 1.0) < kExactTol);
}

TEST_CASE("a chain: image 1 resected from image 0, image 2 (no known vertex) paired with image 1") {
  // Image 0 (calibrated) pins box 0 only; image 1 pins every box; image 2 pins the extra boxes
  // only, none of them known, so it takes two views with image 1 once that is resected. The
  // resected camera stays, image 2 is placed relative to it and the baseline scaled to the
  // (true) model: exact.
  SceneSpec spec;
  spec.num_views = 3;
  spec.extra_boxes = 3;
  spec.principal_point_offset_px = Eigen::Vector2d::Zero();
  Scene s = MakeScene(spec);
  Project& p = s.project;
  const Id id0 = p.images[0].id, id2 = p.images[2].id;
  p.pins.erase(std::remove_if(p.pins.begin(), p.pins.end(),
                              [&](const Pin& pin) {
                                const bool box0 = pin.vertex.primitive_id == s.box_ids[0];
                                return (pin.image_id == id0 && !box0) || (pin.image_id == id2 && box0);
                              }),
               p.pins.end());
  REQUIRE(PinsIn(p, id2) >= 8);
  MultiViewInitOptions options;
  options.focal_px_by_image[id2] = s.truth[2].focal_px;
  Project out;
  const MultiViewInitSummary summary = CalibrateImagesFromPins(p, options, &out);
  INFO(Messages(summary));
  REQUIRE(summary.images[1].path == MultiViewInitPath::kResection);
  REQUIRE(summary.images[2].path == MultiViewInitPath::kTwoView);
  CHECK(summary.images[2].num_known_pins == 0);
  CHECK(summary.images[2].partner_image_id == p.images[1].id);
  CHECK(summary.images[1].initialized);  // by the resection, not moved by the pair
  for (int i : {1, 2}) {
    CAPTURE(i);
    const CameraErrors e = Compare(out.images[i].camera, s.truth[i]);
    CheckCameraExact(e);
  }
}

// First-order standard deviations (rad) of the relative pose that two views with these true
// matches determine under pixel noise sigma: the Jacobian J of the symmetric epipolar residuals
// (core/estimators/two_view.h) with respect to the pose's 5 parameters (rotation 3, baseline direction 2;
// internal::PoseFundamental), each residual a point-to-line distance carrying the noise of
// both points (variance 2 sigma^2), so covariance = 2 sigma^2 (J^T J)^-1. Returns the RMS
// rotation angle and the RMS direction angle (square roots of the blocks' traces).
std::pair<double, double> RelativePoseStd(const Camera& a, const Camera& b, const std::vector<Eigen::Vector3d>& points,
                                          double sigma_px) {
  const auto [rotation, direction] = Relative(a, b);
  internal::PoseFundamental pose;
  pose.K1_inv = a.K().inverse();
  pose.K2_inv = b.K().inverse();
  pose.R = rotation;
  pose.t = direction;
  std::vector<Eigen::Vector2d> uv_a, uv_b;
  for (const auto& x : points) {
    uv_a.push_back(a.Project(x));
    uv_b.push_back(b.Project(x));
  }
  Eigen::VectorXd residuals;
  Eigen::Matrix<double, Eigen::Dynamic, 9> jacobian_f;
  internal::SymmetricEpipolarResiduals(pose.F(), uv_a, uv_b, &residuals, &jacobian_f);
  const Eigen::MatrixXd jacobian = jacobian_f * pose.Tangent();
  const Eigen::MatrixXd covariance = 2.0 * sigma_px * sigma_px * (jacobian.transpose() * jacobian).inverse();
  return {std::sqrt(covariance.topLeftCorner<3, 3>().trace()), std::sqrt(covariance.bottomRightCorner<2, 2>().trace())};
}

TEST_CASE("two views with 0.5 px noise: relative pose within the noise; 2 wrong clicks among 20 are flagged") {
  // Bounds: 4 times the first-order standard deviations of RelativePoseStd for the 18 true
  // inliers (a norm over 3 or 2 axes rarely exceeds 4 times its RMS).
  constexpr double kNoisePx = 0.5;
  constexpr double kSigmas = 4.0;
  for (unsigned seed = 1; seed <= 5; ++seed) {
    CAPTURE(seed);
    Scene s = MakeScene(WithNoise(UncalibratedSpec(), kNoisePx, seed));
    // 20 correspondences: drop the pins of image 1 beyond the first 20.
    const Id id1 = s.project.images[1].id;
    int kept = 0;
    s.project.pins.erase(std::remove_if(s.project.pins.begin(), s.project.pins.end(),
                                        [&](const Pin& pin) { return pin.image_id == id1 && ++kept > 20; }),
                         s.project.pins.end());
    REQUIRE(PinsIn(s.project, id1) == 20);
    // Two wrong clicks in image 1, moved 25 and 40 px across their true epipolar lines (a move
    // along the line is invisible to two views).
    const Eigen::Matrix3d F = FundamentalFromCameras(s.truth[0], s.truth[1]);
    std::vector<Id> wrong;
    std::vector<Eigen::Vector3d> inlier_points;
    int seen = 0;
    for (Pin& pin : s.project.pins) {
      if (pin.image_id != id1) continue;
      ++seen;
      const Eigen::Vector3d x = VertexInWorld(s.project, pin.vertex);
      if (seen != 5 && seen != 13) {
        inlier_points.push_back(x);
        continue;
      }
      const EpipolarLine line = EpipolarLineInImage(F, s.truth[0].Project(x), 1024, 768);
      pin.uv_px += (seen == 5 ? 25.0 : 40.0) * line.line.head<2>();
      wrong.push_back(pin.id);
    }
    REQUIRE(wrong.size() == 2);

    Project out;
    const MultiViewInitSummary summary = CalibrateImagesFromPins(s.project, KnownFocal(s), &out);
    INFO(Messages(summary));
    const MultiViewImageReport& report = summary.images[1];
    REQUIRE(report.path == MultiViewInitPath::kTwoView);
    std::vector<Id> flagged = report.flagged_pins;
    std::sort(flagged.begin(), flagged.end());
    std::sort(wrong.begin(), wrong.end());
    CHECK(flagged == wrong);
    CHECK(summary.images[0].flagged_pins.size() == 2);  // their partners in image 0

    const auto [rotation_error, direction_error] =
        RelativePoseErrors(s.truth[0], s.truth[1], out.images[0].camera, out.images[1].camera);
    const auto [rotation_std, direction_std] = RelativePoseStd(s.truth[0], s.truth[1], inlier_points, kNoisePx);
    MESSAGE("two views 0.5 px, seed " << seed << ": rotation " << rotation_error << " rad (std " << rotation_std
                                      << "), direction " << direction_error << " rad (std " << direction_std
                                      << "), epipolar RMS " << report.residual_px << " px");
    CHECK(rotation_error < kSigmas * rotation_std);
    CHECK(direction_error < kSigmas * direction_std);
    // Each distance carries two points' noise: RMS about sqrt(2) sigma.
    CHECK(report.residual_px < 2.0 * kNoisePx);
  }
}

TEST_CASE("three uncalibrated views: self-calibration recovers the focal length") {
  // self_calibration's own accuracy on noise-free tracks (its linear quadric is exact to 1e-6).
  constexpr double kFocalTol = 1e-6;
  Scene s = MakeScene(UncalibratedSpec(3));
  Project out;
  const MultiViewInitSummary summary = CalibrateImagesFromPins(s.project, {}, &out);
  INFO(Messages(summary));
  REQUIRE(summary.IsUsable());
  for (int i = 0; i < 3; ++i) {
    CAPTURE(i);
    const MultiViewImageReport& report = summary.images[i];
    REQUIRE(report.path == MultiViewInitPath::kSelfCalibration);
    CHECK(report.focal_guessed);
    const CameraErrors e = Compare(out.images[i].camera, s.truth[i]);
    MESSAGE("self-calibration view " << i << ": focal " << e.focal_rel << ", rotation " << e.rotation_rad << " rad, t "
                                     << e.translation_rel << ", RMS " << report.residual_px << " px, "
                                     << summary.time_ms << " ms");
    // The start is not the answer: the guessed 1.2 x 1024 px is 37 % off.
    REQUIRE(std::abs(1.2 * 1024 / s.truth[i].focal_px - 1.0) > 0.3);
    CHECK(e.focal_rel < kFocalTol);
    // Aligned to the (true) model: the poses too.
    CHECK(e.rotation_rad < kFocalTol);
    CHECK(e.translation_rel < kFocalTol);
  }
}

TEST_CASE("four views with 0.5 px noise and a wrong click: self-calibration within the noise, the click flagged") {
  // The focal length within 4 of the bundle adjustment's own standard deviations, which must be
  // a small fraction of it; the residual at the noise (a 2-D distance: RMS about sqrt(2) sigma).
  constexpr double kNoisePx = 0.5;
  for (unsigned seed = 1; seed <= 3; ++seed) {
    CAPTURE(seed);
    Scene s = MakeScene(WithNoise(UncalibratedSpec(4), kNoisePx, seed));
    Pin* wrong = nullptr;
    for (Pin& pin : s.project.pins)
      if (pin.image_id == s.project.images[2].id && !wrong) wrong = &pin;
    REQUIRE(wrong != nullptr);
    wrong->uv_px += Eigen::Vector2d(-30.0, 28.0);
    const Id wrong_id = wrong->id;
    Project out;
    const MultiViewInitSummary summary = CalibrateImagesFromPins(s.project, {}, &out);
    INFO(Messages(summary));
    for (int i = 0; i < 4; ++i) {
      CAPTURE(i);
      const MultiViewImageReport& report = summary.images[i];
      REQUIRE(report.path == MultiViewInitPath::kSelfCalibration);
      const double focal_error_px = std::abs(out.images[i].camera.focal_px - s.truth[i].focal_px);
      MESSAGE("self-calibration 0.5 px, seed " << seed << ", view " << i << ": focal error " << focal_error_px
                                               << " px (std " << report.focal_std_px << "), RMS " << report.residual_px
                                               << " px, flagged " << report.flagged_pins.size());
      CHECK(report.focal_std_px > 0.0);
      CHECK(report.focal_std_px < 0.02 * s.truth[i].focal_px);
      CHECK(focal_error_px < 4.0 * report.focal_std_px);
      CHECK(report.residual_px < 1.5 * std::sqrt(2.0) * kNoisePx);
      if (i == 2) {
        CHECK(std::find(report.flagged_pins.begin(), report.flagged_pins.end(), wrong_id) != report.flagged_pins.end());
      }
    }
  }
}

TEST_CASE("three uncalibrated views, one with 5 pins: self-calibration fails, two views take the other pair") {
  Scene s = MakeScene(UncalibratedSpec(3));
  KeepCorners(&s, s.project.images[2].id, {0, 1, 2, 4, 7});
  Project out;
  const MultiViewInitSummary summary = CalibrateImagesFromPins(s.project, KnownFocal(s), &out);
  INFO(Messages(summary));
  CHECK(summary.images[0].path == MultiViewInitPath::kTwoView);
  CHECK(summary.images[1].path == MultiViewInitPath::kTwoView);
  CHECK(summary.images[2].path == MultiViewInitPath::kNone);
  CHECK_FALSE(out.images[2].camera_calibrated);
  CHECK(out.images[2] == s.project.images[2]);
  REQUIRE(summary.messages.size() == 1);
  CHECK(summary.messages[0].find("self-calibration") != std::string::npos);
  CHECK(summary.messages[0].find("5 vertices pinned in both") != std::string::npos);
  const auto [rotation_error, direction_error] =
      RelativePoseErrors(s.truth[0], s.truth[1], out.images[0].camera, out.images[1].camera);
  CHECK(rotation_error < kExactTol);
  CHECK(direction_error < kExactTol);
}

TEST_CASE("refusals: too few pins, too few shared vertices, collinear pins; the project is unchanged") {
  SUBCASE("4 non-coplanar pins on known vertices") {
    Scene s = MakeScene({});
    KeepCorners(&s, s.project.images[1].id, {0, 1, 2, 7});
    Project out;
    const MultiViewInitSummary summary = CalibrateImagesFromPins(s.project, {}, &out);
    INFO(Messages(summary));
    CHECK(summary.IsUsable());
    CHECK(summary.num_initialized == 0);
    CHECK(summary.images[1].path == MultiViewInitPath::kNone);
    REQUIRE(summary.messages.size() == 1);
    const std::string expected = "image 'view1.png': 4 pins on known vertices; resection needs 6, or 4 on one face";
    CHECK(summary.messages[0].rfind(expected, 0) == 0);
    CHECK(out == s.project);
  }
  SUBCASE("two uncalibrated images sharing 5 vertices") {
    SceneSpec spec;
    spec.first_calibrated = false;
    Scene s = MakeScene(spec);
    KeepCorners(&s, s.project.images[1].id, {0, 1, 2, 4, 7});
    Project out;
    const MultiViewInitSummary summary = CalibrateImagesFromPins(s.project, {}, &out);
    INFO(Messages(summary));
    CHECK(summary.num_initialized == 0);
    REQUIRE(summary.messages.size() == 2);
    CHECK(summary.messages[1].find("5 vertices pinned in both") != std::string::npos);
    CHECK(summary.messages[1].find("two views need 7") != std::string::npos);
    CHECK(out == s.project);
  }
  SUBCASE("6 collinear known vertices") {
    // Three boxes in a row along x: their corners on y = 0, z = 0 lie on one line.
    Scene s = MakeScene({});
    Project& p = s.project;
    std::vector<VertexRef> line = {{s.box_ids[0], 0}, {s.box_ids[0], 1}};
    for (const double x : {5.0, 7.0}) {
      PrimitiveShape shape = MakeBox(kNoId, Eigen::Vector3d(1.0, 1.0, 1.0));
      shape.translation = Eigen::Vector3d(x, 0.0, 0.0);
      Id id = kNoId;
      REQUIRE(AddPrimitiveToProject(&p, shape, "row", &id, nullptr));
      line.push_back({id, 0});
      line.push_back({id, 1});
    }
    p.pins.clear();
    for (size_t i = 0; i < 2; ++i)
      for (const VertexRef& ref : line) {
        Pin pin;
        pin.id = p.NewId();
        pin.image_id = p.images[i].id;
        pin.vertex = ref;
        pin.uv_px = s.truth[i].Project(VertexInWorld(p, ref));
        p.pins.push_back(pin);
      }
    REQUIRE(PinsIn(p, p.images[1].id) == 6);
    Project out;
    const MultiViewInitSummary summary = CalibrateImagesFromPins(p, {}, &out);
    INFO(Messages(summary));
    CHECK(summary.num_initialized == 0);
    REQUIRE(summary.messages.size() == 1);
    CHECK(summary.messages[0].find("6 pins on known vertices, resection failed") != std::string::npos);
    CHECK(out == p);
  }
  SUBCASE("invalid options") {
    Scene s = MakeScene({});
    MultiViewInitOptions options;
    options.wrong_click_threshold_px = -1.0;
    Project out;
    const MultiViewInitSummary summary = CalibrateImagesFromPins(s.project, options, &out);
    CHECK_FALSE(summary.IsUsable());
    CHECK(summary.message.find("wrong_click_threshold_px") != std::string::npos);
    CHECK(out == s.project);
  }
}

// ---- Issue 26: later cameras from pins ----

// Keeps only the pins of image_id on the given (box index, corner) pairs.
void KeepPinsOn(Scene* s, Id image_id, const std::vector<std::pair<int, int>>& corners) {
  auto& pins = s->project.pins;
  std::erase_if(pins, [&](const Pin& pin) {
    if (pin.image_id != image_id) return false;
    for (const auto& [box, corner] : corners)
      if (pin.vertex.primitive_id == s->box_ids[box] && static_cast<int>(pin.vertex.vertex) == corner) return false;
    return true;
  });
}

// Moves a box and puts every pin where its image's true camera sees the vertex now.
void MoveBoxAndReproject(Scene* s, int box, const Eigen::Vector3d& shift) {
  Project& p = s->project;
  p.FindPrimitive(s->box_ids[box])->shape.translation += shift;
  RefreshAllPrimitives(&p);
  for (Pin& pin : p.pins) {
    for (size_t i = 0; i < p.images.size(); ++i)
      if (p.images[i].id == pin.image_id) pin.uv_px = s->truth[i].Project(VertexInWorld(p, pin.vertex));
  }
}

// Noise-free recovery of the second photo's camera (relative focal length and translation,
// rotation in radians).
constexpr double kResectedTol = 1e-6;

void CheckResected(const Camera& estimate, const Camera& truth) {
  const CameraErrors e = Compare(estimate, truth);
  CAPTURE(e.focal_rel);
  CAPTURE(e.rotation_rad);
  CAPTURE(e.translation_rel);
  CHECK(e.focal_rel < kResectedTol);
  CHECK(e.rotation_rad < kResectedTol);
  CHECK(e.translation_rel < kResectedTol);
}

TEST_CASE("resection: 4 pins on a common plane spread over two boxes, not exactly coplanar in the model") {
  SceneSpec spec;
  spec.extra_boxes = 1;
  spec.principal_point_offset_px = Eigen::Vector2d::Zero();  // one view of a plane cannot fix it
  Scene s = MakeScene(spec);
  // The solved model puts the second box's foot 3 cm above the first's (a thickness of
  // ~1e-3 of the points' extent: no plane holds all four): the exact-plane test (1e-4) says "not coplanar", and 4
  // points off a plane were refused ("needs 6, or 4 on one face").
  MoveBoxAndReproject(&s, 1, Eigen::Vector3d(0.0, 0.0, 0.03));
  const Id image_id = s.project.images[1].id;
  KeepPinsOn(&s, image_id, {{0, 0}, {0, 1}, {1, 0}, {1, 3}});
  REQUIRE(PinsIn(s.project, image_id) == 4);
  Project out;
  const MultiViewInitSummary summary = CalibrateImagesFromPins(s.project, {}, &out);
  INFO(Messages(summary));
  const MultiViewImageReport& report = summary.images[1];
  REQUIRE(report.path == MultiViewInitPath::kResection);
  CHECK(report.message.find("nearly planar") != std::string::npos);
  CheckResected(out.images[1].camera, s.truth[1]);
  MESSAGE("4 pins over two boxes, 3 cm off one plane: " << report.message);
}

TEST_CASE("resection: 6 non-planar pins spread over two boxes take the DLT") {
  SceneSpec spec;
  spec.extra_boxes = 1;
  Scene s = MakeScene(spec);
  const Id image_id = s.project.images[1].id;
  KeepPinsOn(&s, image_id, {{0, 0}, {0, 1}, {0, 5}, {1, 2}, {1, 3}, {1, 6}});
  REQUIRE(PinsIn(s.project, image_id) == 6);
  Project out;
  const MultiViewInitSummary summary = CalibrateImagesFromPins(s.project, {}, &out);
  INFO(Messages(summary));
  const MultiViewImageReport& report = summary.images[1];
  REQUIRE(report.path == MultiViewInitPath::kResection);
  CHECK(report.message.rfind("resection from 6 pins", 0) == 0);  // the DLT, principal point free
  CheckResected(out.images[1].camera, s.truth[1]);
  CHECK(Compare(out.images[1].camera, s.truth[1]).principal_point_px < kResectedTol * s.truth[1].focal_px);
}

TEST_CASE("resection: 4 non-planar pins with the focal length of a shared lens or EXIF give the pose") {
  SceneSpec spec;
  spec.extra_boxes = 1;
  spec.principal_point_offset_px = Eigen::Vector2d::Zero();
  Scene s = MakeScene(spec);
  const Id image_id = s.project.images[1].id;
  KeepPinsOn(&s, image_id, {{0, 0}, {0, 5}, {1, 1}, {1, 6}});
  REQUIRE(PinsIn(s.project, image_id) == 4);
  REQUIRE(s.truth[0].focal_px == s.truth[1].focal_px);  // one lens
  {
    // Alone, 4 pins off a plane do not fix f: refused, and the message says what would.
    Project out;
    const MultiViewInitSummary summary = CalibrateImagesFromPins(s.project, {}, &out);
    INFO(Messages(summary));
    CHECK(summary.images[1].path == MultiViewInitPath::kNone);
    CHECK(summary.images[1].message.find("no focal length is known") != std::string::npos);
  }
  SUBCASE("the lens shared with the calibrated photo") {
    for (Image& image : s.project.images) image.lens_group = 1;
    Project out;
    const MultiViewInitSummary summary = CalibrateImagesFromPins(s.project, {}, &out);
    INFO(Messages(summary));
    const MultiViewImageReport& report = summary.images[1];
    REQUIRE(report.path == MultiViewInitPath::kResection);
    CHECK(report.message.find("pose with the known focal length") == 0);
    CHECK(report.message.find("shares with image 'synthetic.png'") != std::string::npos);
    CHECK(out.images[1].camera.focal_px == s.project.images[0].camera.focal_px);
    CheckResected(out.images[1].camera, s.truth[1]);
  }
  SUBCASE("EXIF") {
    MultiViewInitOptions options;
    options.focal_px_by_image[image_id] = s.truth[1].focal_px;
    Project out;
    const MultiViewInitSummary summary = CalibrateImagesFromPins(s.project, options, &out);
    INFO(Messages(summary));
    const MultiViewImageReport& report = summary.images[1];
    REQUIRE(report.path == MultiViewInitPath::kResection);
    CHECK(report.message.find("EXIF") != std::string::npos);
    CheckResected(out.images[1].camera, s.truth[1]);
  }
}

TEST_CASE("resection: a focal length beyond any lens is refused by name, not kept") {
  // The second photo taken with a 350-diagonal telephoto from far away: the DLT measures its
  // focal length (f = 4.5e5 px), which Facet does not accept as a camera.
  SceneSpec spec;
  spec.extra_boxes = 1;
  Scene s = MakeScene(spec);
  Camera& far = s.truth[1];
  const Eigen::Vector3d target(2.0, 1.5, 1.2);
  constexpr double kZoom = 500.0;
  far.SetPose(far.cam_from_world_rotation, target + kZoom * (far.CenterInWorld() - target));
  far.focal_px *= kZoom;
  MoveBoxAndReproject(&s, 0, Eigen::Vector3d::Zero());
  const Id image_id = s.project.images[1].id;
  KeepPinsOn(&s, image_id, {{0, 0}, {0, 1}, {0, 5}, {1, 2}, {1, 3}, {1, 6}});
  REQUIRE(PinsIn(s.project, image_id) == 6);  // fewer than two views need: resection alone
  Project out;
  const MultiViewInitSummary summary = CalibrateImagesFromPins(s.project, {}, &out);
  INFO(Messages(summary));
  const MultiViewImageReport& report = summary.images[1];
  CHECK(report.path == MultiViewInitPath::kNone);
  CHECK_FALSE(out.images[1].camera_calibrated);
  CHECK(report.message.find("f = 450000 px is") != std::string::npos);
  CHECK(report.message.find("image diagonals, outside any lens") != std::string::npos);
  CHECK(out == s.project);
}

TEST_CASE("epipolar line: through the true match, clipped to the image, absent when it misses") {
  const Scene s = MakeScene({});
  const Eigen::Matrix3d F = FundamentalFromCameras(s.truth[0], s.truth[1]);
  const int w = s.truth[1].width_px, h = s.truth[1].height_px;
  int drawn = 0;
  for (VertexId v = 0; v < 8; ++v) {
    const Eigen::Vector3d x = VertexInWorld(s.project, {s.box_ids[0], v});
    const EpipolarLine line = EpipolarLineInImage(F, s.truth[0].Project(x), w, h);
    const Eigen::Vector2d uv1 = s.truth[1].Project(x);
    CAPTURE(v);
    CHECK(std::abs(line.line.head<2>().norm() - 1.0) < 1e-12);
    // Signed distance in px of the true match to the line.
    CHECK(std::abs(line.line.dot(uv1.homogeneous())) < 1e-9);
    REQUIRE(line.segment_px.has_value());
    ++drawn;
    for (const Eigen::Vector2d& end : {line.segment_px->first, line.segment_px->second}) {
      CHECK(std::abs(line.line.dot(end.homogeneous())) < 1e-9);
      const double to_border = std::min({std::abs(end.x() + 0.5), std::abs(end.x() - (w - 0.5)),
                                         std::abs(end.y() + 0.5), std::abs(end.y() - (h - 0.5))});
      CHECK(to_border < 1e-9);
    }
  }
  CHECK(drawn == 8);
  // A line v = 5000 misses a 1024 x 768 image; a zero F gives no line.
  Eigen::Matrix3d far = Eigen::Matrix3d::Zero();
  far(1, 2) = 1.0;
  far(2, 2) = -5000.0;
  const EpipolarLine missed = EpipolarLineInImage(far, Eigen::Vector2d(10.0, 10.0), w, h);
  CHECK(missed.line.norm() > 0.0);
  CHECK_FALSE(missed.segment_px.has_value());
  const EpipolarLine none = EpipolarLineInImage(Eigen::Matrix3d::Zero(), Eigen::Vector2d(10.0, 10.0), w, h);
  CHECK(none.line.norm() == 0.0);
  CHECK_FALSE(none.segment_px.has_value());
}

TEST_CASE("integration: after resection the model update solves with the second image's pins") {
  constexpr double kRmsTolPx = 1e-6;
  Scene s = MakeScene({});
  const Id id1 = s.project.images[1].id;
  // Without the initialisation the second image's pins are skipped.
  ModelUpdateOptions no_init;
  no_init.initialize_from_pins = false;
  Project before;
  const ModelUpdateSummary skipped = UpdateModel(s.project, no_init, &before);
  CHECK(skipped.solve.num_skipped_pins == PinsIn(s.project, id1));
  CHECK_FALSE(before.images[1].camera_calibrated);

  Project initialised;
  const MultiViewInitSummary init = CalibrateImagesFromPins(s.project, {}, &initialised);
  INFO(Messages(init));
  REQUIRE(init.images[1].path == MultiViewInitPath::kResection);
  // The user then edits the box: its free dimensions away from the truth.
  Primitive& box = initialised.primitives[0];
  box.shape.params.x() *= 1.3;
  box.shape.params.y() *= 0.75;
  RefreshPrimitive(&initialised, &box);
  REQUIRE((box.shape.params.head<3>() - s.project.primitives[0].shape.params.head<3>()).norm() > 0.5);

  Project updated;
  const ModelUpdateSummary summary = UpdateModel(initialised, ModelUpdateOptions(), &updated);
  INFO("solve: " << summary.solve.message << "; joint: " << summary.joint.message);
  REQUIRE(summary.ok);
  REQUIRE(summary.joint.IsUsable());
  CHECK(summary.solve.num_skipped_pins == 0);
  bool second_took_part = false;
  for (const ImageDiagnostic& d : summary.joint.images)
    if (d.image_id == id1 && d.num_pins == PinsIn(s.project, id1)) second_took_part = true;
  CHECK(second_took_part);
  const Eigen::Vector3d size = updated.primitives[0].shape.params.head<3>();
  const Eigen::Vector3d true_size = s.project.primitives[0].shape.params.head<3>();
  const double size_error = (size - true_size).norm() / true_size.norm();
  const CameraErrors e1 = Compare(updated.images[1].camera, s.truth[1]);
  MESSAGE("integration: joint RMS " << summary.joint.reprojection_rms_px << " px, size " << size_error
                                    << ", camera 1 rotation " << e1.rotation_rad << " rad, t " << e1.translation_rel);
  CHECK(summary.joint.reprojection_rms_px < kRmsTolPx);
  CHECK(size_error < kExactTol);
  CHECK(e1.rotation_rad < kExactTol);
  CHECK(e1.translation_rel < kExactTol);
}

TEST_CASE("integration: two views and self-calibration, then the model update solves with every image") {
  // Two views with the focal length given, or three self-calibrated; then the user edits box 0
  // and the update recovers it from the initialised cameras' pins alone (no line families).
  constexpr double kRmsTolPx = 1e-6;
  for (const int num_views : {2, 3}) {
    CAPTURE(num_views);
    Scene s = MakeScene(UncalibratedSpec(num_views));
    const MultiViewInitOptions options = num_views == 2 ? KnownFocal(s) : MultiViewInitOptions();
    Project initialised;
    const MultiViewInitSummary init = CalibrateImagesFromPins(s.project, options, &initialised);
    INFO(Messages(init));
    REQUIRE(init.num_initialized == num_views);
    Primitive& box = initialised.primitives[0];
    box.shape.params.x() *= 1.3;
    box.shape.params.y() *= 0.75;
    RefreshPrimitive(&initialised, &box);
    REQUIRE((box.shape.params.head<3>() - s.project.primitives[0].shape.params.head<3>()).norm() > 0.5);

    Project updated;
    const ModelUpdateSummary summary = UpdateModel(initialised, ModelUpdateOptions(), &updated);
    INFO("solve: " << summary.solve.message << "; joint: " << summary.joint.message);
    REQUIRE(summary.ok);
    REQUIRE(summary.joint.IsUsable());
    CHECK(summary.solve.num_skipped_pins == 0);
    CHECK(static_cast<int>(summary.joint.images.size()) == num_views);
    const Eigen::Vector3d size = updated.primitives[0].shape.params.head<3>();
    const Eigen::Vector3d true_size = s.project.primitives[0].shape.params.head<3>();
    const double size_error = (size - true_size).norm() / true_size.norm();
    MESSAGE("integration " << num_views << " views: joint RMS " << summary.joint.reprojection_rms_px << " px, size "
                           << size_error);
    CHECK(summary.joint.reprojection_rms_px < kRmsTolPx);
    CHECK(size_error < kExactTol);
  }
}

TEST_CASE("the recommended wiring: VP calibration and geometry solve, then pins initialise image 1, then the update") {
  // The edit leaves image 0's camera and the box away from the truth, so the model's vertex
  // positions are wrong before the geometry solve: resection must use the solved model.
  constexpr double kRmsTolPx = 1e-6;
  Scene s = MakeScene({});
  Image& image0 = s.project.images[0];
  image0.camera.focal_px *= 1.2;
  const Eigen::Matrix3d tilt = RotationFromAngleAxis(Eigen::Vector3d(0.05, -0.03, 0.08));
  image0.camera.SetPose(tilt * image0.camera.cam_from_world_rotation,
                        image0.camera.CenterInWorld() + Eigen::Vector3d(1.2, -0.8, 0.6));
  Primitive& box = s.project.primitives[0];
  box.shape.params.x() *= 1.3;
  box.shape.params.y() *= 0.75;
  RefreshPrimitive(&s.project, &box);
  const Eigen::Vector3d true_size = MakeScene({}).project.primitives[0].shape.params.head<3>();
  REQUIRE((box.shape.params.head<3>() - true_size).norm() > 0.5);

  // 1. VP calibration and the geometry solve (image 1's pins skipped).
  ModelUpdateOptions first;
  first.joint_solve = false;
  first.initialize_from_pins = false;
  Project solved;
  const ModelUpdateSummary step1 = UpdateModel(s.project, first, &solved);
  REQUIRE(step1.ok);
  CHECK(step1.solve.num_skipped_pins == PinsIn(s.project, s.project.images[1].id));
  // 2. Pins initialise image 1 against the solved model.
  Project initialised;
  const MultiViewInitSummary init = CalibrateImagesFromPins(solved, {}, &initialised);
  INFO(Messages(init));
  REQUIRE(init.images[1].path == MultiViewInitPath::kResection);
  // 3. The update with every image.
  Project updated;
  const ModelUpdateSummary step3 = UpdateModel(initialised, ModelUpdateOptions(), &updated);
  INFO("solve: " << step3.solve.message << "; joint: " << step3.joint.message);
  REQUIRE(step3.ok);
  REQUIRE(step3.joint.IsUsable());
  CHECK(step3.solve.num_skipped_pins == 0);
  const double size_error = (updated.primitives[0].shape.params.head<3>() - true_size).norm() / true_size.norm();
  const CameraErrors e1 = Compare(updated.images[1].camera, s.truth[1]);
  MESSAGE("wiring: resection RMS " << init.images[1].residual_px << " px, joint RMS " << step3.joint.reprojection_rms_px
                                   << " px, size " << size_error << ", camera 1 " << e1.rotation_rad << " rad, t "
                                   << e1.translation_rel);
  CHECK(step3.joint.reprojection_rms_px < kRmsTolPx);
  CHECK(size_error < kExactTol);
  CHECK(e1.rotation_rad < kExactTol);
  CHECK(e1.translation_rel < kExactTol);
}

TEST_CASE("UpdateModel initialises an image without line families from its pins in the same update") {
  // The same edit as above, in one call: the wiring in core/solve/model_update.cpp.
  constexpr double kRmsTolPx = 1e-6;
  Scene s = MakeScene({});
  Image& image0 = s.project.images[0];
  image0.camera.focal_px *= 1.2;
  image0.camera.SetPose(
      RotationFromAngleAxis(Eigen::Vector3d(0.05, -0.03, 0.08)) * image0.camera.cam_from_world_rotation,
      image0.camera.CenterInWorld() + Eigen::Vector3d(1.2, -0.8, 0.6));
  Primitive& box = s.project.primitives[0];
  box.shape.params.x() *= 1.3;
  RefreshPrimitive(&s.project, &box);
  const Eigen::Vector3d true_size = MakeScene({}).project.primitives[0].shape.params.head<3>();
  REQUIRE_FALSE(s.project.images[1].camera_calibrated);

  Project updated;
  const ModelUpdateSummary summary = UpdateModel(s.project, ModelUpdateOptions(), &updated);
  INFO("solve: " << summary.solve.message << "; joint: " << summary.joint.message);
  REQUIRE(summary.ok);
  REQUIRE(summary.multiview.images.size() == 2);
  CHECK(summary.multiview.images[1].path == MultiViewInitPath::kResection);
  CHECK(summary.multiview.num_initialized == 1);
  CHECK(updated.images[1].camera_calibrated);
  CHECK(summary.solve.num_skipped_pins == 0);
  REQUIRE(summary.joint.IsUsable());
  CHECK(summary.joint.reprojection_rms_px < kRmsTolPx);
  const double size_error = (updated.primitives[0].shape.params.head<3>() - true_size).norm() / true_size.norm();
  CHECK(size_error < kExactTol);
  const CameraErrors e1 = Compare(updated.images[1].camera, s.truth[1]);
  CHECK(e1.rotation_rad < kExactTol);
  CHECK(e1.translation_rel < kExactTol);

  // The per-frame path leaves a new image alone (it is initialised by the commit).
  ModelUpdateOptions frame;
  frame.initialize_from_pins = false;
  Project frame_updated;
  const ModelUpdateSummary frame_summary = UpdateModel(s.project, frame, &frame_updated);
  CHECK(frame_summary.multiview.num_initialized == 0);
  CHECK_FALSE(frame_updated.images[1].camera_calibrated);
}

}  // namespace
}  // namespace facet
