#include "app/shell/export_cameras.h"

#include <cctype>
#include <filesystem>
#include <vector>

#include "app/shell/file_actions.h"
#include "core/io/camera_export.h"
#include "core/io/colmap_model_write.h"
#include "core/io/transforms_json.h"

namespace facet::app {
namespace {

bool Finish(AppState* state, ShellState* shell, const std::string& failure, const std::string& written,
            const std::string& what, std::string* error) {
  if (!failure.empty()) {
    *error = failure;
    state->Log(LogLevel::kError, "Export cameras failed: " + failure);
    return false;
  }
  state->Log(LogLevel::kInfo, "Exported the cameras " + what + " to " + written);
  NoteRecentFile(state, shell, written);
  return true;
}

}  // namespace

std::string WhyNoCamerasToExport(const AppState& state) {
  std::vector<const Image*> images;
  std::string why = ImagesForCameraExport(state.document.project(), &images);
  if (!why.empty()) why[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(why[0])));  // a tooltip
  return why;
}

bool ExportColmapCameras(AppState* state, ShellState* shell, const std::string& path, std::string* error) {
  namespace fs = std::filesystem;
  const bool names_cameras_file = fs::path(path).filename() == "cameras.txt";
  const std::string folder = names_cameras_file ? fs::path(path).parent_path().string() : path;
  ColmapModel model;
  std::string failure = ColmapModelFromProject(state->document.project(), {}, &model);
  if (failure.empty()) failure = WriteColmapModelText(folder, model);
  return Finish(state, shell, failure, (fs::path(folder) / "cameras.txt").string(),
                "as a COLMAP text model (cameras.txt, images.txt, points3D.txt)", error);
}

bool ExportTransformsJson(AppState* state, ShellState* shell, const std::string& path, std::string* error) {
  const std::string failure = WriteTransformsJson(state->document.project(), state->project_path, path);
  return Finish(state, shell, failure, path, "as transforms.json", error);
}

}  // namespace facet::app
