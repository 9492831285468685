#include "core/io/transforms_json.h"

#include <filesystem>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/io/camera_export.h"
#include "core/io/colmap_camera.h"
#include "core/io/project_io.h"
#include "core/util/file_write.h"
#include "core/util/utf8.h"

namespace facet {
namespace {

using Json = nlohmann::ordered_json;

// The photo's path as the trainer should open it: relative to the JSON's folder, so that the
// two can move together, unless they share no folder but the root (then absolute: a path up
// to "/" and down again breaks as soon as either moves).
std::string PathFromJsonFolder(const std::string& project_path, const std::string& image_path,
                               const std::string& json_path) {
  namespace fs = std::filesystem;
  const std::string resolved = ResolveImagePath(project_path, image_path);
  std::error_code ec;
  const fs::path photo = fs::absolute(resolved, ec).lexically_normal();
  if (ec) return fs::path(resolved).generic_string();
  const fs::path folder = fs::absolute(fs::path(json_path), ec).parent_path().lexically_normal();
  if (ec) return photo.generic_string();
  const fs::path relative = photo.lexically_relative(folder);
  const auto first_below_root = [](const fs::path& p) {
    auto it = p.begin();
    return it != p.end() && ++it != p.end() ? *it : fs::path();
  };
  const bool share_a_folder = first_below_root(photo) == first_below_root(folder);
  return relative.empty() || !share_a_folder ? photo.generic_string() : relative.generic_string();
}

Json Intrinsics(const Camera& camera) {
  const Eigen::Vector2d c = ColmapPixelFromFacet(camera.principal_point_px);
  return Json{
      {"fl_x", camera.focal_px}, {"fl_y", camera.focal_px}, {"cx", c.x()},     {"cy", c.y()}, {"w", camera.width_px},
      {"h", camera.height_px},   {"k1", camera.k1},         {"k2", camera.k2}, {"p1", 0.0},   {"p2", 0.0}};
}

}  // namespace

Eigen::Matrix4d NerfTransformFromCamera(const Camera& camera) {
  const Eigen::Matrix3d world_from_cam = camera.cam_from_world_rotation.transpose();
  Eigen::Matrix4d transform = Eigen::Matrix4d::Identity();
  transform.block<3, 1>(0, 0) = world_from_cam.col(0);
  transform.block<3, 1>(0, 1) = -world_from_cam.col(1);
  transform.block<3, 1>(0, 2) = -world_from_cam.col(2);
  transform.block<3, 1>(0, 3) = camera.CenterInWorld();
  return transform;
}

std::string FormatTransformsJson(const Project& project, const std::string& project_path, const std::string& json_path,
                                 std::string* text) {
  text->clear();
  std::vector<const Image*> images;
  const std::string error = ImagesForCameraExport(project, &images);
  if (!error.empty()) return error;
  bool shared = true, distorted = false;
  const Json first = Intrinsics(images.front()->camera);
  for (const Image* image : images) {
    shared = shared && Intrinsics(image->camera) == first;
    distorted = distorted || image->camera.HasDistortion();
  }
  Json doc = Json::object();
  doc["camera_model"] = distorted ? "OPENCV" : "PINHOLE";
  if (shared) doc.update(first);
  Json frames = Json::array();
  for (const Image* image : images) {
    const std::string path = PathFromJsonFolder(project_path, image->path, json_path);
    if (!IsValidUtf8(path))
      return "photo " + ValidUtf8OrReplaced(path) + ": its path is not UTF-8, which a JSON file cannot hold exactly";
    Json frame = {{"file_path", path}};
    const Eigen::Matrix4d transform = NerfTransformFromCamera(image->camera);
    Json matrix = Json::array();
    for (int r = 0; r < 4; ++r) matrix.push_back({transform(r, 0), transform(r, 1), transform(r, 2), transform(r, 3)});
    frame["transform_matrix"] = std::move(matrix);
    if (!shared) frame.update(Intrinsics(image->camera));
    frames.push_back(std::move(frame));
  }
  doc["frames"] = std::move(frames);
  *text = doc.dump(2) + "\n";
  return "";
}

std::string WriteTransformsJson(const Project& project, const std::string& project_path, const std::string& json_path) {
  std::string text;
  const std::string error = FormatTransformsJson(project, project_path, json_path, &text);
  if (!error.empty()) return error;
  return WriteFileAtomically(json_path, text);
}

}  // namespace facet
