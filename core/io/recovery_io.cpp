#include "core/io/recovery_io.h"

#include <array>
#include <cassert>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <optional>

#include "core/geometry/id_limits.h"
#include "core/io/project_io_internal.h"
#include "core/util/file_read.h"
#include "core/util/file_write.h"

namespace facet {
namespace {

using project_io_internal::Json;
using project_io_internal::OrderedJson;

constexpr const char* kFormatName = "facet-recovery";
constexpr int kFormatVersion = 2;
constexpr int kLegacyVersion = 1;  // one JSON object, rewritten whole after every edit

// CRC-32 (IEEE 802.3, as zlib's crc32): catches a record whose bytes did not all reach the disk.
std::uint32_t Crc32(const std::string& bytes) {
  static const auto table = [] {
    std::array<std::uint32_t, 256> t{};
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  std::uint32_t crc = 0xFFFFFFFFu;
  for (const char ch : bytes) crc = table[(crc ^ static_cast<unsigned char>(ch)) & 0xFFu] ^ (crc >> 8);
  return crc ^ 0xFFFFFFFFu;
}

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
    if (!r->Unsigned(j["id"], Join(cat, "id"), &value) || value == kNoId || value > kMaxId)
      return r->Fail(Join(cat, "id"), "expected a positive integer id up to " + std::to_string(kMaxId));
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
  if (!r->Object(
          j, at,
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
    // The project file's bound (core/geometry/id_limits.h): a next_id near 2^64 would wrap to 0 at
    // the next object the user creates.
    const auto valid = [](const Json& id) {
      return id.is_number_unsigned() && id.get<std::uint64_t>() != kNoId && id.get<std::uint64_t>() <= kMaxId;
    };
    if (!next_id.is_array() || next_id.size() != 2 || !valid(next_id[0]) || !valid(next_id[1]))
      return r->Fail(Join(at, "next_id"),
                     "expected [before, after] as two positive integers up to " + std::to_string(kMaxId));
    edit->next_id_before = next_id[0].get<std::uint64_t>();
    edit->next_id_after = next_id[1].get<std::uint64_t>();
  }
  if (edit->Empty()) return r->Fail(at, "the edit changes nothing");
  return true;
}

bool ReadEdits(const Json& parent, const char* key, const std::string& at, Reader* r, std::vector<Edit>* out) {
  const std::string list_at = at.empty() ? key : Join(at, key);
  if (!parent.contains(key)) return r->Fail(list_at, "missing field");
  const Json& list = parent[key];
  if (!list.is_array()) return r->Fail(list_at, "expected an array");
  out->resize(list.size());
  for (size_t i = 0; i < list.size(); ++i)
    if (!ReadEdit(list[i], Index(list_at, i), r, &(*out)[i])) return false;
  return true;
}

// The document as the records describe it, before Document::Rebuild checks it.
struct History {
  Project project;
  std::vector<Edit> undo, redo;
  std::uint64_t clean_undo_depth = 0;
  bool clean_is_unreachable = false;
  bool without_history = false;  // an older project layout: the edits cannot be replayed
};

bool ReadCleanState(const Json& j, const std::string& at, Reader* r, History* h) {
  const std::string depth_at = at.empty() ? "clean_undo_depth" : Join(at, "clean_undo_depth");
  const std::string flag_at = at.empty() ? "clean_is_unreachable" : Join(at, "clean_is_unreachable");
  if (!j.contains("clean_undo_depth") || !r->Unsigned(j["clean_undo_depth"], depth_at, &h->clean_undo_depth))
    return r->Fail(depth_at, "expected a non-negative integer");
  if (!j.contains("clean_is_unreachable") || !j["clean_is_unreachable"].is_boolean())
    return r->Fail(flag_at, "expected true or false");
  h->clean_is_unreachable = j["clean_is_unreachable"].get<bool>();
  return true;
}

// The base record (or a whole version 1 file, `legacy`, with its format and version).
bool ReadBase(Json& root, bool legacy, Reader* r, History* h) {
  if (!root.is_object()) return r->Fail("(top level)", "expected a JSON object");
  if (legacy) {
    if (!root.contains("format") || root["format"] != kFormatName)
      return r->Fail("format", std::string("expected \"") + kFormatName + "\": this is not a Facet recovery file");
    if (!root.contains("version") || !root["version"].is_number_unsigned())
      return r->Fail("version", "expected a positive integer");
    if (root["version"].get<std::uint64_t>() != kLegacyVersion)
      return r->Fail("version", "version " + root["version"].dump() + " is not one this build reads (" +
                                    std::to_string(kFormatVersion) + ", in records; " + std::to_string(kLegacyVersion) +
                                    ", one JSON object)");
  }
  if (legacy ? !r->Object(root, "",
                          {"format", "version", "project", "undo", "redo", "clean_undo_depth", "clean_is_unreachable"})
             : !r->Object(root, "", {"project", "undo", "redo", "clean_undo_depth", "clean_is_unreachable"}))
    return false;
  if (!root.contains("project")) return r->Fail("project", "missing field");
  Json& project_json = root["project"];
  // The edits' objects are in the current project layout. A project from an older version
  // (a recovery file left by the Facet before an update) is migrated like a project file,
  // but its edits would no longer match it: the work is restored without its history.
  if (!project_json.is_object() || !project_json.contains("version") || !project_json["version"].is_number_unsigned() ||
      project_json["version"].get<std::uint64_t>() > static_cast<std::uint64_t>(Project::kFormatVersion))
    return r->Fail("project.version", "expected " + std::to_string(Project::kFormatVersion) + " or older");
  const std::uint64_t project_version = project_json["version"].get<std::uint64_t>();
  std::string project_error;
  if (!project_io_internal::ProjectFromJsonObject(project_json, &h->project, &project_error, r->warnings))
    return r->Fail("project", project_error);
  if (project_version < static_cast<std::uint64_t>(Project::kFormatVersion)) {
    r->warnings->push_back("written by an older Facet (project version " + std::to_string(project_version) +
                           "): the project is restored, its undo history is not");
    h->without_history = true;
    return true;
  }
  if (!ReadEdits(root, "undo", "", r, &h->undo) || !ReadEdits(root, "redo", "", r, &h->redo)) return false;
  return ReadCleanState(root, "", r, h);
}

// A journal record, applied to *h: the project follows the undo stack (reverting what it
// drops, applying what it gains), each step checked against the project it meets.
bool ReadJournal(const Json& j, const std::string& at, Reader* r, History* h) {
  if (!r->Object(j, at, {"undo_keep", "redo_keep", "undo", "redo", "clean_undo_depth", "clean_is_unreachable"}))
    return false;
  std::uint64_t undo_keep = 0, redo_keep = 0;
  if (!j.contains("undo_keep") || !r->Unsigned(j["undo_keep"], Join(at, "undo_keep"), &undo_keep))
    return r->Fail(Join(at, "undo_keep"), "expected a non-negative integer");
  if (!j.contains("redo_keep") || !r->Unsigned(j["redo_keep"], Join(at, "redo_keep"), &redo_keep))
    return r->Fail(Join(at, "redo_keep"), "expected a non-negative integer");
  if (undo_keep > h->undo.size())
    return r->Fail(Join(at, "undo_keep"), std::to_string(undo_keep) + " is beyond the undo history (" +
                                              std::to_string(h->undo.size()) + " edits)");
  if (redo_keep > h->redo.size())
    return r->Fail(Join(at, "redo_keep"), std::to_string(redo_keep) + " is beyond the redo history (" +
                                              std::to_string(h->redo.size()) + " edits)");
  std::vector<Edit> undo, redo;
  if (!ReadEdits(j, "undo", at, r, &undo) || !ReadEdits(j, "redo", at, r, &redo)) return false;
  if (!ReadCleanState(j, at, r, h)) return false;
  if (h->without_history) return true;  // the edits cannot be replayed on an older layout
  while (h->undo.size() > undo_keep) {
    const std::string error = TryRevertEdit(h->undo.back(), &h->project);
    if (!error.empty())
      return r->Fail(at, "undo[" + std::to_string(h->undo.size() - 1) + "] does not revert onto the project: " + error);
    h->undo.pop_back();
  }
  h->redo.resize(static_cast<size_t>(redo_keep));
  for (size_t i = 0; i < undo.size(); ++i) {
    const std::string error = TryApplyEdit(undo[i], &h->project);
    if (!error.empty()) return r->Fail(Index(Join(at, "undo"), i), "does not apply onto the project: " + error);
    h->undo.push_back(std::move(undo[i]));
  }
  for (Edit& edit : redo) h->redo.push_back(std::move(edit));
  return true;
}

bool Rebuild(const History& h, Reader* r, Document* document) {
  const std::string rebuild_error =
      h.without_history
          ? Document::Rebuild(h.project, {}, {}, 0, true, project_io_internal::CheckProjectReferences, document)
          : Document::Rebuild(h.project, h.undo, h.redo, static_cast<size_t>(h.clean_undo_depth),
                              h.clean_is_unreachable, project_io_internal::CheckProjectReferences, document);
  if (!rebuild_error.empty()) return r->Fail(h.without_history ? "project" : "history", rebuild_error);
  return true;
}

// One framed record at *pos: its header line, payload and newline, with the checksum right.
// Advances *pos past it; false (with *why) when it is incomplete or damaged.
bool NextRecord(const std::string& text, size_t* pos, std::string* kind, std::string* payload, std::string* why) {
  const size_t eol = text.find('\n', *pos);
  if (eol == std::string::npos) return *why = "the header line is incomplete", false;
  const std::string header = text.substr(*pos, eol - *pos);
  const size_t s1 = header.find(' '), s2 = s1 == std::string::npos ? s1 : header.find(' ', s1 + 1);
  if (s2 == std::string::npos || header.size() - s2 - 1 != 8) return *why = "the header line is malformed", false;
  *kind = header.substr(0, s1);
  std::uint64_t bytes = 0;
  const std::string bytes_text = header.substr(s1 + 1, s2 - s1 - 1);
  if (bytes_text.empty() || bytes_text.size() > 12) return *why = "the header line is malformed", false;
  for (const char c : bytes_text) {
    if (c < '0' || c > '9') return *why = "the header line is malformed", false;
    bytes = 10 * bytes + static_cast<std::uint64_t>(c - '0');
  }
  std::uint32_t crc = 0;
  for (const char c : header.substr(s2 + 1)) {
    const int digit = c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10 : -1;
    if (digit < 0) return *why = "the header line is malformed", false;
    crc = (crc << 4) | static_cast<std::uint32_t>(digit);
  }
  if (bytes + 1 > text.size() - eol - 1) return *why = "the record is cut short", false;
  *payload = text.substr(eol + 1, static_cast<size_t>(bytes));
  if (text[eol + 1 + bytes] != '\n') return *why = "the record does not end where its length says", false;
  if (Crc32(*payload) != crc) return *why = "its checksum does not match", false;
  *pos = eol + 2 + static_cast<size_t>(bytes);
  return true;
}

bool ParsePayload(const std::string& payload, const std::string& at, Json* j, Reader* r) {
  std::string error;
  if (!project_io_internal::ParseJson(payload, j, &error)) return r->Fail(at, error);
  return true;
}

std::string RecordName(size_t k) { return "journal[" + std::to_string(k) + "]"; }
// What the document is restored as of when journal[k] and the records after it are dropped.
std::string AsOf(size_t k) { return k == 0 ? std::string("the base record") : RecordName(k - 1); }

// The base record and at most `max_journal` journal records of a version 2 file, rebuilt into
// a document.
struct PrefixRead {
  std::string base_error;     // the header or the base record is refused: nothing reads
  std::string rebuild_error;  // the records read, but their history does not rebuild
  std::vector<std::string> warnings;
  size_t journal_records = 0;  // read and applied
  size_t end = 0;              // where the bytes not read begin
  // The record that ended the reading before `max_journal`: damaged (a crash), or whole with
  // content that does not apply (`content`; then nothing was rebuilt, the history holds part
  // of it).
  bool stopped = false, content = false;
  std::string why;
  Document document;
};

PrefixRead ReadPrefix(const std::string& text, size_t max_journal) {
  PrefixRead read;
  Reader r{{}, &read.warnings};
  const size_t eol = text.find('\n');
  const std::string header = text.substr(0, eol);
  const std::string want = std::string(kFormatName) + " " + std::to_string(kFormatVersion);
  if (header != want) {
    read.base_error = "version: \"" + header.substr(0, 40) + "\" is not a version this build reads (" + want +
                      "; version " + std::to_string(kLegacyVersion) + " is read as one JSON object)";
    return read;
  }
  size_t pos = eol == std::string::npos ? text.size() : eol + 1;
  std::string kind, payload, why;
  if (!NextRecord(text, &pos, &kind, &payload, &why)) {
    read.base_error = "base: " + why;
    return read;
  }
  History h;
  Json base;
  if (kind != "base") r.Fail("base", "expected the base record first, found \"" + kind + "\"");
  if (!r.error.empty() || !ParsePayload(payload, "base", &base, &r) || !ReadBase(base, /*legacy=*/false, &r, &h)) {
    read.base_error = r.error;
    return read;
  }
  read.end = pos;
  for (size_t k = 0; pos < text.size() && k < max_journal; ++k) {
    const std::string at = RecordName(k);
    if (!NextRecord(text, &pos, &kind, &payload, &why)) {
      read.stopped = true;
      read.why = at + ": " + why;
      break;
    }
    Json j;
    if (kind != "journal") r.Fail(at, "expected a journal record, found \"" + kind + "\"");
    if (!r.error.empty() || !ParsePayload(payload, at, &j, &r) || !ReadJournal(j, at, &r, &h)) {
      read.stopped = read.content = true;
      read.why = r.error;
      return read;
    }
    ++read.journal_records;
    read.end = pos;
  }
  if (h.without_history && read.journal_records > 0)
    read.warnings.push_back("the project is restored as of the base record: the " +
                            std::to_string(read.journal_records) +
                            " journal records after it are in the older layout and are not replayed");
  if (!Rebuild(h, &r, &read.document)) read.rebuild_error = r.error;
  return read;
}

// A version 2 file: the header line, the base record and the journal. The journal restores as
// far as it reads: a record that is damaged, or whole but does not apply (nor rebuild), ends
// it, and the document is that of the record before (result->dropped says which and why).
bool ReadRecords(const std::string& text, Reader* r, RecoveryLoadResult* result) {
  constexpr size_t kAllRecords = std::numeric_limits<size_t>::max();
  auto refuse = [r](const std::string& error) {
    r->error = error;
    return false;
  };
  PrefixRead read = ReadPrefix(text, kAllRecords);
  if (!read.base_error.empty()) return refuse(read.base_error);
  bool torn = read.stopped && !read.content;
  std::string why = read.why;
  // The history holds part of the record that failed: read again, up to the one before it.
  if (read.content) read = ReadPrefix(text, read.journal_records);
  if (!read.rebuild_error.empty()) {
    // Every record applied, but the history they make does not rebuild (a redo edit, the clean
    // depth, which only the rebuild checks): by bisection, a prefix that rebuilds and the record
    // with which it no longer does; O(log records) readings, and only for a damaged file.
    if (read.journal_records == 0) return refuse(read.rebuild_error);
    PrefixRead good = ReadPrefix(text, 0);
    if (!good.rebuild_error.empty()) return refuse(read.rebuild_error);
    size_t bad_count = read.journal_records;
    std::string bad_error = read.rebuild_error;
    while (bad_count - good.journal_records > 1) {
      PrefixRead mid = ReadPrefix(text, good.journal_records + (bad_count - good.journal_records) / 2);
      if (mid.rebuild_error.empty()) {
        good = std::move(mid);
      } else {
        bad_count = mid.journal_records;
        bad_error = mid.rebuild_error;
      }
    }
    read = std::move(good);
    torn = false;
    why = RecordName(read.journal_records) + ": the history with it does not rebuild: " + bad_error;
  }
  const size_t k = read.journal_records;
  if (torn) {
    // What a crash during an append leaves: the work up to the record before is whole.
    result->dropped = why + " (a write cut short by a crash): its " + std::to_string(text.size() - read.end) +
                      " bytes are dropped and the document is restored as of " + AsOf(k);
  } else if (!why.empty()) {
    result->dropped = why + ": " + RecordName(k) + " and what follows it (" + std::to_string(text.size() - read.end) +
                      " bytes) are dropped and the document is restored as of " + AsOf(k);
  }
  if (!result->dropped.empty()) read.warnings.push_back(result->dropped);
  result->warnings.insert(result->warnings.end(), read.warnings.begin(), read.warnings.end());
  result->journal_records = k;
  result->document = std::move(read.document);
  return true;
}

// ---------------------------------------------------------------------------------------
// Writing records.

OrderedJson EditsJson(const std::vector<Edit>& edits, const std::string& at, std::string* error) {
  OrderedJson list = OrderedJson::array();
  for (size_t i = 0; i < edits.size(); ++i) list.push_back(WriteEdit(edits[i], Index(at, i), error));
  return list;
}

std::string Dump(const OrderedJson& j) { return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace); }

std::string BasePayload(const Project& project, const std::vector<Edit>& undo, const std::vector<Edit>& redo,
                        size_t clean_undo_depth, bool clean_is_unreachable, std::string* error) {
  error->clear();
  OrderedJson root;
  std::string project_error;
  root["project"] = project_io_internal::ProjectToJsonObject(project, &project_error);
  if (!project_error.empty()) *error = "project." + project_error;
  root["undo"] = EditsJson(undo, "undo", error);
  root["redo"] = EditsJson(redo, "redo", error);
  root["clean_undo_depth"] = clean_undo_depth;
  root["clean_is_unreachable"] = clean_is_unreachable;
  if (!error->empty()) return {};
  return Dump(root);
}

std::string Frame(const char* kind, const std::string& payload) {
  char crc[9];
  std::snprintf(crc, sizeof crc, "%08x", static_cast<unsigned>(Crc32(payload)));
  return std::string(kind) + " " + std::to_string(payload.size()) + " " + crc + "\n" + payload + "\n";
}

std::string FileHeader() { return std::string(kFormatName) + " " + std::to_string(kFormatVersion) + "\n"; }

}  // namespace

std::string RecoveryToText(const Document& document, std::string* error) {
  const std::string base = BasePayload(document.project(), document.undo_stack(), document.redo_stack(),
                                       document.clean_undo_depth(), document.clean_is_unreachable(), error);
  if (!error->empty()) return {};
  return FileHeader() + Frame("base", base);
}

std::string FrameRecoveryRecords(const std::vector<std::string>& payloads) {
  std::string text = FileHeader();
  for (size_t i = 0; i < payloads.size(); ++i) text += Frame(i == 0 ? "base" : "journal", payloads[i]);
  return text;
}

RecoveryLoadResult RecoveryFromText(const std::string& text) {
  RecoveryLoadResult result;
  try {
    Reader reader{{}, &result.warnings};
    if (text.rfind(std::string(kFormatName) + " ", 0) == 0) {
      if (!ReadRecords(text, &reader, &result)) result.error = reader.error;
    } else {
      // Version 1: one JSON object (or not a recovery file at all: the format check says so).
      Json root;
      History h;
      if (!project_io_internal::ParseJson(text, &root, &result.error)) return result;
      if (!ReadBase(root, /*legacy=*/true, &reader, &h) || !Rebuild(h, &reader, &result.document))
        result.error = reader.error;
    }
  } catch (const std::exception& e) {
    result.error = std::string("cannot read the recovery file: ") + e.what();
  }
  if (!result.ok()) result.document = Document();
  return result;
}

std::string SaveRecovery(const Document& document, const std::string& path) {
  std::string error;
  const std::string text = RecoveryToText(document, &error);
  if (!error.empty()) return "cannot write " + path + ": " + error;
  return WriteFileAtomically(path, text, Symlinks::kRefuse);
}

RecoveryLoadResult LoadRecovery(const std::string& path) {
  RecoveryLoadResult result;
  std::string bytes;
  if (!ReadRegularFile(path, kMaxTextFileBytes, &bytes, &result.error)) return result;
  result = RecoveryFromText(bytes);
  if (!result.ok()) result.error = path + ": " + result.error;
  return result;
}

RecoveryDelta MakeRecoveryDelta(const Document& document, const Edit* unfinished, RecoveryWritten* written) {
  RecoveryDelta delta;
  delta.clean_undo_depth = document.clean_undo_depth();
  delta.clean_is_unreachable = document.clean_is_unreachable();
  const std::vector<Edit>& undo = document.undo_stack();
  const std::vector<Edit>& redo = document.redo_stack();
  if (written->epoch != document.epoch()) {
    // During a drag the project is the preview, which the unfinished edit leads to.
    delta.project = document.project();
    delta.undo = undo;
    delta.redo = redo;
  } else {
    auto common = [](const std::vector<std::uint64_t>& a, const std::vector<std::uint64_t>& b) {
      size_t n = 0;
      while (n < a.size() && n < b.size() && a[n] == b[n]) ++n;
      return n;
    };
    delta.undo_keep = common(written->undo_ids, document.undo_ids());
    delta.redo_keep = common(written->redo_ids, document.redo_ids());
    delta.undo.assign(undo.begin() + static_cast<std::ptrdiff_t>(delta.undo_keep), undo.end());
    delta.redo.assign(redo.begin() + static_cast<std::ptrdiff_t>(delta.redo_keep), redo.end());
  }
  written->epoch = document.epoch();
  written->undo_ids = document.undo_ids();
  written->redo_ids = document.redo_ids();
  if (unfinished) {
    delta.undo.push_back(*unfinished);
    written->undo_ids.push_back(0);  // no edit's id: the next delta replaces it
  }
  return delta;
}

RecoveryWriteResult RecoveryJournal::Write(const std::string& path, RecoveryDelta delta) {
  RecoveryWriteResult result;
  std::string record, error;
  clean_undo_depth_ = delta.clean_undo_depth;
  clean_is_unreachable_ = delta.clean_is_unreachable;
  if (delta.project) {
    project_ = std::move(*delta.project);
    undo_ = std::move(delta.undo);
    redo_ = std::move(delta.redo);
    path_.clear();
  } else {
    assert(delta.undo_keep <= undo_.size() && delta.redo_keep <= redo_.size());
    OrderedJson j;
    j["undo_keep"] = delta.undo_keep;
    j["redo_keep"] = delta.redo_keep;
    j["undo"] = EditsJson(delta.undo, "undo", &error);
    j["redo"] = EditsJson(delta.redo, "redo", &error);
    j["clean_undo_depth"] = delta.clean_undo_depth;
    j["clean_is_unreachable"] = delta.clean_is_unreachable;
    if (!error.empty()) path_.clear();  // the state below still changes: the next write is whole
    record = Frame("journal", Dump(j));
    while (undo_.size() > delta.undo_keep) {
      RevertEdit(undo_.back(), &project_);
      undo_.pop_back();
    }
    redo_.resize(delta.redo_keep);
    for (Edit& edit : delta.undo) {
      ApplyEdit(edit, &project_);
      undo_.push_back(std::move(edit));
    }
    for (Edit& edit : delta.redo) redo_.push_back(std::move(edit));
    if (!error.empty()) {
      result.error = "cannot write " + path + ": " + error;
      return result;
    }
  }
  if (!path_.empty() && path_ == path && journal_bytes_ + record.size() <= base_bytes_) {
    const std::string append_error = AppendToFile(path, record);
    if (append_error.empty()) {
      journal_bytes_ += record.size();
      result.bytes_written = record.size();
      result.file_bytes = base_bytes_ + journal_bytes_;
      return result;
    }
    // Removed meanwhile (nothing was unsaved for a while), or the disk refused: write it whole.
  }
  path_.clear();
  const std::string base = BasePayload(project_, undo_, redo_, clean_undo_depth_, clean_is_unreachable_, &error);
  if (!error.empty()) {
    result.error = "cannot write " + path + ": " + error;
    return result;
  }
  const std::string text = FileHeader() + Frame("base", base);
  result.error = WriteFileAtomically(path, text, Symlinks::kRefuse);
  if (!result.error.empty()) return result;
  path_ = path;
  base_bytes_ = text.size();
  journal_bytes_ = 0;
  result.bytes_written = result.file_bytes = text.size();
  result.compacted = true;
  return result;
}

}  // namespace facet
