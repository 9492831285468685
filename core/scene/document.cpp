#include "core/scene/document.h"

#include <algorithm>
#include <cassert>
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
  const auto& units = forward ? edit.units_after : edit.units_before;
  if (units) project->units = *units;
  const Id next_id = forward ? edit.next_id_after : edit.next_id_before;
  if (next_id != kNoId) project->next_id = next_id;
}

}  // namespace

bool Edit::Empty() const {
  return images.empty() && segments.empty() && primitives.empty() && pins.empty() && constraints.empty() &&
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

bool Document::Commit(const std::string& label, const Project& after) {
  Edit edit = DiffProjects(label, project_, after);
  if (edit.Empty()) return false;
  ApplyEdit(edit, &project_);
  if (undo_.size() < clean_undo_depth_) clean_is_unreachable_ = true;
  undo_.push_back(std::move(edit));
  redo_.clear();
  return true;
}

bool Document::CommitFrom(const std::string& label, const Project& before) {
  Edit edit = DiffProjects(label, before, project_);
  if (edit.Empty()) return false;
  if (undo_.size() < clean_undo_depth_) clean_is_unreachable_ = true;
  undo_.push_back(std::move(edit));
  redo_.clear();
  return true;
}

bool Document::Undo() {
  if (undo_.empty()) return false;
  RevertEdit(undo_.back(), &project_);
  redo_.push_back(std::move(undo_.back()));
  undo_.pop_back();
  return true;
}

bool Document::Redo() {
  if (redo_.empty()) return false;
  ApplyEdit(redo_.back(), &project_);
  undo_.push_back(std::move(redo_.back()));
  redo_.pop_back();
  return true;
}

void Document::MarkClean() {
  clean_undo_depth_ = undo_.size();
  clean_is_unreachable_ = false;
}

void Document::RewriteImagePaths(const std::function<std::string(const std::string&)>& rewrite) {
  for (Image& image : project_.images) image.path = rewrite(image.path);
  for (std::vector<Edit>* stack : {&undo_, &redo_}) {
    for (Edit& edit : *stack) {
      for (Change<Image>& change : edit.images) {
        if (change.before) change.before->path = rewrite(change.before->path);
        if (change.after) change.after->path = rewrite(change.after->path);
      }
    }
  }
}

void Document::Reset(Project project) {
  project_ = std::move(project);
  undo_.clear();
  redo_.clear();
  MarkClean();
}

}  // namespace facet
