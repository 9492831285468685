#include "core/scene/project.h"

#include <algorithm>
#include <cassert>
#include <unordered_map>

#include "core/util/input_limits.h"

namespace facet {

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
const Primitive* Project::FindPrimitive(Id id) const { return FindById(primitives, id); }
Primitive* Project::FindPrimitive(Id id) { return FindById(primitives, id); }
const Constraint* Project::FindConstraint(Id id) const { return FindById(constraints, id); }
Constraint* Project::FindConstraint(Id id) { return FindById(constraints, id); }
const Reference* Project::FindReference(Id id) const { return FindById(references, id); }
Reference* Project::FindReference(Id id) { return FindById(references, id); }

const MeshVertex* Project::FindVertex(const VertexRef& ref) const {
  const Primitive* primitive = FindPrimitive(ref.primitive_id);
  if (primitive == nullptr || !primitive->mesh.IsVertex(ref.vertex)) return nullptr;
  return &primitive->mesh.vertex(ref.vertex);
}

Eigen::Vector3d VertexInWorld(const Project& project, const VertexRef& ref) {
  const MeshVertex* vertex = project.FindVertex(ref);
  assert(vertex != nullptr);
  return vertex->position;
}

bool AddPrimitiveToProject(Project* project, PrimitiveShape shape, const std::string& name, Id* new_id,
                           std::string* message) {
  Primitive primitive;
  primitive.id = project->next_id;
  primitive.name = name;
  shape.id = primitive.id;
  primitive.shape = shape;
  const AddPrimitiveResult added = AddPrimitive(&primitive.mesh, shape);
  if (!added.ok) {
    if (message != nullptr) *message = added.message;
    return false;
  }
  project->NewId();
  project->primitives.push_back(std::move(primitive));
  if (new_id != nullptr) *new_id = project->primitives.back().id;
  return true;
}

void RefreshPrimitive(Project* project, Primitive* primitive) {
  if (primitive->attached_to != kNoId) {
    const Primitive* base = project->FindPrimitive(primitive->attached_to);
    // A base that is gone or no longer a box leaves the primitive where it is.
    if (base != nullptr) AttachOnTop(base->shape, &primitive->shape, nullptr);
  }
  UpdatePrimitivePositions(&primitive->mesh, primitive->shape);
}

int AttachmentDepth(const Project& project, const Primitive& primitive) {
  int depth = 0;
  for (const Primitive* cur = &primitive; cur->attached_to != kNoId && depth < kMaxAttachmentDepth; ++depth) {
    cur = project.FindPrimitive(cur->attached_to);
    if (cur == nullptr) break;
  }
  return depth;
}

void RefreshAllPrimitives(Project* project) {
  // Bases first, by depth. The depths are computed once through an id index: a project of
  // many primitives in deep chains would otherwise walk every chain once per level.
  std::unordered_map<Id, const Primitive*> by_id;
  for (const Primitive& p : project->primitives) by_id[p.id] = &p;
  std::vector<std::pair<int, size_t>> order;  // (depth, index), stable by index within a depth
  for (size_t i = 0; i < project->primitives.size(); ++i) {
    int depth = 0;
    for (const Primitive* cur = &project->primitives[i]; cur->attached_to != kNoId && depth < kMaxAttachmentDepth;
         ++depth) {
      const auto it = by_id.find(cur->attached_to);
      if (it == by_id.end()) break;
      cur = it->second;
    }
    order.emplace_back(depth, i);
  }
  std::sort(order.begin(), order.end());
  for (const auto& [depth, i] : order) RefreshPrimitive(project, &project->primitives[i]);
}

const FaceTextureOverride* FindFaceTextureOverride(const Primitive& primitive, FaceId face) {
  const auto it = std::lower_bound(primitive.face_textures.begin(), primitive.face_textures.end(), face,
                                   [](const FaceTextureOverride& o, FaceId f) { return o.face < f; });
  return it != primitive.face_textures.end() && it->face == face ? &*it : nullptr;
}

void SetFaceTextureOverride(Primitive* primitive, FaceTextureOverride entry) {
  std::sort(entry.excluded_images.begin(), entry.excluded_images.end());
  entry.excluded_images.erase(std::unique(entry.excluded_images.begin(), entry.excluded_images.end()),
                              entry.excluded_images.end());
  std::vector<FaceTextureOverride>& list = primitive->face_textures;
  const auto it = std::lower_bound(list.begin(), list.end(), entry.face,
                                   [](const FaceTextureOverride& o, FaceId f) { return o.face < f; });
  const bool present = it != list.end() && it->face == entry.face;
  if (entry.IsDefault()) {
    if (present) list.erase(it);
  } else if (present) {
    *it = std::move(entry);
  } else {
    list.insert(it, std::move(entry));
  }
}

const char* ConstraintKindName(ConstraintKind kind) {
  switch (kind) {
    case ConstraintKind::kCoplanar: return "coplanar";
    case ConstraintKind::kCollinear: return "collinear";
    case ConstraintKind::kParallel: return "parallel";
    case ConstraintKind::kPerpendicular: return "perpendicular";
    case ConstraintKind::kEqualLength: return "equal_length";
    case ConstraintKind::kDistance: return "distance";
    case ConstraintKind::kFixedPoint: return "fixed_point";
    case ConstraintKind::kAlongAxis: return "along_axis";
    case ConstraintKind::kEdgeOnImageLine: return "edge_on_image_line";
  }
  return "?";
}

std::optional<ConstraintKind> ConstraintKindFromName(const std::string& name) {
  for (int k = 0; k <= static_cast<int>(ConstraintKind::kEdgeOnImageLine); ++k) {
    const auto kind = static_cast<ConstraintKind>(k);
    if (name == ConstraintKindName(kind)) return kind;
  }
  return std::nullopt;
}
const Pin* Project::FindPin(Id id) const { return FindById(pins, id); }
Pin* Project::FindPin(Id id) { return FindById(pins, id); }

bool operator==(const Camera& a, const Camera& b) {
  return a.width_px == b.width_px && a.height_px == b.height_px && a.focal_px == b.focal_px &&
         a.principal_point_px == b.principal_point_px && a.cam_from_world_rotation == b.cam_from_world_rotation &&
         a.cam_from_world_translation == b.cam_from_world_translation && a.k1 == b.k1 && a.k2 == b.k2;
}
bool operator==(const Image& a, const Image& b) {
  return a.id == b.id && a.path == b.path && a.width_px == b.width_px && a.height_px == b.height_px &&
         a.camera == b.camera && a.camera_calibrated == b.camera_calibrated &&
         a.principal_point_mode == b.principal_point_mode && a.fixed_principal_point_px == b.fixed_principal_point_px &&
         a.pose_locked == b.pose_locked && a.focal_locked == b.focal_locked &&
         a.principal_point_locked == b.principal_point_locked && a.focal_mode == b.focal_mode &&
         a.fixed_focal_px == b.fixed_focal_px && a.focal_prior_px == b.focal_prior_px &&
         a.focal_prior_std_px == b.focal_prior_std_px && a.use_horizon == b.use_horizon &&
         a.horizon_px == b.horizon_px && a.estimate_distortion == b.estimate_distortion &&
         a.distortion_locked == b.distortion_locked && a.axis_quarter_turns == b.axis_quarter_turns &&
         a.axis_turn_provisional == b.axis_turn_provisional &&
         a.camera_from_reconstruction == b.camera_from_reconstruction &&
         a.use_for_texture == b.use_for_texture && a.lens_group == b.lens_group;
}
bool operator==(const PrimitiveShape& a, const PrimitiveShape& b) {
  return a.id == b.id && a.kind == b.kind && a.params == b.params && a.segments == b.segments &&
         a.ridge_along_y == b.ridge_along_y && a.rotation == b.rotation && a.translation == b.translation;
}
bool operator==(const Primitive& a, const Primitive& b) {
  return a.id == b.id && a.name == b.name && a.shape == b.shape && a.mesh == b.mesh &&
         a.param_locked == b.param_locked && a.rotation_locked == b.rotation_locked &&
         a.translation_locked == b.translation_locked && a.attached_to == b.attached_to &&
         a.face_textures == b.face_textures;
}
bool operator==(const Constraint& a, const Constraint& b) {
  return a.id == b.id && a.kind == b.kind && a.vertices == b.vertices && a.value == b.value && a.point == b.point &&
         a.axis == b.axis && a.image_id == b.image_id && a.line_a_px == b.line_a_px && a.line_b_px == b.line_b_px;
}
bool operator==(const Pin& a, const Pin& b) {
  return a.id == b.id && a.image_id == b.image_id && a.vertex == b.vertex && a.uv_px == b.uv_px;
}
bool operator==(const Project& a, const Project& b) {
  return a.images == b.images && a.segments == b.segments && a.primitives == b.primitives && a.pins == b.pins &&
         a.constraints == b.constraints && a.references == b.references && a.units == b.units &&
         a.next_id == b.next_id;
}

}  // namespace facet
