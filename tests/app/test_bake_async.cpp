// The texture bake in the real application offscreen (`facet render` with an input script
// and `bake-status` snapshots): off the main thread, an edit's frame returns with the new
// geometry and the bake still in flight, the result that arrives is bit-identical to a
// synchronous bake of the same project and photo, an edit made while a bake runs drops that
// bake's result, and a screenshot waits for the texture. The user's texture choices (issue
// 13): View > Texture sources with its legend, per-face and per-photo overrides as undoable
// edits, and the export resolution (File > Export and `facet export --texels-per-unit`).
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/image/image_io.h"
#include "core/io/project_io.h"
#include "core/texture/textured_mesh.h"
#include "tests/app/app_test_util.h"
#include "tests/synthetic_scene.h"
#include "tests/textured_scene.h"

using namespace facet::testing;

namespace {

// Deliberately large, so that a bake takes far longer than the frame that starts it.
constexpr int kPhotoWidthPx = 3072;
constexpr int kPhotoHeightPx = 2048;
// The frame that starts a bake (snapshot, untextured geometry, thread start) against the bake
// itself: a frame that waited for the bake would cost at least the bake.
constexpr double kMaxStartToBakeRatio = 0.25;

// Same fingerprint as the app's `bake-status` (FNV-1a, 64 bit, over the raw bytes).
template <typename T>
std::string Fingerprint(const std::vector<T>& values) {
  std::uint64_t hash = 14695981039346656037ull;
  const auto* p = reinterpret_cast<const unsigned char*>(values.data());
  for (size_t i = 0; i < values.size() * sizeof(T); ++i) hash = (hash ^ p[i]) * 1099511628211ull;
  char text[24];
  std::snprintf(text, sizeof(text), "%016llx", static_cast<unsigned long long>(hash));
  return text;
}

// A synchronous bake of a project the app saved, from the same photo file, compared with
// what the app showed.
void CheckMatchesSynchronousBake(const std::string& project_path, const std::string& photo_path,
                                 const nlohmann::json& status) {
  const facet::ProjectLoadResult loaded = facet::LoadProject(project_path);
  REQUIRE_MESSAGE(loaded.ok(), loaded.error);
  facet::ImageReadResult photo = facet::ReadImage(photo_path);
  REQUIRE_MESSAGE(photo.ok(), photo.error);
  REQUIRE(loaded.project.images.size() == 1);
  facet::TexturedMesh mesh;
  const facet::TextureBakeSummary summary =
      facet::BakeTexturedMesh(loaded.project, {&photo.image}, facet::TextureBakeOptions{}, &mesh);
  REQUIRE_MESSAGE(summary.IsUsable(), summary.message);
  REQUIRE(summary.faces_textured > 0);
  INFO("status: " << status.dump());
  CHECK(status.at("triangles").get<size_t>() == mesh.indices.size() / 3);
  CHECK(status.at("faces_textured").get<int>() == summary.faces_textured);
  CHECK(status.at("atlas_width").get<int>() == mesh.atlas.width);
  CHECK(status.at("atlas_height").get<int>() == mesh.atlas.height);
  CHECK(status.at("atlas_fnv").get<std::string>() == Fingerprint(mesh.atlas.pixels));
  CHECK(status.at("uvs_fnv").get<std::string>() == Fingerprint(mesh.uvs));
  CHECK(status.at("positions_fnv").get<std::string>() == Fingerprint(mesh.positions));
}

}  // namespace

TEST_CASE("texture bake in the background: the edit's frame does not wait, the result matches, a newer edit wins") {
  TempDir dir("bake_async");
  SyntheticSceneOptions options;
  options.width_px = kPhotoWidthPx;
  options.height_px = kPhotoHeightPx;
  options.focal_px *= static_cast<double>(kPhotoWidthPx) / 1024.0;
  SyntheticScene scene = MakeBoxScene(options);
  facet::Project project = scene.project;
  project.images[0].path = "photo.png";
  // A texture with detail everywhere, so that any texel out of place changes the atlas.
  cv::Mat photo(kPhotoHeightPx, kPhotoWidthPx, CV_8UC3);
  cv::randu(photo, cv::Scalar::all(0), cv::Scalar::all(256));
  REQUIRE(cv::imwrite(dir / "photo.png", photo));
  const std::string project_path = dir / "scene.facet";
  REQUIRE(facet::SaveProject(project, project_path) == "");

  std::ostringstream s;
  s << "frames 2\n";
  s << "command bake-status " << (dir / "s0.json") << "\n";
  // Edit 1 (a second box): its frame starts the bake; the next step looks before waiting.
  s << "command add box\n";
  s << "command bake-status " << (dir / "s1.json") << "\n";
  s << "command bake-status " << (dir / "s2.json") << "\n";
  s << "command save " << (dir / "after1.facet") << "\n";
  // Edit 2 starts a bake; edit 3 comes before it is collected, so its result is stale.
  s << "command add box\n";
  s << "command add box\n";
  s << "command bake-status " << (dir / "s3.json") << "\n";
  s << "command bake-status " << (dir / "s4.json") << "\n";
  s << "command save " << (dir / "after3.facet") << "\n";
  // A screenshot right after an edit shows the finished texture.
  s << "command add box\n";
  s << "screenshot " << (dir / "shot.png") << "\n";
  s << "command bake-status " << (dir / "s5.json") << "\n";
  WriteText(dir / "script.txt", s.str());
  const RunResult run = RunRender(dir, "'" + project_path + "' -o '" + (dir / "out.png") + "' --script '" +
                                           (dir / "script.txt") + "' --report '" + (dir / "report.json") + "'");
  INFO("stderr: " << run.stderr_text);
  REQUIRE(run.exit_code == 0);

  const nlohmann::json s0 = ReadJson(dir / "s0.json");
  const nlohmann::json s1 = ReadJson(dir / "s1.json");
  const nlohmann::json s2 = ReadJson(dir / "s2.json");
  const nlohmann::json s3 = ReadJson(dir / "s3.json");
  const nlohmann::json s4 = ReadJson(dir / "s4.json");
  const nlohmann::json s5 = ReadJson(dir / "s5.json");
  INFO("s0: " << s0.dump());
  INFO("s1: " << s1.dump());
  INFO("s2: " << s2.dump());

  // The opened project is baked and shown before the first edit.
  REQUIRE_FALSE(s0.at("in_flight").get<bool>());
  REQUIRE_FALSE(s0.at("texture_pending").get<bool>());
  REQUIRE(s0.at("faces_textured").get<int>() > 0);
  const size_t one_box_triangles = s0.at("triangles").get<size_t>();

  // After the edit's frame: the second box is in the mesh while its texture is still baking.
  CHECK(s1.at("in_flight").get<bool>());
  CHECK(s1.at("texture_pending").get<bool>());
  CHECK(s1.at("triangles").get<size_t>() == 2 * one_box_triangles);
  CHECK(s1.at("input_revision").get<std::uint64_t>() > s1.at("baked_input_revision").get<std::uint64_t>());
  CHECK(s1.at("started").get<int>() == s0.at("started").get<int>() + 1);
  // Issue 25: that frame said so in the 3D panel, in a row of its own above the counts and
  // mouse help (it was drawn over them), and the collected frame no longer does.
  {
    const nlohmann::json& texts = s1.at("viewport_texts");
    REQUIRE(texts.contains("viewport.help"));
    REQUIRE(texts.contains("viewport.bake_status"));
    const nlohmann::json& help = texts.at("viewport.help");
    const nlohmann::json& baking = texts.at("viewport.bake_status");
    const double help_top = help.at("y").get<double>();
    const double baking_bottom = baking.at("y").get<double>() + baking.at("h").get<double>();
    CHECK(baking_bottom <= help_top);  // no overlap: the status ends where the help begins, or above
    CHECK(baking.at("h").get<double>() > 0.0);
    CHECK_FALSE(s2.at("viewport_texts").contains("viewport.bake_status"));
  }
  // And that frame did not wait for it: starting costs a fraction of the bake.
  const double start_ms = s1.at("start_refresh_ms").get<double>();
  const double bake_ms = s2.at("bake_ms").get<double>();
  CAPTURE(start_ms);
  CAPTURE(bake_ms);
  CHECK(start_ms < kMaxStartToBakeRatio * bake_ms);

  // The next frame collected it: the texture of the edited project, as a synchronous bake.
  CHECK_FALSE(s2.at("in_flight").get<bool>());
  CHECK_FALSE(s2.at("texture_pending").get<bool>());
  CHECK(s2.at("collected").get<int>() == s1.at("collected").get<int>() + 1);
  CHECK(s2.at("dropped").get<int>() == 0);
  CHECK(s2.at("baked_input_revision") == s1.at("input_revision"));
  CheckMatchesSynchronousBake(dir / "after1.facet", dir / "photo.png", s2);

  // Edits 2 and 3: edit 2's bake was overtaken, dropped, and edit 3's baked instead.
  INFO("s3: " << s3.dump());
  INFO("s4: " << s4.dump());
  CHECK(s3.at("dropped").get<int>() == 1);
  CHECK(s3.at("collected").get<int>() == s2.at("collected").get<int>());
  CHECK(s3.at("in_flight").get<bool>());
  CHECK(s3.at("started").get<int>() == s2.at("started").get<int>() + 2);
  CHECK(s3.at("triangles").get<size_t>() == 4 * one_box_triangles);
  CHECK_FALSE(s4.at("in_flight").get<bool>());
  CHECK_FALSE(s4.at("texture_pending").get<bool>());
  CHECK(s4.at("collected").get<int>() == s3.at("collected").get<int>() + 1);
  CHECK(s4.at("baked_input_revision") == s3.at("input_revision"));
  CheckMatchesSynchronousBake(dir / "after3.facet", dir / "photo.png", s4);

  // The screenshot's frame finished the bake of the edit just before it.
  INFO("s5: " << s5.dump());
  CHECK_FALSE(s5.at("in_flight").get<bool>());
  CHECK_FALSE(s5.at("texture_pending").get<bool>());
  CHECK(s5.at("triangles").get<size_t>() == 5 * one_box_triangles);
  CHECK(s5.at("started").get<int>() == s4.at("started").get<int>() + 1);
}

namespace {

// Pixels of `shot` inside the 3D panel (the report's viewport) that show a source colour of
// View > Texture sources: saturated (> 0.55) and within 12 degrees of hue of a palette entry
// (the frustums' light blue and the grey of untextured faces are far less saturated).
int SourceTintedPixels(const cv::Mat& shot, const nlohmann::json& viewport, const std::vector<double>& hues_deg) {
  const int x0 = static_cast<int>(viewport.at("origin_x").get<double>());
  const int y0 = static_cast<int>(viewport.at("origin_y").get<double>());
  const int w = viewport.at("width_px").get<int>(), h = viewport.at("height_px").get<int>();
  cv::Mat hsv;
  cv::cvtColor(shot(cv::Rect(x0, y0, std::min(w, shot.cols - x0), std::min(h, shot.rows - y0))), hsv,
               cv::COLOR_BGR2HSV_FULL);
  int count = 0;
  for (int y = 0; y < hsv.rows; ++y) {
    for (int x = 0; x < hsv.cols; ++x) {
      const cv::Vec3b p = hsv.at<cv::Vec3b>(y, x);
      if (p[1] < 0.55 * 255 || p[2] < 40) continue;
      const double hue = p[0] * 360.0 / 256.0;
      for (double target : hues_deg) {
        const double d = std::abs(std::remainder(hue - target, 360.0));
        if (d < 12.0) {
          ++count;
          break;
        }
      }
    }
  }
  return count;
}

double HueDeg(const std::array<int, 3>& rgb) {
  cv::Mat one(1, 1, CV_8UC3, cv::Scalar(rgb[2], rgb[1], rgb[0]));
  cv::Mat hsv;
  cv::cvtColor(one, hsv, cv::COLOR_BGR2HSV_FULL);
  return hsv.at<cv::Vec3b>(0, 0)[0] * 360.0 / 256.0;
}

}  // namespace

TEST_CASE("the user's texture choices in the app: source colours and legend, overrides undoable, export resolution") {
  TempDir dir("texture_choices");
  // The box seen by two photos of different exposure (a uniform paint at gains 1 and 0.6):
  // photo 1 frontal to its -Y face, photo 2 frontal to its +X face.
  SyntheticScene scene = MakeBoxScene();
  facet::Project project = scene.project;
  project.segments.clear();  // nothing to re-calibrate: the cameras are the truth
  project.pins.clear();
  SyntheticSceneOptions o1, o2;
  o1.camera_center = {2.0, -11.0, 1.6};
  o1.look_at = {2.0, 0.0, 1.2};
  o2.camera_center = {14.0, -3.0, 3.0};
  o2.look_at = {4.0, 1.0, 1.2};
  project.images[0].camera = MakeLookAtCamera(o1);
  project.images[0].path = "photo1.png";
  facet::Image second = project.images[0];
  second.id = project.NewId();
  second.camera = MakeLookAtCamera(o2);
  second.path = "photo2.png";
  project.images.push_back(second);
  const std::vector<facet::testing::PaintedFace> faces = facet::testing::PaintedFaces(project);
  const facet::testing::Paint paint = [](const facet::testing::PaintedFace&, const Eigen::Vector3d&) {
    return Eigen::Vector3d(170, 150, 130);
  };
  for (int k = 0; k < 2; ++k) {
    const facet::ImageRgba8 photo =
        facet::testing::RenderTexturedPhoto(faces, project.images[k].camera, paint, k == 0 ? 1.0 : 0.6);
    REQUIRE(facet::WritePng(dir / project.images[k].path, photo).empty());
  }
  facet::FaceId front = facet::kNoFace, side = facet::kNoFace;
  const facet::PolyMesh& mesh = project.primitives[0].mesh;
  for (facet::FaceId f = 0; f < mesh.FaceIdEnd(); ++f) {
    if (!mesh.IsFace(f)) continue;
    const Eigen::Vector3d n = facet::FaceNormal(mesh, f);
    if ((n + Eigen::Vector3d::UnitY()).norm() < 1e-9) front = f;
    if ((n - Eigen::Vector3d::UnitX()).norm() < 1e-9) side = f;
  }
  REQUIRE(front != facet::kNoFace);
  REQUIRE(side != facet::kNoFace);
  const facet::Id box = project.primitives[0].id, image1 = project.images[0].id, image2 = project.images[1].id;
  const std::string project_path = dir / "scene.facet";
  REQUIRE(facet::SaveProject(project, project_path) == "");

  std::ostringstream s;
  s << "frames 2\ncommand wait-bake\n";
  s << "screenshot " << (dir / "plain.png") << "\n";
  s << "command texture sources on\n";
  s << "screenshot " << (dir / "sources.png") << "\n";
  s << "command save " << (dir / "s0.facet") << "\n";
  s << "command select face " << box << " " << front << "\n";
  s << "command texture source 1\n";
  s << "command save " << (dir / "s1.facet") << "\n";
  s << "command texture exclude 0 on\n";
  s << "command save " << (dir / "s2.facet") << "\n";
  s << "command texture use 1 off\n";
  s << "command save " << (dir / "s3.facet") << "\n";
  s << "command undo\ncommand save " << (dir / "u2.facet") << "\n";
  s << "command undo\ncommand save " << (dir / "u1.facet") << "\n";
  s << "command undo\ncommand save " << (dir / "u0.facet") << "\n";
  s << "command redo\ncommand redo\ncommand save " << (dir / "r2.facet") << "\n";
  s << "command redo\ncommand save " << (dir / "r3.facet") << "\n";
  s << "command undo\n";
  // The export dialog's resolution, then File > Export.
  s << "command texture export-resolution 50\n";
  s << "command export " << (dir / "model.obj") << "\n";
  s << "command wait-bake\n";
  s << "screenshot " << (dir / "forced.png") << "\n";
  const nlohmann::json report = RenderScript(dir, project_path, "choices", s.str());
  INFO("log:\n" << ReportLog(report));

  // Undo and redo restore the overrides exactly: the saved files are byte for byte the same.
  CHECK(ReadText(dir / "u2.facet") == ReadText(dir / "s2.facet"));
  CHECK(ReadText(dir / "u1.facet") == ReadText(dir / "s1.facet"));
  CHECK(ReadText(dir / "u0.facet") == ReadText(dir / "s0.facet"));
  CHECK(ReadText(dir / "r2.facet") == ReadText(dir / "s2.facet"));
  CHECK(ReadText(dir / "r3.facet") == ReadText(dir / "s3.facet"));
  const facet::Project s0 = LoadProjectFile(dir / "s0.facet");
  const facet::Project s1 = LoadProjectFile(dir / "s1.facet");
  const facet::Project s2 = LoadProjectFile(dir / "s2.facet");
  const facet::Project s3 = LoadProjectFile(dir / "s3.facet");
  CHECK(s0.primitives[0].face_textures.empty());
  REQUIRE(s1.primitives[0].face_textures.size() == 1);
  CHECK(s1.primitives[0].face_textures[0] == facet::FaceTextureOverride{front, image2, {}});
  REQUIRE(s2.primitives[0].face_textures.size() == 1);
  CHECK(s2.primitives[0].face_textures[0] == facet::FaceTextureOverride{front, image2, {image1}});
  CHECK(s2.images[1].use_for_texture);
  CHECK_FALSE(s3.images[1].use_for_texture);
  const std::vector<std::string> undo = report.at("undo_stack").get<std::vector<std::string>>();
  REQUIRE(undo.size() == 2);
  CHECK(undo[0].find("from photo 2") != std::string::npos);
  CHECK(undo[1].find("Exclude photo 1") != std::string::npos);

  // What the last bake reports (state s2): the front face from photo 2 alone, as forced,
  // photo 1 excluded there; the side face photo 2's; the legend names photo 2.
  const nlohmann::json& texture = report.at("texture");
  INFO("texture: " << texture.dump());
  CHECK(texture.at("show_sources").get<bool>());
  bool front_seen = false, side_seen = false;
  for (const nlohmann::json& f : texture.at("faces")) {
    if (f.at("primitive_id") != box) continue;
    if (f.at("face") == front) {
      front_seen = true;
      CHECK(f.at("forced_image") == image2);
      REQUIRE(f.at("sources").size() >= 1);
      CHECK(f.at("sources")[0].at("image_id") == image2);
      for (const nlohmann::json& source : f.at("sources")) CHECK(source.at("image_id") != image1);
    }
    if (f.at("face") == side) {
      side_seen = true;
      REQUIRE(f.at("sources").size() >= 1);
      CHECK(f.at("sources")[0].at("image_id") == image2);
    }
  }
  CHECK(front_seen);
  CHECK(side_seen);
  bool legend_names_photo2 = false;
  for (const nlohmann::json& row : texture.at("legend")) {
    legend_names_photo2 = legend_names_photo2 || row.at("label").get<std::string>().find("photo 2 (photo2.png)") == 0;
  }
  CHECK(legend_names_photo2);

  // The pictures: with the sources shown the faces carry the photos' colours (the swatches
  // of the legend too); without, none of them.
  const cv::Mat plain = cv::imread(dir / "plain.png");
  const cv::Mat sources = cv::imread(dir / "sources.png");
  REQUIRE_FALSE(plain.empty());
  REQUIRE_FALSE(sources.empty());
  std::vector<double> hues;
  for (const nlohmann::json& row : texture.at("legend")) {
    hues.push_back(
        HueDeg({row.at("colour")[0].get<int>(), row.at("colour")[1].get<int>(), row.at("colour")[2].get<int>()}));
  }
  hues.push_back(HueDeg({66, 133, 244}));  // photo 1's colour: the front face at the start
  const int tinted = SourceTintedPixels(sources, report.at("viewport"), hues);
  const int untinted = SourceTintedPixels(plain, report.at("viewport"), hues);
  MESSAGE("source-coloured pixels in the 3D panel: " << tinted << " shown, " << untinted << " hidden");
  constexpr int kMinTintedPixels = 3000;
  CHECK(tinted > kMinTintedPixels);
  CHECK(tinted > 10 * untinted);

  // The export at 50 texels per metre: the atlas a core bake of the project makes at that
  // resolution, not the one from the photos.
  const facet::Project exported_project = LoadProjectFile(dir / "s2.facet");
  std::vector<facet::ImageRgba8> photos;
  for (const facet::Image& image : exported_project.images) {
    facet::ImageReadResult read = facet::ReadImage(dir / image.path);
    REQUIRE_MESSAGE(read.ok(), read.error);
    photos.push_back(std::move(read.image));
  }
  facet::TextureBakeOptions at_50;
  at_50.texels_per_unit = 50.0;
  at_50.max_atlas_pages = 8;
  facet::TexturedMesh expected, from_photos;
  REQUIRE(facet::BakeTexturedMesh(exported_project, photos, at_50, &expected).IsUsable());
  REQUIRE(facet::BakeTexturedMesh(exported_project, photos, {}, &from_photos).IsUsable());
  const cv::Mat atlas = cv::imread(dir / "model.png", cv::IMREAD_UNCHANGED);
  REQUIRE_FALSE(atlas.empty());
  CHECK(atlas.cols == expected.atlas.width);
  CHECK(atlas.rows == expected.atlas.height);
  MESSAGE("export atlas at 50 texels/m: " << atlas.cols << " x " << atlas.rows << " (from the photos: "
                                          << from_photos.atlas.width << " x " << from_photos.atlas.height << ")");

  // `facet export --texels-per-unit` makes the same atlas.
  const CliResult cli =
      RunFacet(dir, "export '" + (dir / "s2.facet") + "' -o '" + (dir / "cli.obj") + "' --texels-per-unit 50");
  INFO("stderr: " << cli.err);
  REQUIRE(cli.exit_code == 0);
  const cv::Mat cli_atlas = cv::imread(dir / "cli.png", cv::IMREAD_UNCHANGED);
  REQUIRE_FALSE(cli_atlas.empty());
  CHECK(cli_atlas.cols == expected.atlas.width);
  CHECK(cli_atlas.rows == expected.atlas.height);
  CHECK(RunFacet(dir, "export '" + (dir / "s2.facet") + "' -o '" + (dir / "bad.obj") + "' --texels-per-unit -3")
            .exit_code != 0);
}

// Issue 13's legend with many photos: the colours used to repeat after 8 (a palette of 8),
// so photo 9 looked like photo 1. Twenty photos: photo 1 textures the box, the other 19 are
// taken out of texturing (so the legend lists them too); every one gets its own colour.
TEST_CASE("texture sources: twenty photos get twenty distinct colours in the legend, none grey or orange") {
  TempDir dir("texture_colours");
  SyntheticScene scene = MakeBoxScene();
  facet::Project project = scene.project;
  project.segments.clear();
  project.pins.clear();
  project.images[0].path = "photo1.png";
  const std::vector<facet::testing::PaintedFace> faces = facet::testing::PaintedFaces(project);
  const facet::testing::Paint paint = [](const facet::testing::PaintedFace&, const Eigen::Vector3d&) {
    return Eigen::Vector3d(170, 150, 130);
  };
  REQUIRE(
      facet::WritePng(dir / "photo1.png", facet::testing::RenderTexturedPhoto(faces, project.images[0].camera, paint))
          .empty());
  // The other photos: small grey files, uncalibrated, not used for texture.
  facet::ImageRgba8 grey;
  grey.width = 64;
  grey.height = 48;
  grey.pixels.assign(static_cast<size_t>(grey.width) * grey.height * 4, 128);
  constexpr int kPhotos = 20;
  for (int k = 1; k < kPhotos; ++k) {
    facet::Image image;
    image.id = project.NewId();
    image.path = "photo" + std::to_string(k + 1) + ".png";
    image.width_px = grey.width;
    image.height_px = grey.height;
    image.use_for_texture = false;
    REQUIRE(facet::WritePng(dir / image.path, grey).empty());
    project.images.push_back(image);
  }
  const std::string project_path = dir / "scene.facet";
  REQUIRE(facet::SaveProject(project, project_path).empty());
  const nlohmann::json report =
      RenderScript(dir, project_path, "colours", "frames 2\ncommand wait-bake\ncommand texture sources on\nframes 2\n");
  INFO("log:\n" << ReportLog(report));
  const nlohmann::json& legend = report.at("texture").at("legend");
  REQUIRE(legend.size() == kPhotos);

  std::vector<std::array<int, 3>> colours;
  for (size_t row = 0; row < legend.size(); ++row) {
    CAPTURE(row);
    CHECK(legend[row].at("image_index").get<size_t>() == row);
    CHECK(legend[row].at("used").get<bool>() == (row == 0));
    const std::array<int, 3> c = {legend[row].at("colour")[0].get<int>(), legend[row].at("colour")[1].get<int>(),
                                  legend[row].at("colour")[2].get<int>()};
    colours.push_back(c);
    // Not grey (untextured faces are): the channels spread over at least 100 levels.
    constexpr int kMinChroma = 100;
    CHECK(*std::max_element(c.begin(), c.end()) - *std::min_element(c.begin(), c.end()) >= kMinChroma);
    // Not the selection's orange (hue 29-34 deg): outside 15-50 deg (HueDeg steps 1.4 deg).
    const double hue = HueDeg(c);
    CAPTURE(hue);
    CHECK((hue < 15.0 || hue > 50.0));
  }
  CHECK(legend[0].at("faces").get<int>() > 0);            // photo 1 textures the box
  CHECK(colours[0] == std::array<int, 3>{66, 133, 244});  // photo 1 keeps its blue
  // Distinct: every two colours at least 30 levels apart (Euclidean, RGB); the nearest pair
  // is reported.
  constexpr double kMinColourDistance = 30.0;
  double nearest = 1e9;
  size_t nearest_a = 0, nearest_b = 0;
  for (size_t a = 0; a < colours.size(); ++a) {
    for (size_t b = a + 1; b < colours.size(); ++b) {
      const double d =
          std::hypot(colours[a][0] - colours[b][0], colours[a][1] - colours[b][1], colours[a][2] - colours[b][2]);
      if (d < nearest) {
        nearest = d;
        nearest_a = a;
        nearest_b = b;
      }
    }
  }
  CHECK(nearest >= kMinColourDistance);
  MESSAGE("20 photos' legend colours: the nearest two (photos " << nearest_a + 1 << " and " << nearest_b + 1 << ") are "
                                                                << nearest << " RGB levels apart");
}
