// The document's undo model: random edit sequences undo and redo exactly, identical commits
// record nothing, the dirty flag follows the saved state, drags are one history entry.
#include <doctest/doctest.h>

#include <algorithm>
#include <random>
#include <string>
#include <vector>

#include "core/document.h"
#include "core/project.h"
#include "tests/synthetic_scene.h"

using facet::Axis;
using facet::Box;
using facet::Document;
using facet::Edit;
using facet::Image;
using facet::Pin;
using facet::PrincipalPointMode;
using facet::Project;
using facet::Segment;

namespace {

double Real(std::mt19937& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}
size_t Pick(std::mt19937& rng, size_t n) {  // in [0, n)
  return std::uniform_int_distribution<size_t>(0, n - 1)(rng);
}

template <typename T>
void InsertAtRandom(std::vector<T>* list, const T& item, std::mt19937& rng) {
  list->insert(list->begin() + static_cast<std::ptrdiff_t>(Pick(rng, list->size() + 1)), item);
}

// One random user edit: 1 to 3 insertions, modifications or removals at random positions in
// any of the four lists (removing an image or a box also removes what refers to it), or a
// change of units, or an id drawn and left unused.
Project RandomEdit(const Project& start, std::mt19937& rng) {
  Project p = start;
  const int ops = 1 + static_cast<int>(Pick(rng, 3));
  for (int op = 0; op < ops; ++op) {
    switch (Pick(rng, 14)) {
      case 0: {
        Image im;
        im.id = p.NewId();
        im.path = "img" + std::to_string(im.id) + ".jpg";
        im.width_px = 100 + static_cast<int>(Pick(rng, 4000));
        im.height_px = 100 + static_cast<int>(Pick(rng, 3000));
        im.camera.focal_px = Real(rng, 100, 5000);
        InsertAtRandom(&p.images, im, rng);
        break;
      }
      case 1: {
        if (p.images.empty()) break;
        Segment s;
        s.id = p.NewId();
        s.image_id = p.images[Pick(rng, p.images.size())].id;
        s.axis = static_cast<Axis>(Pick(rng, 3));
        s.a_px = {Real(rng, 0, 1000), Real(rng, 0, 1000)};
        s.b_px = {Real(rng, 0, 1000), Real(rng, 0, 1000)};
        InsertAtRandom(&p.segments, s, rng);
        break;
      }
      case 2: {
        Box b;
        b.id = p.NewId();
        b.name = "box" + std::to_string(b.id);
        b.size = {Real(rng, 0.1, 10), Real(rng, 0.1, 10), Real(rng, 0.1, 10)};
        InsertAtRandom(&p.boxes, b, rng);
        break;
      }
      case 3: {
        if (p.images.empty() || p.boxes.empty()) break;
        Pin pin;
        pin.id = p.NewId();
        pin.image_id = p.images[Pick(rng, p.images.size())].id;
        pin.box_id = p.boxes[Pick(rng, p.boxes.size())].id;
        pin.corner = static_cast<int>(Pick(rng, 8));
        pin.uv_px = {Real(rng, 0, 1000), Real(rng, 0, 1000)};
        InsertAtRandom(&p.pins, pin, rng);
        break;
      }
      case 4: {
        if (p.images.empty()) break;
        Image& im = p.images[Pick(rng, p.images.size())];
        im.camera.focal_px = Real(rng, 100, 5000);
        im.camera.principal_point_px.x() = Real(rng, 0, 100);
        im.camera_calibrated = !im.camera_calibrated;
        im.principal_point_mode = static_cast<PrincipalPointMode>(Pick(rng, 3));
        break;
      }
      case 5: {
        if (p.segments.empty()) break;
        Segment& s = p.segments[Pick(rng, p.segments.size())];
        s.a_px.y() = Real(rng, 0, 1000);
        s.axis = static_cast<Axis>(Pick(rng, 3));
        break;
      }
      case 6: {
        if (p.boxes.empty()) break;
        Box& b = p.boxes[Pick(rng, p.boxes.size())];
        b.translation = {Real(rng, -5, 5), Real(rng, -5, 5), Real(rng, -5, 5)};
        b.size_locked[Pick(rng, 3)] ^= true;
        b.rotation_locked = !b.rotation_locked;
        break;
      }
      case 7: {
        if (p.pins.empty()) break;
        Pin& pin = p.pins[Pick(rng, p.pins.size())];
        pin.uv_px.x() = Real(rng, 0, 1000);
        pin.corner = static_cast<int>(Pick(rng, 8));
        break;
      }
      case 8: {
        if (p.images.empty()) break;
        const size_t i = Pick(rng, p.images.size());
        const facet::Id id = p.images[i].id;
        p.images.erase(p.images.begin() + static_cast<std::ptrdiff_t>(i));
        std::erase_if(p.segments, [id](const Segment& s) { return s.image_id == id; });
        std::erase_if(p.pins, [id](const Pin& pin) { return pin.image_id == id; });
        break;
      }
      case 9: {
        if (p.segments.empty()) break;
        p.segments.erase(p.segments.begin() + static_cast<std::ptrdiff_t>(Pick(rng, p.segments.size())));
        break;
      }
      case 10: {
        if (p.boxes.empty()) break;
        const size_t i = Pick(rng, p.boxes.size());
        const facet::Id id = p.boxes[i].id;
        p.boxes.erase(p.boxes.begin() + static_cast<std::ptrdiff_t>(i));
        std::erase_if(p.pins, [id](const Pin& pin) { return pin.box_id == id; });
        break;
      }
      case 11: {
        if (p.pins.empty()) break;
        p.pins.erase(p.pins.begin() + static_cast<std::ptrdiff_t>(Pick(rng, p.pins.size())));
        break;
      }
      case 12: p.units = p.units == "m" ? "ft" : "m"; break;
      case 13: p.NewId(); break;
    }
  }
  return p;
}

// A starting project with some of everything, so the first edits have material to work on.
Project StartProject() { return facet::testing::MakeBoxScene().project; }

}  // namespace

TEST_CASE("random edit sequences: undo all returns the start, redo all returns the end") {
  for (unsigned seed = 1; seed <= 40; ++seed) {
    CAPTURE(seed);
    std::mt19937 rng(seed);
    Document doc(StartProject());
    std::vector<Project> states = {doc.project()};
    for (int step = 0; step < 60; ++step) {
      const Project next = RandomEdit(doc.project(), rng);
      const bool changed = !(next == doc.project());
      CAPTURE(step);
      REQUIRE(doc.Commit("edit " + std::to_string(step), next) == changed);
      REQUIRE(doc.project() == next);
      if (changed) states.push_back(next);
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
  b.boxes[0].name = "renamed";
  b.pins.erase(b.pins.begin() + 3);
  const Edit edit = facet::DiffProjects("two changes", a, b);
  CHECK(edit.images.empty());
  CHECK(edit.segments.empty());
  REQUIRE(edit.boxes.size() == 1);
  CHECK(edit.boxes[0].before->name == "box");
  CHECK(edit.boxes[0].after->name == "renamed");
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
  changed.boxes[0].size.x() += 1.0;
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
  p.boxes[0].name = "a";
  REQUIRE(doc.Commit("rename a", p));
  CHECK(doc.dirty());
  REQUIRE(doc.Undo());
  CHECK_FALSE(doc.dirty());  // back at the state that was opened
  REQUIRE(doc.Redo());
  CHECK(doc.dirty());
  doc.MarkClean();  // saved with name "a"
  CHECK_FALSE(doc.dirty());
  p.boxes[0].name = "b";
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
  const Eigen::Vector3d start = snapshot.boxes[0].translation;
  for (int frame = 1; frame <= 30; ++frame) {
    doc.MutableProjectForPreview()->boxes[0].translation = start + Eigen::Vector3d(0.1 * frame, 0.0, 0.0);
    CHECK(doc.undo_stack().empty());  // previews are not history
  }
  const Project dragged = doc.project();
  const double moved = (dragged.boxes[0].translation - start).norm();
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
  p.boxes[0].name = "x";
  REQUIRE(doc.Commit("rename", p));
  REQUIRE(doc.Undo());
  const Project snapshot = doc.project();
  doc.MutableProjectForPreview()->boxes[0].size *= 2.0;
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
