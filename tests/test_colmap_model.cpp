// COLMAP models (core/io/colmap_*.h): a synthetic scene photographed by known cameras goes out
// as a text model and comes back to 1e-9; the binary reader equals the text reader on the same
// model; the pixel convention (COLMAP's first pixel centre at (0.5, 0.5)) is applied once;
// camera models are mapped exactly or refused by name; broken models are refused with a
// message naming what is wrong; the import into a project matches photos by file name and
// applies all or nothing.
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/io/colmap_camera.h"
#include "core/io/colmap_import.h"
#include "core/io/colmap_model.h"
#include "core/io/colmap_model_write.h"
#include "tests/colmap_binary_writer.h"
#include "tests/synthetic_scene.h"

namespace fs = std::filesystem;
using namespace facet;
using namespace facet::testing;

namespace {

constexpr double kExact = 1e-9;

fs::path TempDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("facet_test_colmap_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

void WriteBytes(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out << bytes;
}

// The synthetic box scene photographed by three cameras: the first MakeBoxScene's, two more
// from other sides, one with radial distortion k1 and one with k1, k2; each photo pins all
// eight corners.
Project ThreeCameraScene() {
  SyntheticScene scene = MakeBoxScene();
  Project project = scene.project;
  project.images[0].path = "photos/IMG_0001.JPG";
  const std::array<Eigen::Vector3d, 2> centers = {Eigen::Vector3d(-6.0, -8.0, 3.0), Eigen::Vector3d(10.0, 9.0, 7.0)};
  for (int k = 0; k < 2; ++k) {
    SyntheticSceneOptions o;
    o.camera_center = centers[k];
    o.focal_px = 750.0 + 200.0 * k;
    o.roll_deg = -2.0 + 5.0 * k;
    Image image = project.images[0];
    image.id = project.NewId();
    image.path = "photos/IMG_000" + std::to_string(k + 2) + ".JPG";
    image.camera = MakeLookAtCamera(o);
    image.camera.k1 = -0.08 + 0.05 * k;
    image.camera.k2 = k == 1 ? 0.013 : 0.0;
    project.images.push_back(image);
    for (VertexId v = 0; v < 8; ++v) {
      Pin pin;
      pin.id = project.NewId();
      pin.image_id = image.id;
      pin.vertex = {scene.box_id, v};
      pin.uv_px = image.camera.Project(scene.true_box.mesh.vertex(v).position);
      project.pins.push_back(pin);
    }
  }
  return project;
}

void CheckModelsEqual(const ColmapModel& a, const ColmapModel& b) {
  REQUIRE(a.cameras.size() == b.cameras.size());
  for (size_t i = 0; i < a.cameras.size(); ++i) {
    CHECK(a.cameras[i].camera_id == b.cameras[i].camera_id);
    CHECK(a.cameras[i].model == b.cameras[i].model);
    CHECK(a.cameras[i].width_px == b.cameras[i].width_px);
    CHECK(a.cameras[i].height_px == b.cameras[i].height_px);
    CHECK(a.cameras[i].params == b.cameras[i].params);
  }
  REQUIRE(a.images.size() == b.images.size());
  for (size_t i = 0; i < a.images.size(); ++i) {
    const ColmapImage& x = a.images[i];
    const ColmapImage& y = b.images[i];
    CHECK(x.image_id == y.image_id);
    CHECK(x.camera_id == y.camera_id);
    CHECK(x.name == y.name);
    CHECK(x.cam_from_world_rotation.coeffs() == y.cam_from_world_rotation.coeffs());
    CHECK(x.cam_from_world_translation == y.cam_from_world_translation);
    REQUIRE(x.points2d.size() == y.points2d.size());
    for (size_t k = 0; k < x.points2d.size(); ++k) {
      CHECK(x.points2d[k].xy_px == y.points2d[k].xy_px);
      CHECK(x.points2d[k].point3d_id == y.points2d[k].point3d_id);
    }
  }
  REQUIRE(a.points3d.size() == b.points3d.size());
  for (size_t i = 0; i < a.points3d.size(); ++i) {
    const ColmapPoint3D& x = a.points3d[i];
    const ColmapPoint3D& y = b.points3d[i];
    CHECK(x.point3d_id == y.point3d_id);
    CHECK(x.position == y.position);
    CHECK(x.error_px == y.error_px);
    CHECK(std::equal(x.rgb, x.rgb + 3, y.rgb));
    REQUIRE(x.track.size() == y.track.size());
    for (size_t k = 0; k < x.track.size(); ++k) {
      CHECK(x.track[k].image_id == y.track[k].image_id);
      CHECK(x.track[k].point2d_index == y.track[k].point2d_index);
    }
  }
}

// A model written as text from ThreeCameraScene, and that scene.
struct WrittenModel {
  Project project;
  fs::path dir;
};
WrittenModel WriteThreeCameraScene(const std::string& name) {
  WrittenModel w{ThreeCameraScene(), TempDir(name)};
  ColmapModel model;
  REQUIRE(ColmapModelFromProject(w.project, {}, &model).empty());
  REQUIRE(WriteColmapModelText(w.dir.string(), model).empty());
  return w;
}

}  // namespace

TEST_CASE("a synthetic scene written as a COLMAP text model reads back to 1e-9: cameras, poses, points, pins") {
  const WrittenModel w = WriteThreeCameraScene("roundtrip");
  ColmapModel model;
  REQUIRE_MESSAGE(ReadColmapModel(w.dir.string(), &model) == "", "");
  REQUIRE(model.images.size() == 3);
  REQUIRE(model.cameras.size() == 3);
  // The camera models chosen so that the lens reads back exactly.
  CHECK(model.cameras[0].model == ColmapCameraModel::kSimplePinhole);
  CHECK(model.cameras[1].model == ColmapCameraModel::kSimpleRadial);
  CHECK(model.cameras[2].model == ColmapCameraModel::kRadial);

  // Into a copy of the project whose cameras are all wrong: the import restores each.
  Project imported = w.project;
  for (Image& image : imported.images) {
    image.camera.focal_px = 123.0;
    image.camera.k1 = image.camera.k2 = 0.0;
    image.camera.SetPose(Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero());
  }
  ColmapImportReport report;
  REQUIRE(ApplyColmapCameras(model, &imported, &report) == "");
  CHECK(report.updated_images.size() == 3);
  CHECK(report.missing_photos.empty());
  CHECK(report.unused_images.empty());
  for (size_t i = 0; i < 3; ++i) {
    const Camera& truth = w.project.images[i].camera;
    const Camera& got = imported.images[i].camera;
    CAPTURE(i);
    CHECK(got.width_px == truth.width_px);
    CHECK(got.height_px == truth.height_px);
    CHECK(std::abs(got.focal_px - truth.focal_px) < kExact);
    CHECK((got.principal_point_px - truth.principal_point_px).norm() < kExact);
    CHECK(std::abs(got.k1 - truth.k1) < kExact);
    CHECK(std::abs(got.k2 - truth.k2) < kExact);
    CHECK((got.cam_from_world_rotation - truth.cam_from_world_rotation).norm() < kExact);
    CHECK((got.cam_from_world_translation - truth.cam_from_world_translation).norm() < kExact);
  }

  // Points: the box's eight corners, each seen by the three photos at its pins (in Facet's
  // pixels after the half-pixel shift), and the error COLMAP-style (mean reprojection) ~ 0.
  REQUIRE(model.points3d.size() == 8);
  for (const ColmapPoint3D& point : model.points3d) {
    CHECK((point.position - w.project.primitives[0].mesh.vertex(point.point3d_id - 1).position).norm() < kExact);
    REQUIRE(point.track.size() == 3);
    CHECK(point.error_px < 1e-9);
    for (const ColmapTrackElement& element : point.track) {
      const ColmapImage* image = model.FindImage(element.image_id);
      REQUIRE(image);
      const ColmapPoint2D& seen = image->points2d.at(element.point2d_index);
      CHECK(seen.point3d_id == point.point3d_id);
      const Camera& camera = w.project.FindImage(element.image_id)->camera;
      CHECK((FacetPixelFromColmap(seen.xy_px) - camera.Project(point.position)).norm() < 1e-6);
    }
  }
}

TEST_CASE("the binary reader equals the text reader on the same model") {
  const WrittenModel w = WriteThreeCameraScene("binary");
  ColmapModel text;
  REQUIRE(ReadColmapModelText(w.dir.string(), &text) == "");
  WriteBytes(w.dir / "cameras.bin", ColmapCamerasBinary(text));
  WriteBytes(w.dir / "images.bin", ColmapImagesBinary(text));
  WriteBytes(w.dir / "points3D.bin", ColmapPoints3DBinary(text));
  ColmapModel binary;
  REQUIRE(ReadColmapModelBinary(w.dir.string(), &binary) == "");
  CheckModelsEqual(text, binary);
  // ReadColmapModel prefers the binary files when both are there; same model either way.
  ColmapModel preferred;
  REQUIRE(ReadColmapModel(w.dir.string(), &preferred) == "");
  CheckModelsEqual(text, preferred);
}

TEST_CASE("COLMAP's pixel centres are Facet's plus half a pixel, applied once") {
  // A 640 x 480 SIMPLE_PINHOLE camera with COLMAP's principal point at the image centre
  // (320, 240) has Facet's at (319.5, 239.5), the centre of pixels 0..639.
  ColmapCamera colmap{7, ColmapCameraModel::kSimplePinhole, 640, 480, {500.0, 320.0, 240.0}};
  Camera camera;
  REQUIRE(FacetIntrinsicsFromColmap(colmap, &camera) == "");
  CHECK(camera.principal_point_px.x() == doctest::Approx(319.5).epsilon(1e-15));
  CHECK(camera.principal_point_px.y() == doctest::Approx(239.5).epsilon(1e-15));
  // A point projected by COLMAP's formula (u = f X / Z + cx in its pixels) lands on Facet's
  // projection plus (0.5, 0.5).
  const Eigen::Vector3d p(0.3, -0.2, 2.0);
  const Eigen::Vector2d colmap_uv(500.0 * p.x() / p.z() + 320.0, 500.0 * p.y() / p.z() + 240.0);
  CHECK((ColmapPixelFromFacet(camera.Project(p)) - colmap_uv).norm() < 1e-12);
  // And back: Facet's camera out is COLMAP's again.
  const ColmapCamera back = ColmapCameraFromFacet(camera, 7);
  CHECK(back.model == ColmapCameraModel::kSimplePinhole);
  CHECK(back.params == colmap.params);
}

TEST_CASE("camera models: the five that match Facet's are mapped exactly, the others refused by name") {
  Camera camera;
  SUBCASE("PINHOLE with square pixels") {
    REQUIRE(FacetIntrinsicsFromColmap({1, ColmapCameraModel::kPinhole, 100, 80, {90.0, 90.0, 50.0, 40.0}}, &camera) ==
            "");
    CHECK(camera.focal_px == 90.0);
    CHECK(camera.principal_point_px == Eigen::Vector2d(49.5, 39.5));
    CHECK(!camera.HasDistortion());
  }
  SUBCASE("RADIAL") {
    REQUIRE(FacetIntrinsicsFromColmap({1, ColmapCameraModel::kRadial, 100, 80, {90.0, 50.0, 40.0, -0.1, 0.02}},
                                      &camera) == "");
    CHECK(camera.k1 == -0.1);
    CHECK(camera.k2 == 0.02);
  }
  SUBCASE("OPENCV without tangential distortion") {
    REQUIRE(FacetIntrinsicsFromColmap(
                {1, ColmapCameraModel::kOpenCv, 100, 80, {90.0, 90.0, 50.0, 40.0, -0.1, 0.02, 0.0, 0.0}}, &camera) ==
            "");
    CHECK(camera.focal_px == 90.0);
    CHECK(camera.k1 == -0.1);
    CHECK(camera.k2 == 0.02);
  }
  SUBCASE("refusals") {
    const Camera before = camera;
    const std::string fx_fy =
        FacetIntrinsicsFromColmap({3, ColmapCameraModel::kPinhole, 100, 80, {90.0, 91.0, 50.0, 40.0}}, &camera);
    CHECK(fx_fy.find("PINHOLE camera 3") != std::string::npos);
    CHECK(fx_fy.find("square pixels") != std::string::npos);
    const std::string tangential = FacetIntrinsicsFromColmap(
        {4, ColmapCameraModel::kOpenCv, 100, 80, {90.0, 90.0, 50.0, 40.0, -0.1, 0.02, 0.001, 0.0}}, &camera);
    CHECK(tangential.find("OPENCV camera 4") != std::string::npos);
    CHECK(tangential.find("tangential") != std::string::npos);
    const std::string fisheye = FacetIntrinsicsFromColmap(
        {5, ColmapCameraModel::kOpenCvFisheye, 100, 80, {90.0, 90.0, 50.0, 40.0, 0.1, 0.0, 0.0, 0.0}}, &camera);
    CHECK(fisheye.find("OPENCV_FISHEYE camera 5") != std::string::npos);
    const std::string fov =
        FacetIntrinsicsFromColmap({6, ColmapCameraModel::kFov, 100, 80, {90.0, 90.0, 50.0, 40.0, 0.5}}, &camera);
    CHECK(fov.find("FOV camera 6") != std::string::npos);
    CHECK(camera == before);
  }
}

TEST_CASE("broken text models are refused with the file, the line and what is wrong") {
  const WrittenModel w = WriteThreeCameraScene("broken_text");
  ColmapModel model;
  auto read_with = [&](const char* file, const std::string& text) {
    const fs::path dir = TempDir(std::string("broken_text_case"));
    for (const char* name : {"cameras.txt", "images.txt", "points3D.txt"}) fs::copy_file(w.dir / name, dir / name);
    WriteBytes(dir / file, text);
    const std::string error = ReadColmapModel(dir.string(), &model);
    CHECK(model.images.empty());  // nothing half-read
    return error;
  };
  CHECK(read_with("cameras.txt", "1 FISHEYE_X 640 480 1 2 3\n").find("unknown camera model \"FISHEYE_X\"") !=
        std::string::npos);
  CHECK(read_with("cameras.txt", "# c\n1 SIMPLE_PINHOLE 640 480 500 320\n").find("cameras.txt, line 2") !=
        std::string::npos);
  CHECK(read_with("cameras.txt", "1 SIMPLE_PINHOLE 640 480 nan 320 240\n").find("bad parameter \"nan\"") !=
        std::string::npos);
  // Image 1's camera (id 1) is no longer there.
  CHECK(read_with("cameras.txt", "99 SIMPLE_PINHOLE 640 480 500 320 240\n").find("refers to camera") !=
        std::string::npos);
  CHECK(read_with("images.txt", "1 1 0 0 0 0 0 0 1 a.jpg\n1 2\n").find("triples") != std::string::npos);
  CHECK(read_with("images.txt", "1 0 0 0 0 0 0 0 1 a.jpg\n\n").find("unit length") != std::string::npos);
  CHECK(read_with("points3D.txt", "1 0 0 0 1 2 3 0.5 1 99\n").find("names 2D point 99") != std::string::npos);
  CHECK(read_with("points3D.txt", "1 0 0 0 1 2 300 0.5\n").find("bad colour") != std::string::npos);

  const std::string missing = ReadColmapModel(TempDir("missing").string(), &model);
  CHECK(missing.find("neither cameras.bin") != std::string::npos);
  CHECK(ReadColmapModelText(TempDir("missing").string(), &model).find("cameras.txt not found") != std::string::npos);
}

TEST_CASE("broken binary models: every truncation, oversized counts and unknown model ids are refused") {
  const WrittenModel w = WriteThreeCameraScene("broken_binary");
  ColmapModel text;
  REQUIRE(ReadColmapModelText(w.dir.string(), &text) == "");
  const std::string cameras = ColmapCamerasBinary(text);
  const std::string images = ColmapImagesBinary(text);
  const std::string points = ColmapPoints3DBinary(text);
  std::vector<ColmapCamera> parsed_cameras;
  std::vector<ColmapImage> parsed_images;
  std::vector<ColmapPoint3D> parsed_points;
  // Every proper prefix of each file is refused (and names the file); the whole file is read.
  for (size_t n = 0; n < cameras.size(); ++n)
    CHECK(ParseColmapCamerasBinary(cameras.substr(0, n), "cameras.bin", &parsed_cameras).find("cameras.bin") == 0);
  for (size_t n = 0; n < images.size(); ++n)
    CHECK(ParseColmapImagesBinary(images.substr(0, n), "images.bin", &parsed_images).find("images.bin") == 0);
  for (size_t n = 0; n < points.size(); ++n)
    CHECK(ParseColmapPoints3DBinary(points.substr(0, n), "points3D.bin", &parsed_points).find("points3D.bin") == 0);
  CHECK(ParseColmapCamerasBinary(cameras, "cameras.bin", &parsed_cameras) == "");
  CHECK(ParseColmapImagesBinary(images, "images.bin", &parsed_images) == "");
  CHECK(ParseColmapPoints3DBinary(points, "points3D.bin", &parsed_points) == "");
  // A trailing byte is refused too.
  CHECK(ParseColmapCamerasBinary(cameras + "x", "cameras.bin", &parsed_cameras).find("unexpected bytes") !=
        std::string::npos);

  // A count of 2^40 cameras in a file of a hundred bytes: refused before any allocation.
  std::string huge = cameras;
  const std::uint64_t count = 1ull << 40;
  std::memcpy(huge.data(), &count, sizeof count);
  CHECK(ParseColmapCamerasBinary(huge, "cameras.bin", &parsed_cameras).find("more than the file can hold") !=
        std::string::npos);
  // The first image's 2D point count made huge (it sits after id, pose, camera id and name).
  std::string huge_points = images;
  const size_t at = 8 + 4 + 7 * 8 + 4 + text.images[0].name.size() + 1;
  std::memcpy(huge_points.data() + at, &count, sizeof count);
  CHECK(ParseColmapImagesBinary(huge_points, "images.bin", &parsed_images).find("2D points") != std::string::npos);

  // Camera model id 42.
  std::string unknown = cameras;
  const std::int32_t model_id = 42;
  std::memcpy(unknown.data() + 8 + 4, &model_id, sizeof model_id);
  CHECK(ParseColmapCamerasBinary(unknown, "cameras.bin", &parsed_cameras).find("unknown camera model id 42") !=
        std::string::npos);
  // A NaN focal length.
  std::string nan = cameras;
  const double not_a_number = std::nan("");
  std::memcpy(nan.data() + 8 + 4 + 4 + 8 + 8, &not_a_number, sizeof not_a_number);
  CHECK(!ParseColmapCamerasBinary(nan, "cameras.bin", &parsed_cameras).empty());
}

TEST_CASE("import: photos matched by file name, resized copies rescaled, the rest kept, all or nothing") {
  const WrittenModel w = WriteThreeCameraScene("import");
  ColmapModel model;
  REQUIRE(ReadColmapModel(w.dir.string(), &model) == "");

  SUBCASE("a photo the reconstruction lacks keeps its camera; a COLMAP image no photo has is reported") {
    Project project = w.project;
    project.images[2].path = "elsewhere/other.jpg";
    const Camera kept = project.images[2].camera;
    ColmapImportReport report;
    REQUIRE(ApplyColmapCameras(model, &project, &report) == "");
    CHECK(report.updated_images.size() == 2);
    REQUIRE(report.missing_photos.size() == 1);
    CHECK(report.missing_photos[0] == "other.jpg");
    REQUIRE(report.unused_images.size() == 1);
    CHECK(report.unused_images[0] == "IMG_0003.JPG");
    CHECK(project.images[2].camera == kept);
  }
  SUBCASE("a photo halved in size takes the camera scaled exactly") {
    Project project = w.project;
    project.images[0].width_px /= 2;
    project.images[0].height_px /= 2;
    ColmapImportReport report;
    REQUIRE(ApplyColmapCameras(model, &project, &report) == "");
    const Image& image = project.images[0];  // after the import, which replaces the project
    CHECK(report.rescaled_images == std::vector<Id>{image.id});
    const Camera& full = w.project.images[0].camera;
    const Eigen::Vector3d p = w.project.primitives[0].mesh.vertex(6).position;
    // A point's pixel in the half-size photo is its full-size pixel halved, in COLMAP's
    // convention (corner at 0): (uv + 0.5) / 2 - 0.5.
    const Eigen::Vector2d expected = (full.Project(p) + Eigen::Vector2d(0.5, 0.5)) / 2.0 - Eigen::Vector2d(0.5, 0.5);
    CHECK((image.camera.Project(p) - expected).norm() < 1e-9);
  }
  SUBCASE("a size that is no resized copy, or a model Facet cannot hold, changes nothing") {
    Project project = w.project;
    project.images[1].width_px = 1000;
    const Project before = project;
    ColmapImportReport report;
    const std::string error = ApplyColmapCameras(model, &project, &report);
    CHECK(error.find("not a resized copy") != std::string::npos);
    CHECK(project == before);
    ColmapModel fisheye = model;
    fisheye.cameras[2] = {
        fisheye.cameras[2].camera_id, ColmapCameraModel::kRadialFisheye, 1024, 768, {900.0, 512.0, 384.0, 0.1, 0.0}};
    Project untouched = w.project;
    CHECK(ApplyColmapCameras(fisheye, &untouched, &report).find("RADIAL_FISHEYE") != std::string::npos);
    CHECK(untouched == w.project);
  }
}

TEST_CASE("export refuses what COLMAP cannot tell apart: two photos with one file name") {
  Project project = ThreeCameraScene();
  project.images[1].path = "other/IMG_0001.JPG";
  ColmapModel model;
  CHECK(ColmapModelFromProject(project, {}, &model).find("two photos are named \"IMG_0001.JPG\"") != std::string::npos);
  CHECK(model.images.empty());
}
