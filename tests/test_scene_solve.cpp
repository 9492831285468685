// The geometry solve (core/solve/scene_solve.h): analytic Jacobian against finite differences,
// recovery of a synthetic box and camera from its pinned corners (noise-free and noisy, at
// several scales), degenerate inputs and the speed of the interactive (warm-started) path.
#include <doctest/doctest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "core/geometry/camera.h"
#include "core/mesh/extrude.h"
#include "core/mesh/operators.h"
#include "core/scene/project.h"
#include "core/solve/scene_solve.h"
#include "core/solve/scene_solve_internal.h"
#include "tests/synthetic_scene.h"

namespace facet {
namespace {

namespace internal = scene_solve_internal;
using testing::MakeBoxScene;
using testing::SyntheticScene;
using testing::SyntheticSceneOptions;

double RelativeError(const Eigen::VectorXd& estimate, const Eigen::VectorXd& truth) {
  return (estimate - truth).norm() / truth.norm();
}

// Angle (rad) of the rotation between two angle-axis vectors.
double RotationErrorRad(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return Eigen::AngleAxisd(RotationFromAngleAxis(a) * RotationFromAngleAxis(b).transpose()).angle();
}

bool HasWarningContaining(const SceneSolveSummary& summary, const std::string& text) {
  return std::any_of(summary.warnings.begin(), summary.warnings.end(),
                     [&](const std::string& w) { return w.find(text) != std::string::npos; });
}

std::string AllWarnings(const SceneSolveSummary& summary) {
  std::string out;
  for (const auto& w : summary.warnings) out += "[" + w + "] ";
  return out;
}

Eigen::Vector3d Size(const Primitive& primitive) { return primitive.shape.params.head<3>(); }

// Moves the free box sizes (x, y) and the camera centre well away from the truth, by amounts
// relative to the scene's scale so that every scale sees the same problem.
void PerturbSizeAndCamera(SyntheticScene* scene, double scale) {
  Primitive& box = scene->project.primitives[0];
  box.shape.params.x() *= 1.3;
  box.shape.params.y() *= 0.75;
  RefreshPrimitive(&scene->project, &box);
  Camera& camera = scene->project.images[0].camera;
  camera.SetPose(camera.cam_from_world_rotation, camera.CenterInWorld() + scale * Eigen::Vector3d(1.2, -0.8, 0.6));
}

Eigen::Vector3d CameraCenter(const Project& project) { return project.images[0].camera.CenterInWorld(); }

// Adds a second calibrated image looking at the box from another side, with its 8 pins.
void AddSecondImage(SyntheticScene* scene, const SyntheticSceneOptions& options) {
  SyntheticSceneOptions other = options;
  other.camera_center = {-6.0, -8.0, 6.0};
  other.roll_deg = -2.0;
  Image image = scene->project.images[0];
  image.id = scene->project.NewId();
  image.path = "second.png";
  image.camera = testing::MakeLookAtCamera(other);
  scene->project.images.push_back(image);
  for (int c = 0; c < 8; ++c) {
    Pin pin;
    pin.id = scene->project.NewId();
    pin.image_id = image.id;
    pin.vertex = {scene->box_id, static_cast<VertexId>(c)};
    pin.uv_px = image.camera.Project(scene->true_box.mesh.vertex(c).position);
    scene->project.pins.push_back(pin);
  }
}

TEST_CASE("analytic Jacobian matches central finite differences for every parameter kind") {
  SyntheticSceneOptions options;
  SyntheticScene scene = MakeBoxScene(options);
  AddSecondImage(&scene, options);
  Primitive& box = scene.project.primitives[0];
  box.param_locked = {false, false, false, false};
  box.rotation_locked = false;
  box.translation_locked = false;
  // A generic state, away from the truth, so that no derivative vanishes by symmetry.
  box.shape.rotation = Eigen::Vector3d(0.2, -0.1, 0.3);
  box.shape.translation = Eigen::Vector3d(0.3, -0.2, 0.1);
  RefreshPrimitive(&scene.project, &box);
  scene.project.images[1].pose_locked = false;

  internal::SceneState state;
  const internal::SceneProblem problem = internal::BuildSceneProblem(scene.project, &state);
  REQUIRE(problem.observations.size() == 16);
  REQUIRE(problem.num_parameters == 2 * 3 + 3 + 3 + 3);

  Eigen::VectorXd residuals;
  Eigen::MatrixXd jacobian;
  REQUIRE(internal::EvaluateScene(problem, state, &residuals, &jacobian) == 0);

  // Central differences have truncation error O(h^2) ~ 1e-12 and rounding error
  // ~ eps * |r| / h ~ 1e-7 px against columns of ~1e2 px per unit: 1e-6 relative is safe.
  constexpr double kLengthStep = 1e-5;  // world units; the scene is ~5 units across
  constexpr double kAngleStep = 1e-5;   // rad
  constexpr double kRelativeTolerance = 1e-6;
  int kinds_seen[4] = {0, 0, 0, 0};
  for (int j = 0; j < problem.num_parameters; ++j) {
    const auto kind = problem.parameters[j].kind;
    ++kinds_seen[static_cast<int>(kind)];
    const double h = kind == internal::ParameterKind::kPrimitiveRotation ? kAngleStep : kLengthStep;
    Eigen::VectorXd delta = Eigen::VectorXd::Zero(problem.num_parameters);
    Eigen::VectorXd r_plus, r_minus;
    internal::SceneState plus = state, minus = state;
    delta(j) = h;
    internal::ApplySceneStep(problem, delta, &plus);
    delta(j) = -h;
    internal::ApplySceneStep(problem, delta, &minus);
    internal::EvaluateScene(problem, plus, &r_plus, nullptr);
    internal::EvaluateScene(problem, minus, &r_minus, nullptr);
    const Eigen::VectorXd numeric = (r_plus - r_minus) / (2.0 * h);
    const double column_norm = jacobian.col(j).norm();
    const double error = (numeric - jacobian.col(j)).norm() / column_norm;
    CAPTURE(j);
    CAPTURE(static_cast<int>(kind));
    CAPTURE(problem.parameters[j].component);
    CAPTURE(column_norm);
    CAPTURE(error);
    CHECK(column_norm > 1.0);  // px per unit: every parameter moves some pin
    CHECK(error < kRelativeTolerance);
  }
  CHECK(kinds_seen[static_cast<int>(internal::ParameterKind::kCameraCenter)] == 6);
  CHECK(kinds_seen[static_cast<int>(internal::ParameterKind::kPrimitiveParam)] == 3);
  CHECK(kinds_seen[static_cast<int>(internal::ParameterKind::kPrimitiveRotation)] == 3);
  CHECK(kinds_seen[static_cast<int>(internal::ParameterKind::kPrimitiveTranslation)] == 3);
}

TEST_CASE("noise-free: box size and camera centre are recovered from a far start, cold and warm") {
  constexpr double kRelativeTolerance = 1e-9;
  constexpr double kRmsTolerancePx = 1e-6;
  for (const bool warm_start : {false, true}) {
    CAPTURE(warm_start);
    SyntheticScene scene = MakeBoxScene();
    PerturbSizeAndCamera(&scene, 1.0);
    const Eigen::Vector3d true_center = scene.true_camera.CenterInWorld();
    REQUIRE(RelativeError(Size(scene.project.primitives[0]), Size(scene.true_box)) > 0.1);
    REQUIRE(RelativeError(CameraCenter(scene.project), true_center) > 0.1);

    SceneSolveOptions options;
    options.warm_start = warm_start;
    Project solved;
    const SceneSolveSummary summary = SolveScene(scene.project, options, &solved);
    const double size_error = RelativeError(Size(solved.primitives[0]), Size(scene.true_box));
    const double center_error = RelativeError(CameraCenter(solved), true_center);
    INFO(summary.message, " ", AllWarnings(summary));
    CAPTURE(summary.iterations);
    CAPTURE(size_error);
    CAPTURE(center_error);
    CAPTURE(summary.reprojection_rms_px);
    REQUIRE(summary.IsUsable());
    CHECK(summary.linear_initialization_used == !warm_start);
    CHECK(summary.num_residuals == 16);
    CHECK(summary.num_parameters == 5);
    MESSAGE("noise-free, ", warm_start ? "warm" : "cold", ": ", summary.iterations, " iterations (", summary.message,
            "), size error ", size_error, ", centre error ", center_error, " (relative), RMS ",
            summary.reprojection_rms_px, " px");
    CHECK(size_error < kRelativeTolerance);
    CHECK(center_error < kRelativeTolerance);
    CHECK(summary.reprojection_rms_px < kRmsTolerancePx);
    CHECK(summary.initial_cost > 1.0);
    CHECK(summary.final_cost < summary.initial_cost);
    CHECK(summary.warnings.empty());
    // The locked height is the known length and must not move.
    CHECK(solved.primitives[0].shape.params.z() == scene.project.primitives[0].shape.params.z());
    // The cached vertex positions follow the solved shape: corner 6 is (sx, sy, sz).
    CHECK((solved.primitives[0].mesh.vertex(6).position - scene.true_box.mesh.vertex(6).position).norm() <
          kRelativeTolerance * Size(scene.true_box).norm());
    REQUIRE(summary.pin_residuals_px.size() == solved.pins.size());
    for (double e : summary.pin_residuals_px) CHECK(e < kRmsTolerancePx);
  }
}

TEST_CASE("noise-free: two images with free centres are recovered") {
  constexpr double kRelativeTolerance = 1e-9;
  SyntheticSceneOptions scene_options;
  SyntheticScene scene = MakeBoxScene(scene_options);
  AddSecondImage(&scene, scene_options);
  const Eigen::Vector3d true_center_2 = scene.project.images[1].camera.CenterInWorld();
  PerturbSizeAndCamera(&scene, 1.0);
  Camera& second = scene.project.images[1].camera;
  second.SetPose(second.cam_from_world_rotation, true_center_2 + Eigen::Vector3d(-0.9, 0.7, -0.5));
  for (const bool warm_start : {false, true}) {
    CAPTURE(warm_start);
    SceneSolveOptions options;
    options.warm_start = warm_start;
    Project solved;
    const SceneSolveSummary summary = SolveScene(scene.project, options, &solved);
    INFO(summary.message, " ", AllWarnings(summary));
    REQUIRE(summary.IsUsable());
    const double size_error = RelativeError(Size(solved.primitives[0]), Size(scene.true_box));
    const double center_1_error = RelativeError(CameraCenter(solved), scene.true_camera.CenterInWorld());
    const double center_2_error = RelativeError(solved.images[1].camera.CenterInWorld(), true_center_2);
    CAPTURE(size_error);
    CAPTURE(center_1_error);
    CAPTURE(center_2_error);
    CHECK(size_error < kRelativeTolerance);
    CHECK(center_1_error < kRelativeTolerance);
    CHECK(center_2_error < kRelativeTolerance);
    CHECK(summary.reprojection_rms_px < 1e-6);
  }
}

TEST_CASE("noise-free: free rotation and translation with the camera pose locked are recovered") {
  constexpr double kRelativeTolerance = 1e-9;
  constexpr double kAngleToleranceRad = 1e-9;
  for (const bool warm_start : {false, true}) {
    CAPTURE(warm_start);
    SyntheticSceneOptions scene_options;
    scene_options.box_translation = {0.5, -0.3, 0.2};
    SyntheticScene scene = MakeBoxScene(scene_options);
    scene.project.images[0].pose_locked = true;
    Primitive& box = scene.project.primitives[0];
    box.rotation_locked = false;
    box.translation_locked = false;
    box.shape.params.x() *= 1.2;
    box.shape.params.y() *= 0.85;
    box.shape.rotation = Eigen::Vector3d(0.05, -0.08, 0.1);
    box.shape.translation += Eigen::Vector3d(0.3, -0.2, 0.1);
    RefreshPrimitive(&scene.project, &box);
    REQUIRE(RotationErrorRad(box.shape.rotation, scene.true_box.shape.rotation) > 0.1);
    REQUIRE(RelativeError(box.shape.translation, scene.true_box.shape.translation) > 0.3);

    SceneSolveOptions options;
    options.warm_start = warm_start;
    Project solved;
    const SceneSolveSummary summary = SolveScene(scene.project, options, &solved);
    INFO(summary.message, " ", AllWarnings(summary));
    REQUIRE(summary.IsUsable());
    CHECK(summary.num_parameters == 8);
    const Primitive& solved_box = solved.primitives[0];
    const double size_error = RelativeError(Size(solved_box), Size(scene.true_box));
    const double angle_error = RotationErrorRad(solved_box.shape.rotation, scene.true_box.shape.rotation);
    const double translation_error =
        (solved_box.shape.translation - scene.true_box.shape.translation).norm() / Size(scene.true_box).norm();
    CAPTURE(size_error);
    CAPTURE(angle_error);
    CAPTURE(translation_error);
    MESSAGE("rotation+translation free, ", warm_start ? "warm" : "cold", ": ", summary.iterations,
            " iterations, size error ", size_error, ", angle error ", angle_error, " rad, translation error ",
            translation_error);
    CHECK(size_error < kRelativeTolerance);
    CHECK(angle_error < kAngleToleranceRad);
    CHECK(translation_error < kRelativeTolerance);
    CHECK(summary.reprojection_rms_px < 1e-6);
    CHECK(solved.images[0].camera == scene.project.images[0].camera);
  }
}

TEST_CASE("0.5 px noise: errors agree with the Jacobian covariance and the RMS with the dof") {
  constexpr double kNoisePx = 0.5;
  constexpr int kNumSeeds = 20;
  // Each error is within 4 standard deviations of the first-order covariance
  // sigma^2 (J^T J)^-1 (a two-sided 4-sigma event has probability 6e-5 per check).
  constexpr double kSigmaBound = 4.0;
  double sum_rms_sq = 0.0, sum_z_sq = 0.0;
  int num_z = 0, m = 0, n = 0;
  for (int seed = 1; seed <= kNumSeeds; ++seed) {
    SyntheticSceneOptions scene_options;
    scene_options.noise_px = kNoisePx;
    scene_options.seed = static_cast<unsigned>(seed);
    SyntheticScene scene = MakeBoxScene(scene_options);
    PerturbSizeAndCamera(&scene, 1.0);
    Project solved;
    const SceneSolveSummary summary = SolveScene(scene.project, SceneSolveOptions(), &solved);
    CAPTURE(seed);
    INFO(summary.message, " ", AllWarnings(summary));
    REQUIRE(summary.IsUsable());
    CHECK(summary.termination == SolverTermination::kConverged);

    internal::SceneState state;
    const internal::SceneProblem problem = internal::BuildSceneProblem(solved, &state);
    Eigen::VectorXd residuals;
    Eigen::MatrixXd jacobian;
    internal::EvaluateScene(problem, state, &residuals, &jacobian);
    const Eigen::MatrixXd covariance = kNoisePx * kNoisePx * (jacobian.transpose() * jacobian).inverse();
    m = static_cast<int>(jacobian.rows());
    n = static_cast<int>(jacobian.cols());

    Eigen::VectorXd error(n);
    const Eigen::Vector3d center_error = CameraCenter(solved) - scene.true_camera.CenterInWorld();
    for (int j = 0; j < n; ++j) {
      const auto& info = problem.parameters[j];
      error(j) = info.kind == internal::ParameterKind::kPrimitiveParam
                     ? solved.primitives[0].shape.params(info.component) - scene.true_box.shape.params(info.component)
                     : center_error(info.component);
      const double sigma = std::sqrt(covariance(j, j));
      CAPTURE(j);
      CAPTURE(error(j));
      CAPTURE(sigma);
      CHECK(std::abs(error(j)) < kSigmaBound * sigma);
      sum_z_sq += error(j) * error(j) / (sigma * sigma);
      ++num_z;
    }
    sum_rms_sq += summary.reprojection_rms_px * summary.reprojection_rms_px;
  }
  REQUIRE(m == 16);
  REQUIRE(n == 5);
  // reprojection_rms_px is over pins (2 residuals each): E[rms^2] = sum r^2 / (m/2) =
  // 2 sigma^2 (m - n) / m, i.e. sigma * sqrt((m - n) / m) per coordinate. rms^2 is a scaled
  // chi^2 with m - n = 11 dof, relative std sqrt(2/11) = 0.43; its mean over 20 seeds has a
  // relative std of 0.095, so 0.3 is a 3-sigma bound.
  const double expected_rms_sq = 2.0 * kNoisePx * kNoisePx * (m - n) / m;
  const double mean_rms_sq = sum_rms_sq / kNumSeeds;
  CAPTURE(expected_rms_sq);
  CAPTURE(mean_rms_sq);
  MESSAGE("noise 0.5 px: mean RMS ", std::sqrt(mean_rms_sq), " px (per pin), expected ", std::sqrt(expected_rms_sq),
          " px; per coordinate ", std::sqrt(mean_rms_sq / 2.0),
          " vs 0.5*sqrt((m-n)/m) = ", kNoisePx * std::sqrt(double(m - n) / m));
  CHECK(std::abs(mean_rms_sq / expected_rms_sq - 1.0) < 0.3);
  // The normalised squared errors average 1 if the covariance is right; 100 samples, though
  // correlated within a seed, give a mean well within [0.5, 1.6].
  const double mean_z_sq = sum_z_sq / num_z;
  MESSAGE("noise 0.5 px: mean squared error / predicted variance = ", mean_z_sq, " over ", num_z, " estimates");
  CHECK(mean_z_sq > 0.5);
  CHECK(mean_z_sq < 1.6);
}

TEST_CASE("the same scene at x1e-3 and x1e3 gives the same relative accuracy and iterations") {
  constexpr double kRelativeTolerance = 1e-9;
  for (const bool warm_start : {false, true}) {
    CAPTURE(warm_start);
    int reference_iterations = -1;
    for (const double scale : {1.0, 1e-3, 1e3}) {
      CAPTURE(scale);
      SyntheticSceneOptions scene_options;
      scene_options.scale = scale;
      SyntheticScene scene = MakeBoxScene(scene_options);
      PerturbSizeAndCamera(&scene, scale);
      REQUIRE(RelativeError(Size(scene.project.primitives[0]), Size(scene.true_box)) > 0.1);
      SceneSolveOptions options;
      options.warm_start = warm_start;
      Project solved;
      const SceneSolveSummary summary = SolveScene(scene.project, options, &solved);
      INFO(summary.message, " ", AllWarnings(summary));
      REQUIRE(summary.IsUsable());
      const double size_error = RelativeError(Size(solved.primitives[0]), Size(scene.true_box));
      const double center_error = RelativeError(CameraCenter(solved), scene.true_camera.CenterInWorld());
      CAPTURE(size_error);
      CAPTURE(center_error);
      CAPTURE(summary.iterations);
      MESSAGE("scale ", scale, ", ", warm_start ? "warm" : "cold", ": ", summary.iterations, " iterations (",
              summary.message, "), size error ", size_error, ", centre error ", center_error);
      CHECK(size_error < kRelativeTolerance);
      CHECK(center_error < kRelativeTolerance);
      CHECK(summary.reprojection_rms_px < 1e-6);
      CHECK(summary.warnings.empty());
      if (reference_iterations < 0) {
        reference_iterations = summary.iterations;
      } else {
        CHECK(summary.iterations == reference_iterations);
      }
    }
  }
}

TEST_CASE("two pins in one image: the depth no pin sees is held at its value, and the summary says so") {
  SyntheticScene scene = MakeBoxScene();
  // Corner 0 is the origin, corner 5 is (sx, 0, sz): they fix the camera centre and the width
  // but say nothing about the depth.
  std::vector<Pin> kept;
  for (const Pin& pin : scene.project.pins) {
    if (pin.vertex.vertex == 0 || pin.vertex.vertex == 5) kept.push_back(pin);
  }
  scene.project.pins = kept;
  const double depth_before = scene.project.primitives[0].shape.params.y();
  Project solved;
  const SceneSolveSummary summary = SolveScene(scene.project, SceneSolveOptions(), &solved);
  INFO(summary.message, " ", AllWarnings(summary));
  REQUIRE(summary.IsUsable());
  CHECK(summary.linear_initialization_used);
  REQUIRE(summary.held_parameters.size() == 1);
  MESSAGE("two pins: ", summary.held_parameters[0]);
  CHECK(summary.held_parameters[0].find("depth (y size) of box 'box' is seen by no pin") != std::string::npos);
  CHECK(summary.held_parameters[0].find("back face") != std::string::npos);
  CHECK(solved.primitives[0].shape.params.y() == depth_before);
  CHECK_FALSE(HasWarningContaining(summary, "depth"));
  CHECK_FALSE(HasWarningContaining(summary, "width"));
  CHECK_FALSE(HasWarningContaining(summary, "camera centre"));
}

// A roof on a box (AttachOnTop) takes the box's footprint: a pin on the roof's ridge sees the
// box's depth. This solve treats the two apart and holds that depth, but the note must not tell
// the user that no pin sees it (the joint solve fits it from the ridge), nor name the roof's own
// footprint, which follows the box.
TEST_CASE("held dimensions: a base's footprint seen through the roof on it is not called unseen") {
  SyntheticScene scene = MakeBoxScene();
  Project& p = scene.project;
  std::vector<Pin> kept;  // the box's front bottom corners: the width; the height is locked
  for (const Pin& pin : p.pins) {
    if (pin.vertex.vertex == 0 || pin.vertex.vertex == 1) kept.push_back(pin);
  }
  p.pins = kept;
  Id roof_id = kNoId;
  REQUIRE(AddPrimitiveToProject(&p, MakeWedge(kNoId, Eigen::Vector3d(1.0, 1.0, 1.5)), "roof", &roof_id, nullptr));
  p.primitives.back().attached_to = scene.box_id;
  RefreshAllPrimitives(&p);
  const Primitive& roof = *p.FindPrimitive(roof_id);
  const Eigen::Vector3d box_size = p.primitives[0].shape.params.head<3>();
  REQUIRE(roof.shape.params.head<2>() == box_size.head<2>());  // the footprint follows the box
  // Both ends of the ridge, which runs along x at half the depth.
  for (VertexId v : {4u, 5u}) {
    const Eigen::Vector3d x = roof.mesh.vertex(v).position;
    REQUIRE(std::abs(x.y() - (p.primitives[0].shape.translation.y() + 0.5 * box_size.y())) < 1e-12);
    Pin pin;
    pin.id = p.NewId();
    pin.image_id = scene.image_id;
    pin.vertex = {roof_id, v};
    pin.uv_px = scene.true_camera.Project(x);
    p.pins.push_back(pin);
  }
  Project solved;
  const SceneSolveSummary summary = SolveScene(p, SceneSolveOptions(), &solved);
  INFO(summary.message, " ", AllWarnings(summary));
  REQUIRE(summary.IsUsable());
  for (const std::string& held : summary.held_parameters) {
    MESSAGE("held: ", held);
    CHECK(held.find("of box 'box'") == std::string::npos);
    CHECK(held.find("width") == std::string::npos);
    CHECK(held.find("depth") == std::string::npos);
  }
}

// The new user's first box: added at the origin, pinned by the four corners of its front face
// in a photo whose camera the calibration just put at the origin too (on corner 0). No pin sees
// the depth; before, the linear start was rank deficient, the start not finite, and the solve
// failed with "a pinned vertex lies in the plane of its camera".
TEST_CASE("a new box pinned by its four front corners from a camera at its corner solves, depth held") {
  for (const double noise_px : {0.0, 0.5}) {
    CAPTURE(noise_px);
    SyntheticSceneOptions options;
    options.noise_px = noise_px;
    options.seed = 7;
    SyntheticScene scene = MakeBoxScene(options);
    Primitive& box = scene.project.primitives[0];
    box.param_locked = {false, false, true, false};  // the height is the known length
    box.shape.params.x() = 1.0;
    box.shape.params.y() = 1.0;
    RefreshPrimitive(&scene.project, &box);
    std::vector<Pin> front;
    for (const Pin& pin : scene.project.pins) {
      const VertexId v = pin.vertex.vertex;
      if (v == 0 || v == 1 || v == 4 || v == 5) front.push_back(pin);
    }
    scene.project.pins = front;
    Camera& camera = scene.project.images[0].camera;
    camera.SetPose(camera.cam_from_world_rotation, Eigen::Vector3d::Zero());

    for (const bool warm_start : {false, true}) {
      CAPTURE(warm_start);
      SceneSolveOptions solve_options;
      solve_options.warm_start = warm_start;
      Project solved;
      const SceneSolveSummary summary = SolveScene(scene.project, solve_options, &solved);
      INFO(summary.message, " ", AllWarnings(summary));
      if (warm_start) {
        // The warm start is the corner on the camera: it cannot start, and says the reason.
        CHECK_FALSE(summary.IsUsable());
        continue;
      }
      REQUIRE(summary.IsUsable());
      REQUIRE(summary.held_parameters.size() == 1);
      CHECK(summary.held_parameters[0].find("depth") != std::string::npos);
      CHECK(solved.primitives[0].shape.params.y() == 1.0);
      const double width_error = std::abs(solved.primitives[0].shape.params.x() - scene.true_box.shape.params.x());
      const double center_error = (CameraCenter(solved) - scene.true_camera.CenterInWorld()).norm();
      MESSAGE("front face only, noise ", noise_px, " px: RMS ", summary.reprojection_rms_px, " px, width error ",
              width_error, ", centre error ", center_error);
      if (noise_px == 0.0) {
        CHECK(summary.reprojection_rms_px < 1e-6);
        CHECK(width_error < 1e-9 * scene.true_box.shape.params.x());
        CHECK(center_error < 1e-9 * scene.true_camera.CenterInWorld().norm());
      } else {
        // 8 residuals, 5 parameters: the RMS of a fit to 0.5 px noise, sqrt(3 / 8) x 0.5 on average.
        CHECK(summary.reprojection_rms_px < 3.0 * noise_px);
        // 8 residuals for 5 parameters (the centre too): the width is a few times the 0.2 % one
        // click gives on a ~300 px front (1.8 % with this seed).
        CHECK(width_error < 0.05 * scene.true_box.shape.params.x());
      }
    }
  }
}

TEST_CASE("a scene with no known length or no fixed position says so") {
  SUBCASE("scale") {
    SyntheticScene scene = MakeBoxScene();
    scene.project.primitives[0].param_locked = {false, false, false, false};
    Project solved;
    const SceneSolveSummary summary = SolveScene(scene.project, SceneSolveOptions(), &solved);
    INFO(summary.message, " ", AllWarnings(summary));
    REQUIRE(summary.IsUsable());
    MESSAGE("no known length: ", AllWarnings(summary));
    CHECK(HasWarningContaining(summary, "scale of the scene is not fixed"));
    CHECK_FALSE(HasWarningContaining(summary, "box 'box' is not determined"));
    CHECK(summary.reprojection_rms_px < 1e-6);
  }
  SUBCASE("position") {
    SyntheticScene scene = MakeBoxScene();
    scene.project.primitives[0].translation_locked = false;
    Project solved;
    const SceneSolveSummary summary = SolveScene(scene.project, SceneSolveOptions(), &solved);
    INFO(summary.message, " ", AllWarnings(summary));
    REQUIRE(summary.IsUsable());
    CHECK(HasWarningContaining(summary, "position of the scene is not fixed"));
    CHECK_FALSE(HasWarningContaining(summary, "scale"));
  }
}

TEST_CASE("degenerate inputs: nothing to solve, bad pins and bad options leave the project unchanged") {
  SyntheticScene scene = MakeBoxScene();
  SUBCASE("no pins") {
    scene.project.pins.clear();
    Project solved;
    const SceneSolveSummary summary = SolveScene(scene.project, SceneSolveOptions(), &solved);
    CHECK(summary.termination == SolverTermination::kNothingToSolve);
    CHECK_FALSE(summary.IsUsable());
    CHECK(solved == scene.project);
  }
  SUBCASE("everything locked") {
    scene.project.images[0].pose_locked = true;
    scene.project.primitives[0].param_locked = {true, true, true, true};
    Project solved;
    const SceneSolveSummary summary = SolveScene(scene.project, SceneSolveOptions(), &solved);
    CHECK(summary.termination == SolverTermination::kNothingToSolve);
    CHECK(solved == scene.project);
    // The residuals of the locked scene are still reported.
    CHECK(summary.reprojection_rms_px < 1e-9);
  }
  SUBCASE("a NaN pin") {
    scene.project.pins[3].uv_px.x() = std::numeric_limits<double>::quiet_NaN();
    PerturbSizeAndCamera(&scene, 1.0);
    Project solved;
    const SceneSolveSummary summary = SolveScene(scene.project, SceneSolveOptions(), &solved);
    INFO(summary.message);
    CHECK(
        (summary.termination == SolverTermination::kInvalidInput || summary.termination == SolverTermination::kFailed));
    CHECK(summary.message.find("pin #") != std::string::npos);
    // NaN != NaN, so compare with the NaN replaced in both.
    Project a = solved, b = scene.project;
    CHECK(std::isnan(a.pins[3].uv_px.x()));
    a.pins[3].uv_px.x() = b.pins[3].uv_px.x() = 0.0;
    CHECK(a == b);
  }
  SUBCASE("warm start: a pinned corner at the camera centre fails and leaves the project unchanged") {
    Camera& camera = scene.project.images[0].camera;
    camera.SetPose(camera.cam_from_world_rotation, scene.project.primitives[0].mesh.vertex(0).position);
    SceneSolveOptions warm;
    warm.warm_start = true;
    Project solved;
    const SceneSolveSummary summary = SolveScene(scene.project, warm, &solved);
    INFO(summary.message);
    CHECK(summary.termination == SolverTermination::kFailed);
    CHECK_FALSE(summary.message.empty());
    CHECK(solved == scene.project);
  }
  SUBCASE("cold start: a camera just calibrated at a pinned corner is recovered") {
    // After calibration the camera still sits at the world origin, which is where the first
    // box's corner 0 usually is; the linear initialisation does not need a valid start.
    Camera& camera = scene.project.images[0].camera;
    camera.SetPose(camera.cam_from_world_rotation, scene.project.primitives[0].mesh.vertex(0).position);
    Project solved;
    const SceneSolveSummary summary = SolveScene(scene.project, SceneSolveOptions(), &solved);
    INFO(summary.message);
    REQUIRE(summary.IsUsable());
    const double center_error = (solved.images[0].camera.CenterInWorld() - scene.true_camera.CenterInWorld()).norm();
    CHECK(center_error < 1e-9 * scene.true_camera.CenterInWorld().norm());
  }
  SUBCASE("a pin in an uncalibrated image is skipped with a warning") {
    Image uncalibrated = scene.project.images[0];
    uncalibrated.id = scene.project.NewId();
    uncalibrated.path = "raw.png";
    uncalibrated.camera_calibrated = false;
    scene.project.images.push_back(uncalibrated);
    Pin pin = scene.project.pins[0];
    pin.id = scene.project.NewId();
    pin.image_id = uncalibrated.id;
    scene.project.pins.push_back(pin);
    Project solved;
    const SceneSolveSummary summary = SolveScene(scene.project, SceneSolveOptions(), &solved);
    INFO(AllWarnings(summary));
    REQUIRE(summary.IsUsable());
    CHECK(summary.num_skipped_pins == 1);
    CHECK(summary.num_residuals == 16);
    CHECK(HasWarningContaining(summary, "'raw.png' skipped: the image is not calibrated"));
    CHECK(std::isnan(summary.pin_residuals_px.back()));
  }
  SUBCASE("a pin naming a missing primitive is skipped with a warning") {
    Pin pin = scene.project.pins[0];
    pin.id = scene.project.NewId();
    pin.vertex.primitive_id = scene.project.NewId();
    scene.project.pins.push_back(pin);
    Project solved;
    const SceneSolveSummary summary = SolveScene(scene.project, SceneSolveOptions(), &solved);
    INFO(AllWarnings(summary));
    REQUIRE(summary.IsUsable());
    CHECK(summary.num_skipped_pins == 1);
    CHECK(HasWarningContaining(summary, "pin #" + std::to_string(pin.id) + " refers to a missing primitive"));
    CHECK(std::isnan(summary.pin_residuals_px.back()));
    CHECK(summary.time_ms > 0.0);
  }
  SUBCASE("a pin naming a vertex its primitive does not have is skipped with a warning") {
    Pin pin = scene.project.pins[0];
    pin.id = scene.project.NewId();
    pin.vertex.vertex = 99;
    scene.project.pins.push_back(pin);
    Project solved;
    const SceneSolveSummary summary = SolveScene(scene.project, SceneSolveOptions(), &solved);
    INFO(AllWarnings(summary));
    REQUIRE(summary.IsUsable());
    CHECK(summary.num_skipped_pins == 1);
    CHECK(HasWarningContaining(summary, "pin #" + std::to_string(pin.id) + " names vertex 99"));
  }
  SUBCASE("bad options") {
    SceneSolveOptions options;
    std::string error;
    CHECK(options.Check(&error));
    for (int which = 0; which < 4; ++which) {
      SceneSolveOptions bad;
      if (which == 0) bad.max_iterations = 0;
      if (which == 1) bad.function_tolerance = -1.0;
      if (which == 2) bad.gradient_tolerance = -1.0;
      if (which == 3) bad.parameter_tolerance = -1.0;
      CAPTURE(which);
      CHECK_FALSE(bad.Check(&error));
      Project solved;
      const SceneSolveSummary summary = SolveScene(scene.project, bad, &solved);
      CHECK(summary.termination == SolverTermination::kInvalidInput);
      CHECK_FALSE(summary.message.empty());
      CHECK(solved == scene.project);
    }
  }
}

TEST_CASE("interactive path: warm-started solves while one pin is dragged a pixel at a time") {
  SyntheticScene scene = MakeBoxScene();
  SceneSolveOptions options;
  options.warm_start = true;
  options.max_iterations = 5;
  Project current;
  REQUIRE(SolveScene(scene.project, SceneSolveOptions(), &current).IsUsable());

  constexpr int kNumCalls = 200;
  std::vector<double> call_ms;
  const size_t dragged = 6;  // the far top corner
  int usable = 0;
  double worst_rms_px = 0.0;
  for (int i = 0; i < kNumCalls; ++i) {
    // Out 50 px and back, so that the scene stays plausible.
    const double step_px = (i / 50) % 2 == 0 ? 1.0 : -1.0;
    current.pins[dragged].uv_px += Eigen::Vector2d(step_px, 0.5 * step_px);
    Project next;
    const auto start = std::chrono::steady_clock::now();
    const SceneSolveSummary summary = SolveScene(current, options, &next);
    call_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    if (summary.IsUsable()) ++usable;
    worst_rms_px = std::max(worst_rms_px, summary.reprojection_rms_px);
    current = std::move(next);
  }
  CHECK(usable == kNumCalls);
  std::sort(call_ms.begin(), call_ms.end());
  MESSAGE("warm-started solve (1 box, 8 pins, 5 parameters, max 5 iterations): median ",
          call_ms[kNumCalls / 2] * 1000.0, " us per call, 90th percentile ", call_ms[kNumCalls * 9 / 10] * 1000.0,
          " us; worst RMS during the drag ", worst_rms_px, " px");
}

TEST_CASE("pins on vertices made by E_split and by an extrusion take part; the box is recovered") {
  constexpr double kRelativeTolerance = 1e-9;
  constexpr double kExtrusion = 0.5;
  SyntheticScene scene = MakeBoxScene();
  // The same K-ops on the project's box and on the true box give the same ids.
  Primitive& box = scene.project.primitives[0];
  Primitive& truth = scene.true_box;
  VertexId split_vertex = kNoElement;
  std::vector<VertexId> extruded;
  for (Primitive* p : {&box, &truth}) {
    const HalfedgeId top_front = FindHalfedge(p->mesh, 4, 5);  // (0, 0, sz) -> (sx, 0, sz)
    REQUIRE(top_front != kNoElement);
    const ESplitResult split = ESplit(&p->mesh, PolyMesh::EdgeOf(top_front), 0.5);
    REQUIRE_MESSAGE(split.ok, split.message);
    const ExtrudeResult x = ExtrudeFace(&p->mesh, p->shape, 1, kExtrusion);  // the +X face
    REQUIRE_MESSAGE(x.ok, x.message);
    split_vertex = split.vertex;
    extruded = x.new_vertices;
  }
  REQUIRE(box.mesh == truth.mesh);
  // Only the -X corners stay pinned: the width comes from the new vertices alone.
  std::erase_if(scene.project.pins, [](const Pin& pin) { return (pin.vertex.vertex & 1) != 0; });
  std::vector<VertexId> added = extruded;
  added.push_back(split_vertex);
  for (VertexId v : added) {
    Pin pin;
    pin.id = scene.project.NewId();
    pin.image_id = scene.image_id;
    pin.vertex = {scene.box_id, v};
    pin.uv_px = scene.true_camera.Project(truth.mesh.vertex(v).position);
    scene.project.pins.push_back(pin);
  }
  PerturbSizeAndCamera(&scene, 1.0);
  REQUIRE(RelativeError(Size(scene.project.primitives[0]), Size(truth)) > 0.1);
  for (const bool warm_start : {false, true}) {
    CAPTURE(warm_start);
    SceneSolveOptions options;
    options.warm_start = warm_start;
    Project solved;
    const SceneSolveSummary summary = SolveScene(scene.project, options, &solved);
    INFO(summary.message, " ", AllWarnings(summary));
    REQUIRE(summary.IsUsable());
    CHECK(summary.num_residuals == 2 * 9);
    const double size_error = RelativeError(Size(solved.primitives[0]), Size(truth));
    const double center_error = RelativeError(CameraCenter(solved), scene.true_camera.CenterInWorld());
    CAPTURE(size_error);
    CAPTURE(center_error);
    CHECK(size_error < kRelativeTolerance);
    CHECK(center_error < kRelativeTolerance);
    CHECK(summary.reprojection_rms_px < 1e-6);
    // The extruded vertices sit kExtrusion beyond the solved +X face.
    const PolyMesh& mesh = solved.primitives[0].mesh;
    for (size_t i = 0; i < extruded.size(); ++i) {
      const double x = mesh.vertex(extruded[i]).position.x();
      CHECK(std::abs(x - (solved.primitives[0].shape.params.x() + kExtrusion)) < kRelativeTolerance * 10.0);
    }
  }
}

}  // namespace
}  // namespace facet
