#include "app/state/autosave.h"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <limits>
#include <system_error>

#include "app/state/app_state.h"
#include "core/io/recovery_io.h"
#include "core/util/file_write.h"

namespace facet::app {
namespace {

namespace fs = std::filesystem;

// How long a drag may go on before its unfinished state is written, and how long to wait
// before trying again after a failed write (a full disk, a read-only folder).
constexpr double kIntervalS = 30.0;
// A write starts at most once per this many times the last write's duration (autosave.h).
constexpr double kThrottleFactor = 10.0;
// written_revision after writing an unfinished drag: no document revision, so the next
// completed edit (or the drag's cancel) writes again.
constexpr std::uint64_t kDragRevision = std::numeric_limits<std::uint64_t>::max();
constexpr const char* kUntitledPrefix = "untitled-";
constexpr const char* kRecoverySuffix = ".facet.recovery";

double MsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

// Removes a recovery file this session wrote. Only a regular file: a link or a device put
// in its place since is not Facet's (fs::remove would delete the link, never its target, but
// the link is the user's too).
void RemoveFile(const std::string& path) {
  if (!DescribeNonRegular(path).empty()) return;
  std::error_code ec;
  fs::remove(path, ec);
}

// Keeps a recovery file that will not be restored whole out of autosave's way (it would
// otherwise be replaced by the next write and removed at exit): what the log says about it.
std::string KeepAside(const std::string& path) {
  std::string moved_to;
  const std::string error = MoveFileAside(path, "broken", &moved_to);
  if (!error.empty()) return error + " (the next autosave replaces it)";
  return "the file is kept as " + moved_to;
}

void StartWrite(AppState* state, const Edit* unfinished, const std::string& path, std::uint64_t revision) {
  AutosaveState& autosave = state->autosave;
  const auto snapshot_start = std::chrono::steady_clock::now();
  RecoveryDelta delta = MakeRecoveryDelta(state->document, unfinished, &autosave.written);
  autosave.stats.last_snapshot_ms = MsSince(snapshot_start);
  AutosaveJob job;
  job.path = path;
  job.started_s = state->time_s;
  job.revision = revision;
  // The worker owns the delta and, until it is done, the journal: the document goes on
  // changing on the main thread meanwhile.
  job.result = std::async(std::launch::async, [path, journal = autosave.journal, delta = std::move(delta)]() mutable {
    const auto start = std::chrono::steady_clock::now();
    AutosaveWrite write;
    std::error_code ec;
    fs::create_directories(fs::path(path).parent_path().empty() ? fs::path(".") : fs::path(path).parent_path(), ec);
    write.result = journal->Write(path, std::move(delta));
    write.ms = MsSince(start);
    return write;
  });
  autosave.job = std::move(job);
}

// Swaps in a finished write (waiting for it when asked).
void CollectWrite(AppState* state, bool wait) {
  AutosaveState& autosave = state->autosave;
  if (!autosave.job) return;
  if (!wait && autosave.job->result.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return;
  const AutosaveWrite write = autosave.job->result.get();
  const AutosaveJob job = {autosave.job->path, autosave.job->started_s, autosave.job->revision, {}};
  autosave.job.reset();
  autosave.next_write_s = job.started_s + std::min(kIntervalS, kThrottleFactor * write.ms / 1000.0);
  const std::string& error = write.result.error;
  if (!error.empty()) {
    ++autosave.stats.failures;
    // Not every frame: at the next change, or in 30 s (the cause may go away on its own).
    autosave.retry_after_s = state->time_s + kIntervalS;
    // The revision the write held, not the document's now: an edit made while the failing
    // write was under way is a change, and is tried at once.
    autosave.failed_revision = job.revision;
    if (error != autosave.last_error)
      state->Log(LogLevel::kWarning, "Autosave: " + error + " (trying again at the next change, or in 30 s)");
    autosave.last_error = error;
    return;
  }
  if (!autosave.last_error.empty()) state->Log(LogLevel::kInfo, "Autosave: written to " + job.path + " again");
  autosave.last_error.clear();
  autosave.retry_after_s = 0.0;
  if (!autosave.owned_path.empty() && autosave.owned_path != job.path) RemoveFile(autosave.owned_path);
  autosave.owned_path = job.path;
  autosave.written_revision = job.revision;
  ++autosave.stats.writes;
  autosave.stats.compactions += write.result.compacted ? 1 : 0;
  autosave.stats.last_write_ms = write.ms;
  autosave.stats.last_bytes = write.result.file_bytes;
  autosave.stats.last_bytes_written = write.result.bytes_written;
  autosave.stats.bytes_written += write.result.bytes_written;
}

// Whether the document's saved state (its clean depth) is `saved`: the project file it was
// opened from. A recovered history whose project file changed since has no saved state.
bool CleanStateIs(const Document& document, const Project& saved) {
  if (document.clean_is_unreachable()) return false;
  Document probe = document;
  while (probe.undo_stack().size() > probe.clean_undo_depth()) probe.Undo();
  while (probe.undo_stack().size() < probe.clean_undo_depth() && probe.Redo()) {
  }
  return probe.undo_stack().size() == probe.clean_undo_depth() && probe.project() == saved;
}

// Renames `path` to `PATH.TAG-YYYYMMDD-HHMMSS[-N]` (core/util/file_write.h, MoveFileAside);
// the new name, or "" when the rename failed.
std::string MoveAside(const std::string& path, const std::string& tag) {
  std::string moved_to;
  return MoveFileAside(path, tag, &moved_to).empty() ? moved_to : std::string();
}

// Whether this session may write its recovery file `target` now. Never for a project opened
// read-only: the file is the other Facet's. While a recovery offer is unanswered, the offered
// file is first moved aside (and kept for the answer), so the edits made meanwhile are
// written without losing it.
bool MayWrite(AppState* state, const std::string& target) {
  if (state->project_guard.read_only) return false;
  std::optional<RecoveryOffer>& offer = state->autosave.offer;
  if (!offer || offer->recovery_path != target) return true;
  const std::string aside = MoveAside(target, "unanswered");
  if (aside.empty()) return false;  // tried again at the next tick; the offered file stays
  state->Log(LogLevel::kInfo, "The offered recovery file is kept as " + aside +
                                  " until it is restored or discarded; new edits are autosaved to " + target);
  offer->set_aside_from = target;
  offer->recovery_path = aside;
  return true;
}

bool ProcessAlive(pid_t pid) { return pid > 0 && (::kill(pid, 0) == 0 || errno == EPERM); }

// The newest recovery file of an unsaved project whose process is gone (not this one).
std::string FindUntitledRecovery() {
  std::error_code ec;
  std::string best;
  fs::file_time_type best_time;
  for (const fs::directory_entry& entry : fs::directory_iterator(RecoveryFolder(), ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind(kUntitledPrefix, 0) != 0 || name.size() <= std::string(kRecoverySuffix).size() ||
        name.compare(name.size() - std::string(kRecoverySuffix).size(), std::string::npos, kRecoverySuffix) != 0)
      continue;
    const std::string pid_text =
        name.substr(std::string(kUntitledPrefix).size(),
                    name.size() - std::string(kUntitledPrefix).size() - std::string(kRecoverySuffix).size());
    char* end = nullptr;
    const long pid = std::strtol(pid_text.c_str(), &end, 10);
    if (end == pid_text.c_str() || *end != '\0') continue;
    if (pid == ::getpid() || ProcessAlive(static_cast<pid_t>(pid))) continue;  // another window's live file
    std::error_code time_ec;
    const fs::file_time_type time = fs::last_write_time(entry.path(), time_ec);
    if (time_ec || entry.symlink_status(time_ec).type() != fs::file_type::regular) continue;
    if (best.empty() || time > best_time) best = entry.path().string(), best_time = time;
  }
  return best;
}

}  // namespace

std::string RecoveryFolder() {
  const char* data_home = std::getenv("XDG_DATA_HOME");
  if (data_home && data_home[0] == '/') return std::string(data_home) + "/facet/recovery";
  const char* home = std::getenv("HOME");
  return std::string(home && home[0] ? home : ".") + "/.local/share/facet/recovery";
}

std::string RecoveryFileFor(const std::string& project_path) {
  if (!project_path.empty()) return project_path + ".recovery";
  return RecoveryFolder() + "/" + kUntitledPrefix + std::to_string(::getpid()) + kRecoverySuffix;
}

void AutosaveTick(AppState* state) {
  AutosaveState& autosave = state->autosave;
  if (!autosave.enabled) return;
  CollectWrite(state, /*wait=*/false);
  // One write at a time (the next one takes the newest document). The offered file is the
  // user's to restore or discard: MayWrite moves it aside before anything is written there.
  if (autosave.job) return;
  const Document& document = state->document;
  const std::string target = RecoveryFileFor(state->project_path);
  if (state->drag_start) {
    // A drag is one edit when it ends; a very long one is written every 30 s as it stands.
    if (!autosave.drag_since_s) autosave.drag_since_s = state->time_s;
    if (state->time_s - *autosave.drag_since_s < kIntervalS || state->time_s < autosave.retry_after_s) return;
    autosave.drag_since_s = state->time_s;
    if (!MayWrite(state, target)) return;
    const Edit unfinished = DiffProjects(state->drag_label + " (unfinished)", *state->drag_start, document.project());
    StartWrite(state, unfinished.Empty() ? nullptr : &unfinished, target, kDragRevision);
    return;
  }
  autosave.drag_since_s.reset();
  if (!document.dirty()) {
    // Saved, or undone back to the saved state: the project file holds it.
    if (!autosave.owned_path.empty()) RemoveFile(autosave.owned_path);
    autosave.owned_path.clear();
    return;
  }
  if (document.revision() == autosave.written_revision && target == autosave.owned_path) return;
  if (state->time_s < autosave.retry_after_s && document.revision() == autosave.failed_revision) return;
  if (state->time_s < autosave.next_write_s) return;
  if (!MayWrite(state, target)) return;
  StartWrite(state, nullptr, target, document.revision());
}

bool WaitForAutosave(AppState* state, std::string* error) {
  if (!state->autosave.enabled) {
    *error = "autosave is off (facet render --autosave turns it on)";
    return false;
  }
  CollectWrite(state, /*wait=*/true);
  state->autosave.retry_after_s = 0.0;  // now, even after a failure or within the throttle
  state->autosave.next_write_s = 0.0;
  AutosaveTick(state);
  CollectWrite(state, /*wait=*/true);
  if (!state->autosave.last_error.empty()) {
    *error = state->autosave.last_error;
    return false;
  }
  return true;
}

void FinishAutosave(AppState* state) {
  AutosaveState& autosave = state->autosave;
  CollectWrite(state, /*wait=*/true);
  if (!autosave.owned_path.empty()) RemoveFile(autosave.owned_path);
  autosave.owned_path.clear();
  // An offer still unanswered goes back where the next start looks for it.
  std::error_code ec;
  if (autosave.offer && !autosave.offer->set_aside_from.empty() &&
      !fs::exists(fs::symlink_status(autosave.offer->set_aside_from, ec)))
    fs::rename(autosave.offer->recovery_path, autosave.offer->set_aside_from, ec);
}

bool FindRecovery(AppState* state, bool also_unsaved) {
  AutosaveState& autosave = state->autosave;
  if (!autosave.enabled) return false;
  autosave.offer.reset();
  std::string path;
  std::error_code ec;
  // A project opened read-only: its recovery file is the other Facet's, live.
  if (!state->project_path.empty() && !state->project_guard.read_only) {
    path = RecoveryFileFor(state->project_path);
    if (const std::string what = DescribeNonRegular(path); !what.empty()) {
      // Planted or left by something else: neither read nor written (core/util/file_write.h).
      state->Log(LogLevel::kWarning, "Recovery file " + path + " is " + what +
                                         ": not read, and autosave will not write through it until it is removed");
      path.clear();
    } else if (!fs::exists(fs::symlink_status(path, ec))) {
      path.clear();
    } else {
      // Older than the project: the project was saved after it (by another window, or a copy
      // put back), so it holds nothing newer. It is left alone and replaced by the next write.
      const auto recovery_time = fs::last_write_time(path, ec);
      const auto project_time = fs::last_write_time(state->project_path, ec);
      if (!ec && recovery_time < project_time) {
        state->Log(LogLevel::kInfo, "Recovery file " + path + " is older than the project: not offered");
        path.clear();
      }
    }
  }
  if (path.empty() && (state->project_path.empty() || also_unsaved)) path = FindUntitledRecovery();
  if (path.empty()) return false;
  RecoveryLoadResult loaded = LoadRecovery(path);
  if (!loaded.ok()) {
    // Refused (a newer version, a damaged base): what it holds may still be rescued by hand,
    // so it is moved out of the way of the next write rather than replaced.
    state->Log(LogLevel::kError,
               "Recovery file not restored: " + loaded.error + "; " + KeepAside(path) +
                   (state->project_path.empty() ? std::string() : "; " + state->project_path + " opened as saved"));
    return false;
  }
  for (const std::string& warning : loaded.warnings) state->Log(LogLevel::kWarning, path + ": " + warning);
  // An unsaved project's file restores as an unsaved project, whatever was opened.
  const bool untitled = fs::path(path).filename().string().rfind(kUntitledPrefix, 0) == 0 &&
                        fs::path(path).parent_path() == fs::path(RecoveryFolder());
  autosave.offer = RecoveryOffer{path, untitled ? std::string() : state->project_path, std::move(loaded.document),
                                 std::string(), !loaded.dropped.empty()};
  return true;
}

void RestoreRecovery(AppState* state) {
  AutosaveState& autosave = state->autosave;
  if (!autosave.offer) return;
  RecoveryOffer offer = std::move(*autosave.offer);
  autosave.offer.reset();
  // Edits made while the offer waited (written to the usual file) are kept beside it.
  CollectWrite(state, /*wait=*/true);
  if (!autosave.owned_path.empty() && autosave.owned_path != offer.recovery_path && state->document.dirty()) {
    const std::string aside = MoveAside(autosave.owned_path, "replaced");
    if (!aside.empty()) {
      state->Log(LogLevel::kInfo, "The edits made before Restore are kept in " + aside);
      autosave.owned_path.clear();
    }
  }
  // The document is dirty unless the recovered state is the saved one; if the project file is
  // not the history's saved state at all, nothing in it counts as saved.
  if (!CleanStateIs(offer.document, state->document.project())) offer.document.ForgetCleanState();
  const size_t undo = offer.document.undo_stack().size(), redo = offer.document.redo_stack().size();
  RestoreDocument(state, std::move(offer.document), offer.project_path);
  // The file holds exactly this document: it stays until a save, and a later write replaces
  // it (an unsaved project's moves to this process's name). One that holds more (records
  // dropped) is kept aside, and the next write starts a new file.
  std::string kept;
  if (offer.holds_more) {
    kept = "; " + KeepAside(offer.recovery_path);
  } else {
    autosave.owned_path = offer.recovery_path;
    autosave.written_revision = state->document.revision();
  }
  state->Log(LogLevel::kInfo, "Restored from " + offer.recovery_path + " (" + std::to_string(undo) +
                                  (undo == 1 ? " edit" : " edits") + " to undo, " + std::to_string(redo) + " to redo)" +
                                  kept);
}

void DiscardRecovery(AppState* state) {
  AutosaveState& autosave = state->autosave;
  if (!autosave.offer) return;
  if (autosave.offer->holds_more) {
    // The user discarded what was offered, not the records that did not read.
    state->Log(LogLevel::kInfo, "Discarded the recovery of " + autosave.offer->recovery_path + "; " +
                                    KeepAside(autosave.offer->recovery_path));
  } else {
    RemoveFile(autosave.offer->recovery_path);
    state->Log(LogLevel::kInfo, "Discarded the recovery file " + autosave.offer->recovery_path);
  }
  autosave.offer.reset();
}

}  // namespace facet::app
