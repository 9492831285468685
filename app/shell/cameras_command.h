// `facet cameras PROJECT -o OUT.facet`: cameras for every photo of a project from COLMAP
// (core/io/colmap_run.h), brought into the project's frame (core/solve/colmap_alignment.h) and
// written into a copy of the project. Prints a JSON summary on stdout (stage times, photos
// placed, the alignment), progress and errors on stderr; exit code 0 when the project was
// written, 1 otherwise (then nothing is written).
#pragma once

#include <string>

#include <nlohmann/json_fwd.hpp>

#include "core/solve/colmap_alignment.h"

namespace CLI {
class App;
}

namespace facet::app {

struct CamerasCommandOptions {
  std::string colmap = "colmap";  // the colmap program (path or name on PATH); the CLI's default: $FACET_COLMAP
  std::string work_dir;           // "" : OUT.facet's folder / "<OUT stem>.colmap"
  int max_image_size_px = 1600;
  int num_threads = 2;
  bool single_camera = false;  // all photos from one camera and lens
};

struct CamerasCommandArgs {
  std::string project_path;
  std::string output_path;
  CamerasCommandOptions options;
};

// Adds the `cameras` subcommand to `cli`, its values parsed into *args (which must outlive the
// parse); returns it (true after parsing when it was given).
CLI::App* AddCamerasSubcommand(CLI::App* cli, CamerasCommandArgs* args);

// The alignment of the cameras into the project's frame as the JSON summary reports it: the
// message, each source with its note, the transform (scale, angle-axis rotation in rad,
// translation in project units), the residuals over the cameras in common.
nlohmann::json ColmapAlignmentJson(const ColmapAlignmentSummary& alignment);

int RunCamerasCommand(const std::string& project_path, const std::string& output_path,
                      const CamerasCommandOptions& options);

}  // namespace facet::app
