// Editing an existing line pin (kEdgeOnImageLine) in the real application offscreen (`facet
// render` with an input script): its end handle is hovered, dragged with the mouse while the
// model re-solves live, and released as one undoable edit; Escape during the drag cancels it;
// a click on the line selects it and Delete removes it, undoably. Screenshots of the handles
// (hovered and mid-drag) are kept with FACET_KEEP_TEST_DIRS=1.
#include <doctest/doctest.h>

#include <cmath>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/io/project_io.h"
#include "core/mesh/mesh.h"
#include "tests/app/app_test_util.h"
#include "tests/synthetic_scene.h"

using namespace facet::testing;


// These cases check that points land exactly where the mouse went: the Snap option off
// (render --no-snap); tests/app/test_snapping.cpp covers snapping.
const bool kRenderWithoutSnapping = (RenderWithoutSnapping() = true);

namespace {

constexpr double kShiftPx = 3.0;              // the line pin's line, off the true edge (image px)
constexpr int kMoveScreenPx = 6;              // how far the end handle is dragged (screen px)
constexpr double kEndTolerancePx = 1e-9;      // stored end vs. the release pixel's image point
constexpr double kLinePinTolerancePx = 1e-6;  // the joint solve's hard-constraint residual
constexpr double kStartOffPx = 0.5;           // a start this far from the new line is not the answer

Eigen::Vector2d Round(const Eigen::Vector2d& p) { return {std::round(p.x()), std::round(p.y())}; }

// The image point of a whole screen pixel, as the panel computes it (ImGui floors the mouse).
Eigen::Vector2d ToImage(const View& view, const Eigen::Vector2d& screen) {
  return {(screen.x() - view.origin_x) / view.zoom, (screen.y() - view.origin_y) / view.zoom};
}

// The scene with a line pin of the top front x edge (corners 4 -> 5), made by the script,
// then `tool`; saved as before.facet. The pin's line runs from a to b, kShiftPx off the
// edge's projection (a line the model can meet exactly), or with `b_offset_screen_px` to
// b + that offset / zoom (a turned line it can only approach).
struct PinnedScene {
  LineScene f;
  Eigen::Vector2d a = Eigen::Vector2d::Zero(), b = Eigen::Vector2d::Zero();
  Eigen::Vector2d pinned_b = Eigen::Vector2d::Zero();  // the line pin's end b
  std::string setup;                                   // the script up to here
};

PinnedScene MakePinnedScene(const TempDir& dir, const std::string& tool,
                            const Eigen::Vector2d& b_offset_screen_px = Eigen::Vector2d::Zero()) {
  PinnedScene p;
  p.f = WriteLineScene(dir);
  const facet::PolyMesh& mesh = p.f.scene.project.FindPrimitive(p.f.scene.box_id)->mesh;
  const facet::HalfedgeId h = facet::FindHalfedge(mesh, 4, 5);
  REQUIRE(h != facet::kNoElement);
  ShiftedLine(p.f, kShiftPx, &p.a, &p.b);
  p.pinned_b = p.b + b_offset_screen_px / p.f.view.zoom;
  std::ostringstream s;
  s << "frames 2\ncommand select edge " << p.f.scene.box_id << " " << facet::PolyMesh::EdgeOf(h) << "\nframes 1\n"
    << "command line-pin 0 " << FormatXY(p.a) << " " << FormatXY(p.pinned_b) << "\nframes 2\ncommand tool " << tool
    << "\ncommand select none\nframes 2\ncommand save " << (dir / "before.facet") << "\nframes 1\n";
  p.setup = s.str();
  return p;
}

// Mouse steps from `from` to `to` (screen px, both whole pixels) in `steps` moves.
std::string Moves(const Eigen::Vector2d& from, const Eigen::Vector2d& to, int steps) {
  std::ostringstream s;
  for (int i = 1; i <= steps; ++i) s << "move " << FormatXY(Round(from + (to - from) * i / steps)) << "\nframes 1\n";
  return s.str();
}

// Pixels of the handles' colour (kLinePinColor 0, 255, 200) or the hot handle's white within
// `radius` of a screen point.
int CountNear(const cv::Mat& shot, const Eigen::Vector2d& p, int radius, const cv::Vec3b& bgr, int tolerance) {
  int count = 0;
  const int cx = static_cast<int>(std::floor(p.x())), cy = static_cast<int>(std::floor(p.y()));
  for (int y = cy - radius; y <= cy + radius; ++y) {
    for (int x = cx - radius; x <= cx + radius; ++x) {
      if (x < 0 || y < 0 || x >= shot.cols || y >= shot.rows) continue;
      const cv::Vec3b c = shot.at<cv::Vec3b>(y, x);
      count += std::abs(c[0] - bgr[0]) <= tolerance && std::abs(c[1] - bgr[1]) <= tolerance &&
               std::abs(c[2] - bgr[2]) <= tolerance;
    }
  }
  return count;
}

}  // namespace

TEST_CASE("line pin end handle: hovered, dragged with a live re-solve, one undoable edit") {
  for (const std::string tool : {"select", "line-pin"}) {
    CAPTURE(tool);
    TempDir dir("linepin_drag_" + tool);
    // The pin starts turned: its end b kMoveScreenPx screen px below where the model can
    // meet the line exactly. The drag brings it there: pressed on the handle (a whole screen
    // pixel, as ImGui floors the mouse), released kMoveScreenPx above; the handle keeps its
    // offset from the pointer, so the end lands on b.
    const Eigen::Vector2d offset(0.0, kMoveScreenPx);
    PinnedScene p = MakePinnedScene(dir, tool, offset);
    const View& view = p.f.view;
    const Eigen::Vector2d release = Round(view.ToScreen(p.b));
    const Eigen::Vector2d press = release + offset;
    REQUIRE((view.ToScreen(p.pinned_b) - press).norm() < 0.75);  // on the handle
    REQUIRE(view.Inside(press, 10.0));
    REQUIRE(view.Inside(release, 10.0));
    const Eigen::Vector2d expected_b = ToImage(view, release) + (p.pinned_b - ToImage(view, press));
    CHECK((expected_b - p.b).norm() < kEndTolerancePx);
    const Eigen::Vector2d mid_point = press - Eigen::Vector2d(0.0, kMoveScreenPx / 2);

    std::ostringstream s;
    s << p.setup << "move " << FormatXY(press) << "\nframes 2\nscreenshot " << (dir / "hover.png") << "\nframes 1\n";
    s << "down left\nframes 1\n" << Moves(press, mid_point, 1);
    s << "command save " << (dir / "mid.facet") << "\nscreenshot " << (dir / "during.png") << "\nframes 1\n";
    s << Moves(mid_point, release, 2) << "up left\nframes 3\n";
    s << "command save " << (dir / "after.facet") << "\nframes 1\ncommand undo\nframes 2\ncommand save "
      << (dir / "undone.facet") << "\nframes 1\ncommand redo\nframes 2\ncommand save " << (dir / "redone.facet")
      << "\nframes 1\nmove 5 5\nframes 1\n";
    const nlohmann::json report = RenderScript(dir, p.f.path, "drag", s.str());
    INFO("log: " << ReportLog(report));
    const facet::Project before = LoadProjectFile(dir / "before.facet");
    const facet::Project mid = LoadProjectFile(dir / "mid.facet");
    const facet::Project after = LoadProjectFile(dir / "after.facet");
    const facet::Project undone = LoadProjectFile(dir / "undone.facet");
    const facet::Project redone = LoadProjectFile(dir / "redone.facet");
    REQUIRE(before.constraints.size() == 1);
    const facet::Constraint& old_pin = before.constraints[0];
    CHECK((old_pin.line_b_px - p.pinned_b).norm() < kEndTolerancePx);

    // The stored line: end b at the release pixel's image point (plus where on the handle the
    // press was), end a untouched; the same constraint, not a new one.
    REQUIRE(after.constraints.size() == 1);
    const facet::Constraint& moved = after.constraints[0];
    CHECK(moved.id == old_pin.id);
    CHECK(moved.line_a_px == old_pin.line_a_px);
    const double end_error_px = (moved.line_b_px - expected_b).norm();
    CAPTURE(moved.line_b_px.transpose());
    CAPTURE(expected_b.transpose());
    CHECK(end_error_px < kEndTolerancePx);

    // The edge follows: the new line is not satisfied by the model as it was, and is after
    // the release's full solve.
    const double start_px = LinePinDistancePx(before, moved);
    const double after_px = LinePinDistancePx(after, moved);
    MESSAGE(tool << ": end moved " << (moved.line_b_px - old_pin.line_b_px).norm()
                 << " image px; edge from the new line " << after_px << " px after the solve (" << start_px
                 << " px before the drag)");
    CHECK(start_px > kStartOffPx);
    CHECK(after_px < kLinePinTolerancePx);

    // Live: mid-drag the stored end is between, and the previewed model already re-solved
    // towards that line.
    REQUIRE(mid.constraints.size() == 1);
    const facet::Constraint& mid_pin = mid.constraints[0];
    const double mid_before_px = LinePinDistancePx(before, mid_pin), mid_px = LinePinDistancePx(mid, mid_pin);
    MESSAGE(tool << ": mid-drag edge from the line " << mid_px << " px (" << mid_before_px << " px unsolved)");
    CHECK((mid_pin.line_b_px - old_pin.line_b_px).norm() > 0.25 * (moved.line_b_px - old_pin.line_b_px).norm());
    CHECK((mid_pin.line_b_px - moved.line_b_px).norm() > 0.25 * (moved.line_b_px - old_pin.line_b_px).norm());
    CHECK(mid_px < 0.5 * mid_before_px);

    // One history entry; undo restores the old line exactly and the model with it.
    const nlohmann::json& undo = report.at("undo_stack");
    REQUIRE(undo.size() >= 2);
    CHECK(undo.back().dump().find("Move line pin end") != std::string::npos);
    CHECK(undo[undo.size() - 2].dump().find("Move line pin end") == std::string::npos);
    REQUIRE(undone.constraints.size() == 1);
    CHECK(undone.constraints[0] == old_pin);
    CHECK(undone.primitives == before.primitives);
    REQUIRE(redone.constraints.size() == 1);
    CHECK(redone.constraints[0] == moved);

    // The handles: the hovered one drawn white at the press, the other in the line pins'
    // colour; mid-drag the dragged one still lit.
    const cv::Mat hover = cv::imread(dir / "hover.png");
    const cv::Mat during = cv::imread(dir / "during.png");
    REQUIRE(!hover.empty());
    REQUIRE(!during.empty());
    const cv::Vec3b white(255, 255, 255), teal(200, 255, 0);
    constexpr int kColorTolerance = 30;
    const int hot = CountNear(hover, press, 3, white, kColorTolerance);
    const int other = CountNear(hover, view.ToScreen(p.a), 2, teal, kColorTolerance);
    const Eigen::Vector2d mid_screen = view.ToScreen(mid_pin.line_b_px);
    const int dragged = CountNear(during, mid_screen, 3, white, kColorTolerance);
    CAPTURE(hot);
    CAPTURE(other);
    CAPTURE(dragged);
    CHECK(hot >= 10);
    CHECK(other >= 5);
    CHECK(dragged >= 10);
  }
}

TEST_CASE("line pin end handle: Escape during the drag cancels it, nothing recorded") {
  TempDir dir("linepin_escape");
  const PinnedScene p = MakePinnedScene(dir, "select");
  const View& view = p.f.view;
  const Eigen::Vector2d press = Round(view.ToScreen(p.a));
  const Eigen::Vector2d release = press + Eigen::Vector2d(0.0, 2 * kMoveScreenPx);
  std::ostringstream s;
  s << p.setup << "move " << FormatXY(press) << "\nframes 2\ndown left\nframes 1\n" << Moves(press, release, 4);
  s << "command save " << (dir / "mid.facet") << "\nframes 1\nkey escape\nframes 1\n"
    << Moves(release, release + Eigen::Vector2d(2 * kMoveScreenPx, 0.0), 2) << "up left\nframes 3\n";
  s << "command save " << (dir / "after.facet") << "\nframes 1\n";
  const nlohmann::json report = RenderScript(dir, p.f.path, "escape", s.str());
  INFO("log: " << ReportLog(report));
  const facet::Project before = LoadProjectFile(dir / "before.facet");
  const facet::Project mid = LoadProjectFile(dir / "mid.facet");
  const facet::Project after = LoadProjectFile(dir / "after.facet");
  // The drag was under way (the control), then nothing of it is left.
  REQUIRE(mid.constraints.size() == 1);
  REQUIRE(before.constraints.size() == 1);
  CHECK(mid.constraints[0].line_a_px != before.constraints[0].line_a_px);
  CHECK(after.constraints == before.constraints);
  CHECK(after.primitives == before.primitives);
  for (const auto& entry : report.at("undo_stack")) CHECK(entry.dump().find("Move line pin end") == std::string::npos);
}

TEST_CASE("line pin: a click on its line selects it, Delete removes it (not its edge), undo restores it") {
  TempDir dir("linepin_delete");
  const PinnedScene p = MakePinnedScene(dir, "select");
  const View& view = p.f.view;
  const Eigen::Vector2d on_line = Round(view.ToScreen(0.5 * (p.a + p.b)));
  std::ostringstream s;
  s << p.setup << "click left " << FormatXY(on_line) << "\nframes 2\nscreenshot " << (dir / "selected.png")
    << "\nframes 1\nkey delete\nframes 2\ncommand save " << (dir / "deleted.facet")
    << "\nframes 1\ncommand undo\nframes 2\ncommand save " << (dir / "restored.facet") << "\nframes 1\n";
  const nlohmann::json report = RenderScript(dir, p.f.path, "delete", s.str());
  INFO("log: " << ReportLog(report));
  const facet::Project before = LoadProjectFile(dir / "before.facet");
  const facet::Project deleted = LoadProjectFile(dir / "deleted.facet");
  const facet::Project restored = LoadProjectFile(dir / "restored.facet");
  REQUIRE(before.constraints.size() == 1);
  CHECK(deleted.constraints.empty());
  // The edge stays: the mesh has the same edges as before.
  REQUIRE(deleted.primitives.size() == 1);
  CHECK(deleted.primitives[0].mesh.NumEdges() == before.primitives[0].mesh.NumEdges());
  CHECK(restored.constraints == before.constraints);
  // The selected line is drawn with the selection's orange around it.
  const cv::Mat shot = cv::imread(dir / "selected.png");
  REQUIRE(!shot.empty());
  const int orange = CountNear(shot, on_line, 4, cv::Vec3b(30, 140, 255), 40);
  CAPTURE(orange);
  CHECK(orange >= 4);
}

TEST_CASE("line pin: the script command line-pin-move sets one end, as one undoable edit") {
  TempDir dir("linepin_move_command");
  const PinnedScene p = MakePinnedScene(dir, "select", Eigen::Vector2d(0.0, kMoveScreenPx));
  std::ostringstream s;
  s << p.setup << "command line-pin-move 0 0 b " << FormatXY(p.b) << "\nframes 3\ncommand save "
    << (dir / "after.facet") << "\nframes 1\ncommand undo\nframes 2\ncommand save " << (dir / "undone.facet")
    << "\nframes 1\n";
  const nlohmann::json report = RenderScript(dir, p.f.path, "command", s.str());
  INFO("log: " << ReportLog(report));
  const facet::Project before = LoadProjectFile(dir / "before.facet");
  const facet::Project after = LoadProjectFile(dir / "after.facet");
  const facet::Project undone = LoadProjectFile(dir / "undone.facet");
  REQUIRE(before.constraints.size() == 1);
  REQUIRE(after.constraints.size() == 1);
  const facet::Constraint& moved = after.constraints[0];
  CHECK(moved.id == before.constraints[0].id);
  CHECK(moved.line_a_px == before.constraints[0].line_a_px);
  // FormatXY prints enough digits for the end to arrive within the drag test's tolerance.
  CHECK((moved.line_b_px - p.b).norm() < kEndTolerancePx);
  CHECK(LinePinDistancePx(before, moved) > kStartOffPx);
  CHECK(LinePinDistancePx(after, moved) < kLinePinTolerancePx);
  REQUIRE(undone.constraints.size() == 1);
  CHECK(undone.constraints[0] == before.constraints[0]);
  CHECK(undone.primitives == before.primitives);
}
