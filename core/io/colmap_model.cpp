#include "core/io/colmap_model.h"

#include <array>
#include <filesystem>
#include <unordered_map>
#include <unordered_set>

#include "core/util/file_read.h"

namespace facet {
namespace {

struct ModelInfo {
  const char* name;
  int num_params;
};
constexpr std::array<ModelInfo, kNumColmapCameraModels> kModels = {{
    {"SIMPLE_PINHOLE", 3},
    {"PINHOLE", 4},
    {"SIMPLE_RADIAL", 4},
    {"RADIAL", 5},
    {"OPENCV", 8},
    {"OPENCV_FISHEYE", 8},
    {"FULL_OPENCV", 12},
    {"FOV", 5},
    {"SIMPLE_RADIAL_FISHEYE", 4},
    {"RADIAL_FISHEYE", 5},
    {"THIN_PRISM_FISHEYE", 12},
}};

bool IsFile(const std::filesystem::path& path) {
  std::error_code ec;
  return std::filesystem::is_regular_file(path, ec);
}

std::string ReadModelFiles(const std::string& dir, const char* extension, bool binary, ColmapModel* model) {
  *model = {};
  const std::filesystem::path folder(dir);
  std::string bytes, error;
  auto read = [&](const char* stem, bool required, bool* present) -> std::string {
    const std::filesystem::path path = folder / (std::string(stem) + extension);
    *present = IsFile(path);
    if (!*present) return required ? "COLMAP model: " + path.string() + " not found" : "";
    if (!ReadRegularFile(path.string(), kMaxColmapFileBytes, &bytes, &error)) return "COLMAP model: " + error;
    return "";
  };
  bool present = false;
  std::string result = read("cameras", true, &present);
  if (!result.empty()) return result;
  const std::string cameras_name = std::string("cameras") + extension;
  result = binary ? ParseColmapCamerasBinary(bytes, cameras_name, &model->cameras)
                  : ParseColmapCamerasText(bytes, cameras_name, &model->cameras);
  if (result.empty()) result = read("images", true, &present);
  if (result.empty()) {
    const std::string images_name = std::string("images") + extension;
    result = binary ? ParseColmapImagesBinary(bytes, images_name, &model->images)
                    : ParseColmapImagesText(bytes, images_name, &model->images);
  }
  if (result.empty()) result = read("points3D", false, &present);
  if (result.empty() && present) {
    const std::string points_name = std::string("points3D") + extension;
    result = binary ? ParseColmapPoints3DBinary(bytes, points_name, &model->points3d)
                    : ParseColmapPoints3DText(bytes, points_name, &model->points3d);
  }
  if (result.empty()) result = ValidateColmapModel(*model);
  if (!result.empty()) {
    *model = {};
    return "COLMAP model in " + dir + ": " + result;
  }
  return "";
}

}  // namespace

const char* ColmapCameraModelName(ColmapCameraModel model) {
  const int id = static_cast<int>(model);
  return id >= 0 && id < kNumColmapCameraModels ? kModels[id].name : "UNKNOWN";
}

int ColmapCameraModelNumParams(ColmapCameraModel model) {
  const int id = static_cast<int>(model);
  return id >= 0 && id < kNumColmapCameraModels ? kModels[id].num_params : 0;
}

bool ColmapCameraModelFromName(const std::string& name, ColmapCameraModel* model) {
  for (int id = 0; id < kNumColmapCameraModels; ++id)
    if (name == kModels[id].name) {
      *model = static_cast<ColmapCameraModel>(id);
      return true;
    }
  return false;
}

bool ColmapCameraModelFromId(int id, ColmapCameraModel* model) {
  if (id < 0 || id >= kNumColmapCameraModels) return false;
  *model = static_cast<ColmapCameraModel>(id);
  return true;
}

const ColmapCamera* ColmapModel::FindCamera(std::uint32_t camera_id) const {
  for (const ColmapCamera& camera : cameras)
    if (camera.camera_id == camera_id) return &camera;
  return nullptr;
}

const ColmapImage* ColmapModel::FindImage(std::uint32_t image_id) const {
  for (const ColmapImage& image : images)
    if (image.image_id == image_id) return &image;
  return nullptr;
}

std::string ValidateColmapModel(const ColmapModel& model) {
  std::unordered_set<std::uint32_t> camera_ids;
  for (const ColmapCamera& camera : model.cameras)
    if (!camera_ids.insert(camera.camera_id).second)
      return "camera " + std::to_string(camera.camera_id) + " appears twice";
  std::unordered_map<std::uint32_t, size_t> image_points;  // image id -> number of 2D points
  std::unordered_set<std::string> names;
  for (const ColmapImage& image : model.images) {
    if (!image_points.emplace(image.image_id, image.points2d.size()).second)
      return "image " + std::to_string(image.image_id) + " appears twice";
    if (!camera_ids.count(image.camera_id))
      return "image " + std::to_string(image.image_id) + " refers to camera " + std::to_string(image.camera_id) +
             ", which is not in cameras";
    if (!names.insert(image.name).second) return "two images are named \"" + image.name + "\"";
  }
  std::unordered_set<std::uint64_t> point_ids;
  for (const ColmapPoint3D& point : model.points3d) {
    if (!point_ids.insert(point.point3d_id).second)
      return "3D point " + std::to_string(point.point3d_id) + " appears twice";
    for (const ColmapTrackElement& element : point.track) {
      const auto it = image_points.find(element.image_id);
      if (it == image_points.end())
        return "3D point " + std::to_string(point.point3d_id) + " is seen by image " +
               std::to_string(element.image_id) + ", which is not in images";
      if (element.point2d_index >= it->second)
        return "3D point " + std::to_string(point.point3d_id) + " names 2D point " +
               std::to_string(element.point2d_index) + " of image " + std::to_string(element.image_id) +
               ", which has " + std::to_string(it->second);
    }
  }
  return "";
}

std::string ReadColmapModelText(const std::string& dir, ColmapModel* model) {
  return ReadModelFiles(dir, ".txt", false, model);
}

std::string ReadColmapModelBinary(const std::string& dir, ColmapModel* model) {
  return ReadModelFiles(dir, ".bin", true, model);
}

std::string ReadColmapModel(const std::string& dir, ColmapModel* model) {
  const std::filesystem::path folder(dir);
  std::error_code ec;
  if (!std::filesystem::is_directory(folder, ec)) {
    *model = {};
    return "COLMAP model: " + dir + " is not a folder";
  }
  if (IsFile(folder / "cameras.bin") && IsFile(folder / "images.bin")) return ReadColmapModelBinary(dir, model);
  if (IsFile(folder / "cameras.txt") && IsFile(folder / "images.txt")) return ReadColmapModelText(dir, model);
  *model = {};
  return "COLMAP model: " + dir + " has neither cameras.bin and images.bin nor cameras.txt and images.txt";
}

}  // namespace facet
