#include "app/state/add_photo.h"

#include <filesystem>
#include <system_error>

#include "app/state/calgui_exif_prior.h"
#include "core/image/image_io.h"
#include "core/io/project_io.h"

namespace facet::app {
namespace {

// A first guess of the focal length, as wide as a typical phone's main camera (about 28 mm
// equivalent); calibration or the pins replace it.
constexpr double kDefaultFocalFactor = 1.2;

std::string StoredPath(const std::string& project_path, const std::string& photo_path) {
  std::error_code ec;
  const std::filesystem::path absolute = std::filesystem::absolute(photo_path, ec);
  if (ec || project_path.empty()) return ec ? photo_path : absolute.generic_string();
  const std::filesystem::path folder = std::filesystem::absolute(project_path, ec).parent_path();
  const std::filesystem::path relative = absolute.lexically_relative(folder);
  return relative.empty() ? absolute.generic_string() : relative.generic_string();
}

}  // namespace

bool AddPhotoEdit(AppState* state, const std::string& path) {
  if (path.empty()) {
    state->Log(LogLevel::kError, "Add photo: no file name");
    return false;
  }
  // Decoded before it is accepted, so that a truncated or corrupt photo is refused here and
  // not after it joined the project; the decoded pixels are the ones the app then shows.
  ImageReadResult read = ReadImage(path);
  if (!read.ok()) {
    state->Log(LogLevel::kError, "Add photo: " + read.error);
    return false;
  }
  const int width_px = read.image.width;
  const int height_px = read.image.height;
  Project edited = state->document.project();
  Image image;
  image.id = edited.NewId();
  image.path = StoredPath(state->project_path, path);
  image.width_px = width_px;
  image.height_px = height_px;
  image.camera.width_px = width_px;
  image.camera.height_px = height_px;
  image.camera.focal_px = kDefaultFocalFactor * std::max(width_px, height_px);
  image.camera.principal_point_px = Eigen::Vector2d((width_px - 1) / 2.0, (height_px - 1) / 2.0);
  const ExifFocalPrior prior = ReadExifFocalPrior(path, image);
  if (prior.found) {
    image.focal_mode = FocalMode::kPrior;
    image.focal_prior_px = prior.focal_px;
    image.focal_prior_std_px = prior.std_px;
    image.camera.focal_px = prior.focal_px;
  }
  const Id id = image.id;
  const std::string name = std::filesystem::path(path).filename().string();
  edited.images.push_back(std::move(image));
  CommitEdit(state, "Add photo " + name, std::move(edited));
  if (state->document.project().FindImage(id) == nullptr) return false;
  AdoptDecodedPhoto(state, id, std::move(read.image));
  state->active_image_id = id;
  state->Log(LogLevel::kInfo,
             name + ": " + std::to_string(width_px) + " x " + std::to_string(height_px) + " px; " +
                 (prior.found ? prior.message : "no EXIF focal length (calibrate from lines or pins)"));
  return true;
}

bool RelinkPhotoEdit(AppState* state, Id image_id, const std::string& path) {
  const Image* current = state->document.project().FindImage(image_id);
  if (current == nullptr) {
    state->Log(LogLevel::kError, "Relink photo: choose the image to relink first");
    return false;
  }
  if (path.empty()) {
    state->Log(LogLevel::kError, "Relink photo: no file name");
    return false;
  }
  ImageReadResult read = ReadImage(path);
  if (!read.ok()) {
    state->Log(LogLevel::kError, "Relink photo: " + read.error);
    return false;
  }
  if (const std::string other = WhyPhotoIsNotTheImages(*current, path, read.image.width, read.image.height);
      !other.empty()) {
    state->Log(LogLevel::kError, "Relink photo: " + other);
    return false;
  }
  Project edited = state->document.project();
  edited.FindImage(image_id)->path = StoredPath(state->project_path, path);
  const std::string name = std::filesystem::path(path).filename().string();
  CommitEdit(state, "Relink photo " + name, std::move(edited));
  AdoptDecodedPhoto(state, image_id, std::move(read.image));
  state->Log(LogLevel::kInfo, "Relinked the photo to " + path);
  return true;
}

}  // namespace facet::app
