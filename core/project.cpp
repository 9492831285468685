#include "core/project.h"

#include <algorithm>

namespace facet {

const char* AxisName(Axis axis) {
  switch (axis) {
    case Axis::kX: return "x";
    case Axis::kY: return "y";
    case Axis::kZ: return "z";
  }
  return "?";
}

std::optional<Axis> AxisFromName(const std::string& name) {
  if (name == "x") return Axis::kX;
  if (name == "y") return Axis::kY;
  if (name == "z") return Axis::kZ;
  return std::nullopt;
}

namespace {
template <typename T>
T* FindById(std::vector<T>& items, Id id) {
  auto it = std::find_if(items.begin(), items.end(), [id](const T& t) { return t.id == id; });
  return it == items.end() ? nullptr : &*it;
}
template <typename T>
const T* FindById(const std::vector<T>& items, Id id) {
  auto it = std::find_if(items.begin(), items.end(), [id](const T& t) { return t.id == id; });
  return it == items.end() ? nullptr : &*it;
}
}  // namespace

const Image* Project::FindImage(Id id) const { return FindById(images, id); }
Image* Project::FindImage(Id id) { return FindById(images, id); }
const Segment* Project::FindSegment(Id id) const { return FindById(segments, id); }
Segment* Project::FindSegment(Id id) { return FindById(segments, id); }
const Box* Project::FindBox(Id id) const { return FindById(boxes, id); }
Box* Project::FindBox(Id id) { return FindById(boxes, id); }
const Pin* Project::FindPin(Id id) const { return FindById(pins, id); }
Pin* Project::FindPin(Id id) { return FindById(pins, id); }

bool operator==(const Camera& a, const Camera& b) {
  return a.width_px == b.width_px && a.height_px == b.height_px && a.focal_px == b.focal_px &&
         a.principal_point_px == b.principal_point_px &&
         a.cam_from_world_rotation == b.cam_from_world_rotation &&
         a.cam_from_world_translation == b.cam_from_world_translation;
}
bool operator==(const Image& a, const Image& b) {
  return a.id == b.id && a.path == b.path && a.width_px == b.width_px &&
         a.height_px == b.height_px && a.camera == b.camera &&
         a.camera_calibrated == b.camera_calibrated &&
         a.principal_point_mode == b.principal_point_mode &&
         a.fixed_principal_point_px == b.fixed_principal_point_px && a.pose_locked == b.pose_locked;
}
bool operator==(const Segment& a, const Segment& b) {
  return a.id == b.id && a.image_id == b.image_id && a.axis == b.axis && a.a_px == b.a_px &&
         a.b_px == b.b_px;
}
bool operator==(const Box& a, const Box& b) {
  return a.id == b.id && a.name == b.name && a.size == b.size && a.rotation == b.rotation &&
         a.translation == b.translation && a.size_locked == b.size_locked &&
         a.rotation_locked == b.rotation_locked && a.translation_locked == b.translation_locked;
}
bool operator==(const Pin& a, const Pin& b) {
  return a.id == b.id && a.image_id == b.image_id && a.box_id == b.box_id &&
         a.corner == b.corner && a.uv_px == b.uv_px;
}
bool operator==(const Project& a, const Project& b) {
  return a.images == b.images && a.segments == b.segments && a.boxes == b.boxes &&
         a.pins == b.pins && a.units == b.units && a.next_id == b.next_id;
}

}  // namespace facet
