// The recovery file: what autosave writes so that a crash loses no work. It holds the whole
// document (core/scene/document.h): the current project as a project file stores it, the
// undo and redo history with every edit's label and object changes, and the clean depth that
// makes the dirty flag. Objects are written and read by the project file's own writers and
// readers (core/io/project_io_internal.h), image paths exactly as the document holds them
// (relative to the project file's folder, absolute in an unsaved project).
//
// Layout (version 2): a base record of the whole document followed by an append-only journal
// of what changed since, so that keeping the file up to date costs in proportion to each edit,
// not to the history (version 1 rewrote the whole document, history included, after every
// edit: ~0.9 MB more per edit on a 100-box scene). Text: the line "facet-recovery 2", then
// records, each a line "KIND BYTES CRC32" (KIND "base" for the first record, "journal" for the
// others; BYTES the payload's length; CRC32 the IEEE CRC-32 of the payload, 8 lowercase hex
// digits), the payload (one line of compact JSON) and "\n".
// - base: {"project": {a project file of the current version}, "undo": [edit, ...] (oldest
//   first), "redo": [edit, ...] (next redo last), "clean_undo_depth", "clean_is_unreachable"};
//   an edit is {"label", and for each non-empty list of "images", "segments", "primitives",
//   "pins", "constraints", "references": [{"id", "before", "before_index", "after",
//   "after_index"}, ...] (a side absent for an insertion or removal), "units": [before, after]
//   and "next_id": [before, after] when they change}.
// - journal: {"undo_keep", "redo_keep", "undo": [edit, ...], "redo": [edit, ...],
//   "clean_undo_depth", "clean_is_unreachable"}: the undo stack keeps its first undo_keep edits
//   (the project reverts through the ones it drops) and then gains "undo" (the project applies
//   them); the redo stack keeps its first redo_keep and gains "redo". An undo is then
//   {"undo_keep": n - 1, "redo": [that edit]}, a new edit {"undo_keep": n, "undo": [it]}.
// A crash in the middle of an append leaves a last record cut short (or, on a disk that
// reorders writes, one whose checksum fails): the reader drops it and whatever follows, restores
// the document up to the record before it and says so in a warning. A whole journal record
// (its checksum right) whose content does not apply (malformed JSON, an edit that does not fit
// the project, an id beyond kMaxId), or after which the history no longer rebuilds, ends the
// journal the same way: the document is that of the record before, and `dropped` names the
// record and why. The base is only ever written whole (core/util/file_write.h), so a damaged
// base is an error. Version 1's file (the base's JSON object with "format": "facet-recovery",
// "version": 1, unframed) is still read.
//
// Reading is as strict as the project loader's: a malformed file, or a history that does not
// lead exactly to its project (Document::Rebuild), is an error naming the record, the JSON path
// or the edit, never a crash. Ids and next_id are bounded by kMaxId (core/geometry/id_limits.h), as
// in a project file.
//
// Writing never follows a symbolic link nor replaces a device or a FIFO (Symlinks::kRefuse,
// core/util/file_write.h): the file's name is the program's choice, not the user's.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/scene/document.h"

namespace facet {

struct RecoveryLoadResult {
  Document document;
  std::string error;                  // empty on success
  std::vector<std::string> warnings;  // unknown fields; a torn journal tail dropped
  size_t journal_records = 0;         // journal records applied (a torn one not counted)
  // Not empty when the file holds more than the document restored: which record ended the
  // journal and why (also among the warnings). What was dropped may still be rescued by hand,
  // so the app keeps such a file aside rather than replacing it (app/state/autosave.h).
  std::string dropped;
  bool ok() const { return error.empty(); }
};

// A file of one base record holding `document`. Empty with *error naming the first value JSON
// cannot hold (NaN, invalid UTF-8).
std::string RecoveryToText(const Document& document, std::string* error);
RecoveryLoadResult RecoveryFromText(const std::string& text);
// The framing alone, for tests and the fuzz target: a version 2 file of these payloads, the
// first the base record, with correct lengths and checksums.
std::string FrameRecoveryRecords(const std::vector<std::string>& payloads);
// Writes a one-record file atomically (core/util/file_write.h), refusing a symbolic link, a
// device or a FIFO at `path`. Empty on success, else the error.
std::string SaveRecovery(const Document& document, const std::string& path);
RecoveryLoadResult LoadRecovery(const std::string& path);

// What changed in a document since the last write, for RecoveryJournal::Write: either the
// whole document (`project` set: the file is rewritten) or a journal record.
struct RecoveryDelta {
  std::optional<Project> project;  // set: the history below is all of it, not a change
  size_t undo_keep = 0, redo_keep = 0;
  std::vector<Edit> undo, redo;  // appended to the kept edits
  size_t clean_undo_depth = 0;
  bool clean_is_unreachable = false;
};

// What the last delta described, by edit ids (Document::undo_ids): the main thread's side.
struct RecoveryWritten {
  std::uint64_t epoch = 0;  // 0: nothing yet, the next delta is the whole document
  std::vector<std::uint64_t> undo_ids, redo_ids;
};

// The delta from *written to `document` (plus `unfinished`, when set, as one more undo edit on
// top: a drag in progress, whose edit has no id), and records it in *written. It copies only
// the edits that are new since, so its cost is that of the change; when the document's epoch
// changed (opened, restored, paths rewritten) it is the whole document.
RecoveryDelta MakeRecoveryDelta(const Document& document, const Edit* unfinished, RecoveryWritten* written);

struct RecoveryWriteResult {
  std::string error;  // empty on success
  std::uint64_t bytes_written = 0;
  std::uint64_t file_bytes = 0;  // the file's size after the write
  bool compacted = false;        // the whole file was rewritten (else a record was appended)
  bool ok() const { return error.empty(); }
};

// The worker's side: keeps a copy of the document as the file holds it, applies each delta to
// it and appends the delta as a journal record; rewrites the whole file atomically (a
// compaction) on the first write, after a failed one, for another path, and when the journal
// would grow beyond the base, so the file stays at most about twice the document and the bytes
// written per edit stay proportional to the edit (the base doubles between compactions).
// A symbolic link, a device or a FIFO at `path` is refused with a message naming it (never
// appended to, written through or replaced). Not thread-safe: one write at a time.
class RecoveryJournal {
 public:
  RecoveryWriteResult Write(const std::string& path, RecoveryDelta delta);

 private:
  Project project_;
  std::vector<Edit> undo_, redo_;
  size_t clean_undo_depth_ = 0;
  bool clean_is_unreachable_ = false;
  std::string path_;  // the file that holds the state above; empty: rewrite it whole next
  std::uint64_t base_bytes_ = 0, journal_bytes_ = 0;
};

}  // namespace facet
