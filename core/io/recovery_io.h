// The recovery file: what autosave writes so that a crash loses no work. It holds the whole
// document (core/scene/document.h): the current project as a project file stores it, the
// undo and redo history with every edit's label and object changes, and the clean depth that
// makes the dirty flag. Objects are written and read by the project file's own writers and
// readers (core/io/project_io_internal.h), image paths exactly as the document holds them
// (relative to the project file's folder, absolute in an unsaved project).
//
// Layout (version 1): {"format": "facet-recovery", "version": 1, "project": {a project file
// of the current version}, "undo": [edit, ...] (oldest first), "redo": [edit, ...] (next redo last),
// "clean_undo_depth", "clean_is_unreachable"}; an edit is {"label", and for each non-empty
// list of "images", "segments", "primitives", "pins", "constraints", "references": [{"id", "before",
// "before_index", "after", "after_index"}, ...] (a side absent for an insertion or removal),
// "units": [before, after] and "next_id": [before, after] when they change}.
//
// Reading is as strict as the project loader's: a malformed file, or a history that does not
// lead exactly to its project (Document::Rebuild), is an error naming the JSON path or the
// edit, never a crash.
#pragma once

#include <string>
#include <vector>

#include "core/scene/document.h"

namespace facet {

struct RecoveryLoadResult {
  Document document;
  std::string error;                  // empty on success
  std::vector<std::string> warnings;  // unknown fields
  bool ok() const { return error.empty(); }
};

// Compact JSON (the file is for the program: it may be large, and is rewritten after every
// edit). Empty with *error naming the first value JSON cannot hold (NaN, invalid UTF-8).
std::string RecoveryToJson(const Document& document, std::string* error);
RecoveryLoadResult RecoveryFromJson(const std::string& text);
// Writes atomically (core/util/file_write.h). Empty on success, else the error.
std::string SaveRecovery(const Document& document, const std::string& path);
RecoveryLoadResult LoadRecovery(const std::string& path);

}  // namespace facet
