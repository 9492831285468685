// The document's undo model: random edit sequences undo and redo exactly, identical commits
// record nothing, the dirty flag follows the saved state, drags are one history entry.
#include <doctest/doctest.h>

#include <algorithm>
#include <random>
#include <string>
#include <vector>

#include "core/mesh/extrude.h"
#include "core/mesh/operators.h"
#include "core/scene/document.h"
#include "core/scene/project.h"
#include "tests/random_edits.h"
#include "tests/synthetic_scene.h"

using facet::Axis;
using facet::Constraint;
using facet::ConstraintKind;
using facet::Document;
using facet::Edit;
using facet::Image;
using facet::Pin;
using facet::PolyMesh;
using facet::Primitive;
using facet::PrimitiveShape;
using facet::PrincipalPointMode;
using facet::Project;
using facet::Segment;
using facet::VertexId;
using facet::VertexRef;

using facet::testing::DropReferencesTo;
using facet::testing::LiveEdges;
using facet::testing::LiveFaces;
using facet::testing::LiveVertices;
using facet::testing::Pick;
using facet::testing::RandomEdit;
using facet::testing::RandomKOp;
using facet::testing::Real;

namespace {

// A starting project with some of everything, so the first edits have material to work on.
Project StartProject() { return facet::testing::MakeBoxScene().project; }

}  // namespace

TEST_CASE("random edit sequences: undo all returns the start, redo all returns the end") {
  // What the sequences exercised, so that a generator that stopped producing K-ops or
  // constraints would fail here rather than pass vacuously.
  int topology_edits = 0, constraint_edits = 0, primitive_insertions = 0;
  for (unsigned seed = 1; seed <= 40; ++seed) {
    CAPTURE(seed);
    std::mt19937 rng(seed);
    Document doc(StartProject());
    std::vector<Project> states = {doc.project()};
    for (int step = 0; step < 80; ++step) {
      const Project next = RandomEdit(doc.project(), rng);
      const bool changed = !(next == doc.project());
      CAPTURE(step);
      REQUIRE(doc.Commit("edit " + std::to_string(step), next) == changed);
      REQUIRE(doc.project() == next);
      if (!changed) continue;
      states.push_back(next);
      const Edit& edit = doc.undo_stack().back();
      for (const auto& c : edit.primitives) {
        if (c.before && c.after &&
            c.before->mesh.NumVertices() + c.before->mesh.NumFaces() !=
                c.after->mesh.NumVertices() + c.after->mesh.NumFaces())
          ++topology_edits;
        if (!c.before) ++primitive_insertions;
      }
      constraint_edits += static_cast<int>(edit.constraints.size());
    }
    REQUIRE(doc.undo_stack().size() + 1 == states.size());
    REQUIRE(states.size() > 30);
    for (size_t i = states.size() - 1; i > 0; --i) {
      REQUIRE(doc.Undo());
      CAPTURE(i);
      REQUIRE(doc.project() == states[i - 1]);
    }
    CHECK_FALSE(doc.CanUndo());
    CHECK_FALSE(doc.Undo());
    CHECK(doc.project() == states.front());
    for (size_t i = 1; i < states.size(); ++i) {
      REQUIRE(doc.Redo());
      CAPTURE(i);
      REQUIRE(doc.project() == states[i]);
    }
    CHECK_FALSE(doc.CanRedo());
    CHECK_FALSE(doc.Redo());
    CHECK(doc.project() == states.back());
  }
  MESSAGE(topology_edits << " K-op edits, " << constraint_edits << " constraint changes, " << primitive_insertions
                         << " primitives added");
  CHECK(topology_edits > 100);
  CHECK(constraint_edits > 100);
  CHECK(primitive_insertions > 100);
}

TEST_CASE("random commits, undos, redos and saves follow a model of the history") {
  // The model: the states along the current branch, the position in it, and the position of
  // the saved state (-1 once the branch holding it was discarded).
  for (unsigned seed = 100; seed < 130; ++seed) {
    CAPTURE(seed);
    std::mt19937 rng(seed);
    Document doc(StartProject());
    std::vector<Project> states = {doc.project()};
    size_t at = 0;
    long clean_at = 0;
    for (int step = 0; step < 200; ++step) {
      CAPTURE(step);
      const size_t action = Pick(rng, 20);
      if (action < 11) {
        const Project next = RandomEdit(doc.project(), rng);
        if (next == doc.project()) continue;
        REQUIRE(doc.Commit("edit", next));
        states.resize(at + 1);
        if (clean_at > static_cast<long>(at)) clean_at = -1;
        states.push_back(next);
        ++at;
      } else if (action < 15) {
        REQUIRE(doc.Undo() == (at > 0));
        if (at > 0) --at;
      } else if (action < 19) {
        REQUIRE(doc.Redo() == (at + 1 < states.size()));
        if (at + 1 < states.size()) ++at;
      } else {
        doc.MarkClean();
        clean_at = static_cast<long>(at);
      }
      REQUIRE(doc.project() == states[at]);
      REQUIRE(doc.CanUndo() == (at > 0));
      REQUIRE(doc.CanRedo() == (at + 1 < states.size()));
      REQUIRE(doc.undo_stack().size() == at);
      REQUIRE(doc.redo_stack().size() == states.size() - 1 - at);
      CAPTURE(clean_at);
      CAPTURE(at);
      REQUIRE(doc.dirty() == (clean_at != static_cast<long>(at)));
    }
  }
}

TEST_CASE("DiffProjects, ApplyEdit and RevertEdit are exact inverses") {
  for (unsigned seed = 1000; seed < 1100; ++seed) {
    CAPTURE(seed);
    std::mt19937 rng(seed);
    Project a = StartProject();
    for (int k = static_cast<int>(Pick(rng, 5)); k > 0; --k) a = RandomEdit(a, rng);
    Project b = a;
    for (int k = 1 + static_cast<int>(Pick(rng, 8)); k > 0; --k) b = RandomEdit(b, rng);
    const Edit edit = facet::DiffProjects("several edits", a, b);
    CHECK(edit.label == "several edits");
    CHECK(edit.Empty() == (a == b));
    Project p = a;
    facet::ApplyEdit(edit, &p);
    REQUIRE(p == b);
    facet::RevertEdit(edit, &p);
    REQUIRE(p == a);
    CHECK(facet::DiffProjects("none", a, a).Empty());
    CHECK(facet::DiffProjects("none", b, b).Empty());
  }
}

TEST_CASE("an edit records only what changed") {
  Project a = StartProject();
  Project b = a;
  b.primitives[0].name = "renamed";
  b.pins.erase(b.pins.begin() + 3);
  const Edit edit = facet::DiffProjects("two changes", a, b);
  CHECK(edit.images.empty());
  CHECK(edit.segments.empty());
  REQUIRE(edit.primitives.size() == 1);
  CHECK(edit.primitives[0].before->name == "box");
  CHECK(edit.primitives[0].after->name == "renamed");
  CHECK(edit.constraints.empty());
  REQUIRE(edit.pins.size() == 1);
  CHECK(edit.pins[0].id == a.pins[3].id);
  CHECK(edit.pins[0].before_index == 3);
  CHECK_FALSE(edit.pins[0].after.has_value());
  CHECK_FALSE(edit.units_after.has_value());
  CHECK(edit.next_id_after == facet::kNoId);
}

TEST_CASE("committing an identical project records nothing") {
  Document doc(StartProject());
  const Project same = doc.project();
  CHECK_FALSE(doc.Commit("nothing", same));
  CHECK_FALSE(doc.CanUndo());
  CHECK_FALSE(doc.dirty());

  Project changed = same;
  changed.primitives[0].shape.params.x() += 1.0;
  facet::RefreshPrimitive(&changed, &changed.primitives[0]);
  REQUIRE(doc.Commit("resize", changed));
  REQUIRE(doc.Undo());
  CHECK(doc.CanRedo());
  // A no-op commit neither records an entry nor discards the redo stack.
  CHECK_FALSE(doc.Commit("nothing", doc.project()));
  CHECK(doc.CanRedo());
  CHECK_FALSE(doc.CanUndo());
  CHECK(doc.undo_stack().empty());
}

TEST_CASE("dirty flag: commit, undo, redo, MarkClean and an unreachable saved state") {
  Document doc(StartProject());
  CHECK_FALSE(doc.dirty());
  Project p = doc.project();
  p.primitives[0].name = "a";
  REQUIRE(doc.Commit("rename a", p));
  CHECK(doc.dirty());
  REQUIRE(doc.Undo());
  CHECK_FALSE(doc.dirty());  // back at the state that was opened
  REQUIRE(doc.Redo());
  CHECK(doc.dirty());
  doc.MarkClean();  // saved with name "a"
  CHECK_FALSE(doc.dirty());
  p.primitives[0].name = "b";
  REQUIRE(doc.Commit("rename b", p));
  CHECK(doc.dirty());
  REQUIRE(doc.Undo());
  CHECK_FALSE(doc.dirty());  // "a" again
  REQUIRE(doc.Undo());
  CHECK(doc.dirty());  // before the save
  REQUIRE(doc.Redo());
  CHECK_FALSE(doc.dirty());

  // Undo past the save, then branch: the saved state can no longer be reached.
  REQUIRE(doc.Undo());
  Project other = doc.project();
  other.units = "ft";
  REQUIRE(doc.Commit("units", other));
  CHECK(doc.dirty());
  CHECK_FALSE(doc.CanRedo());
  REQUIRE(doc.Undo());
  CHECK(doc.dirty());  // this is the opened state, not the saved one
  REQUIRE(doc.Redo());
  CHECK(doc.dirty());  // same depth as the saved state, yet a different project
  CHECK(doc.undo_stack().size() == 1);
  doc.MarkClean();
  CHECK_FALSE(doc.dirty());

  doc.Reset(StartProject());
  CHECK_FALSE(doc.dirty());
  CHECK_FALSE(doc.CanUndo());
  CHECK_FALSE(doc.CanRedo());
}

TEST_CASE("a drag previews changes and becomes one history entry") {
  Document doc(StartProject());
  const Project snapshot = doc.project();
  const Eigen::Vector3d start = snapshot.primitives[0].shape.translation;
  for (int frame = 1; frame <= 30; ++frame) {
    Project* preview = doc.MutableProjectForPreview();
    preview->primitives[0].shape.translation = start + Eigen::Vector3d(0.1 * frame, 0.0, 0.0);
    facet::RefreshPrimitive(preview, &preview->primitives[0]);
    CHECK(doc.undo_stack().empty());  // previews are not history
  }
  const Project dragged = doc.project();
  const double moved = (dragged.primitives[0].shape.translation - start).norm();
  CHECK(std::abs(moved - 3.0) < 1e-12);
  REQUIRE(doc.CommitFrom("Move box", snapshot));
  REQUIRE(doc.undo_stack().size() == 1);
  CHECK(doc.undo_stack().back().label == "Move box");
  CHECK(doc.project() == dragged);
  CHECK(doc.dirty());
  REQUIRE(doc.Undo());
  CHECK(doc.project() == snapshot);
  REQUIRE(doc.Redo());
  CHECK(doc.project() == dragged);

  // A drag that ends where it started records nothing.
  const Project before_second = doc.project();
  doc.MutableProjectForPreview()->pins[0].uv_px.x() += 5.0;
  doc.MutableProjectForPreview()->pins[0].uv_px.x() -= 5.0;
  CHECK_FALSE(doc.CommitFrom("Move pin", before_second));
  CHECK(doc.undo_stack().size() == 1);

  // A drag after an undo discards the redo stack, like any commit.
  REQUIRE(doc.Undo());
  const Project before_third = doc.project();
  doc.MutableProjectForPreview()->pins[1].uv_px.y() += 7.0;
  REQUIRE(doc.CommitFrom("Move pin", before_third));
  CHECK_FALSE(doc.CanRedo());
  REQUIRE(doc.Undo());
  CHECK(doc.project() == snapshot);
}

TEST_CASE("CancelPreview restores the snapshot and leaves history alone") {
  Document doc(StartProject());
  Project p = doc.project();
  p.primitives[0].name = "x";
  REQUIRE(doc.Commit("rename", p));
  REQUIRE(doc.Undo());
  const Project snapshot = doc.project();
  doc.MutableProjectForPreview()->primitives[0].shape.params *= 2.0;
  facet::RefreshPrimitive(doc.MutableProjectForPreview(), &doc.MutableProjectForPreview()->primitives[0]);
  doc.MutableProjectForPreview()->segments.pop_back();
  REQUIRE_FALSE(doc.project() == snapshot);
  doc.CancelPreview(snapshot);
  CHECK(doc.project() == snapshot);
  CHECK(doc.undo_stack().empty());
  REQUIRE(doc.redo_stack().size() == 1);  // still redoable: the project is back where it was
  CHECK_FALSE(doc.dirty());
  REQUIRE(doc.Redo());
  CHECK(doc.project() == p);
}

TEST_CASE("reordering a list, with or without other changes, applies and reverts exactly") {
  for (unsigned seed = 2000; seed < 2100; ++seed) {
    CAPTURE(seed);
    std::mt19937 rng(seed);
    Project a = StartProject();
    for (int k = 2 + static_cast<int>(Pick(rng, 5)); k > 0; --k) a = RandomEdit(a, rng);
    Project b = a;
    std::shuffle(b.segments.begin(), b.segments.end(), rng);
    std::shuffle(b.pins.begin(), b.pins.end(), rng);
    if (seed % 2 == 0) b = RandomEdit(b, rng);
    Project p = a;
    const Edit edit = facet::DiffProjects("reorder", a, b);
    facet::ApplyEdit(edit, &p);
    REQUIRE(p == b);
    facet::RevertEdit(edit, &p);
    REQUIRE(p == a);

    Document doc(a);
    const bool recorded = doc.Commit("reorder", b);
    CHECK(recorded == !(a == b));
    CHECK(doc.project() == b);
    if (recorded) {
      REQUIRE(doc.Undo());
      CHECK(doc.project() == a);
    }
  }
}

TEST_CASE("a K-op on a primitive's mesh with a pin on the new vertex is one entry, undone exactly") {
  Document doc(StartProject());
  const Project before = doc.project();
  Project after = before;
  Primitive& box = after.primitives[0];
  // E_split on the box's top front edge (corners 4 -> 5, whichever way
  // the edge's half-edge 2e runs, t = 0.5 is its midpoint), on a copy committed whole.
  const facet::HalfedgeId h = facet::FindHalfedge(box.mesh, 4, 5);
  REQUIRE(h != facet::kNoElement);
  const facet::ESplitResult split = facet::ESplit(&box.mesh, facet::PolyMesh::EdgeOf(h), 0.5);
  REQUIRE_MESSAGE(split.ok, split.message);
  Pin pin;
  pin.id = after.NewId();
  pin.image_id = after.images[0].id;
  pin.vertex = {box.id, split.vertex};
  pin.uv_px = {321.0, 123.0};
  after.pins.push_back(pin);
  Constraint c;
  c.id = after.NewId();
  c.kind = ConstraintKind::kCollinear;
  c.vertices = {{box.id, 4}, {box.id, split.vertex}, {box.id, 5}};
  after.constraints.push_back(c);
  REQUIRE(doc.Commit("Split edge and pin", after));
  REQUIRE(doc.undo_stack().size() == 1);
  const Edit& edit = doc.undo_stack().back();
  CHECK(edit.primitives.size() == 1);
  CHECK(edit.pins.size() == 1);
  CHECK(edit.constraints.size() == 1);
  CHECK(edit.images.empty());
  CHECK(edit.segments.empty());
  CHECK(doc.project().FindVertex(pin.vertex) != nullptr);
  REQUIRE(doc.Undo());
  CHECK(doc.project() == before);
  CHECK(doc.project().FindVertex(pin.vertex) == nullptr);
  REQUIRE(doc.Redo());
  CHECK(doc.project() == after);
  const facet::MeshVertex* v = doc.project().FindVertex(pin.vertex);
  REQUIRE(v != nullptr);
  const Eigen::Vector3d expected =
      0.5 * (facet::VertexInWorld(after, {box.id, 4}) + facet::VertexInWorld(after, {box.id, 5}));
  CHECK((v->position - expected).norm() < 1e-12 * expected.norm());
}

TEST_CASE("RewriteImagePaths reaches the project and every image in history; undo and redo keep the new paths") {
  Project start;
  Image first;
  first.id = start.NewId();
  first.path = "photos/a.jpg";
  start.images.push_back(first);
  Document document(start);
  Project with_second = document.project();
  Image second;
  second.id = with_second.NewId();
  second.path = "photos/b.jpg";
  with_second.images.push_back(second);
  REQUIRE(document.Commit("Add photo b.jpg", with_second));
  Project moved_first = document.project();
  moved_first.images[0].camera.focal_px = 1234.0;
  REQUIRE(document.Commit("Focal", moved_first));
  REQUIRE(document.Undo());  // one edit on each stack
  document.MarkClean();

  document.RewriteImagePaths([](const std::string& path) { return "../" + path; });
  CHECK(document.project().images[0].path == "../photos/a.jpg");
  CHECK(document.project().images[1].path == "../photos/b.jpg");
  CHECK_FALSE(document.dirty());
  REQUIRE(document.Redo());
  CHECK(document.project().images[0].path == "../photos/a.jpg");
  CHECK(document.project().images[0].camera.focal_px == 1234.0);
  REQUIRE(document.Undo());
  REQUIRE(document.Undo());
  REQUIRE(document.project().images.size() == 1);
  CHECK(document.project().images[0].path == "../photos/a.jpg");
  REQUIRE(document.Redo());
  CHECK(document.project().images[1].path == "../photos/b.jpg");
}
