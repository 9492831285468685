#include "app/state/file_browser_model.h"

#include "core/util/file_read.h"
#include "core/util/utf8.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <system_error>

#include <nlohmann/json.hpp>

#include "core/io/project_io.h"

namespace facet::app {
namespace {

namespace fs = std::filesystem;

char FoldCase(char c) { return static_cast<char>(std::tolower(static_cast<unsigned char>(c))); }

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), FoldCase);
  return s;
}

const std::vector<std::string> kProjectExtensions = {".facet"};
const std::vector<std::string> kExportExtensions = {".glb", ".obj"};
// What Facet writes, and glTF's JSON form, which other tools write as often as .glb.
const std::vector<std::string> kReferenceExtensions = {".glb", ".gltf", ".obj"};
const std::vector<std::string> kViewExtensions = {".png"};
const std::vector<std::string> kColmapExtensions = {".txt"};
const std::vector<std::string> kTransformsExtensions = {".json"};
// What OpenCV's imgcodecs (core/image/image_io.h) reads on Debian 12.
const std::vector<std::string> kPhotoExtensions = {".jpg", ".jpeg", ".png", ".tif", ".tiff", ".bmp", ".webp"};

std::string WithoutTrailingSeparator(const fs::path& p) {
  std::string s = p.string();
  while (s.size() > 1 && s.back() == '/') s.pop_back();
  return s;
}

std::string ErrorText(const std::error_code& ec) {
  std::string text = ec.message();
  if (!text.empty()) text[0] = static_cast<char>(std::tolower(static_cast<unsigned char>(text[0])));
  return text;
}

bool ReadTextFile(const std::string& path, std::string* text) {
  std::string error;
  return ReadRegularFile(path, kMaxTextFileBytes, text, &error);
}

// Moves `item` to the front of `list` (inserting it when absent), keeping at most `capacity`.
void PushFront(std::vector<std::string>* list, const std::string& item, size_t capacity) {
  std::erase(*list, item);
  list->insert(list->begin(), item);
  if (list->size() > capacity) list->resize(capacity);
}

}  // namespace

const std::vector<std::string>& PurposeExtensions(BrowsePurpose purpose) {
  switch (purpose) {
    case BrowsePurpose::kOpenProject:
    case BrowsePurpose::kSaveProject: return kProjectExtensions;
    case BrowsePurpose::kExport: return kExportExtensions;
    case BrowsePurpose::kExportView: return kViewExtensions;
    case BrowsePurpose::kExportColmap: return kColmapExtensions;
    case BrowsePurpose::kExportTransforms: return kTransformsExtensions;
    case BrowsePurpose::kAddPhoto:
    case BrowsePurpose::kRelinkPhoto: return kPhotoExtensions;
    case BrowsePurpose::kAddReference: return kReferenceExtensions;
  }
  return kProjectExtensions;
}

const char* PurposeTitle(BrowsePurpose purpose) {
  switch (purpose) {
    case BrowsePurpose::kOpenProject: return "Open project";
    case BrowsePurpose::kSaveProject: return "Save project as";
    case BrowsePurpose::kExport: return "Export model";
    case BrowsePurpose::kExportView: return "Export view";
    case BrowsePurpose::kExportColmap: return "Export cameras (COLMAP)";
    case BrowsePurpose::kExportTransforms: return "Export cameras (transforms.json)";
    case BrowsePurpose::kAddPhoto: return "Add photo";
    case BrowsePurpose::kRelinkPhoto: return "Relink photo";
    case BrowsePurpose::kAddReference: return "Add reference mesh";
  }
  return "";
}

const char* PurposeVerb(BrowsePurpose purpose) {
  switch (purpose) {
    case BrowsePurpose::kOpenProject: return "Open";
    case BrowsePurpose::kSaveProject: return "Save";
    case BrowsePurpose::kExport:
    case BrowsePurpose::kExportView:
    case BrowsePurpose::kExportColmap:
    case BrowsePurpose::kExportTransforms: return "Export";
    case BrowsePurpose::kAddPhoto: return "Add";
    case BrowsePurpose::kRelinkPhoto: return "Relink";
    case BrowsePurpose::kAddReference: return "Add";
  }
  return "";
}

const char* PurposeFilterLabel(BrowsePurpose purpose) {
  switch (purpose) {
    case BrowsePurpose::kOpenProject:
    case BrowsePurpose::kSaveProject: return "Facet projects (*.facet)";
    case BrowsePurpose::kExport: return "Models (*.glb, *.obj)";
    case BrowsePurpose::kExportView: return "PNG pictures (*.png)";
    case BrowsePurpose::kExportColmap: return "COLMAP text files (*.txt)";
    case BrowsePurpose::kExportTransforms: return "JSON files (*.json)";
    case BrowsePurpose::kAddPhoto:
    case BrowsePurpose::kRelinkPhoto: return "Photos (*.jpg, *.png, *.tif, ...)";
    case BrowsePurpose::kAddReference: return "Meshes (*.obj, *.glb, *.gltf)";
  }
  return "";
}

bool PurposeWrites(BrowsePurpose purpose) {
  return purpose == BrowsePurpose::kSaveProject || purpose == BrowsePurpose::kExport ||
         purpose == BrowsePurpose::kExportView || purpose == BrowsePurpose::kExportColmap ||
         purpose == BrowsePurpose::kExportTransforms;
}

bool HasExtension(const std::string& name, const std::vector<std::string>& extensions) {
  const std::string lower = Lower(fs::path(name).extension().string());
  return !lower.empty() && std::find(extensions.begin(), extensions.end(), lower) != extensions.end();
}

bool IsProjectFile(const std::string& path) { return HasExtension(path, kProjectExtensions); }
bool IsPhotoFile(const std::string& path) { return HasExtension(path, kPhotoExtensions); }

std::string WithPurposeExtension(const std::string& path, BrowsePurpose purpose) {
  const std::vector<std::string>& extensions = PurposeExtensions(purpose);
  if (path.empty() || HasExtension(path, extensions)) return path;
  return path + extensions.front();
}

bool CaseInsensitiveLess(const std::string& a, const std::string& b) {
  const bool folded_less = std::lexicographical_compare(a.begin(), a.end(), b.begin(), b.end(),
                                                        [](char x, char y) { return FoldCase(x) < FoldCase(y); });
  if (folded_less) return true;
  const bool folded_greater = std::lexicographical_compare(b.begin(), b.end(), a.begin(), a.end(),
                                                           [](char x, char y) { return FoldCase(x) < FoldCase(y); });
  return !folded_greater && a < b;
}

std::string NormalizePath(const std::string& base_folder, const std::string& path) {
  std::string expanded = path;
  if (!expanded.empty() && expanded[0] == '~' && (expanded.size() == 1 || expanded[1] == '/')) {
    const char* home = std::getenv("HOME");
    if (home && *home) expanded = std::string(home) + expanded.substr(1);
  }
  fs::path p(expanded);
  if (p.is_relative()) {
    std::error_code ec;
    const fs::path base = base_folder.empty() ? fs::current_path(ec) : fs::path(base_folder);
    p = base / p;
    if (p.is_relative()) p = fs::absolute(p, ec);
  }
  return WithoutTrailingSeparator(p.lexically_normal());
}

std::string ParentFolder(const std::string& folder) {
  const fs::path p(NormalizePath("", folder));
  return WithoutTrailingSeparator(p.has_relative_path() ? p.parent_path() : p);
}

std::string JoinPath(const std::string& folder, const std::string& name) { return NormalizePath(folder, name); }

std::string FormatSize(std::uintmax_t bytes) {
  char text[32];
  const double b = static_cast<double>(bytes);
  if (bytes < 1024)
    std::snprintf(text, sizeof(text), "%ju B", bytes);
  else if (b < 1024.0 * 1024.0)
    std::snprintf(text, sizeof(text), "%.0f KB", b / 1024.0);
  else if (b < 1024.0 * 1024.0 * 1024.0)
    std::snprintf(text, sizeof(text), "%.1f MB", b / (1024.0 * 1024.0));
  else
    std::snprintf(text, sizeof(text), "%.1f GB", b / (1024.0 * 1024.0 * 1024.0));
  return text;
}

FolderListing ListFolder(const std::string& folder, const ListOptions& options) {
  FolderListing listing;
  listing.folder = NormalizePath("", folder);
  std::error_code ec;
  const fs::file_status status = fs::status(listing.folder, ec);
  if (!fs::exists(status) && (!ec || ec == std::errc::no_such_file_or_directory || ec == std::errc::not_a_directory)) {
    listing.error = "The folder " + listing.folder + " does not exist (any more).";
    return listing;
  }
  if (ec) {
    listing.error = "Cannot reach the folder " + listing.folder + ": " + ErrorText(ec) + ".";
    return listing;
  }
  if (!fs::is_directory(status)) {
    listing.error = listing.folder + " is not a folder.";
    return listing;
  }
  fs::directory_iterator it(listing.folder, ec);
  if (ec) {
    listing.error = "Cannot read the folder " + listing.folder + ": " + ErrorText(ec) + ".";
    return listing;
  }
  for (; it != fs::directory_iterator(); it.increment(ec)) {
    if (ec) break;
    const fs::directory_entry& e = *it;
    BrowserEntry entry;
    entry.name = e.path().filename().string();
    if (entry.name.empty() || (!options.show_hidden && entry.name[0] == '.')) continue;
    std::error_code type_ec;
    entry.is_folder = e.is_directory(type_ec);  // follows links: a link to a folder is a folder
    if (!entry.is_folder) {
      if (!options.all_files && !options.extensions.empty() && !HasExtension(entry.name, options.extensions)) continue;
      std::error_code size_ec;
      const std::uintmax_t size = e.file_size(size_ec);
      entry.size_bytes = size_ec ? 0 : size;
    }
    if (listing.entries.size() == options.max_entries) {
      listing.truncated = true;
      break;
    }
    listing.entries.push_back(std::move(entry));
  }
  if (ec) {
    // A folder that vanished or became unreadable while it was read: what was read is kept.
    listing.error = "Reading the folder " + listing.folder + " stopped: " + ErrorText(ec) + ".";
  }
  std::sort(listing.entries.begin(), listing.entries.end(), [](const BrowserEntry& a, const BrowserEntry& b) {
    if (a.is_folder != b.is_folder) return a.is_folder;
    return CaseInsensitiveLess(a.name, b.name);
  });
  return listing;
}

TypedPath ResolveTypedPath(const std::string& current_folder, const std::string& typed, bool allow_new_file) {
  TypedPath out;
  std::string trimmed = typed;
  while (!trimmed.empty() && std::isspace(static_cast<unsigned char>(trimmed.back()))) trimmed.pop_back();
  while (!trimmed.empty() && std::isspace(static_cast<unsigned char>(trimmed.front()))) trimmed.erase(0, 1);
  if (trimmed.empty()) return out;
  out.path = NormalizePath(current_folder, trimmed);
  std::error_code ec;
  const fs::file_status status = fs::status(out.path, ec);
  if (!ec && fs::is_directory(status)) {
    out.kind = TypedPathKind::kFolder;
  } else if (!ec && fs::exists(status)) {
    out.kind = TypedPathKind::kExistingFile;
  } else {
    const std::string parent = ParentFolder(out.path);
    const bool parent_is_folder = fs::is_directory(parent, ec);
    if (allow_new_file && parent_is_folder && trimmed.back() != '/') {
      out.kind = TypedPathKind::kNewFile;
    } else {
      out.kind = TypedPathKind::kMissing;
      out.error = parent_is_folder ? "There is no " + fs::path(out.path).filename().string() + " in " + parent + "."
                                   : "The folder " + parent + " does not exist.";
    }
  }
  return out;
}

DroppedFiles ClassifyDroppedPaths(const std::vector<std::string>& paths) {
  DroppedFiles out;
  for (const std::string& path : paths) {
    std::error_code ec;
    const bool is_file = fs::is_regular_file(path, ec);
    if (is_file && IsProjectFile(path))
      out.projects.push_back(path);
    else if (is_file && IsPhotoFile(path))
      out.photos.push_back(path);
    else
      out.unknown.push_back(path);
  }
  return out;
}

void AddRecentFile(RecentFiles* recent, const std::string& path) {
  if (path.empty()) return;
  const std::string normal = NormalizePath("", path);
  PushFront(&recent->files, normal, RecentFiles::kMaxFiles);
  AddRecentFolder(recent, ParentFolder(normal));
}

void AddRecentFolder(RecentFiles* recent, const std::string& folder) {
  if (folder.empty()) return;
  PushFront(&recent->folders, NormalizePath("", folder), RecentFiles::kMaxFolders);
}

std::vector<std::string> RecentFilesWith(const RecentFiles& recent, const std::vector<std::string>& extensions) {
  std::vector<std::string> out;
  for (const std::string& f : recent.files) {
    if (extensions.empty() || HasExtension(f, extensions)) out.push_back(f);
  }
  return out;
}

std::string RecentFilesToJson(const RecentFiles& recent) {
  nlohmann::json j;
  j["format"] = "facet-recent";
  j["version"] = 1;
  // JSON holds UTF-8 only: a path in another encoding cannot be stored exactly, and a
  // replaced one would name no file, so it is left out of the list (it throws otherwise).
  const auto storable = [](const std::vector<std::string>& paths) {
    std::vector<std::string> out;
    for (const std::string& path : paths)
      if (IsValidUtf8(path)) out.push_back(path);
    return out;
  };
  j["files"] = storable(recent.files);
  j["folders"] = storable(recent.folders);
  return j.dump(2);
}

bool RecentFilesFromJson(const std::string& text, RecentFiles* recent, std::string* error) {
  const nlohmann::json j = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded() || !j.is_object()) {
    *error = "recent-files file is not valid JSON";
    return false;
  }
  if (j.value("format", std::string()) != "facet-recent" || j.value("version", 0) != 1) {
    *error = "recent-files file has an unknown format or version";
    return false;
  }
  RecentFiles parsed;
  // Oldest first, so that the capacity and de-duplication rules apply as if added anew.
  for (const char* key : {"files", "folders"}) {
    const auto it = j.find(key);
    if (it == j.end()) continue;
    if (!it->is_array()) {
      *error = std::string("recent-files file: '") + key + "' must be a list of paths";
      return false;
    }
    for (auto item = it->rbegin(); item != it->rend(); ++item) {
      if (!item->is_string() || item->get<std::string>().empty()) {
        *error = std::string("recent-files file: '") + key + "' holds something that is not a path";
        return false;
      }
      const std::string path = NormalizePath("", item->get<std::string>());
      if (std::string(key) == "files")
        PushFront(&parsed.files, path, RecentFiles::kMaxFiles);
      else
        PushFront(&parsed.folders, path, RecentFiles::kMaxFolders);
    }
  }
  *recent = std::move(parsed);
  return true;
}

std::string RecentFilesPath(const std::string& config_dir) {
  return config_dir.empty() ? std::string() : config_dir + "/recent.json";
}

bool LoadRecentFiles(const std::string& path, RecentFiles* recent, std::string* error) {
  std::string text;
  if (!ReadTextFile(path, &text)) {
    *error = "cannot read " + path;
    return false;
  }
  if (!RecentFilesFromJson(text, recent, error)) {
    *error = path + ": " + *error;
    return false;
  }
  return true;
}

bool SaveRecentFiles(const std::string& path, const RecentFiles& recent, std::string* error) {
  std::error_code ec;
  fs::create_directories(fs::path(path).parent_path(), ec);
  if (ec) {
    *error = "cannot create " + fs::path(path).parent_path().string() + ": " + ErrorText(ec);
    return false;
  }
  *error = WriteFileAtomically(path, RecentFilesToJson(recent));
  return error->empty();
}

}  // namespace facet::app
