#include "core/scene/document.h"

#include <algorithm>
#include <atomic>
#include <cassert>
#include <string>
#include <unordered_map>

namespace facet {
namespace {

template <typename T>
void DiffList(const std::vector<T>& before, const std::vector<T>& after, std::vector<Change<T>>* out) {
  std::unordered_map<Id, size_t> after_index;
  for (size_t i = 0; i < after.size(); ++i) after_index[after[i].id] = i;
  std::unordered_map<Id, size_t> before_index;
  for (size_t i = 0; i < before.size(); ++i) before_index[before[i].id] = i;

  // Objects present on both sides normally keep their relative order; when they do not, a
  // moved object is recorded as a removal at its old position plus an insertion at its new
  // one, so that applying and reverting restore the order exactly.
  bool kept_order_changed = false;
  size_t last_after = 0;
  bool first = true;
  for (const T& item : before) {
    auto it = after_index.find(item.id);
    if (it == after_index.end()) continue;
    if (!first && it->second < last_after) kept_order_changed = true;
    last_after = it->second;
    first = false;
  }

  for (size_t i = 0; i < before.size(); ++i) {
    auto it = after_index.find(before[i].id);
    if (it == after_index.end() || kept_order_changed) {
      out->push_back({before[i].id, before[i], std::nullopt, i, 0});
    } else if (!(after[it->second] == before[i])) {
      out->push_back({before[i].id, before[i], after[it->second], i, it->second});
    }
  }
  for (size_t i = 0; i < after.size(); ++i) {
    if (!before_index.count(after[i].id) || kept_order_changed)
      out->push_back({after[i].id, std::nullopt, after[i], 0, i});
  }
}

// Moves a list from one side of its changes to the other. Removals go first, in descending
// position, then in-place modifications, then insertions in ascending position, so that every
// object lands exactly where it was.
template <typename T>
void ApplyList(const std::vector<Change<T>>& changes, bool forward, std::vector<T>* list) {
  auto from = [forward](const Change<T>& c) -> const std::optional<T>& { return forward ? c.before : c.after; };
  auto to = [forward](const Change<T>& c) -> const std::optional<T>& { return forward ? c.after : c.before; };
  auto from_index = [forward](const Change<T>& c) { return forward ? c.before_index : c.after_index; };
  auto to_index = [forward](const Change<T>& c) { return forward ? c.after_index : c.before_index; };

  std::vector<const Change<T>*> removals, insertions;
  for (const auto& c : changes) {
    if (from(c) && !to(c)) removals.push_back(&c);
    if (!from(c) && to(c)) insertions.push_back(&c);
  }
  std::sort(removals.begin(), removals.end(), [&](auto a, auto b) { return from_index(*a) > from_index(*b); });
  for (const auto* c : removals) {
    assert(from_index(*c) < list->size() && (*list)[from_index(*c)].id == c->id && "edit does not match project");
    list->erase(list->begin() + static_cast<std::ptrdiff_t>(from_index(*c)));
  }
  for (const auto& c : changes) {
    if (!from(c) || !to(c)) continue;
    auto it = std::find_if(list->begin(), list->end(), [&](const T& t) { return t.id == c.id; });
    assert(it != list->end() && "edit modifies a missing object");
    *it = *to(c);
  }
  std::sort(insertions.begin(), insertions.end(), [&](auto a, auto b) { return to_index(*a) < to_index(*b); });
  for (const auto* c : insertions) {
    const size_t at = std::min(to_index(*c), list->size());
    list->insert(list->begin() + static_cast<std::ptrdiff_t>(at), *to(*c));
  }
}

void ApplyDirection(const Edit& edit, bool forward, Project* project) {
  ApplyList(edit.images, forward, &project->images);
  ApplyList(edit.segments, forward, &project->segments);
  ApplyList(edit.primitives, forward, &project->primitives);
  ApplyList(edit.pins, forward, &project->pins);
  ApplyList(edit.constraints, forward, &project->constraints);
  ApplyList(edit.references, forward, &project->references);
  const auto& units = forward ? edit.units_after : edit.units_before;
  if (units) project->units = *units;
  const Id next_id = forward ? edit.next_id_after : edit.next_id_before;
  if (next_id != kNoId) project->next_id = next_id;
}

// ApplyList's order of work, checking every assumption ApplyList asserts (and that each
// object the edit replaces or removes equals the edit's record of it). Empty or the problem.
template <typename T>
std::string CheckedApplyList(const std::vector<Change<T>>& changes, bool forward, const char* name,
                             std::vector<T>* list) {
  auto from = [forward](const Change<T>& c) -> const std::optional<T>& { return forward ? c.before : c.after; };
  auto to = [forward](const Change<T>& c) -> const std::optional<T>& { return forward ? c.after : c.before; };
  auto from_index = [forward](const Change<T>& c) { return forward ? c.before_index : c.after_index; };
  auto to_index = [forward](const Change<T>& c) { return forward ? c.after_index : c.before_index; };
  const std::string list_name(name);
  auto id_text = [](Id id) { return "id " + std::to_string(id); };

  std::vector<const Change<T>*> removals, insertions;
  for (const auto& c : changes) {
    if (!c.before && !c.after) return list_name + ": a change of " + id_text(c.id) + " has neither before nor after";
    if ((c.before && c.before->id != c.id) || (c.after && c.after->id != c.id))
      return list_name + ": a change of " + id_text(c.id) + " records an object with another id";
    if (from(c) && !to(c)) removals.push_back(&c);
    if (!from(c) && to(c)) insertions.push_back(&c);
  }
  std::sort(removals.begin(), removals.end(), [&](auto a, auto b) { return from_index(*a) > from_index(*b); });
  for (const auto* c : removals) {
    const size_t at = from_index(*c);
    if (at >= list->size() || (*list)[at].id != c->id)
      return list_name + ": " + id_text(c->id) + " is not at index " + std::to_string(at);
    if (!((*list)[at] == *from(*c)))
      return list_name + ": " + id_text(c->id) + " at index " + std::to_string(at) + " differs from the edit's record";
    list->erase(list->begin() + static_cast<std::ptrdiff_t>(at));
  }
  for (const auto& c : changes) {
    if (!from(c) || !to(c)) continue;
    auto it = std::find_if(list->begin(), list->end(), [&](const T& t) { return t.id == c.id; });
    if (it == list->end()) return list_name + ": modifies " + id_text(c.id) + ", which is missing";
    if (!(*it == *from(c))) return list_name + ": " + id_text(c.id) + " differs from the edit's record";
    *it = *to(c);
  }
  std::sort(insertions.begin(), insertions.end(), [&](auto a, auto b) { return to_index(*a) < to_index(*b); });
  for (const auto* c : insertions) {
    const size_t at = to_index(*c);
    if (std::any_of(list->begin(), list->end(), [&](const T& t) { return t.id == c->id; }))
      return list_name + ": inserts " + id_text(c->id) + ", which is there already";
    if (at > list->size())
      return list_name + ": inserts " + id_text(c->id) + " at index " + std::to_string(at) + ", past the end";
    list->insert(list->begin() + static_cast<std::ptrdiff_t>(at), *to(*c));
  }
  return {};
}

std::string CheckedApplyDirection(const Edit& edit, bool forward, Project* project) {
  std::string error;
  if (error.empty()) error = CheckedApplyList(edit.images, forward, "images", &project->images);
  if (error.empty()) error = CheckedApplyList(edit.segments, forward, "segments", &project->segments);
  if (error.empty()) error = CheckedApplyList(edit.primitives, forward, "primitives", &project->primitives);
  if (error.empty()) error = CheckedApplyList(edit.pins, forward, "pins", &project->pins);
  if (error.empty()) error = CheckedApplyList(edit.constraints, forward, "constraints", &project->constraints);
  if (error.empty()) error = CheckedApplyList(edit.references, forward, "references", &project->references);
  if (!error.empty()) return error;
  if (edit.units_before.has_value() != edit.units_after.has_value()) return "units: only one side is recorded";
  if (edit.units_before) {
    if (project->units != (forward ? *edit.units_before : *edit.units_after))
      return "units: the project's units are not the edit's";
    project->units = forward ? *edit.units_after : *edit.units_before;
  }
  if ((edit.next_id_before == kNoId) != (edit.next_id_after == kNoId)) return "next_id: only one side is recorded";
  if (edit.next_id_before != kNoId) {
    if (project->next_id != (forward ? edit.next_id_before : edit.next_id_after))
      return "next_id: the project's next_id is not the edit's";
    project->next_id = forward ? edit.next_id_after : edit.next_id_before;
  }
  return {};
}

}  // namespace

bool Edit::Empty() const {
  return images.empty() && segments.empty() && primitives.empty() && pins.empty() && constraints.empty() &&
         references.empty() &&
         !units_after && next_id_after == kNoId;
}

Edit DiffProjects(const std::string& label, const Project& before, const Project& after) {
  Edit edit;
  edit.label = label;
  DiffList(before.images, after.images, &edit.images);
  DiffList(before.segments, after.segments, &edit.segments);
  DiffList(before.primitives, after.primitives, &edit.primitives);
  DiffList(before.pins, after.pins, &edit.pins);
  DiffList(before.constraints, after.constraints, &edit.constraints);
  DiffList(before.references, after.references, &edit.references);
  if (before.units != after.units) {
    edit.units_before = before.units;
    edit.units_after = after.units;
  }
  if (before.next_id != after.next_id) {
    edit.next_id_before = before.next_id;
    edit.next_id_after = after.next_id;
  }
  return edit;
}

void ApplyEdit(const Edit& edit, Project* project) { ApplyDirection(edit, true, project); }
void RevertEdit(const Edit& edit, Project* project) { ApplyDirection(edit, false, project); }
std::string TryApplyEdit(const Edit& edit, Project* project) { return CheckedApplyDirection(edit, true, project); }
std::string TryRevertEdit(const Edit& edit, Project* project) { return CheckedApplyDirection(edit, false, project); }

std::string Document::Rebuild(const Project& current, const std::vector<Edit>& undo, const std::vector<Edit>& redo,
                              size_t clean_undo_depth, bool clean_is_unreachable,
                              const std::function<std::string(const Project&)>& check_project, Document* out) {
  auto at = [](const char* stack, size_t i) { return std::string(stack) + "[" + std::to_string(i) + "]: "; };
  std::string error = check_project(current);
  if (!error.empty()) return "the current project: " + error;
  // Down to the first project, checking each step against the project it meets.
  Project first = current;
  for (size_t i = undo.size(); i-- > 0;) {
    error = TryRevertEdit(undo[i], &first);
    if (!error.empty()) return at("undo", i) + "does not revert onto the project after it: " + error;
    error = check_project(first);
    if (!error.empty()) return at("undo", i) + "reverting it leaves an unsound project: " + error;
  }
  // Up again through Commit: the stored edits must be exactly what the program would record.
  Document document(std::move(first));
  auto commit = [&](const Edit& edit, const std::string& where) -> std::string {
    Project next = document.project();
    std::string apply_error = TryApplyEdit(edit, &next);
    if (!apply_error.empty()) return where + "does not apply onto the project before it: " + apply_error;
    apply_error = check_project(next);
    if (!apply_error.empty()) return where + "applying it leaves an unsound project: " + apply_error;
    if (!document.Commit(edit.label, next)) return where + "changes nothing";
    if (!(document.undo_.back() == edit))
      return where + "is not the edit of the projects it joins (recomputed, it differs)";
    return {};
  };
  for (size_t i = 0; i < undo.size(); ++i) {
    error = commit(undo[i], at("undo", i));
    if (!error.empty()) return error;
  }
  if (!(document.project() == current)) return "the history does not lead to the current project";
  for (size_t i = redo.size(); i-- > 0;) {
    error = commit(redo[i], at("redo", i));
    if (!error.empty()) return error;
  }
  for (size_t i = 0; i < redo.size(); ++i) document.Undo();
  if (!clean_is_unreachable && clean_undo_depth > undo.size() + redo.size())
    return "clean_undo_depth: " + std::to_string(clean_undo_depth) + " is beyond the history (" +
           std::to_string(undo.size() + redo.size()) + " edits)";
  document.clean_undo_depth_ = clean_undo_depth;
  document.clean_is_unreachable_ = clean_is_unreachable;
  // Revisions only grow on one document object, so a watcher of *out sees the change.
  const std::uint64_t revision = std::max(out->revision_, document.revision_) + 1;
  *out = std::move(document);
  out->revision_ = revision;
  return {};
}

std::uint64_t Document::NewSerial() {
  static std::atomic<std::uint64_t> next{1};
  return next.fetch_add(1, std::memory_order_relaxed);
}

void Document::PushUndo(Edit edit) {
  if (undo_.size() < clean_undo_depth_) clean_is_unreachable_ = true;
  undo_.push_back(std::move(edit));
  undo_ids_.push_back(NewSerial());
  redo_.clear();
  redo_ids_.clear();
  ++revision_;
}

bool Document::Commit(const std::string& label, const Project& after) {
  Edit edit = DiffProjects(label, project_, after);
  if (edit.Empty()) return false;
  ApplyEdit(edit, &project_);
  PushUndo(std::move(edit));
  return true;
}

bool Document::CommitFrom(const std::string& label, const Project& before) {
  Edit edit = DiffProjects(label, before, project_);
  if (edit.Empty()) return false;
  PushUndo(std::move(edit));
  return true;
}

bool Document::Undo() {
  if (undo_.empty()) return false;
  RevertEdit(undo_.back(), &project_);
  redo_.push_back(std::move(undo_.back()));
  undo_.pop_back();
  redo_ids_.push_back(undo_ids_.back());
  undo_ids_.pop_back();
  ++revision_;
  return true;
}

bool Document::Redo() {
  if (redo_.empty()) return false;
  ApplyEdit(redo_.back(), &project_);
  undo_.push_back(std::move(redo_.back()));
  redo_.pop_back();
  undo_ids_.push_back(redo_ids_.back());
  redo_ids_.pop_back();
  ++revision_;
  return true;
}

void Document::MarkClean() {
  clean_undo_depth_ = undo_.size();
  clean_is_unreachable_ = false;
  ++revision_;
}

void Document::ForgetCleanState() {
  clean_is_unreachable_ = true;
  ++revision_;
}

void Document::RewriteImagePaths(const std::function<std::string(const std::string&)>& rewrite) {
  for (Image& image : project_.images) image.path = rewrite(image.path);
  for (Reference& reference : project_.references) reference.path = rewrite(reference.path);
  for (std::vector<Edit>* stack : {&undo_, &redo_}) {
    for (Edit& edit : *stack) {
      for (Change<Image>& change : edit.images) {
        if (change.before) change.before->path = rewrite(change.before->path);
        if (change.after) change.after->path = rewrite(change.after->path);
      }
      for (Change<Reference>& change : edit.references) {
        if (change.before) change.before->path = rewrite(change.before->path);
        if (change.after) change.after->path = rewrite(change.after->path);
      }
    }
  }
  epoch_ = NewSerial();
  ++revision_;
}

void Document::Reset(Project project) {
  project_ = std::move(project);
  undo_.clear();
  redo_.clear();
  undo_ids_.clear();
  redo_ids_.clear();
  epoch_ = NewSerial();
  MarkClean();
}

}  // namespace facet
