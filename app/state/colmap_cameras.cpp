#include "app/state/colmap_cameras.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <system_error>
#include <utility>

#include "app/state/app_state.h"
#include "core/io/colmap_import.h"
#include "core/util/child_process.h"

namespace facet::app {
namespace {

namespace fs = std::filesystem;

std::string FileNameOf(const std::string& path) { return fs::path(path).filename().string(); }

std::string JoinNames(const std::vector<std::string>& names) {
  std::string text;
  for (const std::string& n : names) text += (text.empty() ? "" : ", ") + n;
  return text;
}

// The log lines of a finished run that was applied: the photos placed and not, the alignment
// with its warnings, the time and the log file.
void LogApplied(AppState* state, const ColmapRunSummary& run, const ColmapImportReport& report,
                const ColmapAlignmentSummary& alignment) {
  const Project& project = state->document.project();
  std::vector<std::string> placed;
  for (Id id : report.updated_images)
    if (const Image* image = project.FindImage(id)) placed.push_back(FileNameOf(image->path));
  char seconds[32];
  std::snprintf(seconds, sizeof(seconds), "%.1f", run.time_ms / 1000.0);
  state->Log(LogLevel::kInfo, "COLMAP placed " + std::to_string(placed.size()) + " of " +
                                  std::to_string(placed.size() + report.missing_photos.size()) + " photos in " +
                                  seconds + " s: " + JoinNames(placed));
  if (!report.missing_photos.empty())
    state->Log(LogLevel::kWarning,
               "COLMAP could not place " + JoinNames(report.missing_photos) + "; their cameras are as they were");
  state->Log(LogLevel::kInfo, "Cameras aligned to the project: " + alignment.message);
  for (const std::string& w : alignment.warnings) state->Log(LogLevel::kWarning, "Alignment: " + w);
  if (!alignment.chosen_turns.empty()) {
    std::vector<std::string> turns;
    for (const auto& [id, quarter_turns] : alignment.chosen_turns)
      if (const Image* image = project.FindImage(id))
        turns.push_back(FileNameOf(image->path) + " " + std::to_string(90 * quarter_turns) + " deg");
    state->Log(LogLevel::kInfo, "Line axes turned to agree with COLMAP's cameras: " + JoinNames(turns));
  }
  state->Log(LogLevel::kInfo, "COLMAP's log: " + run.log_path);
}

}  // namespace

ColmapWork::~ColmapWork() {
  if (job && job->worker.joinable()) {
    job->cancel = true;
    job->worker.join();
  }
}

std::string ColmapExecutableFromEnvironment() {
  const char* configured = std::getenv("FACET_COLMAP");
  return configured != nullptr && *configured ? std::string(configured) : std::string("colmap");
}

bool ColmapAvailable(AppState* state) {
  ColmapWork& work = state->colmap;
  if (work.executable.empty()) work.executable = ColmapExecutableFromEnvironment();
  if (!work.available) work.available = !FindExecutable(work.executable).empty();
  return *work.available;
}

std::string ColmapWorkingDir(const AppState& state) {
  if (!state.project_path.empty()) {
    std::error_code ec;
    const fs::path project = fs::absolute(state.project_path, ec);
    return (project.parent_path() / (project.stem().string() + ".colmap")).string();
  }
  std::string cache;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg != nullptr && *xdg) {
    cache = xdg;
  } else if (const char* home = std::getenv("HOME"); home != nullptr && *home) {
    cache = std::string(home) + "/.cache";
  } else {
    cache = fs::temp_directory_path().string();
  }
  return (fs::path(cache) / "facet" / "colmap" / ("untitled-" + std::to_string(::getpid()))).string();
}

bool ColmapInFlight(const AppState& state) { return state.colmap.job != nullptr; }

bool StartColmapCameras(AppState* state) {
  ColmapWork& work = state->colmap;
  if (work.job) {
    state->Log(LogLevel::kError, "Cameras from all photos: COLMAP is already running");
    return false;
  }
  work.available.reset();  // installed or removed since the last look
  if (!ColmapAvailable(state)) {
    state->Log(LogLevel::kError, "Cameras from all photos: " + ColmapInstallHint() +
                                     " (FACET_COLMAP=" + work.executable + " is not found)");
    return false;
  }
  const Project& project = state->document.project();
  if (project.images.size() < 2) {
    state->Log(LogLevel::kError, "Cameras from all photos: COLMAP needs at least two photos in the project");
    return false;
  }
  ColmapRunOptions options;
  options.colmap_executable = work.executable;
  options.working_dir = ColmapWorkingDir(*state);
  for (const Image& image : project.images) options.photo_paths.push_back(PhotoFilePath(*state, image));
  options.single_camera = work.single_camera;
  options.num_threads = std::max(1, static_cast<int>(std::thread::hardware_concurrency()) - 1);

  auto job = std::make_unique<ColmapJob>();
  job->working_dir = options.working_dir;
  job->num_photos = static_cast<int>(options.photo_paths.size());
  job->started_s = state->time_s;
  job->document_generation = state->document_generation;
  ColmapJob* raw = job.get();
  options.cancel = &raw->cancel;
  options.progress = [raw](ColmapStage stage, int step, int) {
    raw->stage = static_cast<int>(stage);
    raw->step = step;
  };
  try {
    raw->worker = std::thread([raw, options = std::move(options)] {
      raw->summary = RunColmap(options);
      raw->finished = true;
    });
  } catch (const std::system_error& e) {
    state->Log(LogLevel::kError, std::string("Cameras from all photos: no thread to run COLMAP on (") + e.what() + ")");
    return false;
  }
  work.job = std::move(job);
  work.window_open = true;
  work.last_message.clear();
  work.last_log_path.clear();
  work.last_alignment.reset();
  work.last_applied = false;
  work.last_working_dir = work.job->working_dir;
  ++work.started;
  state->Log(LogLevel::kInfo,
             "COLMAP started on " + std::to_string(work.job->num_photos) + " photos in " + work.job->working_dir);
  return true;
}

void CancelColmapCameras(AppState* state) {
  if (state->colmap.job) state->colmap.job->cancel = true;
}

bool CollectColmapCameras(AppState* state, bool wait) {
  ColmapWork& work = state->colmap;
  if (!work.job) return false;
  // Not in the middle of a drag: the edit would land inside it.
  if (!wait && (!work.job->finished || state->drag_start)) return false;
  if (state->drag_start) CancelDrag(state);
  work.job->worker.join();
  const std::unique_ptr<ColmapJob> job = std::move(work.job);
  const ColmapRunSummary& run = job->summary;
  work.last_log_path = run.log_path;
  work.last_message = run.message;
  if (job->cancel || run.cancelled) {
    ++work.cancelled;
    work.last_message =
        "COLMAP cancelled during " + std::string(ColmapStageName(run.stage_reached)) + "; nothing was changed";
    state->Log(LogLevel::kInfo, work.last_message);
    return false;
  }
  if (!run.IsUsable()) {
    ++work.failed;
    work.available.reset();  // e.g. the program went away: looked up again
    state->Log(LogLevel::kError, "Cameras from all photos: " + run.message);
    return false;
  }
  if (job->document_generation != state->document_generation) {
    ++work.dropped;
    work.last_message = "COLMAP finished for a project that is no longer open; nothing was changed";
    state->Log(LogLevel::kWarning, work.last_message);
    return false;
  }
  Project edited = state->document.project();
  ColmapImportReport report;
  ColmapAlignmentSummary alignment;
  const std::string error =
      ApplyAlignedColmapCameras(run.model, ColmapAlignmentOptions{}, &edited, &report, &alignment);
  if (!error.empty()) {
    ++work.failed;
    work.last_message = error;
    state->Log(LogLevel::kError, "Cameras from all photos: " + error + "; nothing was changed");
    return false;
  }
  CommitEdit(state, "Cameras from COLMAP (" + std::to_string(report.updated_images.size()) + " photos)",
             std::move(edited));
  LogApplied(state, run, report, alignment);
  ++work.applied;
  work.last_applied = true;
  work.last_alignment = alignment;
  work.last_message = run.message + "; aligned: " + alignment.message;
  return true;
}

bool RunColmapCommand(AppState* state, const std::string& arg, std::string* error) {
  std::istringstream in(arg);
  std::vector<std::string> words;
  for (std::string w; in >> w;) words.push_back(w);
  const std::string verb = words.empty() ? std::string() : words[0];
  auto last_error = [&]() {
    for (auto it = state->log.rbegin(); it != state->log.rend(); ++it)
      if (it->level == LogLevel::kError) return it->text;
    return std::string("see the log");
  };
  if (verb == "start" && words.size() == 1) {
    if (!StartColmapCameras(state)) {
      *error = last_error();
      return false;
    }
    return true;
  }
  if (verb == "cancel" && words.size() == 1) {
    if (!ColmapInFlight(*state)) {
      *error = "colmap cancel: no COLMAP run in flight";
      return false;
    }
    CancelColmapCameras(state);
    return true;
  }
  if (verb == "wait" && words.size() == 1) {
    CollectColmapCameras(state, /*wait=*/true);
    return true;
  }
  if (verb == "wait-stage" && words.size() == 2) {
    // Tests: a picture of the progress at a known stage, however fast the worker is.
    for (int i = 0; i < 6000; ++i) {
      const ColmapJob* job = state->colmap.job.get();
      if (job == nullptr || job->finished) break;
      std::string name = ColmapStageName(static_cast<ColmapStage>(job->stage.load()));
      std::replace(name.begin(), name.end(), ' ', '-');
      if (name == words[1]) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    *error = "colmap wait-stage: the run is not at stage " + words[1] + " (ended, or 60 s passed)";
    return false;
  }
  if ((verb == "open" || verb == "close") && words.size() == 1) {
    state->colmap.window_open = verb == "open";
    return true;
  }
  if (verb == "single-camera" && words.size() == 2 && (words[1] == "on" || words[1] == "off")) {
    state->colmap.single_camera = words[1] == "on";
    return true;
  }
  *error = "colmap: expected start, cancel, wait, wait-stage STAGE, open, close or single-camera on|off";
  return false;
}

}  // namespace facet::app
