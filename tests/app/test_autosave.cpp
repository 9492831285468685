// Autosave and crash recovery through the real application (issue 14): a session killed with
// SIGKILL after an autosave is restored, history included, exactly as it was autosaved; a
// clean exit leaves no recovery file, for a saved project and an unsaved one; Discard deletes
// the file; a corrupt or inconsistent recovery file is reported and the project opens as saved.
#include <doctest/doctest.h>

#include <signal.h>

#include <string>
#include <vector>

#include "core/io/project_io.h"
#include "core/io/recovery_io.h"
#include "core/scene/document.h"
#include "tests/app/app_test_util.h"

namespace {

using facet::testing::TempDir;
namespace fs = std::filesystem;

const std::string kSampleFolder = std::string(FACET_SOURCE_DIR) + "/assets/samples/leuven/";

// A private copy of the Leuven sample (project and photo) in `dir`; returns the project path.
std::string CopySample(const TempDir& dir) {
  fs::copy_file(kSampleFolder + "leuven.facet", dir / "leuven.facet", fs::copy_options::overwrite_existing);
  fs::copy_file(kSampleFolder + "leuvenA.jpg", dir / "leuvenA.jpg", fs::copy_options::overwrite_existing);
  return dir / "leuven.facet";
}

// Three edits, the last one undone: the redo stack is not empty.
const char* kEdits =
    "frames 2\n"
    "command add box\n"
    "command add wedge on-top\n"
    "command add box\n"
    "command undo\n";
const std::vector<std::string> kUndoLabels = {"Add box", "Add wedge on top"};
const std::vector<std::string> kRedoLabels = {"Add box"};

std::vector<std::string> Labels(const std::vector<facet::Edit>& stack) {
  std::vector<std::string> labels;
  for (const facet::Edit& edit : stack) labels.push_back(edit.label);
  return labels;
}

std::vector<std::string> Labels(const nlohmann::json& stack) { return stack.get<std::vector<std::string>>(); }

facet::Project ReportProject(const nlohmann::json& report) {
  const facet::ProjectLoadResult loaded = facet::ProjectFromJson(report.at("project").dump());
  REQUIRE_MESSAGE(loaded.ok(), loaded.error);
  return loaded.project;
}

bool LogHas(const nlohmann::json& report, const std::string& text) {
  return facet::testing::ReportLog(report).find(text) != std::string::npos;
}

nlohmann::json RenderAutosave(const TempDir& dir, const std::string& project, const std::string& name,
                              const std::string& script) {
  facet::testing::WriteText(dir / (name + ".txt"), script);
  const facet::testing::RunResult run = facet::testing::RunRender(
      dir, "--autosave " + (project.empty() ? std::string() : "'" + project + "' ") + "-o '" + (dir / (name + ".png")) +
               "' --script '" + (dir / (name + ".txt")) + "' --report '" + (dir / (name + ".json")) + "'");
  INFO("stderr: " << run.stderr_text);
  REQUIRE(run.exit_code == 0);
  return facet::testing::ReadJson(dir / (name + ".json"));
}

}  // namespace

TEST_CASE("a session killed after an autosave is restored with its history exactly as autosaved") {
  // The document the edits make, from a run that ends normally (no autosave): what the
  // recovery file must hold.
  const TempDir reference_dir("autosave_reference");
  const nlohmann::json reference =
      facet::testing::RenderScript(reference_dir, CopySample(reference_dir), "edits", kEdits);
  REQUIRE(Labels(reference.at("undo_stack")) == kUndoLabels);
  REQUIRE(Labels(reference.at("redo_stack")) == kRedoLabels);

  const TempDir dir("autosave_kill");
  const std::string project = CopySample(dir);
  const facet::Project saved_before = facet::testing::LoadProjectFile(project);
  const std::string recovery = project + ".recovery";
  // The marker screenshot is taken once the autosave of the last edit is on disk; then the
  // session goes on (90,000 frames, far longer than the test waits, within the scripts' limit
  // of 100,000 steps) until it is killed.
  facet::testing::WriteText(dir / "session.txt", std::string(kEdits) + "command wait-autosave\nscreenshot " +
                                                     (dir / "autosaved.png") + "\nframes 90000\n");
  facet::testing::BackgroundRender session = facet::testing::StartRender(
      dir, "session", {"--autosave", project, "-o", dir / "session.png", "--script", dir / "session.txt"});
  const bool autosaved = facet::testing::WaitForFile(dir / "autosaved.png", &session, 240.0);
  CHECK(facet::testing::StopRender(&session, SIGKILL) == SIGKILL);  // still running: a crash, not an exit
  INFO("stderr: " << facet::testing::ReadText(dir / "session.stderr.txt"));
  REQUIRE(autosaved);

  // What the killed session left: the project untouched, the recovery file with the document.
  CHECK(facet::testing::LoadProjectFile(project) == saved_before);
  REQUIRE(fs::exists(recovery));
  const facet::RecoveryLoadResult left = facet::LoadRecovery(recovery);
  REQUIRE_MESSAGE(left.ok(), left.error);
  CHECK(Labels(left.document.undo_stack()) == kUndoLabels);
  CHECK(Labels(left.document.redo_stack()) == kRedoLabels);
  CHECK(left.document.project() == ReportProject(reference));
  CHECK(left.document.dirty());

  // The next start offers it; Restore (the dialog's button) brings back the document and its
  // history, dirty; Save writes it and removes the recovery file.
  const nlohmann::json restored = RenderAutosave(dir, project, "restore",
                                                 "frames 2\n"
                                                 "click left item recover.restore\n"
                                                 "frames 2\n"
                                                 "command save\n");
  INFO(facet::testing::ReportLog(restored));
  CHECK(LogHas(restored, "Restored from " + recovery + " (2 edits to undo, 1 to redo)"));
  CHECK(Labels(restored.at("undo_stack")) == kUndoLabels);
  CHECK(Labels(restored.at("redo_stack")) == kRedoLabels);
  CHECK(ReportProject(restored) == left.document.project());
  CHECK(facet::testing::LoadProjectFile(project) == left.document.project());
  CHECK(restored.at("dirty") == false);  // saved
  CHECK(restored.at("dialog") == "");
  CHECK_FALSE(fs::exists(recovery));
}

TEST_CASE("a clean exit leaves no recovery file, for a saved project and for an unsaved one") {
  const TempDir dir("autosave_clean_exit");
  const std::string project = CopySample(dir);
  // No wait-autosave: the frames after the edits write it on their own (2 s at 60 Hz is far
  // beyond the throttle of ten times a write of this 52 KB file).
  const nlohmann::json saved = RenderAutosave(dir, project, "saved", std::string(kEdits) + "frames 120\n");
  const nlohmann::json& autosave = saved.at("autosave");
  CHECK(autosave.at("writes").get<int>() >= 1);
  CHECK(autosave.at("failures").get<int>() == 0);
  CHECK(autosave.at("recovery_file") == project + ".recovery");  // in use at the end of the script
  CHECK(autosave.at("last_bytes").get<std::uint64_t>() > 0);
  CHECK_FALSE(fs::exists(project + ".recovery"));

  // An unsaved project's file is in the data folder ($XDG_DATA_HOME/facet/recovery).
  const nlohmann::json untitled = RenderAutosave(dir, project, "untitled",
                                                 "frames 2\n"
                                                 "command new\n"
                                                 "command add-photo " +
                                                     (dir / "leuvenA.jpg") +
                                                     "\n"
                                                     "command add box\n"
                                                     "command wait-autosave\n");
  INFO(facet::testing::ReportLog(untitled));
  const std::string untitled_file = untitled.at("autosave").at("recovery_file").get<std::string>();
  CHECK(untitled_file.rfind(dir / "data/facet/recovery/untitled-", 0) == 0);
  CHECK(untitled.at("autosave").at("writes").get<int>() >= 1);
  CHECK_FALSE(fs::exists(untitled_file));
  CHECK(fs::is_empty(dir / "data/facet/recovery"));
}

TEST_CASE("Discard deletes the recovery file and keeps the project as saved") {
  const TempDir dir("autosave_discard");
  const std::string project = CopySample(dir);
  const facet::Project saved = facet::testing::LoadProjectFile(project);
  facet::Document document(saved);
  facet::Project edited = saved;
  edited.units = "ft";
  REQUIRE(document.Commit("Units", edited));
  REQUIRE(facet::SaveRecovery(document, project + ".recovery").empty());

  const nlohmann::json report = RenderAutosave(dir, project, "discard",
                                               "frames 2\n"
                                               "command recover discard\n"
                                               "frames 2\n");
  INFO(facet::testing::ReportLog(report));
  CHECK(LogHas(report, "Discarded the recovery file"));
  CHECK_FALSE(fs::exists(project + ".recovery"));
  CHECK(ReportProject(report) == saved);
  CHECK(report.at("undo_stack").empty());
  CHECK(report.at("dialog") == "");
}

TEST_CASE("a corrupt or inconsistent recovery file is reported, and the project opens as saved") {
  const TempDir dir("autosave_corrupt");
  const std::string project = CopySample(dir);
  const facet::Project saved = facet::testing::LoadProjectFile(project);
  const std::string recovery = project + ".recovery";

  // Truncated JSON: the loader's line and column.
  facet::testing::WriteText(recovery, "{\"format\": \"facet-recovery\", \"version\": 1, \"project\": {");
  nlohmann::json report = RenderAutosave(dir, project, "truncated", "frames 2\n");
  INFO(facet::testing::ReportLog(report));
  CHECK(LogHas(report, "Recovery file not restored: " + recovery + ": line 1, column"));
  CHECK(LogHas(report, project + " opened as saved"));
  CHECK(report.at("dialog") == "");
  CHECK(report.at("autosave").at("offer") == "");
  CHECK(ReportProject(report) == saved);
  CHECK(report.at("undo_stack").empty());

  // Valid JSON whose history does not lead to its project: the edit is named.
  facet::Document document(saved);
  facet::Project edited = saved;
  edited.units = "ft";
  REQUIRE(document.Commit("Units", edited));
  std::string error;
  nlohmann::json text = nlohmann::json::parse(facet::RecoveryToJson(document, &error));
  REQUIRE(error.empty());
  text["undo"][0]["units"] = {"m", "yd"};  // the project it leads to is in feet
  facet::testing::WriteText(recovery, text.dump());
  report = RenderAutosave(dir, project, "inconsistent", "frames 2\n");
  CHECK(LogHas(report, "Recovery file not restored: " + recovery +
                           ": history: undo[0]: does not revert onto the project after it: units: the project's "
                           "units are not the edit's; " +
                           project + " opened as saved"));
  CHECK(ReportProject(report) == saved);
  CHECK(report.at("dialog") == "");
}
