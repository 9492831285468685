// The file browser and drag and drop in the real application offscreen: the Leuven sample
// opened by typing its path into File > Open, a photo added through File > Add photo by
// clicking a folder and the photo, Save as by typing a name (the extension added, the file
// round-tripping, an existing file replaced only after the question), refusals shown in the
// dialog, recent files kept in the config folder and offered by File > Open recent, and the
// script's `drop` of a photo, an unknown file and a project (over unsaved work: the question
// first). Widgets are found through the report's item rectangles (app/panels/file_dialog.h).
#include <doctest/doctest.h>

#include <string>

#include <opencv2/imgcodecs.hpp>

#include "core/io/colmap_model.h"
#include "core/io/project_io.h"
#include "tests/app/app_test_util.h"
#include "tests/gltf_validator.h"
#include "tests/synthetic_scene.h"

using namespace facet::testing;

namespace {

const std::string kSample = std::string(FACET_SOURCE_DIR) + "/assets/samples/leuven/leuven.facet";
const std::string kSamplePhoto = std::string(FACET_SOURCE_DIR) + "/assets/samples/leuven/leuvenA.jpg";

// Runs the app with `script` and an optional config folder; requires success.
nlohmann::json Run(const TempDir& dir, const std::string& project, const std::string& name, const std::string& script,
                   const std::string& config_dir = "") {
  WriteText(dir / (name + ".txt"), script);
  std::string args = "'" + project + "' -o '" + (dir / (name + ".png")) + "' --script '" + (dir / (name + ".txt")) +
                     "' --report '" + (dir / (name + ".json")) + "' --size 1280x800";
  if (!config_dir.empty()) args += " --config-dir '" + config_dir + "'";
  const RunResult run = RunRender(dir, args);
  INFO("stderr: " << run.stderr_text);
  REQUIRE(run.exit_code == 0);
  return ReadJson(dir / (name + ".json"));
}

std::string Click(const nlohmann::json& report, const std::string& item) {
  INFO("items of the report: " << report.at("items").dump());
  REQUIRE(report.at("items").contains(item));
  return "click left " + ItemCenter(report.at("items"), item) + "\nframes 1\n";
}

// Two clicks within ImGui's double-click time, then a pause longer than it, so that the
// next click is never taken for the end of another double-click.
std::string DoubleClick(const nlohmann::json& report, const std::string& item) {
  return Click(report, item) + Click(report, item) + "frames 20\n";
}

double ItemY(const nlohmann::json& report, const std::string& item) {
  REQUIRE(report.at("items").contains(item));
  return report.at("items").at(item).at("y").get<double>();
}

bool LogHas(const nlohmann::json& report, const std::string& level, const std::string& text) {
  for (const auto& e : report.at("log")) {
    if (e.at("level") == level && e.at("text").get<std::string>().find(text) != std::string::npos) return true;
  }
  return false;
}

std::string WriteBoxScene(const TempDir& dir) {
  const std::string path = dir / "scene.facet";
  REQUIRE(facet::SaveProject(MakeBoxScene().project, path) == "");
  return path;
}

std::string Canonical(const std::string& path) { return fs::weakly_canonical(path).string(); }

}  // namespace

TEST_CASE("File > Open by keyboard alone: a folder, Enter, a name without its extension, Enter") {
  TempDir dir("browser_keyboard");
  const std::string scene = WriteBoxScene(dir);
  const std::string sample_folder = fs::path(kSample).parent_path().string();
  const nlohmann::json report =
      Run(dir, scene, "keyboard",
          "frames 2\nkey ctrl+o\nframes 3\ntype " + sample_folder +
              "\nframes 1\nkey enter\nframes 2\ntype leuven\nframes 1\nkey enter\nframes 3\n");
  INFO(ReportLog(report));
  CHECK(report["dialog"] == "");
  CHECK(LogHas(report, "info", "Opened " + kSample));
}

TEST_CASE("File > Open: typing the sample's path and Enter opens it, and it becomes a recent file") {
  TempDir dir("browser_open");
  const std::string scene = WriteBoxScene(dir);
  const nlohmann::json report =
      Run(dir, scene, "open", "frames 2\nkey ctrl+o\nframes 3\ntype " + kSample + "\nframes 1\nkey enter\nframes 3\n");
  INFO(ReportLog(report));
  CHECK(report["dialog"] == "");
  const facet::Project sample = LoadProjectFile(kSample);
  CHECK(report["project"]["images"].size() == sample.images.size());
  CHECK(report["project"]["primitives"].size() == sample.primitives.size());
  CHECK(LogHas(report, "info", "Opened " + kSample));
  REQUIRE(!report["recent_files"]["files"].empty());
  CHECK(report["recent_files"]["files"][0] == kSample);
  CHECK(report["recent_files"]["folders"][0] == fs::path(kSample).parent_path().string());
}

TEST_CASE("File > Add photo: folders first, the photo filter, hidden files on demand; double-clicks add the photo") {
  TempDir dir("browser_add_photo");
  const std::string scene = WriteBoxScene(dir);
  fs::create_directories(dir.path / "photos");
  fs::create_directories(dir.path / ".cache");
  fs::create_directories(dir.path / "Archive");
  REQUIRE(cv::imwrite(dir / "photos/b.png", cv::Mat(300, 400, CV_8UC3, cv::Scalar(60, 80, 100))));
  REQUIRE(cv::imwrite(dir / "photos/A.jpg", cv::Mat(200, 300, CV_8UC3, cv::Scalar(90, 80, 70))));
  WriteText(dir / "photos/notes.txt", "not a photo");

  const nlohmann::json bare = Run(dir, scene, "probe_menu", "frames 2\n");
  const std::string open_file_menu = Click(bare, "menu.file") + "frames 2\n";
  const nlohmann::json menu = Run(dir, scene, "probe_add", "frames 2\n" + open_file_menu);
  const std::string open_browser = "frames 2\n" + open_file_menu + Click(menu, "menu.add_photo") + "frames 3\n";

  // The project's folder, listed for photos: the folders (Archive before photos, the hidden
  // .cache left out), and no .facet file.
  const nlohmann::json start = Run(dir, scene, "start", open_browser);
  REQUIRE(start["dialog"] == "add-photo");
  CHECK(start["file_dialog"]["folder"] == dir.path.string());
  const nlohmann::json& items = start["items"];
  CHECK(items.contains("file.entry/Archive"));
  CHECK(items.contains("file.entry/photos"));
  CHECK(ItemY(start, "file.entry/Archive") < ItemY(start, "file.entry/photos"));
  CHECK_FALSE(items.contains("file.entry/.cache"));
  CHECK_FALSE(items.contains("file.entry/scene.facet"));

  // Hidden files on: .cache comes first.
  const std::string show_hidden = open_browser + Click(start, "file.hidden") + "frames 2\n";
  const nlohmann::json hidden = Run(dir, scene, "hidden", show_hidden);
  CHECK(hidden["items"].contains("file.entry/.cache"));
  CHECK(ItemY(hidden, "file.entry/.cache") < ItemY(hidden, "file.entry/Archive"));

  // Into photos by a click and Enter: A.jpg above b.png (case-insensitive order), the text
  // file filtered out.
  const std::string into_photos = show_hidden + Click(hidden, "file.entry/photos") + "key enter\nframes 20\n";
  const nlohmann::json inside = Run(dir, scene, "inside", into_photos);
  CHECK(inside["file_dialog"]["folder"] == (dir.path / "photos").string());
  CHECK(ItemY(inside, "file.entry/A.jpg") < ItemY(inside, "file.entry/b.png"));
  CHECK_FALSE(inside["items"].contains("file.entry/notes.txt"));

  // The filter switched to all files lists the text file too.
  const std::string open_filter = into_photos + Click(inside, "file.filter") + "frames 2\n";
  const nlohmann::json filter = Run(dir, scene, "filter", open_filter);
  const nlohmann::json all_files =
      Run(dir, scene, "all_files", open_filter + Click(filter, "file.filter/all") + "frames 2\n");
  CHECK(all_files["file_dialog"]["all_files"].get<bool>());
  CHECK(all_files["items"].contains("file.entry/notes.txt"));
  CHECK(ItemY(all_files, "file.entry/b.png") < ItemY(all_files, "file.entry/notes.txt"));

  // A double-click on b.png adds it as one undoable edit.
  const nlohmann::json added =
      Run(dir, scene, "added", into_photos + DoubleClick(inside, "file.entry/b.png") + "command save\n");
  INFO(ReportLog(added));
  CHECK(added["dialog"] == "");
  const facet::Project saved = LoadProjectFile(scene);
  REQUIRE(saved.images.size() == 2);
  CHECK(saved.images[1].path == "photos/b.png");
  CHECK(saved.images[1].width_px == 400);
  REQUIRE(!added["undo_stack"].empty());
  CHECK(added["undo_stack"].back() == "Add photo b.png");
  // Recent: the project just saved, and before it the photo.
  REQUIRE(added["recent_files"]["files"].size() == 2);
  CHECK(added["recent_files"]["files"][0] == scene);
  CHECK(added["recent_files"]["files"][1] == (dir.path / "photos/b.png").string());
}

TEST_CASE("Save as: a typed name gets .facet and round-trips; an existing file is replaced only after the question") {
  TempDir dir("browser_save_as");
  const std::string copy = dir / "copy.facet";
  // The sample's folder is where Save as starts; the name typed is a path into the temp folder.
  const nlohmann::json saved =
      Run(dir, kSample, "save_as",
          "frames 2\nkey ctrl+shift+s\nframes 3\ntype " + (dir / "copy") + "\nframes 1\nkey enter\nframes 3\n");
  INFO(ReportLog(saved));
  CHECK(saved["dialog"] == "");
  REQUIRE(fs::exists(copy));
  CHECK_FALSE(saved["dirty"].get<bool>());

  // The copy is the sample: the same photos (paths re-expressed from the new folder) and the
  // same everything else, and it saves back to the same bytes.
  facet::Project original = LoadProjectFile(kSample);
  facet::Project reloaded = LoadProjectFile(copy);
  REQUIRE(reloaded.images.size() == original.images.size());
  for (size_t i = 0; i < original.images.size(); ++i) {
    CHECK(Canonical(facet::ResolveImagePath(copy, reloaded.images[i].path)) ==
          Canonical(facet::ResolveImagePath(kSample, original.images[i].path)));
    reloaded.images[i].path = original.images[i].path;
  }
  CHECK(facet::ProjectToJson(reloaded) == facet::ProjectToJson(original));
  REQUIRE(facet::SaveProject(LoadProjectFile(copy), dir / "again.facet") == "");
  std::ifstream a(copy), b(dir / "again.facet");
  std::stringstream sa, sb;
  sa << a.rdbuf();
  sb << b.rdbuf();
  CHECK(sa.str() == sb.str());

  // The proposed name's stem is selected: typing a new one keeps ".facet".
  const nlohmann::json renamed =
      Run(dir, copy, "stem", "frames 2\nkey ctrl+shift+s\nframes 3\ntype second\nframes 1\nkey enter\nframes 3\n");
  CHECK(renamed["dialog"] == "");
  CHECK(fs::exists(dir / "second.facet"));

  // Saving as copy.facet again (the proposed name) asks first; the file waits for Replace.
  const size_t primitives = reloaded.primitives.size();
  const std::string edit_and_save_as =
      "frames 2\ncommand add box\nframes 2\nkey ctrl+shift+s\nframes 3\nkey enter\nframes 2\n";
  const nlohmann::json asked = Run(dir, copy, "asked", edit_and_save_as);
  CHECK(asked["dialog"] == "save-as");
  CHECK(asked["file_dialog"]["confirm_overwrite"] == fs::path(copy).string());
  CHECK(asked["items"].contains("file.replace"));
  CHECK(LoadProjectFile(copy).primitives.size() == primitives);

  const nlohmann::json replaced = Run(dir, copy, "replaced", edit_and_save_as + "key enter\nframes 2\n");
  CHECK(replaced["dialog"] == "");
  CHECK_FALSE(replaced["dirty"].get<bool>());
  CHECK(LoadProjectFile(copy).primitives.size() == primitives + 1);
}

TEST_CASE("File > Export glTF: a typed name gets .glb and the model is written there") {
  TempDir dir("browser_export");
  const nlohmann::json bare = Run(dir, kSample, "probe_menu", "frames 2\n");
  const std::string open_file_menu = "frames 2\n" + Click(bare, "menu.file") + "frames 2\n";
  const nlohmann::json menu = Run(dir, kSample, "probe_export", open_file_menu);
  const nlohmann::json exported = Run(dir, kSample, "export",
                                      open_file_menu + Click(menu, "menu.export_gltf") + "frames 3\ntype " +
                                          (dir / "model") + "\nframes 1\nkey enter\nframes 3\n");
  INFO(ReportLog(exported));
  CHECK(exported["dialog"] == "");
  REQUIRE(fs::exists(dir / "model.glb"));
  std::ifstream glb(dir / "model.glb", std::ios::binary);
  char magic[4] = {};
  glb.read(magic, 4);
  CHECK(std::string(magic, 4) == "glTF");
  CHECK(LogHas(exported, "info", "Exported " + (dir / "model.glb")));
  CHECK_GLTF_VALID(dir / "model.glb");
}

TEST_CASE("File > Export cameras: a new folder typed gets the COLMAP model, a name gets .json; off without a camera") {
  TempDir dir("browser_export_cameras");
  const std::string open_file_menu = "frames 1\nclick left item menu.file\nframes 1\n";
  std::string script = open_file_menu + "click left item menu.export_colmap\nframes 2\n";
  script += "type " + (dir / "sparse") + "\nkey enter\nframes 2\n";
  script += open_file_menu + "click left item menu.export_transforms\nframes 2\n";
  script += "type " + (dir / "nerf") + "\nkey enter\nframes 2\n";
  // A new project has no photo: both items are disabled, a click opens nothing.
  script += "command new\n" + open_file_menu + "click left item menu.export_colmap\nframes 2\n";
  const nlohmann::json report = Run(dir, kSample, "export_cameras", script);
  INFO(ReportLog(report));
  CHECK(report["dialog"] == "");
  CHECK(LogHas(report, "info",
               "as a COLMAP text model (cameras.txt, images.txt, points3D.txt) to " + (dir / "sparse/cameras.txt")));
  CHECK(LogHas(report, "info", "as transforms.json to " + (dir / "nerf.json")));
  facet::ColmapModel model;
  REQUIRE(facet::ReadColmapModelText(dir / "sparse", &model) == "");
  CHECK(model.images.size() == 1);
  const nlohmann::json nerf = ReadJson(dir / "nerf.json");
  CHECK(nerf.at("frames").size() == 1);
  CHECK(fs::exists(dir.path / nerf["frames"][0].at("file_path").get<std::string>()));
}

TEST_CASE("The browser explains what it cannot do and keeps open; Escape cancels") {
  TempDir dir("browser_errors");
  const std::string scene = WriteBoxScene(dir);
  const std::string missing = dir / "gone/x.facet";
  const std::string prefix = "frames 2\nkey ctrl+o\nframes 3\ntype " + missing + "\nframes 1\nkey enter\nframes 2\n";
  const nlohmann::json refused = Run(dir, scene, "refused", prefix);
  CHECK(refused["dialog"] == "open");
  CHECK(refused["file_dialog"]["error"] == "The folder " + (dir / "gone") + " does not exist.");
  CHECK(refused["file_dialog"]["folder"] == dir.path.string());

  // A file that is not a project: the open fails with the reason in the dialog.
  WriteText(dir / "broken.facet", "{ not json");
  const nlohmann::json broken =
      Run(dir, scene, "broken",
          "frames 2\nkey ctrl+o\nframes 3\ntype " + (dir / "broken.facet") + "\nframes 1\nkey enter\nframes 2\n");
  CHECK(broken["dialog"] == "open");
  CHECK(broken["file_dialog"]["error"].get<std::string>().find("broken.facet") != std::string::npos);
  CHECK(broken["project"]["primitives"].size() == 1);

  // A folder typed into the path line is entered (a click selects the whole line, so the
  // typing replaces it), Parent goes back up and clears the refusal; Escape closes.
  fs::create_directories(dir.path / "sub");
  const std::string into_sub =
      prefix + Click(refused, "file.path") + "type " + (dir / "sub") + "\nframes 1\nkey enter\nframes 2\n";
  const nlohmann::json sub = Run(dir, scene, "sub", into_sub);
  CHECK(sub["file_dialog"]["folder"] == (dir / "sub"));
  const nlohmann::json cancelled =
      Run(dir, scene, "cancelled", into_sub + Click(refused, "file.parent") + "frames 2\nkey escape\nframes 2\n");
  CHECK(cancelled["file_dialog"]["folder"] == dir.path.string());
  CHECK(cancelled["file_dialog"]["error"] == "");
  CHECK(cancelled["dialog"] == "");
}

TEST_CASE("Recent files persist in the config folder and File > Open recent opens one") {
  TempDir dir("browser_recent");
  const std::string scene = WriteBoxScene(dir);
  const std::string config = dir / "facet_config";
  const nlohmann::json first = Run(dir, scene, "first", "frames 2\ncommand open " + kSample + "\nframes 2\n", config);
  REQUIRE(fs::exists(config + "/recent.json"));

  const std::string open_file_menu = "frames 2\n" + Click(first, "menu.file") + "frames 2\n";
  const nlohmann::json menu = Run(dir, scene, "probe_recent", open_file_menu, config);
  REQUIRE(menu["recent_files"]["files"][0] == kSample);  // read back from the config folder
  const std::string hover_recent = "move " + ItemCenter(menu["items"], "menu.open_recent") + "\nframes 4\n";
  const nlohmann::json submenu = Run(dir, scene, "probe_submenu", open_file_menu + hover_recent, config);
  const nlohmann::json opened =
      Run(dir, scene, "opened", open_file_menu + hover_recent + Click(submenu, "menu.recent/" + kSample), config);
  INFO(ReportLog(opened));
  CHECK(opened["project"]["images"].size() == LoadProjectFile(kSample).images.size());
  CHECK(LogHas(opened, "info", "Opened " + kSample));

  // The browser's side column offers the recent project; a double-click opens it.
  const nlohmann::json browser = Run(dir, scene, "probe_side", "frames 2\nkey ctrl+o\nframes 3\n", config);
  const nlohmann::json from_side =
      Run(dir, scene, "from_side",
          "frames 2\nkey ctrl+o\nframes 3\n" + DoubleClick(browser, "file.recent_file/" + kSample), config);
  CHECK(from_side["dialog"] == "");
  CHECK(from_side["project"]["images"].size() == LoadProjectFile(kSample).images.size());

  // A malformed recent-files file is reported, not fatal, and replaced on the next change.
  WriteText(config + "/recent.json", "{ broken");
  const nlohmann::json malformed = Run(dir, scene, "malformed", "frames 2\ncommand save\nframes 1\n", config);
  CHECK(LogHas(malformed, "warning", "Recent files not restored"));
  std::ifstream in(config + "/recent.json");
  std::stringstream text;
  text << in.rdbuf();
  CHECK(text.str().find(fs::path(scene).filename().string()) != std::string::npos);
}

TEST_CASE("Drop: a photo is added, an unknown file is refused in the log, a project opens (asking over unsaved work)") {
  TempDir dir("browser_drop");
  const std::string scene = WriteBoxScene(dir);
  REQUIRE(cv::imwrite(dir / "dropped photo.png", cv::Mat(240, 320, CV_8UC3, cv::Scalar(20, 120, 200))));
  WriteText(dir / "notes.txt", "not a photo");

  const nlohmann::json dropped = Run(dir, scene, "photo",
                                     "frames 2\ndrop \"" + (dir / "dropped photo.png") + "\" " + (dir / "notes.txt") +
                                         "\nframes 3\ndrop " + kSample + "\nframes 3\n");
  INFO(ReportLog(dropped));
  REQUIRE(dropped["project"]["images"].size() == 2);
  CHECK(dropped["project"]["images"][1]["path"] == "dropped photo.png");
  CHECK(dropped["undo_stack"].back() == "Add photo dropped photo.png");
  CHECK(LogHas(dropped, "error", "notes.txt is neither a Facet project (.facet) nor a photo"));
  // The photo made the project dirty: the dropped project waits for the answer.
  CHECK(dropped["dialog"] == "confirm-open");
  CHECK(dropped["project"]["primitives"].size() == 1);

  // Onto a clean project the drop opens at once; dropped onto the open browser, a file is
  // shown in its folder and named, not opened.
  const nlohmann::json opened = Run(
      dir, scene, "project",
      "frames 2\ndrop " + kSample + "\nframes 3\nkey ctrl+o\nframes 3\ndrop " + (dir / "notes.txt") + "\nframes 2\n");
  CHECK(opened["project"]["images"].size() == LoadProjectFile(kSample).images.size());
  CHECK(LogHas(opened, "info", "Opened " + kSample));
  CHECK(opened["dialog"] == "open");
  CHECK(opened["file_dialog"]["folder"] == dir.path.string());
  CHECK(opened["file_dialog"]["name"] == "notes.txt");
}

TEST_CASE("issue 25: File > New over unsaved work, Save, a name, Enter: saved, then the new project follows") {
  TempDir dir("browser_new_after_save");
  const std::string scene = WriteBoxScene(dir);
  // An unsaved project with a box: New asks; Save opens Save as (it has no file yet).
  const std::string unsaved = "frames 2\ncommand new\nframes 1\ncommand add box\nframes 2\n";
  const nlohmann::json asked = Run(dir, scene, "asked", unsaved + "key ctrl+n\nframes 3\n");
  REQUIRE(asked["dialog"] == "confirm-new");
  const nlohmann::json save_as =
      Run(dir, scene, "save_as", unsaved + "key ctrl+n\nframes 3\n" + Click(asked, "confirm.save") + "frames 3\n");
  REQUIRE(save_as["dialog"] == "save-as");
  const std::string name = dir / "first";
  const nlohmann::json after = Run(dir, scene, "after",
                                   unsaved + "key ctrl+n\nframes 3\n" + Click(asked, "confirm.save") +
                                       "frames 3\ntype " + name + "\nframes 1\nkey enter\nframes 3\n");
  INFO(ReportLog(after));
  // The work is in first.facet, and the app shows the new, empty, untitled project.
  REQUIRE(fs::exists(name + ".facet"));
  CHECK(LoadProjectFile(name + ".facet").primitives.size() == 1);
  CHECK(after["dialog"] == "");
  CHECK(after["project_path"] == "");
  CHECK(after["project"]["primitives"].empty());
  CHECK_FALSE(after["dirty"].get<bool>());
  CHECK(LogHas(after, "info", "New project"));

  // The same through Open: the unsaved work saved under a name, then the chosen project opens.
  const std::string open_scene = "key ctrl+o\nframes 3\ntype " + scene + "\nframes 1\nkey enter\nframes 3\n";
  const nlohmann::json open_asked = Run(dir, scene, "open_asked", unsaved + open_scene);
  REQUIRE(open_asked["dialog"] == "confirm-open");
  const std::string second = dir / "second";
  const nlohmann::json opened = Run(dir, scene, "opened",
                                    unsaved + open_scene + Click(open_asked, "confirm.save") + "frames 3\ntype " +
                                        second + "\nframes 1\nkey enter\nframes 3\n");
  INFO(ReportLog(opened));
  REQUIRE(fs::exists(second + ".facet"));
  CHECK(LoadProjectFile(second + ".facet").primitives.size() == 1);
  CHECK(opened["dialog"] == "");
  CHECK(opened["project_path"] == scene);
  CHECK(LogHas(opened, "info", "Opened " + scene));

  // Cancelling the Save as drops the question's New: a later plain Save as only saves.
  const nlohmann::json cancelled = Run(dir, scene, "cancelled",
                                       unsaved + "key ctrl+n\nframes 3\n" + Click(asked, "confirm.save") +
                                           "frames 3\nkey escape\nframes 2\nkey ctrl+shift+s\nframes 3\ntype " +
                                           (dir / "third") + "\nframes 1\nkey enter\nframes 3\n");
  INFO(ReportLog(cancelled));
  REQUIRE(fs::exists(dir / "third.facet"));
  CHECK(cancelled["project_path"] == dir / "third.facet");
  CHECK(cancelled["project"]["primitives"].size() == 1);
}

TEST_CASE("issue 25: Detect lines is ticked the first time File > Add photo opens, and the added photo is detected") {
  TempDir dir("browser_detect_default");
  const std::string scene = WriteBoxScene(dir);
  cv::Mat photo(300, 400, CV_8UC3, cv::Scalar(70, 70, 70));
  cv::rectangle(photo, cv::Rect(80, 60, 240, 180), cv::Scalar(230, 230, 230), 3);
  REQUIRE(cv::imwrite(dir / "walls.png", photo));
  const nlohmann::json bare = Run(dir, scene, "probe_menu", "frames 2\n");
  const std::string open_file_menu = Click(bare, "menu.file") + "frames 2\n";
  const nlohmann::json menu = Run(dir, scene, "probe_add", "frames 2\n" + open_file_menu);
  const std::string open_browser = "frames 2\n" + open_file_menu + Click(menu, "menu.add_photo") + "frames 3\n";
  const nlohmann::json dialog = Run(dir, scene, "dialog", open_browser);
  REQUIRE(dialog["dialog"] == "add-photo");
  CHECK(dialog["items"].contains("add_photo.detect_lines"));
  CHECK(dialog["detect_lines_on_add"].get<bool>());
  // The photo chosen with the option as it came: its lines are detected.
  const nlohmann::json added = Run(dir, scene, "added", open_browser + DoubleClick(dialog, "file.entry/walls.png"));
  INFO(ReportLog(added));
  CHECK(added["dialog"] == "");
  REQUIRE(added["project"]["images"].size() == 2);
  CHECK(added["line_detection"]["started"] == 1);
  CHECK(added["line_detection"]["last_image_id"] == added["active_image_id"]);
}

TEST_CASE("issue 25: Save and Export start in the project's folder, else the last used, never the bundled sample's") {
  TempDir dir("browser_start_folder");
  const std::string scene = WriteBoxScene(dir);
  const std::string config = dir / "facet_config";
  const std::string sample_folder = fs::path(kSample).parent_path().string();
  const char* home_env = std::getenv("HOME");
  REQUIRE(home_env != nullptr);
  const std::string home = home_env;
  // A first run with no recent files: the bundled sample open, Save as starts at home.
  const nlohmann::json fresh = Run(dir, kSample, "fresh", "frames 2\nkey ctrl+shift+s\nframes 3\n");
  REQUIRE(fresh["dialog"] == "save-as");
  CHECK(fresh["file_dialog"]["folder"] == home);
  // The user's project noted as used, then the sample opened (as the GUI does at start).
  Run(dir, scene, "used", "frames 2\ncommand save\nframes 1\n", config);
  const std::string sample_open = "frames 2\ncommand open " + kSample + "\nframes 2\n";
  const nlohmann::json save_as = Run(dir, scene, "save_as", sample_open + "key ctrl+shift+s\nframes 3\n", config);
  REQUIRE(save_as["dialog"] == "save-as");
  CHECK(save_as["file_dialog"]["folder"] != sample_folder);
  CHECK(save_as["file_dialog"]["folder"] == dir.path.string());
  // Export from the sample: the last folder used too.
  const nlohmann::json menu =
      Run(dir, scene, "probe_menu", sample_open + "click left item menu.file\nframes 2\n", config);
  const nlohmann::json exported = Run(
      dir, scene, "export",
      sample_open + "click left item menu.file\nframes 2\n" + Click(menu, "menu.export_gltf") + "frames 3\n", config);
  REQUIRE(exported["dialog"] == "export");
  CHECK(exported["file_dialog"]["folder"] == dir.path.string());
  // New, then Save as: still not the sample's folder, though the sample is the last project.
  const nlohmann::json fresh_save =
      Run(dir, scene, "new_save", sample_open + "command new\nframes 1\nkey ctrl+shift+s\nframes 3\n", config);
  CHECK(fresh_save["file_dialog"]["folder"] == dir.path.string());
  // A project of the user's own: its folder.
  fs::create_directories(dir.path / "other");
  REQUIRE(facet::SaveProject(MakeBoxScene().project, dir / "other/mine.facet") == "");
  const nlohmann::json own =
      Run(dir, dir / "other/mine.facet", "own", "frames 2\nkey ctrl+shift+s\nframes 3\n", config);
  CHECK(own["file_dialog"]["folder"] == (dir.path / "other").string());
}

TEST_CASE("issue 25: a key tapped and a double-click delivered within one frame both take effect") {
  TempDir dir("browser_fast_input");
  const std::string scene = WriteBoxScene(dir);
  REQUIRE(cv::imwrite(dir / "b.png", cv::Mat(300, 400, CV_8UC3, cv::Scalar(60, 80, 100))));
  // B pressed and released before the frame reads the keyboard: one primitive more.
  const size_t before = LoadProjectFile(scene).primitives.size();
  const nlohmann::json tapped =
      Run(dir, scene, "tapped", "frames 2\nmove item tool.Select\nframes 1\ntap b\nframes 3\n");
  INFO(ReportLog(tapped));
  CHECK(tapped["project"]["primitives"].size() == before + 1);
  // Without Detect lines (so nothing waits), a double-click on the photo in File > Add photo,
  // all four button events within one frame: the photo is added.
  const nlohmann::json bare = Run(dir, scene, "probe_menu", "frames 2\n");
  const std::string open_browser = "frames 2\ncommand lines on-add off\n" + Click(bare, "menu.file") + "frames 2\n" +
                                   "click left item menu.add_photo\nframes 3\n";
  const nlohmann::json browser = Run(dir, scene, "browser", open_browser);
  REQUIRE(browser["dialog"] == "add-photo");
  REQUIRE(browser["items"].contains("file.entry/b.png"));
  const nlohmann::json added =
      Run(dir, scene, "added", open_browser + "double-click left item file.entry/b.png\nframes 4\n");
  INFO(ReportLog(added));
  CHECK(added["dialog"] == "");
  CHECK(added["project"]["images"].size() == 2);
  // The same double-click as one ordinary click (what a lost press leaves) only selects.
  const nlohmann::json single =
      Run(dir, scene, "single", open_browser + "click left item file.entry/b.png\nframes 4\n");
  CHECK(single["dialog"] == "add-photo");
  CHECK(single["project"]["images"].size() == 1);
}
