// The file browser's contents, drawn inside the modal dialog that the shell opens for File >
// Open, Save as, Export and Add photo (app/shell/frame.cpp): the current folder as an
// editable path with a Parent button, places and recent folders and files in a side column,
// the folder's entries (folders first, then the files the purpose's filter lets through),
// a name field, the filter and hidden-files toggles, and the confirm and Cancel buttons.
// Enter confirms (or goes into the folder typed or selected), Escape cancels; an existing
// file chosen for writing asks before it is replaced. The listing and path logic is
// app/state/file_browser_model.h.
#pragma once

#include <string>

#include "app/state/app_state.h"
#include "app/state/file_browser_model.h"

namespace facet::app {

struct FileDialogState {
  BrowsePurpose purpose = BrowsePurpose::kOpenProject;
  std::string folder;      // the folder listed, absolute
  std::string path_field;  // the editable path line (the folder unless the user types)
  std::string name_field;  // the file to open or write: a name in `folder`, or a typed path
  std::string selected;    // the entry highlighted in the list (a name in `folder`)
  bool all_files = false;  // the filter toggle: every file, not only the purpose's
  bool show_hidden = false;
  std::string home_folder;     // "Places" in the side column
  std::string project_folder;  // empty for an unsaved project
  // The listing is read again when the folder or the toggles change and every couple of
  // seconds (files appear), never every frame.
  FolderListing listing;
  bool listing_stale = true;
  double listed_time_s = 0.0;
  std::string error;                 // the last refusal, shown under the list
  std::string confirm_overwrite;     // an existing file chosen for writing, awaiting Replace
  bool focus_pending = true;         // the first frame gives the keyboard to the main field
  bool select_stem_pending = false;  // writing: the name's stem is selected, not its extension
  // After Enter in a field took the browser into a folder, that field keeps the keyboard, so
  // that the next name or path can be typed at once.
  bool refocus_path = false, refocus_name = false;
  bool scroll_to_selected = false;
};

// Starts a browse in `folder` (empty: the working directory) with `name` proposed in the
// name field (for Save as and Export).
void StartFileDialog(FileDialogState* dialog, BrowsePurpose purpose, const std::string& folder, const std::string& name,
                     const std::string& project_folder);

enum class FileDialogOutcome { kBrowsing, kChosen, kCancelled };
struct FileDialogResult {
  FileDialogOutcome outcome = FileDialogOutcome::kBrowsing;
  std::string path;  // kChosen: absolute; for writing, with the purpose's extension
};

// Draws the browser into the current window (the shell's modal popup) and returns what the
// user decided this frame. Widget rectangles are recorded as "file.path", "file.parent",
// "file.name", "file.filter", "file.hidden", "file.confirm", "file.cancel", "file.replace",
// "file.entry/NAME", "file.recent_folder/PATH", "file.recent_file/PATH" and "file.place/NAME"
// (AppState::item_rects). When the chosen file cannot be used, the caller puts the reason in
// dialog->error and keeps drawing.
FileDialogResult DrawFileDialog(AppState* state, FileDialogState* dialog, const RecentFiles& recent, double time_s);

}  // namespace facet::app
