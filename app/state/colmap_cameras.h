// File > Cameras from all photos: COLMAP (core/io/colmap_run.h) on the project's photos, on a
// worker std::thread, so that the frame never waits for it. The worker only runs COLMAP and
// reports its stage through atomics; its result is applied on the main thread, when a frame
// collects it, as ONE undoable edit ("Cameras from COLMAP"): the reconstruction's cameras on
// the photos it placed, brought into the project's frame (ApplyAlignedColmapCameras,
// core/io/colmap_import.h), followed by the usual re-solve (CommitEdit). Cancel sets the run's
// cancel flag (the running stage's processes are ended) and leaves the project as it was; so
// does a run that fails, and one whose document was replaced meanwhile (new, open).
//
// The program: $FACET_COLMAP when set (a path or a name on PATH; tests point it at a stand-in
// script), else `colmap`. Without it the menu item is disabled and says ColmapInstallHint().
// The working folder (COLMAP's database, models and colmap.log, kept after the run): beside a
// saved project as NAME.colmap/, for an unsaved one $XDG_CACHE_HOME/facet/colmap/untitled-PID
// (~/.cache when XDG_CACHE_HOME is unset); never inside the repository.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "core/io/colmap_run.h"
#include "core/solve/colmap_alignment.h"

namespace facet::app {

struct AppState;

// One run on its worker. Heap-held (ColmapWork::job): the thread and the atomics stay put.
struct ColmapJob {
  std::thread worker;
  std::atomic<bool> cancel{false};
  std::atomic<bool> finished{false};  // summary is written; the worker is about to end
  std::atomic<int> stage{0};          // ColmapStage, as the worker reported it last
  std::atomic<int> step{0};           // 1-based COLMAP step (0: preparing, reading)
  ColmapRunSummary summary;           // the worker's; read only once finished
  std::string working_dir;
  int num_photos = 0;
  double started_s = 0.0;                 // AppState::time_s at the start
  std::uint64_t document_generation = 0;  // AppState::document_generation at the start
};

struct ColmapWork {
  // What the app runs: $FACET_COLMAP or "colmap", and whether it is there (looked up once,
  // again after a run could not start it).
  std::string executable;
  std::optional<bool> available;
  bool single_camera = false;  // the window's "one camera and lens" option
  bool window_open = false;    // the window: its options before, its progress during, the outcome after
  std::unique_ptr<ColmapJob> job;
  // The outcome of the last run, shown in the window until the next one.
  std::string last_message;
  std::string last_log_path;
  std::string last_working_dir;
  bool last_applied = false;
  std::optional<ColmapAlignmentSummary> last_alignment;
  int started = 0, applied = 0, cancelled = 0, failed = 0, dropped = 0;

  ColmapWork() = default;
  ColmapWork(const ColmapWork&) = delete;
  ColmapWork& operator=(const ColmapWork&) = delete;
  // A run still going is cancelled and waited for (its processes ended within their grace).
  ~ColmapWork();
};

// $FACET_COLMAP when set and not empty, else "colmap".
std::string ColmapExecutableFromEnvironment();
// Whether the program is there (cached in state->colmap).
bool ColmapAvailable(AppState* state);
// The working folder for the current project (see above).
std::string ColmapWorkingDir(const AppState& state);

// Starts COLMAP on every photo of the project. False (logged as an error, nothing started)
// while a run is in flight, without the program (the install hint), with fewer than two
// photos, or when no thread can be had.
bool StartColmapCameras(AppState* state);
bool ColmapInFlight(const AppState& state);
// Asks the run in flight to stop; the frame that collects it logs the cancel.
void CancelColmapCameras(AppState* state);
// Once per frame (wait = false) and from `colmap wait` (wait = true): a finished run is joined
// and applied (or its failure or cancel logged). Returns true when cameras were applied.
bool CollectColmapCameras(AppState* state, bool wait);

// The script command `colmap ARGS` (app/state/input_script.h):
//   colmap start        StartColmapCameras
//   colmap cancel       CancelColmapCameras (nothing in flight: refused)
//   colmap wait         waits for the run in flight and collects it
//   colmap wait-stage STAGE   waits (at most 60 s) until the run in flight is at STAGE
//                       (ColmapStageName, spaces as '-': feature-extraction, matching,
//                       mapping); refused when it ended first
//   colmap open|close   the window (File > Cameras from all photos...)
//   colmap single-camera on|off   the window's one-lens option
bool RunColmapCommand(AppState* state, const std::string& arg, std::string* error);

}  // namespace facet::app
