#include "core/io/camera_export.h"

#include <cmath>
#include <filesystem>

namespace facet {
namespace {

std::string WhyCameraIsNotExportable(const Camera& camera) {
  if (camera.width_px <= 0 || camera.height_px <= 0)
    return "its camera has no image size (" + std::to_string(camera.width_px) + " x " +
           std::to_string(camera.height_px) + " px)";
  if (!(std::isfinite(camera.focal_px) && camera.focal_px > 0.0))
    return "its focal length (" + std::to_string(camera.focal_px) + " px) is not a positive number";
  const bool finite = camera.principal_point_px.allFinite() && std::isfinite(camera.k1) && std::isfinite(camera.k2) &&
                      camera.cam_from_world_rotation.allFinite() && camera.cam_from_world_translation.allFinite();
  if (!finite) return "its camera holds a number that is not finite";
  return "";
}

}  // namespace

std::string ImagesForCameraExport(const Project& project, std::vector<const Image*>* images) {
  images->clear();
  std::vector<const Image*> calibrated;
  for (const Image& image : project.images) {
    if (!image.camera_calibrated) continue;
    const std::string why = WhyCameraIsNotExportable(image.camera);
    if (!why.empty()) return "photo " + std::filesystem::path(image.path).filename().string() + ": " + why;
    calibrated.push_back(&image);
  }
  if (calibrated.empty())
    return project.images.empty() ? "the project has no photo: there is no camera to export"
                                  : "no photo has a calibrated camera yet: there is no camera to export (calibrate "
                                    "a photo from its lines or pins first)";
  *images = std::move(calibrated);
  return "";
}

}  // namespace facet
