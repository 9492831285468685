// File > Add photo in the real application offscreen (`command add-photo PATH`, app/state/add_photo.h):
// the photo becomes a new image with its size, a path relative to the saved project, an
// uncalibrated camera centred on the photo, and the focal prior of its EXIF when it has one;
// undo removes it; an unreadable file is refused with the reason and changes nothing. Then a
// second view takes part in the solve from its pins alone (resection, core/solve/multiview_init.h).
#include <doctest/doctest.h>

#include <string>

#include <opencv2/imgcodecs.hpp>

#include "core/io/project_io.h"
#include "core/solve/model_update.h"
#include "tests/app/app_test_util.h"
#include "tests/synthetic_scene.h"

using namespace facet::testing;

namespace {

constexpr char kWindowSize[] = "1280x800";
constexpr double kExactRelative = 1e-9;

RunResult Render(const TempDir& dir, const std::string& project, const std::string& script, const std::string& name) {
  WriteText(dir / (name + ".txt"), script);
  return RunRender(dir, "'" + project + "' -o '" + (dir / (name + ".png")) + "' --script '" + (dir / (name + ".txt")) +
                            "' --report '" + (dir / (name + ".json")) + "' --size " + kWindowSize);
}

facet::Project Load(const std::string& path) {
  const facet::ProjectLoadResult loaded = facet::LoadProject(path);
  INFO("loading " << path << ": " << loaded.error);
  REQUIRE(loaded.ok());
  return loaded.project;
}

}  // namespace

TEST_CASE("Add photo: a new uncalibrated image with its size and a relative path; undo; a corrupt file is refused") {
  TempDir dir("add_photo");
  SyntheticScene scene = MakeBoxScene(SyntheticSceneOptions());
  const std::string project = dir / "scene.facet";
  REQUIRE(facet::SaveProject(scene.project, project) == "");
  REQUIRE(cv::imwrite(dir / "second.png", cv::Mat(600, 800, CV_8UC3, cv::Scalar(60, 80, 100))));
  WriteText(dir / "broken.jpg", "not a photo");

  const RunResult added =
      Render(dir, project,
             "frames 2\ncommand add-photo " + (dir / "second.png") +
                 "\nframes 2\ncommand save\ncommand undo\nframes 2\ncommand save " + (dir / "undone.facet") + "\n",
             "add");
  INFO(added.stderr_text);
  REQUIRE(added.exit_code == 0);
  const facet::Project saved = Load(project);
  REQUIRE(saved.images.size() == 2);
  const facet::Image& image = saved.images[1];
  CHECK(image.path == "second.png");
  CHECK(image.width_px == 800);
  CHECK(image.height_px == 600);
  CHECK_FALSE(image.camera_calibrated);
  CHECK(image.focal_mode == facet::FocalMode::kSolve);  // a PNG carries no EXIF focal length
  CHECK(image.camera.principal_point_px.isApprox(Eigen::Vector2d(399.5, 299.5), kExactRelative));
  const nlohmann::json report = ReadJson(dir / "add.json");
  REQUIRE(report["redo_stack"].size() == 1);
  CHECK(report["redo_stack"][0].get<std::string>() == "Add photo second.png");

  // Undo (in the same session) took the photo out again; the broken file stops the script
  // with the reason.
  CHECK(Load(dir / "undone.facet").images.size() == 1);
  const RunResult broken =
      Render(dir, dir / "undone.facet", "frames 2\ncommand add-photo " + (dir / "broken.jpg") + "\n", "broken");
  CHECK(broken.exit_code != 0);
  CHECK(broken.stderr_text.find("broken.jpg") != std::string::npos);

  // A JPEG cut short keeps a valid header, so its size reads; Add photo decodes it first and
  // refuses it (issue 14: it was added and failed only when shown).
  std::vector<unsigned char> jpeg;
  REQUIRE(cv::imencode(".jpg", cv::Mat(600, 800, CV_8UC3, cv::Scalar(60, 80, 100)), jpeg));
  WriteText(dir / "cut.jpg", std::string(jpeg.begin(), jpeg.begin() + static_cast<long>(jpeg.size() / 2)));
  const RunResult cut = Render(dir, dir / "undone.facet",
                               "frames 2\ncommand add-photo " + (dir / "cut.jpg") + "\ncommand save " +
                                   (dir / "after_cut.facet") + "\n",
                               "cut");
  CHECK(cut.exit_code != 0);
  CHECK(cut.stderr_text.find("cut.jpg: JPEG is truncated") != std::string::npos);
}

TEST_CASE("Relink photo: a photo that moved is pointed at again; camera, pins and lines stay; undo; another photo is refused") {
  TempDir dir("relink_photo");
  SyntheticScene scene = MakeBoxScene(SyntheticSceneOptions());
  facet::Project& p = scene.project;
  p.images[0].path = "photos/shot.png";  // not there: the photo moved elsewhere
  const int width = p.images[0].width_px, height = p.images[0].height_px;
  const std::string project = dir / "scene.facet";
  REQUIRE(facet::SaveProject(p, project) == "");
  REQUIRE(cv::imwrite(dir / "shot_moved.png", cv::Mat(height, width, CV_8UC3, cv::Scalar(60, 80, 100))));
  REQUIRE(cv::imwrite(dir / "other.png", cv::Mat(height / 2, width, CV_8UC3, cv::Scalar(60, 80, 100))));

  // Another photo (another size) is refused with both sizes; nothing changes.
  const RunResult other =
      Render(dir, project, "frames 2\ncommand select-image 0\ncommand relink-photo " + (dir / "other.png") + "\n",
             "other");
  CHECK(other.exit_code != 0);
  CHECK(other.stderr_text.find("not the same photo") != std::string::npos);

  const RunResult relinked =
      Render(dir, project,
             "frames 2\ncommand select-image 0\ncommand relink-photo " + (dir / "shot_moved.png") +
                 "\nframes 2\ncommand save\ncommand undo\nframes 2\ncommand save " + (dir / "undone.facet") + "\n",
             "relink");
  INFO(relinked.stderr_text);
  REQUIRE(relinked.exit_code == 0);
  // The photo was missing when the project opened: said so, and its image kept everything.
  const nlohmann::json report = ReadJson(dir / "relink.json");
  REQUIRE(report["redo_stack"].size() == 1);
  CHECK(report["redo_stack"][0].get<std::string>() == "Relink photo shot_moved.png");
  const facet::Project saved = Load(project);
  CHECK(saved.images[0].path == "shot_moved.png");
  // The camera is the scene's (re-solved on open from its exact pins and lines: to 1e-9).
  const facet::Camera& camera = saved.images[0].camera;
  const facet::Camera& truth = p.images[0].camera;
  CHECK(std::abs(camera.focal_px - truth.focal_px) < kExactRelative * truth.focal_px);
  CHECK(camera.cam_from_world_rotation.isApprox(truth.cam_from_world_rotation, kExactRelative));
  CHECK(saved.pins == p.pins);
  CHECK(saved.segments == p.segments);
  CHECK(Load(dir / "undone.facet").images[0].path == "photos/shot.png");
}
