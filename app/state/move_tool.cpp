#include "app/state/move_tool.h"

#include <cmath>
#include <sstream>

#include "app/state/reference_edits.h"
#include "core/solve/vertex_move.h"

namespace facet::app {
namespace {

constexpr double kStartDragPx = 2.0;      // the mouse must leave the press point before a drag begins
constexpr double kReferenceSnapPx = 8.0;  // a dragged vertex snaps to a reference vertex this near (as the image panel snaps)
constexpr double kParallelCosine = 1e-3;  // a ray this close to parallel to the drag plane or axis is ignored
constexpr const char* kToolHelp =
    "Move: drag a vertex (in the plane facing you) or an edge/face (the primitive, horizontally); "
    "hold Shift to move along z; Esc cancels";

bool RayPlane(const PickRay& ray, const Eigen::Vector3d& point, const Eigen::Vector3d& normal, Eigen::Vector3d* hit) {
  const double denominator = ray.direction.dot(normal);
  if (std::abs(denominator) < kParallelCosine * normal.norm()) return false;
  const double t = (point - ray.origin).dot(normal) / denominator;
  if (!(t > 0.0)) return false;
  *hit = ray.origin + t * ray.direction;
  return true;
}

// The point of the line point + s * axis (axis unit) closest to the ray.
bool ClosestOnAxis(const PickRay& ray, const Eigen::Vector3d& point, const Eigen::Vector3d& axis,
                   Eigen::Vector3d* out) {
  const Eigen::Vector3d w0 = point - ray.origin;
  const double b = axis.dot(ray.direction);
  const double denominator = 1.0 - b * b;
  if (denominator < kParallelCosine) return false;
  const double s = (b * ray.direction.dot(w0) - axis.dot(w0)) / denominator;
  *out = point + s * axis;
  return true;
}

// The world point the press hit on an edge or face (the vertex itself for a vertex).
Eigen::Vector3d PressPoint(const Project& project, const ElementPick& pick, const PickRay& ray) {
  const Primitive& primitive = *project.FindPrimitive(pick.element.primitive_id);
  const PolyMesh& mesh = primitive.mesh;
  switch (pick.element.kind) {
    case ElementKind::kVertex: return mesh.vertex(pick.element.element).position;
    case ElementKind::kEdge: {
      const HalfedgeId h = PolyMesh::EdgeHalfedge(pick.element.element, 0);
      const Eigen::Vector3d a = mesh.vertex(mesh.Origin(h)).position, b = mesh.vertex(mesh.Dest(h)).position;
      const double t = ClosestEdgeParameter(a, b, ray.origin, ray.direction);
      return a + t * (b - a);
    }
    default: {
      const std::vector<VertexId> corners = FaceVertices(mesh, pick.element.element);
      Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
      for (VertexId v : corners) centroid += mesh.vertex(v).position;
      centroid /= static_cast<double>(std::max<size_t>(1, corners.size()));
      Eigen::Vector3d hit;
      if (RayPlane(ray, centroid, FaceNormal(mesh, pick.element.element), &hit)) return hit;
      return centroid;
    }
  }
}

// The drag's current world point, or false when the ray misses the plane or axis.
bool DragPoint(const MoveDrag& drag, const PickRay& ray, bool along_z, Eigen::Vector3d* point) {
  if (along_z) return ClosestOnAxis(ray, drag.anchor, Eigen::Vector3d::UnitZ(), point);
  return RayPlane(ray, drag.anchor, drag.plane_normal, point);
}

void Reset(MoveDrag* drag) {
  const std::string hint = drag->hint;
  *drag = MoveDrag();
  drag->hint = hint;
}

}  // namespace

PickFilter MoveToolPickFilter() { return {true, true, true}; }

bool MoveToolOwnsMouse(const MoveDrag& drag) { return drag.tracking; }

std::string MoveToolHint(const MoveDrag& drag) { return drag.hint.empty() ? std::string(kToolHelp) : drag.hint; }

void MoveToolFrame(AppState* state, MoveDrag* drag_state, const MoveToolInput& input) {
  MoveDrag& drag = *drag_state;
  // An undo during the drag cancels it (app_state.cpp): let go as well.
  if (drag.started && !state->drag_start) Reset(&drag);

  if (input.pressed && !drag.tracking && !state->drag_start && !input.pressed_on.element.Empty() &&
      ElementExists(state->document.project(), input.pressed_on.element)) {
    const Project& project = state->document.project();
    const ElementRef& element = input.pressed_on.element;
    state->selection = Selection::Of(element);
    drag = MoveDrag();
    drag.tracking = true;
    drag.vertex = element.kind == ElementKind::kVertex;
    drag.primitive_id = element.primitive_id;
    drag.ref = {element.primitive_id, drag.vertex ? element.element : kNoElement};
    drag.anchor = PressPoint(project, input.pressed_on, input.ray);
    // A vertex moves in the plane facing the camera, a primitive over the ground.
    drag.plane_normal = drag.vertex ? Eigen::Vector3d(-input.ray.direction) : Eigen::Vector3d::UnitZ();
    drag.press_px = input.ray.mouse_px;
    drag.hint = kToolHelp;
    return;
  }
  if (!drag.tracking) return;

  if (drag.cancelled) {
    if (input.released) Reset(&drag);
    return;
  }
  if (input.cancel) {
    if (drag.started) CancelDrag(state);
    drag.hint = "Move cancelled";
    drag.cancelled = true;
    if (input.released) Reset(&drag);
    return;
  }

  if (!drag.started && (input.ray.mouse_px - drag.press_px).norm() >= kStartDragPx) {
    BeginDrag(state, drag.vertex ? "Move vertex" : "Move primitive");
    drag.started = state->drag_start.has_value();
  }
  if (drag.started) {
    Eigen::Vector3d point;
    // A dragged vertex lands exactly on a reference vertex near the mouse (not along z, not with Alt).
    bool snapped = false;
    if (drag.vertex && !input.shift && !input.no_snap)
      snapped = NearestReferenceVertex(*state, input.ray, kReferenceSnapPx, &point);
    if (snapped || DragPoint(drag, input.ray, input.shift, &point)) {
      const Project& start = *state->drag_start;
      Project moved;
      bool ok = false;
      std::string message;
      if (drag.vertex) {
        const VertexMoveSummary summary = MoveVertex(start, drag.ref, point, VertexMoveOptions{}, &moved);
        ok = summary.IsUsable();
        message = summary.message + (snapped ? " (snapped to a reference vertex)" : "");
      } else {
        const PrimitiveMoveSummary summary = MovePrimitive(start, drag.primitive_id, point - drag.anchor, &moved);
        ok = summary.IsUsable();
        message = summary.message;
      }
      drag.hint = message;
      if (ok) {
        // The preview shows the geometry where the user puts it: no solve until release.
        *state->document.MutableProjectForPreview() = std::move(moved);
        drag.accepted = true;
        drag.accepted_message = message;
      }
    }
  }

  if (input.released) {
    if (drag.started && drag.accepted) {
      const std::string refusal = drag.hint != drag.accepted_message ? drag.hint : std::string();
      EndDrag(state);  // the full update, warm-started from the moved state, one history entry
      state->Log(LogLevel::kInfo, drag.accepted_message);
      drag.hint = drag.accepted_message + " (re-solved)";
      if (!refusal.empty()) drag.hint += "; last position refused: " + refusal;
    } else if (drag.started) {
      CancelDrag(state);
      state->Log(LogLevel::kWarning, (drag.vertex ? "Move vertex: " : "Move primitive: ") + drag.hint);
    }
    Reset(&drag);
  }
}

bool RunMoveCommand(AppState* state, const std::string& arg, std::string* error) {
  std::istringstream in(arg);
  std::string what;
  Eigen::Vector3d value;
  in >> what >> value.x() >> value.y() >> value.z();
  std::string rest;
  if (in.fail() || (in >> rest) || (what != "vertex" && what != "primitive")) {
    *error = "move-selection: expected 'vertex X Y Z' or 'primitive DX DY DZ', got '" + arg + "'";
    return false;
  }
  const Project& project = state->document.project();
  const Selection& selection = state->selection;
  Project moved;
  if (what == "vertex") {
    if (selection.element.kind != ElementKind::kVertex || !ElementExists(project, selection.element)) {
      *error = "move-selection vertex: select a vertex first";
      return false;
    }
    const VertexMoveSummary summary = MoveVertex(project, {selection.element.primitive_id, selection.element.element},
                                                 value, VertexMoveOptions{}, &moved);
    if (!summary.IsUsable()) {
      *error = "move-selection vertex: " + summary.message;
      return false;
    }
    state->Log(summary.reached ? LogLevel::kInfo : LogLevel::kWarning, summary.message);
    CommitEdit(state, "Move vertex", std::move(moved));
    return true;
  }
  const Id id = selection.primitive_id != kNoId ? selection.primitive_id : selection.element.primitive_id;
  if (project.FindPrimitive(id) == nullptr) {
    *error = "move-selection primitive: select a primitive first";
    return false;
  }
  const PrimitiveMoveSummary summary = MovePrimitive(project, id, value, &moved);
  if (!summary.IsUsable()) {
    *error = "move-selection primitive: " + summary.message;
    return false;
  }
  state->Log(LogLevel::kInfo, summary.message);
  CommitEdit(state, "Move primitive", std::move(moved));
  return true;
}

}  // namespace facet::app
