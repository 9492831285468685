// File > Cameras from all photos (app/state/colmap_cameras.h) in the real app, offscreen, with a
// stand-in colmap (tests/fake_colmap.h, named by FACET_COLMAP) whose mapper writes the model of
// a synthetic scene: four photos, three of them with cameras in the project, the reconstruction
// the same four cameras under a similarity (scale 0.37, a turn, a shift). The run is started,
// waited for and applied from the script (`command colmap ...`):
// - applied: ONE undoable edit; every camera equals the truth to 1e-9 (the fourth, which the
//   project had no camera for, placed too); the log names the photos, the alignment and the
//   log file; one undo gives the project back exactly;
// - cancelled while the stand-in's matcher sleeps (a picture of the progress window then):
//   the project is unchanged, nothing on the undo stack, within seconds;
// - FACET_COLMAP naming no program: the menu item is disabled with the install hint, a start
//   is refused with it, nothing changes;
// - `facet cameras` with the stand-in: the written cameras are the truth's, the JSON reports
//   the alignment.
#include <cstdlib>

#include "core/io/colmap_model_write.h"
#include "core/solve/colmap_alignment.h"
#include "tests/app/app_test_util.h"
#include "tests/fake_colmap.h"

using namespace facet;
using namespace facet::testing;

namespace {

constexpr double kExact = 1e-9;  // noise-free: rounding only, on a scene ~10 units across
constexpr int kPhotoWidth = 480, kPhotoHeight = 320;

Camera LookAt(const Eigen::Vector3d& center) {
  Camera camera;
  camera.width_px = kPhotoWidth;
  camera.height_px = kPhotoHeight;
  camera.focal_px = 420.0;
  camera.principal_point_px = Eigen::Vector2d(240.5, 159.0);
  camera.SetPose(CamFromWorldLookingAlong((Eigen::Vector3d(0.5, 0.0, 1.0) - center).normalized()), center);
  return camera;
}

// The truth: four photos (written as PNGs), their cameras calibrated.
Project TruthProject(const TempDir& dir) {
  fs::create_directories(dir / "photos");
  Project project;
  const std::vector<Eigen::Vector3d> centers = {
      {-6.0, -9.0, 1.6}, {1.0, -10.0, 2.4}, {8.0, -7.0, 1.2}, {3.0, -12.0, 3.0}};
  for (size_t i = 0; i < centers.size(); ++i) {
    cv::Mat photo(kPhotoHeight, kPhotoWidth, CV_8UC3, cv::Scalar(90 + 30 * i, 110, 140));
    cv::rectangle(photo, cv::Point(60 + 40 * i, 80), cv::Point(300, 240), cv::Scalar(40, 60, 200), -1);
    const std::string name = "p" + std::to_string(i) + ".png";
    REQUIRE(cv::imwrite((dir.path / "photos" / name).string(), photo));
    Image image;
    image.id = project.NewId();
    image.path = "photos/" + name;
    image.width_px = kPhotoWidth;
    image.height_px = kPhotoHeight;
    image.camera = LookAt(centers[i]);
    image.camera_calibrated = true;
    project.images.push_back(image);
  }
  return project;
}

// The truth as the reconstruction would have it (its own frame), written as a text model.
std::string WriteReconstruction(const TempDir& dir, const Project& truth) {
  SimilarityTransform reconstruction_from_project;
  reconstruction_from_project.scale = 0.37;
  reconstruction_from_project.rotation =
      Eigen::AngleAxisd(2.3, Eigen::Vector3d(0.4, -0.7, 0.2).normalized()).toRotationMatrix();
  reconstruction_from_project.translation = Eigen::Vector3d(3.0, -11.0, 4.5);
  Project moved = truth;
  for (Image& image : moved.images) TransformCamera(reconstruction_from_project, &image.camera);
  ColmapModel model;
  ColmapExportOptions options;
  options.include_points = false;
  REQUIRE(ColmapModelFromProject(moved, options, &model) == "");
  const std::string model_dir = dir / "truth_model";
  REQUIRE(WriteColmapModelText(model_dir, model) == "");
  return model_dir;
}

// The project the app opens: the truth without the fourth photo's camera.
std::string WriteStartProject(const TempDir& dir, const Project& truth) {
  Project project = truth;
  project.images[3].camera = Camera();
  project.images[3].camera_calibrated = false;
  const std::string path = dir / "scene.facet";
  REQUIRE(SaveProject(project, path) == "");
  return path;
}

bool LogHas(const nlohmann::json& report, const std::string& text) {
  return ReportLog(report).find(text) != std::string::npos;
}

// Pixels of ImGui's progress-bar fill (the dark style's PlotHistogram, RGB 230 179 0).
int ProgressFillPixels(const std::string& png) {
  const cv::Mat shot = cv::imread(png, cv::IMREAD_COLOR);
  REQUIRE(!shot.empty());
  int count = 0;
  for (int y = 0; y < shot.rows; ++y)
    for (int x = 0; x < shot.cols; ++x) {
      const cv::Vec3b bgr = shot.at<cv::Vec3b>(y, x);
      count += std::abs(bgr[2] - 230) < 12 && std::abs(bgr[1] - 179) < 12 && bgr[0] < 20;
    }
  return count;
}

}  // namespace

TEST_CASE("Cameras from all photos: applied and aligned as one edit, one undo restores the project exactly") {
  TempDir dir("colmap_applied");
  const Project truth = TruthProject(dir);
  FakeColmapOptions fake;
  fake.model_dir = WriteReconstruction(dir, truth);
  ::setenv("FACET_COLMAP", WriteFakeColmap(dir / "fake-colmap", fake).c_str(), 1);
  const std::string project_path = WriteStartProject(dir, truth);
  const Project start = LoadProjectFile(project_path);

  const nlohmann::json report = RenderScript(dir, project_path, "applied",
                                             "command colmap start\n"
                                             "frames 2\n"
                                             "command colmap wait\n"
                                             "frames 2\n"
                                             "command save " +
                                                 (dir / "after.facet") +
                                                 "\n"
                                                 "command undo\n"
                                                 "frames 2\n"
                                                 "command save " +
                                                 (dir / "undone.facet") + "\n");
  INFO("log:\n" << ReportLog(report));
  const nlohmann::json& colmap = report.at("colmap");
  CHECK(colmap.at("applied") == 1);
  CHECK(colmap.at("in_flight") == false);
  CHECK(colmap.at("working_dir") == (dir / "scene.colmap"));  // beside the project
  CHECK(fs::exists(dir.path / "scene.colmap" / "colmap.log"));
  CHECK(colmap.at("alignment").at("message") ==
        "rotation: 3 cameras in common; scale: 3 camera centres; position: 3 camera centres");
  CHECK(LogHas(report, "COLMAP placed 4 of 4 photos in "));
  CHECK(LogHas(report, "p0.png, p1.png, p2.png, p3.png"));
  CHECK(LogHas(report, "Cameras aligned to the project: rotation: 3 cameras in common"));
  CHECK(LogHas(report, "COLMAP's log: " + (dir.path / "scene.colmap" / "colmap.log").string()));
  CHECK(report.at("redo_stack").size() == 1);  // the one edit, undone
  CHECK(report.at("redo_stack")[0] == "Cameras from COLMAP (4 photos)");
  CHECK(report.at("undo_stack").empty());

  const Project after = LoadProjectFile(dir / "after.facet");
  REQUIRE(after.images.size() == truth.images.size());
  for (size_t i = 0; i < truth.images.size(); ++i) {
    const Camera& got = after.images[i].camera;
    const Camera& want = truth.images[i].camera;
    INFO(truth.images[i].path);
    CHECK(after.images[i].camera_calibrated);
    CHECK((got.CenterInWorld() - want.CenterInWorld()).norm() < kExact);
    CHECK((got.cam_from_world_rotation - want.cam_from_world_rotation).norm() < kExact);
    CHECK(std::abs(got.focal_px - want.focal_px) < kExact * want.focal_px);
  }
  CHECK(LoadProjectFile(dir / "undone.facet") == start);
}

TEST_CASE("Cameras from all photos: a cancelled run leaves the project unchanged; the progress window mid-run") {
  TempDir dir("colmap_cancel");
  const Project truth = TruthProject(dir);
  FakeColmapOptions fake;
  fake.model_dir = WriteReconstruction(dir, truth);
  fake.slow_stage = "exhaustive_matcher";
  fake.sleep_s = 60.0;
  ::setenv("FACET_COLMAP", WriteFakeColmap(dir / "fake-colmap", fake).c_str(), 1);
  const std::string project_path = WriteStartProject(dir, truth);
  const Project start = LoadProjectFile(project_path);

  const auto begin = std::chrono::steady_clock::now();
  const nlohmann::json report = RenderScript(dir, project_path, "cancel",
                                             "command colmap start\n"
                                             "command colmap wait-stage matching\n"
                                             "frames 3\n"
                                             "screenshot " +
                                                 (dir / "progress.png") +
                                                 "\n"
                                                 "command colmap cancel\n"
                                                 "command colmap wait\n"
                                                 "frames 2\n"
                                                 "command save " +
                                                 (dir / "cancelled.facet") + "\n");
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
  INFO("log:\n" << ReportLog(report));
  CHECK(seconds < 30.0);  // the 60 s matcher was ended, not waited for
  CHECK(report.at("colmap").at("cancelled") == 1);
  CHECK(report.at("colmap").at("applied") == 0);
  CHECK(LogHas(report, "COLMAP cancelled during matching; nothing was changed"));
  CHECK(report.at("undo_stack").empty());
  CHECK(LoadProjectFile(dir / "cancelled.facet") == start);
  // The progress window was drawn with its bar a third full (matching, 2 of 3).
  const int fill = ProgressFillPixels(dir / "progress.png");
  MESSAGE("progress fill pixels: " << fill << " (" << (dir / "progress.png") << ")");
  CHECK(fill > 500);
  CHECK(ProgressFillPixels(dir / "cancel.png") == 0);  // gone after the cancel
}

TEST_CASE("Cameras from all photos without colmap: the item is disabled with the install hint; nothing changes") {
  TempDir dir("colmap_missing");
  const Project truth = TruthProject(dir);
  ::setenv("FACET_COLMAP", "/nonexistent/colmap", 1);
  const std::string project_path = WriteStartProject(dir, truth);
  const Project start = LoadProjectFile(project_path);

  // The File menu open, the pointer on the item: a click does nothing, the tooltip gives the hint.
  const nlohmann::json report = RenderScript(dir, project_path, "missing",
                                             "click left item menu.file\n"
                                             "frames 2\n"
                                             "click left item menu.colmap_cameras\n"
                                             "frames 3\n"
                                             "command save " +
                                                 (dir / "unchanged.facet") + "\n");
  CHECK(report.at("colmap").at("available") == false);
  CHECK(report.at("colmap").at("executable") == "/nonexistent/colmap");
  CHECK(report.at("colmap").at("window_open") == false);
  CHECK(report.at("colmap").at("started") == 0);
  CHECK(report.at("undo_stack").empty());
  CHECK(LoadProjectFile(dir / "unchanged.facet") == start);

  const std::string refused = RenderScriptRefused(dir, project_path, "start", "command colmap start\n");
  CHECK(refused.find("apt-get install colmap") != std::string::npos);
  CHECK(refused.find("/nonexistent/colmap") != std::string::npos);
}

TEST_CASE("facet cameras with the stand-in colmap: the cameras aligned into the project's frame, the JSON says how") {
  TempDir dir("colmap_cli");
  const Project truth = TruthProject(dir);
  FakeColmapOptions fake;
  fake.model_dir = WriteReconstruction(dir, truth);
  const std::string colmap = WriteFakeColmap(dir / "fake-colmap", fake);
  const std::string project_path = WriteStartProject(dir, truth);
  const CliResult run =
      RunFacet(dir, "cameras '" + project_path + "' -o '" + (dir / "out.facet") + "' --colmap '" + colmap + "'");
  INFO("stderr: " << run.err);
  REQUIRE(run.exit_code == 0);
  const nlohmann::json out = nlohmann::json::parse(run.out);
  CHECK(out.at("num_registered") == 4);
  const nlohmann::json& alignment = out.at("alignment");
  CHECK(alignment.at("message") ==
        "rotation: 3 cameras in common; scale: 3 camera centres; position: 3 camera centres");
  CHECK(alignment.at("rotation").at("source") == "cameras in common");
  CHECK(std::abs(alignment.at("project_from_reconstruction").at("scale").get<double>() - 1.0 / 0.37) < kExact);
  CHECK(alignment.at("center_rms").get<double>() < kExact);
  CHECK(run.err.find("aligned to the project: rotation: 3 cameras in common") != std::string::npos);
  const Project written = LoadProjectFile(dir / "out.facet");
  for (size_t i = 0; i < truth.images.size(); ++i) {
    INFO(truth.images[i].path);
    CHECK((written.images[i].camera.CenterInWorld() - truth.images[i].camera.CenterInWorld()).norm() < kExact);
    CHECK((written.images[i].camera.cam_from_world_rotation - truth.images[i].camera.cam_from_world_rotation).norm() <
          kExact);
  }
}
