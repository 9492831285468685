// DrawFrame: the one per-frame UI function that the windowed (GLFW) and the offscreen (EGL)
// modes both call between ImGui::NewFrame() and ImGui::Render(). It refreshes the derived
// state, then draws the menu bar, the tiled and floating panels, the splitters and the
// modal dialogs, and handles the global shortcuts. Everything the shell keeps between frames
// that is neither document nor app state lives in ShellState, the panels' own state included.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "app/panels/file_dialog.h"
#include "app/panels/image_panel.h"
#include "app/panels/side_panels.h"
#include "app/panels/viewport_panel.h"
#include "app/shell/layout.h"
#include "app/state/app_state.h"
#include "app/state/input_queue.h"

namespace facet::app {

enum class Dialog {
  kNone,
  kOpen,
  kSaveAs,
  kExport,
  kExportView,  // File > Export view: a panel as a PNG (app/shell/export_view.h)
  // File > Export cameras: the calibrated cameras as a COLMAP text model (the browser picks
  // cameras.txt in the model's folder) or as nerfstudio's transforms.json.
  kExportColmap,
  kExportTransforms,
  kAddPhoto,
  kRelinkPhoto,
  kAddReference,
  kAbout,
  kConfirmQuit,
  kConfirmNew,
  kConfirmOpen,
  kRecover,  // a recovery file was found: Restore or Discard (app/state/autosave.h)
  // The project guard's questions (app/state/project_guard.h): the project is open in another
  // Facet (read-only, a copy, cancel); the project file changed on disk (overwrite, save as, cancel).
  kProjectLocked,
  kSaveChanged,
};
// The dialogs that are the file browser (app/shell/file_actions.h).
inline bool IsFileBrowserDialog(Dialog d) {
  return d == Dialog::kOpen || d == Dialog::kSaveAs || d == Dialog::kExport || d == Dialog::kExportView ||
         d == Dialog::kExportColmap || d == Dialog::kExportTransforms || d == Dialog::kAddPhoto ||
         d == Dialog::kRelinkPhoto || d == Dialog::kAddReference;
}

struct ShellState {
  Layout layout = DefaultLayout();
  // The panels' own state between frames (views, GL resources, interactions). The GL side
  // must be shut down (ShutdownImagePanel, ShutdownViewportPanel) while the context lives.
  ImagePanelState image_panel;
  ViewportPanelState viewport_panel;
  PropertiesPanelState properties_panel;
  bool offscreen = false;  // no quitting dialogs, no layout persistence
  // Offscreen only: added to the fixed-step clock by the script's `advance-clock`, so a test
  // reaches a 30 s timer (autosave during a long drag) without rendering 30 s of frames.
  double clock_offset_s = 0.0;

  // Modal dialogs.
  Dialog dialog = Dialog::kNone;
  bool dialog_just_opened = false;
  std::string dialog_path;  // the project waiting for the unsaved-changes answer (kConfirmOpen)
  // The file browser of the dialogs IsFileBrowserDialog names (app/shell/file_actions.h).
  FileDialogState file_dialog;
  // Recent files and folders; persisted at recent_files_path after each change unless empty
  // (offscreen renders keep them in memory unless given --config-dir).
  RecentFiles recent_files;
  std::string recent_files_path;
  // Paths dropped onto the window (GLFW) or by the script's `drop`, handled at the start of
  // the next frame (HandleDroppedFiles).
  std::vector<std::string> dropped_paths;
  // The window's input events (GLFW callbacks) or the script's, taken by each frame in turn
  // (app/state/input_queue.h), so that none is lost when a frame is slow.
  InputQueue input_queue;

  // Set when the user confirmed quitting (or there was nothing to save); the platform loop
  // then exits.
  bool quit_now = false;
  // The unsaved-changes question (kConfirmQuit, kConfirmNew, kConfirmOpen) whose Save opened
  // the Save As dialog: once that save succeeds, its quit, new project or open (of
  // after_save_path) follows. kNone: a plain Save As.
  Dialog after_save = Dialog::kNone;
  std::string after_save_path;

  // Splitter and tear-off interaction.
  int active_splitter = -1;  // index into the last TiledLayout's splitters
  int tearing_panel = -1;    // a docked panel whose title bar is being dragged
  float tear_press_x = 0, tear_press_y = 0;
  int floating_to_place = -1;   // a panel that became floating this frame: set its rect once
  bool layout_changed = false;  // to persist the layout on exit

  // File > Export view (app/shell/export_view.h): the dialog's choices, the export asked for
  // (done after the frame), and while its frames run, the panel drawn alone.
  PanelId export_view_panel = PanelId::kImage;
  int export_view_width = 1920, export_view_height = 1080;
  std::optional<std::string> pending_export_view;  // the `export-view` arguments
  ImagePanelState* export_image_panel = nullptr;       // set only during the export's frames
  ViewportPanelState* export_viewport_panel = nullptr;
  Rect export_canvas;  // the exported panel's canvas in the last export frame (screen px)

  // What the last frame drew, for the render report (screen px).
  std::array<Rect, kNumPanels> panel_rects{};
  std::array<bool, kNumPanels> panel_drawn{};
  Rect menu_bar_rect;
};

// Fonts, style and IO flags shared by both modes; `offscreen` also disables the ini file.
// `ui_scale` enlarges fonts and sizes for high-density displays (1 offscreen).
void ConfigureImGui(bool offscreen, float ui_scale = 1.0f);

// Runs one frame's UI for the state. `time_s` is the time since start (fixed steps offscreen).
void DrawFrame(AppState* state, ShellState* shell, double time_s);

// "Facet - name*" (the star while the document has unsaved changes).
std::string WindowTitle(const AppState& state);

// Named app commands shared by the menus, the shortcuts and the input script: undo, redo,
// save [PATH], open PATH, tool NAME, select-image INDEX, fit, export PATH, add KIND [on-top],
// select vertex|edge|face PRIMITIVE_ID ELEMENT_ID | primitive ID | none, free-vertex,
// planar-face (app/state/input_script.h documents them). A successful open, save, export or
// add-photo puts its file among the recent ones (app/shell/file_actions.h). Returns false
// with *error set for unknown commands, bad arguments or a failed save/open/export.
bool RunAppCommand(AppState* state, ShellState* shell, const std::string& name, const std::vector<std::string>& args,
                   std::string* error);

// Opens a modal dialog; `path` is the project a kConfirmOpen is about.
void OpenDialog(ShellState* shell, Dialog dialog, std::string path = {});

// What an answered unsaved-changes question (kConfirmQuit, kConfirmNew, kConfirmOpen)
// leads to once the changes are saved or discarded: quit, a new project, or opening `path`.
void ProceedAfterConfirm(AppState* state, ShellState* shell, Dialog question, const std::string& path);

// Asks to quit: quits at once when nothing is unsaved, else opens the confirmation dialog.
void RequestQuit(AppState* state, ShellState* shell);

}  // namespace facet::app
