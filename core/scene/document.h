// The document: a project, its undo history and its dirty flag. Every user edit is an Edit
// (the paper's operators on the state (K, F)): a labelled set of object changes, each with
// the object before and after, so that applying and reverting are exact. "Do" is "redo".
#pragma once

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
};

struct Edit {
  std::string label;  // shown in the history panel, e.g. "Move pin"
  std::vector<Change<Image>> images;
  std::vector<Change<Segment>> segments;
  std::vector<Change<Primitive>> primitives;
  std::vector<Change<Pin>> pins;
  std::vector<Change<Constraint>> constraints;
  std::optional<std::string> units_before, units_after;
  Id next_id_before = kNoId, next_id_after = kNoId;

  bool Empty() const;
};

// The edit that turns `before` into `after`, matching objects by id. Applying it to
// `before` gives exactly `after` and reverting it gives exactly `before`, order included.
Edit DiffProjects(const std::string& label, const Project& before, const Project& after);
void ApplyEdit(const Edit& edit, Project* project);
void RevertEdit(const Edit& edit, Project* project);

class Document {
 public:
  Document() = default;
  explicit Document(Project project) : project_(std::move(project)) {}

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

  bool dirty() const { return undo_.size() != clean_undo_depth_ || clean_is_unreachable_; }
  void MarkClean();
  // Replaces the whole document (File > Open, New); clears history.
  void Reset(Project project);
  // Rewrites every image's stored path, in the project and in every image held by the
  // history, so that undo and redo keep finding the photos after the project file moved
  // (Save as into another folder). Not an edit: history and dirty flag stay as they are.
  void RewriteImagePaths(const std::function<std::string(const std::string&)>& rewrite);

 private:
  Project project_;
  std::vector<Edit> undo_;
  std::vector<Edit> redo_;
  size_t clean_undo_depth_ = 0;
  bool clean_is_unreachable_ = false;
};

}  // namespace facet
