#include "app/model_edits.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <sstream>

#include "core/mesh_extrude.h"
#include "core/mesh_operators.h"

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

int NumShapeParams(PrimitiveKind kind) {
  switch (kind) {
    case PrimitiveKind::kPrism:
    case PrimitiveKind::kCylinder:
    case PrimitiveKind::kPlane: return 2;
    default: return 3;
  }
}

const char* ShapeParamName(PrimitiveKind kind, int index) {
  switch (kind) {
    case PrimitiveKind::kPrism:
    case PrimitiveKind::kCylinder: return index == 0 ? "Radius" : "Height";
    case PrimitiveKind::kPyramid:
    case PrimitiveKind::kWedge: return index == 0 ? "Size x" : index == 1 ? "Size y" : "Height";
    default: return index == 0 ? "Size x" : index == 1 ? "Size y" : "Size z";
  }
}

bool CanAttachOnTop(PrimitiveKind kind) {
  return kind == PrimitiveKind::kWedge || kind == PrimitiveKind::kPyramid || kind == PrimitiveKind::kPlane ||
         kind == PrimitiveKind::kBox;
}

const Primitive* AttachBaseFor(const AppState& state, PrimitiveKind kind) {
  const Primitive* base = state.document.project().FindPrimitive(state.selection.primitive_id);
  if (base == nullptr || base->shape.kind != PrimitiveKind::kBox || !CanAttachOnTop(kind)) return nullptr;
  return base;
}

bool AddPrimitiveEdit(AppState* state, PrimitiveKind kind, Id base_id) {
  Project edited = state->document.project();
  PrimitiveShape shape = DefaultShape(kind);
  const bool first = edited.primitives.empty();
  if (!first && base_id == kNoId) {
    // Beside everything there is, so that a new primitive does not hide inside another.
    double max_x = -std::numeric_limits<double>::infinity();
    for (const Primitive& p : edited.primitives) {
      for (VertexId v = 0; v < p.mesh.VertexIdEnd(); ++v) {
        if (p.mesh.IsVertex(v)) max_x = std::max(max_x, p.mesh.vertex(v).position.x());
      }
    }
    const Primitive& last = edited.primitives.back();
    shape.translation = Eigen::Vector3d(max_x + 0.25, last.shape.translation.y(), last.shape.translation.z());
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
    PrimitiveShape attached = primitive->shape;
    if (!AttachOnTop(base->shape, &attached, &message)) return Refuse(state, label + " on top", message);
    primitive->attached_to = base_id;
    label += " on top";
    RefreshPrimitive(&edited, primitive);
  }
  state->selection = Selection();
  state->selection.primitive_id = id;
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
    return std::any_of(c.vertices.begin(), c.vertices.end(), [&](const VertexRef& v) { return v.primitive_id == primitive_id; });
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

// Adds `c` (a fresh id) unless an equal constraint (kind, vertices, value, axis) exists.
bool AddConstraint(AppState* state, Constraint c, const std::string& label) {
  Project edited = state->document.project();
  for (const Constraint& old : edited.constraints) {
    if (old.kind == c.kind && old.vertices == c.vertices && old.value == c.value && old.axis == c.axis) {
      return Refuse(state, label, "the same constraint exists already");
    }
  }
  c.id = edited.NewId();
  edited.constraints.push_back(c);
  CommitEdit(state, label, std::move(edited));
  state->Log(LogLevel::kInfo, label + ": constraint " + std::to_string(c.id) + " added");
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
  const bool pending = state->constraint_first_kind == kind && ElementExists(state->document.project(),
                                                                              state->constraint_first_edge);
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
    done = ConstrainLengthEdit(state, e, v);
  } else if (kind == "parallel" || kind == "perpendicular" || kind == "equal-length") {
    const ConstraintKind k = kind == "parallel"        ? ConstraintKind::kParallel
                             : kind == "perpendicular" ? ConstraintKind::kPerpendicular
                                                       : ConstraintKind::kEqualLength;
    done = ConstraintPairStep(state, k);
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
             "' (along-x, along-y, along-z, length VALUE, parallel, perpendicular, equal-length, fix, remove ID)";
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
  switch (state->tool) {
    case Tool::kSelect:
    case Tool::kPin:
      if (picked.Empty()) return false;
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
    default: return false;
  }
}

bool RunSelectAddCommand(AppState* /*state*/, const std::string& arg, std::string* error) {
  *error = "select-add: not available yet ('" + arg + "')";
  return false;
}

bool RunLinePinCommand(AppState* /*state*/, const std::string& arg, std::string* error) {
  *error = "line-pin: not available yet ('" + arg + "')";
  return false;
}

}  // namespace facet::app
