// Cameras for a photo set from COLMAP (https://colmap.github.io; Debian package `colmap`),
// run as child processes: feature extraction (SIFT on the CPU), matching (exhaustive for a few
// dozen photos, sequential beyond), the incremental mapper. Options -> RunColmap -> Summary, as
// every solver (core/optim/solver_summary.h). Nothing here touches a project: the caller
// applies the summary's model (core/io/colmap_import.h) only when the run is usable, so a
// failed or cancelled run changes nothing.
//
// The working folder (the caller's, never inside the repo: beside the project, or the user's
// cache) holds, after a run: images/ (links to the photos, named by file name), database.db,
// sparse/<n>/ (COLMAP's binary models), colmap.log (every stage's output, kept for the user).
// A run starts by removing those, so the folder holds one run.
#pragma once

#include <array>
#include <atomic>
#include <functional>
#include <string>
#include <vector>

#include "core/io/colmap_model.h"
#include "core/optim/solver_summary.h"

namespace facet {

enum class ColmapStage { kPreparing = 0, kFeatureExtraction, kMatching, kMapping, kReadingModel, kDone };
constexpr int kNumColmapStages = 6;
const char* ColmapStageName(ColmapStage stage);  // "preparing", "feature extraction", ...

struct ColmapRunOptions {
  std::string colmap_executable = "colmap";  // a path, or a name looked up along PATH
  std::string working_dir;                   // required; created when missing
  std::vector<std::string> photo_paths;      // the photos; their file names must differ
  // Photos are read by COLMAP at full size but their features found at most this many pixels
  // on the longer side (SiftExtraction.max_image_size): the run's time falls with it, and the
  // cameras are still those of the full-size photos.
  int max_image_size_px = 1600;
  int max_num_features = 8192;  // per photo (SiftExtraction.max_num_features)
  int num_threads = 2;          // -1: all cores
  // One lens for all photos (ImageReader.single_camera): the same camera, focal setting and
  // size. Off: each photo gets its own intrinsics.
  bool single_camera = false;
  std::string camera_model = "SIMPLE_RADIAL";  // one Facet can import (core/io/colmap_camera.h)
  // Above this many photos the matcher pairs each photo with its neighbours in file-name order
  // (sequential_matcher) instead of with every other photo.
  int max_photos_for_exhaustive_matching = 40;
  // Called from the calling thread as each stage starts: the stage, its 1-based number among the
  // three COLMAP stages (0 for preparing and reading), 3.
  std::function<void(ColmapStage stage, int step, int num_steps)> progress;
  // Set (from any thread) to stop the run: the running stage's process group is ended and the
  // summary says cancelled.
  const std::atomic<bool>* cancel = nullptr;
};

struct ColmapRunSummary {
  // kConverged: a model with at least two registered photos came out; kInvalidInput: options
  // refused (no colmap, too few photos, ...); kFailed: a stage failed or was cancelled.
  SolverTermination termination = SolverTermination::kInvalidInput;
  bool cancelled = false;
  ColmapStage stage_reached = ColmapStage::kPreparing;  // the last stage started
  std::string message;                                  // one sentence for the log or the status bar
  std::vector<std::string> warnings;                    // e.g. photos COLMAP could not register
  std::vector<bool> registered;                         // per photo_paths: in the model
  int num_registered = 0;
  std::array<double, kNumColmapStages> stage_time_ms = {};  // wall time per stage
  double time_ms = 0.0;
  std::string log_path;   // colmap.log in the working folder
  std::string model_dir;  // the chosen sparse/<n>/ (the model with the most photos)
  ColmapModel model;      // that model, read

  bool IsUsable() const { return termination == SolverTermination::kConverged; }
};

ColmapRunSummary RunColmap(const ColmapRunOptions& options);

// What a user without COLMAP is told (the menu item and the command line show it).
std::string ColmapInstallHint();

}  // namespace facet
