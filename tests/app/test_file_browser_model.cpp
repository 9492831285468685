// The file browser's model (app/state/file_browser_model.h) on real temporary folders:
// listing with the purpose filters, hidden entries and case-insensitive order, the parent at
// the root, what typed paths mean, drop classification, and the recent files' capacity,
// de-duplication and persistence round trip, plus the messages for folders that vanished,
// are files or cannot be read.
#include <doctest/doctest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "app/state/file_browser_model.h"

namespace fs = std::filesystem;
using namespace facet::app;

namespace {

struct TempTree {
  fs::path root;
  explicit TempTree(const std::string& name) {
    root = fs::temp_directory_path() / ("facet_browser_test_" + std::to_string(::getpid()) + "_" + name);
    fs::remove_all(root);
    fs::create_directories(root);
  }
  ~TempTree() {
    std::error_code ec;
    fs::permissions(root, fs::perms::owner_all, fs::perm_options::add, ec);
    for (const auto& e : fs::recursive_directory_iterator(root, fs::directory_options::skip_permission_denied, ec)) {
      fs::permissions(e.path(), fs::perms::owner_all, fs::perm_options::add, ec);
    }
    fs::remove_all(root, ec);
  }
  std::string operator/(const std::string& name) const { return (root / name).string(); }
  void File(const std::string& name, size_t bytes = 0) const {
    std::ofstream out(root / name, std::ios::binary);
    out << std::string(bytes, 'x');
  }
  void Folder(const std::string& name) const { fs::create_directories(root / name); }
};

std::vector<std::string> Names(const FolderListing& listing) {
  std::vector<std::string> names;
  for (const BrowserEntry& e : listing.entries) names.push_back(e.is_folder ? e.name + "/" : e.name);
  return names;
}

// Runs `body` as an unprivileged user when this process is root (permission bits do not
// stop root), so that an unreadable folder is unreadable; returns what `body` wrote.
std::string RunWithoutPrivileges(const std::function<std::string()>& body) {
  if (::geteuid() != 0) return body();
  int pipe_fds[2];
  REQUIRE(::pipe(pipe_fds) == 0);
  const pid_t child = ::fork();
  REQUIRE(child >= 0);
  if (child == 0) {
    ::close(pipe_fds[0]);
    constexpr uid_t kNobody = 65534;
    std::string out = ::setgid(kNobody) == 0 && ::setuid(kNobody) == 0 ? body() : std::string("setuid failed");
    if (::write(pipe_fds[1], out.data(), out.size()) < 0) _exit(2);
    _exit(0);
  }
  ::close(pipe_fds[1]);
  std::string out;
  char buffer[512];
  for (ssize_t n; (n = ::read(pipe_fds[0], buffer, sizeof(buffer))) > 0;) out.append(buffer, static_cast<size_t>(n));
  ::close(pipe_fds[0]);
  int status = 0;
  ::waitpid(child, &status, 0);
  REQUIRE(WIFEXITED(status));
  return out;
}

}  // namespace

TEST_CASE("Listing: folders first, then the purpose's files, each sorted case-insensitively; hidden ones left out") {
  TempTree t("listing");
  t.Folder("beta");
  t.Folder("Alpha");
  t.Folder(".git");
  t.File("zebra.facet", 10);
  t.File("Apple.FACET", 3000);
  t.File("mango.facet");
  t.File("photo.JPG");
  t.File("notes.txt");
  t.File(".hidden.facet");

  ListOptions projects;
  projects.extensions = PurposeExtensions(BrowsePurpose::kOpenProject);
  const FolderListing listing = ListFolder(t.root.string(), projects);
  REQUIRE(listing.ok());
  CHECK(listing.folder == t.root.string());
  CHECK(Names(listing) == std::vector<std::string>{"Alpha/", "beta/", "Apple.FACET", "mango.facet", "zebra.facet"});
  CHECK(listing.entries[2].size_bytes == 3000);
  CHECK_FALSE(listing.truncated);

  ListOptions photos;
  photos.extensions = PurposeExtensions(BrowsePurpose::kAddPhoto);
  CHECK(Names(ListFolder(t.root.string(), photos)) == std::vector<std::string>{"Alpha/", "beta/", "photo.JPG"});

  ListOptions everything = projects;
  everything.all_files = true;
  everything.show_hidden = true;
  CHECK(Names(ListFolder(t.root.string(), everything)) ==
        std::vector<std::string>{".git/", "Alpha/", "beta/", ".hidden.facet", "Apple.FACET", "mango.facet", "notes.txt",
                                 "photo.JPG", "zebra.facet"});

  ListOptions capped = everything;
  capped.max_entries = 4;
  const FolderListing cut = ListFolder(t.root.string(), capped);
  CHECK(cut.truncated);
  CHECK(cut.entries.size() == 4);
}

TEST_CASE("Case-insensitive order is total: case decides only between otherwise equal names") {
  CHECK(CaseInsensitiveLess("a", "B"));
  CHECK(CaseInsensitiveLess("B", "b"));
  CHECK_FALSE(CaseInsensitiveLess("b", "B"));
  CHECK(CaseInsensitiveLess("b", "c"));
  CHECK(CaseInsensitiveLess("House2", "house3"));
  CHECK_FALSE(CaseInsensitiveLess("x", "x"));
}

TEST_CASE("Parent of a folder, the root is its own parent; paths are normalised and ~ is home") {
  CHECK(ParentFolder("/") == "/");
  CHECK(ParentFolder("/usr") == "/");
  CHECK(ParentFolder("/usr/share/") == "/usr");
  CHECK(ParentFolder("/a/b/../c") == "/a");
  CHECK(JoinPath("/a/b", "../c") == "/a/c");
  CHECK(JoinPath("/a/b", "/x/y") == "/x/y");
  const char* home = std::getenv("HOME");
  REQUIRE(home != nullptr);
  CHECK(NormalizePath("/elsewhere", "~/projects") == NormalizePath("", std::string(home) + "/projects"));
  CHECK(NormalizePath("/elsewhere", "~other") == "/elsewhere/~other");
}

TEST_CASE("Typed paths: folder, existing file, new file only when writing, and what is missing") {
  TempTree t("typed");
  t.Folder("sub");
  t.File("sub/house.facet");
  const std::string here = t.root.string();

  CHECK(ResolveTypedPath(here, "  ", false).kind == TypedPathKind::kEmpty);
  const TypedPath folder = ResolveTypedPath(here, "sub/", false);
  CHECK(folder.kind == TypedPathKind::kFolder);
  CHECK(folder.path == t / "sub");
  const TypedPath file = ResolveTypedPath(here, t / "sub/house.facet", false);
  CHECK(file.kind == TypedPathKind::kExistingFile);
  CHECK(file.path == t / "sub/house.facet");
  CHECK(ResolveTypedPath(t / "sub", "house.facet", true).kind == TypedPathKind::kExistingFile);

  const TypedPath new_file = ResolveTypedPath(here, "sub/new", true);
  CHECK(new_file.kind == TypedPathKind::kNewFile);
  CHECK(WithPurposeExtension(new_file.path, BrowsePurpose::kSaveProject) == t / "sub/new.facet");
  CHECK(WithPurposeExtension("x.FACET", BrowsePurpose::kSaveProject) == "x.FACET");
  CHECK(WithPurposeExtension("model", BrowsePurpose::kExport) == "model.glb");
  CHECK(WithPurposeExtension("model.obj", BrowsePurpose::kExport) == "model.obj");

  const TypedPath not_there = ResolveTypedPath(here, "sub/new", false);
  CHECK(not_there.kind == TypedPathKind::kMissing);
  CHECK(not_there.error.find("There is no new in " + t / "sub") != std::string::npos);
  const TypedPath no_folder = ResolveTypedPath(here, "gone/new.facet", true);
  CHECK(no_folder.kind == TypedPathKind::kMissing);
  CHECK(no_folder.error.find("The folder " + t / "gone" + " does not exist") != std::string::npos);
}

TEST_CASE("A vanished folder, a file taken for a folder and an unreadable folder give messages, not entries") {
  TempTree t("errors");
  t.File("plain.txt");
  t.Folder("locked");
  t.File("locked/inside.facet");

  const FolderListing gone = ListFolder(t / "gone", ListOptions());
  CHECK_FALSE(gone.ok());
  CHECK(gone.entries.empty());
  CHECK(gone.error == "The folder " + t / "gone" + " does not exist (any more).");

  const FolderListing file = ListFolder(t / "plain.txt", ListOptions());
  CHECK(file.error == t / "plain.txt" + " is not a folder.");

  // Readable by nobody but its owner (root here, or this user, from whom the bits are taken).
  fs::permissions(t.root, fs::perms::others_exec | fs::perms::others_read, fs::perm_options::add);
  fs::permissions(t / "locked", fs::perms::owner_all, fs::perm_options::replace);
  const std::string locked_folder = t / "locked";
  if (::geteuid() != 0) fs::permissions(locked_folder, fs::perms::none, fs::perm_options::replace);
  const std::string message = RunWithoutPrivileges([&] {
    const FolderListing locked = ListFolder(locked_folder, ListOptions());
    return locked.entries.empty() ? locked.error : std::string("listed ") + locked.entries[0].name;
  });
  CHECK(message == "Cannot read the folder " + locked_folder + ": permission denied.");
  // Below an unreadable folder nothing can even be looked at: said so, not "does not exist".
  const std::string inside = locked_folder + "/deeper";
  fs::permissions(locked_folder, fs::perms::owner_all, fs::perm_options::replace);
  fs::create_directories(inside);
  if (::geteuid() != 0) fs::permissions(locked_folder, fs::perms::none, fs::perm_options::replace);
  const std::string below = RunWithoutPrivileges([&] { return ListFolder(inside, ListOptions()).error; });
  CHECK(below == "Cannot reach the folder " + inside + ": permission denied.");
}

TEST_CASE("Drops are sorted into projects, photos and the rest") {
  TempTree t("drops");
  t.File("a.facet");
  t.File("b.JPEG");
  t.File("c.png");
  t.File("d.txt");
  t.Folder("e.png");  // a folder named like a photo is not one
  const DroppedFiles dropped =
      ClassifyDroppedPaths({t / "d.txt", t / "b.JPEG", t / "a.facet", t / "e.png", t / "c.png", t / "missing.png"});
  CHECK(dropped.projects == std::vector<std::string>{t / "a.facet"});
  CHECK(dropped.photos == std::vector<std::string>{t / "b.JPEG", t / "c.png"});
  CHECK(dropped.unknown == std::vector<std::string>{t / "d.txt", t / "e.png", t / "missing.png"});
}

TEST_CASE("Recent files: newest first, each once, capped; their folders follow") {
  RecentFiles recent;
  AddRecentFile(&recent, "/p/one.facet");
  AddRecentFile(&recent, "/p/two.facet");
  AddRecentFile(&recent, "/q/photo.jpg");
  AddRecentFile(&recent, "/p/x/../one.facet");  // the same file again, spelled differently
  CHECK(recent.files == std::vector<std::string>{"/p/one.facet", "/q/photo.jpg", "/p/two.facet"});
  CHECK(recent.folders == std::vector<std::string>{"/p", "/q"});
  CHECK(RecentFilesWith(recent, {".facet"}) == std::vector<std::string>{"/p/one.facet", "/p/two.facet"});

  for (size_t i = 0; i < RecentFiles::kMaxFiles + 5; ++i) {
    AddRecentFile(&recent, "/f" + std::to_string(i) + "/file.facet");
  }
  REQUIRE(recent.files.size() == RecentFiles::kMaxFiles);
  CHECK(recent.files.front() == "/f" + std::to_string(RecentFiles::kMaxFiles + 4) + "/file.facet");
  CHECK(recent.files.back() == "/f5/file.facet");
  REQUIRE(recent.folders.size() == RecentFiles::kMaxFolders);
  CHECK(recent.folders.front() == "/f" + std::to_string(RecentFiles::kMaxFiles + 4));
}

TEST_CASE("Recent files round-trip through their file; a malformed file is refused and changes nothing") {
  TempTree t("recent");
  RecentFiles recent;
  AddRecentFile(&recent, t / "b.facet");
  AddRecentFile(&recent, t / "photos/c.jpg");
  AddRecentFolder(&recent, t / "exports");
  const std::string path = RecentFilesPath(t / "config/facet");
  CHECK(path == t / "config/facet/recent.json");
  std::string error;
  REQUIRE_MESSAGE(SaveRecentFiles(path, recent, &error), error);
  RecentFiles loaded;
  REQUIRE_MESSAGE(LoadRecentFiles(path, &loaded, &error), error);
  CHECK(loaded.files == recent.files);
  CHECK(loaded.folders == recent.folders);

  for (const std::string& bad : {std::string("{not json"), std::string(R"({"format": "facet-layout", "version": 1})"),
                                 std::string(R"({"format": "facet-recent", "version": 1, "files": [3]})"),
                                 std::string(R"({"format": "facet-recent", "version": 1, "files": "a"})")}) {
    RecentFiles kept = loaded;
    std::string why;
    CHECK_FALSE(RecentFilesFromJson(bad, &kept, &why));
    CHECK_FALSE(why.empty());
    CHECK(kept.files == loaded.files);
  }
  CHECK_FALSE(LoadRecentFiles(t / "nowhere.json", &loaded, &error));
  CHECK(error == "cannot read " + t / "nowhere.json");
  CHECK(RecentFilesPath("").empty());
}

TEST_CASE("Extensions are matched case-insensitively, by the last one only") {
  CHECK(IsProjectFile("/a/House.FaCeT"));
  CHECK_FALSE(IsProjectFile("/a/house.facet.bak"));
  CHECK(IsPhotoFile("IMG_0001.JPG"));
  CHECK(IsPhotoFile("scan.tiff"));
  CHECK_FALSE(IsPhotoFile("jpg"));
  CHECK_FALSE(HasExtension("noext", {".facet"}));
  CHECK(PurposeWrites(BrowsePurpose::kSaveProject));
  CHECK(PurposeWrites(BrowsePurpose::kExport));
  CHECK_FALSE(PurposeWrites(BrowsePurpose::kOpenProject));
  CHECK_FALSE(PurposeWrites(BrowsePurpose::kAddPhoto));
  CHECK(FormatSize(512) == "512 B");
  CHECK(FormatSize(3000) == "3 KB");
  CHECK(FormatSize(5u * 1024 * 1024 + 1) == "5.0 MB");
}
