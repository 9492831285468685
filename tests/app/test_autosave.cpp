// Autosave and crash recovery through the real application (issue 14): a session killed with
// SIGKILL after an autosave is restored, history included, exactly as it was autosaved; a
// session killed 30 s into a drag restores the drag as an unfinished edit; a failed write is
// reported once and written at the next edit once its cause is gone; a clean exit leaves no
// recovery file, for a saved project and an unsaved one; an unsaved project's file is offered
// at start and restores as an unsaved project, also when its journal is torn; Discard deletes
// the file; a corrupt or inconsistent recovery file is reported and the project opens as saved.
// A link at the recovery file's name (to the project, to another project) is refused by name and
// what it points to is untouched; a recovery file that is refused (a newer version, a damaged
// base) is moved aside with its bytes, never replaced nor deleted, and one that restores only
// in part is kept aside too.
// The 30 s timers read the offscreen clock, which the scripts move on with `advance-clock`.
#include <doctest/doctest.h>

#include <signal.h>

#include <filesystem>

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

  // Truncated JSON (a version 1 file): the loader's line and column.
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
  const std::string whole = facet::RecoveryToText(document, &error);
  REQUIRE(error.empty());
  // The base record's JSON is the file's second line (compact JSON holds no raw newline).
  const size_t base_start = whole.find('\n', whole.find('\n') + 1) + 1;
  nlohmann::json text = nlohmann::json::parse(whole.substr(base_start, whole.find('\n', base_start) - base_start));
  text["undo"][0]["units"] = {"m", "yd"};  // the project it leads to is in feet
  facet::testing::WriteText(recovery, facet::FrameRecoveryRecords({text.dump()}));
  report = RenderAutosave(dir, project, "inconsistent", "frames 2\n");
  CHECK(LogHas(report, "Recovery file not restored: " + recovery +
                           ": history: undo[0]: does not revert onto the project after it: units: the project's "
                           "units are not the edit's; the file is kept as " +
                           recovery + ".broken-"));
  CHECK(LogHas(report, project + " opened as saved"));
  CHECK_FALSE(fs::exists(recovery));  // moved aside, both of them (the test that follows checks the bytes)
  CHECK(ReportProject(report) == saved);
  CHECK(report.at("dialog") == "");
}

namespace {

facet::Project ProjectOf(const nlohmann::json& report) { return ReportProject(report); }

const facet::Pin* PinOf(const facet::Project& project, facet::Id id) {
  for (const facet::Pin& pin : project.pins)
    if (pin.id == id) return &pin;
  return nullptr;
}

// A pin of the Leuven sample (its first) dragged by (11.5, 8.5) px of the photo, the mouse
// held down at the end.
constexpr facet::Id kDraggedPin = 41;
const char* kLongDrag =
    "frames 2\n"
    "move image 318.5 395.5\n"
    "frames 1\n"
    "down left\n"
    "frames 1\n"
    "move image 324 399\n"
    "frames 1\n"
    "move image 330 404\n"
    "frames 2\n";

}  // namespace

TEST_CASE("a drag longer than 30 s is autosaved as an unfinished edit, and restores as one") {
  // The same drag released: its label and where the pin lands.
  const TempDir reference_dir("autosave_drag_reference");
  const nlohmann::json reference = facet::testing::RenderScript(reference_dir, CopySample(reference_dir), "drag",
                                                                std::string(kLongDrag) + "up left\nframes 2\n");
  REQUIRE(reference.at("undo_stack").size() == 1);
  const std::string label = reference.at("undo_stack")[0].get<std::string>();
  const facet::Project reference_project = ProjectOf(reference);
  const facet::Pin* moved = PinOf(reference_project, kDraggedPin);
  REQUIRE(moved != nullptr);
  const facet::Project sample = facet::testing::LoadProjectFile(kSampleFolder + "leuven.facet");
  const facet::Pin* original = PinOf(sample, kDraggedPin);
  REQUIRE(original != nullptr);
  REQUIRE((moved->uv_px - original->uv_px).norm() > 5.0);  // the drag moved it

  // 29 s into the drag nothing is written (the file would hold no completed edit); the script
  // ends with the mouse still down, so the drag never becomes an edit.
  const TempDir early_dir("autosave_drag_early");
  const nlohmann::json early = RenderAutosave(early_dir, CopySample(early_dir), "early",
                                              std::string(kLongDrag) +
                                                  "command advance-clock 29\nframes 3\n"
                                                  "command wait-autosave\n");
  CHECK(early.at("autosave").at("writes").get<int>() == 0);

  // 31 s into the drag the drag so far is written, as one more edit; then the session dies.
  const TempDir dir("autosave_drag");
  const std::string project = CopySample(dir);
  const std::string recovery = project + ".recovery";
  facet::testing::WriteText(dir / "session.txt", std::string(kLongDrag) +
                                                     "command advance-clock 31\nframes 3\ncommand wait-autosave\n"
                                                     "screenshot " +
                                                     (dir / "autosaved.png") + "\nframes 90000\n");
  facet::testing::BackgroundRender session = facet::testing::StartRender(
      dir, "session", {"--autosave", project, "-o", dir / "session.png", "--script", dir / "session.txt"});
  const bool autosaved = facet::testing::WaitForFile(dir / "autosaved.png", &session, 240.0);
  CHECK(facet::testing::StopRender(&session, SIGKILL) == SIGKILL);
  INFO("stderr: " << facet::testing::ReadText(dir / "session.stderr.txt"));
  REQUIRE(autosaved);
  const facet::RecoveryLoadResult left = facet::LoadRecovery(recovery);
  REQUIRE_MESSAGE(left.ok(), left.error);
  CHECK(Labels(left.document.undo_stack()) == std::vector<std::string>{label + " (unfinished)"});
  const facet::Pin* held = PinOf(left.document.project(), kDraggedPin);
  REQUIRE(held != nullptr);
  CHECK((held->uv_px - moved->uv_px).norm() < 1e-9);  // where the mouse was when it was written

  const nlohmann::json restored =
      RenderAutosave(dir, project, "restore", "frames 2\ncommand recover restore\nframes 2\n");
  INFO(facet::testing::ReportLog(restored));
  CHECK(Labels(restored.at("undo_stack")) == std::vector<std::string>{label + " (unfinished)"});
  CHECK(ReportProject(restored) == left.document.project());
  CHECK(restored.at("dirty") == true);
}

TEST_CASE("a failed autosave is reported once, and written at the next edit once the cause is gone") {
  // The recovery file a link into a missing folder: every write fails at once (a link at the
  // recovery file's name is refused, core/util/file_write.h).
  const TempDir dir("autosave_fail");
  const std::string project = CopySample(dir);
  const std::string blocker = project + ".recovery";
  fs::create_symlink(dir / "missing/leuven.facet.recovery", blocker);
  // Two edits, each tried once (20 and 60 frames after them: no attempt per frame; the 60 leave
  // the second attempt time to end under a sanitizer, whose write throttle is longer); then the
  // test removes the folder and a third edit is written.
  facet::testing::WriteText(dir / "fail.txt",
                            "frames 2\n"
                            "command add box\n"
                            "frames 20\n"
                            "command add box\n"
                            "frames 60\n"
                            "screenshot " +
                                (dir / "failed.png") +
                                "\n"
                                "command wait-removed " +
                                blocker +
                                "\n"
                                "command add box\n"
                                "command wait-autosave\n"
                                "frames 2\n");
  facet::testing::BackgroundRender session = facet::testing::StartRender(
      dir, "fail",
      {"--autosave", project, "-o", dir / "fail.png", "--script", dir / "fail.txt", "--report", dir / "fail.json"});
  const bool failed = facet::testing::WaitForFile(dir / "failed.png", &session, 240.0);
  const bool still_blocked = fs::is_symlink(blocker);
  fs::remove(blocker);
  const bool reported = failed && facet::testing::WaitForFile(dir / "fail.json", &session, 240.0);
  // The report is written before the exit's clean-up: wait for the exit itself.
  const bool exited_cleanly = reported && facet::testing::WaitForExit(&session, 240.0);
  if (!reported) facet::testing::StopRender(&session, SIGKILL);
  INFO("stderr: " << facet::testing::ReadText(dir / "fail.stderr.txt"));
  REQUIRE(failed);
  REQUIRE(reported);
  CHECK(exited_cleanly);
  CHECK(still_blocked);
  const nlohmann::json report = facet::testing::ReadJson(dir / "fail.json");
  const std::string log = facet::testing::ReportLog(report);
  INFO(log);
  const nlohmann::json& autosave = report.at("autosave");
  // One attempt per edit, never one per frame; one warning for the two.
  CHECK(autosave.at("failures").get<int>() == 2);
  CHECK(autosave.at("writes").get<int>() >= 1);
  size_t warnings = 0;
  for (size_t at = log.find("warning: Autosave: "); at != std::string::npos;
       at = log.find("warning: Autosave: ", at + 1))
    ++warnings;
  CHECK(warnings == 1);
  CHECK(log.find("warning: Autosave: refusing to write " + blocker + ": it is a symbolic link (to " +
                 (dir / "missing/leuven.facet.recovery") + "), not a file Facet wrote") != std::string::npos);
  CHECK(log.find("(trying again at the next change, or in 30 s)") != std::string::npos);
  CHECK(log.find("info: Autosave: written to " + blocker + " again") != std::string::npos);
  CHECK(Labels(report.at("undo_stack")) == std::vector<std::string>{"Add box", "Add box", "Add box"});
  CHECK_FALSE(fs::exists(blocker));  // the clean exit removed the file it wrote
}

TEST_CASE("an unsaved project's recovery file is offered at start and restores as an unsaved project") {
  const TempDir dir("autosave_untitled");
  CopySample(dir);
  // What a crashed unsaved session left: the photo added by absolute path, two edits, one
  // more appended to the journal and then a record cut short by the crash.
  facet::Project start;
  {
    facet::Project sample = facet::testing::LoadProjectFile(kSampleFolder + "leuven.facet");
    start.next_id = sample.next_id;
    start.images = sample.images;
    start.images[0].path = dir / "leuvenA.jpg";
  }
  facet::Document document(start);
  facet::Project edited = start;
  edited.units = "ft";
  REQUIRE(document.Commit("Units", edited));
  const std::string folder = dir / "data/facet/recovery";
  fs::create_directories(folder);
  const std::string recovery = folder + "/untitled-2147483000.facet.recovery";  // no such process
  facet::RecoveryJournal journal;
  facet::RecoveryWritten written;
  REQUIRE(journal.Write(recovery, facet::MakeRecoveryDelta(document, nullptr, &written)).ok());
  edited.units = "yd";
  REQUIRE(document.Commit("Units again", edited));
  const facet::RecoveryWriteResult appended =
      journal.Write(recovery, facet::MakeRecoveryDelta(document, nullptr, &written));
  REQUIRE(appended.ok());
  REQUIRE_FALSE(appended.compacted);
  {
    std::ofstream torn(recovery, std::ios::app | std::ios::binary);
    torn << "journal 120 0000";
  }

  // At start, with no project: the dialog offers it.
  const nlohmann::json offered = RenderAutosave(dir, "", "offered", "frames 2\n");
  INFO(facet::testing::ReportLog(offered));
  CHECK(offered.at("dialog") == "recover");
  CHECK(offered.at("autosave").at("offer") == recovery);
  CHECK(LogHas(offered, recovery + ": journal[1]: the header line is incomplete (a write cut short by a crash): its 16 "
                                   "bytes are dropped and the document is restored as of journal[0]"));
  CHECK(fs::exists(recovery));  // nothing answered: kept

  const nlohmann::json restored =
      RenderAutosave(dir, "", "restored", "frames 2\nclick left item recover.restore\nframes 2\n");
  INFO(facet::testing::ReportLog(restored));
  CHECK(LogHas(restored, "Restored from " + recovery + " (2 edits to undo, 0 to redo)"));
  CHECK(Labels(restored.at("undo_stack")) == std::vector<std::string>{"Units", "Units again"});
  CHECK(ReportProject(restored) == document.project());
  CHECK(restored.at("project_path") == "");
  CHECK(restored.at("dirty") == true);
  CHECK(restored.at("dialog") == "");
}

namespace {

// The files in `dir` whose name starts with `prefix`.
std::vector<std::string> FilesStartingWith(const TempDir& dir, const std::string& prefix) {
  std::vector<std::string> found;
  for (const auto& entry : fs::directory_iterator(dir / ""))
    if (entry.path().filename().string().rfind(prefix, 0) == 0) found.push_back(entry.path().string());
  return found;
}

size_t Count(const std::string& text, const std::string& part) {
  size_t n = 0;
  for (size_t at = text.find(part); at != std::string::npos; at = text.find(part, at + 1)) ++n;
  return n;
}

}  // namespace

TEST_CASE("a link at the recovery file's name is refused by name, and what it points to is untouched") {
  const TempDir dir("autosave_link");
  const std::string project = CopySample(dir);
  fs::copy_file(project, dir / "other.facet");
  const std::string recovery = project + ".recovery";
  // To another project, then to the project itself: either was overwritten by the first autosave.
  for (const std::string& target : {dir / "other.facet", project}) {
    CAPTURE(target);
    const std::string bytes_before = facet::testing::ReadText(target);
    fs::remove(recovery);
    fs::create_symlink(target, recovery);
    const nlohmann::json report = RenderAutosave(dir, project, "link",
                                                 "frames 2\n"
                                                 "command add box\n"
                                                 "frames 20\n"
                                                 "command add box\n"
                                                 "frames 60\n");
    const std::string log = facet::testing::ReportLog(report);
    INFO(log);
    CHECK(facet::testing::ReadText(target) == bytes_before);
    CHECK(fs::is_symlink(recovery));  // neither replaced nor removed at exit
    CHECK(LogHas(report, "Recovery file " + recovery +
                             " is a symbolic link: not read, and autosave will not write through it until it is "
                             "removed"));
    // Each edit is refused, reported once: the user is told autosave is not protecting them.
    CHECK(report.at("autosave").at("failures").get<int>() == 2);
    CHECK(report.at("autosave").at("writes").get<int>() == 0);
    CHECK(Count(log, "warning: Autosave: refusing to write " + recovery + ": it is a symbolic link (to " + target +
                         "), not a file Facet wrote") == 1);
    CHECK(Labels(report.at("undo_stack")) == std::vector<std::string>{"Add box", "Add box"});
  }
}

TEST_CASE("a recovery file that is refused is moved aside with its bytes, never replaced nor deleted") {
  const TempDir dir("autosave_refused");
  const std::string project = CopySample(dir);
  const facet::Project saved = facet::testing::LoadProjectFile(project);
  const std::string recovery = project + ".recovery";
  facet::Document document(saved);
  facet::Project edited = saved;
  edited.units = "ft";
  REQUIRE(document.Commit("Units", edited));
  std::string error;
  const std::string good = facet::RecoveryToText(document, &error);
  REQUIRE(error.empty());
  std::string damaged_base = good;
  damaged_base[good.size() - 3] ^= 0x01;  // in the base's payload: its checksum fails
  struct Case {
    const char* name;
    std::string bytes;
    std::string why;
  };
  const Case cases[] = {
      {"written by a newer Facet", "facet-recovery 3\n" + good.substr(good.find('\n') + 1),
       "version: \"facet-recovery 3\" is not a version this build reads"},
      {"a damaged base", damaged_base, "base: its checksum does not match"},
  };
  for (const Case& c : cases) {
    CAPTURE(c.name);
    for (const std::string& old : FilesStartingWith(dir, "leuven.facet.recovery.broken-")) fs::remove(old);
    facet::testing::WriteText(recovery, c.bytes);
    // Edits after it: the autosave writes a new file of its own and removes it at exit.
    const nlohmann::json report =
        RenderAutosave(dir, project, "refused", "frames 2\ncommand add box\ncommand wait-autosave\nframes 2\n");
    const std::string log = facet::testing::ReportLog(report);
    INFO(log);
    const std::vector<std::string> aside = FilesStartingWith(dir, "leuven.facet.recovery.broken-");
    REQUIRE(aside.size() == 1);
    CHECK(facet::testing::ReadText(aside[0]) == c.bytes);
    CHECK(LogHas(report, "Recovery file not restored: " + recovery + ": " + c.why));
    CHECK(LogHas(report, "; the file is kept as " + aside[0] + "; " + project + " opened as saved"));
    CHECK(report.at("autosave").at("writes").get<int>() >= 1);
    CHECK(Labels(report.at("undo_stack")) == std::vector<std::string>{"Add box"});
    CHECK_FALSE(fs::exists(recovery));  // the session's own file, removed at the clean exit
  }
}

TEST_CASE("a recovery file that restores only in part is offered, and kept aside whatever the answer") {
  const TempDir dir("autosave_partial");
  const std::string project = CopySample(dir);
  const facet::Project saved = facet::testing::LoadProjectFile(project);
  const std::string recovery = project + ".recovery";
  // The base, one journal record (units ft), then a whole record (its checksum right) whose
  // edit does not apply: it starts from yards.
  facet::Document document(saved);
  facet::RecoveryJournal journal;
  facet::RecoveryWritten written;
  REQUIRE(journal.Write(recovery, facet::MakeRecoveryDelta(document, nullptr, &written)).ok());
  facet::Project edited = saved;
  edited.units = "ft";
  REQUIRE(document.Commit("Units", edited));
  REQUIRE_FALSE(journal.Write(recovery, facet::MakeRecoveryDelta(document, nullptr, &written)).compacted);
  const std::string bad = R"({"undo_keep":1,"redo_keep":0,"undo":[{"label":"Units","units":["yd","in"]}],)"
                          R"("redo":[],"clean_undo_depth":0,"clean_is_unreachable":false})";
  const std::string header_and_base = facet::FrameRecoveryRecords({"{}"});
  const std::string bad_frame = facet::FrameRecoveryRecords({"{}", bad}).substr(header_and_base.size());
  facet::testing::WriteText(recovery, facet::testing::ReadText(recovery) + bad_frame);
  const std::string original = facet::testing::ReadText(recovery);

  for (const std::string answer : {"restore", "discard"}) {
    CAPTURE(answer);
    for (const std::string& old : FilesStartingWith(dir, "leuven.facet.recovery.broken-")) fs::remove(old);
    facet::testing::WriteText(recovery, original);
    const nlohmann::json report =
        RenderAutosave(dir, project, answer, "frames 2\nclick left item recover." + answer + "\nframes 2\n");
    const std::string log = facet::testing::ReportLog(report);
    INFO(log);
    CHECK(LogHas(report, recovery + ": journal[1].undo[0]: does not apply onto the project: units"));
    CHECK(LogHas(report, "journal[1] and what follows it (" + std::to_string(bad_frame.size()) +
                             " bytes) are dropped and the document is restored as of journal[0]"));
    const std::vector<std::string> aside = FilesStartingWith(dir, "leuven.facet.recovery.broken-");
    REQUIRE(aside.size() == 1);
    CHECK(facet::testing::ReadText(aside[0]) == original);
    CHECK(LogHas(report, "the file is kept as " + aside[0]));
    if (answer == "restore") {
      CHECK(LogHas(report, "Restored from " + recovery + " (1 edit to undo, 0 to redo)"));
      CHECK(Labels(report.at("undo_stack")) == std::vector<std::string>{"Units"});
      CHECK(ReportProject(report).units == "ft");
    } else {
      CHECK(report.at("undo_stack").empty());
      CHECK(ReportProject(report) == saved);
    }
  }
}
