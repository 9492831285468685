#include "core/io/colmap_run.h"

#include <chrono>
#include <filesystem>
#include <fstream>
#include <set>

#include "core/util/child_process.h"
#include "core/util/timer.h"

namespace facet {
namespace {

namespace fs = std::filesystem;

constexpr std::array<const char*, kNumColmapStages> kStageNames = {"preparing", "feature extraction", "matching",
                                                                   "mapping",   "reading the model",  "done"};

void AppendToLog(const std::string& path, const std::string& line) {
  std::ofstream log(path, std::ios::app);
  log << line << "\n";
}

std::string Join(const std::vector<std::string>& words) {
  std::string text;
  for (const std::string& w : words) text += (text.empty() ? "" : " ") + w;
  return text;
}

}  // namespace

const char* ColmapStageName(ColmapStage stage) {
  const int i = static_cast<int>(stage);
  return i >= 0 && i < kNumColmapStages ? kStageNames[i] : "unknown";
}

std::string ColmapInstallHint() {
  return "COLMAP is not installed: install it with `sudo apt-get install colmap` (Debian, Ubuntu; "
         "scripts/setup.sh does it) or from https://colmap.github.io, or give the path of the colmap program";
}

ColmapRunSummary RunColmap(const ColmapRunOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  ColmapRunSummary summary;
  summary.registered.assign(options.photo_paths.size(), false);
  auto stage_start = start;
  auto enter = [&](ColmapStage stage, int step) {
    summary.stage_time_ms[static_cast<int>(summary.stage_reached)] = internal::MsSince(stage_start);
    stage_start = std::chrono::steady_clock::now();
    summary.stage_reached = stage;
    if (options.progress) options.progress(stage, step, 3);
  };
  auto finish = [&](SolverTermination termination, std::string message) {
    summary.stage_time_ms[static_cast<int>(summary.stage_reached)] = internal::MsSince(stage_start);
    summary.termination = termination;
    summary.message = std::move(message);
    summary.time_ms = internal::MsSince(start);
    if (!summary.log_path.empty()) AppendToLog(summary.log_path, "# facet: " + summary.message);
    return summary;
  };
  if (options.progress) options.progress(ColmapStage::kPreparing, 0, 3);

  // Refusals before anything is touched.
  const std::string colmap = FindExecutable(options.colmap_executable);
  if (colmap.empty()) return finish(SolverTermination::kInvalidInput, ColmapInstallHint());
  if (options.working_dir.empty() || fs::path(options.working_dir).lexically_normal() == "/")
    return finish(SolverTermination::kInvalidInput, "COLMAP needs a working folder");
  if (options.photo_paths.size() < 2)
    return finish(SolverTermination::kInvalidInput, "COLMAP needs at least two photos");
  std::set<std::string> names;
  std::vector<std::string> photo_names;
  for (const std::string& photo : options.photo_paths) {
    std::error_code ec;
    if (!fs::is_regular_file(photo, ec))
      return finish(SolverTermination::kInvalidInput, "photo " + photo + " is not there");
    photo_names.push_back(fs::path(photo).filename().string());
    if (!names.insert(photo_names.back()).second)
      return finish(SolverTermination::kInvalidInput,
                    "two photos are named " + photo_names.back() + ": COLMAP tells photos apart by file name");
  }

  // The working folder: last run's files removed, the photos linked in by file name.
  const fs::path work = fs::absolute(options.working_dir);
  const fs::path images = work / "images";
  const fs::path database = work / "database.db";
  const fs::path sparse = work / "sparse";
  std::error_code ec;
  fs::create_directories(work, ec);
  for (const fs::path& old : {images, sparse, database, fs::path(database.string() + "-shm"),
                              fs::path(database.string() + "-wal"), work / "colmap.log"})
    fs::remove_all(old, ec);
  fs::create_directories(images, ec);
  fs::create_directories(sparse, ec);
  if (ec)
    return finish(SolverTermination::kInvalidInput,
                  "cannot prepare the working folder " + work.string() + ": " + ec.message());
  for (size_t i = 0; i < options.photo_paths.size(); ++i) {
    fs::create_symlink(fs::absolute(options.photo_paths[i]), images / photo_names[i], ec);
    if (ec)
      return finish(SolverTermination::kInvalidInput,
                    "cannot link " + options.photo_paths[i] + " into " + images.string() + ": " + ec.message());
  }
  summary.log_path = (work / "colmap.log").string();

  const std::string threads = std::to_string(options.num_threads);
  const bool exhaustive = static_cast<int>(options.photo_paths.size()) <= options.max_photos_for_exhaustive_matching;
  struct Step {
    ColmapStage stage;
    std::vector<std::string> arguments;
  };
  const std::vector<Step> steps = {
      {ColmapStage::kFeatureExtraction,
       {"feature_extractor", "--database_path", database.string(), "--image_path", images.string(),
        "--ImageReader.camera_model", options.camera_model, "--ImageReader.single_camera",
        options.single_camera ? "1" : "0", "--SiftExtraction.use_gpu", "0", "--SiftExtraction.max_image_size",
        std::to_string(options.max_image_size_px), "--SiftExtraction.max_num_features",
        std::to_string(options.max_num_features), "--SiftExtraction.num_threads", threads}},
      {ColmapStage::kMatching,
       {exhaustive ? "exhaustive_matcher" : "sequential_matcher", "--database_path", database.string(),
        "--SiftMatching.use_gpu", "0", "--SiftMatching.num_threads", threads}},
      {ColmapStage::kMapping,
       {"mapper", "--database_path", database.string(), "--image_path", images.string(), "--output_path",
        sparse.string(), "--Mapper.num_threads", threads}},
  };
  int step_number = 0;
  for (const Step& step : steps) {
    enter(step.stage, ++step_number);
    AppendToLog(summary.log_path,
                "# facet: " + std::string(ColmapStageName(step.stage)) + ": " + colmap + " " + Join(step.arguments));
    ChildProcessOptions child;
    child.executable = colmap;
    child.arguments = step.arguments;
    child.working_dir = work.string();
    child.log_path = summary.log_path;
    // No display is needed on the CPU path; offscreen keeps Qt from looking for one.
    child.environment = {{"QT_QPA_PLATFORM", "offscreen"}};
    if (options.cancel) child.should_cancel = [&] { return options.cancel->load(); };
    const ChildProcessResult result = RunChildProcess(child);
    if (result.cancelled) {
      summary.cancelled = true;
      return finish(SolverTermination::kFailed,
                    std::string("COLMAP cancelled during ") + ColmapStageName(step.stage) + "; nothing was changed");
    }
    if (!result.started) return finish(SolverTermination::kFailed, "COLMAP could not start: " + result.error);
    if (!result.Succeeded())
      return finish(SolverTermination::kFailed, std::string("COLMAP's ") + ColmapStageName(step.stage) + " failed (" +
                                                    (result.signal ? "signal " + std::to_string(result.signal)
                                                                   : "exit code " + std::to_string(result.exit_code)) +
                                                    "); its log is " + summary.log_path);
  }

  // The mapper writes one model per connected part of the photo set: the one with the most
  // photos is taken.
  enter(ColmapStage::kReadingModel, 0);
  size_t best_images = 0;
  std::string read_error;
  for (const auto& entry : fs::directory_iterator(sparse, ec)) {
    if (!entry.is_directory()) continue;
    ColmapModel model;
    const std::string error = ReadColmapModel(entry.path().string(), &model);
    if (!error.empty()) {
      read_error = error;
      continue;
    }
    if (model.images.size() > best_images) {
      best_images = model.images.size();
      summary.model = std::move(model);
      summary.model_dir = entry.path().string();
    }
  }
  if (best_images < 2)
    return finish(SolverTermination::kFailed,
                  read_error.empty()
                      ? "COLMAP registered fewer than two photos together; its log is " + summary.log_path
                      : read_error);
  std::set<std::string> registered_names;
  for (const ColmapImage& image : summary.model.images)
    registered_names.insert(fs::path(image.name).filename().string());
  for (size_t i = 0; i < photo_names.size(); ++i) {
    summary.registered[i] = registered_names.count(photo_names[i]) > 0;
    summary.num_registered += summary.registered[i];
    if (!summary.registered[i]) summary.warnings.push_back("COLMAP could not place photo " + photo_names[i]);
  }
  enter(ColmapStage::kDone, 0);
  return finish(SolverTermination::kConverged, "COLMAP placed " + std::to_string(summary.num_registered) + " of " +
                                                   std::to_string(photo_names.size()) + " photos in " +
                                                   std::to_string(static_cast<int>(internal::MsSince(start) / 1000.0)) +
                                                   " s");
}

}  // namespace facet
