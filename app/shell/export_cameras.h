// File > Export cameras (COLMAP) and (transforms.json), and the script's `command
// export-colmap PATH` and `command export-transforms PATH`: the document's calibrated cameras
// written by core/io/colmap_model_write.h or core/io/transforms_json.h, as `facet export`
// writes them.
#pragma once

#include <string>

#include "app/shell/frame.h"
#include "app/state/app_state.h"

namespace facet::app {

// Why File > Export cameras is disabled (the menu's tooltip), or "" when there is a camera to
// export.
std::string WhyNoCamerasToExport(const AppState& state);

// Writes the COLMAP text model into `path`'s folder when `path` names cameras.txt, else into the
// folder `path` (created when missing). Logs the result and notes the file among the recent
// ones; false with *error set when nothing could be written.
bool ExportColmapCameras(AppState* state, ShellState* shell, const std::string& path, std::string* error);

// Writes transforms.json to `path`, photo paths relative to its folder.
bool ExportTransformsJson(AppState* state, ShellState* shell, const std::string& path, std::string* error);

}  // namespace facet::app
