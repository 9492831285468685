// What runs after every edit (core/model_update.h): on synthetic scenes, calibration from the
// line families, the geometry solve and the joint solve together recover the true camera and
// box from a perturbed start; a failed solve leaves the project as the edit made it.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <string>

#include <Eigen/Geometry>

#include "core/camera.h"
#include "core/model_update.h"
#include "core/project.h"
#include "tests/synthetic_scene.h"

namespace facet {
namespace {

using testing::MakeBoxScene;
using testing::SyntheticScene;
using testing::SyntheticSceneOptions;

Eigen::Vector3d Size(const Primitive& primitive) { return primitive.shape.params.head<3>(); }

double RotationErrorRad(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a * b.transpose()).angle();
}

std::string Messages(const ModelUpdateSummary& summary) {
  std::string out = "solve: " + summary.solve.message + "; joint: " + summary.joint.message;
  for (const auto& m : summary.messages) out += "; " + m;
  return out;
}

// The edit a user might leave behind: the camera's intrinsics, rotation and centre and the
// box's free dimensions all away from the truth, by amounts relative to the scene's scale.
void Perturb(SyntheticScene* scene, double scale) {
  Image& image = scene->project.images[0];
  Camera& camera = image.camera;
  camera.focal_px *= 1.2;
  camera.principal_point_px += Eigen::Vector2d(25.0, -15.0);
  const Eigen::Matrix3d tilt = RotationFromAngleAxis(Eigen::Vector3d(0.05, -0.03, 0.08));
  camera.SetPose(tilt * camera.cam_from_world_rotation, camera.CenterInWorld() + scale * Eigen::Vector3d(1.2, -0.8, 0.6));
  Primitive& box = scene->project.primitives[0];
  box.shape.params.x() *= 1.3;
  box.shape.params.y() *= 0.75;
  RefreshPrimitive(&scene->project, &box);
}

TEST_CASE("noise-free: calibration, geometry solve and joint solve recover camera and box from a perturbed start") {
  // Noise-free data: every step is exact up to rounding and solver tolerances (1e-14).
  constexpr double kRelativeTolerance = 1e-9;
  constexpr double kAngleToleranceRad = 1e-9;
  constexpr double kPrincipalPointTolerancePx = 1e-6;
  for (const double scale : {1.0, 1e-3, 1e3}) {
    CAPTURE(scale);
    SyntheticSceneOptions options;
    options.scale = scale;
    SyntheticScene scene = MakeBoxScene(options);
    Perturb(&scene, scale);
    const Camera& start = scene.project.images[0].camera;
    const Camera& truth = scene.true_camera;
    REQUIRE(std::abs(start.focal_px / truth.focal_px - 1.0) > 0.1);
    REQUIRE(RotationErrorRad(start.cam_from_world_rotation, truth.cam_from_world_rotation) > 0.05);
    REQUIRE((Size(scene.project.primitives[0]) - Size(scene.true_box)).norm() > 0.1 * Size(scene.true_box).norm());

    Project updated;
    const ModelUpdateSummary summary = UpdateModel(scene.project, ModelUpdateOptions(), &updated);
    INFO(Messages(summary));
    REQUIRE(summary.ok);
    REQUIRE(summary.calibration.count(scene.image_id) == 1);
    CHECK(summary.calibration.at(scene.image_id).IsUsable());
    REQUIRE(summary.solve.IsUsable());
    REQUIRE(summary.joint.IsUsable());

    const Camera& camera = updated.images[0].camera;
    const double focal_error = std::abs(camera.focal_px / truth.focal_px - 1.0);
    const double pp_error_px = (camera.principal_point_px - truth.principal_point_px).norm();
    const double rotation_error = RotationErrorRad(camera.cam_from_world_rotation, truth.cam_from_world_rotation);
    const double center_error =
        (camera.CenterInWorld() - truth.CenterInWorld()).norm() / truth.CenterInWorld().norm();
    const Primitive& box = updated.primitives[0];
    const double size_error = (Size(box) - Size(scene.true_box)).norm() / Size(scene.true_box).norm();
    double vertex_error = 0.0;  // the cached positions follow the solved shape
    for (VertexId v = 0; v < 8; ++v)
      vertex_error = std::max(vertex_error, (box.mesh.vertex(v).position - scene.true_box.mesh.vertex(v).position).norm());
    vertex_error /= Size(scene.true_box).norm();
    MESSAGE("scale " << scale << ": focal " << focal_error << ", principal point " << pp_error_px << " px, rotation "
                     << rotation_error << " rad, centre " << center_error << ", size " << size_error
                     << " (relative); joint solve " << summary.joint.iterations << " iterations, RMS "
                     << summary.joint.reprojection_rms_px << " px, " << summary.time_ms << " ms in all");
    CHECK(focal_error < kRelativeTolerance);
    CHECK(pp_error_px < kPrincipalPointTolerancePx);
    CHECK(rotation_error < kAngleToleranceRad);
    CHECK(center_error < kRelativeTolerance);
    CHECK(size_error < kRelativeTolerance);
    CHECK(vertex_error < kRelativeTolerance);
    CHECK(box.shape.params.z() == scene.project.primitives[0].shape.params.z());  // the known length
    CHECK(summary.joint.reprojection_rms_px < 1e-6);
    // Nothing else changed: the pins, segments and topology are the edit's.
    CHECK(updated.pins == scene.project.pins);
    CHECK(updated.segments == scene.project.segments);
    CHECK(updated.primitives[0].mesh.NumVertices() == 8);
  }
}

TEST_CASE("0.5 px noise: the full update stays within bounds scaled to the noise") {
  // 8 pins and 24 segments at 0.5 px: the box within 1 % and the focal length within 2 %
  // (a few standard deviations of what such a scene determines; see test_scene_solve's
  // covariance test for the geometry solve alone).
  constexpr double kMaxSizeError = 0.01;
  constexpr double kMaxFocalError = 0.02;
  for (unsigned seed = 1; seed <= 5; ++seed) {
    CAPTURE(seed);
    SyntheticSceneOptions options;
    options.noise_px = 0.5;
    options.seed = seed;
    SyntheticScene scene = MakeBoxScene(options);
    Perturb(&scene, 1.0);
    Project updated;
    const ModelUpdateSummary summary = UpdateModel(scene.project, ModelUpdateOptions(), &updated);
    INFO(Messages(summary));
    REQUIRE(summary.ok);
    REQUIRE(summary.joint.IsUsable());
    const double size_error =
        (Size(updated.primitives[0]) - Size(scene.true_box)).norm() / Size(scene.true_box).norm();
    const double focal_error = std::abs(updated.images[0].camera.focal_px / scene.true_camera.focal_px - 1.0);
    CAPTURE(size_error);
    CAPTURE(focal_error);
    CHECK(size_error < kMaxSizeError);
    CHECK(focal_error < kMaxFocalError);
    // The joint solve refines the geometry solve's result: its pin RMS is at the noise level.
    CHECK(summary.joint.reprojection_rms_px < 3.0 * options.noise_px);
  }
}

TEST_CASE("a failed solve leaves the project as the edit made it") {
  SyntheticScene scene = MakeBoxScene();
  Perturb(&scene, 1.0);
  scene.project.pins[3].uv_px.x() = std::numeric_limits<double>::quiet_NaN();
  const Project& edited = scene.project;
  // NaN != NaN: compare with the NaN replaced on both sides.
  auto same_as_edited = [&](Project p) {
    Project e = edited;
    if (!std::isnan(p.pins[3].uv_px.x())) return false;
    p.pins[3].uv_px.x() = e.pins[3].uv_px.x() = 0.0;
    return p == e;
  };
  for (const bool calibrate : {false, true}) {
    for (const bool warm_start : {false, true}) {
      CAPTURE(calibrate);
      CAPTURE(warm_start);
      ModelUpdateOptions options;
      options.calibrate = calibrate;
      options.solve.warm_start = warm_start;
      Project updated;
      const ModelUpdateSummary summary = UpdateModel(edited, options, &updated);
      INFO(Messages(summary));
      CHECK_FALSE(summary.ok);
      CHECK_FALSE(summary.solve.IsUsable());
      REQUIRE_FALSE(summary.messages.empty());
      CHECK(summary.messages.back().find("pin #") != std::string::npos);
      // The joint solve did not run on a failed geometry solve.
      CHECK(summary.joint.termination == JointSolveSummary::Termination::kInvalidInput);
      CHECK(same_as_edited(updated));
    }
  }
}

TEST_CASE("nothing to solve is not a failure: the calibrated cameras are kept") {
  SyntheticScene scene = MakeBoxScene();
  Perturb(&scene, 1.0);
  scene.project.pins.clear();
  Project updated;
  const ModelUpdateSummary summary = UpdateModel(scene.project, ModelUpdateOptions(), &updated);
  INFO(Messages(summary));
  CHECK(summary.ok);
  CHECK(summary.solve.termination == SolveTermination::kNothingToSolve);
  const double focal_error = std::abs(updated.images[0].camera.focal_px / scene.true_camera.focal_px - 1.0);
  CAPTURE(focal_error);
  CHECK(focal_error < 1e-9);
  CHECK(updated.primitives == scene.project.primitives);
}

}  // namespace
}  // namespace facet
