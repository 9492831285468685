#include "core/io/recovery_io.h"

#include <cstdint>
#include <optional>

#include "core/io/project_io_internal.h"
#include "core/util/file_read.h"
#include "core/util/file_write.h"

namespace facet {
namespace {

using project_io_internal::Json;
using project_io_internal::OrderedJson;

constexpr const char* kFormatName = "facet-recovery";
constexpr int kFormatVersion = 1;

std::string Join(const std::string& base, const std::string& key) { return base + "." + key; }
std::string Index(const std::string& base, size_t i) { return base + "[" + std::to_string(i) + "]"; }

// ---------------------------------------------------------------------------------------
// Writing.

template <typename T>
void WriteChanges(const std::vector<Change<T>>& changes, const char* key, const std::string& at, OrderedJson* edit,
                  std::string* error) {
  if (changes.empty()) return;  // most edits touch one or two lists: absent means none
  OrderedJson list = OrderedJson::array();
  for (size_t i = 0; i < changes.size(); ++i) {
    const Change<T>& c = changes[i];
    const std::string cat = Index(Join(at, key), i);
    OrderedJson j;
    j["id"] = c.id;
    if (c.before) {
      j["before"] = project_io_internal::ObjectToJson(*c.before, Join(cat, "before"), error);
      j["before_index"] = c.before_index;
    }
    if (c.after) {
      j["after"] = project_io_internal::ObjectToJson(*c.after, Join(cat, "after"), error);
      j["after_index"] = c.after_index;
    }
    list.push_back(std::move(j));
  }
  (*edit)[key] = std::move(list);
}

OrderedJson WriteEdit(const Edit& edit, const std::string& at, std::string* error) {
  OrderedJson j;
  j["label"] = edit.label;
  WriteChanges(edit.images, "images", at, &j, error);
  WriteChanges(edit.segments, "segments", at, &j, error);
  WriteChanges(edit.primitives, "primitives", at, &j, error);
  WriteChanges(edit.pins, "pins", at, &j, error);
  WriteChanges(edit.constraints, "constraints", at, &j, error);
  WriteChanges(edit.references, "references", at, &j, error);
  if (edit.units_before || edit.units_after)
    j["units"] = {edit.units_before.value_or(""), edit.units_after.value_or("")};
  if (edit.next_id_before != kNoId || edit.next_id_after != kNoId)
    j["next_id"] = {edit.next_id_before, edit.next_id_after};
  return j;
}

// ---------------------------------------------------------------------------------------
// Reading: every check names the JSON path of what it reads; the first error wins.

struct Reader {
  std::string error;
  std::vector<std::string>* warnings;

  bool Fail(const std::string& path, const std::string& what) {
    if (error.empty()) error = path + ": " + what;
    return false;
  }
  bool Object(const Json& j, const std::string& path, std::initializer_list<const char*> known) {
    if (!j.is_object()) return Fail(path, "expected an object");
    for (auto it = j.begin(); it != j.end(); ++it) {
      bool is_known = false;
      for (const char* k : known) is_known = is_known || it.key() == k;
      if (!is_known) warnings->push_back(Join(path, it.key()) + ": unknown field ignored");
    }
    return true;
  }
  bool Unsigned(const Json& j, const std::string& path, std::uint64_t* out) {
    if (!j.is_number_unsigned()) return Fail(path, "expected a non-negative integer");
    *out = j.get<std::uint64_t>();
    return true;
  }
};

template <typename T>
bool ReadChanges(const Json& edit, const char* key, const std::string& at, Reader* r, std::vector<Change<T>>* out) {
  out->clear();
  auto it = edit.find(key);
  if (it == edit.end()) return true;
  const std::string list_at = Join(at, key);
  if (!it->is_array()) return r->Fail(list_at, "expected an array");
  for (size_t i = 0; i < it->size(); ++i) {
    const Json& j = (*it)[i];
    const std::string cat = Index(list_at, i);
    if (!r->Object(j, cat, {"id", "before", "before_index", "after", "after_index"})) return false;
    Change<T> change;
    std::uint64_t value = 0;
    if (!j.contains("id")) return r->Fail(Join(cat, "id"), "missing field");
    if (!r->Unsigned(j["id"], Join(cat, "id"), &value) || value == kNoId)
      return r->Fail(Join(cat, "id"), "expected a positive integer id");
    change.id = value;
    for (const bool before : {true, false}) {
      const char* side = before ? "before" : "after";
      const char* index_key = before ? "before_index" : "after_index";
      std::optional<T>& object = before ? change.before : change.after;
      size_t& index = before ? change.before_index : change.after_index;
      if (!j.contains(side)) {
        if (j.contains(index_key)) return r->Fail(Join(cat, index_key), std::string("without \"") + side + "\"");
        continue;
      }
      object.emplace();
      if (!project_io_internal::ObjectFromJson(j[side], Join(cat, side), &*object, &r->error, r->warnings))
        return false;
      if (object->id != change.id) return r->Fail(Join(Join(cat, side), "id"), "is not the change's id");
      if (!j.contains(index_key)) return r->Fail(Join(cat, index_key), "missing field");
      if (!r->Unsigned(j[index_key], Join(cat, index_key), &value)) return false;
      index = static_cast<size_t>(value);
    }
    if (!change.before && !change.after) return r->Fail(cat, "a change needs \"before\", \"after\" or both");
    out->push_back(std::move(change));
  }
  return true;
}

bool ReadEdit(const Json& j, const std::string& at, Reader* r, Edit* edit) {
  if (!r->Object(j, at,
                 {"label", "images", "segments", "primitives", "pins", "constraints", "references", "units", "next_id"}))
    return false;
  if (!j.contains("label") || !j["label"].is_string()) return r->Fail(Join(at, "label"), "expected a string");
  edit->label = j["label"].get<std::string>();
  if (!ReadChanges(j, "images", at, r, &edit->images) || !ReadChanges(j, "segments", at, r, &edit->segments) ||
      !ReadChanges(j, "primitives", at, r, &edit->primitives) || !ReadChanges(j, "pins", at, r, &edit->pins) ||
      !ReadChanges(j, "constraints", at, r, &edit->constraints) ||
      !ReadChanges(j, "references", at, r, &edit->references))
    return false;
  if (j.contains("units")) {
    const Json& units = j["units"];
    if (!units.is_array() || units.size() != 2 || !units[0].is_string() || !units[1].is_string())
      return r->Fail(Join(at, "units"), "expected [before, after] as two strings");
    edit->units_before = units[0].get<std::string>();
    edit->units_after = units[1].get<std::string>();
  }
  if (j.contains("next_id")) {
    const Json& next_id = j["next_id"];
    if (!next_id.is_array() || next_id.size() != 2 || !next_id[0].is_number_unsigned() ||
        !next_id[1].is_number_unsigned() || next_id[0].get<std::uint64_t>() == kNoId ||
        next_id[1].get<std::uint64_t>() == kNoId)
      return r->Fail(Join(at, "next_id"), "expected [before, after] as two positive integers");
    edit->next_id_before = next_id[0].get<std::uint64_t>();
    edit->next_id_after = next_id[1].get<std::uint64_t>();
  }
  if (edit->Empty()) return r->Fail(at, "the edit changes nothing");
  return true;
}

bool ReadEdits(const Json& root, const char* key, Reader* r, std::vector<Edit>* out) {
  if (!root.contains(key)) return r->Fail(key, "missing field");
  const Json& list = root[key];
  if (!list.is_array()) return r->Fail(key, "expected an array");
  out->resize(list.size());
  for (size_t i = 0; i < list.size(); ++i)
    if (!ReadEdit(list[i], Index(key, i), r, &(*out)[i])) return false;
  return true;
}

bool ReadRecovery(Json& root, Reader* r, Document* document) {
  if (!root.is_object()) return r->Fail("(top level)", "expected a JSON object");
  if (!root.contains("format") || root["format"] != kFormatName)
    return r->Fail("format", std::string("expected \"") + kFormatName + "\": this is not a Facet recovery file");
  if (!root.contains("version") || !root["version"].is_number_unsigned())
    return r->Fail("version", "expected a positive integer");
  if (root["version"].get<std::uint64_t>() != kFormatVersion)
    return r->Fail("version", "version " + root["version"].dump() + " is not the one this build reads (" +
                                  std::to_string(kFormatVersion) + ")");
  if (!r->Object(root, "",
                 {"format", "version", "project", "undo", "redo", "clean_undo_depth", "clean_is_unreachable"}))
    return false;
  if (!root.contains("project")) return r->Fail("project", "missing field");
  Json& project_json = root["project"];
  // The edits' objects are in the current project layout. A project from an older version
  // (a recovery file left by the Facet before an update) is migrated like a project file,
  // but its edits would no longer match it: the work is restored without its history.
  if (!project_json.is_object() || !project_json.contains("version") ||
      !project_json["version"].is_number_unsigned() ||
      project_json["version"].get<std::uint64_t>() > static_cast<std::uint64_t>(Project::kFormatVersion))
    return r->Fail("project.version", "expected " + std::to_string(Project::kFormatVersion) + " or older");
  const std::uint64_t project_version = project_json["version"].get<std::uint64_t>();
  Project project;
  std::string project_error;
  if (!project_io_internal::ProjectFromJsonObject(project_json, &project, &project_error, r->warnings))
    return r->Fail("project", project_error);
  if (project_version < static_cast<std::uint64_t>(Project::kFormatVersion)) {
    r->warnings->push_back("written by an older Facet (project version " + std::to_string(project_version) +
                           "): the project is restored, its undo history is not");
    const std::string rebuild_error =
        Document::Rebuild(project, {}, {}, 0, true, project_io_internal::CheckProjectReferences, document);
    if (!rebuild_error.empty()) return r->Fail("project", rebuild_error);
    return true;
  }
  std::vector<Edit> undo, redo;
  if (!ReadEdits(root, "undo", r, &undo) || !ReadEdits(root, "redo", r, &redo)) return false;
  std::uint64_t clean_depth = 0;
  if (!root.contains("clean_undo_depth") || !r->Unsigned(root["clean_undo_depth"], "clean_undo_depth", &clean_depth))
    return r->Fail("clean_undo_depth", "expected a non-negative integer");
  if (!root.contains("clean_is_unreachable") || !root["clean_is_unreachable"].is_boolean())
    return r->Fail("clean_is_unreachable", "expected true or false");
  const std::string rebuild_error =
      Document::Rebuild(project, undo, redo, static_cast<size_t>(clean_depth), root["clean_is_unreachable"].get<bool>(),
                        project_io_internal::CheckProjectReferences, document);
  if (!rebuild_error.empty()) return r->Fail("history", rebuild_error);
  return true;
}

}  // namespace

std::string RecoveryToJson(const Document& document, std::string* error) {
  error->clear();
  OrderedJson root;
  root["format"] = kFormatName;
  root["version"] = kFormatVersion;
  std::string project_error;
  root["project"] = project_io_internal::ProjectToJsonObject(document.project(), &project_error);
  if (!project_error.empty()) *error = "project." + project_error;
  for (const bool undo : {true, false}) {
    const char* key = undo ? "undo" : "redo";
    const std::vector<Edit>& stack = undo ? document.undo_stack() : document.redo_stack();
    OrderedJson list = OrderedJson::array();
    for (size_t i = 0; i < stack.size(); ++i) list.push_back(WriteEdit(stack[i], Index(key, i), error));
    root[key] = std::move(list);
  }
  root["clean_undo_depth"] = document.clean_undo_depth();
  root["clean_is_unreachable"] = document.clean_is_unreachable();
  if (!error->empty()) return {};
  return root.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

RecoveryLoadResult RecoveryFromJson(const std::string& text) {
  RecoveryLoadResult result;
  try {
    Json root;
    if (!project_io_internal::ParseJson(text, &root, &result.error)) return result;
    Reader reader{{}, &result.warnings};
    if (!ReadRecovery(root, &reader, &result.document)) result.error = reader.error;
  } catch (const std::exception& e) {
    result.error = std::string("cannot read the recovery file: ") + e.what();
  }
  if (!result.ok()) result.document = Document();
  return result;
}

std::string SaveRecovery(const Document& document, const std::string& path) {
  std::string error;
  const std::string text = RecoveryToJson(document, &error);
  if (!error.empty()) return "cannot write " + path + ": " + error;
  return WriteFileAtomically(path, text);
}

RecoveryLoadResult LoadRecovery(const std::string& path) {
  RecoveryLoadResult result;
  std::string bytes;
  if (!ReadRegularFile(path, kMaxTextFileBytes, &bytes, &result.error)) return result;
  result = RecoveryFromJson(bytes);
  if (!result.ok()) result.error = path + ": " + result.error;
  return result;
}

}  // namespace facet
