#include "app/panels/file_dialog.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>

#include <imgui.h>
#include <imgui_stdlib.h>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>  // key codes only

#include "app/panels/widgets.h"

namespace facet::app {
namespace {

namespace fs = std::filesystem;

constexpr double kRelistAfterS = 2.0;
constexpr float kSideColumnWidthPx = 190.0f;
const ImVec4 kFolderText(0.55f, 0.75f, 1.00f, 1.0f);

std::string FileNameOf(const std::string& path) {
  const std::string name = fs::path(path).filename().string();
  return name.empty() ? path : name;
}

void GoToFolder(FileDialogState* dialog, const std::string& folder) {
  dialog->folder = NormalizePath(dialog->folder, folder);
  dialog->path_field = dialog->folder;
  dialog->selected.clear();
  dialog->error.clear();
  dialog->confirm_overwrite.clear();
  dialog->listing_stale = true;
}

void Relist(FileDialogState* dialog, double time_s) {
  ListOptions options;
  options.extensions = PurposeExtensions(dialog->purpose);
  options.all_files = dialog->all_files;
  options.show_hidden = dialog->show_hidden;
  dialog->listing = ListFolder(dialog->folder, options);
  dialog->listing_stale = false;
  dialog->listed_time_s = time_s;
}

constexpr const char* kColmapCamerasFile = "cameras.txt";

// A COLMAP model is a folder, chosen by its cameras.txt: a name typed that is neither an
// existing folder (entered, as always) nor cameras.txt names the model's folder.
std::string AsColmapCamerasFile(const FileDialogState& dialog, const std::string& typed) {
  const TypedPath as_typed = ResolveTypedPath(dialog.folder, typed, true);
  if (as_typed.kind == TypedPathKind::kEmpty || as_typed.kind == TypedPathKind::kFolder) return typed;
  if (fs::path(as_typed.path).filename() == kColmapCamerasFile) return typed;
  return JoinPath(as_typed.path, kColmapCamerasFile);
}

// What Enter or the confirm button does with a typed or selected path: go into a folder,
// choose a file, or explain why not.
FileDialogResult Accept(FileDialogState* dialog, const std::string& typed_text) {
  const bool writes = PurposeWrites(dialog->purpose);
  const bool colmap = dialog->purpose == BrowsePurpose::kExportColmap;
  const std::string typed = colmap ? AsColmapCamerasFile(*dialog, typed_text) : typed_text;
  TypedPath target = ResolveTypedPath(dialog->folder, typed, writes);
  if (colmap && target.kind == TypedPathKind::kMissing) {
    // A new model folder, created by the export, in a folder that is there.
    std::error_code ec;
    if (fs::is_directory(ParentFolder(ParentFolder(target.path)), ec)) return {FileDialogOutcome::kChosen, target.path};
  }
  if (target.kind == TypedPathKind::kMissing && !writes) {
    // "house" opens house.facet when that is what is there.
    const TypedPath with_extension =
        ResolveTypedPath(dialog->folder, WithPurposeExtension(typed, dialog->purpose), writes);
    if (with_extension.kind == TypedPathKind::kExistingFile) target = with_extension;
  }
  switch (target.kind) {
    case TypedPathKind::kEmpty:
      dialog->error = writes ? "Type a file name." : "Choose a file, or type its name or path.";
      return {};
    case TypedPathKind::kFolder:
      if (typed == dialog->name_field) dialog->name_field = colmap ? kColmapCamerasFile : "";
      GoToFolder(dialog, target.path);
      return {};
    case TypedPathKind::kMissing: dialog->error = target.error; return {};
    case TypedPathKind::kExistingFile:
      if (writes) {
        dialog->confirm_overwrite = target.path;
        return {};
      }
      return {FileDialogOutcome::kChosen, target.path};
    case TypedPathKind::kNewFile: {
      const std::string path = WithPurposeExtension(target.path, dialog->purpose);
      std::error_code ec;
      if (fs::exists(path, ec)) {
        dialog->confirm_overwrite = path;
        return {};
      }
      return {FileDialogOutcome::kChosen, path};
    }
  }
  return {};
}

// The side column: places, recent folders, recent files of the purpose's kinds.
void DrawSideColumn(AppState* state, FileDialogState* dialog, const RecentFiles& recent, std::string* go_to,
                    std::string* choose_file, bool* accept_file) {
  auto place = [&](const char* label, const std::string& folder, const std::string& record_name) {
    if (folder.empty()) return;
    if (ImGui::Selectable(label, NormalizePath("", folder) == dialog->folder)) *go_to = folder;
    RecordItem(state, "file.place/" + record_name);
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", folder.c_str());
  };
  ImGui::TextColored(kDimText, "Places");
  place("Home", dialog->home_folder, "home");
  place("Project folder", dialog->project_folder, "project");
  std::error_code ec;
  place("Working folder", fs::current_path(ec).string(), "working");
  if (!recent.folders.empty()) {
    ImGui::Spacing();
    ImGui::TextColored(kDimText, "Recent folders");
    for (const std::string& folder : recent.folders) {
      ImGui::PushID(folder.c_str());
      if (ImGui::Selectable((FileNameOf(folder) + "/").c_str(), folder == dialog->folder)) *go_to = folder;
      RecordItem(state, "file.recent_folder/" + folder);
      if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", folder.c_str());
      ImGui::PopID();
    }
  }
  const std::vector<std::string> files =
      RecentFilesWith(recent, dialog->all_files ? std::vector<std::string>() : PurposeExtensions(dialog->purpose));
  if (!files.empty()) {
    ImGui::Spacing();
    ImGui::TextColored(kDimText, "Recent files");
    for (const std::string& file : files) {
      const bool exists = fs::exists(file, ec);
      ImGui::PushID(file.c_str());
      if (!exists) ImGui::PushStyleColor(ImGuiCol_Text, kDimText);
      if (ImGui::Selectable(FileNameOf(file).c_str(), false, ImGuiSelectableFlags_AllowDoubleClick)) {
        *choose_file = file;
        *accept_file = ImGui::IsMouseDoubleClicked(ImGuiMouseButton_Left);
      }
      if (!exists) ImGui::PopStyleColor();
      RecordItem(state, "file.recent_file/" + file);
      if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s%s", file.c_str(), exists ? "" : " (no longer there)");
      ImGui::PopID();
    }
  }
}

// The folder's entries in a two-column table; sets *activate on a double-click.
void DrawEntries(AppState* state, FileDialogState* dialog, const ImVec2& size, bool* activate) {
  const ImGuiTableFlags flags = ImGuiTableFlags_ScrollY | ImGuiTableFlags_RowBg | ImGuiTableFlags_BordersOuter |
                                ImGuiTableFlags_SizingStretchProp;
  if (!ImGui::BeginTable("##entries", 2, flags, size)) return;
  ImGui::TableSetupScrollFreeze(0, 1);
  ImGui::TableSetupColumn("Name", ImGuiTableColumnFlags_WidthStretch);
  ImGui::TableSetupColumn("Size", ImGuiTableColumnFlags_WidthFixed, ImGui::GetFontSize() * 5.5f);
  ImGui::TableHeadersRow();
  const FolderListing& listing = dialog->listing;
  if (!listing.ok()) {
    ImGui::TableNextRow();
    ImGui::TableNextColumn();
    ImGui::PushTextWrapPos(0.0f);
    ImGui::TextColored(kErrorText, "%s", listing.error.c_str());
    ImGui::PopTextWrapPos();
  } else if (listing.entries.empty()) {
    ImGui::TableNextRow();
    ImGui::TableNextColumn();
    ImGui::TextColored(kDimText, dialog->all_files ? "(empty folder)" : "(no folders or matching files here)");
  }
  ImGuiListClipper clipper;
  clipper.Begin(static_cast<int>(listing.entries.size()));
  int selected_index = -1;
  if (dialog->scroll_to_selected) {
    for (size_t i = 0; i < listing.entries.size(); ++i) {
      if (listing.entries[i].name == dialog->selected) selected_index = static_cast<int>(i);
    }
    if (selected_index >= 0) clipper.ForceDisplayRangeByIndices(selected_index, selected_index + 1);
  }
  while (clipper.Step()) {
    for (int i = clipper.DisplayStart; i < clipper.DisplayEnd; ++i) {
      const BrowserEntry& e = listing.entries[i];
      ImGui::TableNextRow();
      ImGui::TableNextColumn();
      const bool selected = e.name == dialog->selected;
      if (e.is_folder) ImGui::PushStyleColor(ImGuiCol_Text, kFolderText);
      const std::string label = e.is_folder ? e.name + "/" : e.name;
      ImGui::PushID(i);
      if (ImGui::Selectable(label.c_str(), selected,
                            ImGuiSelectableFlags_AllowDoubleClick | ImGuiSelectableFlags_SpanAllColumns)) {
        dialog->selected = e.name;
        dialog->error.clear();
        if (!e.is_folder)
          dialog->name_field = e.name;
        else if (!PurposeWrites(dialog->purpose))
          dialog->name_field.clear();  // Open now means "go into this folder"
        if (ImGui::IsMouseDoubleClicked(ImGuiMouseButton_Left)) *activate = true;
      }
      ImGui::PopID();
      if (e.is_folder) ImGui::PopStyleColor();
      RecordItem(state, "file.entry/" + e.name);
      if (i == selected_index) {
        ImGui::SetScrollHereY(0.5f);
        dialog->scroll_to_selected = false;
      }
      ImGui::TableNextColumn();
      if (!e.is_folder) ImGui::TextColored(kDimText, "%s", FormatSize(e.size_bytes).c_str());
    }
  }
  if (listing.truncated) {
    ImGui::TableNextRow();
    ImGui::TableNextColumn();
    ImGui::TextColored(kWarningText, "(only the first %zu entries are listed)", listing.entries.size());
  }
  ImGui::EndTable();
}

// Save as, Export: when the name field first takes the keyboard, only the stem is selected,
// so that typing replaces "untitled" and keeps ".facet" (as desktop file choosers do).
int SelectStem(ImGuiInputTextCallbackData* data) {
  auto* dialog = static_cast<FileDialogState*>(data->UserData);
  if (!dialog->select_stem_pending) return 0;
  dialog->select_stem_pending = false;
  const std::string name(data->Buf, static_cast<size_t>(data->BufTextLen));
  const size_t dot = name.rfind('.');
  const int stem = dot == std::string::npos || dot == 0 ? data->BufTextLen : static_cast<int>(dot);
  data->SelectionStart = 0;
  data->SelectionEnd = stem;
  data->CursorPos = stem;
  return 0;
}

// Up/Down move the highlight through the list while no text field has the keyboard.
void MoveSelection(FileDialogState* dialog, int step) {
  const std::vector<BrowserEntry>& entries = dialog->listing.entries;
  if (entries.empty()) return;
  int index = -1;
  for (size_t i = 0; i < entries.size(); ++i) {
    if (entries[i].name == dialog->selected) index = static_cast<int>(i);
  }
  index = index < 0 ? (step > 0 ? 0 : static_cast<int>(entries.size()) - 1)
                    : std::clamp(index + step, 0, static_cast<int>(entries.size()) - 1);
  dialog->selected = entries[index].name;
  if (!entries[index].is_folder) dialog->name_field = entries[index].name;
  dialog->scroll_to_selected = true;
}

}  // namespace

void StartFileDialog(FileDialogState* dialog, BrowsePurpose purpose, const std::string& folder, const std::string& name,
                     const std::string& project_folder) {
  const bool keep_toggles = dialog->purpose == purpose;
  const bool all_files = keep_toggles && dialog->all_files;
  const bool show_hidden = dialog->show_hidden;
  *dialog = FileDialogState();
  dialog->purpose = purpose;
  dialog->all_files = all_files;
  dialog->show_hidden = show_hidden;
  const char* home = std::getenv("HOME");
  dialog->home_folder = home && *home ? NormalizePath("", home) : std::string();
  dialog->project_folder = project_folder;
  std::error_code ec;
  std::string start = folder;
  if (start.empty() || !fs::is_directory(start, ec)) start = fs::current_path(ec).string();
  GoToFolder(dialog, start);
  dialog->name_field = name;
  // A COLMAP model's name is its folder's, typed over the whole of "cameras.txt".
  dialog->select_stem_pending = PurposeWrites(purpose) && !name.empty() && purpose != BrowsePurpose::kExportColmap;
}

FileDialogResult DrawFileDialog(AppState* state, FileDialogState* dialog, const RecentFiles& recent, double time_s) {
  if (dialog->listing_stale || time_s - dialog->listed_time_s > kRelistAfterS || time_s < dialog->listed_time_s) {
    Relist(dialog, time_s);
  }
  const bool writes = PurposeWrites(dialog->purpose);
  const ImGuiStyle& style = ImGui::GetStyle();
  FileDialogResult result;
  bool enter_used = false;
  std::string go_to;               // a folder to list after this frame's widgets
  std::string choose_file;         // a recent file clicked
  bool accept_choice = false;      // ... double-clicked
  bool activate_selected = false;  // an entry double-clicked, or Enter on the list
  std::string accept_text;         // a path to Accept after the widgets
  bool accept_requested = false;

  // The path line: Parent, then the folder as an editable path.
  if (ImGui::Button("Parent")) go_to = ParentFolder(dialog->folder);
  RecordItem(state, "file.parent");
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("The folder above (Backspace in the list)");
  ImGui::SameLine();
  ImGui::SetNextItemWidth(-1.0f);
  if ((dialog->focus_pending && !writes) || dialog->refocus_path) ImGui::SetKeyboardFocusHere();
  dialog->refocus_path = false;
  bool enter_in_path = false, enter_in_name = false;
  if (ImGui::InputText("##path", &dialog->path_field,
                       ImGuiInputTextFlags_EnterReturnsTrue | ImGuiInputTextFlags_AutoSelectAll)) {
    accept_requested = true;
    accept_text = dialog->path_field;
    enter_used = enter_in_path = true;
  }
  RecordItem(state, "file.path");
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Type a folder or a file path and press Enter (~ is your home)");

  // Side column and entries.
  const float footer_h =
      ImGui::GetFrameHeightWithSpacing() * 2 + ImGui::GetTextLineHeightWithSpacing() + style.ItemSpacing.y;
  const float body_h = std::max(120.0f, ImGui::GetContentRegionAvail().y - footer_h);
  ImGui::BeginChild("##side", ImVec2(kSideColumnWidthPx, body_h), true);
  DrawSideColumn(state, dialog, recent, &go_to, &choose_file, &accept_choice);
  ImGui::EndChild();
  ImGui::SameLine();
  DrawEntries(state, dialog, ImVec2(ImGui::GetContentRegionAvail().x, body_h), &activate_selected);

  // Name, filter, buttons.
  const float label_w = ImGui::CalcTextSize("Name").x + style.ItemSpacing.x;
  ImGui::AlignTextToFramePadding();
  ImGui::TextUnformatted("Name");
  ImGui::SameLine(label_w + style.WindowPadding.x);
  const float filter_w = ImGui::CalcTextSize(PurposeFilterLabel(dialog->purpose)).x + ImGui::GetFrameHeight() * 2;
  ImGui::SetNextItemWidth(ImGui::GetContentRegionAvail().x - filter_w - style.ItemSpacing.x);
  if ((dialog->focus_pending && writes) || dialog->refocus_name) ImGui::SetKeyboardFocusHere();
  dialog->refocus_name = false;
  if (ImGui::InputText(
          "##name", &dialog->name_field,
          ImGuiInputTextFlags_EnterReturnsTrue | ImGuiInputTextFlags_AutoSelectAll | ImGuiInputTextFlags_CallbackAlways,
          SelectStem, dialog)) {
    accept_requested = true;
    accept_text = dialog->name_field;
    enter_used = enter_in_name = true;
  }
  RecordItem(state, "file.name");
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip(writes ? "The file to write; the extension is added when missing" : "The file to open");
  dialog->focus_pending = false;
  ImGui::SameLine();
  ImGui::SetNextItemWidth(filter_w);
  const char* kAllFilesLabel = "All files (*)";
  const bool filter_open =
      ImGui::BeginCombo("##filter", dialog->all_files ? kAllFilesLabel : PurposeFilterLabel(dialog->purpose));
  if (!filter_open) RecordItem(state, "file.filter");
  if (filter_open) {
    for (const bool all : {false, true}) {
      if (ImGui::Selectable(all ? kAllFilesLabel : PurposeFilterLabel(dialog->purpose), dialog->all_files == all) &&
          dialog->all_files != all) {
        dialog->all_files = all;
        dialog->listing_stale = true;
      }
      RecordItem(state, all ? "file.filter/all" : "file.filter/purpose");
    }
    ImGui::EndCombo();
  }

  if (!dialog->error.empty()) {
    ImGui::TextColored(kErrorText, "%s", dialog->error.c_str());
  } else if (!dialog->confirm_overwrite.empty()) {
    ImGui::TextColored(kWarningText, "%s already exists. Replace it?", FileNameOf(dialog->confirm_overwrite).c_str());
  } else {
    ImGui::TextColored(kDimText, "%s", dialog->folder.c_str());
  }

  if (ImGui::Checkbox("Hidden files", &dialog->show_hidden)) dialog->listing_stale = true;
  RecordItem(state, "file.hidden");
  if (dialog->purpose == BrowsePurpose::kExport) {
    // The texture's resolution: a view setting of the export (app/state/texture_choices.h).
    ImGui::SameLine();
    const std::string label = "Texels per " + state->document.project().units;
    ImGui::AlignTextToFramePadding();
    ImGui::TextUnformatted(label.c_str());
    ImGui::SameLine();
    ImGui::SetNextItemWidth(ImGui::GetFontSize() * 5.0f);
    double texels = state->texture.export_texels_per_unit;
    if (ImGui::InputDouble("##texels_per_unit", &texels, 0.0, 0.0, "%.6g")) {
      state->texture.export_texels_per_unit = std::isfinite(texels) ? std::max(0.0, texels) : 0.0;
    }
    RecordItem(state, "file.texels_per_unit");
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip(
          "Texture resolution of the exported model, capped by the 8192 atlas page; 0: from the "
          "photos (one texel per photo pixel of each face's best view)");
  }
  const float button_w = ImGui::GetFontSize() * 6.5f;
  ImGui::SameLine(ImGui::GetWindowContentRegionMax().x - 2 * button_w - style.ItemSpacing.x);
  const bool escape = ImGui::IsKeyPressed(GLFW_KEY_ESCAPE, false);
  const bool enter =
      !enter_used && (ImGui::IsKeyPressed(GLFW_KEY_ENTER, false) || ImGui::IsKeyPressed(GLFW_KEY_KP_ENTER, false));
  if (!dialog->confirm_overwrite.empty()) {
    if (ImGui::Button("Replace", ImVec2(button_w, 0)) || enter) {
      result = {FileDialogOutcome::kChosen, dialog->confirm_overwrite};
      dialog->confirm_overwrite.clear();
    }
    RecordItem(state, "file.replace");
    ImGui::SameLine();
    if (ImGui::Button("Cancel", ImVec2(button_w, 0)) || escape) dialog->confirm_overwrite.clear();
    RecordItem(state, "file.cancel");
    return result;
  }
  if (ImGui::Button(PurposeVerb(dialog->purpose), ImVec2(button_w, 0))) {
    // A folder highlighted in the list is entered; else the name is used.
    activate_selected = true;
    accept_text = dialog->name_field;
  }
  RecordItem(state, "file.confirm");
  ImGui::SameLine();
  if (ImGui::Button("Cancel", ImVec2(button_w, 0)) || escape) return {FileDialogOutcome::kCancelled, {}};
  RecordItem(state, "file.cancel");

  // Keys of the list, while no text field has the keyboard.
  if (!ImGui::IsAnyItemActive() && !enter_used) {
    if (enter) {
      activate_selected = true;
      accept_text = dialog->name_field;
    }
    if (ImGui::IsKeyPressed(GLFW_KEY_DOWN)) MoveSelection(dialog, 1);
    if (ImGui::IsKeyPressed(GLFW_KEY_UP)) MoveSelection(dialog, -1);
    if (ImGui::IsKeyPressed(GLFW_KEY_BACKSPACE)) go_to = ParentFolder(dialog->folder);
  }

  // Act once all widgets are drawn (the listing must not change under the loop above).
  if (!go_to.empty()) {
    GoToFolder(dialog, go_to);
    return result;
  }
  if (!choose_file.empty()) {
    GoToFolder(dialog, ParentFolder(choose_file));
    dialog->selected = FileNameOf(choose_file);
    dialog->name_field = dialog->selected;
    dialog->scroll_to_selected = true;
    if (accept_choice) return Accept(dialog, choose_file);
    return result;
  }
  if (activate_selected) {
    const auto it = std::find_if(dialog->listing.entries.begin(), dialog->listing.entries.end(),
                                 [&](const BrowserEntry& e) { return e.name == dialog->selected; });
    if (it != dialog->listing.entries.end() && it->is_folder) {
      GoToFolder(dialog, JoinPath(dialog->folder, it->name));
      return result;
    }
    if (accept_text.empty() && it != dialog->listing.entries.end()) accept_text = it->name;
    accept_requested = true;
  }
  if (accept_requested) {
    const std::string folder_before = dialog->folder;
    result = Accept(dialog, accept_text);
    const bool entered_folder = dialog->folder != folder_before;
    dialog->refocus_path = entered_folder && enter_in_path;
    dialog->refocus_name = entered_folder && enter_in_name;
  }
  return result;
}

}  // namespace facet::app
