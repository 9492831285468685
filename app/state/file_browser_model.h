// The file browser's model, without ImGui: which files each use of the browser offers,
// listing a folder (folders first, then files, each sorted case-insensitively; hidden
// entries and other extensions left out unless asked), the parent of a folder, what a typed
// path means, what a drop onto the window holds, and the recent files and folders that
// persist in the config folder. The dialog that draws it is app/panels/file_dialog.h.
// Paths are UTF-8 strings as std::filesystem gives them on Linux.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace facet::app {

// The four uses of the one browser.
enum class BrowsePurpose {
  kOpenProject,
  kSaveProject,
  kExport,
  kAddPhoto,
  kRelinkPhoto,
  kAddReference,
  kExportView,
  kExportColmap,  // cameras.txt in the COLMAP model's folder (images.txt, points3D.txt beside it)
  kExportTransforms,
};

// The extensions a purpose offers, lower case with the dot; the first is the one Save as and
// Export append to a name without one (".facet", ".glb").
const std::vector<std::string>& PurposeExtensions(BrowsePurpose purpose);
const char* PurposeTitle(BrowsePurpose purpose);        // "Open project", "Save project as", ...
const char* PurposeVerb(BrowsePurpose purpose);         // the confirm button: "Open", "Save", ...
const char* PurposeFilterLabel(BrowsePurpose purpose);  // "Facet projects (*.facet)"
// Save as and Export write: a name that does not exist yet is fine, an existing one asks first.
bool PurposeWrites(BrowsePurpose purpose);

// Whether the file name ends in one of `extensions` (".jpg"), compared case-insensitively.
bool HasExtension(const std::string& name, const std::vector<std::string>& extensions);
bool IsProjectFile(const std::string& path);  // .facet
bool IsPhotoFile(const std::string& path);    // what File > Add photo reads: .jpg .jpeg .png .tif ...
// `path` with the purpose's first extension appended unless it has one of its extensions
// already ("house" -> "house.facet"; "house.FACET" stays).
std::string WithPurposeExtension(const std::string& path, BrowsePurpose purpose);

struct BrowserEntry {
  std::string name;  // file name only
  bool is_folder = false;
  std::uintmax_t size_bytes = 0;  // files only; 0 when unknown
};

struct ListOptions {
  std::vector<std::string> extensions;  // files shown; empty: all
  bool all_files = false;               // ignore `extensions`
  bool show_hidden = false;             // names starting with '.'
  size_t max_entries = 5000;            // a huge folder is cut here (FolderListing::truncated)
};

struct FolderListing {
  std::string folder;  // absolute, normalised, without a trailing '/' (except "/")
  std::vector<BrowserEntry> entries;
  bool truncated = false;
  std::string error;  // empty when the folder was read; else what went wrong, for the dialog
  bool ok() const { return error.empty(); }
};

// Lists `folder` (absolute, or relative to the working directory): folders first, then the
// files that pass `options`, each group ordered by CaseInsensitiveLess. A folder that does
// not exist, is a file or cannot be read gives an empty listing with a readable error; an
// entry whose type cannot be read is listed as a file.
FolderListing ListFolder(const std::string& folder, const ListOptions& options);

// Orders by the case-folded ASCII bytes, ties broken by the exact bytes, so that the order is
// total: "a" < "B" < "b" < "c".
bool CaseInsensitiveLess(const std::string& a, const std::string& b);

// The folder above `folder` (absolute, normalised); the root is its own parent.
std::string ParentFolder(const std::string& folder);
// `folder`/`name`, normalised.
std::string JoinPath(const std::string& folder, const std::string& name);
// Absolute and lexically normal, "~" and "~/..." expanded from $HOME, relative paths taken
// from `base_folder`, no trailing '/' except for the root.
std::string NormalizePath(const std::string& base_folder, const std::string& path);
// "12 KB", "3.4 MB": for the size column.
std::string FormatSize(std::uintmax_t bytes);

// What the user typed into the path or name field means once Enter is pressed.
enum class TypedPathKind {
  kEmpty,         // nothing typed
  kFolder,        // an existing folder: go there
  kExistingFile,  // an existing file: choose it
  kNewFile,       // (writing only) a name in an existing folder: choose it
  kMissing,       // nothing there (or its folder is missing): `error` says which
};
struct TypedPath {
  TypedPathKind kind = TypedPathKind::kEmpty;
  std::string path;   // NormalizePath of what was typed
  std::string error;  // for kMissing
};
TypedPath ResolveTypedPath(const std::string& current_folder, const std::string& typed, bool allow_new_file);

// What was dropped onto the window, by kind, in drop order.
struct DroppedFiles {
  std::vector<std::string> projects;
  std::vector<std::string> photos;
  std::vector<std::string> unknown;  // folders and files of other kinds
};
DroppedFiles ClassifyDroppedPaths(const std::vector<std::string>& paths);

// Recently used files (projects, photos, exports) and the folders they were in, most recent
// first, absolute and normalised, each at most once.
struct RecentFiles {
  static constexpr size_t kMaxFiles = 16;
  static constexpr size_t kMaxFolders = 8;
  std::vector<std::string> files;
  std::vector<std::string> folders;
};
// Puts `path` first among the files and its folder first among the folders (moving them up
// when already listed), dropping the oldest beyond the capacity.
void AddRecentFile(RecentFiles* recent, const std::string& path);
void AddRecentFolder(RecentFiles* recent, const std::string& folder);
// The recent files that have one of `extensions` (all when empty), most recent first.
std::vector<std::string> RecentFilesWith(const RecentFiles& recent, const std::vector<std::string>& extensions);

// The recent-files file: JSON ({"format": "facet-recent", "version": 1, ...}). Malformed
// content gives false with *error set and leaves *recent untouched.
std::string RecentFilesToJson(const RecentFiles& recent);
bool RecentFilesFromJson(const std::string& text, RecentFiles* recent, std::string* error);
// `config_dir`/recent.json; empty when `config_dir` is.
std::string RecentFilesPath(const std::string& config_dir);
bool LoadRecentFiles(const std::string& path, RecentFiles* recent, std::string* error);
// Atomic: the previous file stays whole when writing fails. Creates the folder.
bool SaveRecentFiles(const std::string& path, const RecentFiles& recent, std::string* error);

}  // namespace facet::app
