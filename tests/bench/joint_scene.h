// Synthetic scenes for the joint-solve benchmark (issue 5, "Speed"): N boxes on a grid seen
// by M calibrated cameras on a ring, P vertex pins with Gaussian pixel noise, and a perturbed
// copy of the scene for warm and cold starts. Shared by tests/bench/bench_joint_solve.cpp, the
// Ceres comparison (tests/bench/ceres_joint_solve.cpp) and tests/test_joint_scene_generator.cpp.
//
// Scene: boxes of varied sizes (1-3 m footprint, 1-4 m high) on a grid of pitch `pitch_m`,
// centred on the world origin, rotation locked (aligned with the world axes), dimensions and
// translation free. Gauge: primitive 0 keeps its translation (origin) and height (scale).
// Cameras: 1920x1080, focal 1000 px, principal point at the image centre, focal and principal
// point locked, pose free; on a ring around the grid, raised, looking at its centre.
// Pins: P / N per primitive (the remainder to the first ones), spread round-robin over the
// images in which the primitive has visible vertices (in front of the camera, inside the
// image), at distinct vertices per image, so a primitive is pinned in two images or more
// whenever two cameras see it. Box corner i (core/mesh/box.h bit code) is vertex i.
#pragma once

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "core/geometry/camera.h"
#include "core/mesh/primitives.h"
#include "core/scene/project.h"

namespace facet::testing {

struct JointSceneOptions {
  int num_primitives = 10;
  int num_images = 3;
  int num_pins = 60;
  int width_px = 1920;
  int height_px = 1080;
  double focal_px = 1000.0;
  double pitch_m = 4.0;   // grid spacing between box origins
  double noise_px = 0.5;  // standard deviation of each pin coordinate's noise
  // The start point: each free box dimension and each camera centre's distance to the scene
  // centre off by up to this fraction; each free translation off by up to this fraction of
  // its box's diagonal per axis; each camera rotation by up to `start_rotation_deg`.
  double start_fraction = 0.03;
  double start_rotation_deg = 0.3;
  unsigned seed = 1;
};

struct JointScene {
  Project truth;                            // true cameras and primitives; pins with noise
  Project start;                            // the same images, primitives and pins with perturbed cameras and shapes
  std::vector<Eigen::Vector2d> true_uv_px;  // noise-free projection of each pin (pins order)
  Eigen::Vector3d look_at = Eigen::Vector3d::Zero();
  double ring_radius_m = 0.0;
};

namespace joint_scene_detail {

inline Camera LookAtCamera(const JointSceneOptions& o, const Eigen::Vector3d& center, const Eigen::Vector3d& look_at) {
  Camera camera;
  camera.width_px = o.width_px;
  camera.height_px = o.height_px;
  camera.focal_px = o.focal_px;
  camera.principal_point_px = Eigen::Vector2d((o.width_px - 1) / 2.0, (o.height_px - 1) / 2.0);
  const Eigen::Vector3d forward = (look_at - center).normalized();
  const Eigen::Matrix3d cam_from_world = CamFromWorldLookingAlong(forward);
  camera.SetPose(cam_from_world, center);
  return camera;
}

inline bool Visible(const Camera& camera, const Eigen::Vector3d& p_in_world) {
  constexpr double kMinDepthM = 0.1;
  if (camera.CamFromWorld(p_in_world).z() < kMinDepthM) return false;
  const Eigen::Vector2d uv_px = camera.Project(p_in_world);
  return uv_px.x() >= 0.0 && uv_px.y() >= 0.0 && uv_px.x() <= camera.width_px - 1.0 &&
         uv_px.y() <= camera.height_px - 1.0;
}

}  // namespace joint_scene_detail

inline JointScene MakeJointScene(const JointSceneOptions& o) {
  using joint_scene_detail::LookAtCamera;
  using joint_scene_detail::Visible;
  JointScene scene;
  std::mt19937 rng(o.seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  std::normal_distribution<double> gaussian(0.0, 1.0);
  auto in_range = [&](double lo, double hi) { return lo + (hi - lo) * 0.5 * (uniform(rng) + 1.0); };

  Project& p = scene.truth;
  const int cols = std::max(1, static_cast<int>(std::ceil(std::sqrt(static_cast<double>(o.num_primitives)))));
  const int rows = std::max(1, (o.num_primitives + cols - 1) / cols);
  const Eigen::Vector3d grid_origin(-0.5 * o.pitch_m * (cols - 1), -0.5 * o.pitch_m * (rows - 1), 0.0);
  for (int i = 0; i < o.num_primitives; ++i) {
    const Eigen::Vector3d size(in_range(1.0, 3.0), in_range(1.0, 3.0), in_range(1.0, 4.0));
    PrimitiveShape shape = MakeBox(kNoId, size);
    shape.translation = grid_origin + Eigen::Vector3d(o.pitch_m * (i % cols), o.pitch_m * (i / cols), 0.0);
    Id id = kNoId;
    AddPrimitiveToProject(&p, shape, "box" + std::to_string(i), &id, nullptr);
    Primitive& box = p.primitives.back();
    box.rotation_locked = true;
    box.translation_locked = (i == 0);
    box.param_locked = {false, false, i == 0, false};
  }

  // The ring sees the whole grid: its half-diagonal plus a box, at 2.2x that distance, raised
  // by 0.6x (about 30 degrees down), so the grid fits the 1000 px focal's field of view.
  const double half_diagonal_m = 0.5 * o.pitch_m * std::hypot(cols - 1.0, rows - 1.0) + 3.0;
  scene.look_at = Eigen::Vector3d(0.0, 0.0, 1.0);
  scene.ring_radius_m = std::max(12.0, 2.2 * half_diagonal_m);
  for (int j = 0; j < o.num_images; ++j) {
    const double angle = 2.0 * M_PI * j / std::max(1, o.num_images) + 0.3;
    const Eigen::Vector3d center(scene.ring_radius_m * std::cos(angle), scene.ring_radius_m * std::sin(angle),
                                 0.6 * scene.ring_radius_m);
    Image image;
    image.id = p.NewId();
    image.path = "ring" + std::to_string(j) + ".png";
    image.width_px = o.width_px;
    image.height_px = o.height_px;
    image.camera = LookAtCamera(o, center, scene.look_at);
    image.camera_calibrated = true;
    image.pose_locked = false;
    image.focal_locked = true;
    image.principal_point_locked = true;
    p.images.push_back(image);
  }

  for (int i = 0; i < o.num_primitives; ++i) {
    const Primitive& box = p.primitives[i];
    const int wanted = o.num_pins / o.num_primitives + (i < o.num_pins % o.num_primitives ? 1 : 0);
    // Per image, the box's visible vertices in random order; then one pin per image in turn.
    std::vector<std::vector<VertexId>> visible(p.images.size());
    for (size_t j = 0; j < p.images.size(); ++j) {
      for (VertexId v = 0; v < box.mesh.VertexIdEnd(); ++v) {
        if (box.mesh.IsVertex(v) && Visible(p.images[j].camera, box.mesh.vertex(v).position)) visible[j].push_back(v);
      }
      std::shuffle(visible[j].begin(), visible[j].end(), rng);
    }
    std::vector<size_t> order(p.images.size());
    for (size_t j = 0; j < order.size(); ++j) order[j] = j;
    std::shuffle(order.begin(), order.end(), rng);
    std::vector<size_t> used(p.images.size(), 0);
    int placed = 0;
    for (bool progress = true; placed < wanted && progress;) {
      progress = false;
      for (size_t j : order) {
        if (placed == wanted) break;
        if (used[j] == visible[j].size()) continue;
        const VertexId v = visible[j][used[j]++];
        Pin pin;
        pin.id = p.NewId();
        pin.image_id = p.images[j].id;
        pin.vertex = {box.id, v};
        const Eigen::Vector2d uv_px = p.images[j].camera.Project(box.mesh.vertex(v).position);
        scene.true_uv_px.push_back(uv_px);
        pin.uv_px = uv_px + o.noise_px * Eigen::Vector2d{gaussian(rng), gaussian(rng)};
        p.pins.push_back(pin);
        ++placed;
        progress = true;
      }
    }
  }

  Project& s = scene.start;
  s = p;
  for (Primitive& box : s.primitives) {
    const double diagonal_m = box.shape.params.head<3>().norm();
    for (int k = 0; k < 3; ++k) {
      if (!box.param_locked[k]) box.shape.params[k] *= 1.0 + o.start_fraction * uniform(rng);
    }
    if (!box.translation_locked) {
      box.shape.translation +=
          o.start_fraction * diagonal_m * Eigen::Vector3d{uniform(rng), uniform(rng), uniform(rng)};
    }
  }
  RefreshAllPrimitives(&s);
  for (Image& image : s.images) {
    const Eigen::Vector3d center = image.camera.CenterInWorld();
    const double distance_m = (center - scene.look_at).norm();
    const Eigen::Vector3d moved = center + o.start_fraction * distance_m *
                                               Eigen::Vector3d{uniform(rng), uniform(rng), uniform(rng)} /
                                               std::sqrt(3.0);
    const Eigen::Vector3d axis = Eigen::Vector3d{uniform(rng), uniform(rng), uniform(rng)}.normalized();
    const Eigen::Matrix3d turn = Eigen::AngleAxisd(o.start_rotation_deg * M_PI / 180.0, axis).toRotationMatrix();
    image.camera.SetPose(turn * image.camera.cam_from_world_rotation, moved);
  }
  return scene;
}

// The benchmark's settings, shared by our solve and the Ceres comparison so both run the
// same problem with the same budget.
constexpr int kFrameIterations = 5;        // the app's per-frame budget while a pin is dragged
constexpr int kFullIterations = 100;       // a full solve (cold start, or when a drag ends)
constexpr double kSolveTolerance = 1e-14;  // function, gradient and parameter tolerances
constexpr double kInitialLambda = 1e-4;    // LM damping; Ceres's trust region is its inverse
constexpr double kDragStepPx = 2.0;        // how far the dragged pin moves between frames

inline JointSceneOptions JointSceneSize(int primitives, int images, int pins) {
  JointSceneOptions o;
  o.num_primitives = primitives;
  o.num_images = images;
  o.num_pins = pins;
  return o;
}

// The scaling table's scenes: 10 pins per primitive and about one image per three
// primitives, at least 2 (a box seen once has a free depth) and at most 10.
inline JointSceneOptions ScalingSceneSize(int primitives) {
  const int images = std::clamp(static_cast<int>(std::lround(0.3 * primitives)), 2, 10);
  return JointSceneSize(primitives, images, 10 * primitives);
}

}  // namespace facet::testing
