#include "app/shell/file_actions.h"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <utility>

#include <imgui.h>

#include "app/state/file_browser_model.h"

namespace facet::app {
namespace {

namespace fs = std::filesystem;

BrowsePurpose PurposeOf(Dialog dialog) {
  switch (dialog) {
    case Dialog::kSaveAs: return BrowsePurpose::kSaveProject;
    case Dialog::kExport: return BrowsePurpose::kExport;
    case Dialog::kExportView: return BrowsePurpose::kExportView;
    case Dialog::kExportColmap: return BrowsePurpose::kExportColmap;
    case Dialog::kExportTransforms: return BrowsePurpose::kExportTransforms;
    case Dialog::kAddPhoto: return BrowsePurpose::kAddPhoto;
    case Dialog::kRelinkPhoto: return BrowsePurpose::kRelinkPhoto;
    case Dialog::kAddReference: return BrowsePurpose::kAddReference;
    default: return BrowsePurpose::kOpenProject;
  }
}

const char* CommandOf(BrowsePurpose purpose) {
  switch (purpose) {
    case BrowsePurpose::kOpenProject: return "open";
    case BrowsePurpose::kSaveProject: return "save";
    case BrowsePurpose::kExport: return "export";
    case BrowsePurpose::kExportView: return "export-view";
    case BrowsePurpose::kExportColmap: return "export-colmap";
    case BrowsePurpose::kExportTransforms: return "export-transforms";
    case BrowsePurpose::kAddPhoto: return "add-photo";
    case BrowsePurpose::kRelinkPhoto: return "relink-photo";
    case BrowsePurpose::kAddReference: return "add-reference";
  }
  return "";
}

std::string ProjectFolder(const AppState& state) {
  return state.project_path.empty() ? std::string() : ParentFolder(NormalizePath("", state.project_path));
}

// The bundled samples (the source tree's assets/samples, an install's share/facet/samples):
// where the app's first project comes from, never where the user's own files should go.
bool IsBundledSampleFolder(const std::string& folder) {
  std::error_code ec;
  const fs::path canonical = fs::weakly_canonical(folder, ec);
  if (ec) return false;
  std::vector<fs::path> roots = {fs::path(FACET_SOURCE_DIR) / "assets/samples"};
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) roots.push_back(exe.parent_path() / "../share/facet/samples");
  for (const fs::path& root : roots) {
    const fs::path r = fs::weakly_canonical(root, ec);
    if (ec) continue;
    const auto [root_end, folder_it] = std::mismatch(r.begin(), r.end(), canonical.begin(), canonical.end());
    if (root_end == r.end()) return true;
  }
  return false;
}

std::string HomeFolder() {
  const char* home = std::getenv("HOME");
  std::error_code ec;
  return home && *home ? std::string(home) : fs::current_path(ec).string();
}

std::string StartFolder(const AppState& state, const ShellState& shell, BrowsePurpose purpose) {
  std::error_code ec;
  const bool writes = PurposeWrites(purpose);
  // Files written never go into the bundled sample's folder unless the user goes there.
  auto usable = [&](const std::string& folder) {
    return !folder.empty() && fs::is_directory(folder, ec) && !(writes && IsBundledSampleFolder(folder));
  };
  // Saving and exporting go next to the project, else where the user last wrote that kind of
  // file or last went, else home; opening and adding photos where the last file of that
  // kind came from.
  std::vector<std::string> candidates;
  const std::vector<std::string> same_kind = RecentFilesWith(shell.recent_files, PurposeExtensions(purpose));
  if (writes) {
    candidates.push_back(ProjectFolder(state));
    for (const std::string& file : same_kind) candidates.push_back(ParentFolder(file));
  } else {
    if (!same_kind.empty()) candidates.push_back(ParentFolder(same_kind.front()));
    candidates.push_back(ProjectFolder(state));
  }
  for (const std::string& folder : shell.recent_files.folders) candidates.push_back(folder);
  for (const std::string& folder : candidates) {
    if (usable(folder)) return folder;
  }
  return writes ? HomeFolder() : fs::current_path(ec).string();
}

void CloseBrowser(ShellState* shell) {
  shell->dialog = Dialog::kNone;
  ImGui::CloseCurrentPopup();
}

void SaveRecent(AppState* state, const ShellState& shell) {
  if (shell.recent_files_path.empty()) return;
  std::string error;
  if (!SaveRecentFiles(shell.recent_files_path, shell.recent_files, &error)) {
    state->Log(LogLevel::kWarning, "Recent files not kept: " + error);
  }
}

std::string PhotoExtensionList() {
  std::string list;
  for (const std::string& e : PurposeExtensions(BrowsePurpose::kAddPhoto)) list += (list.empty() ? "" : ", ") + e;
  return list;
}

}  // namespace

void OpenFileBrowser(AppState* state, ShellState* shell, Dialog dialog, const std::string& name) {
  const BrowsePurpose purpose = PurposeOf(dialog);
  std::string proposed = name;
  if (proposed.empty() && purpose == BrowsePurpose::kSaveProject) {
    proposed = state->project_path.empty() ? "untitled.facet" : fs::path(state->project_path).filename().string();
  }
  StartFileDialog(&shell->file_dialog, purpose, StartFolder(*state, *shell, purpose), proposed, ProjectFolder(*state));
  OpenDialog(shell, dialog);
}

void DrawFileBrowser(AppState* state, ShellState* shell) {
  const FileDialogResult result = DrawFileDialog(state, &shell->file_dialog, shell->recent_files, state->time_s);
  if (result.outcome == FileDialogOutcome::kCancelled) {
    shell->after_save = Dialog::kNone;  // the question's quit, new or open is off too
    CloseBrowser(shell);
    return;
  }
  if (result.outcome != FileDialogOutcome::kChosen) return;
  const BrowsePurpose purpose = shell->file_dialog.purpose;
  if (purpose == BrowsePurpose::kOpenProject && state->document.dirty()) {
    ImGui::CloseCurrentPopup();
    OpenDialog(shell, Dialog::kConfirmOpen, result.path);
    return;
  }
  std::string error;
  if (RunAppCommand(state, shell, CommandOf(purpose), {result.path}, &error)) {
    CloseBrowser(shell);
    if (purpose == BrowsePurpose::kSaveProject && shell->after_save != Dialog::kNone) {
      const Dialog question = std::exchange(shell->after_save, Dialog::kNone);
      ProceedAfterConfirm(state, shell, question, shell->after_save_path);
    }
  } else {
    shell->file_dialog.error = error;
  }
}

void OpenProjectAsking(AppState* state, ShellState* shell, const std::string& path) {
  if (state->document.dirty()) {
    OpenDialog(shell, Dialog::kConfirmOpen, path);
    return;
  }
  std::string error;
  RunAppCommand(state, shell, "open", {path}, &error);  // a failure is in the log
}

void NoteRecentFile(AppState* state, ShellState* shell, const std::string& path) {
  AddRecentFile(&shell->recent_files, path);
  SaveRecent(state, *shell);
}

void ClearRecentFiles(AppState* state, ShellState* shell) {
  shell->recent_files = RecentFiles();
  SaveRecent(state, *shell);
}

void UseRecentFilesIn(AppState* state, ShellState* shell, const std::string& config_dir) {
  shell->recent_files_path = RecentFilesPath(config_dir);
  if (shell->recent_files_path.empty()) return;
  std::error_code ec;
  if (!fs::exists(shell->recent_files_path, ec)) return;
  std::string error;
  if (!LoadRecentFiles(shell->recent_files_path, &shell->recent_files, &error)) {
    state->Log(LogLevel::kWarning, "Recent files not restored (" + error + ")");
  }
}

void HandleDroppedFiles(AppState* state, ShellState* shell) {
  if (shell->dropped_paths.empty()) return;
  const std::vector<std::string> paths = std::move(shell->dropped_paths);
  shell->dropped_paths.clear();
  const bool browsing = IsFileBrowserDialog(shell->dialog);
  if (browsing) {
    // Into the open browser: a folder is listed, a file is listed in its folder and named.
    FileDialogState& dialog = shell->file_dialog;
    const std::string path = NormalizePath("", paths.front());
    std::error_code ec;
    const bool folder = fs::is_directory(path, ec);
    dialog.folder = folder ? path : ParentFolder(path);
    dialog.path_field = dialog.folder;
    dialog.selected = folder ? std::string() : fs::path(path).filename().string();
    if (!folder) dialog.name_field = dialog.selected;
    dialog.error.clear();
    dialog.confirm_overwrite.clear();
    dialog.listing_stale = true;
    dialog.scroll_to_selected = true;
    return;
  }
  if (shell->dialog != Dialog::kNone) {
    state->Log(LogLevel::kWarning, "Dropped files ignored: answer the open dialog first");
    return;
  }
  const DroppedFiles dropped = ClassifyDroppedPaths(paths);
  for (const std::string& path : dropped.unknown) {
    std::error_code ec;
    const std::string name = fs::path(path).filename().string();
    std::string extension = fs::path(path).extension().string();
    for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if ((extension == ".obj" || extension == ".glb" || extension == ".gltf") && fs::is_regular_file(path, ec)) {
      // A mesh made elsewhere comes in as reference geometry (one undoable edit).
      std::string error;
      RunAppCommand(state, shell, "reference", {"add " + path}, &error);
      continue;
    }
    if (fs::is_directory(path, ec)) {
      state->Log(LogLevel::kError, "Dropped " + name + " is a folder: drop a project (.facet) or photos");
    } else if (!fs::exists(path, ec)) {
      state->Log(LogLevel::kError, "Dropped " + path + " does not exist");
    } else {
      state->Log(LogLevel::kError,
                 "Dropped " + name + " is neither a Facet project (.facet) nor a photo (" + PhotoExtensionList() +
                     ") nor a reference mesh (.obj, .glb, .gltf)");
    }
  }
  if (!dropped.projects.empty()) {
    if (dropped.projects.size() > 1 || !dropped.photos.empty()) {
      state->Log(LogLevel::kWarning, "Dropped " + std::to_string(dropped.projects.size() + dropped.photos.size()) +
                                         " files with a project: only " +
                                         fs::path(dropped.projects.front()).filename().string() +
                                         " is opened; drop photos onto it once it is open");
    }
    OpenProjectAsking(state, shell, dropped.projects.front());
    return;
  }
  // One undoable edit per photo, the same as File > Add photo; a bad one is logged and the
  // others still come in.
  for (const std::string& photo : dropped.photos) {
    std::string error;
    RunAppCommand(state, shell, "add-photo", {photo}, &error);
  }
}

}  // namespace facet::app
