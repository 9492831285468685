// The image panel as a user drives it, through `facet render` scripts (offscreen, no
// display): zoom about the cursor and fit, pixel-exact display at high zoom with small
// texture tiles (seams), drawing a line with a line tool, Escape during a drag, Delete, and
// the pin tool. Positions on screen come from the render report's image-to-screen transform.
#include <doctest/doctest.h>

#include <array>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/io/project_io.h"
#include "core/mesh/box.h"
#include "tests/app/app_test_util.h"
#include "tests/synthetic_scene.h"

namespace fs = std::filesystem;
using facet::testing::FormatXY;
using facet::testing::TempDir;
using facet::testing::WriteText;
using facet::testing::MakeBoxScene;
using facet::testing::SyntheticScene;

namespace {

// A colour per pixel from a hash, so that any offset of one pixel shows.
cv::Vec3b PixelColor(int x, int y) {
  std::uint32_t h = static_cast<std::uint32_t>(x) * 73856093u ^ static_cast<std::uint32_t>(y) * 19349663u;
  h ^= h >> 13;
  h *= 0x5bd1e995u;
  h ^= h >> 15;
  return cv::Vec3b(h & 0xff, (h >> 8) & 0xff, (h >> 16) & 0xff);
}

struct Fixture {
  SyntheticScene scene;
  std::string project_path;
  std::string photo_path;
};

// Photo of per-pixel colours and the synthetic project (segments, box, pins as asked).
Fixture WriteFixture(const TempDir& dir, bool with_segments, bool with_pins) {
  Fixture f;
  f.scene = MakeBoxScene();
  facet::Project& p = f.scene.project;
  if (!with_segments) p.segments.clear();
  if (!with_pins) p.pins.clear();
  cv::Mat photo(f.scene.true_camera.height_px, f.scene.true_camera.width_px, CV_8UC3);
  for (int y = 0; y < photo.rows; ++y) {
    for (int x = 0; x < photo.cols; ++x) photo.at<cv::Vec3b>(y, x) = PixelColor(x, y);
  }
  f.photo_path = dir / "synthetic.png";
  REQUIRE(cv::imwrite(f.photo_path, photo));
  f.project_path = dir / "scene.facet";
  REQUIRE(facet::SaveProject(p, f.project_path) == "");
  return f;
}

struct RunResult {
  int exit_code = -1;
  std::string stderr_text;
};
// These cases place points exactly where the mouse goes: the Snap option off (render --no-snap);
// tests/app/test_snapping.cpp covers snapping.

RunResult RunRenderNoSnap(const TempDir& dir, const std::string& args, const std::string& env = "") {
  const std::string err = dir / "stderr.txt";
  const std::string cmd = "env -u DISPLAY -u WAYLAND_DISPLAY XDG_CONFIG_HOME='" + (dir / "config") + "' " + env + " '" +
                          std::string(FACET_APP_EXE) + "' render --no-snap " + args + " 2> '" + err + "'";
  const int status = std::system(cmd.c_str());
  RunResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream in(err);
  std::ostringstream ss;
  ss << in.rdbuf();
  r.stderr_text = ss.str();
  return r;
}

nlohmann::json ReadJson(const std::string& path) {
  std::ifstream in(path);
  REQUIRE_MESSAGE(in.good(), "missing report " << path);
  return nlohmann::json::parse(in);
}

struct View {
  double origin_x = 0, origin_y = 0, zoom = 1;
  double rect_x = 0, rect_y = 0, rect_w = 0, rect_h = 0;
  Eigen::Vector2d ToScreen(const Eigen::Vector2d& uv) const {
    return {origin_x + zoom * uv.x(), origin_y + zoom * uv.y()};
  }
  Eigen::Vector2d ToImage(const Eigen::Vector2d& s) const {
    return {(s.x() - origin_x) / zoom, (s.y() - origin_y) / zoom};
  }
  bool Inside(const Eigen::Vector2d& s, double margin) const {
    return s.x() >= rect_x + margin && s.y() >= rect_y + margin && s.x() < rect_x + rect_w - margin &&
           s.y() < rect_y + rect_h - margin;
  }
};

View ViewFromReport(const nlohmann::json& report) {
  const auto& v = report.at("image_view");
  const auto& r = v.at("rect");
  return {v.at("origin_x").get<double>(), v.at("origin_y").get<double>(), v.at("zoom").get<double>(),
          r.at("x").get<double>(),        r.at("y").get<double>(),        r.at("w").get<double>(),
          r.at("h").get<double>()};
}

facet::Project ProjectFromReport(const nlohmann::json& report) {
  facet::ProjectLoadResult loaded = facet::ProjectFromJson(report.at("project").dump());
  REQUIRE_MESSAGE(loaded.ok(), loaded.error);
  return loaded.project;
}

// Renders `script` (may be empty) and returns the report.
nlohmann::json Render(const TempDir& dir, const Fixture& f, const std::string& name, const std::string& script,
                      const std::string& env = "") {
  std::string args =
      "'" + f.project_path + "' -o '" + (dir / (name + ".png")) + "' --report '" + (dir / (name + ".json")) + "'";
  if (!script.empty()) {
    WriteText(dir / (name + ".txt"), script);
    args += " --script '" + (dir / (name + ".txt")) + "'";
  }
  const RunResult run = RunRenderNoSnap(dir, args, env);
  INFO("stderr: " << run.stderr_text);
  REQUIRE(run.exit_code == 0);
  return ReadJson(dir / (name + ".json"));
}

// ImGui floors mouse positions to whole screen pixels: scripts use whole pixels.
Eigen::Vector2d Whole(const Eigen::Vector2d& s) { return {std::floor(s.x()), std::floor(s.y())}; }

// The screen point of the view's centre.
Eigen::Vector2d ViewCenter(const View& v) { return {v.rect_x + 0.5 * v.rect_w, v.rect_y + 0.5 * v.rect_h}; }

}  // namespace

TEST_CASE("image panel: the wheel zooms about the cursor and F fits the image again") {
  TempDir dir("zoom");
  const Fixture f = WriteFixture(dir, false, false);
  const View fitted = ViewFromReport(Render(dir, f, "fit", ""));
  // Fitted: the whole image inside the view, touching it on one axis (8 px margin).
  const facet::Camera& cam = f.scene.true_camera;
  const Eigen::Vector2d top_left = fitted.ToScreen({-0.5, -0.5});
  const Eigen::Vector2d bottom_right = fitted.ToScreen({cam.width_px - 0.5, cam.height_px - 0.5});
  CAPTURE(top_left.transpose());
  CAPTURE(bottom_right.transpose());
  CHECK(fitted.Inside(top_left, 7.0));
  CHECK(fitted.Inside(bottom_right - Eigen::Vector2d(1, 1), 7.0));
  constexpr double kFitMarginTolerancePx = 0.6;
  const double slack_x = fitted.rect_w - (bottom_right.x() - top_left.x());
  const double slack_y = fitted.rect_h - (bottom_right.y() - top_left.y());
  CHECK(std::min(slack_x, slack_y) == doctest::Approx(16.0).epsilon(kFitMarginTolerancePx / 16.0));

  // Zoom in at a point off the centre: that image point stays under the cursor.
  const Eigen::Vector2d cursor = Whole(fitted.ToScreen({300.25, 200.75}));
  REQUIRE(fitted.Inside(cursor, 10.0));
  const View zoomed =
      ViewFromReport(Render(dir, f, "zoomed", "frames 2\nwheel 3 " + FormatXY(cursor, 10) + "\nframes 2\n"));
  CHECK(zoomed.zoom > fitted.zoom * 1.5);
  const Eigen::Vector2d before = fitted.ToImage(cursor), after = zoomed.ToImage(cursor);
  constexpr double kAnchorToleranceScreenPx = 0.05;  // float rounding of origin and zoom
  CAPTURE(before.transpose());
  CAPTURE(after.transpose());
  CHECK((after - before).norm() * zoomed.zoom < kAnchorToleranceScreenPx);
  // The check can fail: a zoom about the view's centre would move this point.
  CHECK((zoomed.ToScreen(before) - cursor).norm() < kAnchorToleranceScreenPx);
  CHECK((ViewCenter(fitted) - cursor).norm() > 20.0);

  // F (with the mouse over the view) restores the fitted transform.
  const View refit = ViewFromReport(Render(dir, f, "refit",
                                           "frames 2\nwheel 3 " + FormatXY(cursor, 10) + "\nframes 2\nmove " +
                                               FormatXY(cursor, 10) + "\nkey f\nframes 2\n"));
  CHECK(refit.zoom == doctest::Approx(fitted.zoom).epsilon(1e-6));
  CHECK(std::abs(refit.origin_x - fitted.origin_x) < 0.01);
  CHECK(std::abs(refit.origin_y - fitted.origin_y) < 0.01);
}

TEST_CASE("image panel: zoomed in past 1:1 every screen pixel shows its photo pixel, across small tiles") {
  TempDir dir("tiles");
  const Fixture f = WriteFixture(dir, false, false);
  const View fitted = ViewFromReport(Render(dir, f, "fit", ""));
  // Zoom in around a point where four 64 px tiles meet (tile seams at multiples of 62 drawn
  // pixels: 64 minus one padding pixel on each side).
  const Eigen::Vector2d seam_uv(62.0 * 4 - 0.5, 62.0 * 3 - 0.5);
  const Eigen::Vector2d cursor = fitted.ToScreen(seam_uv);
  REQUIRE(fitted.Inside(cursor, 10.0));
  const nlohmann::json report =
      Render(dir, f, "zoomed", "frames 2\nwheel 12 " + FormatXY(cursor, 10) + "\nframes 3\n", "FACET_IMAGE_TILE_PX=64");
  const View view = ViewFromReport(report);
  REQUIRE(view.zoom > 2.0);
  const cv::Mat shot = cv::imread(dir / "zoomed.png", cv::IMREAD_COLOR);
  REQUIRE(!shot.empty());

  // Nearest filtering: the screen pixel centre (x + 0.5, y + 0.5) shows photo pixel
  // round((s - origin) / zoom). Pixels within 0.02 image px of a pixel border are skipped
  // (rasteriser rounding), and the overlays cover none of this photo-only project.
  int total = 0, matched = 0, seam_total = 0, seam_matched = 0;
  const int x0 = static_cast<int>(cursor.x()) - 60, y0 = static_cast<int>(cursor.y()) - 60;
  for (int y = y0; y < y0 + 120; ++y) {
    for (int x = x0; x < x0 + 120; ++x) {
      const Eigen::Vector2d uv = view.ToImage({x + 0.5, y + 0.5});
      const double fx = uv.x() + 0.5 - std::floor(uv.x() + 0.5), fy = uv.y() + 0.5 - std::floor(uv.y() + 0.5);
      if (fx < 0.02 || fx > 0.98 || fy < 0.02 || fy > 0.98) continue;
      if (!view.Inside({x + 0.5, y + 0.5}, 1.0)) continue;
      const int u = static_cast<int>(std::floor(uv.x() + 0.5)), v = static_cast<int>(std::floor(uv.y() + 0.5));
      const bool ok = shot.at<cv::Vec3b>(y, x) == PixelColor(u, v);
      ++total;
      matched += ok;
      if (std::abs(u - 247.5) <= 2 || std::abs(v - 185.5) <= 2) {
        ++seam_total;
        seam_matched += ok;
      }
    }
  }
  MESSAGE("exact pixels: " << matched << " of " << total << "; at the tile seams " << seam_matched << " of "
                           << seam_total << " (zoom " << view.zoom << ")");
  CHECK(total > 5000);
  CHECK(seam_total > 500);
  CHECK(matched == total);
  CHECK(seam_matched == seam_total);
}

TEST_CASE("image panel: a line tool drag adds one segment of its family where the mouse went") {
  TempDir dir("line");
  const Fixture f = WriteFixture(dir, false, false);
  const View view = ViewFromReport(Render(dir, f, "start", ""));
  const Eigen::Vector2d a = Whole(ViewCenter(view) + Eigen::Vector2d(-80, 40));
  const Eigen::Vector2d b = Whole(ViewCenter(view) + Eigen::Vector2d(60, -30));
  const Eigen::Vector2d tiny = a + Eigen::Vector2d(2, 1);  // under 3 px: ignored
  const std::string script = "frames 2\ncommand tool line-y\ndrag left " + FormatXY(a, 10) + " " + FormatXY(b, 10) +
                             " 8\nframes 2\n" + "drag left " + FormatXY(a, 10) + " " + FormatXY(tiny, 10) +
                             " 3\nframes 2\n";
  const nlohmann::json report = Render(dir, f, "line", script);
  const facet::Project project = ProjectFromReport(report);
  REQUIRE(project.segments.size() == 1);
  CHECK(report.at("undo_stack").size() == 1);
  const facet::Segment& s = project.segments.front();
  CHECK(s.axis == facet::Axis::kY);
  CHECK(s.image_id == f.scene.image_id);
  // Screen positions are floats: allow their rounding, in image px.
  const double tolerance_px = 0.01 / view.zoom;
  CAPTURE(s.a_px.transpose());
  CAPTURE(s.b_px.transpose());
  CHECK((s.a_px - view.ToImage(a)).norm() < tolerance_px);
  CHECK((s.b_px - view.ToImage(b)).norm() < tolerance_px);
}

TEST_CASE("image panel: Escape cancels an endpoint drag; Delete removes the selected segment") {
  TempDir dir("escape");
  const Fixture f = WriteFixture(dir, true, false);
  const nlohmann::json start = Render(dir, f, "start", "");
  const View view = ViewFromReport(start);
  const facet::Project& p = f.scene.project;
  // The endpoint farthest on screen from every other endpoint, so the press picks it alone.
  const facet::Segment* best = nullptr;
  int best_end = 0;
  double best_gap = -1;
  for (const facet::Segment& s : p.segments) {
    for (int end = 0; end < 2; ++end) {
      const Eigen::Vector2d q = end == 0 ? s.a_px : s.b_px;
      double gap = 1e9;
      for (const facet::Segment& o : p.segments) {
        for (int oe = 0; oe < 2; ++oe) {
          if (&o == &s && oe == end) continue;
          gap = std::min(gap, ((oe == 0 ? o.a_px : o.b_px) - q).norm() * view.zoom);
        }
      }
      if (gap > best_gap && view.Inside(view.ToScreen(q), 40.0)) {
        best_gap = gap;
        best = &s;
        best_end = end;
      }
    }
  }
  REQUIRE(best != nullptr);
  REQUIRE(best_gap > 12.0);
  const Eigen::Vector2d from = Whole(view.ToScreen(best_end == 0 ? best->a_px : best->b_px));
  const Eigen::Vector2d to = from + Eigen::Vector2d(25, 15);

  const std::string cancel = "frames 2\nmove " + FormatXY(from, 10) + "\nframes 1\ndown left\nmove " +
                             FormatXY(from + (to - from) * 0.5, 10) + "\nmove " + FormatXY(to, 10) +
                             "\nframes 1\nkey escape\nup left\nframes 2\n";
  const nlohmann::json cancelled = Render(dir, f, "cancel", cancel);
  CHECK(cancelled.at("undo_stack").empty());
  CHECK(cancelled.at("project") == start.at("project"));

  // Without the Escape the same drag moves the endpoint (so the check above can fail).
  const std::string moved_script =
      "frames 2\ndrag left " + FormatXY(from, 10) + " " + FormatXY(to, 10) + " 6\nframes 2\n";
  const facet::Project moved = ProjectFromReport(Render(dir, f, "moved", moved_script));
  const facet::Segment* m = moved.FindSegment(best->id);
  REQUIRE(m != nullptr);
  const Eigen::Vector2d expected = (best_end == 0 ? best->a_px : best->b_px) + (to - from) / view.zoom;
  CHECK(((best_end == 0 ? m->a_px : m->b_px) - expected).norm() < 0.01 / view.zoom);

  // A click selects the segment at its endpoint; Delete removes it as one undo entry.
  const std::string del = "frames 2\nclick left " + FormatXY(from, 10) + "\nframes 1\nkey delete\nframes 2\n";
  const nlohmann::json deleted = Render(dir, f, "delete", del);
  const facet::Project after = ProjectFromReport(deleted);
  CHECK(after.segments.size() == p.segments.size() - 1);
  CHECK(after.FindSegment(best->id) == nullptr);
  CHECK(deleted.at("undo_stack").size() == 1);
}

// The box corner farthest on screen from the others (at least 20 px from each), inside the view.
int LonelyCorner(const Fixture& f, const View& view) {
  std::array<Eigen::Vector3d, 8> corners;  // the box mesh's vertex i is corner i
  for (int c = 0; c < 8; ++c) corners[c] = f.scene.true_box.mesh.vertex(static_cast<facet::VertexId>(c)).position;
  int best = -1;
  double best_gap = -1;
  for (int i = 0; i < 8; ++i) {
    double gap = 1e9;
    for (int j = 0; j < 8; ++j) {
      if (j != i)
        gap = std::min(gap, (f.scene.true_camera.Project(corners[i]) - f.scene.true_camera.Project(corners[j])).norm() *
                                view.zoom);
    }
    if (gap > best_gap && view.Inside(view.ToScreen(f.scene.true_camera.Project(corners[i])), 40.0)) {
      best_gap = gap;
      best = i;
    }
  }
  REQUIRE(best >= 0);
  REQUIRE(best_gap > 20.0);
  return best;
}

Eigen::Vector2d CornerOnScreen(const Fixture& f, const View& view, int corner) {
  return Whole(view.ToScreen(
      f.scene.true_camera.Project(f.scene.true_box.mesh.vertex(static_cast<facet::VertexId>(corner)).position)));
}

TEST_CASE("image panel: the pin tool pins a clicked box vertex where the next click lands") {
  TempDir dir("pin");
  const Fixture f = WriteFixture(dir, false, false);
  const View view = ViewFromReport(Render(dir, f, "start", ""));
  const int best = LonelyCorner(f, view);
  const Eigen::Vector2d corner_screen = CornerOnScreen(f, view, best);
  const Eigen::Vector2d target = corner_screen + Eigen::Vector2d(-14, 9);
  const std::string script = "frames 2\ncommand tool pin\nclick left " + FormatXY(corner_screen, 10) +
                             "\nframes 1\nclick left " + FormatXY(target, 10) + "\nframes 2\n";
  const nlohmann::json report = Render(dir, f, "pin", script);
  const facet::Project project = ProjectFromReport(report);
  REQUIRE(project.pins.size() == 1);
  const facet::Pin& pin = project.pins.front();
  CHECK(pin.vertex.primitive_id == f.scene.box_id);
  CHECK(pin.vertex.vertex == static_cast<facet::VertexId>(best));
  CHECK(pin.image_id == f.scene.image_id);
  CHECK((pin.uv_px - view.ToImage(target)).norm() < 0.01 / view.zoom);
  CHECK(report.at("undo_stack").size() == 1);
}

TEST_CASE("issue 25: a pin lands where the button was released, though the pointer moved on in that frame") {
  TempDir dir("pin_release");
  const Fixture f = WriteFixture(dir, false, false);
  const View view = ViewFromReport(Render(dir, f, "start", ""));
  const int corner = LonelyCorner(f, view);
  const Eigen::Vector2d corner_screen = CornerOnScreen(f, view, corner);
  const Eigen::Vector2d target = corner_screen + Eigen::Vector2d(-14, 9);
  // The user releases at the target and moves on 150 px before the frame reads the input.
  const Eigen::Vector2d moved_on = target + Eigen::Vector2d(150, 60);
  REQUIRE(view.Inside(moved_on, 5.0));
  const std::string script = "frames 2\ncommand tool pin\nclick left " + FormatXY(corner_screen, 10) +
                             "\nframes 1\nmove " + FormatXY(target, 10) + "\ndown left\nup-then-move left " +
                             FormatXY(moved_on, 10) + "\nframes 3\n";
  const nlohmann::json report = Render(dir, f, "pin", script);
  const facet::Project project = ProjectFromReport(report);
  REQUIRE(project.pins.size() == 1);
  const facet::Pin& pin = project.pins.front();
  CHECK(pin.vertex.vertex == static_cast<facet::VertexId>(corner));
  // Within a hundredth of a screen pixel of the release, 160 px from where the pointer went.
  CHECK((pin.uv_px - view.ToImage(target)).norm() < 0.01 / view.zoom);
  CHECK(report.at("undo_stack").size() == 1);
}

TEST_CASE("issue 25: a pin released off the photo is refused with a message; the model is unchanged") {
  TempDir dir("pin_outside");
  const Fixture f = WriteFixture(dir, false, false);
  const View view = ViewFromReport(Render(dir, f, "start", ""));
  const int corner = LonelyCorner(f, view);
  const Eigen::Vector2d corner_screen = CornerOnScreen(f, view, corner);
  // Zoomed out about the photo's centre, the panel shows a margin around the photo: the
  // release lands 40 image px left of its left edge.
  const Eigen::Vector2d centre =
      Whole(view.ToScreen({0.5 * f.scene.true_camera.width_px, 0.5 * f.scene.true_camera.height_px}));
  const std::string script = "frames 2\ncommand tool pin\nclick left " + FormatXY(corner_screen, 10) +
                             "\nframes 1\nwheel -4 " + FormatXY(centre, 10) + "\nframes 2\nclick left image -40 " +
                             std::to_string(f.scene.true_camera.height_px / 2) + "\nframes 2\n";
  const nlohmann::json report = Render(dir, f, "pin", script);
  const View zoomed = ViewFromReport(report);
  REQUIRE(zoomed.zoom < view.zoom);
  REQUIRE(zoomed.Inside(zoomed.ToScreen({-40.0, 0.5 * f.scene.true_camera.height_px}), 2.0));
  const facet::Project project = ProjectFromReport(report);
  CHECK(project.pins.empty());
  CHECK(report.at("undo_stack").size() == 0);
  bool said = false;
  for (const auto& e : report.at("log")) said = said || e.at("text").get<std::string>().rfind("Pin not placed", 0) == 0;
  CHECK(said);
}

TEST_CASE("image panel: with Shift held during a press the pointer moves at 1/magnification of the mouse") {
  TempDir dir("fine");
  const Fixture f = WriteFixture(dir, false, false);
  const View view = ViewFromReport(Render(dir, f, "start", ""));
  const Eigen::Vector2d a = Whole(ViewCenter(view) + Eigen::Vector2d(-50, 20));
  const Eigen::Vector2d mouse_motion(40, -12);
  constexpr double kMagnification = 4.0;  // the loupe's default
  // Shift is down before the press: the press lands on the mouse, the motion is slowed.
  const std::string script = "frames 2\ncommand tool line-z\nmove " + FormatXY(a, 10) +
                             "\nhold shift\nframes 2\ndown left\nmove " + FormatXY(a + 0.5 * mouse_motion, 10) +
                             "\nmove " + FormatXY(a + mouse_motion, 10) +
                             "\nframes 1\nup left\nframes 1\nrelease shift\nframes 2\n";
  const facet::Project project = ProjectFromReport(Render(dir, f, "fine", script));
  REQUIRE(project.segments.size() == 1);
  const facet::Segment& s = project.segments.front();
  CHECK(s.axis == facet::Axis::kZ);
  const Eigen::Vector2d expected_a = view.ToImage(a);
  const Eigen::Vector2d expected_b = expected_a + mouse_motion / (view.zoom * kMagnification);
  const double tolerance_px = 0.01 / view.zoom;
  CAPTURE(s.a_px.transpose());
  CAPTURE(s.b_px.transpose());
  CAPTURE(expected_b.transpose());
  CHECK((s.a_px - expected_a).norm() < tolerance_px);
  CHECK((s.b_px - expected_b).norm() < tolerance_px);
  // The check can fail: without fine mode b would be where the mouse is.
  CHECK((view.ToImage(a + mouse_motion) - expected_b).norm() > 10.0);
}
