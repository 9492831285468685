// The one synthetic-scene generator for core tests: a known box seen by a known camera,
// with the box edges (and extra lines on its faces) projected as the user's line segments
// and its corners projected as pins, optionally with Gaussian pixel noise.
#pragma once

#include <array>
#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "core/geometry/camera.h"
#include "core/mesh/box.h"
#include "core/scene/project.h"

namespace facet::testing {

struct SyntheticSceneOptions {
  int width_px = 1024;
  int height_px = 768;
  double focal_px = 900.0;
  Eigen::Vector2d principal_point_offset_px = {12.0, -9.0};  // from the image centre
  Eigen::Vector3d box_size = {4.0, 3.0, 2.5};
  Eigen::Vector3d box_translation = {0.0, 0.0, 0.0};
  Eigen::Vector3d camera_center = {9.0, -7.0, 5.0};
  Eigen::Vector3d look_at = {2.0, 1.5, 1.0};
  double roll_deg = 3.0;
  double scale = 1.0;            // multiplies every length in the scene
  int extra_lines_per_axis = 4;  // lines on the box faces, beside the 4 edges per axis
  double noise_px = 0.0;         // standard deviation of pixel noise on segments and pins
  unsigned seed = 1;
};

struct SyntheticScene {
  Project project;  // one calibrated image, its segments, the box primitive and 8 pins
  Camera true_camera;
  Primitive true_box;  // the box as built, with its mesh (vertex i = corner i)
  Id image_id = kNoId;
  Id box_id = kNoId;
};

inline Camera MakeLookAtCamera(const SyntheticSceneOptions& o) {
  Camera cam;
  cam.width_px = o.width_px;
  cam.height_px = o.height_px;
  cam.focal_px = o.focal_px;
  cam.principal_point_px =
      Eigen::Vector2d((o.width_px - 1) / 2.0, (o.height_px - 1) / 2.0) + o.principal_point_offset_px;
  const Eigen::Vector3d center = o.camera_center * o.scale;
  const Eigen::Vector3d forward = (o.look_at * o.scale - center).normalized();
  const Eigen::Matrix3d cam_from_world = CamFromWorldLookingAlong(forward);
  const Eigen::Matrix3d roll =
      Eigen::AngleAxisd(o.roll_deg * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  cam.SetPose(roll * cam_from_world, center);
  return cam;
}

inline SyntheticScene MakeBoxScene(const SyntheticSceneOptions& o = {}) {
  SyntheticScene s;
  std::mt19937 rng(o.seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  // One draw per statement: the order of two draws in one call's arguments is unspecified
  // (GCC draws y first, clang x), which made the scene depend on the compiler. GCC's order
  // keeps the scenes every figure was measured on.
  auto jitter = [&](const Eigen::Vector2d& uv) -> Eigen::Vector2d {
    if (!(o.noise_px > 0)) return uv;
    const double dy = noise(rng);
    const double dx = noise(rng);
    return uv + o.noise_px * Eigen::Vector2d(dx, dy);
  };

  s.true_camera = MakeLookAtCamera(o);

  Project& p = s.project;
  Image image;
  image.id = p.NewId();
  image.path = "synthetic.png";
  image.width_px = o.width_px;
  image.height_px = o.height_px;
  image.camera = s.true_camera;
  image.camera_calibrated = true;
  p.images.push_back(image);
  s.image_id = image.id;

  PrimitiveShape shape = MakeBox(kNoId, o.box_size * o.scale);
  shape.translation = o.box_translation * o.scale;
  Id box_id = kNoId;
  AddPrimitiveToProject(&p, shape, "box", &box_id, nullptr);
  Primitive& box = p.primitives.back();
  box.param_locked = {false, false, true, false};  // the height is the known length
  s.true_box = box;
  s.box_id = box_id;

  // The 12 edges, then extra lines across the faces, parallel to each axis.
  auto add_segment = [&](Axis axis, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    Segment seg;
    seg.id = p.NewId();
    seg.image_id = image.id;
    seg.axis = axis;
    seg.a_px = jitter(s.true_camera.Project(a));
    seg.b_px = jitter(s.true_camera.Project(b));
    p.segments.push_back(seg);
  };
  std::array<Eigen::Vector3d, 8> corners;
  for (int c = 0; c < 8; ++c) corners[c] = box.mesh.vertex(c).position;
  const auto& edges = BoxEdges();
  for (int e = 0; e < 12; ++e) add_segment(static_cast<Axis>(e / 4), corners[edges[e][0]], corners[edges[e][1]]);
  const Eigen::Vector3d sz = o.box_size * o.scale;
  const Eigen::Vector3d t = shape.translation;
  for (int k = 1; k <= o.extra_lines_per_axis; ++k) {
    const double f = static_cast<double>(k) / (o.extra_lines_per_axis + 1);
    // x lines on the y = 0 face, y lines on the x = sx face, z lines on both.
    add_segment(Axis::kX, t + Eigen::Vector3d(0, 0, f * sz.z()), t + Eigen::Vector3d(sz.x(), 0, f * sz.z()));
    add_segment(Axis::kY, t + Eigen::Vector3d(sz.x(), 0, f * sz.z()), t + Eigen::Vector3d(sz.x(), sz.y(), f * sz.z()));
    add_segment(Axis::kZ, t + Eigen::Vector3d(f * sz.x(), 0, 0), t + Eigen::Vector3d(f * sz.x(), 0, sz.z()));
  }

  for (int c = 0; c < 8; ++c) {
    Pin pin;
    pin.id = p.NewId();
    pin.image_id = image.id;
    pin.vertex = {box_id, static_cast<VertexId>(c)};
    pin.uv_px = jitter(s.true_camera.Project(corners[c]));
    p.pins.push_back(pin);
  }
  return s;
}

}  // namespace facet::testing
