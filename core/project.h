// The modeling state of a Facet project: images with their cameras, the user's line
// segments, the primitives (topology K and parameters) and the constraints F (pins).
// Plain structs; every object has a stable id and is referred to by it, never by index.
// Edits go through core/document.h so that each one is undoable.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/camera.h"

namespace facet {

using Id = std::uint64_t;
constexpr Id kNoId = 0;

// World axis a line family or a box edge is parallel to (core/conventions.h: z is up).
enum class Axis { kX = 0, kY = 1, kZ = 2 };
const char* AxisName(Axis axis);                           // "x", "y", "z"
std::optional<Axis> AxisFromName(const std::string& name);  // inverse of AxisName

// How single-image calibration treats the principal point.
enum class PrincipalPointMode { kSolve = 0, kImageCenter = 1, kFixed = 2 };

struct Image {
  Id id = kNoId;
  std::string path;  // as stored in the project file: relative to the project file's folder
  int width_px = 0;
  int height_px = 0;
  Camera camera;
  bool camera_calibrated = false;  // true once calibration produced intrinsics and rotation
  PrincipalPointMode principal_point_mode = PrincipalPointMode::kSolve;
  Eigen::Vector2d fixed_principal_point_px = Eigen::Vector2d::Zero();  // for kFixed
  bool pose_locked = false;  // the geometry solve keeps this camera's position
};

// A user-drawn line segment in one image, assigned to a vanishing-point family.
struct Segment {
  Id id = kNoId;
  Id image_id = kNoId;
  Axis axis = Axis::kX;
  Eigen::Vector2d a_px = Eigen::Vector2d::Zero();
  Eigen::Vector2d b_px = Eigen::Vector2d::Zero();
};

// A box primitive (K_create). Local coordinates run from 0 to size on each axis; corner i
// has local position (i & 1 ? sx : 0, i & 2 ? sy : 0, i & 4 ? sz : 0). World position of a
// local point p is RotationFromAngleAxis(rotation) * p + translation (core/box.h).
struct Box {
  Id id = kNoId;
  std::string name;
  Eigen::Vector3d size = Eigen::Vector3d::Ones();         // (sx, sy, sz) in world units
  Eigen::Vector3d rotation = Eigen::Vector3d::Zero();     // world_from_box, angle-axis
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();  // world_from_box
  // Parameters the geometry solve must keep. A locked size component is a known length:
  // it fixes the scale of the scene.
  std::array<bool, 3> size_locked = {false, false, false};
  bool rotation_locked = true;  // aligned with the world axes found by calibration
  bool translation_locked = true;
};

// V_proj: a box corner pinned to a pixel of an image.
struct Pin {
  Id id = kNoId;
  Id image_id = kNoId;
  Id box_id = kNoId;
  int corner = 0;  // 0..7, see Box
  Eigen::Vector2d uv_px = Eigen::Vector2d::Zero();
};

struct Project {
  static constexpr int kFormatVersion = 1;
  std::vector<Image> images;
  std::vector<Segment> segments;
  std::vector<Box> boxes;
  std::vector<Pin> pins;
  std::string units = "m";
  Id next_id = 1;  // ids are never reused within a project

  Id NewId() { return next_id++; }

  const Image* FindImage(Id id) const;
  Image* FindImage(Id id);
  const Segment* FindSegment(Id id) const;
  Segment* FindSegment(Id id);
  const Box* FindBox(Id id) const;
  Box* FindBox(Id id);
  const Pin* FindPin(Id id) const;
  Pin* FindPin(Id id);
};

bool operator==(const Camera& a, const Camera& b);
bool operator==(const Image& a, const Image& b);
bool operator==(const Segment& a, const Segment& b);
bool operator==(const Box& a, const Box& b);
bool operator==(const Pin& a, const Pin& b);
bool operator==(const Project& a, const Project& b);

}  // namespace facet
