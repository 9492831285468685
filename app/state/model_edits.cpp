#include "app/state/model_edits.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <set>
#include <sstream>

#include <imgui.h>
#include <Eigen/Geometry>

#include "core/mesh/extrude.h"
#include "core/mesh/operators.h"
#include "core/solve/joint_solve.h"
#include "core/solve/vertex_move.h"
#include "core/util/input_limits.h"

namespace facet::app {
namespace {

// Logs a refusal: the core's message as an error (the status bar shows the last one).
bool Refuse(AppState* state, const std::string& what, const std::string& message) {
  state->Log(LogLevel::kError, what + ": " + message);
  return false;
}

// A copy of the project and the named primitive in it, or null (and a logged error).
Primitive* EditablePrimitive(AppState* state, Project* edited, Id primitive_id, const std::string& what) {
  *edited = state->document.project();
  Primitive* primitive = edited->FindPrimitive(primitive_id);
  if (primitive == nullptr) Refuse(state, what, "the primitive is gone");
  return primitive;
}

bool NamesVertex(const std::vector<VertexRef>& refs, const VertexRef& v) {
  return std::find(refs.begin(), refs.end(), v) != refs.end();
}

}  // namespace

PrimitiveShape DefaultShape(PrimitiveKind kind) {
  switch (kind) {
    case PrimitiveKind::kBox: return MakeBox(kNoId, Eigen::Vector3d::Ones());
    case PrimitiveKind::kWedge: return MakeWedge(kNoId, Eigen::Vector3d(1.0, 1.0, 0.5));
    case PrimitiveKind::kPyramid: return MakePyramid(kNoId, Eigen::Vector3d(1.0, 1.0, 0.5));
    case PrimitiveKind::kPrism: return MakePrism(kNoId, 6, 0.5, 1.0);
    case PrimitiveKind::kCylinder: return MakeCylinder(kNoId, 16, 0.5, 1.0);
    case PrimitiveKind::kPlane: return MakePlane(kNoId, 1.0, 1.0);
  }
  return MakeBox(kNoId, Eigen::Vector3d::Ones());
}

int NumShapeParams(PrimitiveKind kind) { return ShapeParamCount(kind); }

const char* ShapeParamName(PrimitiveKind kind, int index) { return ShapeParamLabel(kind, index); }

bool CanAttachOnTop(PrimitiveKind kind) {
  return kind == PrimitiveKind::kWedge || kind == PrimitiveKind::kPyramid || kind == PrimitiveKind::kPlane ||
         kind == PrimitiveKind::kBox;
}

const Primitive* AttachBaseFor(const AppState& state, PrimitiveKind kind) {
  const Primitive* base = state.document.project().FindPrimitive(state.selection.primitive_id);
  if (base == nullptr || base->shape.kind != PrimitiveKind::kBox || !CanAttachOnTop(kind)) return nullptr;
  return base;
}

namespace {

// World bounding box of a primitive's live vertices.
Eigen::AlignedBox3d PrimitiveBounds(const Primitive& primitive) {
  Eigen::AlignedBox3d box;
  for (VertexId v = 0; v < primitive.mesh.VertexIdEnd(); ++v) {
    if (primitive.mesh.IsVertex(v)) box.extend(primitive.mesh.vertex(v).position);
  }
  return box;
}

// The aim's ray when it points down enough to meet the ground in front; else the ray through
// the image's centre column, three quarters down (where the ground of a photo usually is).
Eigen::Vector3d AimRay(const Camera& camera, const Eigen::Vector2d& aim_px) {
  constexpr double kMinDownward = 0.02;  // |sin| of the angle below the horizon
  const Eigen::Vector3d aim = camera.RayDirectionInWorld(aim_px);
  if (aim.z() < -kMinDownward) return aim;
  const Eigen::Vector3d low = camera.RayDirectionInWorld(
      Eigen::Vector2d(camera.principal_point_px.x(), 0.75 * std::max(1, camera.height_px)));
  return low.z() < aim.z() ? low : aim;
}

// Keeps the added box on the ground plane z = 0: its base corners and the world's origin in
// one coplanar constraint. The origin is the first box's corner 0, held there by its kept
// position and rotation whatever its sizes; its other base corners are not read, since they
// move with its width and depth (a ground constraint over them counted an unpinned depth as
// seen, which then drifted below zero). Returns the log note, or "" when there is no such
// origin (the first primitive is not a box standing at z = 0 with its pose kept) or a base
// corner of the added box is gone or off the ground.
std::string KeepOnGround(Project* project, Id added_id) {
  if (project->primitives.size() < 2) return {};
  const Primitive& first = project->primitives.front();
  const Primitive* added = project->FindPrimitive(added_id);
  constexpr VertexId kOrigin = 0;                    // core/mesh/box.h: the corner at the box's translation
  constexpr VertexId kBaseCorners[] = {0, 1, 2, 3};  // bit 2 (z) clear
  if (added == nullptr || added->id == first.id || first.shape.kind != PrimitiveKind::kBox ||
      added->shape.kind != PrimitiveKind::kBox || !first.translation_locked || !first.rotation_locked ||
      first.attached_to != kNoId || !first.mesh.IsVertex(kOrigin) ||
      std::abs(first.mesh.vertex(kOrigin).position.z()) > 1e-9) {
    return {};
  }
  Constraint c;
  c.kind = ConstraintKind::kCoplanar;
  c.vertices.push_back({first.id, kOrigin});
  for (VertexId v : kBaseCorners) {
    if (!added->mesh.IsVertex(v) || std::abs(added->mesh.vertex(v).position.z()) > 1e-9) return {};
    c.vertices.push_back({added->id, v});
  }
  c.id = project->NewId();
  project->constraints.push_back(c);
  return "it stands on the ground: its base is kept on the plane z = 0 through the origin (" + first.name +
         "'s corner 0; constraint " + std::to_string(c.id) + "; remove it to lift the box, e.g. when " + first.name +
         " is not on the ground)";
}

// The largest "nice" length (1, 1.5, 2, 3, 4, 5, 6 or 8 times a power of ten) not above
// `length` (> 0): a size the properties show as a round number, to type over or keep.
double RoundDownToNiceLength(double length) {
  constexpr double kSteps[] = {8.0, 6.0, 5.0, 4.0, 3.0, 2.0, 1.5, 1.0};
  const double decade = std::pow(10.0, std::floor(std::log10(length)));
  for (double step : kSteps) {
    if (step * decade <= length * (1.0 + 1e-12)) return step * decade;
  }
  return decade;
}

// The depth (camera z) of the nearest vertex of `probe` scaled by `scale` and moved by
// `translation`.
double NearestDepth(const Camera& camera, const Primitive& probe, double scale, const Eigen::Vector3d& translation) {
  double nearest = std::numeric_limits<double>::infinity();
  for (VertexId v = 0; v < probe.mesh.VertexIdEnd(); ++v) {
    if (!probe.mesh.IsVertex(v)) continue;
    nearest = std::min(nearest, camera.CamFromWorld(scale * probe.mesh.vertex(v).position + translation).z());
  }
  return nearest;
}

}  // namespace

NewPrimitivePlacement PlaceNewPrimitive(const Project& project, const PrimitiveShape& shape, const Image* view,
                                        const std::optional<Eigen::Vector2d>& aim_px, Id scale_from) {
  NewPrimitivePlacement out;
  const bool first = project.primitives.empty();
  Primitive probe;
  probe.shape = shape;
  AddPrimitive(&probe.mesh, shape);
  const Eigen::AlignedBox3d own = PrimitiveBounds(probe);
  const double own_size = own.isEmpty() ? 1.0 : std::max(own.sizes().maxCoeff(), 1e-9);
  // The point of the default shape that stands on the ground: its footprint's centre.
  const Eigen::Vector3d own_base(0.5 * (own.min().x() + own.max().x()), 0.5 * (own.min().y() + own.max().y()),
                                 own.min().z());

  if (view == nullptr || !view->camera_calibrated) {
    // No camera to aim with: the first primitive at the origin, the others as large as the one
    // the user works on (else the last one) and beside everything there is, so that a new one
    // does not hide inside another.
    if (first) return out;
    const Primitive* reference = project.FindPrimitive(scale_from);
    if (reference == nullptr) reference = &project.primitives.back();
    const Eigen::AlignedBox3d ref = PrimitiveBounds(*reference);
    if (!ref.isEmpty() && ref.sizes().maxCoeff() > 0.0) out.scale = ref.sizes().maxCoeff() / own_size;
    double max_x = -std::numeric_limits<double>::infinity();
    for (const Primitive& p : project.primitives) {
      const Eigen::AlignedBox3d b = PrimitiveBounds(p);
      if (!b.isEmpty()) max_x = std::max(max_x, b.max().x());
    }
    const Primitive& last = project.primitives.back();
    out.translation =
        Eigen::Vector3d(max_x + 0.25 * out.scale * own_size, last.shape.translation.y(), last.shape.translation.z());
    return out;
  }

  const Camera& camera = view->camera;
  const Eigen::Vector2d aim = aim_px.value_or(camera.principal_point_px);
  const Eigen::Vector3d ray = AimRay(camera, aim);
  const Eigen::Vector3d eye = camera.CenterInWorld();
  bool cameras_free = first;  // no pin or constraint names a vertex yet: the cameras' centres are the gauge
  for (const Image& image : project.images) cameras_free = cameras_free && !image.pose_locked;
  if (cameras_free) {
    // The first primitive fixes the origin and its default size the unit (it stays there);
    // the cameras move so that it stands under the aim, filling about a third of the photo's
    // height.
    const double framing_depth = 3.0 * camera.focal_px * own_size / std::max(1, camera.height_px);
    out.camera_shift = (own_base - framing_depth * ray) - eye;
    return out;
  }
  Eigen::Vector3d ground;
  if (eye.z() > 0.0 && ray.z() < 0.0) {
    ground = eye - (eye.z() / ray.z()) * ray;  // the ground plane (z = 0) under the aim
    out.on_ground = true;
  } else {
    // The camera is not above the ground: at the model's depth along the ray.
    Eigen::AlignedBox3d all;
    for (const Primitive& p : project.primitives) all.extend(PrimitiveBounds(p));
    double depth = all.isEmpty() ? 1.0 : (all.center() - eye).dot(ray);
    if (!(depth > 0.0)) depth = all.isEmpty() ? 1.0 : std::max(all.sizes().maxCoeff(), 1e-6);
    ground = eye + depth * ray;
  }
  // As large as it looks where it stands, as a shape drawn there in SketchUp is: a quarter of
  // the photo's height at the aimed point's depth, rounded down to a round length. Not the
  // size of the last primitive: an 8 m house's size aimed at the ground just in front of the
  // camera made a cube that straddled the camera.
  constexpr double kPhotoHeightFraction = 0.25;
  const double aim_depth = camera.CamFromWorld(ground).z();
  const double looks_size = kPhotoHeightFraction * std::max(1, camera.height_px) * aim_depth / camera.focal_px;
  out.scale = looks_size > 0.0 ? RoundDownToNiceLength(looks_size) / own_size : 1.0;
  // Never straddling or behind the camera: its nearest corner at least half the aimed depth
  // away (a wide lens aimed low could otherwise reach back past the camera).
  constexpr double kMinNearestDepthFraction = 0.5;
  for (int halvings = 0; halvings < 60; ++halvings) {
    if (NearestDepth(camera, probe, out.scale, ground - out.scale * own_base) >= kMinNearestDepthFraction * aim_depth) {
      break;
    }
    out.scale *= 0.5;
  }
  out.translation = ground - out.scale * own_base;
  return out;
}

bool AddPrimitiveEdit(AppState* state, PrimitiveKind kind, Id base_id, const std::optional<Eigen::Vector2d>& aim_px) {
  Project edited = state->document.project();
  PrimitiveShape shape = DefaultShape(kind);
  const bool first = edited.primitives.empty();
  bool on_ground = false;
  if (base_id == kNoId) {
    const NewPrimitivePlacement placement =
        PlaceNewPrimitive(edited, shape, state->ActiveImage(), aim_px, state->selection.primitive_id);
    on_ground = placement.on_ground;
    shape.params *= placement.scale;
    shape.translation = placement.translation;
    if (placement.camera_shift != Eigen::Vector3d::Zero()) {
      for (Image& image : edited.images) {
        image.camera.SetPose(image.camera.cam_from_world_rotation, image.camera.CenterInWorld() + placement.camera_shift);
      }
    }
  }
  int count = 1;
  for (const Primitive& p : edited.primitives) count += p.shape.kind == kind;
  const std::string name = std::string(PrimitiveKindName(kind)) + " " + std::to_string(count);
  Id id = kNoId;
  std::string message;
  if (!AddPrimitiveToProject(&edited, shape, name, &id, &message)) return Refuse(state, "Add " + name, message);
  Primitive* primitive = edited.FindPrimitive(id);
  // The first primitive fixes origin and scale: its position and last dimension are kept.
  primitive->translation_locked = first;
  if (first) primitive->param_locked[NumShapeParams(kind) - 1] = true;
  std::string label = "Add " + std::string(PrimitiveKindName(kind));
  if (base_id != kNoId) {
    const Primitive* base = edited.FindPrimitive(base_id);
    if (base == nullptr) return Refuse(state, label, "the base primitive is gone");
    if (AttachmentDepth(edited, *base) >= kMaxAttachmentDepth)
      return Refuse(state, label + " on top",
                    "a primitive may sit on at most " + std::to_string(kMaxAttachmentDepth) +
                        " others (a chain of attachments); " + base->name + " sits on " +
                        std::to_string(kMaxAttachmentDepth) + " already");
    PrimitiveShape attached = primitive->shape;
    if (!AttachOnTop(base->shape, &attached, &message)) return Refuse(state, label + " on top", message);
    if (kind == PrimitiveKind::kWedge && base->shape.params[1] > base->shape.params[0]) {
      // A gable roof's ridge runs along the longer side of the box it covers.
      primitive->shape.ridge_along_y = true;
      primitive->mesh = PolyMesh();
      AddPrimitive(&primitive->mesh, primitive->shape);
    }
    primitive->attached_to = base_id;
    label += " on top";
    RefreshPrimitive(&edited, primitive);
  }
  if (on_ground && kind == PrimitiveKind::kBox) {
    if (const std::string note = KeepOnGround(&edited, id); !note.empty()) state->Log(LogLevel::kInfo, label + ": " + note);
  }
  state->selection = Selection();
  state->selection.primitive_id = id;
  CommitEdit(state, label, std::move(edited));
  return true;
}

bool SetWedgeRidgeEdit(AppState* state, Id primitive_id, bool along_y) {
  const std::string label = std::string("Ridge along ") + (along_y ? "y" : "x");
  Project edited;
  Primitive* primitive = EditablePrimitive(state, &edited, primitive_id, label);
  if (primitive == nullptr) return false;
  if (primitive->shape.kind != PrimitiveKind::kWedge) return Refuse(state, label, "only a wedge has a ridge");
  if (primitive->shape.ridge_along_y == along_y) return Refuse(state, label, "the ridge runs that way already");
  // The ridge is in the vertices' local definitions: the mesh is built again, which would
  // lose what the K-operators or a freed vertex made of it.
  const PolyMesh& mesh = primitive->mesh;
  bool edited_mesh = mesh.NumVertices() != 6 || mesh.NumFaces() != 5 || mesh.VertexIdEnd() != 6;
  for (VertexId v = 0; v < mesh.VertexIdEnd() && !edited_mesh; ++v) {
    edited_mesh = !mesh.IsVertex(v) || mesh.vertex(v).local.on_edge || mesh.vertex(v).local.free;
  }
  if (edited_mesh) return Refuse(state, label, "the wedge's mesh was edited (split, connected or freed vertices)");
  primitive->shape.ridge_along_y = along_y;
  PolyMesh rebuilt;
  const AddPrimitiveResult added = AddPrimitive(&rebuilt, primitive->shape);
  if (!added.ok) return Refuse(state, label, added.message);
  primitive->mesh = std::move(rebuilt);
  RefreshPrimitive(&edited, primitive);
  CommitEdit(state, label, std::move(edited));
  return true;
}

bool DeletePrimitiveEdit(AppState* state, Id primitive_id) {
  Project edited = state->document.project();
  const Primitive* primitive = edited.FindPrimitive(primitive_id);
  if (primitive == nullptr) return Refuse(state, "Delete primitive", "the primitive is gone");
  const std::string label = "Delete " + std::string(PrimitiveKindName(primitive->shape.kind));
  std::erase_if(edited.primitives, [&](const Primitive& p) { return p.id == primitive_id; });
  std::erase_if(edited.pins, [&](const Pin& pin) { return pin.vertex.primitive_id == primitive_id; });
  std::erase_if(edited.constraints, [&](const Constraint& c) {
    return std::any_of(c.vertices.begin(), c.vertices.end(),
                       [&](const VertexRef& v) { return v.primitive_id == primitive_id; });
  });
  for (Primitive& p : edited.primitives) {
    if (p.attached_to == primitive_id) p.attached_to = kNoId;
  }
  state->selection = Selection();
  CommitEdit(state, label, std::move(edited));
  return true;
}

bool SplitEdgeEdit(AppState* state, Id primitive_id, EdgeId edge, double t) {
  Project edited;
  Primitive* primitive = EditablePrimitive(state, &edited, primitive_id, "Split edge");
  if (primitive == nullptr) return false;
  const ESplitResult result = ESplit(&primitive->mesh, edge, t);
  if (!result.ok) return Refuse(state, "Split edge", result.message);
  UpdatePrimitivePositions(&primitive->mesh, primitive->shape);
  state->selection = Selection::Of({ElementKind::kVertex, primitive_id, result.vertex});
  CommitEdit(state, "Split edge", std::move(edited));
  return true;
}

bool DeleteVertexEdit(AppState* state, Id primitive_id, VertexId vertex) {
  Project edited;
  Primitive* primitive = EditablePrimitive(state, &edited, primitive_id, "Delete vertex");
  if (primitive == nullptr) return false;
  const VDeleteResult result = VDelete(&primitive->mesh, vertex);
  if (!result.ok) return Refuse(state, "Delete vertex", result.message);
  const VertexRef ref{primitive_id, vertex};
  std::erase_if(edited.pins, [&](const Pin& pin) { return pin.vertex == ref; });
  std::erase_if(edited.constraints, [&](const Constraint& c) { return NamesVertex(c.vertices, ref); });
  state->selection = Selection::Of({ElementKind::kEdge, primitive_id, result.kept_edge});
  CommitEdit(state, "Delete vertex", std::move(edited));
  return true;
}

bool DropFlaggedPinsEdit(AppState* state) {
  const std::vector<FlaggedPin> flagged = state->last_update.joint.flagged_pins;
  if (flagged.empty()) return Refuse(state, "Drop flagged pins", "the last solve flagged no pin");
  Project edited = state->document.project();
  std::vector<std::string> dropped;
  for (const FlaggedPin& f : flagged) {
    const size_t before = edited.pins.size();
    std::erase_if(edited.pins, [&](const Pin& pin) { return pin.id == f.pin_id; });
    if (edited.pins.size() < before) dropped.push_back(f.sentence);
  }
  if (dropped.empty()) return Refuse(state, "Drop flagged pins", "the flagged pins are gone already");
  for (const std::string& why : dropped) state->Log(LogLevel::kInfo, "Dropped a flagged pin: " + why);
  if (state->selection.pin_id != kNoId && edited.FindPin(state->selection.pin_id) == nullptr)
    state->selection.pin_id = kNoId;
  const std::string label =
      "Drop " + std::to_string(dropped.size()) + " flagged pin" + (dropped.size() == 1 ? "" : "s");
  CommitEdit(state, label, std::move(edited));
  return true;
}

bool ConnectVerticesEdit(AppState* state, Id primitive_id, VertexId a, VertexId b) {
  Project edited;
  Primitive* primitive = EditablePrimitive(state, &edited, primitive_id, "Connect vertices");
  if (primitive == nullptr) return false;
  const PolyMesh& mesh = primitive->mesh;
  if (!mesh.IsVertex(a) || !mesh.IsVertex(b)) return Refuse(state, "Connect vertices", "a vertex is gone");
  // The face both lie on; with several (adjacent vertices), the core refuses on the first.
  FaceId face = kNoFace;
  for (FaceId f = 0; f < mesh.FaceIdEnd() && face == kNoFace; ++f) {
    if (!mesh.IsFace(f)) continue;
    const std::vector<VertexId> vs = FaceVertices(mesh, f);
    if (std::count(vs.begin(), vs.end(), a) && std::count(vs.begin(), vs.end(), b)) face = f;
  }
  if (face == kNoFace) {
    return Refuse(state, "Connect vertices",
                  "vertices " + std::to_string(a) + " and " + std::to_string(b) + " do not lie on one face");
  }
  const VConnectResult result = VConnect(&primitive->mesh, face, a, b);
  if (!result.ok) return Refuse(state, "Connect vertices", result.message);
  state->selection = Selection::Of({ElementKind::kEdge, primitive_id, result.edge});
  CommitEdit(state, "Connect vertices", std::move(edited));
  return true;
}

bool DeleteEdgeEdit(AppState* state, Id primitive_id, EdgeId edge) {
  Project edited;
  Primitive* primitive = EditablePrimitive(state, &edited, primitive_id, "Delete edge");
  if (primitive == nullptr) return false;
  const EDeleteResult result = EDelete(&primitive->mesh, edge);
  if (!result.ok) return Refuse(state, "Delete edge", result.message);
  state->selection = Selection::Of({ElementKind::kFace, primitive_id, result.kept_face});
  CommitEdit(state, "Delete edge", std::move(edited));
  return true;
}

bool ToggleFreeVertexEdit(AppState* state, Id primitive_id, VertexId vertex) {
  Project edited;
  Primitive* primitive = EditablePrimitive(state, &edited, primitive_id, "Free vertex");
  if (primitive == nullptr) return false;
  if (!primitive->mesh.IsVertex(vertex)) return Refuse(state, "Free vertex", "the vertex is gone");
  LocalDefinition& local = primitive->mesh.vertex(vertex).local;
  local.free = !local.free;
  if (!local.free) local.offset = Eigen::Vector3d::Zero();
  UpdatePrimitivePositions(&primitive->mesh, primitive->shape);
  const std::string label = local.free ? "Free vertex" : "Fix vertex";
  state->selection = Selection::Of({ElementKind::kVertex, primitive_id, vertex});
  CommitEdit(state, label, std::move(edited));
  return true;
}

bool TogglePlanarFaceEdit(AppState* state, Id primitive_id, FaceId face) {
  Project edited;
  Primitive* primitive = EditablePrimitive(state, &edited, primitive_id, "Planar face");
  if (primitive == nullptr) return false;
  if (!primitive->mesh.IsFace(face)) return Refuse(state, "Planar face", "the face is gone");
  std::vector<VertexRef> vertices;
  for (VertexId v : FaceVertices(primitive->mesh, face)) vertices.push_back({primitive_id, v});
  if (vertices.size() < 4) return Refuse(state, "Planar face", "a triangle is always planar");
  auto same = [&](const Constraint& c) { return c.kind == ConstraintKind::kCoplanar && c.vertices == vertices; };
  const size_t before = edited.constraints.size();
  std::erase_if(edited.constraints, same);
  std::string label = "Unconstrain face";
  if (edited.constraints.size() == before) {
    Constraint c;
    c.id = edited.NewId();
    c.kind = ConstraintKind::kCoplanar;
    c.vertices = vertices;
    edited.constraints.push_back(c);
    label = "Keep face planar";
  }
  CommitEdit(state, label, std::move(edited));
  return true;
}

namespace {

// The two vertices of an edge element (a -> b of half-edge 2 * edge), or false.
bool EdgeVertices(const Project& project, const ElementRef& edge, VertexRef* a, VertexRef* b) {
  if (edge.kind != ElementKind::kEdge || !ElementExists(project, edge)) return false;
  const PolyMesh& mesh = project.FindPrimitive(edge.primitive_id)->mesh;
  *a = {edge.primitive_id, mesh.Origin(2 * edge.element)};
  *b = {edge.primitive_id, mesh.Dest(2 * edge.element)};
  return true;
}

bool VertexLess(const VertexRef& a, const VertexRef& b) {
  return a.primitive_id != b.primitive_id ? a.primitive_id < b.primitive_id : a.vertex < b.vertex;
}

std::vector<VertexRef> Sorted(std::vector<VertexRef> v) {
  std::sort(v.begin(), v.end(), VertexLess);
  return v;
}

// An edge (two vertices) as an unordered pair.
std::pair<VertexRef, VertexRef> UnorderedEdge(const VertexRef& a, const VertexRef& b) {
  return VertexLess(a, b) ? std::make_pair(a, b) : std::make_pair(b, a);
}

bool PairLess(const std::pair<VertexRef, VertexRef>& a, const std::pair<VertexRef, VertexRef>& b) {
  if (!(a.first == b.first)) return VertexLess(a.first, b.first);
  return VertexLess(a.second, b.second);
}

// Whether two constraints say the same thing: vertex sets for coplanar and collinear, edge
// pairs in either order and direction for the two-edge kinds, the same edge either way for
// a distance; otherwise the same vertices in order. Values, axes and images must match.
bool SameConstraint(const Constraint& a, const Constraint& b) {
  if (a.kind != b.kind || a.vertices.size() != b.vertices.size()) return false;
  switch (a.kind) {
    case ConstraintKind::kCoplanar:
    case ConstraintKind::kCollinear: return Sorted(a.vertices) == Sorted(b.vertices);
    case ConstraintKind::kParallel:
    case ConstraintKind::kPerpendicular:
    case ConstraintKind::kEqualLength: {
      auto edges = [](const Constraint& c) {
        std::array<std::pair<VertexRef, VertexRef>, 2> e = {UnorderedEdge(c.vertices[0], c.vertices[1]),
                                                            UnorderedEdge(c.vertices[2], c.vertices[3])};
        if (PairLess(e[1], e[0])) std::swap(e[0], e[1]);
        return e;
      };
      return edges(a) == edges(b);
    }
    case ConstraintKind::kDistance:
      return a.value == b.value &&
             UnorderedEdge(a.vertices[0], a.vertices[1]) == UnorderedEdge(b.vertices[0], b.vertices[1]);
    case ConstraintKind::kAlongAxis:
      return a.axis == b.axis &&
             UnorderedEdge(a.vertices[0], a.vertices[1]) == UnorderedEdge(b.vertices[0], b.vertices[1]);
    case ConstraintKind::kEdgeOnImageLine:
      return a.image_id == b.image_id && a.vertices == b.vertices && a.line_a_px == b.line_a_px &&
             a.line_b_px == b.line_b_px;
    default: return a.vertices == b.vertices && a.value == b.value && a.axis == b.axis && a.point == b.point;
  }
}

// Adds `c` (a fresh id) unless the same constraint (SameConstraint) exists.
bool AddConstraint(AppState* state, Constraint c, const std::string& label) {
  Project edited = state->document.project();
  for (const Constraint& old : edited.constraints) {
    if (SameConstraint(old, c)) return Refuse(state, label, "the same constraint exists already");
  }
  // The first known length the pins see takes over the scale from the first primitive's kept
  // last dimension (AddPrimitiveEdit keeps it only so that a model without one has a scale);
  // both would fix the scale, and they would disagree. A known length on an edge no pin sees
  // (a box's depth when only its front is pinned) says nothing about the size of the rest:
  // releasing the kept dimension for it left nothing to fix the scale, and the solve shrank
  // the model to 1e-16 (issue 14). The kept dimension then stays, and the log says why.
  std::string released;
  // Before any pin is on the edge's primitives nothing is known yet: the length is taken to
  // be what the user will pin (as before), not held against them.
  auto pins_see = [&](const Constraint& length) {
    const bool pinned = std::any_of(edited.pins.begin(), edited.pins.end(), [&](const Pin& pin) {
      return pin.vertex.primitive_id == length.vertices[0].primitive_id ||
             pin.vertex.primitive_id == length.vertices[1].primitive_id;
    });
    return !pinned || PinsSeeLength(edited, length.vertices[0], length.vertices[1]);
  };
  const bool scale_from_length =
      std::any_of(edited.constraints.begin(), edited.constraints.end(),
                  [&](const Constraint& old) { return old.kind == ConstraintKind::kDistance && pins_see(old); });
  if (c.kind == ConstraintKind::kDistance && !scale_from_length && !edited.primitives.empty()) {
    Primitive& first = edited.primitives.front();
    const int last = NumShapeParams(first.shape.kind) - 1;
    if (last >= 0 && first.param_locked[last]) {
      const std::string kept = first.name + "'s " + ShapeParamLabel(first.shape.kind, last);
      if (pins_see(c)) {
        first.param_locked[last] = false;
        released = kept + " is no longer kept: the known length sets the scale";
      } else {
        released = kept +
                   " stays kept and sets the scale: no pin sees this edge's length (pin a vertex that moves "
                   "with it for the known length to set the scale)";
      }
    }
  }
  c.id = edited.NewId();
  edited.constraints.push_back(c);
  CommitEdit(state, label, std::move(edited));
  state->Log(LogLevel::kInfo, label + ": constraint " + std::to_string(c.id) + " added");
  if (!released.empty()) state->Log(LogLevel::kInfo, label + ": " + released);
  return true;
}

}  // namespace

std::string ConstraintEditLabel(ConstraintKind kind) {
  switch (kind) {
    case ConstraintKind::kAlongAxis: return "Along axis";
    case ConstraintKind::kDistance: return "Known length";
    case ConstraintKind::kParallel: return "Parallel";
    case ConstraintKind::kPerpendicular: return "Perpendicular";
    case ConstraintKind::kEqualLength: return "Equal length";
    case ConstraintKind::kFixedPoint: return "Fix vertex";
    default: return std::string("Constrain ") + ConstraintKindName(kind);
  }
}

std::string DescribeVertex(const Project& project, const VertexRef& ref) {
  const Primitive* p = project.FindPrimitive(ref.primitive_id);
  const std::string name = p != nullptr ? p->name : "primitive " + std::to_string(ref.primitive_id);
  return name + " v" + std::to_string(ref.vertex);
}

bool ConstrainAlongAxisEdit(AppState* state, const ElementRef& edge, Axis axis) {
  const std::string label = std::string("Along ") + AxisName(axis);
  Constraint c;
  c.kind = ConstraintKind::kAlongAxis;
  c.axis = axis;
  c.vertices.resize(2);
  if (!EdgeVertices(state->document.project(), edge, &c.vertices[0], &c.vertices[1])) {
    return Refuse(state, label, "select an edge first");
  }
  return AddConstraint(state, c, label);
}

bool MeasuredPair(const Selection& selection, ElementRef* a, ElementRef* b) {
  if (selection.element.kind != ElementKind::kVertex || selection.extra.size() != 1 ||
      selection.extra[0].kind != ElementKind::kVertex || selection.extra[0] == selection.element) {
    return false;
  }
  *a = selection.element;
  *b = selection.extra[0];
  return true;
}

bool ConstrainDistanceEdit(AppState* state, const ElementRef& a, const ElementRef& b, double length) {
  const std::string label = "Known length";
  if (!std::isfinite(length) || length <= 0.0) return Refuse(state, label, "the length must be positive");
  const Project& project = state->document.project();
  if (a.kind != ElementKind::kVertex || b.kind != ElementKind::kVertex || !ElementExists(project, a) ||
      !ElementExists(project, b)) {
    return Refuse(state, label, "pick two vertices");
  }
  if (a == b) return Refuse(state, label, "pick two different vertices");
  Constraint c;
  c.kind = ConstraintKind::kDistance;
  c.value = length;
  c.vertices = {VertexRef{a.primitive_id, a.element}, VertexRef{b.primitive_id, b.element}};
  return AddConstraint(state, c, label);
}

bool ConstrainLengthEdit(AppState* state, const ElementRef& edge, double length) {
  const std::string label = "Known length";
  if (!std::isfinite(length) || length <= 0.0) return Refuse(state, label, "the length must be positive");
  Constraint c;
  c.kind = ConstraintKind::kDistance;
  c.value = length;
  c.vertices.resize(2);
  if (!EdgeVertices(state->document.project(), edge, &c.vertices[0], &c.vertices[1])) {
    return Refuse(state, label, "select an edge first");
  }
  return AddConstraint(state, c, label);
}

bool ConstrainEdgePairEdit(AppState* state, ConstraintKind kind, const ElementRef& first, const ElementRef& second) {
  const std::string label = ConstraintEditLabel(kind);
  if (kind != ConstraintKind::kParallel && kind != ConstraintKind::kPerpendicular &&
      kind != ConstraintKind::kEqualLength) {
    return Refuse(state, label, "not a two-edge constraint");
  }
  if (first == second) return Refuse(state, label, "pick two different edges");
  Constraint c;
  c.kind = kind;
  c.vertices.resize(4);
  const Project& project = state->document.project();
  if (!EdgeVertices(project, first, &c.vertices[0], &c.vertices[1]) ||
      !EdgeVertices(project, second, &c.vertices[2], &c.vertices[3])) {
    return Refuse(state, label, "an edge is gone");
  }
  return AddConstraint(state, c, label);
}

bool FixVertexEdit(AppState* state, const ElementRef& vertex) {
  const std::string label = "Fix vertex";
  const Project& project = state->document.project();
  if (vertex.kind != ElementKind::kVertex || !ElementExists(project, vertex)) {
    return Refuse(state, label, "select a vertex first");
  }
  Constraint c;
  c.kind = ConstraintKind::kFixedPoint;
  c.vertices = {VertexRef{vertex.primitive_id, vertex.element}};
  c.point = VertexInWorld(project, c.vertices[0]);
  return AddConstraint(state, c, label);
}

std::vector<VertexRef> VerticesOfElements(const Project& project, const std::vector<ElementRef>& elements) {
  std::vector<VertexRef> out;
  auto add = [&](Id primitive_id, VertexId v) {
    const VertexRef ref{primitive_id, v};
    if (!NamesVertex(out, ref)) out.push_back(ref);
  };
  for (const ElementRef& e : elements) {
    if (!ElementExists(project, e)) continue;
    const PolyMesh& mesh = project.FindPrimitive(e.primitive_id)->mesh;
    switch (e.kind) {
      case ElementKind::kVertex: add(e.primitive_id, e.element); break;
      case ElementKind::kEdge:
        add(e.primitive_id, mesh.Origin(2 * e.element));
        add(e.primitive_id, mesh.Dest(2 * e.element));
        break;
      case ElementKind::kFace:
        for (VertexId v : FaceVertices(mesh, e.element)) add(e.primitive_id, v);
        break;
      case ElementKind::kNone: break;
    }
  }
  return out;
}

namespace {

// Relative tolerance for "collinear" and "coincident" in the builder's refusals: the points
// as they are now, before the solve (the core skips such constraints as degenerate).
constexpr double kDegenerateRelTolerance = 1e-9;

// Whether points a, b, c are collinear relative to their spread.
bool Collinear3(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const double scale = std::max({(b - a).norm(), (c - a).norm(), (c - b).norm()});
  return (b - a).cross(c - a).norm() <= kDegenerateRelTolerance * scale * scale;
}

}  // namespace

bool ConstrainVertexSetEdit(AppState* state, ConstraintKind kind, const std::vector<ElementRef>& elements,
                            const std::string& label_in) {
  const bool coplanar = kind == ConstraintKind::kCoplanar;
  const std::string label = !label_in.empty() ? label_in : coplanar ? "Coplanar" : "Collinear";
  if (kind != ConstraintKind::kCoplanar && kind != ConstraintKind::kCollinear) {
    return Refuse(state, label, "not a vertex-set constraint");
  }
  const Project& project = state->document.project();
  for (const ElementRef& e : elements) {
    if (!ElementExists(project, e)) return Refuse(state, label, DescribeElement(project, e) + " is gone");
    if (!coplanar && e.kind == ElementKind::kFace) return Refuse(state, label, "select vertices or edges, not faces");
  }
  const std::vector<VertexRef> vertices = VerticesOfElements(project, elements);
  const size_t need = coplanar ? 4 : 3;
  if (vertices.size() < need) {
    return Refuse(state, label,
                  "needs " + std::to_string(need) + " or more different vertices (" + std::to_string(vertices.size()) +
                      " selected" +
                      (coplanar ? "; 3 points are always coplanar)" : "; 2 points are always collinear)"));
  }
  std::vector<Eigen::Vector3d> p;
  for (const VertexRef& v : vertices) p.push_back(VertexInWorld(project, v));
  // The farthest point from the first, then the one farthest off that line (as the solve
  // picks its frame).
  size_t i1 = 1;
  for (size_t k = 1; k < p.size(); ++k) {
    if ((p[k] - p[0]).norm() > (p[i1] - p[0]).norm()) i1 = k;
  }
  double spread = (p[i1] - p[0]).norm();
  if (spread <= 0.0) return Refuse(state, label, "the vertices coincide");
  if (coplanar) {
    double best = 0.0;
    for (size_t k = 1; k < p.size(); ++k) best = std::max(best, (p[i1] - p[0]).cross(p[k] - p[0]).norm());
    if (best <= kDegenerateRelTolerance * spread * spread) {
      return Refuse(state, label, "the vertices are collinear: they do not define a plane");
    }
    if (p.size() == 4) {
      for (int skip = 0; skip < 4; ++skip) {
        std::vector<int> rest;
        for (int k = 0; k < 4; ++k) {
          if (k != skip) rest.push_back(k);
        }
        if (Collinear3(p[rest[0]], p[rest[1]], p[rest[2]])) {
          return Refuse(state, label,
                        DescribeVertex(project, vertices[rest[0]]) + ", " + DescribeVertex(project, vertices[rest[1]]) +
                            " and " + DescribeVertex(project, vertices[rest[2]]) +
                            " are collinear: with a fourth point they are always coplanar");
        }
      }
    }
  }
  Constraint c;
  c.kind = kind;
  c.vertices = vertices;
  return AddConstraint(state, c, label + " (" + std::to_string(vertices.size()) + " vertices)");
}

bool ConstrainParallelFacesEdit(AppState* state, const ElementRef& first, const ElementRef& second) {
  const std::string label = "Parallel faces";
  const Project& project = state->document.project();
  if (first.kind != ElementKind::kFace || second.kind != ElementKind::kFace || !ElementExists(project, first) ||
      !ElementExists(project, second)) {
    return Refuse(state, label, "select two faces");
  }
  if (first == second) return Refuse(state, label, "pick two different faces");
  struct FaceEdge {
    VertexRef a, b;
    Eigen::Vector3d dir;
  };
  auto edges_of = [&](const ElementRef& face) {
    std::vector<FaceEdge> out;
    const PolyMesh& mesh = project.FindPrimitive(face.primitive_id)->mesh;
    for (HalfedgeId h : FaceHalfedges(mesh, face.element)) {
      FaceEdge e{{face.primitive_id, mesh.Origin(h)}, {face.primitive_id, mesh.Dest(h)}, Eigen::Vector3d::Zero()};
      const Eigen::Vector3d d = mesh.vertex(mesh.Dest(h)).position - mesh.vertex(mesh.Origin(h)).position;
      if (d.norm() <= 0.0) continue;
      e.dir = d.normalized();
      out.push_back(e);
    }
    return out;
  };
  const std::vector<FaceEdge> ea = edges_of(first), eb = edges_of(second);
  auto sin_angle = [](const Eigen::Vector3d& u, const Eigen::Vector3d& v) { return u.cross(v).norm(); };
  auto same_edge = [](const FaceEdge& x, const FaceEdge& y) {
    return UnorderedEdge(x.a, x.b) == UnorderedEdge(y.a, y.b);
  };
  // The most nearly parallel pair, then the best pair whose first-face edge is not parallel
  // to the first pair's (so the two pairs span the plane).
  constexpr double kMinSpanSin = 0.34;  // about 20 degrees between the two directions
  int best_i = -1, best_j = -1;
  double best = 2.0;
  for (size_t i = 0; i < ea.size(); ++i) {
    for (size_t j = 0; j < eb.size(); ++j) {
      if (same_edge(ea[i], eb[j])) continue;
      const double sa = sin_angle(ea[i].dir, eb[j].dir);
      if (sa < best) best = sa, best_i = static_cast<int>(i), best_j = static_cast<int>(j);
    }
  }
  int second_i = -1, second_j = -1;
  double second_best = 2.0;
  if (best_i >= 0) {
    for (size_t i = 0; i < ea.size(); ++i) {
      if (sin_angle(ea[i].dir, ea[best_i].dir) < kMinSpanSin) continue;
      for (size_t j = 0; j < eb.size(); ++j) {
        if (same_edge(ea[i], eb[j]) || sin_angle(eb[j].dir, eb[best_j].dir) < kMinSpanSin) continue;
        const double sa = sin_angle(ea[i].dir, eb[j].dir);
        if (sa < second_best) second_best = sa, second_i = static_cast<int>(i), second_j = static_cast<int>(j);
      }
    }
  }
  const double max_sin = std::sin(kParallelFacesMaxAngleDeg * M_PI / 180.0);
  if (best_i < 0 || second_i < 0 || best > max_sin || second_best > max_sin) {
    char text[200];
    std::snprintf(text, sizeof(text),
                  "the faces have no two pairs of edges within %.0f deg of parallel; parallel faces are made of "
                  "parallel edge pairs, which would also turn the faces within their planes",
                  kParallelFacesMaxAngleDeg);
    return Refuse(state, label, text);
  }
  Project edited = project;
  int added = 0;
  for (const auto& [i, j] : {std::make_pair(best_i, best_j), std::make_pair(second_i, second_j)}) {
    Constraint c;
    c.kind = ConstraintKind::kParallel;
    c.vertices = {ea[i].a, ea[i].b, eb[j].a, eb[j].b};
    const bool exists = std::any_of(edited.constraints.begin(), edited.constraints.end(),
                                    [&](const Constraint& old) { return SameConstraint(old, c); });
    if (exists) continue;
    c.id = edited.NewId();
    edited.constraints.push_back(c);
    ++added;
  }
  if (added == 0) return Refuse(state, label, "the same constraints exist already");
  CommitEdit(state, label, std::move(edited));
  state->Log(LogLevel::kInfo, label + ": " + std::to_string(added) + " parallel-edge constraints added");
  return true;
}

bool LinePinEdit(AppState* state, const ElementRef& edge, Id image_id, const Eigen::Vector2d& a_px,
                 const Eigen::Vector2d& b_px) {
  const std::string label = "Line pin";
  const Project& project = state->document.project();
  Constraint c;
  c.kind = ConstraintKind::kEdgeOnImageLine;
  c.vertices.resize(2);
  if (!EdgeVertices(project, edge, &c.vertices[0], &c.vertices[1])) return Refuse(state, label, "select an edge first");
  const Image* image = project.FindImage(image_id);
  if (image == nullptr) return Refuse(state, label, "the image is gone");
  if (!image->camera_calibrated) return Refuse(state, label, "the image is not calibrated yet (draw its lines first)");
  if (!a_px.allFinite() || !b_px.allFinite() || (b_px - a_px).norm() < kMinLinePinLengthPx) {
    return Refuse(state, label, "draw the line along the photo's edge (two points further apart)");
  }
  c.image_id = image_id;
  c.line_a_px = a_px;
  c.line_b_px = b_px;
  Project edited = project;
  const auto same_edge = [&](const Constraint& old) {
    return old.kind == ConstraintKind::kEdgeOnImageLine && old.image_id == image_id &&
           UnorderedEdge(old.vertices[0], old.vertices[1]) == UnorderedEdge(c.vertices[0], c.vertices[1]);
  };
  for (const Constraint& old : edited.constraints) {
    if (same_edge(old) && old.line_a_px == a_px && old.line_b_px == b_px) {
      return Refuse(state, label, "the same constraint exists already");
    }
  }
  const size_t before = edited.constraints.size();
  std::erase_if(edited.constraints, same_edge);
  const bool replaced = edited.constraints.size() != before;
  c.id = edited.NewId();
  edited.constraints.push_back(c);
  const std::string full = replaced ? label + " (replaced)" : label;
  const std::string what = DescribeElement(project, edge);
  CommitEdit(state, full, std::move(edited));
  state->Log(LogLevel::kInfo, full + ": constraint " + std::to_string(c.id) + " on " + what);
  return true;
}

std::vector<Id> LinePinsOfImage(const Project& project, Id image_id) {
  std::vector<Id> ids;
  for (const Constraint& c : project.constraints) {
    if (c.kind == ConstraintKind::kEdgeOnImageLine && c.image_id == image_id) ids.push_back(c.id);
  }
  return ids;
}

ElementRef LinePinEdge(const Project& project, const Constraint& line_pin) {
  if (line_pin.kind != ConstraintKind::kEdgeOnImageLine || line_pin.vertices.size() != 2) return {};
  const VertexRef& a = line_pin.vertices[0];
  const VertexRef& b = line_pin.vertices[1];
  const Primitive* primitive = project.FindPrimitive(a.primitive_id);
  if (primitive == nullptr || b.primitive_id != a.primitive_id || !primitive->mesh.IsVertex(a.vertex) ||
      !primitive->mesh.IsVertex(b.vertex)) {
    return {};
  }
  const HalfedgeId h = FindHalfedge(primitive->mesh, a.vertex, b.vertex);
  if (h == kNoElement) return {};
  return {ElementKind::kEdge, a.primitive_id, PolyMesh::EdgeOf(h)};
}

bool MoveLinePinEnd(Project* project, Id constraint_id, int end, const Eigen::Vector2d& uv_px) {
  Constraint* c = project->FindConstraint(constraint_id);
  if (c == nullptr || c->kind != ConstraintKind::kEdgeOnImageLine || (end != 0 && end != 1) || !uv_px.allFinite()) {
    return false;
  }
  const Eigen::Vector2d& other = end == 0 ? c->line_b_px : c->line_a_px;
  if ((uv_px - other).norm() < kMinLinePinLengthPx) return false;
  (end == 0 ? c->line_a_px : c->line_b_px) = uv_px;
  return true;
}

bool MoveLinePinEndEdit(AppState* state, Id constraint_id, int end, const Eigen::Vector2d& uv_px) {
  const std::string label = "Move line pin end";
  const Constraint* c = state->document.project().FindConstraint(constraint_id);
  if (c == nullptr || c->kind != ConstraintKind::kEdgeOnImageLine) return Refuse(state, label, "no such line pin");
  if (end != 0 && end != 1) return Refuse(state, label, "the end is 0 (a) or 1 (b)");
  if ((end == 0 ? c->line_a_px : c->line_b_px) == uv_px) return Refuse(state, label, "the end is there already");
  Project edited = state->document.project();
  if (!MoveLinePinEnd(&edited, constraint_id, end, uv_px)) {
    return Refuse(state, label, "the line's two points must stay further apart than 2 px");
  }
  CommitEdit(state, label, std::move(edited));
  return true;
}

bool RemoveConstraintEdit(AppState* state, Id constraint_id) {
  Project edited = state->document.project();
  const size_t before = edited.constraints.size();
  std::erase_if(edited.constraints, [&](const Constraint& c) { return c.id == constraint_id; });
  if (edited.constraints.size() == before) return Refuse(state, "Remove constraint", "the constraint is gone");
  CommitEdit(state, "Remove constraint", std::move(edited));
  return true;
}

bool ConstraintPairStep(AppState* state, ConstraintKind kind) {
  const ElementRef edge = state->selection.element;
  const std::string label = ConstraintEditLabel(kind);
  if (edge.kind != ElementKind::kEdge) return Refuse(state, label, "select an edge first");
  const bool pending =
      state->constraint_first_kind == kind && ElementExists(state->document.project(), state->constraint_first_edge);
  if (!pending) {
    state->constraint_first_edge = edge;
    state->constraint_first_kind = kind;
    state->Log(LogLevel::kInfo, label + ": first edge " + DescribeElement(state->document.project(), edge) +
                                    "; select the second edge and click again");
    return true;
  }
  if (edge == state->constraint_first_edge) return Refuse(state, label, "pick a second, different edge");
  const ElementRef first = state->constraint_first_edge;
  const bool done = ConstrainEdgePairEdit(state, kind, first, edge);
  if (done) {
    state->constraint_first_edge = ElementRef();
    state->constraint_first_kind.reset();
  }
  return done;
}

bool RunConstrainCommand(AppState* state, const std::string& arg, std::string* error) {
  std::istringstream in(arg);
  std::string kind;
  in >> kind;
  std::string value_text;
  in >> value_text;
  const ElementRef e = state->selection.element;
  bool done = false;
  if (kind == "along-x" || kind == "along-y" || kind == "along-z") {
    done = ConstrainAlongAxisEdit(state, e, *AxisFromName(kind.substr(6)));
  } else if (kind == "length") {
    char* end = nullptr;
    const double v = std::strtod(value_text.c_str(), &end);
    if (value_text.empty() || *end != '\0') {
      *error = "constrain length: needs a number (project units)";
      return false;
    }
    ElementRef a, b;
    done = MeasuredPair(state->selection, &a, &b) ? ConstrainDistanceEdit(state, a, b, v)
                                                   : ConstrainLengthEdit(state, e, v);
  } else if (kind == "parallel" || kind == "perpendicular" || kind == "equal-length") {
    const ConstraintKind k = kind == "parallel"        ? ConstraintKind::kParallel
                             : kind == "perpendicular" ? ConstraintKind::kPerpendicular
                                                       : ConstraintKind::kEqualLength;
    const std::vector<ElementRef> selected = SelectedElements(state->selection);
    if (selected.size() == 2) {
      done = ConstrainEdgePairEdit(state, k, selected[0], selected[1]);
    } else {
      done = ConstraintPairStep(state, k);
    }
  } else if (kind == "coplanar" || kind == "collinear") {
    done = ConstrainVertexSetEdit(state, kind == "coplanar" ? ConstraintKind::kCoplanar : ConstraintKind::kCollinear,
                                  SelectedElements(state->selection));
  } else if (kind == "parallel-faces") {
    const std::vector<ElementRef> selected = SelectedElements(state->selection);
    if (selected.size() != 2) {
      *error = "constrain parallel-faces: select exactly two faces";
      return false;
    }
    done = ConstrainParallelFacesEdit(state, selected[0], selected[1]);
  } else if (kind == "fix") {
    done = FixVertexEdit(state, e);
  } else if (kind == "remove") {
    char* end = nullptr;
    const long long id = std::strtoll(value_text.c_str(), &end, 10);
    if (value_text.empty() || *end != '\0') {
      *error = "constrain remove: needs a constraint id";
      return false;
    }
    done = RemoveConstraintEdit(state, static_cast<Id>(id));
  } else {
    *error = "constrain: unknown kind '" + kind +
             "' (along-x, along-y, along-z, length VALUE, parallel, perpendicular, equal-length, fix, remove ID, "
             "coplanar, collinear, parallel-faces)";
    return false;
  }
  if (!done) *error = state->log.empty() ? "constrain: refused" : state->log.back().text;
  return done;
}

bool PushPullFaceEdit(AppState* state, Id primitive_id, FaceId face, double distance) {
  Project edited;
  Primitive* primitive = EditablePrimitive(state, &edited, primitive_id, "Push/pull face");
  if (primitive == nullptr) return false;
  const ExtrudeResult result = ExtrudeFace(&primitive->mesh, primitive->shape, face, distance);
  if (!result.ok) return Refuse(state, "Push/pull face", result.message);
  state->selection = Selection::Of({ElementKind::kFace, primitive_id, face});
  CommitEdit(state, "Push/pull face", std::move(edited));
  return true;
}

double DefaultPushPullDistance(const Primitive& primitive) {
  constexpr double kFraction = 0.1;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  const PolyMesh& mesh = primitive.mesh;
  for (VertexId v = 0; v < mesh.VertexIdEnd(); ++v) {
    if (!mesh.IsVertex(v)) continue;
    lo = lo.cwiseMin(mesh.vertex(v).position);
    hi = hi.cwiseMax(mesh.vertex(v).position);
  }
  const double size = (hi - lo).maxCoeff();
  return std::isfinite(size) && size > 0.0 ? kFraction * size : kFraction;
}

Id PinVertex(Project* project, Id image_id, const VertexRef& vertex, const Eigen::Vector2d& uv_px) {
  for (Pin& pin : project->pins) {
    if (pin.image_id == image_id && pin.vertex == vertex) {
      pin.uv_px = uv_px;
      return pin.id;
    }
  }
  Pin pin;
  pin.id = project->NewId();
  pin.image_id = image_id;
  pin.vertex = vertex;
  pin.uv_px = uv_px;
  project->pins.push_back(pin);
  return pin.id;
}

bool ApplyToolClick(AppState* state, const ElementRef& picked, double t) {
  const bool shift = ImGui::GetCurrentContext() != nullptr && ImGui::GetIO().KeyShift;
  return ApplyToolClick(state, picked, t, shift);
}

bool ApplyToolClick(AppState* state, const ElementRef& picked, double t, bool extend) {
  switch (state->tool) {
    case Tool::kSelect:
      if (extend) {
        ToggleSelected(&state->selection, picked);  // nothing picked: the selection stays
        return true;
      }
      if (picked.Empty()) return false;
      state->selection = Selection::Of(picked);
      return true;
    case Tool::kPin:
      if (picked.Empty()) return false;
      state->selection = Selection::Of(picked);
      return true;
    case Tool::kLinePin:
      if (picked.kind != ElementKind::kEdge) return false;
      state->selection = Selection::Of(picked);
      return true;
    case Tool::kSplitEdge:
      if (picked.kind != ElementKind::kEdge) return false;
      SplitEdgeEdit(state, picked.primitive_id, picked.element, t);
      return true;
    case Tool::kDeleteVertex:
      if (picked.kind != ElementKind::kVertex) return false;
      DeleteVertexEdit(state, picked.primitive_id, picked.element);
      return true;
    case Tool::kDeleteEdge:
      if (picked.kind != ElementKind::kEdge) return false;
      DeleteEdgeEdit(state, picked.primitive_id, picked.element);
      return true;
    case Tool::kConnectVertices: {
      if (picked.kind != ElementKind::kVertex) return false;
      const ElementRef from = state->selection.connect_from;
      if (from.Empty() || from.primitive_id != picked.primitive_id || from == picked) {
        state->selection = Selection::Of(picked);
        state->selection.connect_from = from == picked ? ElementRef() : picked;
        return true;
      }
      if (!ConnectVerticesEdit(state, picked.primitive_id, from.element, picked.element)) {
        state->selection = Selection::Of(picked);  // start again from the second vertex
        state->selection.connect_from = picked;
      }
      return true;
    }
    case Tool::kPushPull:
      // Picks a face (the tools panel then offers its distance and Extrude).
      if (picked.kind != ElementKind::kFace) return false;
      state->selection = Selection::Of(picked);
      return true;
    case Tool::kMeasure: {
      // The first vertex, then the second (the tools panel then asks for their distance); a
      // third click starts a new pair.
      if (picked.kind != ElementKind::kVertex) return false;
      const Selection& s = state->selection;
      const bool one_vertex = s.element.kind == ElementKind::kVertex && s.extra.empty();
      if (one_vertex && s.element != picked) {
        state->selection.extra = {picked};
      } else {
        state->selection = Selection::Of(picked);
      }
      return true;
    }
    default: return false;
  }
}

bool ResolvePrimitiveToken(const Project& project, const std::string& token, Id* id, std::string* error) {
  const auto number = [](const std::string& text, unsigned long long* value) {
    if (text.empty() || !std::isdigit(static_cast<unsigned char>(text[0]))) return false;
    char* end = nullptr;
    errno = 0;
    *value = std::strtoull(text.c_str(), &end, 10);
    return *end == '\0' && errno == 0;
  };
  unsigned long long value = 0;
  if (token == "last") {
    if (project.primitives.empty()) {
      *error = "no primitive yet ('last')";
      return false;
    }
    *id = project.primitives.back().id;
    return true;
  }
  if (token.size() > 1 && token[0] == '@' && number(token.substr(1), &value)) {
    if (value < 1 || value > project.primitives.size()) {
      *error = "no primitive " + token + " (the project has " + std::to_string(project.primitives.size()) + ")";
      return false;
    }
    *id = project.primitives[value - 1].id;
    return true;
  }
  if (number(token, &value)) {
    *id = static_cast<Id>(value);
    if (project.FindPrimitive(*id) == nullptr) {
      *error = "no primitive " + token;
      return false;
    }
    return true;
  }
  *error = "'" + token + "' is no primitive: expected its id, @N or last";
  return false;
}

bool RunSelectAddCommand(AppState* state, const std::string& arg, std::string* error) {
  std::istringstream in(arg);
  std::string kind, primitive, extra;
  unsigned long long element = 0;
  ElementRef ref;
  const Project& project = state->document.project();
  if (in >> kind >> primitive >> element && !(in >> extra)) {
    ref.kind = kind == "vertex" ? ElementKind::kVertex
               : kind == "edge" ? ElementKind::kEdge
               : kind == "face" ? ElementKind::kFace
                                : ElementKind::kNone;
    ref.element = static_cast<std::uint32_t>(element);
  }
  if (ref.kind == ElementKind::kNone) {
    *error = "select-add: expected 'vertex|edge|face PRIMITIVE ELEMENT_ID' (PRIMITIVE: an id, @N or last)";
    return false;
  }
  std::string why;
  if (!ResolvePrimitiveToken(project, primitive, &ref.primitive_id, &why)) {
    *error = "select-add: " + why;
    return false;
  }
  if (!ElementExists(project, ref)) {
    *error = "select-add: no " + DescribeElement(project, ref);
    return false;
  }
  if (!AddSelected(&state->selection, ref)) {
    *error = "select-add: " + DescribeElement(project, ref) + " is selected already";
    return false;
  }
  return true;
}

bool RunLinePinCommand(AppState* state, const std::string& arg, std::string* error) {
  std::istringstream in(arg);
  long index = -1;
  double x1, y1, x2, y2;
  std::string extra;
  if (!(in >> index >> x1 >> y1 >> x2 >> y2) || (in >> extra)) {
    *error = "line-pin: expected 'IMAGE_INDEX X1 Y1 X2 Y2' (image pixels) with an edge selected";
    return false;
  }
  const auto& images = state->document.project().images;
  if (index < 0 || index >= static_cast<long>(images.size())) {
    *error = "line-pin: image index " + std::to_string(index) + " is not in 0.." +
             std::to_string(static_cast<long>(images.size()) - 1);
    return false;
  }
  const bool done = LinePinEdit(state, state->selection.element, images[index].id, {x1, y1}, {x2, y2});
  if (!done) *error = state->log.empty() ? "line-pin: refused" : state->log.back().text;
  return done;
}

bool RunLinePinMoveCommand(AppState* state, const std::string& arg, std::string* error) {
  std::istringstream in(arg);
  long image_index = -1, pin_index = -1;
  std::string end_name, extra;
  double x, y;
  const char* usage = "line-pin-move: expected 'IMAGE_INDEX PIN_INDEX END X Y' (END 0|a or 1|b, image pixels)";
  if (!(in >> image_index >> pin_index >> end_name >> x >> y) || (in >> extra)) {
    *error = usage;
    return false;
  }
  const int end = end_name == "0" || end_name == "a" ? 0 : end_name == "1" || end_name == "b" ? 1 : -1;
  if (end < 0) {
    *error = usage;
    return false;
  }
  const Project& project = state->document.project();
  if (image_index < 0 || image_index >= static_cast<long>(project.images.size())) {
    *error = "line-pin-move: image index " + std::to_string(image_index) + " is not in 0.." +
             std::to_string(static_cast<long>(project.images.size()) - 1);
    return false;
  }
  const std::vector<Id> pins = LinePinsOfImage(project, project.images[image_index].id);
  if (pin_index < 0 || pin_index >= static_cast<long>(pins.size())) {
    *error = "line-pin-move: the image has " + std::to_string(pins.size()) + " line pins, no index " +
             std::to_string(pin_index);
    return false;
  }
  const bool done = MoveLinePinEndEdit(state, pins[pin_index], end, {x, y});
  if (!done) *error = state->log.empty() ? "line-pin-move: refused" : state->log.back().text;
  return done;
}

}  // namespace facet::app
