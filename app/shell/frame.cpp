#include "app/shell/frame.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <thread>

#include <imgui.h>
#include <imgui_internal.h>  // the window's title-bar rectangle, for the Dock/Undock button
#include <imgui_stdlib.h>
#include <nlohmann/json.hpp>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>  // key codes only

#include "app/panels/camera_sections.h"
#include "app/panels/colmap_window.h"
#include "app/panels/image_panel.h"
#include "app/panels/side_panels.h"
#include "app/panels/teach_overlay.h"
#include "app/panels/viewport_panel.h"
#include "app/panels/widgets.h"
#include "app/shell/export_cameras.h"
#include "app/shell/export_view.h"
#include "app/shell/file_actions.h"
#include "app/shell/menu_bar.h"
#include "app/state/add_photo.h"
#include "app/state/colmap_cameras.h"
#include "app/state/ghost_pins.h"
#include "app/state/line_proposals.h"
#include "app/state/model_edits.h"
#include "app/state/move_tool.h"
#include "app/state/reference_edits.h"
#include "core/io/export.h"
#include "core/util/file_write.h"

namespace facet::app {
namespace {

constexpr float kWorkAreaMarginPx = 4.0f;
constexpr float kTearOffDistancePx = 14.0f;
const ImVec4 kErrorText(1.00f, 0.42f, 0.40f, 1.0f);

// FNV-1a (64 bit) of raw bytes: the `bake-status` fingerprints that let a test compare the
// app's bake with its own, bit for bit, without shipping the atlas.
std::uint64_t Fnv1a(const void* data, size_t bytes, std::uint64_t hash = 14695981039346656037ull) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < bytes; ++i) hash = (hash ^ p[i]) * 1099511628211ull;
  return hash;
}

template <typename T>
std::string FingerprintHex(const std::vector<T>& values) {
  char text[24];
  std::snprintf(text, sizeof(text), "%016llx",
                static_cast<unsigned long long>(Fnv1a(values.data(), values.size() * sizeof(T))));
  return text;
}

// `bake-status PATH`: the background bake's state and the mesh shown, as JSON.
bool WriteBakeStatus(const AppState& state, const std::string& path, std::string* error) {
  const TexturedMesh& mesh = state.mesh;
  nlohmann::json status = {
      {"in_flight", BakeInFlight(state)},
      {"texture_pending", TexturePending(state)},
      {"input_revision", state.bake_input_revision},
      {"baked_input_revision", state.baked_input_revision},
      {"started", state.bake_stats.started},
      {"collected", state.bake_stats.collected},
      {"dropped", state.bake_stats.dropped},
      {"start_refresh_ms", state.bake_stats.start_refresh_ms},
      {"last_wait_ms", state.bake_stats.last_wait_ms},
      {"bake_ms", state.last_bake.time_ms},
      {"faces_textured", state.last_bake.faces_textured},
      {"triangles", mesh.indices.size() / 3},
      {"atlas_width", mesh.atlas.width},
      {"atlas_height", mesh.atlas.height},
      {"atlas_fnv", FingerprintHex(mesh.atlas.pixels)},
      {"uvs_fnv", FingerprintHex(mesh.uvs)},
      {"positions_fnv", FingerprintHex(mesh.positions)},
  };
  // The 3D panel's overlay texts as the last frame drew them (the status while it bakes).
  nlohmann::json texts = nlohmann::json::object();
  for (const auto& [name, r] : state.item_rects) {
    if (name.rfind("viewport.", 0) == 0) texts[name] = {{"x", r.x}, {"y", r.y}, {"w", r.w}, {"h", r.h}};
  }
  status["viewport_texts"] = std::move(texts);
  const std::string write_error =
      WriteFileAtomically(path, status.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");
  if (!write_error.empty()) {
    *error = "bake-status: " + write_error;
    return false;
  }
  return true;
}

std::string LastLoggedError(const AppState& state) {
  for (auto it = state.log.rbegin(); it != state.log.rend(); ++it) {
    if (it->level == LogLevel::kError) return it->text;
  }
  return "see the log";
}

void HandleGlobalShortcuts(AppState* state, ShellState* shell) {
  const ImGuiIO& io = ImGui::GetIO();
  if (io.WantTextInput || shell->dialog != Dialog::kNone || !io.KeyCtrl) return;
  std::string error;
  if (ImGui::IsKeyPressed(GLFW_KEY_Z, true)) {
    if (io.KeyShift)
      Redo(state);
    else
      Undo(state);
  }
  if (ImGui::IsKeyPressed(GLFW_KEY_Y, true)) Redo(state);
  if (ImGui::IsKeyPressed(GLFW_KEY_S, false)) {
    if (io.KeyShift || SaveNeedsName(*state)) {
      OpenFileBrowser(state, shell, Dialog::kSaveAs);
    } else {
      SaveProjectAs(state, "");
    }
  }
  if (ImGui::IsKeyPressed(GLFW_KEY_O, false)) OpenFileBrowser(state, shell, Dialog::kOpen);
  if (ImGui::IsKeyPressed(GLFW_KEY_N, false)) {
    if (state->document.dirty())
      OpenDialog(shell, Dialog::kConfirmNew);
    else
      NewProject(state);
  }
  if (ImGui::IsKeyPressed(GLFW_KEY_Q, false)) RequestQuit(state, shell);
}

// The bars between tiled panels live in a background window that covers the work area.
void DrawSplitters(ShellState* shell, const TiledLayout& tiled, const Rect& work) {
  ImGui::SetNextWindowPos(ImVec2(work.x, work.y));
  ImGui::SetNextWindowSize(ImVec2(work.w, work.h));
  ImGui::PushStyleVar(ImGuiStyleVar_WindowPadding, ImVec2(0, 0));
  ImGui::PushStyleVar(ImGuiStyleVar_WindowBorderSize, 0.0f);
  const ImGuiWindowFlags flags = ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_NoMove |
                                 ImGuiWindowFlags_NoSavedSettings | ImGuiWindowFlags_NoBringToFrontOnFocus |
                                 ImGuiWindowFlags_NoNavFocus | ImGuiWindowFlags_NoBackground |
                                 ImGuiWindowFlags_NoScrollWithMouse;
  ImGui::Begin("##workspace", nullptr, flags);
  ImGui::PopStyleVar(2);
  // Behind every panel, also those created later: ImGui puts new windows that never come to
  // the front at the bottom of the stack, which would otherwise leave this one above them.
  ImGui::BringWindowToDisplayBack(ImGui::GetCurrentWindow());
  ImDrawList* draw = ImGui::GetWindowDrawList();
  for (size_t i = 0; i < tiled.splitters.size(); ++i) {
    const Splitter& s = tiled.splitters[i];
    ImGui::SetCursorScreenPos(ImVec2(s.bar.x, s.bar.y));
    ImGui::PushID(s.split);
    ImGui::InvisibleButton("##splitter", ImVec2(std::max(1.0f, s.bar.w), std::max(1.0f, s.bar.h)));
    ImGui::PopID();
    const bool hovered = ImGui::IsItemHovered();
    const bool active = ImGui::IsItemActive();
    if (hovered || active)
      ImGui::SetMouseCursor(s.side_by_side ? ImGuiMouseCursor_ResizeEW : ImGuiMouseCursor_ResizeNS);
    if (active) {
      const ImVec2 m = ImGui::GetIO().MousePos;
      shell->layout.split_ratio[s.split] = SplitRatioForMouse(s, m.x, m.y);
      shell->layout_changed = true;
    }
    if (hovered || active) {
      draw->AddRectFilled(ImVec2(s.bar.x + 1, s.bar.y + 1), ImVec2(s.bar.x + s.bar.w - 1, s.bar.y + s.bar.h - 1),
                          ImGui::GetColorU32(active ? ImGuiCol_SeparatorActive : ImGuiCol_SeparatorHovered), 2.0f);
    }
  }
  ImGui::End();
}

void MakeFloating(ShellState* shell, int panel, const Rect& from) {
  PanelPlacement& p = shell->layout.panels[panel];
  p.floating = true;
  const ImGuiViewport* vp = ImGui::GetMainViewport();
  const float w = std::clamp(from.w, 240.0f, std::min(720.0f, vp->Size.x));
  const float h = std::clamp(from.h, 160.0f, std::min(520.0f, vp->Size.y));
  // Fully inside the window, so that the title bar (and its Dock button) stays reachable.
  const float x = std::clamp(from.x + 24, vp->Pos.x, std::max(vp->Pos.x, vp->Pos.x + vp->Size.x - w));
  const float y = std::clamp(from.y + 24, vp->Pos.y, std::max(vp->Pos.y, vp->Pos.y + vp->Size.y - h));
  p.floating_rect = {x, y, w, h};
  shell->floating_to_place = panel;
  shell->layout_changed = true;
}

// A small button in the window's title bar, left of the close button; left out when the
// bar is too narrow to show it beside the title (the title's context menu still works).
bool TitleBarButton(const char* label, const char* window_title, const char* tooltip) {
  ImGuiWindow* window = ImGui::GetCurrentWindow();
  const ImGuiStyle& style = ImGui::GetStyle();
  const ImRect title = window->TitleBarRect();
  const float width = ImGui::CalcTextSize(label, nullptr, true).x + style.FramePadding.x * 2;
  const float x = title.Max.x - style.FramePadding.x - ImGui::GetFontSize() - style.ItemInnerSpacing.x * 2 - width;
  if (x < title.Min.x + style.FramePadding.x * 2 + ImGui::CalcTextSize(window_title).x + 8.0f) return false;
  const ImVec2 cursor = ImGui::GetCursorScreenPos();
  const ImVec2 max_pos = window->DC.CursorMaxPos;
  ImGui::PushClipRect(title.Min, title.Max, false);
  ImGui::SetCursorScreenPos(ImVec2(x, title.Min.y + (title.GetHeight() - ImGui::GetFontSize()) * 0.5f));
  ImGui::PushStyleColor(ImGuiCol_Button, ImVec4(0, 0, 0, 0));
  ImGui::PushStyleColor(ImGuiCol_Text, kDimText);
  const bool pressed = ImGui::SmallButton(label);
  ImGui::PopStyleColor(2);
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", tooltip);
  ImGui::PopClipRect();
  ImGui::SetCursorScreenPos(cursor);
  window->DC.CursorMaxPos = max_pos;
  return pressed;
}

void DrawPanelContents(AppState* state, ShellState* shell, PanelId panel) {
  switch (panel) {
    case PanelId::kTools: DrawToolsPanel(state); break;
    case PanelId::kImage: DrawImagePanel(state, &shell->image_panel); break;
    case PanelId::kViewport: DrawViewportPanel(state, &shell->viewport_panel); break;
    case PanelId::kProperties: DrawPropertiesPanel(state, &shell->properties_panel); break;
    case PanelId::kHistory: DrawHistoryPanel(state); break;
    case PanelId::kLog: DrawLogPanel(state); break;
  }
}

void DrawPanel(AppState* state, ShellState* shell, int index, const TiledLayout& tiled) {
  const PanelId panel = static_cast<PanelId>(index);
  PanelPlacement& placement = shell->layout.panels[index];
  if (!placement.visible) return;
  const bool floating = placement.floating;
  const bool canvas = panel == PanelId::kImage || panel == PanelId::kViewport;
  ImGuiWindowFlags flags = ImGuiWindowFlags_NoCollapse | ImGuiWindowFlags_NoSavedSettings;
  if (canvas) flags |= ImGuiWindowFlags_NoScrollbar | ImGuiWindowFlags_NoScrollWithMouse;
  const ImGuiIO& io = ImGui::GetIO();

  if (floating) {
    Rect& r = placement.floating_rect;
    if (shell->floating_to_place == index) {
      ImGui::SetNextWindowPos(ImVec2(r.x, r.y), ImGuiCond_Always);
      ImGui::SetNextWindowSize(ImVec2(r.w, r.h), ImGuiCond_Always);
      ImGui::SetNextWindowFocus();
    } else {
      ImGui::SetNextWindowPos(ImVec2(r.x, r.y), ImGuiCond_Appearing);
      ImGui::SetNextWindowSize(ImVec2(r.w, r.h), ImGuiCond_Appearing);
    }
    if (shell->tearing_panel == index && io.MouseDown[0]) {
      // Still held after the tear-off: the window follows the cursor like a title-bar move.
      ImGui::SetNextWindowPos(ImVec2(io.MousePos.x - 40, io.MousePos.y - 10), ImGuiCond_Always);
    }
  } else {
    const std::optional<Rect>& r = tiled.docked_rects[index];
    if (!r) return;
    ImGui::SetNextWindowPos(ImVec2(r->x, r->y), ImGuiCond_Always);
    ImGui::SetNextWindowSize(ImVec2(r->w, r->h), ImGuiCond_Always);
    flags |= ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoBringToFrontOnFocus;
  }

  if (canvas) ImGui::PushStyleVar(ImGuiStyleVar_WindowPadding, ImVec2(3, 3));
  bool open = true;
  const bool expanded = ImGui::Begin(PanelTitle(panel), &open, flags);
  if (canvas) ImGui::PopStyleVar();
  if (floating && shell->floating_to_place == index) {
    // A panel created while docked sits at the bottom of ImGui's window stack (docked
    // windows never come to the front); once floating it must be above the tiled panels.
    ImGui::BringWindowToDisplayFront(ImGui::GetCurrentWindow());
  }
  const ImVec2 pos = ImGui::GetWindowPos();
  const ImVec2 size = ImGui::GetWindowSize();
  const Rect window_rect{pos.x, pos.y, size.x, size.y};
  shell->panel_rects[index] = window_rect;
  shell->panel_drawn[index] = expanded;
  const bool placed_now = floating && shell->floating_to_place == index;
  if (placed_now) shell->floating_to_place = -1;
  if (floating && !placed_now) {
    if (window_rect.x != placement.floating_rect.x || window_rect.y != placement.floating_rect.y ||
        window_rect.w != placement.floating_rect.w || window_rect.h != placement.floating_rect.h) {
      shell->layout_changed = true;
    }
    placement.floating_rect = window_rect;
  }

  // Title bar: Dock/Undock button, context menu, and tear-off by dragging a docked title.
  ImGuiWindow* window = ImGui::GetCurrentWindow();
  const ImRect title = window->TitleBarRect();
  bool toggle_dock = TitleBarButton(floating ? "Dock##dock" : "Undock##dock", PanelTitle(panel),
                                    floating ? "Return to its place in the layout" : "Float as a separate window");
  const bool title_hovered = ImGui::IsWindowHovered(ImGuiHoveredFlags_AllowWhenBlockedByActiveItem) &&
                             title.Contains(io.MousePos) && !ImGui::IsAnyItemHovered();
  if (title_hovered && ImGui::IsMouseReleased(ImGuiMouseButton_Right)) ImGui::OpenPopup("##panel_menu");
  if (ImGui::BeginPopup("##panel_menu")) {
    if (ImGui::MenuItem(floating ? "Dock" : "Undock")) toggle_dock = true;
    if (ImGui::MenuItem("Hide")) open = false;
    ImGui::EndPopup();
  }
  if (!floating && title_hovered && ImGui::IsMouseClicked(ImGuiMouseButton_Left)) {
    shell->tearing_panel = index;
    shell->tear_press_x = io.MousePos.x;
    shell->tear_press_y = io.MousePos.y;
  }
  if (!floating && shell->tearing_panel == index && io.MouseDown[0]) {
    const float dx = io.MousePos.x - shell->tear_press_x, dy = io.MousePos.y - shell->tear_press_y;
    if (dx * dx + dy * dy > kTearOffDistancePx * kTearOffDistancePx) {
      MakeFloating(shell, index, {io.MousePos.x - 64, io.MousePos.y - 34, window_rect.w, window_rect.h});
    }
  }

  if (expanded) DrawPanelContents(state, shell, panel);
  ImGui::End();

  if (toggle_dock) {
    if (floating) {
      placement.floating = false;
      shell->layout_changed = true;
    } else {
      MakeFloating(shell, index, window_rect);
    }
  }
  if (!open) {
    placement.visible = false;
    shell->layout_changed = true;
  }
}

const char* DialogTitle(Dialog dialog) {
  switch (dialog) {
    case Dialog::kOpen: return "Open project";
    case Dialog::kSaveAs: return "Save project as";
    case Dialog::kExport: return "Export model";
    case Dialog::kExportView: return "Export view";
    case Dialog::kExportColmap: return "Export cameras (COLMAP)";
    case Dialog::kExportTransforms: return "Export cameras (transforms.json)";
    case Dialog::kAddPhoto: return "Add photo";
    case Dialog::kRelinkPhoto: return "Relink photo";
    case Dialog::kAddReference: return "Add reference mesh";
    case Dialog::kAbout: return "About Facet";
    case Dialog::kConfirmQuit: return "Unsaved changes##quit";
    case Dialog::kConfirmNew: return "Unsaved changes##new";
    case Dialog::kConfirmOpen: return "Unsaved changes##open";
    case Dialog::kRecover: return "Recover unsaved work";
    case Dialog::kProjectLocked: return "Project open elsewhere";
    case Dialog::kSaveChanged: return "Project changed on disk";
    case Dialog::kNone: break;
  }
  return "";
}

void CloseDialog(ShellState* shell) {
  shell->dialog = Dialog::kNone;
  ImGui::CloseCurrentPopup();
}

// The project guard's questions (app/state/project_guard.h). Both leave the state as it was
// on Cancel; the question is answered (cleared) by any button.
void DrawProjectGuardDialog(AppState* state, ShellState* shell) {
  ProjectGuard& guard = state->project_guard;
  const GuardQuestion question = guard.question;
  if (question == GuardQuestion::kNone) {
    CloseDialog(shell);
    return;
  }
  const std::string path = guard.question_path;
  ImGui::TextUnformatted((guard.question_text + ".").c_str());
  if (question == GuardQuestion::kOpenLocked) {
    ImGui::TextColored(kDimText, "Read-only: nothing is written to it or to its recovery file; Save becomes Save as.");
    ImGui::TextColored(kDimText, "A copy: it opens read-only and asks for a new name to save it under.");
  } else {
    ImGui::TextColored(kDimText, "Another program or another Facet wrote it. Overwrite replaces that version.");
  }
  ImGui::Spacing();
  const char* first = question == GuardQuestion::kOpenLocked ? "Open read-only" : "Overwrite";
  const char* second = question == GuardQuestion::kOpenLocked ? "Open a copy..." : "Save as...";
  const bool answer_first = ImGui::Button(first, ImVec2(130, 0));
  RecordItem(state, question == GuardQuestion::kOpenLocked ? "locked.read_only" : "changed.overwrite");
  ImGui::SameLine();
  const bool answer_second = ImGui::Button(second, ImVec2(130, 0));
  RecordItem(state, question == GuardQuestion::kOpenLocked ? "locked.copy" : "changed.save_as");
  ImGui::SameLine();
  const bool cancel = ImGui::Button("Cancel", ImVec2(110, 0)) || ImGui::IsKeyPressed(GLFW_KEY_ESCAPE, false);
  RecordItem(state, question == GuardQuestion::kOpenLocked ? "locked.cancel" : "changed.cancel");
  if (!answer_first && !answer_second && !cancel) return;
  guard.question = GuardQuestion::kNone;
  guard.question_path.clear();
  guard.question_text.clear();
  CloseDialog(shell);
  if (cancel) return;
  if (question == GuardQuestion::kOpenLocked) {
    if (!OpenProject(state, path, OpenAccess::kReadOnly)) return;  // the log says why
    NoteRecentFile(state, shell, path);
    if (answer_second) {
      OpenFileBrowser(state, shell, Dialog::kSaveAs, std::filesystem::path(path).stem().string() + "-copy.facet");
    }
    return;
  }
  if (answer_first) {
    if (SaveProjectAs(state, path, /*overwrite_changed=*/true)) NoteRecentFile(state, shell, path);
  } else {
    OpenFileBrowser(state, shell, Dialog::kSaveAs);
  }
}

// Open, Save as, Export, Add photo: the file browser (app/shell/file_actions.h) under a
// line about what the chosen file becomes.
void DrawPathDialog(AppState* state, ShellState* shell) {
  const Dialog d = shell->dialog;
  if (d == Dialog::kAddPhoto) {
    ImGui::TextColored(kDimText, "A JPEG, PNG or TIFF photo; its EXIF focal length becomes a prior");
    ImGui::Checkbox("Detect lines (proposals to accept in the image panel)", &state->detect_lines_on_add);
    RecordItem(state, "add_photo.detect_lines");
  }
  if (d == Dialog::kExport) ImGui::TextColored(kDimText, "The extension chooses the format: .glb (glTF) or .obj");
  if (d == Dialog::kExportColmap)
    ImGui::TextColored(kDimText,
                       "cameras.txt, images.txt and points3D.txt (the vertices, their pins as tracks) in the folder "
                       "chosen; a new folder name typed is created");
  if (d == Dialog::kExportTransforms)
    ImGui::TextColored(kDimText, "nerfstudio / instant-ngp cameras; photo paths relative to the file's folder");
  if (d == Dialog::kAddReference)
    ImGui::TextColored(kDimText,
                       "A mesh to model against (.obj, .glb or .gltf, Y up): drawn, snapped to, never exported");
  if (d == Dialog::kExportView) {
    ImGui::TextColored(kDimText, "The panel with its overlays, as on screen, at this size (a PNG):");
    int panel = shell->export_view_panel == PanelId::kImage ? 0 : 1;
    ImGui::RadioButton("Image panel", &panel, 0);
    ImGui::SameLine();
    ImGui::RadioButton("3D panel", &panel, 1);
    shell->export_view_panel = panel == 0 ? PanelId::kImage : PanelId::kViewport;
    ImGui::SameLine();
    ImGui::SetNextItemWidth(110);
    ImGui::InputInt("x##export_w", &shell->export_view_width, 0);
    ImGui::SameLine();
    ImGui::SetNextItemWidth(110);
    ImGui::InputInt("px##export_h", &shell->export_view_height, 0);
    shell->export_view_width = std::clamp(shell->export_view_width, 64, 8192);
    shell->export_view_height = std::clamp(shell->export_view_height, 64, 8192);
  }
  if (d == Dialog::kRelinkPhoto) {
    const Image* image = state->document.project().FindImage(state->active_image_id);
    if (image != nullptr)
      ImGui::TextColored(kDimText, "The file for %s (%d x %d px); its camera, pins and lines stay", image->path.c_str(),
                         image->width_px, image->height_px);
  }
  DrawFileBrowser(state, shell);
}

void DrawDialogs(AppState* state, ShellState* shell) {
  if (shell->dialog == Dialog::kNone) return;
  const char* title = DialogTitle(shell->dialog);
  if (shell->dialog_just_opened) {
    ImGui::OpenPopup(title);
    shell->dialog_just_opened = false;
  }
  const ImGuiViewport* vp = ImGui::GetMainViewport();
  const bool browser = IsFileBrowserDialog(shell->dialog);
  ImGuiWindowFlags flags = ImGuiWindowFlags_NoSavedSettings;
  if (browser) {
    // The browser is as large as the window allows, up to a comfortable reading size.
    constexpr float kBrowserMaxW = 980.0f, kBrowserMaxH = 620.0f, kBrowserMarginPx = 40.0f;
    ImGui::SetNextWindowSize(ImVec2(std::min(kBrowserMaxW, vp->Size.x - kBrowserMarginPx),
                                    std::min(kBrowserMaxH, vp->Size.y - kBrowserMarginPx)),
                             ImGuiCond_Appearing);
    ImGui::SetNextWindowPos(ImVec2(vp->Pos.x + vp->Size.x * 0.5f, vp->Pos.y + vp->Size.y * 0.5f), ImGuiCond_Appearing,
                            ImVec2(0.5f, 0.5f));
  } else {
    flags |= ImGuiWindowFlags_AlwaysAutoResize;
    ImGui::SetNextWindowPos(ImVec2(vp->Pos.x + vp->Size.x * 0.5f, vp->Pos.y + vp->Size.y * 0.4f), ImGuiCond_Appearing,
                            ImVec2(0.5f, 0.5f));
  }
  if (!ImGui::BeginPopupModal(title, nullptr, flags)) {
    shell->dialog = Dialog::kNone;
    return;
  }
  const std::string name = state->project_path.empty() ? "the untitled project"
                                                       : std::filesystem::path(state->project_path).filename().string();
  switch (shell->dialog) {
    case Dialog::kOpen:
    case Dialog::kSaveAs:
    case Dialog::kAddPhoto:
    case Dialog::kRelinkPhoto:
    case Dialog::kAddReference:
    case Dialog::kExport:
    case Dialog::kExportColmap:
    case Dialog::kExportTransforms:
    case Dialog::kExportView: DrawPathDialog(state, shell); break;
    case Dialog::kAbout:
      ImGui::Text("Facet %s", "0.1");
      ImGui::TextColored(kDimText, "Textured 3D models from uncalibrated photos:");
      ImGui::TextColored(kDimText, "vanishing-point calibration, primitives, K-operators, pins.");
      ImGui::TextColored(kDimText, "After Debevec, Taylor and Malik, SIGGRAPH 1996.");
      ImGui::Spacing();
      if (ImGui::Button("Close", ImVec2(100, 0)) || ImGui::IsKeyPressed(GLFW_KEY_ESCAPE, false)) CloseDialog(shell);
      break;
    case Dialog::kRecover: {
      // Only the two answers close it: an unanswered offer keeps the file for the next start.
      const RecoveryOffer* offer = state->autosave.offer ? &*state->autosave.offer : nullptr;
      if (offer == nullptr) {
        CloseDialog(shell);
        break;
      }
      const std::string what = offer->project_path.empty()
                                   ? std::string("An unsaved project")
                                   : std::filesystem::path(offer->project_path).filename().string();
      ImGui::Text("%s has unsaved work from a session that did not end normally.", what.c_str());
      const size_t undo = offer->document.undo_stack().size();
      ImGui::TextColored(kDimText, "%zu %s to undo, %zu to redo: %s", undo, undo == 1 ? "edit" : "edits",
                         offer->document.redo_stack().size(), offer->recovery_path.c_str());
      ImGui::Spacing();
      const bool restore = ImGui::Button("Restore", ImVec2(110, 0));
      RecordItem(state, "recover.restore");
      ImGui::SameLine();
      const bool discard = ImGui::Button("Discard", ImVec2(110, 0));
      RecordItem(state, "recover.discard");
      if (restore) RestoreRecovery(state);
      if (discard) DiscardRecovery(state);
      if (restore || discard) CloseDialog(shell);
      break;
    }
    case Dialog::kConfirmQuit:
    case Dialog::kConfirmNew:
    case Dialog::kConfirmOpen: {
      const Dialog d = shell->dialog;
      ImGui::Text("%s has unsaved changes.", name.c_str());
      ImGui::TextColored(kDimText, d == Dialog::kConfirmQuit ? "Save them before quitting?" : "Save them first?");
      ImGui::Spacing();
      const std::string pending_path = shell->dialog_path;
      auto proceed = [&]() { ProceedAfterConfirm(state, shell, d, pending_path); };
      const bool save = ImGui::Button("Save", ImVec2(110, 0));
      RecordItem(state, "confirm.save");
      if (save) {
        if (SaveNeedsName(*state)) {
          CloseDialog(shell);
          OpenFileBrowser(state, shell, Dialog::kSaveAs);
          shell->after_save = d;  // the question's answer follows the save
          shell->after_save_path = pending_path;
          break;
        }
        CloseDialog(shell);  // first: what follows may open a dialog of its own (recovery)
        if (SaveProjectAs(state, "")) proceed();
        break;
      }
      ImGui::SameLine();
      const bool discard = ImGui::Button("Discard", ImVec2(110, 0));
      RecordItem(state, "confirm.discard");
      if (discard) {
        CloseDialog(shell);
        proceed();
        break;
      }
      ImGui::SameLine();
      if (ImGui::Button("Cancel", ImVec2(110, 0)) || ImGui::IsKeyPressed(GLFW_KEY_ESCAPE, false)) CloseDialog(shell);
      break;
    }
    case Dialog::kProjectLocked:
    case Dialog::kSaveChanged: DrawProjectGuardDialog(state, shell); break;
    case Dialog::kNone: break;
  }
  ImGui::EndPopup();
}

std::optional<Tool> ToolFromName(const std::string& name) {
  if (name == "select") return Tool::kSelect;
  if (name == "line-x" || name == "linex" || name == "x") return Tool::kLineX;
  if (name == "line-y" || name == "liney" || name == "y") return Tool::kLineY;
  if (name == "line-z" || name == "linez" || name == "z") return Tool::kLineZ;
  if (name == "pin") return Tool::kPin;
  if (name == "add-primitive" || name == "add-box" || name == "addbox" || name == "box") return Tool::kAddPrimitive;
  if (name == "split-edge" || name == "e-split") return Tool::kSplitEdge;
  if (name == "delete-vertex" || name == "v-delete") return Tool::kDeleteVertex;
  if (name == "connect-vertices" || name == "v-connect") return Tool::kConnectVertices;
  if (name == "delete-edge" || name == "e-delete") return Tool::kDeleteEdge;
  if (name == "push-pull" || name == "extrude") return Tool::kPushPull;
  if (name == "move") return Tool::kMove;
  if (name == "measure") return Tool::kMeasure;
  if (name == "line-pin") return Tool::kLinePin;
  return std::nullopt;
}

std::optional<PrimitiveKind> KindFromName(const std::string& name) {
  for (PrimitiveKind kind : {PrimitiveKind::kBox, PrimitiveKind::kWedge, PrimitiveKind::kPrism, PrimitiveKind::kPyramid,
                             PrimitiveKind::kCylinder, PrimitiveKind::kPlane}) {
    if (name == PrimitiveKindName(kind)) return kind;
  }
  return std::nullopt;
}

std::vector<std::string> Words(const std::string& text) {
  std::istringstream in(text);
  std::vector<std::string> words;
  for (std::string w; in >> w;) words.push_back(w);
  return words;
}

// "select vertex|edge|face PRIMITIVE_ID ELEMENT_ID" or "select primitive ID" or "select none".
bool RunSelectCommand(AppState* state, const std::string& arg, std::string* error) {
  const std::vector<std::string> w = Words(arg);
  if (w.size() == 1 && w[0] == "none") {
    state->selection = {};
    return true;
  }
  char* end = nullptr;
  auto number = [&](const std::string& text, unsigned long long* value) {
    *value = std::strtoull(text.c_str(), &end, 10);
    return !text.empty() && *end == '\0';
  };
  unsigned long long element = 0;
  const Project& project = state->document.project();
  Id primitive_id = kNoId;
  std::string why;
  if (w.size() == 2 && w[0] == "primitive") {
    if (!ResolvePrimitiveToken(project, w[1], &primitive_id, &why)) {
      *error = "select: " + why;
      return false;
    }
    state->selection = {};
    state->selection.primitive_id = primitive_id;
    return true;
  }
  ElementRef ref;
  if (w.size() == 3 && number(w[2], &element)) {
    ref.kind = w[0] == "vertex" ? ElementKind::kVertex
               : w[0] == "edge" ? ElementKind::kEdge
               : w[0] == "face" ? ElementKind::kFace
                                : ElementKind::kNone;
    ref.element = static_cast<std::uint32_t>(element);
  }
  if (ref.kind == ElementKind::kNone) {
    *error = "select: expected 'vertex|edge|face PRIMITIVE ELEMENT_ID', 'primitive PRIMITIVE' or 'none' (PRIMITIVE: an "
             "id, @N or last)";
    return false;
  }
  if (!ResolvePrimitiveToken(project, w[1], &ref.primitive_id, &why)) {
    *error = "select: " + why;
    return false;
  }
  if (!ElementExists(project, ref)) {
    *error = "select: no " + DescribeElement(project, ref);
    return false;
  }
  state->selection = Selection::Of(ref);
  return true;
}

}  // namespace

void ProceedAfterConfirm(AppState* state, ShellState* shell, Dialog question, const std::string& path) {
  if (question == Dialog::kConfirmQuit) {
    shell->quit_now = true;
  } else if (question == Dialog::kConfirmNew) {
    std::string error;
    RunAppCommand(state, shell, "new", {}, &error);
  } else if (question == Dialog::kConfirmOpen) {
    std::string error;
    RunAppCommand(state, shell, "open", {path}, &error);  // a failure is in the log
  }
}

void OpenDialog(ShellState* shell, Dialog dialog, std::string path) {
  shell->dialog = dialog;
  shell->dialog_just_opened = true;
  shell->dialog_path = std::move(path);
}

std::string WindowTitle(const AppState& state) {
  const std::string name = state.project_path.empty() ? std::string("untitled")
                                                      : std::filesystem::path(state.project_path).filename().string();
  return "Facet - " + name + (state.project_guard.read_only ? " (read-only)" : "") +
         (state.document.dirty() ? " *" : "");
}

void RequestQuit(AppState* state, ShellState* shell) {
  if (shell->offscreen || !state->document.dirty()) {
    shell->quit_now = true;
  } else {
    OpenDialog(shell, Dialog::kConfirmQuit);
  }
}

namespace {

// `teach NAME on|off` and `teach second-image INDEX` (app/state/input_script.h).
bool RunTeachCommand(AppState* state, const std::vector<std::string>& args, std::string* error) {
  if (args.size() == 2 && args[0] == "second-image") {
    const Project& project = state->document.project();
    const int index = std::atoi(args[1].c_str());
    if (index < 0 || index >= static_cast<int>(project.images.size())) {
      *error = "teach second-image: no image " + args[1];
      return false;
    }
    state->teach.second_image_id = project.images[index].id;
    return true;
  }
  // The Solver steps window: step, reset, start perturbed|as-is, perturbation AMOUNT.
  if (args.size() == 1 && args[0] == "step") {
    TeachStep(state);  // a step that changes nothing (finished, failed) says why in the window
    return true;
  }
  if (args.size() == 1 && args[0] == "reset") {
    TeachResetSteps(state);
    return true;
  }
  if (args.size() == 2 && args[0] == "start") {
    const std::optional<TeachStepStart> start = TeachStepStartFromName(args[1]);
    if (!start) {
      *error = "teach start: expected perturbed or as-is";
      return false;
    }
    TeachEndSteps(state);
    state->teach.solver.start = *start;
    return true;
  }
  if (args.size() == 2 && args[0] == "subject") {
    const std::optional<TeachStepSubject> subject = TeachStepSubjectFromName(args[1]);
    if (!subject) {
      *error = "teach subject: expected joint, vanishing or two-view";
      return false;
    }
    TeachEndSteps(state);
    state->teach.solver.subject = *subject;
    return true;
  }
  if (args.size() == 2 && args[0] == "residual-scale") {
    char* end = nullptr;
    const double scale = std::strtod(args[1].c_str(), &end);
    if (*end != '\0' || !(scale > 0.0) || !std::isfinite(scale)) {
      *error = "teach residual-scale: expected a positive factor, e.g. 5";
      return false;
    }
    state->teach.solver.residual_scale = scale;  // until stepping begins again
    state->teach.solver.vp.residual_scale = scale;
    return true;
  }
  if (args.size() == 2 && args[0] == "perturbation") {
    char* end = nullptr;
    const double amount = std::strtod(args[1].c_str(), &end);
    if (*end != '\0' || !(amount > 0.0) || amount > 0.5) {
      *error = "teach perturbation: expected an amount in (0, 0.5], e.g. 0.05";
      return false;
    }
    TeachEndSteps(state);
    state->teach.solver.perturbation = amount;
    return true;
  }
  bool* flag = args.size() == 2 ? TeachFlag(&state->teach, args[0]) : nullptr;
  if (flag == nullptr || (args[1] != "on" && args[1] != "off")) {
    *error =
        "teach: expected 'teach vanishing|epipolar|numbers|state|steps on|off', 'teach second-image INDEX', "
        "'teach step', 'teach reset', 'teach subject joint|vanishing|two-view', 'teach start perturbed|as-is', "
        "'teach perturbation AMOUNT' or "
        "'teach residual-scale S'";
    return false;
  }
  *flag = args[1] == "on";
  return true;
}

}  // namespace

bool RunAppCommand(AppState* state, ShellState* shell, const std::string& name, const std::vector<std::string>& args,
                   std::string* error) {
  const std::string arg = args.empty() ? std::string() : args.front();
  if (name == "new") {
    NewProject(state);
    return true;
  }
  if (name == "undo") {
    Undo(state);
    return true;
  }
  if (name == "redo") {
    Redo(state);
    return true;
  }
  if (name == "save") {
    if (!SaveProjectAs(state, arg)) {
      // A script is refused with the reason; the GUI's Save asks (kSaveChanged).
      state->project_guard.question = GuardQuestion::kNone;
      *error = LastLoggedError(*state);
      return false;
    }
    NoteRecentFile(state, shell, state->project_path);
    return true;
  }
  if (name == "open") {
    if (!OpenProject(state, arg)) {
      // Open in another Facet: the next frame asks, as after File > Open (kProjectLocked).
      if (state->project_guard.question == GuardQuestion::kOpenLocked) return true;
      *error = LastLoggedError(*state);
      return false;
    }
    NoteRecentFile(state, shell, arg);
    if (FindRecovery(state, /*also_unsaved=*/false)) OpenDialog(shell, Dialog::kRecover);
    return true;
  }
  if (name == "recover") {
    if (arg != "restore" && arg != "discard") {
      *error = "expected 'recover restore' or 'recover discard'";
      return false;
    }
    if (!state->autosave.offer) {
      *error = "no recovery file is offered";
      return false;
    }
    if (arg == "restore") {
      RestoreRecovery(state);
    } else {
      DiscardRecovery(state);
    }
    // The dialog closes itself in the next frame, once there is no offer to show.
    return true;
  }
  if (name == "wait-autosave") return WaitForAutosave(state, error);
  if (name == "advance-clock") {
    char* end = nullptr;
    const double seconds = std::strtod(arg.c_str(), &end);
    if (!shell->offscreen || end == arg.c_str() || *end != '\0' || !(seconds > 0.0 && seconds < 1e6)) {
      *error = shell->offscreen ? "expected a number of seconds in (0, 1e6)" : "only offscreen";
      return false;
    }
    shell->clock_offset_s += seconds;
    return true;
  }
  if (name == "wait-removed") {
    if (!shell->offscreen) {
      *error = "only offscreen";
      return false;
    }
    for (int i = 0; i < 12000; ++i) {
      std::error_code ec;
      if (!std::filesystem::exists(std::filesystem::symlink_status(arg, ec))) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    *error = arg + " still exists after 120 s";
    return false;
  }
  if (name == "tool") {
    const std::optional<Tool> tool = ToolFromName(arg);
    if (!tool) {
      *error = "unknown tool '" + arg +
               "' (select, line-x, line-y, line-z, pin, add-primitive, split-edge, delete-vertex, "
               "connect-vertices, delete-edge, push-pull, move, line-pin, measure)";
      return false;
    }
    if (*tool == Tool::kAddPrimitive) {
      if (arg == "add-box" || arg == "addbox" || arg == "box") state->add_kind = PrimitiveKind::kBox;
      AddPrimitiveAction(state);
    } else {
      SetTool(state, *tool);
    }
    return true;
  }
  if (name == "add") {
    // add KIND [on-top] | add KIND at U V (aimed at image px U, V of the active image)
    std::vector<std::string> w = Words(arg);
    const std::optional<PrimitiveKind> kind = w.empty() ? std::nullopt : KindFromName(w[0]);
    std::optional<Eigen::Vector2d> aim;
    if (w.size() == 4 && w[1] == "at") {
      char* end_u = nullptr;
      char* end_v = nullptr;
      const double u = std::strtod(w[2].c_str(), &end_u), v = std::strtod(w[3].c_str(), &end_v);
      if (*end_u != '\0' || *end_v != '\0' || !std::isfinite(u) || !std::isfinite(v)) {
        *error = "add: 'at' needs two numbers (image px)";
        return false;
      }
      aim = Eigen::Vector2d(u, v);
      w.resize(1);
    }
    if (!kind || w.size() > 2 || (w.size() == 2 && w[1] != "on-top")) {
      *error = "add: expected 'KIND [on-top]' or 'KIND at U V' with KIND box, wedge, prism, pyramid, cylinder or plane";
      return false;
    }
    Id base = kNoId;
    if (w.size() == 2) {
      const Primitive* b = AttachBaseFor(*state, *kind);
      if (b == nullptr) {
        *error = "add: 'on-top' needs a selected box and a wedge, pyramid or plane";
        return false;
      }
      base = b->id;
    }
    state->add_kind = *kind;
    if (!AddPrimitiveEdit(state, *kind, base, aim)) {
      *error = LastLoggedError(*state);
      return false;
    }
    return true;
  }
  if (name == "select") return RunSelectCommand(state, arg, error);
  if (name == "ridge") {
    // ridge x|y: the selected wedge's ridge direction
    if (arg != "x" && arg != "y") {
      *error = "ridge: expected x or y";
      return false;
    }
    if (!SetWedgeRidgeEdit(state, state->selection.primitive_id, arg == "y")) {
      *error = LastLoggedError(*state);
      return false;
    }
    return true;
  }
  if (name == "add-photo") {
    if (!AddPhotoEdit(state, arg)) {
      *error = LastLoggedError(*state);
      return false;
    }
    NoteRecentFile(state, shell, arg);
    // The photo is in; the lines arrive as proposals when its worker finishes (a detection
    // that finds none only logs why).
    if (state->detect_lines_on_add) StartLineDetection(state, state->active_image_id);
    return true;
  }
  if (name == "relink-photo") {
    // relink-photo PATH: the active image's photo file (File > Relink photo)
    if (!RelinkPhotoEdit(state, state->active_image_id, arg)) {
      *error = LastLoggedError(*state);
      return false;
    }
    NoteRecentFile(state, shell, arg);
    return true;
  }
  if (name == "lines") return RunLinesCommand(state, arg, error);
  if (name == "colmap") return RunColmapCommand(state, arg, error);
  if (name == "pin-proposals") return RunPinProposalsCommand(state, arg, error);
  if (name == "constrain") return RunConstrainCommand(state, arg, error);
  if (name == "select-add") return RunSelectAddCommand(state, arg, error);
  if (name == "line-pin") return RunLinePinCommand(state, arg, error);
  if (name == "line-pin-move") return RunLinePinMoveCommand(state, arg, error);
  if (name == "calibration") return RunCalibrationCommand(state, &shell->properties_panel.exif_feedback, arg, error);
  if (name == "move-selection") return RunMoveCommand(state, arg, error);
  if (name == "texture") return RunTextureCommand(state, arg, error);
  if (name == "add-reference") return RunAppCommand(state, shell, "reference", {"add " + arg}, error);
  if (name == "reference") {
    // reference add PATH | reference add-z-up PATH | reference remove INDEX (app/state/reference_edits.h)
    const size_t space = arg.find(' ');
    const std::string verb = arg.substr(0, space);
    const std::string rest = space == std::string::npos ? std::string() : arg.substr(space + 1);
    if ((verb == "add" || verb == "add-z-up") && !rest.empty()) {
      if (!AddReferenceEdit(state, rest, verb == "add")) {
        *error = LastLoggedError(*state);
        return false;
      }
      NoteRecentFile(state, shell, rest);
      return true;
    }
    if (verb == "remove" || verb == "show" || verb == "hide") {
      const auto& references = state->document.project().references;
      char* end = nullptr;
      const long index = std::strtol(rest.c_str(), &end, 10);
      if (rest.empty() || *end != '\0' || index < 0 || index >= static_cast<long>(references.size())) {
        *error = "reference " + verb + ": index " + rest + " is not in 0.." +
                 std::to_string(static_cast<long>(references.size()) - 1);
        return false;
      }
      if (verb == "remove") return RemoveReferenceEdit(state, references[index].id);
      return SetReferenceVisibleEdit(state, references[index].id, verb == "show");
    }
    *error = "reference: expected 'add PATH', 'add-z-up PATH', or 'remove|show|hide INDEX'";
    return false;
  }
  if (name == "free-vertex" || name == "planar-face") {
    const ElementRef& e = state->selection.element;
    const bool vertex = name == "free-vertex";
    if (e.kind != (vertex ? ElementKind::kVertex : ElementKind::kFace)) {
      *error = name + ": select a " + (vertex ? "vertex" : "face") + " first";
      return false;
    }
    const bool done = vertex ? ToggleFreeVertexEdit(state, e.primitive_id, e.element)
                             : TogglePlanarFaceEdit(state, e.primitive_id, e.element);
    if (!done) *error = LastLoggedError(*state);
    return done;
  }
  if (name == "teach") {  // teach NAME on|off (app/state/teach.h), or teach second-image INDEX
    std::vector<std::string> words;
    std::istringstream in(arg);
    for (std::string w; in >> w;) words.push_back(w);
    return RunTeachCommand(state, words, error);
  }
  if (name == "export-view") {  // done after this frame (app/shell/export_view.h)
    ExportViewRequest request;
    *error = ParseExportViewArgs(arg, *shell, &request);
    if (!error->empty()) return false;
    shell->pending_export_view = arg;
    return true;
  }
  if (name == "select-image") {
    const auto& images = state->document.project().images;
    char* end = nullptr;
    const long index = std::strtol(arg.c_str(), &end, 10);
    if (arg.empty() || *end != '\0' || index < 0 || index >= static_cast<long>(images.size())) {
      *error = "select-image: index " + arg + " is not in 0.." + std::to_string(static_cast<long>(images.size()) - 1);
      return false;
    }
    state->active_image_id = images[index].id;
    return true;
  }
  if (name == "fit") {
    RequestImageFit(&shell->image_panel);
    return true;
  }
  if (name == "wait-bake") {
    FinishBake(state);
    return true;
  }
  if (name == "bake-status") return WriteBakeStatus(*state, arg, error);
  if (name == "export-colmap") return ExportColmapCameras(state, shell, arg, error);
  if (name == "export-transforms") return ExportTransformsJson(state, shell, arg, error);
  if (name == "export") {
    // The model as it is now, textured (at the export dialog's resolution, when one is set).
    TexturedMesh mesh;
    std::string bake_message;
    if (!MeshForExport(state, &mesh, &bake_message)) {
      *error = "export: texture: " + bake_message;
      state->Log(LogLevel::kError, "Export failed: " + *error);
      return false;
    }
    const std::string ext = std::filesystem::path(arg).extension().string();
    if (mesh.indices.empty()) {
      *error = "export: there is no model yet (add a primitive and pin it)";
      return false;
    }
    if (state->texture.export_texels_per_unit > 0.0) state->Log(LogLevel::kInfo, "Export texture: " + bake_message);
    ExportSummary summary;
    if (ext == ".glb") {
      summary = ExportGlb(mesh, state->document.project(), arg);
    } else if (ext == ".obj") {
      summary = ExportObj(mesh, arg);
    } else {
      *error = "export: the file name must end in .glb or .obj";
      return false;
    }
    if (!summary.success) {
      state->Log(LogLevel::kError, "Export failed: " + summary.message);
      *error = summary.message;
      return false;
    }
    state->Log(LogLevel::kInfo, "Exported " + arg);
    NoteRecentFile(state, shell, arg);
    return true;
  }
  *error = "unknown command '" + name + "'";
  return false;
}

namespace {

// A frame of File > Export view (app/shell/export_view.h): the exported panel alone, filling
// the display without a title bar; its canvas is noted for the crop.
void DrawExportViewFrame(AppState* state, ShellState* shell) {
  state->item_rects.clear();
  state->clipped_items.clear();
  const ImGuiViewport* vp = ImGui::GetMainViewport();
  ImGui::SetNextWindowPos(vp->Pos, ImGuiCond_Always);
  ImGui::SetNextWindowSize(vp->Size, ImGuiCond_Always);
  ImGui::PushStyleVar(ImGuiStyleVar_WindowPadding, ImVec2(3, 3));
  ImGui::PushStyleVar(ImGuiStyleVar_WindowRounding, 0.0f);
  ImGui::PushStyleVar(ImGuiStyleVar_WindowBorderSize, 0.0f);
  constexpr ImGuiWindowFlags kFlags = ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_NoSavedSettings |
                                      ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoScrollWithMouse |
                                      ImGuiWindowFlags_NoBringToFrontOnFocus;
  ImGui::Begin("##export_view", nullptr, kFlags);
  ImGui::PopStyleVar(3);
  if (shell->export_image_panel != nullptr) {
    DrawImagePanel(state, shell->export_image_panel);
    const ImageViewReport r = LastImageViewReport(*shell->export_image_panel);
    shell->export_canvas = {r.rect_x, r.rect_y, r.rect_w, r.rect_h};
  } else if (shell->export_viewport_panel != nullptr) {
    DrawViewportPanel(state, shell->export_viewport_panel);
    const ViewportReport r = LastViewportReport(*shell->export_viewport_panel);
    if (r.drawn)
      shell->export_canvas = {r.origin_x, r.origin_y, static_cast<float>(r.width_px), static_cast<float>(r.height_px)};
  }
  ImGui::End();
}

}  // namespace

void DrawFrame(AppState* state, ShellState* shell, double time_s) {
  state->time_s = time_s;
  state->bake_mode = shell->offscreen ? BakeMode::kFinishNextFrame : BakeMode::kBackground;
  RefreshDerived(state);
  SyncReferenceMeshes(state);
  CollectLineDetection(state, /*wait=*/false);
  CollectColmapCameras(state, /*wait=*/false);  // a finished run becomes one edit
  UpdateTeachSteps(state);  // View > Teach > Solver steps: dropped when the document changed
  if (shell->export_image_panel != nullptr || shell->export_viewport_panel != nullptr) {
    DrawExportViewFrame(state, shell);
    return;
  }
  AutosaveTick(state);
  if (state->autosave.offer && shell->dialog == Dialog::kNone) OpenDialog(shell, Dialog::kRecover);
  if (state->project_guard.question != GuardQuestion::kNone && shell->dialog == Dialog::kNone) {
    OpenDialog(
        shell,
        state->project_guard.question == GuardQuestion::kOpenLocked ? Dialog::kProjectLocked : Dialog::kSaveChanged,
        state->project_guard.question_path);
  }
  if (state->request_quit) {
    state->request_quit = false;
    RequestQuit(state, shell);
  }
  HandleDroppedFiles(state, shell);
  HandleGlobalShortcuts(state, shell);

  state->item_rects.clear();
  state->clipped_items.clear();
  const float menu_height = DrawMenuBar(state, shell);
  const ImGuiViewport* vp = ImGui::GetMainViewport();
  const Rect work{vp->Pos.x + kWorkAreaMarginPx, vp->Pos.y + menu_height + kWorkAreaMarginPx,
                  vp->Size.x - 2 * kWorkAreaMarginPx, vp->Size.y - menu_height - 2 * kWorkAreaMarginPx};
  const TiledLayout tiled = ComputeTiledLayout(shell->layout, work);

  // Keep floating panels reachable after the window shrank.
  for (PanelPlacement& p : shell->layout.panels) {
    if (!p.floating) continue;
    p.floating_rect.x = std::clamp(p.floating_rect.x, vp->Pos.x - p.floating_rect.w + 60, vp->Pos.x + vp->Size.x - 60);
    p.floating_rect.y = std::clamp(p.floating_rect.y, vp->Pos.y, vp->Pos.y + vp->Size.y - 30);
  }

  shell->panel_drawn.fill(false);
  DrawSplitters(shell, tiled, work);
  // Docked panels first: floating ones are created later and so stay in front.
  for (int pass = 0; pass < 2; ++pass) {
    for (int i = 0; i < kNumPanels; ++i) {
      if (shell->layout.panels[i].floating == (pass == 1)) DrawPanel(state, shell, i, tiled);
    }
  }
  if (!ImGui::GetIO().MouseDown[0]) shell->tearing_panel = -1;

  DrawTeachNumbersWindow(state);  // View > Teach > Numbers
  DrawTeachStepsWindow(state);    // View > Teach > Solver steps
  DrawColmapWindow(state);        // File > Cameras from all photos
  DrawDialogs(state, shell);
  if (shell->dialog == Dialog::kNone) HandleToolShortcuts(state);
}

void ConfigureImGui(bool offscreen, float ui_scale) {
  ui_scale = std::clamp(ui_scale, 1.0f, 4.0f);
  ImGuiIO& io = ImGui::GetIO();
  io.ConfigWindowsMoveFromTitleBarOnly = true;  // drags inside the image and 3D panels never move windows
  io.ConfigFlags |= ImGuiConfigFlags_NavEnableKeyboard;

  const char* font_path = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";
  std::error_code ec;
  if (std::filesystem::exists(font_path, ec)) {
    ImFontConfig config;
    config.OversampleH = 2;
    io.Fonts->AddFontFromFileTTF(font_path, std::round(15.0f * ui_scale), &config);
  } else {
    io.Fonts->AddFontDefault();
  }

  ImGui::StyleColorsDark();
  ImGuiStyle& style = ImGui::GetStyle();
  style.WindowRounding = 3.0f;
  style.ChildRounding = 2.0f;
  style.FrameRounding = 3.0f;
  style.PopupRounding = 3.0f;
  style.GrabRounding = 3.0f;
  style.ScrollbarRounding = 3.0f;
  style.WindowBorderSize = 1.0f;
  style.FramePadding = ImVec2(6, 4);
  style.ItemSpacing = ImVec2(8, 5);
  style.WindowPadding = ImVec2(8, 7);
  style.WindowTitleAlign = ImVec2(0.0f, 0.5f);
  ImVec4* c = style.Colors;
  c[ImGuiCol_WindowBg] = ImVec4(0.125f, 0.133f, 0.145f, 1.0f);
  c[ImGuiCol_ChildBg] = ImVec4(0.10f, 0.105f, 0.115f, 1.0f);
  c[ImGuiCol_PopupBg] = ImVec4(0.14f, 0.15f, 0.16f, 0.98f);
  c[ImGuiCol_MenuBarBg] = ImVec4(0.16f, 0.17f, 0.185f, 1.0f);
  c[ImGuiCol_TitleBg] = ImVec4(0.16f, 0.17f, 0.185f, 1.0f);
  c[ImGuiCol_TitleBgActive] = ImVec4(0.19f, 0.23f, 0.30f, 1.0f);
  c[ImGuiCol_Border] = ImVec4(0.24f, 0.25f, 0.28f, 1.0f);
  c[ImGuiCol_FrameBg] = ImVec4(0.19f, 0.20f, 0.22f, 1.0f);
  c[ImGuiCol_FrameBgHovered] = ImVec4(0.24f, 0.27f, 0.31f, 1.0f);
  c[ImGuiCol_Button] = ImVec4(0.21f, 0.23f, 0.26f, 1.0f);
  c[ImGuiCol_ButtonHovered] = ImVec4(0.27f, 0.34f, 0.45f, 1.0f);
  c[ImGuiCol_ButtonActive] = ImVec4(0.26f, 0.45f, 0.72f, 1.0f);
  c[ImGuiCol_Header] = ImVec4(0.22f, 0.25f, 0.30f, 1.0f);
  c[ImGuiCol_HeaderHovered] = ImVec4(0.27f, 0.34f, 0.45f, 1.0f);
  c[ImGuiCol_HeaderActive] = ImVec4(0.26f, 0.45f, 0.72f, 1.0f);
  c[ImGuiCol_SeparatorHovered] = ImVec4(0.30f, 0.50f, 0.80f, 0.8f);
  c[ImGuiCol_SeparatorActive] = ImVec4(0.35f, 0.58f, 0.92f, 1.0f);

  style.ScaleAllSizes(ui_scale);
  if (offscreen) {
    io.IniFilename = nullptr;  // deterministic screenshots: never read or write user settings
  }
}

}  // namespace facet::app
