// The calibration modes of the image panel in the real application offscreen (`facet render`
// with `command calibration ...` script lines, app/panels/camera_sections.h): a known focal length and
// a fixed principal point are kept exactly, a focal prior pulls the result towards itself as
// its std shrinks, one line family with a known focal length and the horizon gives the
// camera's vertical, undo restores the previous mode, the focal prior comes from the photo's
// EXIF, and every command is one history entry.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "app/state/calgui_exif_prior.h"
#include "core/geometry/camera_checks.h"
#include "core/io/project_io.h"
#include "tests/app/app_test_util.h"
#include "tests/synthetic_scene.h"

using namespace facet::testing;

namespace {

constexpr double kTrueFocalPx = 900.0;       // SyntheticSceneOptions default
constexpr double kFixedFocalPx = 950.0;      // the known lens the test types in
constexpr double kExifFocal35mm = 26.0;      // the photo's FocalLengthIn35mmFilm
constexpr double kNoisePx = 0.5;             // pixel noise of the modes scene's segments
constexpr double kExifRelTolerance = 1e-12;  // a product and a quotient of a few doubles
// Noise-free: the closed form and the fit recover the vertical to rounding.
constexpr double kVerticalTolerance = 1e-6;

// A JPEG of the given size with an EXIF block holding only FocalLengthIn35mmFilm (tag 0xa405,
// SHORT), written byte by byte: TIFF header, IFD0 with the Exif IFD pointer, the Exif IFD.
void WriteJpegWithExifFocal(const std::string& path, int width, int height, int focal_35mm) {
  std::vector<uint8_t> jpeg;
  REQUIRE(cv::imencode(".jpg", cv::Mat(height, width, CV_8UC3, cv::Scalar(90, 110, 120)), jpeg));
  std::vector<uint8_t> tiff(8 + 18 + 18, 0);
  auto put16 = [&](size_t at, uint32_t v) { tiff[at] = v & 0xff, tiff[at + 1] = (v >> 8) & 0xff; };
  auto put32 = [&](size_t at, uint32_t v) {
    for (int k = 0; k < 4; ++k) tiff[at + k] = (v >> (8 * k)) & 0xff;
  };
  tiff[0] = 'I', tiff[1] = 'I';
  put16(2, 42);
  put32(4, 8);
  put16(8, 1);        // IFD0: one entry
  put16(10, 0x8769);  // ExifIFDPointer, LONG, 1, -> 26
  put16(12, 4);
  put32(14, 1);
  put32(18, 26);
  put32(22, 0);
  put16(26, 1);       // Exif IFD: one entry
  put16(28, 0xa405);  // FocalLengthIn35mmFilm, SHORT, 1
  put16(30, 3);
  put32(32, 1);
  put16(36, static_cast<uint32_t>(focal_35mm));
  put32(40, 0);
  const size_t length = 2 + 6 + tiff.size();
  std::vector<uint8_t> app1 = {
      0xff, 0xe1, static_cast<uint8_t>(length >> 8), static_cast<uint8_t>(length & 0xff), 'E', 'x', 'i', 'f', 0, 0};
  app1.insert(app1.end(), tiff.begin(), tiff.end());
  jpeg.insert(jpeg.begin() + 2, app1.begin(), app1.end());
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(jpeg.data()), static_cast<std::streamsize>(jpeg.size()));
  REQUIRE(out.good());
}

// Tall enough for the whole properties panel (image section, result, solve) without scrolling.
constexpr const char* kWindowSize = "1600x1500";

RunResult Render(const TempDir& dir, const std::string& project, const std::string& script, const std::string& name) {
  WriteText(dir / (name + ".txt"), script);
  return RunRender(dir, "'" + project + "' -o '" + (dir / (name + ".png")) + "' --script '" + (dir / (name + ".txt")) +
                            "' --report '" + (dir / (name + ".json")) + "' --size " + kWindowSize);
}

// The true horizon of `camera` (pixels p with (R e_z) . K^-1 p = 0) at the image's left and
// right borders.
Eigen::Vector4d TrueHorizon(const facet::Camera& camera) {
  const Eigen::Vector3d line = camera.K().inverse().transpose() * camera.cam_from_world_rotation.col(2);
  const double right = camera.width_px - 1;
  return {0.0, -line.z() / line.y(), right, -(line.x() * right + line.z()) / line.y()};
}

facet::Image SavedImage(const std::string& path) {
  const facet::ProjectLoadResult loaded = facet::LoadProject(path);
  INFO("loading " << path << ": " << loaded.error);
  REQUIRE(loaded.ok());
  REQUIRE(loaded.project.images.size() == 1);
  return loaded.project.images[0];
}

}  // namespace

TEST_CASE("calibration modes from the script: known focal, undo, prior strength, fixed principal point, EXIF") {
  TempDir dir("calgui_modes");
  SyntheticSceneOptions options;
  options.noise_px = kNoisePx;
  options.seed = 7;
  SyntheticScene scene = MakeBoxScene(options);
  facet::Project& project = scene.project;
  project.images[0].path = "photo.jpg";
  WriteJpegWithExifFocal(dir / "photo.jpg", options.width_px, options.height_px, static_cast<int>(kExifFocal35mm));
  const std::string project_path = dir / "modes.facet";
  REQUIRE(facet::SaveProject(project, project_path) == "");
  const facet::Image original = SavedImage(project_path);
  REQUIRE(original.focal_mode == facet::FocalMode::kSolve);
  // The start is not the answer: the camera has the true focal length and principal point.
  REQUIRE(original.camera.focal_px != kFixedFocalPx);

  // The priors: 15 % above the free solution, ever tighter.
  const std::vector<double> prior_stds = {1e4, 100.0, 10.0, 1.0, 0.1};
  const Eigen::Vector2d fixed_pp(520.25, 370.75);
  auto save = [&](const std::string& name) { return "command save " + (dir / name) + "\nframes 1\n"; };

  std::ostringstream s;
  s << "frames 2\ncommand calibration focal fixed " << kFixedFocalPx << "\nframes 1\n" << save("fixed.facet");
  s << "command undo\nframes 1\n" << save("undone.facet");
  s << "command calibration focal solve\nframes 1\n" << save("free.facet");
  const std::string head = s.str();
  const RunResult first = Render(dir, project_path, head, "first");
  INFO("stderr: " << first.stderr_text);
  REQUIRE(first.exit_code == 0);

  // (a) A known focal length is the camera's, exactly.
  const facet::Image fixed = SavedImage(dir / "fixed.facet");
  CHECK(fixed.focal_mode == facet::FocalMode::kFixed);
  CHECK(fixed.fixed_focal_px == kFixedFocalPx);
  CHECK(fixed.camera_calibrated);
  CHECK(fixed.camera.focal_px == kFixedFocalPx);

  // (e) Undo restores the previous mode and camera.
  const facet::Image undone = SavedImage(dir / "undone.facet");
  CHECK(undone.focal_mode == facet::FocalMode::kSolve);
  CHECK(undone == original);

  const facet::Image free_image = SavedImage(dir / "free.facet");
  const double free_focal = free_image.camera.focal_px;
  const double prior_focal = 1.15 * free_focal;
  const double gap = prior_focal - free_focal;
  CAPTURE(free_focal);
  REQUIRE(std::abs(free_focal - kTrueFocalPx) < 0.05 * kTrueFocalPx);

  for (size_t k = 0; k < prior_stds.size(); ++k) {
    s << "command calibration focal prior " << prior_focal << " " << prior_stds[k] << "\nframes 1\n"
      << save("prior" + std::to_string(k) + ".facet");
  }
  s << "command calibration principal-point fixed " << fixed_pp.x() << " " << fixed_pp.y() << "\nframes 1\n"
    << save("pp.facet");
  s << "command calibration focal exif\nframes 1\n" << save("exif.facet");
  s << "command calibration distortion on\nframes 1\ncommand calibration distortion-lock off\nframes 1\n"
    << save("unlocked.facet");
  s << "command calibration horizon level 300\nframes 1\n" << save("level.facet");
  const Eigen::Vector4d horizon = TrueHorizon(scene.true_camera);
  s.precision(17);
  s << "command calibration horizon " << horizon[0] << " " << horizon[1] << " " << horizon[2] << " " << horizon[3]
    << "\nframes 1\n"
    << save("last.facet");
  s << "frames 3\n";
  const RunResult run = Render(dir, project_path, s.str(), "modes");
  INFO("stderr: " << run.stderr_text);
  REQUIRE(run.exit_code == 0);
  const nlohmann::json report = ReadJson(dir / "modes.json");

  // (b) The prior pulls: the distance to it shrinks with its std, from the free solution to
  // the prior's value.
  std::vector<double> focal;
  for (size_t k = 0; k < prior_stds.size(); ++k) {
    const facet::Image im = SavedImage(dir / ("prior" + std::to_string(k) + ".facet"));
    CHECK(im.focal_mode == facet::FocalMode::kPrior);
    CHECK(im.focal_prior_std_px == prior_stds[k]);
    focal.push_back(im.camera.focal_px);
    MESSAGE("prior " << prior_focal << " +- " << prior_stds[k] << " px: focal " << focal.back() << " px (free "
                     << free_focal << ")");
  }
  for (size_t k = 1; k < focal.size(); ++k) {
    CAPTURE(k);
    CHECK(std::abs(focal[k] - prior_focal) < std::abs(focal[k - 1] - prior_focal));
  }
  // A prior 100 times wider than the gap barely moves the result; one 1000 times tighter
  // than the segments' own uncertainty leaves it at the prior.
  CHECK(std::abs(focal.front() - free_focal) < 0.01 * gap);
  CHECK(std::abs(focal.back() - prior_focal) < 0.01 * gap);

  // (c) A fixed principal point is the camera's, exactly.
  const facet::Image pp = SavedImage(dir / "pp.facet");
  CHECK(pp.principal_point_mode == facet::PrincipalPointMode::kFixed);
  CHECK(pp.camera.principal_point_px == fixed_pp);
  REQUIRE((original.camera.principal_point_px - fixed_pp).norm() > 1.0);

  // The EXIF prior: 26 mm over the full frame's 43.27 mm diagonal on the image's diagonal,
  // with its std.
  const facet::Image exif = SavedImage(dir / "exif.facet");
  const double exif_focal =
      kExifFocal35mm / std::hypot(36.0, 24.0) * std::hypot(double(options.width_px), double(options.height_px));
  CHECK(exif.focal_mode == facet::FocalMode::kPrior);
  CHECK(std::abs(exif.focal_prior_px - exif_focal) <= kExifRelTolerance * exif_focal);
  facet::ExifFocal tags;
  tags.found = true;
  tags.focal_px = exif_focal;
  tags.focal_35mm_equivalent_mm = kExifFocal35mm;
  CHECK(std::abs(exif.focal_prior_std_px - facet::app::ExifFocalPriorStdPx(tags)) <= kExifRelTolerance * exif_focal);
  CHECK(report.at("log").dump().find("from EXIF (26 mm equivalent)") != std::string::npos);

  const facet::Image level = SavedImage(dir / "level.facet");
  CHECK(level.estimate_distortion);
  CHECK_FALSE(level.distortion_locked);
  CHECK(level.use_horizon);
  CHECK(level.horizon_px == Eigen::Vector4d(0, 300, options.width_px - 1, 300));
  // That level horizon contradicts the line families (the photo's runs from row 20 to 73): the
  // update fails by name and the box keeps its size, never 4e8 m wide (issue 14).
  const facet::Project level_project = facet::LoadProject(dir / "level.facet").project;
  const facet::Project unlocked_project = facet::LoadProject(dir / "unlocked.facet").project;
  REQUIRE(level_project.primitives.size() == 1);
  REQUIRE(unlocked_project.primitives.size() == 1);
  CHECK(level_project.primitives[0].shape.params == unlocked_project.primitives[0].shape.params);
  CHECK(report.at("log").dump().find("the model ran off to infinity") != std::string::npos);
  // Unlocking the distortion of this pinhole photo let the joint solve bend it past any lens
  // (k1 = 0.31, k2 = -3.0): refused by name, the camera keeps a distortion that maps the photo
  // one to one.
  const facet::Camera& unlocked_camera = unlocked_project.images[0].camera;
  CHECK(facet::WhyDistortionFolds(unlocked_camera.k1, unlocked_camera.k2, unlocked_camera.focal_px,
                                  unlocked_camera.principal_point_px, options.width_px, options.height_px) == "");
  CHECK(report.at("log").dump().find("folds the photo") != std::string::npos);
  const facet::Image last = SavedImage(dir / "last.facet");
  CHECK(last.use_horizon);
  CHECK(last.horizon_px == horizon);

  // Every command is one history entry: solve, 5 priors, principal point, EXIF, distortion,
  // lock, level horizon, horizon (the known focal was undone).
  const nlohmann::json& undo = report.at("undo_stack");
  INFO("undo stack: " << undo.dump());
  CHECK(undo.size() == 12);
  CHECK(undo.back() == "Horizon");

  // The properties panel with the calibration's details open, for a person to look at.
  const nlohmann::json& items = report.at("items");
  REQUIRE(items.contains("calibration.details"));
  const nlohmann::json& r = items.at("calibration.details");
  std::ostringstream shot;
  shot << s.str() << "click left " << r.at("x").get<double>() + 20 << " "
       << r.at("y").get<double>() + 0.5 * r.at("h").get<double>() << "\nframes 3\n";
  const RunResult panel = Render(dir, project_path, shot.str(), "panel");
  INFO("panel stderr: " << panel.stderr_text);
  REQUIRE(panel.exit_code == 0);
  CHECK(ReadJson(dir / "panel.json").at("items").contains("solve.geometry_node"));
  MESSAGE("properties panel: " << (dir / "panel.png"));
}

TEST_CASE("calibration focal exif on a photo without EXIF fails with a message") {
  TempDir dir("calgui_noexif");
  SyntheticScene scene = MakeBoxScene();
  scene.project.images[0].path = "photo.png";
  REQUIRE(cv::imwrite(dir / "photo.png", cv::Mat(768, 1024, CV_8UC3, cv::Scalar(100, 100, 100))));
  const std::string project_path = dir / "noexif.facet";
  REQUIRE(facet::SaveProject(scene.project, project_path) == "");
  const RunResult run = Render(dir, project_path, "frames 2\ncommand calibration focal exif\nframes 1\n", "noexif");
  INFO("stderr: " << run.stderr_text);
  CHECK(run.exit_code != 0);
  CHECK(run.stderr_text.find("No EXIF focal length") != std::string::npos);
}

TEST_CASE("one line family, a known focal length and the horizon give the camera's vertical") {
  TempDir dir("calgui_horizon");
  SyntheticSceneOptions options;
  options.principal_point_offset_px = Eigen::Vector2d::Zero();  // at the image centre
  SyntheticScene scene = MakeBoxScene(options);
  facet::Project& project = scene.project;
  // The x family alone: no pins, no model, an uncalibrated camera.
  std::vector<facet::Segment> x_only;
  for (const facet::Segment& seg : project.segments)
    if (seg.axis == facet::Axis::kX) x_only.push_back(seg);
  project.segments = x_only;
  project.pins.clear();
  project.primitives.clear();
  project.images[0].camera = facet::Camera();
  project.images[0].camera_calibrated = false;
  project.images[0].path = "photo.png";
  REQUIRE(
      cv::imwrite(dir / "photo.png", cv::Mat(options.height_px, options.width_px, CV_8UC3, cv::Scalar(80, 90, 100))));
  const std::string project_path = dir / "horizon.facet";
  REQUIRE(facet::SaveProject(project, project_path) == "");

  const facet::Camera& truth = scene.true_camera;
  const Eigen::Vector4d horizon = TrueHorizon(truth);
  const Eigen::Vector3d true_up = truth.cam_from_world_rotation.col(2);
  REQUIRE((facet::Camera().cam_from_world_rotation.col(2) - true_up).norm() > 0.1);

  std::ostringstream s;
  s.precision(17);
  s << "frames 2\ncommand calibration principal-point center\nframes 1\n";
  s << "command calibration focal fixed " << truth.focal_px << "\nframes 1\n";
  s << "command calibration horizon " << horizon[0] << " " << horizon[1] << " " << horizon[2] << " " << horizon[3]
    << "\nframes 2\n";
  s << "command save " << (dir / "solved.facet") << "\nframes 2\n";
  const RunResult run = Render(dir, project_path, s.str(), "horizon");
  INFO("stderr: " << run.stderr_text);
  REQUIRE(run.exit_code == 0);
  const nlohmann::json report = ReadJson(dir / "horizon.json");
  INFO("log: " << report.at("log").dump());
  const facet::Image solved = SavedImage(dir / "solved.facet");
  REQUIRE(solved.camera_calibrated);
  const Eigen::Vector3d up = solved.camera.cam_from_world_rotation.col(2);
  const double error = (up - true_up).norm();
  MESSAGE("vertical error " << error << " (x family, f known, horizon)");
  CHECK(error < kVerticalTolerance);
  CHECK(solved.camera.focal_px == truth.focal_px);
  CHECK(report.at("undo_stack").size() == 3);
}

TEST_CASE("overlay: an outlier segment is crossed out, the given horizon dashed across the image") {
  TempDir dir("calgui_overlay");
  SyntheticSceneOptions options;
  options.noise_px = 0.3;
  SyntheticScene scene = MakeBoxScene(options);
  facet::Project& project = scene.project;
  // A wrong click: the first x segment's end 25 px off its edge.
  facet::Segment& wrong = project.segments.at(0);
  REQUIRE(wrong.axis == facet::Axis::kX);
  const Eigen::Vector2d dir_ab = (wrong.b_px - wrong.a_px).normalized();
  wrong.b_px += 25.0 * Eigen::Vector2d(-dir_ab.y(), dir_ab.x());
  const Eigen::Vector2d wrong_mid = 0.5 * (wrong.a_px + wrong.b_px);
  project.images[0].path = "photo.png";
  REQUIRE(
      cv::imwrite(dir / "photo.png", cv::Mat(options.height_px, options.width_px, CV_8UC3, cv::Scalar(40, 40, 40))));
  const std::string project_path = dir / "overlay.facet";
  REQUIRE(facet::SaveProject(project, project_path) == "");
  constexpr double kRow = 60.0;  // above the box: nothing else is drawn there
  const RunResult run =
      Render(dir, project_path, "frames 2\ncommand calibration horizon level " + std::to_string(kRow) + "\nframes 3\n",
             "overlay");
  INFO("stderr: " << run.stderr_text);
  REQUIRE(run.exit_code == 0);
  const nlohmann::json report = ReadJson(dir / "overlay.json");
  const View view = ViewFromReport(report);
  const cv::Mat shot = cv::imread(dir / "overlay.png");
  REQUIRE(!shot.empty());
  auto count_color = [&](int x0, int y0, int x1, int y1, const std::array<int, 3>& rgb) {
    constexpr int kTolerance = 12;
    int n = 0;
    for (int y = std::max(0, y0); y <= std::min(shot.rows - 1, y1); ++y)
      for (int x = std::max(0, x0); x <= std::min(shot.cols - 1, x1); ++x) {
        const cv::Vec3b c = shot.at<cv::Vec3b>(y, x);
        n += std::abs(c[2] - rgb[0]) <= kTolerance && std::abs(c[1] - rgb[1]) <= kTolerance &&
             std::abs(c[0] - rgb[2]) <= kTolerance;
      }
    return n;
  };
  // The cross at the wrong segment's midpoint (app/panels/calibration_overlay.cpp colours).
  const Eigen::Vector2d m = view.ToScreen(wrong_mid);
  REQUIRE(view.Inside(m, 10.0));
  const int cross = count_color(int(m.x()) - 7, int(m.y()) - 7, int(m.x()) + 7, int(m.y()) + 7, {190, 190, 190});
  CAPTURE(cross);
  CHECK(cross >= 10);
  // The horizon: dashes (10 of every 16 px) along the row across the image's width.
  const Eigen::Vector2d left = view.ToScreen({0.0, kRow}), right = view.ToScreen({options.width_px - 1.0, kRow});
  const int dashes =
      count_color(int(left.x()) + 40, int(left.y()) - 1, int(right.x()) - 10, int(left.y()) + 1, {255, 160, 60});
  const int span = int(right.x()) - 10 - (int(left.x()) + 40);
  CAPTURE(dashes);
  CAPTURE(span);
  CHECK(dashes >= span / 2);  // 3 rows x 10/16 coverage, minus antialiased edges
  CHECK(dashes < 3 * span);
}

TEST_CASE("intrinsics locks from the script: focal and principal point unlocked for the joint solve, undo relocks") {
  TempDir dir("calgui_locks");
  SyntheticScene scene = MakeBoxScene(SyntheticSceneOptions());
  const std::string project = dir / "locks.facet";
  REQUIRE(facet::SaveProject(scene.project, project) == "");
  REQUIRE(scene.project.images[0].focal_locked);
  REQUIRE(scene.project.images[0].principal_point_locked);
  const RunResult run =
      Render(dir, project,
             "frames 2\ncommand calibration focal-lock off\nframes 1\n"
             "command calibration principal-point-lock off\nframes 1\ncommand save " +
                 (dir / "unlocked.facet") + "\ncommand undo\nframes 1\ncommand save " + (dir / "relocked.facet") + "\n",
             "locks");
  INFO(run.stderr_text);
  REQUIRE(run.exit_code == 0);
  const facet::Image unlocked = SavedImage(dir / "unlocked.facet");
  CHECK_FALSE(unlocked.focal_locked);
  CHECK_FALSE(unlocked.principal_point_locked);
  const facet::Image relocked = SavedImage(dir / "relocked.facet");
  CHECK_FALSE(relocked.focal_locked);  // undo takes back the last edit only
  CHECK(relocked.principal_point_locked);
  const bool error = run.stderr_text.find("unknown key") != std::string::npos;
  CHECK_FALSE(error);
}

TEST_CASE("same lens as other photos: the checkbox and `calibration lens-group N` set the group, undo takes it back") {
  TempDir dir("calgui_lens_group");
  SyntheticScene scene = MakeBoxScene(SyntheticSceneOptions());
  const std::string project = dir / "lens.facet";
  REQUIRE(facet::SaveProject(scene.project, project) == "");
  REQUIRE(scene.project.images[0].lens_group == 0);
  const RunResult probe = Render(dir, project, "frames 2\n", "lens_probe");
  INFO(probe.stderr_text);
  REQUIRE(probe.exit_code == 0);
  const nlohmann::json items = ReadJson(dir / "lens_probe.json").at("items");
  REQUIRE(items.contains("calibration.lens_group"));
  const auto save = [&](const std::string& name) { return "command save " + (dir / name) + "\nframes 1\n"; };
  const RunResult run =
      Render(dir, project,
             "frames 2\n" + save("before.facet") + "click left " + ItemCenter(items, "calibration.lens_group") +
                 "\nframes 2\n" + save("ticked.facet") + "command undo\nframes 1\n" + save("undone.facet") +
                 "command calibration lens-group 2\nframes 1\n" + save("group2.facet") +
                 "command calibration lens-group 0\nframes 1\n" + save("own.facet"),
             "lens");
  INFO(run.stderr_text);
  REQUIRE(run.exit_code == 0);
  CHECK(SavedImage(dir / "ticked.facet").lens_group == 1);
  const facet::Image undone = SavedImage(dir / "undone.facet");
  CHECK(undone.lens_group == 0);
  CHECK(undone == SavedImage(dir / "before.facet"));
  CHECK(SavedImage(dir / "group2.facet").lens_group == 2);
  CHECK(SavedImage(dir / "own.facet").lens_group == 0);
  const nlohmann::json undo = ReadJson(dir / "lens.json").at("undo_stack");
  INFO("undo stack: " << undo.dump());
  REQUIRE(undo.size() == 2);
  CHECK(undo[0] == "Share the lens");
  CHECK(undo[1] == "Own lens");
  // A group must be a whole number >= 0: the script stops with the usage.
  const RunResult bad = Render(dir, project, "frames 2\ncommand calibration lens-group 1.5\nframes 1\n", "lens_bad");
  CHECK(bad.exit_code != 0);
  CHECK(bad.stderr_text.find("calibration lens-group: expected N") != std::string::npos);
}
