// The document: a project, its undo history and its dirty flag. Every user edit is an Edit
// (the paper's operators on the state (K, F)): a labelled set of object changes, each with
// the object before and after, so that applying and reverting are exact. "Do" is "redo".
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/scene/project.h"

namespace facet {

template <typename T>
struct Change {
  Id id = kNoId;
  std::optional<T> before;  // nullopt: the object did not exist (an insertion)
  std::optional<T> after;   // nullopt: the object is removed
  size_t before_index = 0;  // position in its list before the edit (when `before` is set)
  size_t after_index = 0;   // position in its list after the edit (when `after` is set)
  friend bool operator==(const Change&, const Change&) = default;
};

struct Edit {
  std::string label;  // shown in the history panel, e.g. "Move pin"
  std::vector<Change<Image>> images;
  std::vector<Change<Segment>> segments;
  std::vector<Change<Primitive>> primitives;
  std::vector<Change<Pin>> pins;
  std::vector<Change<Constraint>> constraints;
  std::vector<Change<Reference>> references;
  std::optional<std::string> units_before, units_after;
  Id next_id_before = kNoId, next_id_after = kNoId;

  bool Empty() const;
  friend bool operator==(const Edit&, const Edit&) = default;
};

// The edit that turns `before` into `after`, matching objects by id. Applying it to
// `before` gives exactly `after` and reverting it gives exactly `before`, order included.
Edit DiffProjects(const std::string& label, const Project& before, const Project& after);
void ApplyEdit(const Edit& edit, Project* project);
void RevertEdit(const Edit& edit, Project* project);
// ApplyEdit and RevertEdit for an edit from outside the program (a recovery file): they check,
// instead of assuming, that the edit fits the project (every object it removes or modifies is
// there, at its index, equal to the edit's record of it; every object it inserts is absent;
// units and next_id are what the edit starts from). Empty on success; else what does not fit,
// e.g. "primitives: id 7 at index 2 differs from the edit's record", and *project is
// unspecified.
std::string TryApplyEdit(const Edit& edit, Project* project);
std::string TryRevertEdit(const Edit& edit, Project* project);

class Document {
 public:
  Document() = default;
  explicit Document(Project project) : project_(std::move(project)) {}

  // Rebuilds the exact document a recovery file describes, from its current project and
  // history (undo oldest first, redo with the next redo last, as undo_stack() and
  // redo_stack() give them), or fails with a message naming the faulty edit ("undo[3]: ...").
  // The undo edits are reverted one by one from `current` down to the first project, each
  // checked against the project it is applied to (TryRevertEdit) and every project on the
  // way by `check_project` (e.g. the loader's reference checks: empty when it is sound);
  // then the whole history is replayed through Commit, so that every stored edit must equal
  // the one Commit recomputes from the projects it joins, and the redo edits are undone
  // again. `clean_undo_depth` and `clean_is_unreachable` restore the dirty flag.
  static std::string Rebuild(const Project& current, const std::vector<Edit>& undo, const std::vector<Edit>& redo,
                             size_t clean_undo_depth, bool clean_is_unreachable,
                             const std::function<std::string(const Project&)>& check_project, Document* out);

  const Project& project() const { return project_; }

  // Replaces the project by `after` as one undoable step labelled `label`. Returns false
  // (and records nothing) when nothing changed.
  bool Commit(const std::string& label, const Project& after);
  // For interactive drags: the caller snapshots project() when the drag starts, previews
  // changes through MutableProjectForPreview(), and calls CommitFrom(snapshot) on release so
  // that the whole drag is one history entry.
  Project* MutableProjectForPreview() { return &project_; }
  bool CommitFrom(const std::string& label, const Project& before);
  // Discards a preview: restores the snapshot without touching history.
  void CancelPreview(const Project& before) { project_ = before; }

  bool CanUndo() const { return !undo_.empty(); }
  bool CanRedo() const { return !redo_.empty(); }
  bool Undo();
  bool Redo();
  const std::vector<Edit>& undo_stack() const { return undo_; }  // oldest first
  const std::vector<Edit>& redo_stack() const { return redo_; }  // next redo last
  // An id for each edit of undo_stack() and redo_stack() (same order), unique in the process
  // and kept by an edit as it moves between the stacks, and the epoch, which changes whenever
  // the project or the recorded edits change other than through the history (Reset, Rebuild,
  // RewriteImagePaths). Equal ids in the same epoch are the same edit, so a watcher (the
  // recovery journal, core/io/recovery_io.h) finds what changed by comparing ids, in time
  // proportional to the number of edits, not their size, and copies only the new ones.
  const std::vector<std::uint64_t>& undo_ids() const { return undo_ids_; }
  const std::vector<std::uint64_t>& redo_ids() const { return redo_ids_; }
  std::uint64_t epoch() const { return epoch_; }

  bool dirty() const { return undo_.size() != clean_undo_depth_ || clean_is_unreachable_; }
  // The undo depth at the last MarkClean, and whether an edit since has made it unreachable
  // (what dirty() compares; a recovery file keeps both).
  size_t clean_undo_depth() const { return clean_undo_depth_; }
  bool clean_is_unreachable() const { return clean_is_unreachable_; }
  void MarkClean();
  // No state of the history is the saved one any more (a restored recovery whose project file
  // is not its saved state): dirty until the next MarkClean.
  void ForgetCleanState();
  // Increments whenever the committed document changes (an edit, undo, redo, reset, a clean
  // mark or a path rewrite; not a drag's preview), so that a watcher such as the autosave
  // notices every change, even two within one frame that leave the stack sizes as they were.
  std::uint64_t revision() const { return revision_; }
  // Replaces the whole document (File > Open, New); clears history.
  void Reset(Project project);
  // Rewrites every image's and reference's stored path, in the project and in every one held
  // by the history, so that undo and redo keep finding the files after the project file moved
  // (Save as into another folder). Not an edit: history and dirty flag stay as they are.
  void RewriteImagePaths(const std::function<std::string(const std::string&)>& rewrite);

 private:
  // Process-wide, never 0: for edit ids and epochs.
  static std::uint64_t NewSerial();
  void PushUndo(Edit edit);

  Project project_;
  std::vector<Edit> undo_;
  std::vector<Edit> redo_;
  std::vector<std::uint64_t> undo_ids_, redo_ids_;
  std::uint64_t epoch_ = NewSerial();
  size_t clean_undo_depth_ = 0;
  bool clean_is_unreachable_ = false;
  std::uint64_t revision_ = 0;
};

}  // namespace facet
