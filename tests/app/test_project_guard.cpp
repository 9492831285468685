// Two Facets on one project (issue 25) through the real application: the second is told by
// name who has the project open and, read-only, writes neither the project nor its recovery
// file, and its `command save` is refused; a real second process on a project another render
// is editing leaves that render's recovery file and save alone; Open a copy saves under a new
// name and locks it; a save after the project file changed on disk is refused (script) or
// asked (Ctrl+S: Cancel writes nothing, Overwrite writes); `facet solve -o` onto a project
// open elsewhere is refused; edits made while a recovery offer waits are autosaved, the
// offered file kept aside and put back at exit, and edits replaced by Restore kept.
#include <doctest/doctest.h>

#include <signal.h>
#include <unistd.h>

#include <string>
#include <vector>

#include "core/io/project_io.h"
#include "core/io/recovery_io.h"
#include "core/scene/document.h"
#include "core/util/project_lock.h"
#include "tests/app/app_test_util.h"

namespace {

using facet::testing::TempDir;
namespace fs = std::filesystem;

const std::string kSampleFolder = std::string(FACET_SOURCE_DIR) + "/assets/samples/leuven/";

// A private copy of the Leuven sample (project and photo) in `dir` under `name`.
std::string CopySample(const TempDir& dir, const std::string& name = "leuven.facet") {
  fs::copy_file(kSampleFolder + "leuven.facet", dir / name, fs::copy_options::overwrite_existing);
  fs::copy_file(kSampleFolder + "leuvenA.jpg", dir / "leuvenA.jpg", fs::copy_options::overwrite_existing);
  return dir / name;
}

std::string Bytes(const std::string& path) { return facet::testing::ReadText(path); }

bool LogHas(const nlohmann::json& report, const std::string& text) {
  return facet::testing::ReportLog(report).find(text) != std::string::npos;
}

facet::Project ReportProject(const nlohmann::json& report) {
  const facet::ProjectLoadResult loaded = facet::ProjectFromJson(report.at("project").dump());
  REQUIRE_MESSAGE(loaded.ok(), loaded.error);
  return loaded.project;
}

std::vector<std::string> UndoLabels(const std::string& recovery) {
  const facet::RecoveryLoadResult loaded = facet::LoadRecovery(recovery);
  REQUIRE_MESSAGE(loaded.ok(), loaded.error);
  std::vector<std::string> labels;
  for (const facet::Edit& edit : loaded.document.undo_stack()) labels.push_back(edit.label);
  return labels;
}

// `render --autosave [PROJECT] -o ... --script ... --report ...`, required to succeed.
nlohmann::json Render(const TempDir& dir, const std::string& project, const std::string& name,
                      const std::string& script) {
  facet::testing::WriteText(dir / (name + ".txt"), script);
  const facet::testing::RunResult run =
      facet::testing::RunRender(dir, "--autosave '" + project + "' -o '" + (dir / (name + ".png")) + "' --script '" +
                                         (dir / (name + ".txt")) + "' --report '" + (dir / (name + ".json")) + "'");
  INFO("stderr: " << run.stderr_text);
  REQUIRE(run.exit_code == 0);
  return facet::testing::ReadJson(dir / (name + ".json"));
}

// Files in `dir` whose names start with `prefix`.
std::vector<std::string> FilesStartingWith(const TempDir& dir, const std::string& prefix) {
  std::vector<std::string> names;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir.path)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind(prefix, 0) == 0) names.push_back(name);
  }
  std::sort(names.begin(), names.end());
  return names;
}

}  // namespace

TEST_CASE("a project open in another Facet: the second is told by name, and read-only writes nothing") {
  const TempDir dir("guard_read_only");
  const std::string project = CopySample(dir);
  const std::string other = CopySample(dir, "other.facet");
  const std::string recovery = project + ".recovery";
  // The other Facet: this test process holds the lock and has a recovery file of its own.
  facet::ProjectLockResult held = facet::TryLockProject(project);
  REQUIRE_MESSAGE(held.ok(), held.error);
  facet::testing::WriteText(recovery, "the other Facet's recovery file");
  const std::string project_bytes = Bytes(project);
  const std::string holder = "leuven.facet is open in another Facet (pid " + std::to_string(::getpid()) + ", since ";

  // File > Open (the script's `open`) asks; the report shows the question's dialog.
  const nlohmann::json asked = Render(dir, other, "asked", "frames 2\ncommand open " + project + "\nframes 3\n");
  INFO(facet::testing::ReportLog(asked));
  CHECK(asked.at("dialog") == "project-locked");
  CHECK(LogHas(asked, "Cannot open " + project + " for editing: " + holder));
  CHECK(asked.at("project_lock").at("question_path") == project);
  CHECK(asked.at("project_path") == other);  // nothing opened yet

  // Open read-only, edit, give the autosave two seconds, and press Ctrl+S: Save as.
  const nlohmann::json read_only = Render(dir, other, "read_only",
                                          "frames 2\ncommand open " + project +
                                              "\nframes 3\n"
                                              "click left item locked.read_only\n"
                                              "frames 2\n"
                                              "command add box\n"
                                              "command add wedge on-top\n"
                                              "frames 120\n"
                                              "key ctrl+s\n"
                                              "frames 3\n");
  INFO(facet::testing::ReportLog(read_only));
  CHECK(read_only.at("project_path") == project);
  CHECK(read_only.at("project_lock").at("read_only") == true);
  CHECK(read_only.at("project_lock").at("held") == false);
  CHECK(LogHas(read_only, "Opened " + project + " read-only (" + holder));
  CHECK(read_only.at("dirty") == true);
  CHECK(read_only.at("autosave").at("writes") == 0);
  CHECK(read_only.at("autosave").at("offer") == "");  // the other Facet's file is not offered
  CHECK(read_only.at("dialog") == "save-as");
  CHECK(Bytes(project) == project_bytes);
  CHECK(Bytes(recovery) == "the other Facet's recovery file");
  CHECK(FilesStartingWith(dir, "leuven.facet") ==
        std::vector<std::string>{"leuven.facet", "leuven.facet.lock", "leuven.facet.recovery"});

  // A script's `save` onto it is refused by name; an offscreen start opens it read-only.
  const std::string refused =
      facet::testing::RenderScriptRefused(dir, project, "refused", "frames 2\ncommand add box\ncommand save\n");
  CHECK(refused.find("Cannot save " + project + ": " + holder) != std::string::npos);
  CHECK(Bytes(project) == project_bytes);
  CHECK(Bytes(recovery) == "the other Facet's recovery file");

  // Once the other Facet is gone, the lock is this one's.
  held.lock.Release();
  const nlohmann::json freed = Render(dir, project, "freed", "frames 2\n");
  CHECK(freed.at("project_lock").at("read_only") == false);
  CHECK(freed.at("project_lock").at("held") == true);
  CHECK(freed.at("project_lock").at("lock_file") == project + ".lock");
  CHECK_FALSE(fs::exists(project + ".lock"));  // released at exit
}

TEST_CASE("Open a copy saves the project under a new name, and locks that one") {
  const TempDir dir("guard_copy");
  const std::string project = CopySample(dir);
  const std::string other = CopySample(dir, "other.facet");
  facet::ProjectLockResult held = facet::TryLockProject(project);
  REQUIRE(held.ok());
  const std::string project_bytes = Bytes(project);

  // The Save as browser proposes "leuven-copy.facet" in the project's folder: Enter saves.
  const nlohmann::json copied = Render(dir, other, "copied",
                                       "frames 2\ncommand open " + project +
                                           "\nframes 3\n"
                                           "click left item locked.copy\n"
                                           "frames 3\n"
                                           "key enter\n"
                                           "frames 3\n"
                                           "command add box\n"
                                           "command wait-autosave\n");
  INFO(facet::testing::ReportLog(copied));
  const std::string copy = dir / "leuven-copy.facet";
  CHECK(copied.at("dialog") == "");
  CHECK(copied.at("project_path") == copy);
  CHECK(copied.at("project_lock").at("read_only") == false);
  CHECK(copied.at("project_lock").at("lock_file") == copy + ".lock");
  CHECK(copied.at("autosave").at("recovery_file") == copy + ".recovery");  // edits are autosaved again
  CHECK(facet::testing::LoadProjectFile(copy) == facet::testing::LoadProjectFile(project));
  CHECK(Bytes(project) == project_bytes);
  CHECK_FALSE(fs::exists(project + ".recovery"));
}

TEST_CASE("a second process on a project another render edits leaves its recovery file and its save alone") {
  const TempDir dir("guard_two_processes");
  const std::string project = CopySample(dir);
  const std::string recovery = project + ".recovery";
  // A: edits, autosaves, waits while B runs (each wait at most 120 s: one per B run), then saves.
  const std::string go1 = dir / "go1", go2 = dir / "go2";
  facet::testing::WriteText(go1, "");
  facet::testing::WriteText(go2, "");
  facet::testing::WriteText(dir / "a.txt", "frames 2\ncommand add box\ncommand wait-autosave\nscreenshot " +
                                               (dir / "a_ready.png") + "\ncommand wait-removed " + go1 + "\ncommand wait-removed " +
                                               go2 + "\ncommand save\nframes 2\n");
  facet::testing::BackgroundRender a = facet::testing::StartRender(
      dir, "a", {"--autosave", project, "-o", dir / "a.png", "--script", dir / "a.txt", "--report", dir / "a.json"});
  const bool ready = facet::testing::WaitForFile(dir / "a_ready.png", &a, 240.0);
  if (!ready) facet::testing::StopRender(&a, SIGKILL);
  INFO("A's stderr: " << facet::testing::ReadText(dir / "a.stderr.txt"));
  REQUIRE(ready);
  REQUIRE(fs::exists(recovery));
  const std::string a_recovery = Bytes(recovery);

  // B on the same project: read-only, its edits autosaved nowhere, its exit removes nothing.
  const nlohmann::json b = Render(dir, project, "b", "frames 2\ncommand add wedge\ncommand add box\nframes 120\n");
  INFO(facet::testing::ReportLog(b));
  CHECK(b.at("project_lock").at("read_only") == true);
  CHECK(b.at("autosave").at("writes") == 0);
  CHECK(Bytes(recovery) == a_recovery);
  fs::remove(go1);
  // B's save is refused by name.
  const std::string refused =
      facet::testing::RenderScriptRefused(dir, project, "b_save", "frames 2\ncommand add wedge\ncommand save\n");
  CHECK(refused.find("leuven.facet is open in another Facet (pid " + std::to_string(a.pid)) != std::string::npos);
  CHECK(Bytes(recovery) == a_recovery);

  // A saves: its file was not touched, so the save goes through and its recovery file goes.
  fs::remove(go2);
  int status = 0;
  for (int i = 0; i < 6000 && !a.reaped; ++i) {
    if (::waitpid(a.pid, &status, WNOHANG) == a.pid) a.reaped = true, a.status = status;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  REQUIRE(a.reaped);
  CHECK(WIFEXITED(a.status));
  CHECK(WEXITSTATUS(a.status) == 0);
  const nlohmann::json a_report = facet::testing::ReadJson(dir / "a.json");
  INFO(facet::testing::ReportLog(a_report));
  CHECK(a_report.at("dirty") == false);
  CHECK(facet::testing::LoadProjectFile(project) == ReportProject(a_report));
  CHECK_FALSE(fs::exists(recovery));
  CHECK_FALSE(fs::exists(project + ".lock"));
}

TEST_CASE("a save after the project file changed on disk is refused or asked, and nothing is overwritten unasked") {
  const TempDir dir("guard_changed");
  const std::string project = CopySample(dir);
  facet::Project theirs = facet::testing::LoadProjectFile(project);
  theirs.units = "ft";  // what another program writes meanwhile

  // Runs `script_before`, signals, waits for `go` to go, then runs `script_after`; the test
  // writes their version of the project in between.
  auto run_with_change = [&](const std::string& name, const std::string& script_after, bool expect_ok) {
    fs::copy_file(kSampleFolder + "leuven.facet", project, fs::copy_options::overwrite_existing);
    const std::string go = dir / (name + "_go"), ready = dir / (name + "_ready.png");
    facet::testing::WriteText(go, "");
    facet::testing::WriteText(dir / (name + ".txt"), "frames 2\ncommand add box\nscreenshot " + ready +
                                                         "\ncommand wait-removed " + go + "\n" + script_after);
    facet::testing::BackgroundRender run = facet::testing::StartRender(
        dir, name,
        {project, "-o", dir / (name + ".png"), "--script", dir / (name + ".txt"), "--report", dir / (name + ".json")});
    const bool started = facet::testing::WaitForFile(ready, &run, 240.0);
    if (!started) facet::testing::StopRender(&run, SIGKILL);
    REQUIRE(started);
    REQUIRE(facet::SaveProject(theirs, project).empty());
    fs::remove(go);
    int status = 0;
    for (int i = 0; i < 6000 && !run.reaped; ++i) {
      if (::waitpid(run.pid, &status, WNOHANG) == run.pid) run.reaped = true, run.status = status;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    REQUIRE(run.reaped);
    const std::string stderr_text = facet::testing::ReadText(dir / (name + ".stderr.txt"));
    INFO("stderr: " << stderr_text);
    CHECK(WIFEXITED(run.status));
    CHECK((WEXITSTATUS(run.status) == 0) == expect_ok);
    return stderr_text;
  };

  // A script's save is refused with the reason.
  const std::string refused = run_with_change("script", "command save\n", false);
  CHECK(refused.find("Cannot save " + project + ": leuven.facet changed on disk since it was opened or saved here") !=
        std::string::npos);
  CHECK(facet::testing::LoadProjectFile(project) == theirs);

  // Ctrl+S asks: Cancel writes nothing (checked while the run waits), Overwrite writes.
  const std::string cancelled = dir / "cancelled";
  facet::testing::WriteText(cancelled, "");
  // The second wait lets the test look at the file after Cancel, before Overwrite.
  std::thread check_after_cancel;
  const std::string asked_script = "key ctrl+s\nframes 3\nscreenshot " + (dir / "asked.png") +
                                   "\nclick left item changed.cancel\nframes 2\nscreenshot " +
                                   (dir / "after_cancel.png") + "\ncommand wait-removed " + cancelled +
                                   "\nkey ctrl+s\nframes 3\nclick left item changed.overwrite\nframes 3\n";
  // Removing `cancelled` once the cancel's marker is there, after checking the file.
  bool theirs_after_cancel = false;
  struct JoinAtExit {
    std::thread* thread;
    ~JoinAtExit() {
      if (thread->joinable()) thread->join();
    }
  } join_at_exit{&check_after_cancel};
  check_after_cancel = std::thread([&]() {
    for (int i = 0; i < 12000 && !fs::exists(dir / "after_cancel.png"); ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    const facet::ProjectLoadResult loaded = facet::LoadProject(project);
    theirs_after_cancel = loaded.ok() && loaded.project == theirs;
    fs::remove(cancelled);
  });
  run_with_change("asked", asked_script, true);
  if (check_after_cancel.joinable()) check_after_cancel.join();
  CHECK(theirs_after_cancel);
  const nlohmann::json asked = facet::testing::ReadJson(dir / "asked.json");
  INFO(facet::testing::ReportLog(asked));
  CHECK(LogHas(asked, "Cannot save " + project + ": leuven.facet changed on disk"));
  CHECK(asked.at("dialog") == "");
  CHECK(asked.at("dirty") == false);
  CHECK(facet::testing::LoadProjectFile(project) == ReportProject(asked));
  CHECK(ReportProject(asked).units != "ft");
}

TEST_CASE("facet solve -o onto a project open in another Facet is refused by name") {
  const TempDir dir("guard_solve");
  const std::string project = CopySample(dir);
  facet::ProjectLockResult held = facet::TryLockProject(project);
  REQUIRE(held.ok());
  const std::string before = Bytes(project);
  const facet::testing::CliResult run = facet::testing::RunFacet(dir, "solve '" + project + "' -o '" + project + "'");
  CHECK(run.exit_code == 1);
  CHECK(run.err.find("facet solve: cannot write " + project + ": leuven.facet is open in another Facet (pid " +
                     std::to_string(::getpid())) != std::string::npos);
  CHECK(Bytes(project) == before);
  // Into another file it solves as before.
  const facet::testing::CliResult elsewhere =
      facet::testing::RunFacet(dir, "solve '" + project + "' -o '" + (dir / "solved.facet") + "'");
  CHECK_MESSAGE(elsewhere.exit_code == 0, elsewhere.err);
  CHECK_FALSE(fs::exists(dir / "solved.facet.lock"));
}

TEST_CASE("edits made while a recovery offer waits are autosaved, and the offered file is kept") {
  const TempDir dir("guard_pending_offer");
  const std::string project = CopySample(dir);
  const std::string recovery = project + ".recovery";
  const facet::Project saved = facet::testing::LoadProjectFile(project);
  auto write_offer = [&]() {
    facet::Document document(saved);
    facet::Project edited = saved;
    edited.units = "ft";
    REQUIRE(document.Commit("Units", edited));
    REQUIRE(facet::SaveRecovery(document, recovery).empty());
  };
  write_offer();
  const std::string offered = Bytes(recovery);

  // Unanswered: the edits go to the usual file, the offered one is kept aside meanwhile and
  // put back at the clean exit, for the next start to offer again.
  const nlohmann::json pending = Render(dir, project, "pending",
                                        "frames 2\ncommand add box\ncommand add wedge on-top\n"
                                        "command wait-autosave\n");
  INFO(facet::testing::ReportLog(pending));
  CHECK(pending.at("dialog") == "recover");
  const std::string aside = pending.at("autosave").at("offer").get<std::string>();
  CHECK(aside.rfind(recovery + ".unanswered-", 0) == 0);
  CHECK(pending.at("autosave").at("recovery_file") == recovery);
  CHECK(pending.at("autosave").at("writes").get<int>() >= 1);
  CHECK(LogHas(pending, "The offered recovery file is kept as " + aside));
  CHECK(Bytes(recovery) == offered);  // back at exit
  CHECK_FALSE(fs::exists(aside));

  // Restore after edits: the edits it replaces are kept beside it.
  const nlohmann::json restored = Render(dir, project, "restored",
                                         "frames 2\ncommand add box\ncommand wait-autosave\n"
                                         "command recover restore\nframes 2\ncommand wait-autosave\n");
  INFO(facet::testing::ReportLog(restored));
  CHECK(restored.at("dialog") == "");
  CHECK(ReportProject(restored).units == "ft");
  const std::vector<std::string> replaced = FilesStartingWith(dir, "leuven.facet.recovery.replaced-");
  REQUIRE(replaced.size() == 1);
  CHECK(LogHas(restored, "The edits made before Restore are kept in " + (dir / replaced[0])));
  CHECK(UndoLabels(dir / replaced[0]) == std::vector<std::string>{"Add box"});
  CHECK(FilesStartingWith(dir, "leuven.facet.recovery.unanswered-").empty());
}
