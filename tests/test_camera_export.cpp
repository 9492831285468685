// Facet's cameras out for the tools people use next (issue 27): a COLMAP text model
// (core/io/colmap_model_write.h) and nerfstudio's transforms.json (core/io/transforms_json.h).
// Three boxes photographed by three known cameras (different sizes and focal lengths, one
// with k1, one with k1 and k2), every vertex pinned at its exact projection, go out and are
// read back: the cameras come back to 1e-9, and the vertices projected through the files'
// cameras, with each format's own conventions written out here, land on their pins to 1e-6 px.
// Projects with nothing to export, and folders that cannot be written, are refused by name.
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <string>

#include <nlohmann/json.hpp>

#include "core/io/colmap_camera.h"
#include "core/io/colmap_import.h"
#include "core/io/colmap_model.h"
#include "core/io/colmap_model_write.h"
#include "core/io/transforms_json.h"
#include "tests/synthetic_scene.h"
#include "tests/temp_files.h"

namespace fs = std::filesystem;
using namespace facet;
using namespace facet::testing;

namespace {

constexpr double kExact = 1e-9;     // numbers written with 17 digits read back to rounding
constexpr double kPinTolPx = 1e-6;  // a vertex projected through a written camera vs its pin

// Three boxes and three calibrated photos of them: MakeBoxScene's camera (1024 x 768, no
// distortion), a 1280 x 960 one with k1 (COLMAP's SIMPLE_RADIAL) and a portrait 800 x 1000 one
// with k1, k2 (RADIAL); each photo pins every vertex at its exact projection.
Project ThreeBoxesThreePhotos() {
  Project project = MakeBoxScene().project;
  project.pins.clear();
  project.images[0].path = "photos/IMG_0001.JPG";
  for (const auto& [size, at] : {std::pair{Eigen::Vector3d(2.0, 2.0, 4.0), Eigen::Vector3d(6.0, 0.0, 0.0)},
                                 std::pair{Eigen::Vector3d(3.0, 1.5, 1.5), Eigen::Vector3d(0.0, 5.0, 0.0)}}) {
    PrimitiveShape shape = MakeBox(kNoId, size);
    shape.translation = at;
    Id id = kNoId;
    REQUIRE(AddPrimitiveToProject(&project, shape, "box", &id, nullptr));
  }
  const struct {
    Eigen::Vector3d center;
    int width, height;
    double focal, k1, k2;
  } more[] = {{{-6.0, -9.0, 6.0}, 1280, 960, 1100.0, -0.08, 0.0}, {{14.0, 11.0, 8.0}, 800, 1000, 820.0, 0.05, -0.013}};
  for (int k = 0; k < 2; ++k) {
    SyntheticSceneOptions o;
    o.camera_center = more[k].center;
    o.look_at = {3.0, 2.5, 1.0};
    o.width_px = more[k].width;
    o.height_px = more[k].height;
    o.focal_px = more[k].focal;
    o.principal_point_offset_px = {-20.0 + 30.0 * k, 7.0};
    o.roll_deg = -4.0 + 6.0 * k;
    Image image = project.images[0];
    image.id = project.NewId();
    image.path = "photos/IMG_000" + std::to_string(k + 2) + ".JPG";
    image.width_px = o.width_px;
    image.height_px = o.height_px;
    image.camera = MakeLookAtCamera(o);
    image.camera.k1 = more[k].k1;
    image.camera.k2 = more[k].k2;
    project.images.push_back(image);
  }
  for (const Image& image : project.images)
    for (const Primitive& primitive : project.primitives)
      for (VertexId v = 0; v < primitive.mesh.VertexIdEnd(); ++v) {
        if (!primitive.mesh.IsVertex(v)) continue;
        const Eigen::Vector3d p = primitive.mesh.vertex(v).position;
        REQUIRE(image.camera.CamFromWorld(p).z() > 0.0);
        Pin pin;
        pin.id = project.NewId();
        pin.image_id = image.id;
        pin.vertex = {primitive.id, v};
        pin.uv_px = image.camera.Project(p);
        project.pins.push_back(pin);
      }
  return project;
}

// The model's vertices in the order the export numbers its 3D points (1, 2, ...).
std::vector<VertexRef> VerticesInExportOrder(const Project& project) {
  std::vector<VertexRef> vertices;
  for (const Primitive& primitive : project.primitives)
    for (VertexId v = 0; v < primitive.mesh.VertexIdEnd(); ++v)
      if (primitive.mesh.IsVertex(v)) vertices.push_back({primitive.id, v});
  return vertices;
}

// A world point through a COLMAP image and camera as COLMAP defines them (its pixels: the
// first pixel's centre at (0.5, 0.5)); the three models Facet writes.
Eigen::Vector2d ColmapProject(const ColmapCamera& camera, const ColmapImage& image, const Eigen::Vector3d& p) {
  const Eigen::Vector3d x = image.cam_from_world_rotation.normalized() * p + image.cam_from_world_translation;
  const Eigen::Vector2d xy = x.head<2>() / x.z();
  const std::vector<double>& q = camera.params;
  const double r2 = xy.squaredNorm();
  double k1 = 0.0, k2 = 0.0;
  switch (camera.model) {
    case ColmapCameraModel::kSimplePinhole: break;
    case ColmapCameraModel::kSimpleRadial: k1 = q.at(3); break;
    case ColmapCameraModel::kRadial: k1 = q.at(3), k2 = q.at(4); break;
    default: FAIL("unexpected camera model ", ColmapCameraModelName(camera.model));
  }
  const Eigen::Vector2d distorted = xy * (1.0 + k1 * r2 + k2 * r2 * r2);
  return q.at(0) * distorted + Eigen::Vector2d(q.at(1), q.at(2));
}

}  // namespace

TEST_CASE("the COLMAP text model of three boxes and three photos reads back: cameras, points and pins as tracks") {
  const Project project = ThreeBoxesThreePhotos();
  TempDir dir("camera_export_colmap");
  const std::string model_dir = dir / "sparse/0";  // a folder that does not exist yet
  ColmapModel written;
  REQUIRE(ColmapModelFromProject(project, {}, &written) == "");
  REQUIRE(WriteColmapModelText(model_dir, written) == "");
  ColmapModel model;
  REQUIRE(ReadColmapModelText(model_dir, &model) == "");
  REQUIRE(model.images.size() == 3);
  CHECK(model.cameras[0].model == ColmapCameraModel::kSimplePinhole);
  CHECK(model.cameras[1].model == ColmapCameraModel::kSimpleRadial);
  CHECK(model.cameras[2].model == ColmapCameraModel::kRadial);

  SUBCASE("the import onto a copy whose cameras are cleared restores every camera to 1e-9") {
    Project cleared = project;
    for (Image& image : cleared.images) {
      image.camera = Camera();
      image.camera_calibrated = false;
    }
    ColmapImportReport report;
    REQUIRE(ApplyColmapCameras(model, &cleared, &report) == "");
    CHECK(report.updated_images.size() == 3);
    CHECK(report.rescaled_images.empty());
    for (size_t i = 0; i < 3; ++i) {
      CAPTURE(i);
      const Camera& truth = project.images[i].camera;
      const Camera& got = cleared.images[i].camera;
      CHECK(cleared.images[i].camera_calibrated);
      CHECK(got.width_px == truth.width_px);
      CHECK(got.height_px == truth.height_px);
      CHECK(std::abs(got.focal_px - truth.focal_px) < kExact * truth.focal_px);
      CHECK((got.principal_point_px - truth.principal_point_px).norm() < kExact * truth.focal_px);
      CHECK(std::abs(got.k1 - truth.k1) < kExact);
      CHECK(std::abs(got.k2 - truth.k2) < kExact);
      CHECK((got.cam_from_world_rotation - truth.cam_from_world_rotation).norm() < kExact);
      CHECK((got.cam_from_world_translation - truth.cam_from_world_translation).norm() < kExact);
    }
  }

  SUBCASE("points3D are the vertices; each track is the vertex's pins; every vertex projects onto its pins") {
    const std::vector<VertexRef> vertices = VerticesInExportOrder(project);
    REQUIRE(model.points3d.size() == vertices.size());
    REQUIRE(vertices.size() == 24);
    std::map<std::pair<Id, VertexId>, std::vector<const Pin*>> pins_of;
    for (const Pin& pin : project.pins) pins_of[{pin.vertex.primitive_id, pin.vertex.vertex}].push_back(&pin);
    double worst_px = 0.0;
    for (size_t k = 0; k < vertices.size(); ++k) {
      const ColmapPoint3D& point = model.points3d[k];
      const Eigen::Vector3d truth = VertexInWorld(project, vertices[k]);
      CAPTURE(k);
      CHECK(point.point3d_id == k + 1);
      CHECK((point.position - truth).norm() < kExact);
      const std::vector<const Pin*>& pins = pins_of[{vertices[k].primitive_id, vertices[k].vertex}];
      REQUIRE(point.track.size() == pins.size());
      for (const Pin* pin : pins) {
        // The pin's image lists it once in the track, as the image's 2D point the track names.
        int found = 0;
        for (const ColmapTrackElement& element : point.track) {
          if (element.image_id != pin->image_id) continue;
          ++found;
          const ColmapImage* image = model.FindImage(element.image_id);
          REQUIRE(image != nullptr);
          const ColmapPoint2D& seen = image->points2d.at(element.point2d_index);
          CHECK(seen.point3d_id == point.point3d_id);
          CHECK((seen.xy_px - (pin->uv_px + Eigen::Vector2d(0.5, 0.5))).norm() < kExact);
          const Eigen::Vector2d projected = ColmapProject(*model.FindCamera(image->camera_id), *image, point.position);
          worst_px = std::max(worst_px, (projected - seen.xy_px).norm());
        }
        CHECK(found == 1);
      }
    }
    MESSAGE("worst distance of a vertex through a written camera to its pin: ", worst_px, " px");
    CHECK(worst_px < kPinTolPx);
    // And no image holds a 2D point that no track names.
    size_t observations = 0;
    for (const ColmapImage& image : model.images) observations += image.points2d.size();
    CHECK(observations == project.pins.size());
  }
}

namespace {

// Writes the scene's transforms.json, its photos with one lens (`shared`: the intrinsics at the
// top level) or each their own (in each frame), and projects every pinned vertex through it.
void CheckTransformsJson(bool shared) {
  Project project = ThreeBoxesThreePhotos();
  TempDir dir("camera_export_nerf");
  const std::string project_path = dir / "street.facet";
  const std::string json_path = dir / "nerf/transforms.json";
  fs::create_directories(dir.path / "nerf");
  if (shared)
    for (Image& image : project.images) {
      const Camera& first = project.images[0].camera;
      image.camera.width_px = first.width_px, image.camera.height_px = first.height_px;
      image.camera.focal_px = first.focal_px;
      image.camera.principal_point_px = first.principal_point_px;
      image.camera.k1 = first.k1, image.camera.k2 = first.k2;
      for (Pin& pin : project.pins)
        if (pin.image_id == image.id) pin.uv_px = image.camera.Project(VertexInWorld(project, pin.vertex));
    }
  REQUIRE(WriteTransformsJson(project, project_path, json_path) == "");
  const nlohmann::json doc = nlohmann::json::parse(ReadText(json_path));
  CHECK(doc.at("camera_model") == (shared ? "PINHOLE" : "OPENCV"));  // the first camera has no distortion
  CHECK(doc.contains("fl_x") == shared);
  REQUIRE(doc.at("frames").size() == 3);
  double worst_px = 0.0;
  for (size_t i = 0; i < 3; ++i) {
    CAPTURE(i);
    const Image& image = project.images[i];
    const nlohmann::json& frame = doc["frames"][i];
    CHECK(frame.at("file_path") == "../photos/IMG_000" + std::to_string(i + 1) + ".JPG");
    CHECK(frame.contains("fl_x") == !shared);
    const nlohmann::json& intrinsics = shared ? doc : frame;
    CHECK(intrinsics.at("w").get<int>() == image.camera.width_px);
    CHECK(intrinsics.at("h").get<int>() == image.camera.height_px);
    const double fx = intrinsics.at("fl_x"), fy = intrinsics.at("fl_y");
    const double cx = intrinsics.at("cx"), cy = intrinsics.at("cy");
    const double k1 = intrinsics.at("k1"), k2 = intrinsics.at("k2");
    const double p1 = intrinsics.at("p1"), p2 = intrinsics.at("p2");
    CHECK(p1 == 0.0);
    CHECK(p2 == 0.0);
    // camera-to-world with OpenGL's camera axes; OpenCV's camera (y down, looking down +z) is
    // it with y and z negated.
    Eigen::Matrix4d c2w;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) c2w(r, c) = frame.at("transform_matrix").at(r).at(c);
    CHECK((c2w.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).norm() == 0.0);
    const Eigen::Matrix3d world_from_cam = c2w.topLeftCorner<3, 3>() * Eigen::Vector3d(1, -1, -1).asDiagonal();
    const Eigen::Vector3d center = c2w.topRightCorner<3, 1>();
    CHECK((world_from_cam.transpose() - image.camera.cam_from_world_rotation).norm() < kExact);
    CHECK((center - image.camera.CenterInWorld()).norm() < kExact);
    for (const Pin& pin : project.pins) {
      if (pin.image_id != image.id) continue;
      const Eigen::Vector3d x = world_from_cam.transpose() * (VertexInWorld(project, pin.vertex) - center);
      const Eigen::Vector2d xy = x.head<2>() / x.z();
      const double r2 = xy.squaredNorm();
      const double d = 1.0 + k1 * r2 + k2 * r2 * r2;
      // transforms.json's pixels: the first pixel's centre at (0.5, 0.5); Facet's at (0, 0).
      const Eigen::Vector2d uv(fx * xy.x() * d + cx - 0.5, fy * xy.y() * d + cy - 0.5);
      worst_px = std::max(worst_px, (uv - pin.uv_px).norm());
    }
  }
  MESSAGE("worst distance of a vertex through a transforms.json camera to its pin: ", worst_px, " px");
  CHECK(worst_px < kPinTolPx);
}

}  // namespace

TEST_CASE("transforms.json: OpenGL camera-to-world and intrinsics that put every vertex on its pins") {
  SUBCASE("each photo its own intrinsics, in its frame") { CheckTransformsJson(false); }
  SUBCASE("one lens for every photo: the intrinsics at the top level") { CheckTransformsJson(true); }
}

TEST_CASE("camera exports refuse a project with no calibrated photo, a broken camera, a folder they cannot write") {
  TempDir dir("camera_export_refusals");
  const std::string json_path = dir / "transforms.json";
  const std::string model_dir = dir / "colmap";
  ColmapModel model;
  SUBCASE("no calibrated photo: nothing is written") {
    Project project = ThreeBoxesThreePhotos();
    for (Image& image : project.images) image.camera_calibrated = false;
    const std::string colmap_error = ColmapModelFromProject(project, {}, &model);
    CHECK(colmap_error.find("no photo has a calibrated camera") != std::string::npos);
    CHECK(model.images.empty());
    CHECK(WriteTransformsJson(project, dir / "p.facet", json_path).find("no photo has a calibrated camera") !=
          std::string::npos);
    CHECK(!fs::exists(json_path));
    project.images.clear();
    CHECK(ColmapModelFromProject(project, {}, &model).find("the project has no photo") != std::string::npos);
  }
  SUBCASE("a calibrated camera whose focal length is not a number is refused, naming its photo") {
    Project project = ThreeBoxesThreePhotos();
    project.images[1].camera.focal_px = std::nan("");
    CHECK(ColmapModelFromProject(project, {}, &model).find("photo IMG_0002.JPG: its focal length") !=
          std::string::npos);
    CHECK(WriteTransformsJson(project, dir / "p.facet", json_path).find("photo IMG_0002.JPG") != std::string::npos);
    CHECK(!fs::exists(json_path));
  }
  SUBCASE("a file where the folder should be: the error names it, the file is untouched") {
    const Project project = ThreeBoxesThreePhotos();
    WriteText(dir / "blocker", "not a folder");
    REQUIRE(ColmapModelFromProject(project, {}, &model) == "");
    const std::string colmap_error = WriteColmapModelText(dir / "blocker/sparse", model);
    CHECK(colmap_error.find("cannot create the folder") != std::string::npos);
    CHECK(colmap_error.find("blocker") != std::string::npos);
    const std::string json_error = WriteTransformsJson(project, dir / "p.facet", dir / "blocker/transforms.json");
    CHECK(json_error.find("blocker") != std::string::npos);
    CHECK(ReadText(dir / "blocker") == "not a folder");
  }
  SUBCASE("a folder named images.txt in the model's folder: refused before cameras.txt is written") {
    const Project project = ThreeBoxesThreePhotos();
    fs::create_directories(dir.path / "colmap/images.txt");
    REQUIRE(ColmapModelFromProject(project, {}, &model) == "");
    const std::string error = WriteColmapModelText(model_dir, model);
    CHECK(error.find("images.txt is a folder") != std::string::npos);
    CHECK(!fs::exists(dir / "colmap/cameras.txt"));
  }
}
