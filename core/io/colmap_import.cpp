#include "core/io/colmap_import.h"

#include <cmath>
#include <filesystem>
#include <map>
#include <set>

#include "core/io/colmap_camera.h"

namespace facet {
namespace {

std::string FileNameOf(const std::string& path) { return std::filesystem::path(path).filename().string(); }

// Rescales the intrinsics of `camera` (at COLMAP's size) to a photo of width x height, when that
// photo is a uniformly resized copy. Pixel coordinates scale about the image's top-left corner
// in COLMAP's convention (corner at 0), i.e. about (-0.5, -0.5) in Facet's.
bool RescaleToPhoto(int width, int height, Camera* camera) {
  const double s = static_cast<double>(width) / camera->width_px;
  if (std::abs(camera->height_px * s - height) > 0.5) return false;
  const double sy = static_cast<double>(height) / camera->height_px;
  const Eigen::Vector2d corner(-0.5, -0.5);
  const Eigen::Vector2d c = camera->principal_point_px - corner;
  camera->principal_point_px = corner + Eigen::Vector2d(c.x() * s, c.y() * sy);
  camera->focal_px *= s;
  camera->width_px = width;
  camera->height_px = height;
  return true;
}

}  // namespace

std::string ApplyColmapCameras(const ColmapModel& model, Project* project, ColmapImportReport* report) {
  *report = {};
  std::map<std::string, const ColmapImage*> by_name;
  for (const ColmapImage& image : model.images) {
    const std::string name = FileNameOf(image.name);
    if (!by_name.emplace(name, &image).second)
      return "the COLMAP model has two images named \"" + name + "\": cannot tell which photo is which";
  }
  Project updated = *project;
  std::set<std::string> used;
  ColmapImportReport out;
  for (Image& image : updated.images) {
    const std::string name = FileNameOf(image.path);
    const auto it = by_name.find(name);
    if (it == by_name.end()) {
      out.missing_photos.push_back(name);
      continue;
    }
    used.insert(name);
    const ColmapImage& colmap_image = *it->second;
    const ColmapCamera* colmap_camera = model.FindCamera(colmap_image.camera_id);
    if (!colmap_camera) return "COLMAP image \"" + colmap_image.name + "\" has no camera";
    Camera camera = image.camera;
    const std::string error = FacetIntrinsicsFromColmap(*colmap_camera, &camera);
    if (!error.empty()) return "photo " + name + ": " + error;
    SetFacetPoseFromColmap(colmap_image, &camera);
    if (image.width_px > 0 && image.height_px > 0 &&
        (image.width_px != camera.width_px || image.height_px != camera.height_px)) {
      if (!RescaleToPhoto(image.width_px, image.height_px, &camera))
        return "photo " + name + " is " + std::to_string(image.width_px) + " x " + std::to_string(image.height_px) +
               " px, but COLMAP's camera is " + std::to_string(colmap_camera->width_px) + " x " +
               std::to_string(colmap_camera->height_px) + " px, not a resized copy of it";
      out.rescaled_images.push_back(image.id);
    }
    image.camera = camera;
    image.camera_calibrated = true;
    // Held as COLMAP gave it: neither its lines (model_update's calibration) nor the solves move
    // it until the user frees it (Properties' locks).
    image.camera_from_reconstruction = true;
    image.pose_locked = image.focal_locked = image.principal_point_locked = image.distortion_locked = true;
    out.updated_images.push_back(image.id);
  }
  for (const auto& [name, colmap_image] : by_name)
    if (!used.count(name)) out.unused_images.push_back(colmap_image->name);
  *project = std::move(updated);
  *report = std::move(out);
  return "";
}

std::string ApplyAlignedColmapCameras(const ColmapModel& model, const ColmapAlignmentOptions& options, Project* project,
                                      ColmapImportReport* report, ColmapAlignmentSummary* alignment) {
  *alignment = {};
  Project imported = *project;
  const std::string error = ApplyColmapCameras(model, &imported, report);
  if (!error.empty()) return error;
  *alignment = AlignReconstructionToProject(*project, report->updated_images, options, &imported);
  if (!alignment->IsUsable()) return "cameras not aligned to the project: " + alignment->message;
  *project = std::move(imported);
  return "";
}

}  // namespace facet
