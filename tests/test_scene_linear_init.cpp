// The geometry solve's linear initialisation (core/solve/scene_solve_internal.h): its Schur path
// (used above 300 unknowns) must give the dense SVD's solution, and both must recover a
// noise-free scene exactly from a cold start (every camera at the origin, every free box a unit
// cube at the origin), whatever the start. Scenes from tests/bench/joint_scene.h.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "core/solve/scene_solve.h"
#include "core/solve/scene_solve_internal.h"
#include "tests/bench/joint_scene.h"

namespace {

using facet::scene_solve_internal::LinearInitMethod;

// Noise-free recovery: the linear system is exact, so only rounding remains.
constexpr double kExactRelative = 1e-9;
// The two paths solve the same least-squares problem by different factorisations.
constexpr double kPathsAgreeRelative = 1e-9;

facet::Project ColdStart(const facet::Project& truth) {
  facet::Project cold = truth;
  for (facet::Image& image : cold.images)
    image.camera.SetPose(image.camera.cam_from_world_rotation, Eigen::Vector3d::Zero());
  for (facet::Primitive& p : cold.primitives) {
    for (int k = 0; k < facet::kMaxPrimitiveParams; ++k)
      if (!p.param_locked[k] && p.shape.params[k] > 0.0) p.shape.params[k] = 1.0;
    if (!p.translation_locked) p.shape.translation.setZero();
  }
  facet::RefreshAllPrimitives(&cold);
  return cold;
}

double MaxRelativeDifference(const facet::Project& a, const facet::Project& b) {
  double worst = 0.0;
  for (size_t i = 0; i < a.primitives.size(); ++i) {
    const auto& pa = a.primitives[i].shape;
    const auto& pb = b.primitives[i].shape;
    for (int k = 0; k < 3; ++k) worst = std::max(worst, std::abs(pa.params[k] - pb.params[k]) / std::abs(pb.params[k]));
    worst = std::max(worst, (pa.translation - pb.translation).norm() / (1.0 + pb.translation.norm()));
  }
  for (size_t i = 0; i < a.images.size(); ++i) {
    const Eigen::Vector3d ca = a.images[i].camera.CenterInWorld(), cb = b.images[i].camera.CenterInWorld();
    worst = std::max(worst, (ca - cb).norm() / cb.norm());
  }
  return worst;
}

facet::Project Initialise(const facet::Project& cold, LinearInitMethod method, std::string* why) {
  facet::scene_solve_internal::SceneState state;
  const auto problem = facet::scene_solve_internal::BuildSceneProblem(cold, &state);
  facet::Project out = cold;
  if (!facet::scene_solve_internal::LinearInitialization(problem, &state, why, method)) return out;
  facet::scene_solve_internal::WriteSceneState(problem, state, &out);
  return out;
}

}  // namespace

TEST_CASE("linear initialisation: the Schur path equals the dense SVD and recovers a noise-free scene") {
  for (const auto& [primitives, images] : {std::pair{12, 3}, std::pair{40, 6}}) {
    facet::testing::JointSceneOptions size = facet::testing::JointSceneSize(primitives, images, 12 * primitives);
    size.noise_px = 0.0;
    const facet::testing::JointScene scene = facet::testing::MakeJointScene(size);
    const facet::Project cold = ColdStart(scene.truth);
    const int num_primitives = primitives;  // clang 14 cannot capture a structured binding (CAPTURE)
    CAPTURE(num_primitives);
    REQUIRE(MaxRelativeDifference(cold, scene.truth) > 0.1);  // the start is far from the answer

    std::string dense_why, schur_why;
    const facet::Project dense = Initialise(cold, LinearInitMethod::kDense, &dense_why);
    const facet::Project schur = Initialise(cold, LinearInitMethod::kSchur, &schur_why);
    INFO("dense: " << dense_why << "; schur: " << schur_why);
    REQUIRE(dense_why.empty());
    REQUIRE(schur_why.empty());
    const double dense_error = MaxRelativeDifference(dense, scene.truth);
    const double schur_error = MaxRelativeDifference(schur, scene.truth);
    const double paths = MaxRelativeDifference(schur, dense);
    MESSAGE(primitives << " boxes, " << images << " images: dense " << dense_error << ", Schur " << schur_error
                       << " from the truth; paths differ by " << paths);
    CHECK(dense_error < kExactRelative);
    CHECK(schur_error < kExactRelative);
    CHECK(paths < kPathsAgreeRelative);
  }
}

TEST_CASE("linear initialisation: the Schur path names a box no two views fix, and leaves the state alone") {
  facet::testing::JointSceneOptions size = facet::testing::JointSceneSize(12, 3, 144);
  size.noise_px = 0.0;
  facet::testing::JointScene scene = facet::testing::MakeJointScene(size);
  // Box 5 is pinned at all 8 corners, but in one image only: one view cannot tell its size
  // from its distance.
  const facet::Primitive& box = scene.truth.primitives[5];
  std::erase_if(scene.truth.pins, [&](const facet::Pin& pin) { return pin.vertex.primitive_id == box.id; });
  const facet::Image& only = scene.truth.images[0];
  for (facet::VertexId v = 0; v < 8; ++v) {
    facet::Pin pin;
    pin.id = scene.truth.NewId();
    pin.image_id = only.id;
    pin.vertex = {box.id, v};
    pin.uv_px = only.camera.Project(box.mesh.vertex(v).position);
    REQUIRE(only.camera.CamFromWorld(box.mesh.vertex(v).position).z() > 0.0);
    scene.truth.pins.push_back(pin);
  }
  const facet::Project cold = ColdStart(scene.truth);
  facet::scene_solve_internal::SceneState state;
  const auto problem = facet::scene_solve_internal::BuildSceneProblem(cold, &state);
  const facet::scene_solve_internal::SceneState before = state;
  std::string why;
  CHECK_FALSE(facet::scene_solve_internal::LinearInitialization(problem, &state, &why, LinearInitMethod::kSchur));
  MESSAGE(why);
  CHECK(why.find("rank deficient (the pins do not fix primitive 6") != std::string::npos);
  CHECK(state.primitive_params == before.primitive_params);
  CHECK(state.camera_centers == before.camera_centers);
}
