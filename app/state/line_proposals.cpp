#include "app/state/line_proposals.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <sstream>
#include <system_error>
#include <utility>

#include "app/state/app_state.h"
#include "core/io/project_io.h"
#include "core/util/input_limits.h"

namespace facet::app {
namespace {

bool ValidIndex(const AppState& state, int index) {
  return state.line_proposals && index >= 0 && index < static_cast<int>(state.line_proposals->segments.size());
}

// The detection's options from the image's calibration settings, so that the proposals'
// families are those the calibration will see after accepting.
ManhattanLinesOptions OptionsFor(const Image& image) {
  ManhattanLinesOptions options;
  VpCalibrationOptions& cal = options.calibration;
  cal.principal_point_mode = image.principal_point_mode;
  cal.fixed_principal_point_px = image.fixed_principal_point_px;
  if (image.focal_mode == FocalMode::kFixed) cal.fixed_focal_px = image.fixed_focal_px;
  if (image.focal_mode == FocalMode::kPrior) {
    cal.focal_prior_px = image.focal_prior_px;
    cal.focal_prior_std_px = image.focal_prior_std_px;
  }
  return options;
}

}  // namespace

bool StartLineDetection(AppState* state, Id image_id) {
  const Image* image = state->document.project().FindImage(image_id);
  if (image == nullptr) {
    state->Log(LogLevel::kError, "Detect lines: no such image");
    return false;
  }
  const std::string path =
      state->project_path.empty() ? image->path : ResolveImagePath(state->project_path, image->path);
  auto photo = state->photos.find(image_id);
  if (photo == state->photos.end()) {
    // Just added (the frame loads new photos after the edit): load it now, as that would.
    ImageReadResult read = ReadImage(path);
    if (!read.ok()) {
      state->Log(LogLevel::kError, "Detect lines: " + read.error);
      return false;
    }
    photo = state->photos.emplace(image_id, std::move(read.image)).first;
  }
  if (photo->second.empty()) {
    state->Log(LogLevel::kError, "Detect lines: the photo is empty");
    return false;
  }
  const auto start = std::chrono::steady_clock::now();
  DropLineDetection(state);
  state->line_proposals.reset();
  LineDetectionJob job;
  job.image_id = image_id;
  job.photo_name = std::filesystem::path(path).filename().string();
  job.started_s = state->time_s;
  const ManhattanLinesOptions options = OptionsFor(*image);
  // The worker detects on its own copy of the photo, made first thing (the app may free the
  // original once photo_copied is ready: photo removed, project replaced).
  auto copied = std::make_shared<std::promise<void>>();
  job.photo_copied = copied->get_future().share();
  std::shared_future<void> held;
  if (state->line_detection.hold) held = state->line_detection.hold_released;
  try {
    job.result = std::async(std::launch::async, [source = &photo->second, copied, options, held] {
      ImageRgba8 copy;
      try {
        copy = *source;
      } catch (...) {
        copied->set_value();
        throw;
      }
      copied->set_value();
      if (held.valid()) held.wait();
      return DetectManhattanLines(copy, options);
    });
  } catch (const std::system_error& e) {
    // No thread to be had: detect here rather than not at all.
    state->Log(LogLevel::kWarning, std::string("Detect lines: running on the main thread (") + e.what() + ")");
    copied->set_value();
    std::promise<ManhattanLinesSummary> done;
    done.set_value(DetectManhattanLines(photo->second, options));
    job.result = done.get_future();
  }
  state->line_detection.job = std::move(job);
  ++state->line_detection.stats.started;
  state->line_detection.stats.last_start_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return true;
}

bool LineDetectionInFlight(const AppState& state) { return state.line_detection.job.has_value(); }

bool CollectLineDetection(AppState* state, bool wait) {
  LineDetectionWork& work = state->line_detection;
  std::erase_if(work.abandoned, [](const std::future<ManhattanLinesSummary>& f) {
    return f.wait_for(std::chrono::seconds(0)) == std::future_status::ready;
  });
  if (!work.job) return false;
  LineDetectionJob& job = *work.job;
  if (wait) {
    HoldLineDetection(state, false);
    job.result.wait();
  } else if (job.result.wait_for(std::chrono::seconds(0)) != std::future_status::ready) {
    ++job.frames_in_flight;
    return false;
  }
  const Id image_id = job.image_id;
  const int frames_in_flight = job.frames_in_flight;
  ManhattanLinesSummary found;
  try {
    found = job.result.get();
  } catch (const std::exception& e) {
    found.termination = SolverTermination::kFailed;
    found.message = std::string("the detection failed: ") + e.what();
  }
  work.job.reset();
  if (state->document.project().FindImage(image_id) == nullptr) {
    ++work.stats.dropped;
    state->Log(LogLevel::kInfo, "Detect lines: the photo left the project before its lines were found");
    return false;
  }
  ++work.stats.collected;
  work.stats.last_image_id = image_id;
  work.stats.last_frames_in_flight = frames_in_flight;
  if (!found.IsUsable()) {
    state->Log(LogLevel::kError, "Detect lines: " + found.message);
    return false;
  }
  LineProposals proposals;
  proposals.image_id = image_id;
  proposals.segments = found.labelled_segments;
  for (Segment& s : proposals.segments) s.image_id = image_id;
  for (size_t i = 0; i < found.segments_px.size(); ++i)
    if (found.segment_family[i] < 0) proposals.outliers.push_back(found.segments_px[i]);
  proposals.focal_px = found.calibration.focal_px;
  proposals.message = found.message;
  state->line_proposals = std::move(proposals);
  char text[200];
  std::snprintf(text, sizeof(text),
                "Detect lines: %d proposed (x %d, y %d, z %d), %d left out, f ~ %.0f px in %.0f ms; "
                "accept to calibrate",
                static_cast<int>(found.labelled_segments.size()), found.segments_per_family[0],
                found.segments_per_family[1], found.segments_per_family[2], found.num_outliers,
                found.calibration.focal_px, found.time_ms);
  state->Log(LogLevel::kInfo, text);
  return true;
}

void HoldLineDetection(AppState* state, bool hold) {
  LineDetectionWork& work = state->line_detection;
  if (hold && !work.hold) {
    work.hold.emplace();
    work.hold_released = work.hold->get_future().share();
  } else if (!hold && work.hold) {
    work.hold->set_value();
    work.hold.reset();
  }
}

void WaitForLineDetectionPhotoCopy(const AppState& state) {
  if (state.line_detection.job) state.line_detection.job->photo_copied.wait();
}

void DropLineDetection(AppState* state) {
  LineDetectionWork& work = state->line_detection;
  if (!work.job) return;
  work.job->photo_copied.wait();  // an abandoned worker never reads the app's photos again
  work.abandoned.push_back(std::move(work.job->result));
  work.job.reset();
  ++work.stats.dropped;
}

bool DetectLineProposals(AppState* state, Id image_id) {
  return StartLineDetection(state, image_id) && CollectLineDetection(state, /*wait=*/true);
}

bool RemoveLineProposal(AppState* state, int index) {
  if (!ValidIndex(*state, index)) return false;
  LineProposals& p = *state->line_proposals;
  p.segments.erase(p.segments.begin() + index);
  if (p.selected == index) p.selected = -1;
  if (p.selected > index) --p.selected;
  return true;
}

bool AssignLineProposal(AppState* state, int index, Axis axis) {
  if (!ValidIndex(*state, index)) return false;
  state->line_proposals->segments[index].axis = axis;
  return true;
}

bool AcceptLineProposals(AppState* state) {
  if (!state->line_proposals || state->line_proposals->segments.empty()) {
    state->Log(LogLevel::kError, "Accept lines: there are no proposed lines");
    return false;
  }
  const LineProposals proposals = *state->line_proposals;
  if (state->document.project().FindImage(proposals.image_id) == nullptr) {
    state->line_proposals.reset();
    state->Log(LogLevel::kError, "Accept lines: the image is gone");
    return false;
  }
  Project edited = state->document.project();
  const size_t already =
      static_cast<size_t>(std::count_if(edited.segments.begin(), edited.segments.end(),
                                        [&](const Segment& s) { return s.image_id == proposals.image_id; }));
  if (already + proposals.segments.size() > kMaxCalibrationSegments) {
    state->Log(LogLevel::kError, "Accept lines: a photo may have at most " + std::to_string(kMaxCalibrationSegments) +
                                     " line segments; this one would have " +
                                     std::to_string(already + proposals.segments.size()));
    return false;
  }
  for (Segment s : proposals.segments) {
    s.id = edited.NewId();
    s.image_id = proposals.image_id;
    edited.segments.push_back(s);
  }
  state->line_proposals.reset();
  CommitEdit(state, "Accept " + std::to_string(proposals.segments.size()) + " detected lines", std::move(edited));
  return true;
}

void DiscardLineProposals(AppState* state) { state->line_proposals.reset(); }

void ValidateLineProposals(AppState* state) {
  if (state->line_proposals && state->document.project().FindImage(state->line_proposals->image_id) == nullptr)
    state->line_proposals.reset();
}

bool RunLinesCommand(AppState* state, const std::string& arg, std::string* error) {
  std::istringstream in(arg);
  std::string verb;
  in >> verb;
  std::vector<std::string> words;
  for (std::string w; in >> w;) words.push_back(w);
  auto index_arg = [&](size_t i, int* out) {
    if (i >= words.size()) return false;
    char* end = nullptr;
    const long v = std::strtol(words[i].c_str(), &end, 10);
    if (*end != '\0') return false;
    *out = static_cast<int>(v);
    return true;
  };
  if (verb == "detect" && words.size() <= 1) {
    Id image_id = state->active_image_id;
    if (words.size() == 1) {
      int index = -1;
      const auto& images = state->document.project().images;
      if (!index_arg(0, &index) || index < 0 || index >= static_cast<int>(images.size())) {
        *error = "lines detect: no image " + words[0];
        return false;
      }
      image_id = images[index].id;
    }
    if (!DetectLineProposals(state, image_id)) {
      *error = state->log.empty() ? "lines detect failed" : state->log.back().text;
      return false;
    }
    return true;
  }
  if (verb == "wait" && words.empty()) {
    CollectLineDetection(state, /*wait=*/true);  // a failed detection only logs, as in the app
    return true;
  }
  if (verb == "hold" && words.size() == 1 && (words[0] == "on" || words[0] == "off")) {
    HoldLineDetection(state, words[0] == "on");
    return true;
  }
  // The commands below act on the proposals: a detection in flight makes them first.
  if (verb != "on-add") CollectLineDetection(state, /*wait=*/true);
  if ((verb == "remove" || verb == "select") && words.size() == 1) {
    int index = -1;
    if (!index_arg(0, &index) || !ValidIndex(*state, index)) {
      *error = "lines " + verb + ": no proposed line " + words[0];
      return false;
    }
    if (verb == "remove") return RemoveLineProposal(state, index);
    state->line_proposals->selected = index;
    return true;
  }
  if (verb == "assign" && words.size() == 2) {
    int index = -1;
    const std::optional<Axis> axis = AxisFromName(words[1]);
    if (!index_arg(0, &index) || !ValidIndex(*state, index) || !axis) {
      *error = "lines assign: expected a proposed line's index and x, y or z";
      return false;
    }
    return AssignLineProposal(state, index, *axis);
  }
  if (verb == "accept" && words.empty()) {
    if (!AcceptLineProposals(state)) {
      *error = state->log.empty() ? "lines accept failed" : state->log.back().text;
      return false;
    }
    return true;
  }
  if (verb == "discard" && words.empty()) {
    DiscardLineProposals(state);
    return true;
  }
  if (verb == "on-add" && words.size() == 1 && (words[0] == "on" || words[0] == "off")) {
    state->detect_lines_on_add = words[0] == "on";
    return true;
  }
  *error =
      "lines: expected detect [IMAGE_INDEX], wait, remove I, assign I x|y|z, select I, accept, discard, "
      "on-add on|off or hold on|off; got '" +
      arg + "'";
  return false;
}

}  // namespace facet::app
