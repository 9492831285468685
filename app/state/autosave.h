// Autosave and crash recovery (issue 14, "work is never lost"). While the document has
// unsaved changes, the whole document, undo and redo history included, is kept in a recovery
// file (core/io/recovery_io.h): brought up to date after every completed edit, undo or redo (a drag
// once it is released, never per drag frame), and every 30 s during a drag that lasts longer
// (the drag then appears as an "(unfinished)" edit). The main thread hands the worker only what
// changed since the last write (MakeRecoveryDelta: the new edits, found by their ids), and the
// worker appends it to the file as a journal record, compacting the file (rewriting it whole,
// atomically) when the journal outgrows the base (core/io/recovery_io.h), so the cost of a
// write is that of the edit, not of the history (tests/bench/bench_recovery.cpp). A crash in the
// middle of an append leaves a torn last record, which the reader drops. A write starts at most
// once per ten times the last write's duration (at most once per 30 s): after a slow write (a
// compaction of a large history) the worker is busy at most a tenth of the time; changes made
// meanwhile are pending and go into the next write. A failed write (a full disk, a folder in
// the way) is logged once until its message changes, and tried again at the next change of the
// document or 30 s later, never every frame; the first success after it is logged too.
//
// Where: beside the project as `NAME.facet.recovery` (not hidden: a user looking for lost work
// finds it next to the project, and the file browser lists only projects, so it does not
// clutter it), or for an unsaved project in `$XDG_DATA_HOME/facet/recovery/untitled-PID.facet
// .recovery` (default ~/.local/share/facet/recovery/). A save, a document with nothing
// unsaved (undone back to the saved state), opening another project and a clean exit remove
// it: after a save the project file holds the state, and the history lives on in memory only.
//
// On start, and after opening a project, a recovery file newer than the project (or, with no
// project, an unsaved project's file left by a process that is gone) is offered: Restore
// loads the recovered document with its history, Discard deletes the file. A recovery file
// that does not read (a newer version, a damaged base) is never replaced nor deleted: it is
// moved aside to `NAME.facet.recovery.broken-YYYYMMDD-HHMMSS` (core/util/file_write.h,
// MoveFileAside), the log says where, and the project opens as saved. One that restores only
// in part (a journal record that does not apply, core/io/recovery_io.h) is offered as far as
// it reads, and moved aside the same way whatever the answer. Edits made while the offer
// waits are autosaved too: the offered file is first moved aside as
// `NAME.facet.recovery.unanswered-DATE` (moved back at a clean exit while still unanswered),
// and edits replaced by Restore are kept as `NAME.facet.recovery.replaced-DATE`.
//
// A project opened read-only (another Facet holds its lock, app/state/project_guard.h) has no
// recovery file here: nothing is written, removed or offered at its recovery path.
//
// The recovery file's name is the program's choice, so a symbolic link, a FIFO or a device at
// that name is not Facet's: it is never read, written through or removed. Finding one is
// logged; each write then fails with a message naming it, logged once as a warning (as any
// failed write, see above) and counted in the failures, until it is removed.
#pragma once

#include <cstdint>
#include <future>
#include <memory>
#include <optional>
#include <string>

#include "core/io/recovery_io.h"
#include "core/scene/document.h"

namespace facet::app {

struct AppState;

// What one write took, for the report and the measurements quoted in the README.
struct AutosaveStats {
  int writes = 0;
  int failures = 0;
  int compactions = 0;            // writes that rewrote the whole file
  double last_snapshot_ms = 0.0;  // main thread: the delta (copying the new edits)
  double last_write_ms = 0.0;     // worker: serialising and writing (fsync included)
  std::uint64_t last_bytes = 0;   // the file's size after the last write
  std::uint64_t last_bytes_written = 0;
  std::uint64_t bytes_written = 0;  // in all
};

struct AutosaveWrite {
  RecoveryWriteResult result;
  double ms = 0.0;
};

struct AutosaveJob {
  std::string path;
  double started_s = 0.0;      // AppState::time_s
  std::uint64_t revision = 0;  // of the document written (kDragRevision for an unfinished drag)
  std::future<AutosaveWrite> result;
};

// A recovery file found at start or on open, waiting for the user's Restore or Discard.
struct RecoveryOffer {
  std::string recovery_path;
  std::string project_path;  // the document's project file; empty for an unsaved project
  Document document;
  // Where the offered file was before an edit made while the offer waited moved it aside
  // (autosave.cpp, MayWrite); empty while it is where it was found.
  std::string set_aside_from;
  // The file holds more than `document` (RecoveryLoadResult::dropped): it is kept aside, not
  // removed, whatever the answer.
  bool holds_more = false;
};

struct AutosaveState {
  bool enabled = false;  // the GUI always; `facet render` with --autosave
  // The recovery file this session wrote and removes when it is no longer needed.
  std::string owned_path;
  std::uint64_t written_revision = 0;  // Document::revision() of what owned_path holds
  // After a failed write: the next attempt, at the next change of the document or 30 s later.
  double retry_after_s = 0.0;
  std::uint64_t failed_revision = 0;
  double next_write_s = 0.0;           // throttle: not before this (see above)
  std::string last_error;              // logged once until it changes
  std::optional<double> drag_since_s;  // when the drag in progress was first seen, or last written
  std::optional<AutosaveJob> job;
  // What the journal has been told (main thread), and the journal itself (the worker's while
  // a job runs).
  RecoveryWritten written;
  std::shared_ptr<RecoveryJournal> journal = std::make_shared<RecoveryJournal>();
  std::optional<RecoveryOffer> offer;
  AutosaveStats stats;
};

// The recovery file of a project (`PATH.recovery`), or of this process's unsaved project.
std::string RecoveryFileFor(const std::string& project_path);
// $XDG_DATA_HOME/facet/recovery (default ~/.local/share/facet/recovery).
std::string RecoveryFolder();

// Per frame: collects a finished write and starts the next one when the document changed.
void AutosaveTick(AppState* state);
// Blocks until the recovery file holds the document as it is now (or is removed, when
// nothing is unsaved). False with *error when autosave is off or the write failed.
bool WaitForAutosave(AppState* state, std::string* error);
// A clean exit: waits for a write in flight and removes this session's recovery file.
void FinishAutosave(AppState* state);

// Looks for a recovery file of the document just opened, then, when there is none and the
// state has no project file or `also_unsaved` (the GUI's start), for an unsaved project's: a
// readable one becomes state->autosave.offer; an unreadable one is logged. Returns whether
// there is an offer.
bool FindRecovery(AppState* state, bool also_unsaved);
// The user's answer to the offer.
void RestoreRecovery(AppState* state);
void DiscardRecovery(AppState* state);

}  // namespace facet::app
