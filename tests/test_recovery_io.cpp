// The recovery file (core/io/recovery_io.h): a document with a varied history round-trips
// exactly (project, every undo and redo edit's label and changes, the dirty flag), and
// malformed or inconsistent files are errors that name what is wrong, never crashes.
#include <doctest/doctest.h>

#include <random>
#include <string>

#include <nlohmann/json.hpp>

#include "core/io/project_io.h"
#include "core/io/recovery_io.h"
#include "core/scene/document.h"
#include "tests/random_edits.h"
#include "tests/synthetic_scene.h"

using facet::Document;
using facet::Edit;
using facet::Project;
using facet::RecoveryFromJson;
using facet::RecoveryLoadResult;
using facet::RecoveryToJson;

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
  const RecoveryLoadResult loaded = RecoveryFromJson(text);
  CHECK_FALSE(loaded.ok());
  MESSAGE(loaded.error);
  return loaded.error;
}

std::string Text(const Document& doc) {
  std::string error;
  const std::string text = RecoveryToJson(doc, &error);
  REQUIRE_MESSAGE(error.empty(), error);
  return text;
}

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
    const RecoveryLoadResult loaded = RecoveryFromJson(Text(original));
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
  RecoveryLoadResult loaded = RecoveryFromJson(Text(doc));
  REQUIRE_MESSAGE(loaded.ok(), loaded.error);
  CheckSameDocument(loaded.document, doc);
  CHECK(loaded.document.dirty());

  const Document empty(facet::testing::MakeBoxScene().project);
  loaded = RecoveryFromJson(Text(empty));
  REQUIRE_MESSAGE(loaded.ok(), loaded.error);
  CheckSameDocument(loaded.document, empty);
}

// A recovery file left by the Facet before an update (its project in an older format) still
// gives the work back: the project is migrated like a project file; its edits, written in the
// old layout, cannot be replayed, so the history is dropped and the warning says so.
TEST_CASE("a recovery file from an older Facet restores the project without its history") {
  Document doc = VariedDocument(21, 4, 1, 0);
  doc.MarkClean();  // the restored work is unsaved whatever the file said
  nlohmann::json j = nlohmann::json::parse(Text(doc));
  // The project as version 2 wrote it: no texture choices, no references.
  j["project"]["version"] = 2;
  j["project"].erase("references");
  for (auto& image : j["project"]["images"]) image.erase("use_for_texture");
  for (auto& primitive : j["project"]["primitives"]) primitive.erase("face_textures");
  const RecoveryLoadResult loaded = RecoveryFromJson(j.dump());
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
  for (const std::string& w : loaded.warnings) warned = warned || w.find("its undo history is not") != std::string::npos;
  CHECK(warned);
  // A newer project version is refused by name.
  j["project"]["version"] = Project::kFormatVersion + 1;
  CHECK(ErrorOf(j.dump()).find("project.version:") == 0);
}

TEST_CASE("malformed recovery files are errors naming the place, never crashes") {
  const Document doc = VariedDocument(5, 6, 2, 1);
  const std::string good = Text(doc);
  CHECK(RecoveryFromJson(good).ok());

  CHECK(ErrorOf("") == "line 1, column 1: the file is empty");
  CHECK(ErrorOf(good.substr(0, good.size() / 2)).find("line 1, column") == 0);
  CHECK(ErrorOf("[]").find("expected a JSON object") != std::string::npos);
  CHECK(ErrorOf(facet::ProjectToJson(doc.project())).find("format:") == 0);

  using nlohmann::json;
  auto mutated = [&](auto change) {
    json j = json::parse(good);
    change(j);
    return ErrorOf(j.dump());
  };
  CHECK(mutated([](json& j) { j["version"] = 2; }).find("version:") == 0);
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
  REQUIRE(RecoveryFromJson(good).ok());
  using nlohmann::json;
  auto mutated = [&](auto change) {
    json j = json::parse(good);
    change(j);
    return ErrorOf(j.dump());
  };

  // The last undo edit's "after" is not the current project.
  std::string error = mutated([](json& j) { j["undo"][1]["images"][0]["after"]["camera"]["focal_px"] = 801.0; });
  CHECK(error.find("history: undo[1]: does not revert onto the project after it: images: id") == 0);
  // The current project is not where the history leads.
  error = mutated([](json& j) { j["project"]["images"][0]["camera"]["focal_px"] = 850.0; });
  CHECK(error.find("history: undo[1]: does not revert") == 0);
  // A redo edit that starts from another project.
  error = mutated([](json& j) { j["redo"][0]["images"][0]["before"]["camera"]["focal_px"] = 1.0; });
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
  const RecoveryLoadResult loaded = RecoveryFromJson(Text(doc));
  REQUIRE_MESSAGE(loaded.ok(), loaded.error);
  CheckSameDocument(loaded.document, doc);
  Document rebuilt = loaded.document;
  REQUIRE(rebuilt.Redo());
  CHECK(rebuilt.project() == removed);
  REQUIRE(rebuilt.Undo());
  REQUIRE(rebuilt.Undo());
  CHECK(rebuilt.project().references.empty());
}
