// Screenshot tests of the real application binary in offscreen mode (`facet render`, EGL
// surfaceless, no display): the layout's panels, the photo under the image view's reported
// transform, the projected model over the photo, and a scripted pin drag undone with ctrl+z.
// Each test writes its own synthetic photo and project into a temporary folder.
#include <doctest/doctest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/io/project_io.h"
#include "core/mesh/box.h"
#include "core/mesh/mesh.h"
#include "tests/app/app_test_util.h"
#include "tests/synthetic_scene.h"

namespace fs = std::filesystem;
using facet::testing::MakeBoxScene;
using facet::testing::SyntheticScene;
using namespace facet::testing;  // app_test_util.h

namespace {

constexpr int kCheckerCellPx = 48;

// BGR colour of the checker cell (i, j): six distinct colours, none close to the model's yellow.
cv::Vec3b CheckerColor(int i, int j) {
  static const cv::Vec3b palette[] = {{140, 60, 40}, {210, 200, 200}, {90, 150, 90},
                                      {60, 70, 160}, {60, 60, 60},    {80, 150, 220}};
  return palette[(i * 7 + j * 3 + (i * j) % 5) % 6];
}

// The synthetic photo: a checkerboard, with the scene's box painted over it (visible faces
// only, one flat colour each) when `with_box` holds.
cv::Mat MakePhoto(const SyntheticScene& scene, bool with_box) {
  const facet::Camera& cam = scene.true_camera;
  cv::Mat photo(cam.height_px, cam.width_px, CV_8UC3);
  for (int y = 0; y < photo.rows; ++y) {
    for (int x = 0; x < photo.cols; ++x)
      photo.at<cv::Vec3b>(y, x) = CheckerColor(x / kCheckerCellPx, y / kCheckerCellPx);
  }
  if (with_box) {
    const cv::Scalar face_colors[] = {{200, 90, 170},  {70, 200, 230}, {230, 230, 90},
                                      {120, 120, 240}, {40, 140, 255}, {250, 250, 250}};
    const auto corners = BoxCorners(scene.true_box);
    const Eigen::Vector3d eye = cam.CenterInWorld();
    for (int f = 0; f < 6; ++f) {
      const auto& face = facet::BoxFaces()[f];
      Eigen::Vector3d centre = Eigen::Vector3d::Zero();
      for (int c : face) centre += corners[c] / 4.0;
      // The box mesh's face f is BoxFaces()[f] (core/mesh/primitives.h builds them in order).
      if (facet::FaceNormal(scene.true_box.mesh, static_cast<facet::FaceId>(f)).dot(eye - centre) <= 0) continue;
      std::vector<cv::Point> poly;
      for (int c : face) {
        const Eigen::Vector2d uv = cam.Project(corners[c]);
        // Sub-pixel vertices (4 fractional bits): pixel centres at integer coordinates.
        poly.emplace_back(static_cast<int>(std::lround(uv.x() * 16)), static_cast<int>(std::lround(uv.y() * 16)));
      }
      cv::fillConvexPoly(photo, poly, face_colors[f], cv::LINE_AA, 4);
    }
  }
  return photo;
}

struct Fixture {
  SyntheticScene scene;
  std::string project_path;
  std::string photo_path;
};

// Writes photo and project into `dir`. The project keeps the image, its true camera, and
// optionally the box and its eight pins; never the line segments (their overlays would
// cover the edges under test).
Fixture WriteFixture(const TempDir& dir, bool with_box, bool with_pins) {
  Fixture f;
  f.scene = MakeBoxScene();
  facet::Project& p = f.scene.project;
  p.segments.clear();
  if (!with_box) p.primitives.clear();
  if (!with_box || !with_pins) p.pins.clear();
  f.photo_path = dir / "synthetic.png";
  REQUIRE(cv::imwrite(f.photo_path, MakePhoto(f.scene, with_box)));
  f.project_path = dir / "scene.facet";
  REQUIRE(facet::SaveProject(p, f.project_path) == "");
  return f;
}

int MaxChannelDifference(const cv::Vec3b& a, const cv::Vec3b& b) {
  int d = 0;
  for (int c = 0; c < 3; ++c) d = std::max(d, std::abs(int(a[c]) - int(b[c])));
  return d;
}

// Fraction of checker-cell centres inside the view whose screenshot pixel matches the photo
// within `tolerance`, with the view shifted by (dx, dy) screen px (0 for the real check).
double CheckerMatchFraction(const cv::Mat& shot, const cv::Mat& photo, const View& view, double dx, double dy,
                            int tolerance, int* samples) {
  int matched = 0, total = 0;
  for (int j = 0; j * kCheckerCellPx < photo.rows; ++j) {
    for (int i = 0; i * kCheckerCellPx < photo.cols; ++i) {
      const Eigen::Vector2d uv((i + 0.5) * kCheckerCellPx - 0.5, (j + 0.5) * kCheckerCellPx - 0.5);
      if (uv.x() >= photo.cols || uv.y() >= photo.rows) continue;
      const Eigen::Vector2d s = view.ToScreen(uv) + Eigen::Vector2d(dx, dy);
      if (!view.Inside(s, 2.0)) continue;
      ++total;
      const cv::Vec3b expected = photo.at<cv::Vec3b>(static_cast<int>(uv.y()), static_cast<int>(uv.x()));
      const cv::Vec3b seen =
          shot.at<cv::Vec3b>(static_cast<int>(std::floor(s.y())), static_cast<int>(std::floor(s.x())));
      if (MaxChannelDifference(expected, seen) <= tolerance) ++matched;
    }
  }
  *samples = total;
  return total ? static_cast<double>(matched) / total : 0.0;
}

}  // namespace

TEST_CASE("render: the PNG has the requested size and every panel is inside the window, none overlapping") {
  TempDir dir("layout");
  const Fixture f = WriteFixture(dir, /*with_box=*/true, /*with_pins=*/true);
  // A saved user layout that hides panels must not affect offscreen renders.
  fs::create_directories(dir.path / "config" / "facet");
  const std::string user_layout = R"({"format":"facet-layout","version":1,"split_ratio":[0.5,0.5,0.5,0.5,0.5],)"
                                  R"("panels":{"tools":{"visible":false,"floating":false,"rect":[0,0,0,0]}}})";
  WriteText(dir / "config/facet/layout.json", user_layout);

  constexpr int kWidth = 1280, kHeight = 800;
  const RunResult run =
      RunRender(dir, "'" + f.project_path + "' -o '" + (dir / "shot.png") + "' --size " + std::to_string(kWidth) + "x" +
                         std::to_string(kHeight) + " --report '" + (dir / "report.json") + "'");
  INFO("stderr: " << run.stderr_text);
  REQUIRE(run.exit_code == 0);
  const cv::Mat shot = cv::imread(dir / "shot.png", cv::IMREAD_COLOR);
  REQUIRE(!shot.empty());
  CHECK(shot.cols == kWidth);
  CHECK(shot.rows == kHeight);

  const nlohmann::json report = ReadJson(dir / "report.json");
  const auto& panels = report.at("panels");
  const std::vector<std::string> names = {"Tools", "Image", "3D", "Properties", "History", "Log"};
  std::vector<std::array<double, 4>> rects;
  for (const std::string& name : names) {
    REQUIRE_MESSAGE(panels.contains(name), "panel " << name << " missing from the report: " << panels.dump());
    const auto& r = panels.at(name);
    const std::array<double, 4> rect = {r.at("x").get<double>(), r.at("y").get<double>(), r.at("w").get<double>(),
                                        r.at("h").get<double>()};
    CAPTURE(name);
    CAPTURE(r.dump());
    CHECK(rect[2] >= 100);
    CHECK(rect[3] >= 100);
    CHECK(rect[0] >= 0);
    CHECK(rect[1] >= 0);
    CHECK(rect[0] + rect[2] <= kWidth);
    CHECK(rect[1] + rect[3] <= kHeight);
    rects.push_back(rect);
  }
  for (size_t a = 0; a < rects.size(); ++a) {
    for (size_t b = a + 1; b < rects.size(); ++b) {
      const double ox =
          std::min(rects[a][0] + rects[a][2], rects[b][0] + rects[b][2]) - std::max(rects[a][0], rects[b][0]);
      const double oy =
          std::min(rects[a][1] + rects[a][3], rects[b][1] + rects[b][3]) - std::max(rects[a][1], rects[b][1]);
      INFO(names[a] << " and " << names[b] << " overlap by " << ox << " x " << oy << " px");
      CHECK((ox <= 0 || oy <= 0));
    }
  }
  // The image and 3D panels sit side by side, between tools (left) and properties (right).
  CHECK(rects[0][0] < rects[1][0]);
  CHECK(rects[1][0] < rects[2][0]);
  CHECK(rects[2][0] < rects[3][0]);
  CHECK(std::abs(rects[1][1] - rects[2][1]) < 1.0);
  // The user's layout file was neither applied nor rewritten.
  std::ifstream in(dir / "config/facet/layout.json");
  std::ostringstream ss;
  ss << in.rdbuf();
  CHECK(ss.str() == user_layout);
  CHECK(report.at("renderer").get<std::string>() != "");
}

TEST_CASE("render: the image panel shows the photo under the reported image-to-screen transform") {
  TempDir dir("photo");
  const Fixture f = WriteFixture(dir, /*with_box=*/false, /*with_pins=*/false);
  const RunResult run = RunRender(
      dir, "'" + f.project_path + "' -o '" + (dir / "shot.png") + "' --report '" + (dir / "report.json") + "'");
  INFO("stderr: " << run.stderr_text);
  REQUIRE(run.exit_code == 0);
  const cv::Mat shot = cv::imread(dir / "shot.png", cv::IMREAD_COLOR);
  const cv::Mat photo = cv::imread(f.photo_path, cv::IMREAD_COLOR);
  REQUIRE(!shot.empty());
  const nlohmann::json report = ReadJson(dir / "report.json");
  const View view = ViewFromReport(report);
  INFO("image view: " << report.at("image_view").dump());
  REQUIRE(view.zoom > 0.1);
  // The view rectangle lies inside the Image panel.
  const auto& panel = report.at("panels").at("Image");
  CHECK(view.rect_x >= panel.at("x").get<double>());
  CHECK(view.rect_y >= panel.at("y").get<double>());
  CHECK(view.rect_x + view.rect_w <= panel.at("x").get<double>() + panel.at("w").get<double>() + 0.5);
  CHECK(view.rect_y + view.rect_h <= panel.at("y").get<double>() + panel.at("h").get<double>() + 0.5);

  // Cell centres are a uniform colour for +-0.5 cell, so filtering leaves them exact up to
  // rounding; a small tolerance absorbs the texture sampler's rounding.
  constexpr int kColorTolerance = 12;
  constexpr double kRequiredFraction = 0.98;
  int samples = 0;
  const double fraction = CheckerMatchFraction(shot, photo, view, 0, 0, kColorTolerance, &samples);
  MESSAGE("photo match: " << fraction * 100 << "% of " << samples << " cell centres");
  CHECK(samples >= 200);
  CHECK(fraction >= kRequiredFraction);
  // The check can fail: the same samples under a transform off by half a cell do not match.
  int shifted_samples = 0;
  const double shifted = CheckerMatchFraction(shot, photo, view, 0.5 * kCheckerCellPx * view.zoom,
                                              0.5 * kCheckerCellPx * view.zoom, kColorTolerance, &shifted_samples);
  MESSAGE("shifted transform: " << shifted * 100 << "% match");
  CHECK(shifted < 0.6);
}

TEST_CASE("render: the projected box edges land on the photo's box edges") {
  TempDir dir("edges");
  const Fixture f = WriteFixture(dir, /*with_box=*/true, /*with_pins=*/false);
  const RunResult run = RunRender(
      dir, "'" + f.project_path + "' -o '" + (dir / "shot.png") + "' --report '" + (dir / "report.json") + "'");
  INFO("stderr: " << run.stderr_text);
  REQUIRE(run.exit_code == 0);
  const cv::Mat shot = cv::imread(dir / "shot.png", cv::IMREAD_COLOR);
  const cv::Mat photo = cv::imread(f.photo_path, cv::IMREAD_COLOR);
  const View view = ViewFromReport(ReadJson(dir / "report.json"));
  const facet::Camera& cam = f.scene.true_camera;
  const auto corners = BoxCorners(f.scene.true_box);

  // The model colour must be drawn within kEdgeRadiusPx of every sampled point of the 12
  // projected edges, and the photo must change colour across the visible (outline) edges
  // right there: the overlay sits on the photo's box, not merely somewhere on screen.
  constexpr int kEdgeRadiusPx = 2;
  constexpr int kColorTolerance = 40;
  int samples = 0, hits = 0, photo_edges = 0, photo_samples = 0;
  for (const auto& e : facet::BoxEdges()) {
    const Eigen::Vector2d a = cam.Project(corners[e[0]]), b = cam.Project(corners[e[1]]);
    const Eigen::Vector2d normal = Eigen::Vector2d(-(b - a).y(), (b - a).x()).normalized();
    for (int k = 2; k <= 18; ++k) {
      const Eigen::Vector2d uv = a + (b - a) * (k / 20.0);
      const Eigen::Vector2d s = view.ToScreen(uv);
      if (!view.Inside(s, 4.0)) continue;
      ++samples;
      if (ModelColorNear(shot, s, kEdgeRadiusPx, kColorTolerance)) ++hits;
      // Photo: colours 4 px to either side of the edge.
      const Eigen::Vector2d p = uv + 4.0 * normal, q = uv - 4.0 * normal;
      if (p.x() < 0 || q.x() < 0 || p.y() < 0 || q.y() < 0 || p.x() >= photo.cols || q.x() >= photo.cols ||
          p.y() >= photo.rows || q.y() >= photo.rows) {
        continue;
      }
      ++photo_samples;
      if (MaxChannelDifference(photo.at<cv::Vec3b>(int(p.y()), int(p.x())),
                               photo.at<cv::Vec3b>(int(q.y()), int(q.x()))) > 30) {
        ++photo_edges;
      }
    }
  }
  MESSAGE("model colour found at " << hits << " of " << samples << " edge samples; photo colour changes across "
                                   << photo_edges << " of " << photo_samples);
  CHECK(samples >= 150);
  CHECK(hits == samples);
  // Hidden edges run over a face of one colour; the outline and the visible inner edges
  // (9 of 12 edges) separate two colours.
  CHECK(photo_edges >= photo_samples / 2);

  // The check can fail: away from the edges (12 px along the normal), no model colour.
  int far_samples = 0, far_hits = 0;
  for (const auto& e : facet::BoxEdges()) {
    const Eigen::Vector2d a = cam.Project(corners[e[0]]), b = cam.Project(corners[e[1]]);
    const Eigen::Vector2d normal = Eigen::Vector2d(-(b - a).y(), (b - a).x()).normalized();
    for (int k = 4; k <= 16; k += 4) {
      const Eigen::Vector2d s = view.ToScreen(a + (b - a) * (k / 20.0)) + 12.0 * normal;
      if (!view.Inside(s, 4.0)) continue;
      // Skip points that come close to another edge.
      bool near_other = false;
      for (const auto& o : facet::BoxEdges()) {
        const Eigen::Vector2d oa = view.ToScreen(cam.Project(corners[o[0]])),
                              ob = view.ToScreen(cam.Project(corners[o[1]]));
        const double t = std::clamp((s - oa).dot(ob - oa) / (ob - oa).squaredNorm(), 0.0, 1.0);
        if ((oa + t * (ob - oa) - s).norm() < 8.0) near_other = true;
      }
      if (near_other) continue;
      ++far_samples;
      if (ModelColorNear(shot, s, 1, kColorTolerance)) ++far_hits;
    }
  }
  MESSAGE("model colour away from edges: " << far_hits << " of " << far_samples);
  CHECK(far_samples >= 20);
  CHECK(far_hits == 0);
}

TEST_CASE("render: a scripted pin drag is one undo entry and ctrl+z restores the project") {
  TempDir dir("drag");
  const Fixture f = WriteFixture(dir, /*with_box=*/true, /*with_pins=*/true);
  const std::string start_json = facet::ProjectToJson(facet::LoadProject(f.project_path).project);

  // Locate the pins on screen from a first render.
  RunResult run = RunRender(
      dir, "'" + f.project_path + "' -o '" + (dir / "start.png") + "' --report '" + (dir / "start.json") + "'");
  INFO("stderr: " << run.stderr_text);
  REQUIRE(run.exit_code == 0);
  const nlohmann::json start = ReadJson(dir / "start.json");
  const View view = ViewFromReport(start);
  REQUIRE(start.at("undo_stack").empty());

  // The pin farthest from every other pin on screen, so the press picks it alone.
  const auto& pins = f.scene.project.pins;
  size_t best = 0;
  double best_gap = -1;
  for (size_t i = 0; i < pins.size(); ++i) {
    double gap = 1e9;
    for (size_t j = 0; j < pins.size(); ++j) {
      if (j != i) gap = std::min(gap, (pins[i].uv_px - pins[j].uv_px).norm() * view.zoom);
    }
    if (view.Inside(view.ToScreen(pins[i].uv_px), 40.0) && gap > best_gap) {
      best_gap = gap;
      best = i;
    }
  }
  REQUIRE(best_gap > 20.0);
  const Eigen::Vector2d from = view.ToScreen(pins[best].uv_px);
  const Eigen::Vector2d delta_screen(30.0, -20.0);
  const Eigen::Vector2d to = from + delta_screen;
  std::ostringstream drag;
  drag << "# drag pin " << pins[best].id << "\n"
       << "frames 2\n"
       << "drag left " << from.x() << " " << from.y() << " " << to.x() << " " << to.y() << " 12\n"
       << "frames 2\n";
  const std::string saved = dir / "after_drag.facet";
  WriteText(dir / "drag.txt", drag.str() + "command save " + saved + "\n");
  WriteText(dir / "drag_undo.txt", drag.str() + "key ctrl+z\nframes 2\n");

  run = RunRender(dir, "'" + f.project_path + "' -o '" + (dir / "drag.png") + "' --script '" + (dir / "drag.txt") +
                           "' --report '" + (dir / "drag.json") + "'");
  REQUIRE(run.exit_code == 0);
  const nlohmann::json after_drag = ReadJson(dir / "drag.json");
  INFO("undo stack after the drag: " << after_drag.at("undo_stack").dump());
  CHECK(after_drag.at("undo_stack").size() == start.at("undo_stack").size() + 1);
  const facet::ProjectLoadResult dragged = facet::LoadProject(saved);
  REQUIRE(dragged.ok());
  const facet::Pin* moved = dragged.project.FindPin(pins[best].id);
  REQUIRE(moved != nullptr);
  // The pin follows the cursor: the screen displacement divided by the zoom, within a pixel
  // of the view (the image panel keeps the grab offset).
  const Eigen::Vector2d moved_px = moved->uv_px - pins[best].uv_px;
  const double tolerance_px = 1.0 / view.zoom;
  CAPTURE(moved_px.transpose());
  CHECK(std::abs(moved_px.x() - delta_screen.x() / view.zoom) <= tolerance_px);
  CHECK(std::abs(moved_px.y() - delta_screen.y() / view.zoom) <= tolerance_px);
  CHECK(facet::ProjectToJson(dragged.project) != start_json);
  CHECK(after_drag.at("project") == nlohmann::json::parse(facet::ProjectToJson(dragged.project)));

  run = RunRender(dir, "'" + f.project_path + "' -o '" + (dir / "undo.png") + "' --script '" + (dir / "drag_undo.txt") +
                           "' --report '" + (dir / "undo.json") + "'");
  REQUIRE(run.exit_code == 0);
  const nlohmann::json undone = ReadJson(dir / "undo.json");
  CHECK(undone.at("undo_stack").empty());
  CHECK(undone.at("redo_stack").size() == 1);
  CHECK(undone.at("project") == nlohmann::json::parse(start_json));
}

TEST_CASE("render: script errors name the line and exit with 1") {
  TempDir dir("script_error");
  const Fixture f = WriteFixture(dir, /*with_box=*/false, /*with_pins=*/false);
  WriteText(dir / "bad.txt", "frames 1\n# a comment\nclick left 10\n");
  RunResult run =
      RunRender(dir, "'" + f.project_path + "' -o '" + (dir / "shot.png") + "' --script '" + (dir / "bad.txt") + "'");
  CAPTURE(run.stderr_text);
  CHECK(run.exit_code == 1);
  CHECK(run.stderr_text.find("line 3") != std::string::npos);
  CHECK(!fs::exists(dir / "shot.png"));

  WriteText(dir / "unknown.txt", "jump 3\n");
  run = RunRender(dir,
                  "'" + f.project_path + "' -o '" + (dir / "shot.png") + "' --script '" + (dir / "unknown.txt") + "'");
  CAPTURE(run.stderr_text);
  CHECK(run.exit_code == 1);
  CHECK(run.stderr_text.find("line 1") != std::string::npos);
  CHECK(run.stderr_text.find("jump") != std::string::npos);

  // A command that fails while running (opening a missing project) also names its line.
  WriteText(dir / "missing.txt", "frames 1\ncommand open " + (dir / "missing.facet") + "\n");
  run = RunRender(dir,
                  "'" + f.project_path + "' -o '" + (dir / "shot.png") + "' --script '" + (dir / "missing.txt") + "'");
  CAPTURE(run.stderr_text);
  CHECK(run.exit_code == 1);
  CHECK(run.stderr_text.find("line 2") != std::string::npos);
}

TEST_CASE("gui: without a display the app says how to render offscreen and exits with 2") {
  TempDir dir("nodisplay");
  const std::string err = dir / "stderr.txt";
  const std::string cmd = "env -u DISPLAY -u WAYLAND_DISPLAY XDG_CONFIG_HOME='" + (dir / "config") + "' '" +
                          std::string(FACET_APP_EXE) + "' 2> '" + err + "'";
  const int status = std::system(cmd.c_str());
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 2);
  std::ifstream in(err);
  std::ostringstream ss;
  ss << in.rdbuf();
  CAPTURE(ss.str());
  CHECK(ss.str().find("facet render") != std::string::npos);
}

TEST_CASE("render: a splitter drag resizes its neighbours; title-bar drag and Undock float panels, Dock returns them") {
  TempDir dir("layout_edit");
  const Fixture f = WriteFixture(dir, /*with_box=*/false, /*with_pins=*/false);
  RunResult run = RunRender(
      dir, "'" + f.project_path + "' -o '" + (dir / "start.png") + "' --report '" + (dir / "start.json") + "'");
  INFO("stderr: " << run.stderr_text);
  REQUIRE(run.exit_code == 0);
  const nlohmann::json start = ReadJson(dir / "start.json").at("panels");
  auto num = [](const nlohmann::json& panel, const char* key) { return panel.at(key).get<double>(); };
  const nlohmann::json& image = start.at("Image");
  const nlohmann::json& log = start.at("Log");
  const nlohmann::json& history = start.at("History");

  // The bar between Image and 3D lies in the gap right of the image panel.
  constexpr double kShiftPx = -120.0;
  const double bar_x = num(image, "x") + num(image, "w") + 3.0;
  const double bar_y = num(image, "y") + num(image, "h") / 2;
  // Log's Undock button sits left of the close button at the title bar's right end.
  const double undock_x = num(log, "x") + num(log, "w") - 60.0, title_y = num(log, "y") + 10.0;
  std::ostringstream script;
  script << "frames 2\n"
         << "drag left " << bar_x << " " << bar_y << " " << bar_x + kShiftPx << " " << bar_y << " 8\n"
         << "frames 2\n"
         << "click left " << undock_x << " " << title_y << "\n"
         << "frames 2\n"
         // Tear History off by dragging its title bar up into the middle of the window.
         << "drag left " << num(history, "x") + 80 << " " << num(history, "y") + 10 << " 500 300 10\n"
         << "frames 2\n";
  WriteText(dir / "layout.txt", script.str());
  run = RunRender(dir, "'" + f.project_path + "' -o '" + (dir / "edited.png") + "' --script '" + (dir / "layout.txt") +
                           "' --report '" + (dir / "edited.json") + "'");
  REQUIRE(run.exit_code == 0);
  const nlohmann::json edited = ReadJson(dir / "edited.json").at("panels");
  INFO("panels after the edits: " << edited.dump());
  constexpr double kPositionTolerancePx = 1.0;
  CHECK(std::abs(num(edited.at("Image"), "w") - (num(image, "w") + kShiftPx)) <= kPositionTolerancePx);
  CHECK(std::abs(num(edited.at("3D"), "x") - (num(start.at("3D"), "x") + kShiftPx)) <= kPositionTolerancePx);
  CHECK(edited.at("Log").at("floating").get<bool>());
  CHECK(edited.at("History").at("floating").get<bool>());
  // With the bottom row empty, the tiled panels grow down to the bottom of the window.
  CHECK(num(edited.at("Image"), "y") + num(edited.at("Image"), "h") > num(log, "y") + num(log, "h") - 1.0);
  // The torn-off panel follows the cursor (its title bar under the release point).
  CHECK(std::abs(num(edited.at("History"), "y") + 10.0 - 300.0) <= 12.0);

  // Dock the floating log again with its title-bar button.
  const nlohmann::json& floating_log = edited.at("Log");
  const double dock_x = num(floating_log, "x") + num(floating_log, "w") - 52.0;
  WriteText(dir / "dock.txt", script.str() + "click left " + std::to_string(dock_x) + " " +
                                  std::to_string(num(floating_log, "y") + 10.0) + "\nframes 2\n");
  run = RunRender(dir, "'" + f.project_path + "' -o '" + (dir / "docked.png") + "' --script '" + (dir / "dock.txt") +
                           "' --report '" + (dir / "docked.json") + "'");
  REQUIRE(run.exit_code == 0);
  const nlohmann::json docked = ReadJson(dir / "docked.json").at("panels");
  INFO("panels after docking the log: " << docked.dump());
  CHECK(!docked.at("Log").at("floating").get<bool>());
  // Back in its slot: the bottom row, now alone there, across the whole width.
  CHECK(std::abs(num(docked.at("Log"), "y") - num(log, "y")) <= kPositionTolerancePx);
  CHECK(std::abs(num(docked.at("Log"), "x") - num(history, "x")) <= kPositionTolerancePx);
}

TEST_CASE("render: a property drag is one undo entry; clicking the first history entry undoes everything") {
  TempDir dir("properties");
  const Fixture f = WriteFixture(dir, /*with_box=*/true, /*with_pins=*/false);
  const std::string start_json = facet::ProjectToJson(facet::LoadProject(f.project_path).project);
  RunResult run = RunRender(
      dir, "'" + f.project_path + "' -o '" + (dir / "start.png") + "' --report '" + (dir / "start.json") + "'");
  INFO("stderr: " << run.stderr_text);
  REQUIRE(run.exit_code == 0);
  const View view = ViewFromReport(ReadJson(dir / "start.json"));

  // Select the box by pressing on its projected corner 4 (in front, on the outline).
  const Eigen::Vector2d corner = view.ToScreen(f.scene.true_camera.Project(BoxCorners(f.scene.true_box)[4]));
  REQUIRE(view.Inside(corner, 10.0));
  std::ostringstream select;
  select << "frames 2\nclick left " << corner.x() << " " << corner.y() << "\nframes 2\n";
  WriteText(dir / "select.txt", select.str());
  run = RunRender(dir, "'" + f.project_path + "' -o '" + (dir / "selected.png") + "' --script '" +
                           (dir / "select.txt") + "' --report '" + (dir / "selected.json") + "'");
  REQUIRE(run.exit_code == 0);
  const nlohmann::json selected = ReadJson(dir / "selected.json");
  INFO("selection: " << selected.at("selection").dump() << " items: " << selected.at("items").dump());
  REQUIRE(selected.at("selection").at("primitive_id").get<facet::Id>() == f.scene.box_id);
  CHECK(selected.at("selection").at("element").at("kind").get<std::string>() == "vertex");
  CHECK(selected.at("selection").at("element").at("id").get<int>() == 4);
  REQUIRE(selected.at("items").contains("primitive.param.0"));
  const auto& size_item = selected.at("items").at("primitive.param.0");
  const double grab_x = size_item.at("x").get<double>() + 20.0;  // inside the size x field
  const double grab_y = size_item.at("y").get<double>() + size_item.at("h").get<double>() / 2;

  // Drag the size's x component 40 px to the right over ten frames, then key p (pin tool).
  std::ostringstream edit;
  edit << select.str() << "drag left " << grab_x << " " << grab_y << " " << grab_x + 40 << " " << grab_y << " 10\n"
       << "frames 2\nkey p\nframes 1\n";
  WriteText(dir / "edit.txt", edit.str());
  run = RunRender(dir, "'" + f.project_path + "' -o '" + (dir / "edit.png") + "' --script '" + (dir / "edit.txt") +
                           "' --report '" + (dir / "edit.json") + "'");
  REQUIRE(run.exit_code == 0);
  const nlohmann::json edited = ReadJson(dir / "edit.json");
  INFO("undo stack: " << edited.at("undo_stack").dump());
  CHECK(edited.at("undo_stack") == nlohmann::json::array({"Resize box"}));
  CHECK(edited.at("tool").get<std::string>() == "Pin");
  const facet::ProjectLoadResult after = facet::ProjectFromJson(edited.at("project").dump());
  REQUIRE(after.ok());
  const facet::Primitive* box = after.project.FindPrimitive(f.scene.box_id);
  REQUIRE(box != nullptr);
  // ImGui's drag speed here is 0.01 per px: 40 px is about 0.4 (a few px go to the drag threshold).
  const facet::PrimitiveParams& size = box->shape.params;
  const facet::PrimitiveParams& true_size = f.scene.true_box.shape.params;
  const double grown = size.x() - true_size.x();
  CAPTURE(grown);
  CHECK(grown > 0.2);
  CHECK(grown < 0.45);
  CHECK(size.y() == true_size.y());
  CHECK(size.z() == true_size.z());

  // Clicking history entry 0 ("Opened") undoes back to the file's project.
  const auto& first = edited.at("items").at("history.0");
  std::ostringstream undo_all;
  undo_all << edit.str() << "click left " << first.at("x").get<double>() + 40 << " "
           << first.at("y").get<double>() + first.at("h").get<double>() / 2 << "\nframes 2\n";
  WriteText(dir / "undo_all.txt", undo_all.str());
  run = RunRender(dir, "'" + f.project_path + "' -o '" + (dir / "undo_all.png") + "' --script '" +
                           (dir / "undo_all.txt") + "' --report '" + (dir / "undo_all.json") + "'");
  REQUIRE(run.exit_code == 0);
  const nlohmann::json undone = ReadJson(dir / "undo_all.json");
  CHECK(undone.at("undo_stack").empty());
  CHECK(undone.at("redo_stack").size() == 1);
  CHECK(undone.at("project") == nlohmann::json::parse(start_json));
  CHECK(!undone.at("dirty").get<bool>());
}
