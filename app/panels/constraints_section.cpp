#include "app/panels/constraints_section.h"

#include <cstdio>

#include <imgui.h>

#include "app/panels/widgets.h"
#include "app/state/model_edits.h"

namespace facet::app {

namespace {

// The constraint builder for a selected edge: one-edge kinds at once, two-edge kinds in two
// clicks (the first stores the edge, the second, with another edge selected, adds). With a
// multi-selection the two-edge kinds are in the selection's builder instead.
void DrawEdgeConstraintBuilder(AppState* state, const ElementRef& element, bool pair_buttons) {
  ImGui::Spacing();
  ImGui::TextColored(kDimText, "Constrain edge");
  for (const Axis axis : {Axis::kX, Axis::kY, Axis::kZ}) {
    const std::string label = std::string("Along ") + AxisName(axis);
    if (axis != Axis::kX) ImGui::SameLine();
    if (ImGui::Button(label.c_str())) ConstrainAlongAxisEdit(state, element, axis);
    RecordItem(state, std::string("constraint.along_") + AxisName(axis));
  }
  ImGui::SetNextItemWidth(ImGui::GetFontSize() * 6.0f);
  ImGui::InputDouble("##constraint_length", &state->constraint_length, 0.0, 0.0, "%.4g");
  RecordItem(state, "constraint.length_value");
  ImGui::SameLine();
  const std::string length_label = "Known length (" + state->document.project().units + ")";
  if (ImGui::Button(length_label.c_str())) ConstrainLengthEdit(state, element, state->constraint_length);
  RecordItem(state, "constraint.length");
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("The edge's length in project units: sets the scale");
  const std::pair<ConstraintKind, const char*> pairs[] = {{ConstraintKind::kParallel, "parallel"},
                                                          {ConstraintKind::kPerpendicular, "perpendicular"},
                                                          {ConstraintKind::kEqualLength, "equal_length"}};
  bool first_button = true;
  for (const auto& [kind, key] : pairs) {
    if (!pair_buttons) break;
    if (!first_button) ImGui::SameLine();
    first_button = false;
    const std::string label = ConstraintEditLabel(kind);
    if (ImGui::Button(label.c_str())) ConstraintPairStep(state, kind);
    RecordItem(state, std::string("constraint.") + key);
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Click with the first edge selected, then with the second");
  }
  const Project& project = state->document.project();
  if (state->constraint_first_kind && ElementExists(project, state->constraint_first_edge)) {
    ImGui::TextColored(kWarningText, "%s: first edge: %s", ConstraintEditLabel(*state->constraint_first_kind).c_str(),
                       DescribeElement(project, state->constraint_first_edge).c_str());
    ImGui::SameLine();
    if (ImGui::SmallButton("Cancel##constraint_pair")) {
      state->constraint_first_kind.reset();
      state->constraint_first_edge = ElementRef();
    }
  }
}

// The builder on a multi-selection (element + extra): coplanar / collinear on the selected
// vertices (edges and faces give theirs), the two-edge kinds between two selected edges, and
// coplanar / parallel faces for two faces. Each button is one undoable edit.
void DrawSelectionBuilder(AppState* state) {
  const std::vector<ElementRef> selected = SelectedElements(state->selection);
  if (selected.size() < 2) return;
  const Project& project = state->document.project();
  int counts[4] = {0, 0, 0, 0};
  for (const ElementRef& e : selected) ++counts[static_cast<int>(e.kind)];
  const int vertices = counts[static_cast<int>(ElementKind::kVertex)];
  const int edges = counts[static_cast<int>(ElementKind::kEdge)];
  const int faces = counts[static_cast<int>(ElementKind::kFace)];
  const size_t distinct = VerticesOfElements(project, selected).size();
  ImGui::Spacing();
  ImGui::PushStyleColor(ImGuiCol_Text, kDimText);
  ImGui::TextWrapped("Selection: %d vertices, %d edges, %d faces (%zu distinct vertices)", vertices, edges, faces,
                     distinct);
  ImGui::PopStyleColor();
  for (size_t i = 0; i < selected.size(); ++i) {
    ImGui::PushID(static_cast<int>(i));
    if (ImGui::SmallButton("x")) {
      ToggleSelected(&state->selection, selected[i]);
      ImGui::PopID();
      return;  // the list changed
    }
    RecordItem(state, "selection.remove." + std::to_string(i));
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Remove from the selection");
    ImGui::SameLine();
    ImGui::TextUnformatted(DescribeElement(project, selected[i]).c_str());
    ImGui::PopID();
  }
  ImGui::PushStyleColor(ImGuiCol_Text, kDimText);
  ImGui::TextWrapped("Shift+click adds or removes; Esc or a click on nothing clears");
  ImGui::PopStyleColor();
  const bool two_faces = faces == 2 && selected.size() == 2;
  const bool two_edges = edges == 2 && selected.size() == 2;
  bool same_line = false;
  auto next = [&]() {
    if (same_line) ImGui::SameLine();
    same_line = true;
  };
  if (distinct >= 4) {
    next();
    const std::string label = two_faces ? "Coplanar faces" : "Coplanar (" + std::to_string(distinct) + ")";
    if (ImGui::Button(label.c_str())) {
      ConstrainVertexSetEdit(state, ConstraintKind::kCoplanar, selected, two_faces ? "Coplanar faces" : "");
    }
    RecordItem(state, "constraint.coplanar");
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip("Keep the selected vertices (and those of selected edges and faces) on one plane");
  }
  if (faces == 0 && distinct >= 3) {
    next();
    const std::string label = "Collinear (" + std::to_string(distinct) + ")";
    if (ImGui::Button(label.c_str())) ConstrainVertexSetEdit(state, ConstraintKind::kCollinear, selected);
    RecordItem(state, "constraint.collinear");
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Keep the selected vertices (and edge ends) on one line");
  }
  if (two_faces) {
    next();
    if (ImGui::Button("Parallel faces")) ConstrainParallelFacesEdit(state, selected[0], selected[1]);
    RecordItem(state, "constraint.parallel_faces");
    if (ImGui::IsItemHovered()) {
      ImGui::SetTooltip("Two parallel-edge constraints between the faces' most nearly parallel edges");
    }
  }
  if (two_edges) {
    const std::pair<ConstraintKind, const char*> pairs[] = {{ConstraintKind::kParallel, "parallel"},
                                                            {ConstraintKind::kPerpendicular, "perpendicular"},
                                                            {ConstraintKind::kEqualLength, "equal_length"}};
    same_line = false;
    for (const auto& [kind, key] : pairs) {
      next();
      if (ImGui::Button(ConstraintEditLabel(kind).c_str()))
        ConstrainEdgePairEdit(state, kind, selected[0], selected[1]);
      RecordItem(state, std::string("constraint.") + key);
    }
  }
}

}  // namespace

void DrawConstraintsSection(AppState* state) {
  const Project& project = state->document.project();
  const std::string title = "Constraints (" + std::to_string(project.constraints.size()) + ")###Constraints";
  if (!ImGui::CollapsingHeader(title.c_str(), ImGuiTreeNodeFlags_DefaultOpen)) return;
  if (project.constraints.empty()) {
    ImGui::TextColored(kDimText, "None: select an edge or vertex to add one.");
    return;
  }
  const std::vector<Constraint> constraints = project.constraints;  // the remove edit replaces them
  const std::vector<ConstraintDiagnostic>& diagnostics = state->last_update.joint.constraints;
  Id remove_id = kNoId;
  for (size_t i = 0; i < constraints.size(); ++i) {
    const Constraint& c = constraints[i];
    ImGui::PushID(static_cast<int>(c.id));
    std::string text = ConstraintKindName(c.kind);
    if (c.kind == ConstraintKind::kAlongAxis) text += std::string(" ") + AxisName(c.axis);
    if (c.kind == ConstraintKind::kDistance) {
      char v[48];
      std::snprintf(v, sizeof(v), " %.4g %s", c.value, project.units.c_str());
      text += v;
    }
    if (c.kind == ConstraintKind::kEdgeOnImageLine) {
      int index = 0;
      for (const Image& image : project.images) {
        if (image.id == c.image_id) break;
        ++index;
      }
      text += " in image " + std::to_string(index + 1);
    }
    text += ":";
    // Appended in two steps: GCC 12 reports a false -Wrestrict on " " + std::string.
    for (const VertexRef& v : c.vertices) {
      text += ' ';
      text += DescribeVertex(project, v);
    }
    const ConstraintDiagnostic* d = nullptr;
    for (const ConstraintDiagnostic& diag : diagnostics) {
      if (diag.constraint_id == c.id) d = &diag;
    }
    // Removed after the loop: the edit replaces the project and the diagnostics that `c` and
    // `d` point into.
    if (ImGui::SmallButton("x")) remove_id = c.id;
    RecordItem(state, "constraint.remove." + std::to_string(i));
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Remove constraint");
    ImGui::SameLine();
    ImGui::TextWrapped("%s", text.c_str());
    if (d != nullptr) {
      ImGui::SameLine();
      ImGui::TextColored(d->satisfied ? kGoodText : kErrorText, "%.3g %s", d->residual, d->unit.c_str());
    } else {
      ImGui::SameLine();
      ImGui::TextColored(kDimText, "(not solved)");
    }
    ImGui::PopID();
  }
  if (remove_id != kNoId) RemoveConstraintEdit(state, remove_id);
}

void DrawElementSection(AppState* state, const Primitive& primitive, const ElementRef& element) {
  const PolyMesh& mesh = primitive.mesh;
  const std::string title = std::string(ElementKindName(element.kind)) + " " + std::to_string(element.element);
  if (!ImGui::CollapsingHeader("Element", ImGuiTreeNodeFlags_DefaultOpen)) return;
  ImGui::TextUnformatted(title.c_str());
  if (element.kind == ElementKind::kVertex) {
    const MeshVertex& v = mesh.vertex(element.element);
    LabelValue("Position", "%.3f, %.3f, %.3f", v.position.x(), v.position.y(), v.position.z());
    LabelValue("Defined", "%s", v.local.on_edge ? "on an edge (split)" : "primitive corner");
    if (v.local.free)
      LabelValue("Offset", "%.3f, %.3f, %.3f", v.local.offset.x(), v.local.offset.y(), v.local.offset.z());
    bool free = v.local.free;
    char label[64];
    std::snprintf(label, sizeof(label), "Free vertex (%s)", kFreeVertexShortcut);
    if (ImGui::Checkbox(label, &free)) ToggleFreeVertexEdit(state, element.primitive_id, element.element);
    RecordItem(state, "element.free");
    if (ImGui::IsItemHovered()) {
      ImGui::SetTooltip("Let the solve move this vertex off its definition (e.g. a ridge above a face) (%s)",
                        kFreeVertexShortcut);
    }
    if (ImGui::Button("Fix at origin")) FixVertexEdit(state, element);
    RecordItem(state, "constraint.fix");
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("A fixed-point constraint at the vertex's current position");
    int pins = 0;
    for (const Pin& pin : state->document.project().pins)
      pins += pin.vertex == VertexRef{primitive.id, element.element};
    LabelValue("Pins", "%d", pins);
  } else if (element.kind == ElementKind::kEdge) {
    const VertexId a = mesh.Origin(2 * element.element), b = mesh.Dest(2 * element.element);
    LabelValue("Vertices", "%u - %u", a, b);
    LabelValue("Length", "%.3f", (mesh.vertex(b).position - mesh.vertex(a).position).norm());
    DrawEdgeConstraintBuilder(state, element, state->selection.extra.empty());
  } else if (element.kind == ElementKind::kFace) {
    LabelValue("Vertices", "%d", FaceDegree(mesh, element.element));
    const Eigen::Vector3d n = FaceNormal(mesh, element.element);
    LabelValue("Normal", "%.2f, %.2f, %.2f", n.x(), n.y(), n.z());
    char label[64];
    std::snprintf(label, sizeof(label), "Keep planar (%s)", kPlanarFaceShortcut);
    if (ImGui::Button(label)) TogglePlanarFaceEdit(state, element.primitive_id, element.element);
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("A coplanarity constraint on the face's vertices (toggle)");
  }
  DrawSelectionBuilder(state);
}

}  // namespace facet::app
