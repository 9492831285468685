#include "app/shell/menu_bar.h"

#include <cstdio>
#include <filesystem>
#include <string>

#include <imgui.h>

#include "core/io/colmap_run.h"

#include "app/panels/side_panels.h"
#include "app/panels/widgets.h"
#include "app/shell/export_cameras.h"
#include "app/shell/file_actions.h"
#include "app/state/colmap_cameras.h"
#include "app/state/file_browser_model.h"
#include "app/state/model_edits.h"

namespace facet::app {
namespace {

std::string StemOf(const std::string& path) {
  if (path.empty()) return "model";
  return std::filesystem::path(path).stem().string();
}

// File > Open recent: the recent projects, newest first, with their folders; a vanished one
// is shown but cannot be chosen.
void DrawOpenRecentMenu(AppState* state, ShellState* shell) {
  constexpr size_t kMaxShown = 10;
  const std::vector<std::string> projects = RecentFilesWith(shell->recent_files, {".facet"});
  const bool open = ImGui::BeginMenu("Open recent", !projects.empty());
  RecordItem(state, "menu.open_recent");
  if (!open) return;
  for (size_t i = 0; i < projects.size() && i < kMaxShown; ++i) {
    const std::filesystem::path path(projects[i]);
    std::error_code ec;
    const bool exists = std::filesystem::exists(path, ec);
    ImGui::PushID(static_cast<int>(i));
    if (ImGui::MenuItem(path.filename().string().c_str(), path.parent_path().string().c_str(), false, exists)) {
      OpenProjectAsking(state, shell, projects[i]);
    }
    RecordItem(state, "menu.recent/" + projects[i]);
    if (!exists && ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled)) ImGui::SetTooltip("No longer there");
    ImGui::PopID();
  }
  ImGui::Separator();
  if (ImGui::MenuItem("Clear recent files")) ClearRecentFiles(state, shell);
  ImGui::EndMenu();
}

// View > Teach (issue 15): each overlay of app/state/teach.h on or off; view settings, not
// part of the project.
void DrawTeachMenu(AppState* state) {
  const bool open = ImGui::BeginMenu("Teach");
  RecordItem(state, "menu.teach");
  if (!open) return;
  TeachView& teach = state->teach;
  ImGui::MenuItem("Vanishing points", nullptr, &teach.vanishing_points);
  RecordItem(state, "menu.teach.vanishing");
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip(
        "Each family's vanishing point with its uncertainty, the vanishing triangle, the principal point "
        "as its orthocentre, the construction of the focal length, the horizon; rays in 3D");
  ImGui::MenuItem("Epipolar geometry", nullptr, &teach.epipolar);
  RecordItem(state, "menu.teach.epipolar");
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("The epipolar lines and epipoles of a selected pin, or of the pointer, in the other photos");
  ImGui::MenuItem("Numbers (K, R, t, F)", nullptr, &teach.numbers);
  RecordItem(state, "menu.teach.numbers");
  ImGui::MenuItem("Modelling state in History", nullptr, &teach.modelling_state);
  RecordItem(state, "menu.teach.state");
  ImGui::MenuItem("Solver steps", nullptr, &teach.solver_steps);
  RecordItem(state, "menu.teach.steps");
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("The joint solve one Levenberg-Marquardt iteration per Step, from a perturbed start: residual "
                      "vectors on the photo, cost, damping and step norm, constraint violations");
  ImGui::EndMenu();
}

}  // namespace

float DrawMenuBar(AppState* state, ShellState* shell) {
  float height = 0;
  if (!ImGui::BeginMainMenuBar()) return height;
  height = ImGui::GetWindowSize().y;
  shell->menu_bar_rect = {0, 0, ImGui::GetWindowSize().x, height};
  // Recorded before BeginMenu: once the menu is open, the last item is inside its popup.
  const ImVec2 file_pos = ImGui::GetCursorScreenPos();
  state->item_rects["menu.file"] = {file_pos.x, file_pos.y,
                                    ImGui::CalcTextSize("File").x + ImGui::GetStyle().ItemSpacing.x * 2, height};
  if (ImGui::BeginMenu("File")) {
    if (ImGui::MenuItem("New", "Ctrl+N")) {
      if (state->document.dirty()) {
        OpenDialog(shell, Dialog::kConfirmNew);
      } else {
        std::string error;
        RunAppCommand(state, shell, "new", {}, &error);
      }
    }
    if (ImGui::MenuItem("Open...", "Ctrl+O")) OpenFileBrowser(state, shell, Dialog::kOpen);
    RecordItem(state, "menu.open");
    DrawOpenRecentMenu(state, shell);
    if (ImGui::MenuItem("Add photo...")) OpenFileBrowser(state, shell, Dialog::kAddPhoto);
    RecordItem(state, "menu.add_photo");
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip(
          "A new image: draw line families on it, or pin model vertices in it (or drop photos onto the window)");
    const bool has_active_image = state->document.project().FindImage(state->active_image_id) != nullptr;
    if (ImGui::MenuItem("Relink photo...", nullptr, false, has_active_image))
      OpenFileBrowser(state, shell, Dialog::kRelinkPhoto);
    RecordItem(state, "menu.relink_photo");
    if (ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled))
      ImGui::SetTooltip("Point the active image at its photo file after the project or the photo moved; its camera, "
                        "pins and lines stay");
    if (ImGui::MenuItem("Add reference mesh...")) OpenFileBrowser(state, shell, Dialog::kAddReference);
    RecordItem(state, "menu.add_reference");
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip("A mesh made elsewhere (.obj, .glb, .gltf) to model against: drawn see-through in both panels, a "
                        "snap target for the Move tool, not part of the model (or drop it onto the window)");
    // COLMAP on every photo, in the background (app/state/colmap_cameras.h); its window shows
    // the progress. Disabled without the program, with the install hint as its tooltip.
    const bool colmap = ColmapAvailable(state);
    const size_t num_photos = state->document.project().images.size();
    if (ImGui::MenuItem("Cameras from all photos...", nullptr, false,
                        colmap && num_photos >= 2 && !ColmapInFlight(*state)))
      state->colmap.window_open = true;
    RecordItem(state, "menu.colmap_cameras");
    if (ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled)) {
      if (!colmap) {
        ImGui::SetTooltip("%s (FACET_COLMAP names the program)", ColmapInstallHint().c_str());
      } else if (ColmapInFlight(*state)) {
        ImGui::SetTooltip("COLMAP is running (its window shows how far)");
      } else if (num_photos < 2) {
        ImGui::SetTooltip("Add two photos or more first");
      } else {
        ImGui::SetTooltip("A camera for every photo from COLMAP (structure from motion), in the background, "
                          "brought into the project's frame as one undoable edit");
      }
    }
    ImGui::Separator();
    if (ImGui::MenuItem("Save", "Ctrl+S")) {
      if (SaveNeedsName(*state)) {
        OpenFileBrowser(state, shell, Dialog::kSaveAs);
      } else {
        SaveProjectAs(state, "");
      }
    }
    if (ImGui::MenuItem("Save As...", "Ctrl+Shift+S")) OpenFileBrowser(state, shell, Dialog::kSaveAs);
    RecordItem(state, "menu.save_as");
    ImGui::Separator();
    const bool has_mesh = !state->mesh.indices.empty();
    if (ImGui::MenuItem("Export glTF...", nullptr, false, has_mesh)) {
      OpenFileBrowser(state, shell, Dialog::kExport, StemOf(state->project_path) + ".glb");
    }
    RecordItem(state, "menu.export_gltf");
    if (ImGui::MenuItem("Export OBJ...", nullptr, false, has_mesh)) {
      OpenFileBrowser(state, shell, Dialog::kExport, StemOf(state->project_path) + ".obj");
    }
    // The cameras alone, for the tools that start from calibrated photos (dense MVS, NeRF,
    // Gaussian splatting) where structure from motion fails.
    const std::string no_cameras = WhyNoCamerasToExport(*state);
    if (ImGui::MenuItem("Export cameras (COLMAP)...", nullptr, false, no_cameras.empty()))
      OpenFileBrowser(state, shell, Dialog::kExportColmap, "cameras.txt");
    RecordItem(state, "menu.export_colmap");
    if (ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled))
      ImGui::SetTooltip("%s", no_cameras.empty() ? "The calibrated cameras as a COLMAP text model: cameras.txt, "
                                                   "images.txt and points3D.txt (the vertices, their pins as tracks)"
                                                 : no_cameras.c_str());
    if (ImGui::MenuItem("Export cameras (transforms.json)...", nullptr, false, no_cameras.empty()))
      OpenFileBrowser(state, shell, Dialog::kExportTransforms, "transforms.json");
    RecordItem(state, "menu.export_transforms");
    if (ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled))
      ImGui::SetTooltip("%s", no_cameras.empty()
                                  ? "The calibrated cameras for nerfstudio or instant-ngp (OpenGL camera-to-world "
                                    "matrices, intrinsics, OpenCV distortion)"
                                  : no_cameras.c_str());
    if (ImGui::MenuItem("Export view...")) {
      OpenFileBrowser(state, shell, Dialog::kExportView, StemOf(state->project_path) + "-view.png");
    }
    RecordItem(state, "menu.export_view");
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip("The image panel or the 3D panel with its overlays as a PNG of a chosen size (for slides)");
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
    ImGui::Separator();
    ImGui::MenuItem("Texture sources", nullptr, &state->texture.show_sources);
    RecordItem(state, "menu.texture_sources");
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip("Tint each face in the 3D panel by the photo that gave most of its texture, with a legend");
    DrawTeachMenu(state);
    ImGui::EndMenu();
  }
  if (ImGui::BeginMenu("Help")) {
    if (ImGui::MenuItem("About Facet")) OpenDialog(shell, Dialog::kAbout);
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
