// The joint-solve benchmark's scene generator (tests/bench/joint_scene.h): the true scene
// reprojects exactly onto noise-free pins, every pin is visible, the noise has the requested
// statistics, the pins determine every primitive and camera, and the start is perturbed
// within its stated bounds and keeps the gauge.
#include <doctest/doctest.h>

#include <cmath>
#include <map>
#include <set>

#include "tests/bench/joint_scene.h"

namespace {

using facet::Id;
using facet::Project;
using facet::testing::JointScene;
using facet::testing::JointSceneOptions;
using facet::testing::MakeJointScene;

JointSceneOptions Sizes(int primitives, int images, int pins, double noise_px) {
  JointSceneOptions o;
  o.num_primitives = primitives;
  o.num_images = images;
  o.num_pins = pins;
  o.noise_px = noise_px;
  return o;
}

// World position of a pinned vertex from the primitive's shape, not from the cached mesh.
Eigen::Vector3d VertexFromShape(const Project& project, const facet::VertexRef& ref) {
  const facet::Primitive* primitive = project.FindPrimitive(ref.primitive_id);
  REQUIRE(primitive != nullptr);
  REQUIRE(primitive->mesh.IsVertex(ref.vertex));
  return facet::PrimitiveLocalToWorld(primitive->shape,
                                      primitive->mesh.vertex(ref.vertex).LocalPosition(primitive->shape.params));
}

double ReprojectionRmsPx(const Project& project) {
  double sum = 0.0;
  for (const facet::Pin& pin : project.pins) {
    const Eigen::Vector2d uv_px = project.FindImage(pin.image_id)->camera.Project(VertexFromShape(project, pin.vertex));
    sum += (uv_px - pin.uv_px).squaredNorm();
  }
  return std::sqrt(sum / project.pins.size());
}

}  // namespace

TEST_CASE("noise-free pins are the exact projections of the true scene and are visible") {
  // Reprojection of the same double arithmetic through a different path (shape, not cache).
  constexpr double kExactPx = 1e-9 * 1920.0;
  for (const auto& o : {Sizes(1, 2, 10, 0.0), Sizes(10, 3, 60, 0.0), Sizes(100, 10, 1000, 0.0)}) {
    const JointScene scene = MakeJointScene(o);
    CAPTURE(o.num_primitives);
    REQUIRE(scene.truth.pins.size() == scene.true_uv_px.size());
    double worst_px = 0.0;
    for (size_t k = 0; k < scene.truth.pins.size(); ++k) {
      const facet::Pin& pin = scene.truth.pins[k];
      const facet::Camera& camera = scene.truth.FindImage(pin.image_id)->camera;
      const Eigen::Vector3d p_in_world = VertexFromShape(scene.truth, pin.vertex);
      const Eigen::Vector2d uv_px = camera.Project(p_in_world);
      worst_px = std::max({worst_px, (uv_px - pin.uv_px).norm(), (uv_px - scene.true_uv_px[k]).norm()});
      CHECK(camera.CamFromWorld(p_in_world).z() > 0.0);
      CHECK(uv_px.x() >= 0.0);
      CHECK(uv_px.y() >= 0.0);
      CHECK(uv_px.x() <= camera.width_px - 1.0);
      CHECK(uv_px.y() <= camera.height_px - 1.0);
    }
    INFO("worst reprojection of the truth: " << worst_px << " px");
    CHECK(worst_px <= kExactPx);
  }
}

TEST_CASE("pins are spread so that every primitive and every camera is determined") {
  for (const auto& o :
       {Sizes(1, 2, 10, 0.5), Sizes(10, 3, 60, 0.5), Sizes(100, 10, 1000, 0.5), Sizes(300, 10, 3000, 0.5)}) {
    const JointScene scene = MakeJointScene(o);
    CAPTURE(o.num_primitives);
    CHECK(static_cast<int>(scene.truth.primitives.size()) == o.num_primitives);
    CHECK(static_cast<int>(scene.truth.images.size()) == o.num_images);
    CHECK(static_cast<int>(scene.truth.pins.size()) == o.num_pins);
    std::map<Id, int> pins_per_primitive;
    std::map<Id, std::set<Id>> images_per_primitive;
    std::map<Id, int> pins_per_image;
    std::set<std::pair<Id, std::pair<Id, facet::VertexId>>> distinct;
    for (const facet::Pin& pin : scene.truth.pins) {
      ++pins_per_primitive[pin.vertex.primitive_id];
      images_per_primitive[pin.vertex.primitive_id].insert(pin.image_id);
      ++pins_per_image[pin.image_id];
      distinct.insert({pin.image_id, {pin.vertex.primitive_id, pin.vertex.vertex}});
    }
    CHECK(distinct.size() == scene.truth.pins.size());  // no vertex pinned twice in one image
    const int per_primitive = o.num_pins / o.num_primitives;
    for (const facet::Primitive& box : scene.truth.primitives) {
      CAPTURE(box.name);
      CHECK(pins_per_primitive[box.id] >= per_primitive);
      CHECK(pins_per_primitive[box.id] <= per_primitive + 1);
      // A box seen in one image only keeps its depth free along the rays.
      CHECK(images_per_primitive[box.id].size() >= 2);
    }
    for (const facet::Image& image : scene.truth.images) {
      CAPTURE(image.path);
      CHECK(pins_per_image[image.id] >= 3);  // six pose parameters
    }
  }
}

TEST_CASE("pin noise has zero mean and the requested standard deviation") {
  const JointSceneOptions o = Sizes(300, 10, 3000, 0.5);
  const JointScene scene = MakeJointScene(o);
  const int n = 2 * static_cast<int>(scene.truth.pins.size());
  double sum = 0.0;
  double sum_sq = 0.0;
  for (size_t k = 0; k < scene.truth.pins.size(); ++k) {
    const Eigen::Vector2d e = scene.truth.pins[k].uv_px - scene.true_uv_px[k];
    sum += e.x() + e.y();
    sum_sq += e.squaredNorm();
  }
  const double mean_px = sum / n;
  const double std_px = std::sqrt(sum_sq / n - mean_px * mean_px);
  // Five standard errors: of the mean sigma / sqrt(n), of the standard deviation sigma / sqrt(2n).
  const double mean_bound_px = 5.0 * o.noise_px / std::sqrt(n);
  const double std_bound_px = 5.0 * o.noise_px / std::sqrt(2.0 * n);
  INFO("noise mean " << mean_px << " px, std " << std_px << " px over " << n << " coordinates");
  CHECK(std::abs(mean_px) <= mean_bound_px);
  CHECK(std::abs(std_px - o.noise_px) <= std_bound_px);
}

TEST_CASE("the start is perturbed within its bounds, keeps the gauge and is not the answer") {
  const JointSceneOptions o = Sizes(100, 10, 1000, 0.5);
  const JointScene scene = MakeJointScene(o);
  constexpr double kRoundingRel = 1e-12;
  CHECK(scene.start.pins == scene.truth.pins);
  for (size_t i = 0; i < scene.truth.primitives.size(); ++i) {
    const facet::Primitive& truth = scene.truth.primitives[i];
    const facet::Primitive& start = scene.start.primitives[i];
    CAPTURE(truth.name);
    CHECK(start.shape.rotation == truth.shape.rotation);
    for (int k = 0; k < 3; ++k) {
      const double rel = std::abs(start.shape.params[k] / truth.shape.params[k] - 1.0);
      CAPTURE(k);
      CHECK(rel <= o.start_fraction + kRoundingRel);
      if (truth.param_locked[k]) CHECK(start.shape.params[k] == truth.shape.params[k]);
    }
    const double diagonal_m = truth.shape.params.head<3>().norm();
    const Eigen::Vector3d moved_m = start.shape.translation - truth.shape.translation;
    CHECK(moved_m.cwiseAbs().maxCoeff() <= o.start_fraction * diagonal_m * (1.0 + kRoundingRel));
    if (truth.translation_locked) CHECK(moved_m.norm() == 0.0);
    // The cached vertex positions follow the perturbed shape.
    const Eigen::Vector3d cached = start.mesh.vertex(7).position;
    const Eigen::Vector3d from_shape =
        facet::PrimitiveLocalToWorld(start.shape, start.mesh.vertex(7).LocalPosition(start.shape.params));
    CHECK((cached - from_shape).norm() <= kRoundingRel * (1.0 + from_shape.norm()));
  }
  // Exactly one gauge: primitive 0's translation and height.
  int locked_translations = 0;
  int locked_params = 0;
  for (const facet::Primitive& box : scene.truth.primitives) {
    locked_translations += box.translation_locked ? 1 : 0;
    for (int k = 0; k < 3; ++k) locked_params += box.param_locked[k] ? 1 : 0;
    CHECK(box.rotation_locked);
  }
  CHECK(locked_translations == 1);
  CHECK(locked_params == 1);
  for (size_t j = 0; j < scene.truth.images.size(); ++j) {
    const facet::Camera& truth = scene.truth.images[j].camera;
    const facet::Camera& start = scene.start.images[j].camera;
    const double distance_m = (truth.CenterInWorld() - scene.look_at).norm();
    CHECK((start.CenterInWorld() - truth.CenterInWorld()).norm() <=
          o.start_fraction * distance_m * (1.0 + kRoundingRel));
    const double turn_deg =
        Eigen::AngleAxisd(start.cam_from_world_rotation * truth.cam_from_world_rotation.transpose()).angle() * 180.0 /
        M_PI;
    CHECK(turn_deg == doctest::Approx(o.start_rotation_deg).epsilon(1e-6));
    CHECK(start.focal_px == truth.focal_px);
    CHECK(start.principal_point_px == truth.principal_point_px);
  }
  const double truth_rms_px = ReprojectionRmsPx(scene.truth);
  const double start_rms_px = ReprojectionRmsPx(scene.start);
  INFO("reprojection RMS: truth " << truth_rms_px << " px, start " << start_rms_px << " px");
  // The truth sits at the noise level (sqrt(2) sigma per pin); the start far above it.
  CHECK(truth_rms_px <= 1.2 * std::sqrt(2.0) * o.noise_px);
  CHECK(start_rms_px >= 10.0 * truth_rms_px);
}

TEST_CASE("the scene is a function of the seed") {
  JointSceneOptions o = Sizes(10, 3, 60, 0.5);
  const JointScene a = MakeJointScene(o);
  const JointScene b = MakeJointScene(o);
  CHECK(a.truth == b.truth);
  CHECK(a.start == b.start);
  o.seed = 2;
  const JointScene c = MakeJointScene(o);
  CHECK_FALSE(a.truth == c.truth);
}
