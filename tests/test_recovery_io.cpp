// The recovery file (core/io/recovery_io.h): a document with a varied history round-trips
// exactly (project, every undo and redo edit's label and changes, the dirty flag), and
// malformed or inconsistent files are errors that name what is wrong, never crashes.
#include <doctest/doctest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/geometry/id_limits.h"
#include "core/io/project_io.h"
#include "core/io/recovery_io.h"
#include "core/scene/document.h"
#include "tests/random_edits.h"
#include "tests/synthetic_scene.h"

using facet::Document;
using facet::Edit;
using facet::Project;
using facet::RecoveryFromText;
using facet::RecoveryLoadResult;
using facet::RecoveryToText;

namespace {

// Whether the project file would store `project` and read it back equal: the random edits
// can make projects the loader refuses (an image-line constraint without an image), which no
// user can save either, so the history keeps to savable ones.
bool Savable(const Project& project) {
  if (!facet::CheckProjectSavable(project).empty()) return false;
  const facet::ProjectLoadResult back = facet::ProjectFromJson(facet::ProjectToJson(project));
  return back.ok() && back.project == project;
}

// A document with `edits` random savable edits, then some undone (so the redo stack holds
// them), saved (MarkClean) somewhere along the way.
Document VariedDocument(unsigned seed, int edits, int undos, int clean_at) {
  std::mt19937 rng(seed);
  Document doc(facet::testing::MakeBoxScene().project);
  int committed = 0;
  for (int attempt = 0; committed < edits && attempt < 20 * edits; ++attempt) {
    const Project next = facet::testing::RandomEdit(doc.project(), rng);
    if (!Savable(next)) continue;
    if (doc.Commit("edit " + std::to_string(committed) + " \u00e9", next)) ++committed;
    if (committed == clean_at) doc.MarkClean();
  }
  REQUIRE(committed == edits);
  for (int i = 0; i < undos; ++i) REQUIRE(doc.Undo());
  return doc;
}

void CheckSameDocument(const Document& got, const Document& want) {
  CHECK(got.project() == want.project());
  REQUIRE(got.undo_stack().size() == want.undo_stack().size());
  REQUIRE(got.redo_stack().size() == want.redo_stack().size());
  for (size_t i = 0; i < want.undo_stack().size(); ++i) {
    CAPTURE(i);
    CHECK(got.undo_stack()[i].label == want.undo_stack()[i].label);
    CHECK(got.undo_stack()[i] == want.undo_stack()[i]);
  }
  for (size_t i = 0; i < want.redo_stack().size(); ++i) {
    CAPTURE(i);
    CHECK(got.redo_stack()[i].label == want.redo_stack()[i].label);
    CHECK(got.redo_stack()[i] == want.redo_stack()[i]);
  }
  CHECK(got.dirty() == want.dirty());
  CHECK(got.clean_undo_depth() == want.clean_undo_depth());
  CHECK(got.clean_is_unreachable() == want.clean_is_unreachable());
}

std::string ErrorOf(const std::string& text) {
  const RecoveryLoadResult loaded = RecoveryFromText(text);
  CHECK_FALSE(loaded.ok());
  MESSAGE(loaded.error);
  return loaded.error;
}

std::string Text(const Document& doc) {
  std::string error;
  const std::string text = RecoveryToText(doc, &error);
  REQUIRE_MESSAGE(error.empty(), error);
  return text;
}

// The base record's JSON of a one-record file (the payload is the second line: compact JSON
// holds no raw newline), and a file made of a changed one.
nlohmann::json Base(const std::string& text) {
  const size_t start = text.find('\n', text.find('\n') + 1) + 1;
  return nlohmann::json::parse(text.substr(start, text.find('\n', start) - start));
}
std::string Framed(const nlohmann::json& base) { return facet::FrameRecoveryRecords({base.dump()}); }

}  // namespace

TEST_CASE("a document with a varied history round-trips exactly, and behaves the same after") {
  int with_redo = 0, dirty = 0, clean = 0;
  for (unsigned seed = 1; seed <= 12; ++seed) {
    CAPTURE(seed);
    const int edits = 6 + static_cast<int>(seed % 7);
    const int undos = static_cast<int>(seed % 4);
    // Every fourth seed ends where it was saved: not dirty, with a redo stack beyond it.
    const int clean_at = seed % 4 == 0 ? edits - undos : static_cast<int>(seed % 5);
    const Document original = VariedDocument(seed, edits, undos, clean_at);
    const RecoveryLoadResult loaded = RecoveryFromText(Text(original));
    REQUIRE_MESSAGE(loaded.ok(), loaded.error);
    CHECK(loaded.warnings.empty());
    CheckSameDocument(loaded.document, original);
    with_redo += !original.redo_stack().empty();
    (original.dirty() ? dirty : clean) += 1;

    // The rebuilt history is live: undo everything and redo everything, on both.
    Document a = original, b = loaded.document;
    while (a.CanUndo()) {
      REQUIRE(b.Undo());
      a.Undo();
      CHECK(a.project() == b.project());
      CHECK(a.dirty() == b.dirty());
    }
    CHECK_FALSE(b.CanUndo());
    while (a.CanRedo()) {
      REQUIRE(b.Redo());
      a.Redo();
      CHECK(a.project() == b.project());
    }
    // Writing the rebuilt document gives the same bytes.
    CHECK(Text(loaded.document) == Text(original));
  }
  // The seeds must cover what the test names.
  CHECK(with_redo >= 6);
  CHECK(dirty >= 3);
  CHECK(clean >= 1);
}

TEST_CASE("an unreachable saved state and an empty history round-trip") {
  Document doc = VariedDocument(77, 5, 2, 5);  // saved at 5 edits, 2 undone
  std::mt19937 rng(78);
  Project next = facet::testing::RandomEdit(doc.project(), rng);
  while (!Savable(next) || next == doc.project()) next = facet::testing::RandomEdit(doc.project(), rng);
  REQUIRE(doc.Commit("branch", next));  // the saved state is now beyond reach
  REQUIRE(doc.clean_is_unreachable());
  RecoveryLoadResult loaded = RecoveryFromText(Text(doc));
  REQUIRE_MESSAGE(loaded.ok(), loaded.error);
  CheckSameDocument(loaded.document, doc);
  CHECK(loaded.document.dirty());

  const Document empty(facet::testing::MakeBoxScene().project);
  loaded = RecoveryFromText(Text(empty));
  REQUIRE_MESSAGE(loaded.ok(), loaded.error);
  CheckSameDocument(loaded.document, empty);
}

// A recovery file left by the Facet before an update (its project in an older format) still
// gives the work back: the project is migrated like a project file; its edits, written in the
// old layout, cannot be replayed, so the history is dropped and the warning says so.
TEST_CASE("a recovery file from an older Facet restores the project without its history") {
  Document doc = VariedDocument(21, 4, 1, 0);
  doc.MarkClean();  // the restored work is unsaved whatever the file said
  nlohmann::json j = Base(Text(doc));
  // The project as version 2 wrote it: no texture choices, no references.
  j["project"]["version"] = 2;
  j["project"].erase("references");
  for (auto& image : j["project"]["images"]) image.erase("use_for_texture");
  for (auto& primitive : j["project"]["primitives"]) primitive.erase("face_textures");
  const RecoveryLoadResult loaded = RecoveryFromText(Framed(j));
  REQUIRE_MESSAGE(loaded.ok(), loaded.error);
  Project expected = doc.project();
  expected.references.clear();
  for (facet::Image& image : expected.images) image.use_for_texture = true;
  for (facet::Primitive& primitive : expected.primitives) primitive.face_textures.clear();
  CHECK(loaded.document.project() == expected);
  CHECK(loaded.document.undo_stack().empty());
  CHECK(loaded.document.redo_stack().empty());
  CHECK(loaded.document.dirty());
  bool warned = false;
  for (const std::string& w : loaded.warnings)
    warned = warned || w.find("its undo history is not") != std::string::npos;
  CHECK(warned);
  // A newer project version is refused by name.
  j["project"]["version"] = Project::kFormatVersion + 1;
  CHECK(ErrorOf(Framed(j)).find("project.version:") == 0);
}

TEST_CASE("malformed recovery files are errors naming the place, never crashes") {
  const Document doc = VariedDocument(5, 6, 2, 1);
  const std::string good = Text(doc);
  CHECK(RecoveryFromText(good).ok());

  CHECK(ErrorOf("") == "line 1, column 1: the file is empty");
  // The base is written whole (atomically), so a cut one is damage, not a torn append.
  CHECK(ErrorOf(good.substr(0, good.size() / 2)) == "base: the record is cut short");
  CHECK(ErrorOf("facet-recovery 3\n" + good.substr(good.find('\n') + 1)).find("version: \"facet-recovery 3\" is not") ==
        0);
  CHECK(ErrorOf("[]").find("expected a JSON object") != std::string::npos);
  CHECK(ErrorOf(facet::ProjectToJson(doc.project())).find("format:") == 0);

  using nlohmann::json;
  auto mutated = [&](auto change) {
    json j = Base(good);
    change(j);
    return ErrorOf(Framed(j));
  };
  CHECK(mutated([](json& j) { j.erase("undo"); }) == "undo: missing field");
  CHECK(mutated([](json& j) { j["undo"][1]["label"] = 3; }) == "undo[1].label: expected a string");
  CHECK(mutated([](json& j) { j["clean_undo_depth"] = -1; }).find("clean_undo_depth:") == 0);
  // The project is read by the project loader, reference checks included.
  CHECK(mutated([](json& j) { j["project"]["next_id"] = 1; }).find("project: next_id: must be greater than every id") ==
        0);
  // An object inside an edit is read by the project loader's own reader, with its path.
  CHECK(mutated([](json& j) {
          for (auto& [key, list] : j["undo"][0].items()) {
            if (!list.is_array() || key == "units" || key == "next_id") continue;
            for (auto& change : list) {
              if (change.contains("after")) {
                change["after"]["id"] = "x";
                return;
              }
            }
          }
        }).find("undo[0].") == 0);
  CHECK(mutated([](json& j) { j["redo"][0] = json{{"label", "nothing"}}; }) == "redo[0]: the edit changes nothing");
}

TEST_CASE("a history that does not lead to its project is an error naming the edit") {
  // One image whose focal length three edits change, so each edit's record is known.
  Project p = facet::testing::MakeBoxScene().project;
  Document doc(p);
  for (double focal : {700.0, 800.0, 900.0}) {
    p.images[0].camera.focal_px = focal;
    REQUIRE(doc.Commit("focal " + std::to_string(static_cast<int>(focal)), p));
  }
  REQUIRE(doc.Undo());  // undo: 700, 800; redo: 900
  const std::string good = Text(doc);
  REQUIRE(RecoveryFromText(good).ok());
  using nlohmann::json;
  auto mutated = [&](auto change) {
    json j = Base(good);
    change(j);
    return ErrorOf(Framed(j));
  };

  // The last undo edit's "after" is not the current project.
  std::string error = mutated([](json& j) { j["undo"][1]["images"][0]["after"]["camera"]["focal_px"] = 801.0; });
  CHECK(error.find("history: undo[1]: does not revert onto the project after it: images: id") == 0);
  // The current project is not where the history leads.
  error = mutated([](json& j) { j["project"]["images"][0]["camera"]["focal_px"] = 850.0; });
  CHECK(error.find("history: undo[1]: does not revert") == 0);
  // A redo edit that starts from another project.
  error = mutated([](json& j) { j["redo"][0]["images"][0]["before"]["camera"]["focal_px"] = 1000.0; });
  CHECK(error.find("history: redo[0]: does not apply onto the project before it") == 0);
  // An index that points past the list.
  error = mutated([](json& j) {
    json change = j["undo"][0]["images"][0];
    change.erase("after");
    change.erase("after_index");
    change["id"] = 9999;
    change["before"]["id"] = 9999;
    change["before_index"] = 40;
    j["undo"][0]["images"].push_back(change);
  });
  CHECK(error.find(
            "history: undo[0]: does not revert onto the project after it: images: inserts id 9999 at index 40") == 0);
  // An edit that is not what the program records: one more change, with the same segment
  // before and after.
  error = mutated([](json& j) {
    const json segment = j["project"]["segments"][0];
    j["undo"][1]["segments"] = json::array({json{
        {"id", segment["id"]}, {"before", segment}, {"before_index", 0}, {"after", segment}, {"after_index", 0}}});
  });
  CHECK(error.find("history: undo[1]: is not the edit of the projects it joins") == 0);
  // Reverting leaves a project the loader would refuse: a pin on a missing primitive.
  error = mutated([](json& j) {
    json pin = j["project"]["pins"][0];
    pin["id"] = 9000;
    pin["primitive_id"] = 8999;
    j["undo"][0]["pins"] = json::array({json{{"id", 9000}, {"before", pin}, {"before_index", 0}}});
  });
  CHECK(error.find("history: undo[0]: reverting it leaves an unsound project: pins[0].vertex: refers to a missing "
                   "primitive 8999") == 0);
  // A saved state beyond the history.
  error = mutated([](json& j) { j["clean_undo_depth"] = 7; });
  CHECK(error.find("history: clean_undo_depth: 7 is beyond the history (3 edits)") == 0);
}

TEST_CASE("adding and removing reference geometry round-trips through the recovery file") {
  Document doc(facet::testing::MakeBoxScene().project);
  Project added = doc.project();
  for (const char* path : {"plan.obj", "../scans/site.glb"}) {
    facet::Reference reference;
    reference.id = added.NewId();
    reference.path = path;
    reference.y_up = path[0] == 'p';
    added.references.push_back(reference);
  }
  REQUIRE(doc.Commit("Add references", added));
  Project removed = doc.project();
  removed.references.erase(removed.references.begin());
  REQUIRE(doc.Commit("Remove reference plan.obj", removed));
  REQUIRE(doc.Undo());  // the removal waits on the redo stack
  REQUIRE(doc.undo_stack().back().references.size() == 2);
  const RecoveryLoadResult loaded = RecoveryFromText(Text(doc));
  REQUIRE_MESSAGE(loaded.ok(), loaded.error);
  CheckSameDocument(loaded.document, doc);
  Document rebuilt = loaded.document;
  REQUIRE(rebuilt.Redo());
  CHECK(rebuilt.project() == removed);
  REQUIRE(rebuilt.Undo());
  REQUIRE(rebuilt.Undo());
  CHECK(rebuilt.project().references.empty());
}

namespace {

// A private file in the temporary folder, removed at the end of the test.
struct TempFile {
  std::string path;
  explicit TempFile(const std::string& name)
      : path((std::filesystem::temp_directory_path() /
              ("facet_test_recovery_" + std::to_string(::getpid()) + "_" + name))
                 .string()) {
    std::filesystem::remove(path);
  }
  ~TempFile() { std::filesystem::remove(path); }
};

std::string ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// The document a write with an unfinished drag edit describes.
Document WithUnfinished(const Document& doc, const Project& drag_start, const Project& preview) {
  Document copy = doc;
  copy.CancelPreview(drag_start);
  *copy.MutableProjectForPreview() = preview;
  REQUIRE(copy.CommitFrom("drag (unfinished)", drag_start));
  return copy;
}

}  // namespace

// The journal (version 2): after every write the file loads to exactly the document written
// (project, both stacks, dirty flag), through commits, undos, redos, saves, a branch that
// drops the redo stack and a drag written unfinished; most writes are appends of a record the
// size of the change, and the file stays within about twice its base.
TEST_CASE("the recovery journal holds the document after every write, appending what changed") {
  const TempFile file("journal");
  std::mt19937 rng(2024);
  Document doc(facet::testing::MakeBoxScene().project);
  facet::RecoveryJournal journal;
  facet::RecoveryWritten written;
  int appends = 0, compactions = 0, undos = 0, redos = 0, branches = 0, drags = 0;
  std::uint64_t max_append = 0;
  size_t largest_whole = 0;
  auto write = [&](const Edit* unfinished, const Document& want) {
    const facet::RecoveryWriteResult result =
        journal.Write(file.path, facet::MakeRecoveryDelta(doc, unfinished, &written));
    REQUIRE_MESSAGE(result.ok(), result.error);
    CHECK(result.file_bytes == std::filesystem::file_size(file.path));
    if (result.compacted) {
      ++compactions;
    } else {
      ++appends;
      max_append = std::max(max_append, result.bytes_written);
    }
    const RecoveryLoadResult loaded = facet::LoadRecovery(file.path);
    REQUIRE_MESSAGE(loaded.ok(), loaded.error);
    CHECK(loaded.warnings.empty());
    CheckSameDocument(loaded.document, want);
    // The journal never grows beyond the base, a whole write of an earlier document, so the
    // file is at most twice the largest whole write.
    std::string error;
    largest_whole = std::max(largest_whole, RecoveryToText(want, &error).size());
    CHECK(result.file_bytes <= 2 * largest_whole);
  };
  for (int step = 0; step < 60; ++step) {
    CAPTURE(step);
    const int op = static_cast<int>(rng() % 10);
    if (op < 5 || !doc.CanUndo()) {
      const Project next = facet::testing::RandomEdit(doc.project(), rng);
      if (!Savable(next)) continue;
      branches += doc.CanRedo() ? 1 : 0;
      if (!doc.Commit("edit " + std::to_string(step), next)) continue;
    } else if (op < 7) {
      REQUIRE(doc.Undo());
      ++undos;
    } else if (op < 9 && doc.CanRedo()) {
      REQUIRE(doc.Redo());
      ++redos;
    } else if (op == 9) {
      // A drag in progress: its edit so far is written as one more undo edit.
      const Project drag_start = doc.project();
      Project preview = facet::testing::RandomEdit(drag_start, rng);
      if (!Savable(preview) || preview == drag_start) continue;
      const Document want = WithUnfinished(doc, drag_start, preview);
      *doc.MutableProjectForPreview() = preview;
      const Edit unfinished = facet::DiffProjects("drag (unfinished)", drag_start, preview);
      write(&unfinished, want);
      ++drags;
      if (rng() % 2) {
        doc.CancelPreview(drag_start);  // cancelled: the next write drops the unfinished edit
      } else {
        REQUIRE(doc.CommitFrom("drag", drag_start));
      }
    } else {
      doc.MarkClean();
    }
    write(nullptr, doc);
  }
  MESSAGE("appends " << appends << ", compactions " << compactions << ", largest append " << max_append << " B");
  CHECK(undos >= 5);
  CHECK(redos >= 3);
  CHECK(branches >= 1);
  CHECK(drags >= 3);
  // Appends are the rule, compactions the exception (the base doubles between them).
  CHECK(appends >= 4 * compactions);

  // A new document (File > Open): the next write is whole, and holds the new document alone.
  doc.Reset(facet::testing::MakeBoxScene().project);
  const facet::RecoveryDelta whole = facet::MakeRecoveryDelta(doc, nullptr, &written);
  CHECK(whole.project.has_value());
  CHECK(journal.Write(file.path, whole).compacted);
  CheckSameDocument(facet::LoadRecovery(file.path).document, doc);
}

// A crash in the middle of an append leaves the last record cut short, or (on a disk that
// reorders writes) with bytes that never arrived: the file restores as of the record before,
// and says so.
TEST_CASE("a torn journal restores up to its last whole record and says so") {
  const TempFile file("torn");
  std::mt19937 rng(7);
  Document doc(facet::testing::MakeBoxScene().project);
  facet::RecoveryJournal journal;
  facet::RecoveryWritten written;
  REQUIRE(journal.Write(file.path, facet::MakeRecoveryDelta(doc, nullptr, &written)).compacted);
  // A large base (many edits at once) so that the next small edits are appended.
  for (int i = 0; i < 12;) {
    const Project next = facet::testing::RandomEdit(doc.project(), rng);
    i += Savable(next) && doc.Commit("base edit", next) ? 1 : 0;
  }
  REQUIRE(journal.Write(file.path, facet::MakeRecoveryDelta(doc, nullptr, &written)).compacted);
  std::vector<Document> after;  // the document as of each journal record
  std::vector<size_t> ends;     // the file's size after each record
  for (int i = 0; i < 3;) {
    Project next = doc.project();
    next.units = "unit" + std::to_string(i);
    if (!doc.Commit("units " + std::to_string(i), next)) continue;
    const facet::RecoveryWriteResult result =
        journal.Write(file.path, facet::MakeRecoveryDelta(doc, nullptr, &written));
    REQUIRE_MESSAGE(result.ok(), result.error);
    REQUIRE_FALSE(result.compacted);
    after.push_back(doc);
    ends.push_back(result.file_bytes);
    ++i;
  }
  REQUIRE(doc.Undo());
  REQUIRE_FALSE(journal.Write(file.path, facet::MakeRecoveryDelta(doc, nullptr, &written)).compacted);
  after.push_back(doc);
  ends.push_back(std::filesystem::file_size(file.path));
  const std::string whole = ReadAll(file.path);
  REQUIRE(whole.size() == ends.back());

  const size_t last_start = ends[ends.size() - 2];
  const size_t header_end = whole.find('\n', last_start);
  // Cut inside the header line, inside the payload, and just before the closing newline.
  for (const size_t cut : {last_start + 3, (header_end + whole.size()) / 2, whole.size() - 1}) {
    CAPTURE(cut);
    const RecoveryLoadResult loaded = RecoveryFromText(whole.substr(0, cut));
    REQUIRE_MESSAGE(loaded.ok(), loaded.error);
    CHECK(loaded.journal_records == 3);
    CheckSameDocument(loaded.document, after[2]);
    REQUIRE(loaded.warnings.size() == 1);
    CHECK(loaded.warnings[0] ==
          "journal[3]: " +
              std::string(cut == last_start + 3 ? "the header line is incomplete" : "the record is cut short") +
              " (a write cut short by a crash): its " + std::to_string(cut - last_start) +
              " bytes are dropped and the document is restored as of journal[2]");
  }
  // A byte of the last record's payload that did not reach the disk: its checksum fails.
  std::string damaged = whole;
  damaged[whole.size() - 5] ^= 0x20;
  RecoveryLoadResult loaded = RecoveryFromText(damaged);
  REQUIRE_MESSAGE(loaded.ok(), loaded.error);
  CheckSameDocument(loaded.document, after[2]);
  REQUIRE(loaded.warnings.size() == 1);
  CHECK(loaded.warnings[0].find("journal[3]: its checksum does not match") == 0);
  // Cut inside the first journal record: the base alone, as of the base record.
  loaded = RecoveryFromText(whole.substr(0, ends[0] - 2));
  REQUIRE_MESSAGE(loaded.ok(), loaded.error);
  CHECK(loaded.journal_records == 0);
  CHECK(loaded.document.undo_stack().size() == 12);
  REQUIRE(loaded.warnings.size() == 1);
  CHECK(loaded.warnings[0].find("restored as of the base record") != std::string::npos);

  CHECK_FALSE(loaded.dropped.empty());  // the app keeps such a file aside (app/state/autosave.h)
}

namespace {

// A journal record (core/io/recovery_io.h) that sets the units: the edit from `from` to `to`
// on top of `undo_keep` kept edits.
std::string UnitsRecord(size_t undo_keep, const std::string& from, const std::string& to) {
  nlohmann::json record = {{"undo_keep", undo_keep},
                           {"redo_keep", 0},
                           {"undo", nlohmann::json::array({{{"label", "units " + to}, {"units", {from, to}}}})},
                           {"redo", nlohmann::json::array()},
                           {"clean_undo_depth", 0},
                           {"clean_is_unreachable", false}};
  return record.dump();
}

// The document after `n` units records of UnitsRecord's chain m -> u0 -> u1 -> ...
Document UnitsDocument(size_t n) {
  Document doc(facet::testing::MakeBoxScene().project);
  for (size_t i = 0; i < n; ++i) {
    Project next = doc.project();
    next.units = "u" + std::to_string(i);
    REQUIRE(doc.Commit("units " + next.units, next));
  }
  return doc;
}

}  // namespace

// A whole record (its checksum right) whose content does not apply ends the journal like a
// torn one: the document is that of the record before, and `dropped` names the record and
// why; the records after it are dropped with it (their base is gone).
TEST_CASE("a journal record that does not apply restores up to the record before it and names it") {
  const Document empty(facet::testing::MakeBoxScene().project);
  const std::string base = Base(Text(empty)).dump();
  const std::string r0 = UnitsRecord(0, "m", "u0"), r1 = UnitsRecord(1, "u0", "u1"), r2 = UnitsRecord(2, "u1", "u2");
  REQUIRE(UnitsDocument(0).project() == empty.project());
  {
    const RecoveryLoadResult whole = RecoveryFromText(facet::FrameRecoveryRecords({base, r0, r1, r2}));
    REQUIRE_MESSAGE(whole.ok(), whole.error);
    CHECK(whole.dropped.empty());
    CHECK(whole.journal_records == 3);
    CHECK(whole.document.project().units == "u2");
  }
  // Frames made by hand: FrameRecoveryRecords calls every record after the first "journal".
  const std::string base_only = facet::FrameRecoveryRecords({base});
  const std::string base_frame = base_only.substr(base_only.find('\n') + 1);
  auto journal_frame = [&](const std::string& payload) {
    return facet::FrameRecoveryRecords({base, payload}).substr(base_only.size());
  };
  struct Case {
    const char* name;
    std::string bad_frame;  // in place of journal[1]
    std::string why;        // the start of `dropped`
  };
  const Case cases[] = {
      {"an undo_keep beyond the history",
       journal_frame(R"({"undo_keep":9,"redo_keep":0,"undo":[],"redo":[],"clean_undo_depth":0,)"
                     R"("clean_is_unreachable":false})"),
       "journal[1].undo_keep: 9 is beyond the undo history (1 edits)"},
      {"an edit that does not fit the project", journal_frame(UnitsRecord(1, "yd", "u1")),
       "journal[1].undo[0]: does not apply onto the project: units"},
      {"not JSON", journal_frame("{\"undo_keep\": 1,"), "journal[1]: line 1, column"},
      {"a base record in the middle", base_frame, "journal[1]: expected a journal record, found \"base\""},
      {"a next_id that would wrap at the next object",
       journal_frame(R"({"undo_keep":1,"redo_keep":0,"undo":[{"label":"ids","next_id":[)" +
                     std::to_string(empty.project().next_id) +
                     R"(,18446744073709551615]}],"redo":[],"clean_undo_depth":0,"clean_is_unreachable":false})"),
       "journal[1].undo[0].next_id: expected [before, after] as two positive integers up to 4611686018427387904"},
  };
  for (const Case& c : cases) {
    CAPTURE(c.name);
    const std::string text = facet::FrameRecoveryRecords({base, r0}) + c.bad_frame + journal_frame(r2);
    const RecoveryLoadResult loaded = RecoveryFromText(text);
    REQUIRE_MESSAGE(loaded.ok(), loaded.error);
    CHECK(loaded.journal_records == 1);
    CheckSameDocument(loaded.document, UnitsDocument(1));
    INFO(loaded.dropped);
    CHECK(loaded.dropped.rfind(c.why, 0) == 0);
    CHECK(loaded.dropped.find(
              "journal[1] and what follows it (" + std::to_string(c.bad_frame.size() + journal_frame(r2).size()) +
              " bytes) are dropped and the document is restored as of journal[0]") != std::string::npos);
    CHECK(std::find(loaded.warnings.begin(), loaded.warnings.end(), loaded.dropped) != loaded.warnings.end());
  }
  // In the first record: the base alone.
  const RecoveryLoadResult first = RecoveryFromText(facet::FrameRecoveryRecords({base, UnitsRecord(0, "yd", "u0")}));
  REQUIRE_MESSAGE(first.ok(), first.error);
  CHECK(first.journal_records == 0);
  CheckSameDocument(first.document, UnitsDocument(0));
  CHECK(first.dropped.find("restored as of the base record") != std::string::npos);
}

// Every record applies, but with one of them the history no longer rebuilds (a redo edit is
// only checked then): the longest prefix that rebuilds is restored, the record named.
TEST_CASE("a journal record after which the history does not rebuild is dropped with what follows") {
  const Document empty(facet::testing::MakeBoxScene().project);
  const std::string base = Base(Text(empty)).dump();
  std::vector<std::string> records = {base};
  for (size_t i = 0; i < 6; ++i)
    records.push_back(UnitsRecord(i, i == 0 ? "m" : "u" + std::to_string(i - 1), "u" + std::to_string(i)));
  // journal[4]: keeps the 4 edits and gains a redo that cannot follow the project (its units
  // start from "yd"); journal[5] then builds on it, keeping the redo.
  records[5] = R"({"undo_keep":4,"redo_keep":0,"undo":[],"redo":[{"label":"bad redo","units":["yd","ft"]}],)"
               R"("clean_undo_depth":0,"clean_is_unreachable":false})";
  nlohmann::json keeps_redo = nlohmann::json::parse(UnitsRecord(4, "u3", "u4"));
  keeps_redo["redo_keep"] = 1;
  records[6] = keeps_redo.dump();
  const RecoveryLoadResult loaded = RecoveryFromText(facet::FrameRecoveryRecords(records));
  REQUIRE_MESSAGE(loaded.ok(), loaded.error);
  INFO(loaded.dropped);
  CHECK(loaded.journal_records == 4);
  CheckSameDocument(loaded.document, UnitsDocument(4));
  CHECK(loaded.dropped.rfind("journal[4]: the history with it does not rebuild: history: redo[0]: does not apply", 0) ==
        0);
  CHECK(loaded.dropped.find("restored as of journal[3]") != std::string::npos);
}

// Ids enter through the project file's reader and the recovery file's: each refuses values
// beyond kMaxId, so the next object's id (next_id, counted up) can never wrap to 0.
TEST_CASE("a next_id or an id that would wrap is refused where it is read") {
  const Document doc(facet::testing::MakeBoxScene().project);
  nlohmann::json base = Base(Text(doc));
  for (const std::uint64_t value : {std::uint64_t{18446744073709551615u}, facet::kMaxId + 1}) {
    CAPTURE(value);
    nlohmann::json j = base;
    j["project"]["next_id"] = value;
    CHECK(ErrorOf(Framed(j)).rfind("project: next_id: expected an id up to 4611686018427387904 (2^62), found ", 0) ==
          0);
    nlohmann::json project = nlohmann::json::parse(facet::ProjectToJson(doc.project()));
    project["next_id"] = value;
    const facet::ProjectLoadResult loaded = facet::ProjectFromJson(project.dump());
    CHECK_FALSE(loaded.ok());
    CHECK(loaded.error.find("next_id: expected an id up to 4611686018427387904 (2^62)") != std::string::npos);
    project["next_id"] = doc.project().next_id;
    project["images"][0]["id"] = value;
    CHECK(facet::ProjectFromJson(project.dump()).error.find("images[0].id: expected an id up to") != std::string::npos);
  }
  // kMaxId itself is a valid next_id; the next objects count on from it.
  nlohmann::json j = base;
  j["project"]["next_id"] = facet::kMaxId;
  const RecoveryLoadResult at_max = RecoveryFromText(Framed(j));
  REQUIRE_MESSAGE(at_max.ok(), at_max.error);
  Project next = at_max.document.project();
  CHECK(next.NewId() == facet::kMaxId);
  CHECK(next.next_id == facet::kMaxId + 1);
}

// The recovery file's name is the program's: a link or a FIFO there is refused by name, and
// what the link points to is untouched (issue 25: a link to the project turned it into
// recovery text).
TEST_CASE("the recovery journal refuses a symbolic link or a FIFO at its path") {
  const TempFile file("linked");
  const TempFile other("other_project");
  {
    std::ofstream out(other.path, std::ios::binary);
    out << "the other project";
  }
  std::filesystem::remove(file.path);
  std::filesystem::create_symlink(other.path, file.path);
  Document doc(facet::testing::MakeBoxScene().project);
  facet::RecoveryJournal journal;
  facet::RecoveryWritten written;
  facet::RecoveryWriteResult result = journal.Write(file.path, facet::MakeRecoveryDelta(doc, nullptr, &written));
  CHECK(result.error ==
        "refusing to write " + file.path + ": it is a symbolic link (to " + other.path + "), not a file Facet wrote");
  CHECK(ReadAll(other.path) == "the other project");
  CHECK(facet::SaveRecovery(doc, file.path).find("it is a symbolic link") != std::string::npos);
  CHECK(ReadAll(other.path) == "the other project");
  // Written whole once the link is gone; then a link put in its place stops the appends too.
  std::filesystem::remove(file.path);
  REQUIRE(journal.Write(file.path, facet::MakeRecoveryDelta(doc, nullptr, &written)).ok());
  std::filesystem::remove(file.path);
  std::filesystem::create_symlink(other.path, file.path);
  Project next = doc.project();
  next.units = "ft";
  REQUIRE(doc.Commit("units", next));
  result = journal.Write(file.path, facet::MakeRecoveryDelta(doc, nullptr, &written));
  CHECK(result.error.find("it is a symbolic link") != std::string::npos);
  CHECK(ReadAll(other.path) == "the other project");
  std::filesystem::remove(file.path);
  REQUIRE(::mkfifo(file.path.c_str(), 0644) == 0);
  result = journal.Write(file.path, facet::MakeRecoveryDelta(doc, nullptr, &written));
  CHECK(result.error == "refusing to write " + file.path + ": it is a FIFO, not a regular file");
  std::filesystem::remove(file.path);
}

// Version 1 (one JSON object, rewritten whole after every edit) is still read: its document
// comes back exactly; another version is refused by name.
TEST_CASE("a version 1 recovery file is migrated; an unknown version is refused by name") {
  const Document doc = VariedDocument(31, 7, 2, 3);
  nlohmann::json v1 = Base(Text(doc));
  nlohmann::ordered_json legacy;
  legacy["format"] = "facet-recovery";
  legacy["version"] = 1;
  for (auto& [key, value] : v1.items()) legacy[key] = value;
  const RecoveryLoadResult loaded = RecoveryFromText(legacy.dump());
  REQUIRE_MESSAGE(loaded.ok(), loaded.error);
  CHECK(loaded.warnings.empty());
  CheckSameDocument(loaded.document, doc);
  legacy["version"] = 7;
  CHECK(ErrorOf(legacy.dump()) == "version: version 7 is not one this build reads (2, in records; 1, one JSON object)");
}
