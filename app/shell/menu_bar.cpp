#include "app/shell/menu_bar.h"

#include <cstdio>
#include <filesystem>
#include <string>

#include <imgui.h>

#include "app/panels/side_panels.h"
#include "app/panels/widgets.h"
#include "app/state/model_edits.h"

namespace facet::app {
namespace {

std::string StemOf(const std::string& path) {
  if (path.empty()) return "model";
  return std::filesystem::path(path).replace_extension().string();
}

}  // namespace

float DrawMenuBar(AppState* state, ShellState* shell) {
  float height = 0;
  if (!ImGui::BeginMainMenuBar()) return height;
  height = ImGui::GetWindowSize().y;
  shell->menu_bar_rect = {0, 0, ImGui::GetWindowSize().x, height};
  auto open_dialog = [&](Dialog d, std::string path) {
    shell->dialog = d;
    shell->dialog_just_opened = true;
    shell->dialog_path = std::move(path);
    shell->dialog_error.clear();
  };
  if (ImGui::BeginMenu("File")) {
    if (ImGui::MenuItem("New", "Ctrl+N")) {
      if (state->document.dirty()) {
        open_dialog(Dialog::kConfirmNew, "");
      } else {
        std::string error;
        RunAppCommand(state, shell, "new", {}, &error);
      }
    }
    if (ImGui::MenuItem("Open...", "Ctrl+O")) open_dialog(Dialog::kOpen, state->project_path);
    if (ImGui::MenuItem("Add photo...")) open_dialog(Dialog::kAddPhoto, "");
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("A new image: draw line families on it, or pin model vertices in it");
    ImGui::Separator();
    if (ImGui::MenuItem("Save", "Ctrl+S")) {
      if (state->project_path.empty()) {
        open_dialog(Dialog::kSaveAs, "untitled.facet");
      } else {
        SaveProjectAs(state, "");
      }
    }
    if (ImGui::MenuItem("Save As...", "Ctrl+Shift+S")) {
      open_dialog(Dialog::kSaveAs, state->project_path.empty() ? "untitled.facet" : state->project_path);
    }
    ImGui::Separator();
    const bool has_mesh = !state->mesh.indices.empty();
    if (ImGui::MenuItem("Export glTF...", nullptr, false, has_mesh)) {
      open_dialog(Dialog::kExport, StemOf(state->project_path) + ".glb");
    }
    if (ImGui::MenuItem("Export OBJ...", nullptr, false, has_mesh)) {
      open_dialog(Dialog::kExport, StemOf(state->project_path) + ".obj");
    }
    ImGui::Separator();
    if (ImGui::MenuItem("Quit", "Ctrl+Q")) RequestQuit(state, shell);
    ImGui::EndMenu();
  }
  if (ImGui::BeginMenu("Edit")) {
    const auto& undo = state->document.undo_stack();
    const auto& redo = state->document.redo_stack();
    const std::string undo_label = undo.empty() ? "Undo" : "Undo " + undo.back().label;
    const std::string redo_label = redo.empty() ? "Redo" : "Redo " + redo.back().label;
    if (ImGui::MenuItem(undo_label.c_str(), "Ctrl+Z", false, !undo.empty())) Undo(state);
    if (ImGui::MenuItem(redo_label.c_str(), "Ctrl+Shift+Z", false, !redo.empty())) Redo(state);
    ImGui::Separator();
    if (ImGui::BeginMenu("Add primitive")) {
      for (PrimitiveKind kind : kPrimitiveKinds) {
        if (ImGui::MenuItem(PrimitiveKindName(kind), kind == state->add_kind ? "B" : nullptr)) {
          AddPrimitiveEdit(state, kind, kNoId);
          state->add_kind = kind;
        }
      }
      ImGui::EndMenu();
    }
    const Primitive* base = state->document.project().FindPrimitive(state->selection.primitive_id);
    for (PrimitiveKind kind : {PrimitiveKind::kWedge, PrimitiveKind::kPyramid}) {
      const std::string label = std::string("Add ") + PrimitiveKindName(kind) + " on top" +
                                (base ? " of '" + base->name + "'" : std::string());
      if (ImGui::MenuItem(label.c_str(), nullptr, false, AttachBaseFor(*state, kind) != nullptr)) {
        AddPrimitiveEdit(state, kind, base->id);
      }
    }
    ImGui::Separator();
    if (ImGui::MenuItem("Solve")) SolveNow(state);
    ImGui::EndMenu();
  }
  if (ImGui::BeginMenu("View")) {
    for (int i = 0; i < kNumPanels; ++i) {
      PanelPlacement& p = shell->layout.panels[i];
      if (ImGui::MenuItem(PanelTitle(static_cast<PanelId>(i)), nullptr, &p.visible)) shell->layout_changed = true;
    }
    ImGui::Separator();
    if (ImGui::MenuItem("Dock all panels")) {
      for (PanelPlacement& p : shell->layout.panels) p.floating = false;
      shell->layout_changed = true;
    }
    if (ImGui::MenuItem("Reset layout")) {
      shell->layout = DefaultLayout();
      shell->layout_changed = true;
    }
    ImGui::EndMenu();
  }
  if (ImGui::BeginMenu("Help")) {
    if (ImGui::MenuItem("About Facet")) open_dialog(Dialog::kAbout, "");
    ImGui::EndMenu();
  }
  // Right-aligned status: tool and solve quality.
  const SceneSolveSummary& s = state->last_update.solve;
  const JointSolveSummary& joint = state->last_update.joint;
  const Project& project = state->document.project();
  char status[160];
  if (s.IsUsable() || joint.IsUsable()) {
    // The joint solve, when it ran, is the final word (it also fits free vertices).
    const double rms_px = joint.IsUsable() ? joint.reprojection_rms_px : s.reprojection_rms_px;
    std::snprintf(status, sizeof(status), "%s   |   RMS %.2f px   |   %zu primitives, %zu pins", ToolName(state->tool),
                  rms_px, project.primitives.size(), project.pins.size());
  } else {
    std::snprintf(status, sizeof(status), "%s   |   %zu primitives, %zu pins", ToolName(state->tool),
                  project.primitives.size(), project.pins.size());
  }
  const float w = ImGui::CalcTextSize(status).x;
  // The last refusal or failure, for a few seconds, left of the status.
  constexpr double kErrorShownS = 6.0;
  if (!state->log.empty() && state->log.back().level == LogLevel::kError &&
      state->time_s - state->log.back().time_s < kErrorShownS) {
    const std::string& text = state->log.back().text;
    const float error_w = ImGui::CalcTextSize(text.c_str()).x;
    const float right = ImGui::GetWindowWidth() - w - ImGui::GetStyle().ItemSpacing.x * 6;
    if (error_w < right - ImGui::GetCursorPosX()) {
      ImGui::SameLine(right - error_w);
      ImGui::TextColored(kErrorText, "%s", text.c_str());
    }
  }
  ImGui::SameLine(ImGui::GetWindowWidth() - w - ImGui::GetStyle().ItemSpacing.x * 2);
  ImGui::TextColored(kDimText, "%s", status);
  ImGui::EndMainMenuBar();
  return height;
}

}  // namespace facet::app
