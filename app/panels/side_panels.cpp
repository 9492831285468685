#include "app/panels/side_panels.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>

#include <imgui.h>
#include <imgui_stdlib.h>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>  // key codes only: io.KeysDown is indexed by GLFW key codes in both modes

#include "app/panels/camera_sections.h"
#include "app/panels/constraints_section.h"
#include "app/panels/teach_overlay.h"
#include "app/panels/texture_sections.h"
#include "app/panels/widgets.h"
#include "app/state/model_edits.h"
#include "core/solve/scene_solve.h"

namespace facet::app {
namespace {

constexpr int kFreeVertexKey = GLFW_KEY_T;
constexpr int kPlanarFaceKey = GLFW_KEY_K;

struct ToolButton {
  Tool tool;
  const char* label;
  const char* shortcut;
  int key;
  const char* hint;
};
constexpr ToolButton kToolButtons[] = {
    {Tool::kSelect, "Select", "V", GLFW_KEY_V,
     "Pick vertices, edges and faces of the model; drag line ends and pins; drag from a vertex to pin it."},
    {Tool::kLineX, "Line X", "X", GLFW_KEY_X, "Drag in the image to draw a line parallel to the world x axis."},
    {Tool::kLineY, "Line Y", "Y", GLFW_KEY_Y, "Drag in the image to draw a line parallel to the world y axis."},
    {Tool::kLineZ, "Line Z", "Z", GLFW_KEY_Z, "Drag in the image to draw a vertical line (world z)."},
    {Tool::kPin, "Pin", "P", GLFW_KEY_P, "Pick a model vertex, then click where it is in the photo (V_proj)."},
    {Tool::kAddPrimitive, "Add primitive", "B", GLFW_KEY_B,
     "Adds a primitive of the kind chosen below (K_create); pin its vertices to place it."},
    {Tool::kSplitEdge, "Split edge", "E", GLFW_KEY_E,
     "E_split: click on an edge to add a vertex there (snaps to the middle)."},
    {Tool::kDeleteVertex, "Delete vertex", "D", GLFW_KEY_D,
     "V_delete: click on a vertex made by a split to remove it."},
    {Tool::kConnectVertices, "Connect vertices", "C", GLFW_KEY_C,
     "V_connect: click two vertices of one face to split the face by a new edge."},
    {Tool::kDeleteEdge, "Delete edge", "R", GLFW_KEY_R, "E_delete: click on an edge between two faces to merge them."},
    {Tool::kPushPull, "Push/pull", "U", GLFW_KEY_U,
     "Push/pull: select a face, type a distance (negative pushes in) and press Enter or Extrude."},
    {Tool::kMove, "Move", "M", GLFW_KEY_M,
     "V_op: in the 3D panel, drag a vertex (in the plane facing you) or an edge/face to move the whole "
     "primitive over the ground; Shift: along z; Esc cancels. The solve starts from where you leave it."},
    {Tool::kLinePin, "Line pin", "L", GLFW_KEY_L,
     "Select an edge, then drag in the image along the line it lies on (edge on image line)."},
    {Tool::kMeasure, "Measure", "N", GLFW_KEY_N,
     "Click two vertices, type the length between them and press Enter: a known length (it sets the scale)."},
};

// Takes a copy: the edits below replace the project that a reference would point into.
void DrawPrimitiveSection(AppState* state, const Primitive primitive) {
  const std::string kind = PrimitiveKindName(primitive.shape.kind);
  if (!ImGui::CollapsingHeader("Primitive", ImGuiTreeNodeFlags_DefaultOpen)) return;
  const Id id = primitive.id;
  ImGui::PushID("primitive");
  std::string name = primitive.name;
  ImGui::SetNextItemWidth(-FLT_MIN);
  const bool renamed = ImGui::InputTextWithHint("##name", "name", &name);
  RecordItem(state, "primitive.name");
  TrackEdit(state, "Rename " + kind, renamed, [&](Project* p) { p->FindPrimitive(id)->name = name; });
  LabelValue("Kind", "%s", kind.c_str());
  if (primitive.shape.segments > 0) {
    ImGui::SameLine();
    ImGui::TextColored(kDimText, "(%d sides)", primitive.shape.segments);
  }
  LabelValue("Mesh", "%d vertices, %d edges, %d faces", primitive.mesh.NumVertices(), primitive.mesh.NumEdges(),
             primitive.mesh.NumFaces());
  const Primitive* base = state->document.project().FindPrimitive(primitive.attached_to);
  if (primitive.attached_to != kNoId) LabelValue("On top of", "%s", base ? base->name.c_str() : "(missing)");
  if (primitive.shape.kind == PrimitiveKind::kWedge) {
    ImGui::TextColored(kDimText, "Ridge along");
    ImGui::SameLine();
    if (ImGui::RadioButton("x##ridge", !primitive.shape.ridge_along_y) && primitive.shape.ridge_along_y) {
      SetWedgeRidgeEdit(state, id, false);
    }
    RecordItem(state, "primitive.ridge_x");
    ImGui::SameLine();
    if (ImGui::RadioButton("y##ridge", primitive.shape.ridge_along_y) && !primitive.shape.ridge_along_y) {
      SetWedgeRidgeEdit(state, id, true);
    }
    RecordItem(state, "primitive.ridge_y");
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("The roof's ridge along the primitive's x or y side");
  }

  // Parameters by kind, each with its name and its lock (a kept dimension is a known length).
  const int num_params = NumShapeParams(primitive.shape.kind);
  const int first_free = primitive.attached_to != kNoId ? 2 : 0;  // the base gives the footprint
  for (int i = 0; i < num_params; ++i) {
    ImGui::PushID(i);
    double value = primitive.shape.params[i];
    bool locked = primitive.param_locked[i];
    if (ImGui::Checkbox("Keep##lock", &locked)) {
      Project edited = state->document.project();
      edited.FindPrimitive(id)->param_locked[i] = locked;
      CommitEdit(state, std::string(locked ? "Keep " : "Free ") + ShapeParamName(primitive.shape.kind, i),
                 std::move(edited));
    }
    RecordItem(state, "primitive.keep." + std::to_string(i));
    if (ImGui::IsItemHovered()) {
      ImGui::SetTooltip("Keep %s while solving: a kept dimension is a known length (the scale)",
                        ShapeParamName(primitive.shape.kind, i));
    }
    ImGui::SameLine();
    ImGui::BeginDisabled(i < first_free);
    // The field leaves room for its name, which says which dimension the Keep box keeps.
    const char* param_name = ShapeParamName(primitive.shape.kind, i);
    const float name_w = ImGui::CalcTextSize(param_name).x + ImGui::GetStyle().ItemInnerSpacing.x;
    ImGui::SetNextItemWidth(std::max(ImGui::GetFontSize() * 3.0f, ImGui::GetContentRegionAvail().x - name_w));
    const bool resized = DragDoubles(param_name, &value, 1, 0.01f, "%.3f");
    ImGui::EndDisabled();
    RecordItem(state, "primitive.param." + std::to_string(i));
    TrackEdit(state, "Resize " + kind, resized, [&](Project* p) {
      p->FindPrimitive(id)->shape.params[i] = std::max(1e-3, value);
      RefreshAllPrimitives(p);
    });
    ImGui::PopID();
  }
  ImGui::BeginDisabled(primitive.attached_to != kNoId);
  double t[3] = {primitive.shape.translation.x(), primitive.shape.translation.y(), primitive.shape.translation.z()};
  const bool moved = DragDoubles("Position", t, 3, 0.01f, "%.3f");
  RecordItem(state, "primitive.position");
  TrackEdit(state, "Move " + kind, moved, [&](Project* p) {
    p->FindPrimitive(id)->shape.translation = Eigen::Vector3d(t[0], t[1], t[2]);
    RefreshAllPrimitives(p);
  });
  const Eigen::Vector3d& rotation = primitive.shape.rotation;
  double r[3] = {rotation.x() * kRadToDeg, rotation.y() * kRadToDeg, rotation.z() * kRadToDeg};
  const bool rotated = DragDoublesRecorded(state, "Rotation", r, 3, 0.2f, "%.1f deg", "primitive.rotation");
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Angle-axis vector in degrees (world_from_primitive)");
  TrackEdit(state, "Rotate " + kind, rotated, [&](Project* p) {
    p->FindPrimitive(id)->shape.rotation = Eigen::Vector3d(r[0], r[1], r[2]) / kRadToDeg;
    RefreshAllPrimitives(p);
  });
  ImGui::EndDisabled();

  ImGui::TextColored(kDimText, "Keep while solving");
  Primitive locks = primitive;
  bool lock_changed = ImGui::Checkbox("Rotation", &locks.rotation_locked);
  RecordItem(state, "primitive.keep_rotation");
  ImGui::SameLine();
  lock_changed |= ImGui::Checkbox("Position", &locks.translation_locked);
  RecordItem(state, "primitive.keep_position");
  if (lock_changed) {
    Project edited = state->document.project();
    *edited.FindPrimitive(id) = locks;
    CommitEdit(state, "Primitive locks", std::move(edited));
  }
  if (ImGui::Button("Delete primitive")) DeletePrimitiveEdit(state, id);
  ImGui::PopID();
}

void DrawPinSection(AppState* state, const Pin pin) {
  if (!ImGui::CollapsingHeader("Pin", ImGuiTreeNodeFlags_DefaultOpen)) return;
  const Project& project = state->document.project();
  const Id pin_id = pin.id;
  const Primitive* primitive = project.FindPrimitive(pin.vertex.primitive_id);
  LabelValue("Primitive", "%s", primitive ? primitive->name.c_str() : "(missing)");
  LabelValue("Vertex", "%u", pin.vertex.vertex);
  ImGui::PushID("pin");
  double uv[2] = {pin.uv_px.x(), pin.uv_px.y()};
  const bool moved = DragDoubles("Pixel", uv, 2, 0.25f, "%.2f");
  RecordItem(state, "pin.uv");
  TrackEdit(state, "Move pin", moved, [&](Project* p) { p->FindPin(pin_id)->uv_px = Eigen::Vector2d(uv[0], uv[1]); });
  ImGui::PopID();
  // The joint solve's figure when it ran (it also fits free vertices), else the geometry solve's.
  const Project& current = state->document.project();
  if (state->last_update.joint.IsUsable()) {
    for (const PinDiagnostic& d : state->last_update.joint.pins) {
      if (d.pin_id == pin_id && std::isfinite(d.error_px)) LabelValue("Residual", "%.3f px", d.error_px);
    }
    return;
  }
  const auto& residuals = state->last_update.solve.pin_residuals_px;
  for (size_t i = 0; i < current.pins.size() && i < residuals.size(); ++i) {
    if (current.pins[i].id == pin_id && std::isfinite(residuals[i])) LabelValue("Residual", "%.3f px", residuals[i]);
  }
}

void DrawSegmentSection(AppState* state, const Segment segment) {
  if (!ImGui::CollapsingHeader("Segment", ImGuiTreeNodeFlags_DefaultOpen)) return;
  const Project& project = state->document.project();
  const Id seg_id = segment.id;
  ImGui::PushID("segment");
  int axis = static_cast<int>(segment.axis);
  const char* axes[] = {"x", "y", "z"};
  if (ImGui::Combo("Family", &axis, axes, 3)) {
    Project edited = project;
    edited.FindSegment(seg_id)->axis = static_cast<Axis>(axis);
    CommitEdit(state, "Change line family", std::move(edited));
  }
  double a[2] = {segment.a_px.x(), segment.a_px.y()};
  const bool moved_a = DragDoubles("Start", a, 2, 0.25f, "%.2f");
  TrackEdit(state, "Move line end", moved_a,
            [&](Project* p) { p->FindSegment(seg_id)->a_px = Eigen::Vector2d(a[0], a[1]); });
  double b[2] = {segment.b_px.x(), segment.b_px.y()};
  const bool moved_b = DragDoubles("End", b, 2, 0.25f, "%.2f");
  TrackEdit(state, "Move line end", moved_b,
            [&](Project* p) { p->FindSegment(seg_id)->b_px = Eigen::Vector2d(b[0], b[1]); });
  ImGui::PopID();
  LabelValue("Length", "%.1f px", (segment.b_px - segment.a_px).norm());
  // Calibration residuals follow the order of the image's segments in the project.
  const auto cal = state->last_update.calibration.find(segment.image_id);
  if (cal != state->last_update.calibration.end()) {
    size_t index = 0;
    for (const Segment& s : project.segments) {
      if (s.image_id != segment.image_id) continue;
      if (s.id == seg_id) {
        if (index < cal->second.segment_residuals_px.size()) {
          LabelValue("Residual", "%.3f px", cal->second.segment_residuals_px[index]);
        }
        break;
      }
      ++index;
    }
  }
}

// The kind of primitive the Add primitive tool adds, and "on top of the selected box".
void DrawAddPrimitiveOptions(AppState* state, float width) {
  ImGui::Indent(8.0f);
  ImGui::SetNextItemWidth(width - 8.0f);
  if (ImGui::BeginCombo("##add_kind", PrimitiveKindName(state->add_kind))) {
    for (PrimitiveKind kind : kPrimitiveKinds) {
      if (ImGui::Selectable(PrimitiveKindName(kind), kind == state->add_kind)) state->add_kind = kind;
      RecordItem(state, std::string("tool.add_kind/") + PrimitiveKindName(kind));
    }
    ImGui::EndCombo();
  }
  RecordItem(state, "tool.add_kind");
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Kind of primitive that Add primitive (B) adds");
  const Primitive* base = state->add_kind != PrimitiveKind::kBox ? AttachBaseFor(*state, state->add_kind) : nullptr;
  if (base != nullptr) {
    const std::string label = "on top of '" + base->name + "'";
    ImGui::Checkbox(label.c_str(), &state->add_on_top);
    RecordItem(state, "tool.add_on_top");
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("AttachOnTop: its footprint and pose follow the box");
  }
  ImGui::Unindent(8.0f);
}

// Push/pull's distance field and Extrude button, for the selected face. A newly selected face
// (or the tool just chosen) gets the default distance and the keyboard focus, so that typing
// a value and Enter extrudes, as in SketchUp.
void DrawPushPullOptions(AppState* state, float width) {
  ImGui::Indent(8.0f);
  const ElementRef face = state->selection.element;
  const Project& project = state->document.project();
  const Primitive* primitive = face.kind == ElementKind::kFace && ElementExists(project, face)
                                   ? project.FindPrimitive(face.primitive_id)
                                   : nullptr;
  if (primitive == nullptr) {
    state->push_pull_face = {};
    ImGui::TextColored(kDimText, "Select a face to push or pull.");
    ImGui::Unindent(8.0f);
    return;
  }
  const bool fresh = state->push_pull_face != face;
  if (fresh) {
    state->push_pull_face = face;
    state->push_pull_distance = DefaultPushPullDistance(*primitive);
    ImGui::SetKeyboardFocusHere();
  }
  ImGui::SetNextItemWidth(width - 8.0f);
  const bool entered = ImGui::InputDouble("##push_pull_distance", &state->push_pull_distance, 0.0, 0.0, "%.4g",
                                          ImGuiInputTextFlags_EnterReturnsTrue);
  RecordItem(state, "tool.push_pull_distance");
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Distance along the face's normal, project units (negative: in)");
  const bool clicked = ImGui::Button("Extrude##push_pull", ImVec2(width - 8.0f, 0.0f));
  RecordItem(state, "tool.push_pull_extrude");
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("Extrude %s (Enter in the field)", DescribeElement(project, face).c_str());
  if (entered || clicked) {
    const Id primitive_id = face.primitive_id;
    PushPullFaceEdit(state, primitive_id, face.element, state->push_pull_distance);
  }
  ImGui::Unindent(8.0f);
}

// Measure's length field for the two picked vertices, with their current distance. A new
// pair gets that distance and the keyboard focus, so that typing the length and Enter adds
// the known length.
void DrawMeasureOptions(AppState* state, float width) {
  ImGui::Indent(8.0f);
  const Project& project = state->document.project();
  ElementRef a, b;
  if (!MeasuredPair(state->selection, &a, &b) || !ElementExists(project, a) || !ElementExists(project, b)) {
    state->measure_pair = {};
    ImGui::TextColored(kDimText, state->selection.element.kind == ElementKind::kVertex
                                     ? "Click the second vertex."
                                     : "Click the first vertex.");
    ImGui::Unindent(8.0f);
    return;
  }
  const double now = (VertexInWorld(project, {b.primitive_id, b.element}) -
                      VertexInWorld(project, {a.primitive_id, a.element}))
                         .norm();
  const bool fresh = state->measure_pair != std::array<ElementRef, 2>{a, b};
  if (fresh) {
    state->measure_pair = {a, b};
    state->measure_length = now;
    ImGui::SetKeyboardFocusHere();
  }
  ImGui::SetNextItemWidth(width - 8.0f);
  const bool entered = ImGui::InputDouble("##measure_length", &state->measure_length, 0.0, 0.0, "%.4g",
                                          ImGuiInputTextFlags_EnterReturnsTrue);
  RecordItem(state, "tool.measure_length");
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Known length between the two vertices, project units");
  ImGui::TextColored(kDimText, "now %.4g", now);
  const bool clicked = ImGui::Button("Set length##measure", ImVec2(width - 8.0f, 0.0f));
  RecordItem(state, "tool.measure_set");
  if (ImGui::IsItemHovered()) {
    ImGui::SetTooltip("Known length between %s and %s (Enter in the field)", DescribeElement(project, a).c_str(),
                      DescribeElement(project, b).c_str());
  }
  if (entered || clicked) ConstrainDistanceEdit(state, a, b, state->measure_length);
  ImGui::Unindent(8.0f);
}

}  // namespace

void HandleToolShortcuts(AppState* state) {
  const ImGuiIO& io = ImGui::GetIO();
  if (io.WantTextInput || io.KeyCtrl || io.KeyAlt || io.KeySuper) return;
  for (const ToolButton& b : kToolButtons) {
    if (!ImGui::IsKeyPressed(b.key, false)) continue;
    if (b.tool == Tool::kAddPrimitive) {
      AddPrimitiveAction(state);
    } else {
      SetTool(state, b.tool);
    }
  }
  const ElementRef& element = state->selection.element;
  if (ImGui::IsKeyPressed(kFreeVertexKey, false) && element.kind == ElementKind::kVertex) {
    ToggleFreeVertexEdit(state, element.primitive_id, element.element);
  }
  if (ImGui::IsKeyPressed(kPlanarFaceKey, false) && element.kind == ElementKind::kFace) {
    TogglePlanarFaceEdit(state, element.primitive_id, element.element);
  }
}

void SetTool(AppState* state, Tool tool) {
  if (tool != state->tool) state->selection.connect_from = {};
  if (tool != state->tool) state->push_pull_face = {};  // the distance field gets the focus again
  if (tool != state->tool) state->measure_pair = {};
  state->tool = tool;
}

void AddPrimitiveAction(AppState* state) {
  const Primitive* base = state->add_on_top ? AttachBaseFor(*state, state->add_kind) : nullptr;
  // "On top" is for roofs: a new box always goes beside the others.
  if (base != nullptr && state->add_kind == PrimitiveKind::kBox) base = nullptr;
  // Aimed at the pointer when it is over the active image (the B key), else at its centre.
  const Image* image = state->ActiveImage();
  const bool aimed = image != nullptr && state->pointer_image_id == image->id;
  if (AddPrimitiveEdit(state, state->add_kind, base ? base->id : kNoId,
                       aimed ? state->pointer_in_image_px : std::nullopt)) {
    state->tool = Tool::kPin;
  }
}

void SolveNow(AppState* state) { CommitEdit(state, "Solve", state->document.project()); }

void DrawToolsPanel(AppState* state) {
  const float width = ImGui::GetContentRegionAvail().x;
  const ImVec2 button_size(width, ImGui::GetFrameHeight() * 1.25f);
  for (const ToolButton& b : kToolButtons) {
    const bool active = state->tool == b.tool;
    if (active) ImGui::PushStyleColor(ImGuiCol_Button, ImGui::GetStyleColorVec4(ImGuiCol_ButtonActive));
    char label[64];
    std::snprintf(label, sizeof(label), "%s##tool", b.label);
    if (ImGui::Button(label, button_size)) {
      if (b.tool == Tool::kAddPrimitive) {
        AddPrimitiveAction(state);
      } else {
        SetTool(state, b.tool);
      }
    }
    if (active) ImGui::PopStyleColor();
    RecordItem(state, std::string("tool.") + b.label);
    // The shortcut letter at the right end of the button.
    const ImVec2 max = ImGui::GetItemRectMax();
    const ImVec2 min = ImGui::GetItemRectMin();
    const ImVec2 text = ImGui::CalcTextSize(b.shortcut);
    if (ImGui::CalcTextSize(b.label).x + 2 * text.x + 24 < max.x - min.x) {
      ImGui::GetWindowDrawList()->AddText(ImVec2(max.x - text.x - 8, (min.y + max.y - text.y) / 2),
                                          ImGui::GetColorU32(kDimText), b.shortcut);
    }
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s (%s)", b.hint, b.shortcut);
    if (b.tool == Tool::kAddPrimitive) DrawAddPrimitiveOptions(state, width);
    if (b.tool == Tool::kPushPull && active) DrawPushPullOptions(state, width);
    if (b.tool == Tool::kMeasure && active) DrawMeasureOptions(state, width);
  }
  ImGui::Spacing();
  ImGui::Separator();
  ImGui::Spacing();
  const ElementRef& element = state->selection.element;
  ImGui::BeginDisabled(element.kind != ElementKind::kVertex);
  char free_label[64];
  std::snprintf(free_label, sizeof(free_label), "Free vertex##action");
  if (ImGui::Button(free_label, button_size)) ToggleFreeVertexEdit(state, element.primitive_id, element.element);
  ImGui::EndDisabled();
  RecordItem(state, "action.free_vertex");
  if (ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled)) {
    ImGui::SetTooltip("Toggle: the solve may move the selected vertex off its definition (%s)", kFreeVertexShortcut);
  }
  ImGui::BeginDisabled(element.kind != ElementKind::kFace);
  if (ImGui::Button("Keep face planar##action", button_size)) {
    TogglePlanarFaceEdit(state, element.primitive_id, element.element);
  }
  ImGui::EndDisabled();
  RecordItem(state, "action.planar_face");
  if (ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled)) {
    ImGui::SetTooltip("Toggle a coplanarity constraint on the selected face's vertices (%s)", kPlanarFaceShortcut);
  }
  ImGui::Spacing();
  ImGui::Separator();
  ImGui::Spacing();
  if (ImGui::Button("Solve", button_size)) SolveNow(state);
  RecordItem(state, "tool.Solve");
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Re-run calibration and the geometry solve");
  ImGui::Spacing();
  for (const ToolButton& b : kToolButtons) {
    if (b.tool == state->tool) {
      ImGui::PushStyleColor(ImGuiCol_Text, kDimText);
      ImGui::TextWrapped("%s", b.hint);
      ImGui::PopStyleColor();
    }
  }
}

void DrawPropertiesPanel(AppState* state, PropertiesPanelState* panel) {
  // What is selected comes first, at the top, where a click lands: the image and solve
  // sections above it would push its fields down, and move them whenever a solve's figures
  // change length.
  const Project& project = state->document.project();
  if (const Primitive* primitive = project.FindPrimitive(state->selection.primitive_id)) {
    const Primitive copy = *primitive;
    DrawPrimitiveSection(state, copy);
    const ElementRef element = state->selection.element;
    if (!element.Empty() && ElementExists(state->document.project(), element) && element.primitive_id == copy.id) {
      if (const Primitive* current = state->document.project().FindPrimitive(copy.id)) {
        const Primitive again = *current;
        DrawElementSection(state, again, element);
        if (element.kind == ElementKind::kFace) {
          if (const Primitive* latest = state->document.project().FindPrimitive(copy.id)) {
            if (latest->mesh.IsFace(element.element))
              DrawFaceTextureSection(state, Primitive(*latest), element.element);
          }
        }
      }
    }
  }
  if (const Pin* pin = project.FindPin(state->selection.pin_id)) DrawPinSection(state, *pin);
  if (const Segment* seg = project.FindSegment(state->selection.segment_id)) DrawSegmentSection(state, *seg);
  if (state->selection.Empty()) {
    ImGui::TextColored(kDimText, "Select a primitive, pin or line to edit it.");
    ImGui::Spacing();
  }
  DrawImageSection(state, &panel->exif_feedback);
  DrawSolveSection(state);
  DrawConstraintsSection(state);
}

void DrawHistoryPanel(AppState* state) {
  const auto& undo = state->document.undo_stack();
  const auto& redo = state->document.redo_stack();
  const int n_undo = static_cast<int>(undo.size());
  const int n_redo = static_cast<int>(redo.size());
  // Position k: the state after the first k edits (0 = as opened).
  int target = -1;
  if (state->teach.modelling_state) {  // View > Teach: the same list with the (K, F) counts
    DrawTeachHistory(state, &target);
    for (int i = target; target >= 0 && i < n_undo; ++i) Undo(state);
    for (int i = n_undo; i < target; ++i) Redo(state);
    return;
  }
  auto entry = [&](int position, const std::string& label, bool future) {
    const bool current = position == n_undo;
    if (future) ImGui::PushStyleColor(ImGuiCol_Text, kDimText);
    char text[256];
    std::snprintf(text, sizeof(text), "%3d  %s##h%d", position, label.c_str(), position);
    if (ImGui::Selectable(text, current) && !current) target = position;
    RecordItem(state, "history." + std::to_string(position));
    if (current && ImGui::IsWindowAppearing()) ImGui::SetScrollHereY();
    if (future) ImGui::PopStyleColor();
  };
  entry(0, state->project_path.empty() ? "New project" : "Opened", false);
  for (int i = 0; i < n_undo; ++i) entry(i + 1, undo[i].label, false);
  for (int i = n_redo - 1; i >= 0; --i) entry(n_undo + (n_redo - i), redo[i].label, true);
  if (target >= 0) {
    for (int i = target; i < n_undo; ++i) Undo(state);
    for (int i = n_undo; i < target; ++i) Redo(state);
  }
}

void DrawLogPanel(AppState* state) {
  if (ImGui::SmallButton("Clear")) state->log.clear();
  ImGui::SameLine();
  ImGui::TextColored(kDimText, "%zu messages", state->log.size());
  ImGui::Separator();
  ImGui::BeginChild("##log_lines", ImVec2(0, 0), false, ImGuiWindowFlags_HorizontalScrollbar);
  const bool at_bottom = ImGui::GetScrollY() >= ImGui::GetScrollMaxY() - 1.0f;
  ImGuiListClipper clipper;
  clipper.Begin(static_cast<int>(state->log.size()));
  while (clipper.Step()) {
    for (int i = clipper.DisplayStart; i < clipper.DisplayEnd; ++i) {
      const LogEntry& e = state->log[i];
      ImGui::TextColored(kDimText, "%7.2f", e.time_s);
      ImGui::SameLine();
      switch (e.level) {
        case LogLevel::kInfo: ImGui::TextUnformatted(e.text.c_str()); break;
        case LogLevel::kWarning: ImGui::TextColored(kWarningText, "%s", e.text.c_str()); break;
        case LogLevel::kError: ImGui::TextColored(kErrorText, "%s", e.text.c_str()); break;
      }
    }
  }
  if (at_bottom) ImGui::SetScrollHereY(1.0f);
  ImGui::EndChild();
}

}  // namespace facet::app
