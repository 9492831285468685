// The shell's file handling around the browser (app/panels/file_dialog.h): where File >
// Open, Save as, Export and Add photo start browsing and what runs on the file chosen, the
// recent files and folders (noted after every open, save, export and added photo, persisted
// under the config folder), and files dropped onto the window, from GLFW or the script's
// `drop`, which take the same paths as the menu: a project opens (asking about unsaved
// work first), each photo is added as one undoable edit, anything else is refused with a
// log message.
#pragma once

#include <string>

#include "app/shell/frame.h"
#include "app/state/app_state.h"

namespace facet::app {

// Opens the browser as `dialog` (kOpen, kSaveAs, kExport or kAddPhoto). Open and Add photo
// start in the folder of the last file of the same kind, else the project's folder, else the
// last folder used, else the working directory. Save and Export start in the project's
// folder, else the folder of the last file of that kind, else the last folder used, else
// home; never in the bundled sample's folder. `name` is proposed for writing (Save as: the
// project's file name when empty).
void OpenFileBrowser(AppState* state, ShellState* shell, Dialog dialog, const std::string& name = {});

// Draws the browser into the open modal popup and, once a file is chosen, runs the open,
// save, export or add-photo command: success closes the dialog, failure shows the reason in
// it. Opening over unsaved changes goes through the kConfirmOpen question.
void DrawFileBrowser(AppState* state, ShellState* shell);

// Opens the project at `path` now, or asks about unsaved changes first (kConfirmOpen).
void OpenProjectAsking(AppState* state, ShellState* shell, const std::string& path);

// Puts a used file (and its folder) first among the recent ones and saves the list when it
// persists (ShellState::recent_files_path); a failed save is logged as a warning.
void NoteRecentFile(AppState* state, ShellState* shell, const std::string& path);
void ClearRecentFiles(AppState* state, ShellState* shell);
// Reads the recent files kept in `config_dir` (when there) and keeps them there from now on.
// A malformed file is reported in the log and replaced on the next change.
void UseRecentFilesIn(AppState* state, ShellState* shell, const std::string& config_dir);

// Handles and clears shell->dropped_paths: called by DrawFrame before anything is drawn.
// While the file browser is open a dropped file or folder is shown in it instead; while
// another dialog is open the drop is refused with a log message.
void HandleDroppedFiles(AppState* state, ShellState* shell);

}  // namespace facet::app
