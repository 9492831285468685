// Lines found for the user in the app: "Detect lines" (the image panel's button, or the Add
// photo option) runs core/estimators/line_detection.h on the photo, on a worker thread, and
// shows its families as proposals when it finishes, on the photo it was started for (also
// when the user has switched to another meanwhile). Proposals are not yet part of the project.
// The user removes single proposals or re-assigns them to another family, then accepts them
// all as ONE undoable edit that adds them as the image's line segments (the calibration then
// runs as for drawn lines), or discards them. Proposals are view state: undo never sees them,
// and they go when the project or the image changes; so does a detection still in flight.
#pragma once

#include <future>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/estimators/line_detection.h"
#include "core/geometry/segment.h"

namespace facet::app {

struct AppState;

struct LineProposals {
  Id image_id = kNoId;
  std::vector<Segment> segments;          // proposed, `axis` the family (ids unset)
  std::vector<Eigen::Vector4d> outliers;  // detected but in no family: shown faintly
  int selected = -1;                      // index into segments, -1 for none
  double focal_px = 0.0;                  // the detection's own calibration, for the status line
  std::string message;                    // the detection's summary
};

// A detection on a worker thread. The worker first copies the photo from AppState::photos
// (12 MP: 48 MB, too slow for the frame that starts it), then detects on its copy; until
// photo_copied is ready, the app frees no loaded photo (WaitForLineDetectionPhotoCopy).
struct LineDetectionJob {
  Id image_id = kNoId;
  std::shared_future<void> photo_copied;
  std::string photo_name;    // the photo's file name, for the toolbar
  double started_s = 0.0;    // AppState::time_s when it started
  int frames_in_flight = 0;  // frames drawn while the worker ran
  std::future<ManhattanLinesSummary> result;
};

struct LineDetectionStats {
  int started = 0;
  int collected = 0;              // results that arrived for a photo still in the project
  int dropped = 0;                // photo removed, project closed or replaced, or a newer detection started
  Id last_image_id = kNoId;       // of the latest collected result
  int last_frames_in_flight = 0;  // of the latest collected result
  // Main-thread time of the latest start (thread start; the photo's loading when it was
  // just added is not counted).
  double last_start_ms = 0.0;
};

struct LineDetectionWork {
  std::optional<LineDetectionJob> job;
  // Dropped jobs whose worker still runs: kept until it finishes, since the future of
  // std::async waits for its worker when destroyed and the frame must not.
  std::vector<std::future<ManhattanLinesSummary>> abandoned;
  LineDetectionStats stats;
  // `lines hold on` (scripts): a detection started while held waits to begin until the hold
  // is let go (`lines hold off`, or a wait for the result), so a test can show the frames
  // going on while the worker has surely not finished. Declared last: destroyed first, a
  // held promise lets its workers go (broken promise), so the futures above never wait
  // forever.
  std::optional<std::promise<void>> hold;
  std::shared_future<void> hold_released;
};

// Starts detecting lines on the image's photo (loaded first when it was just added) on a
// worker thread, with the image's principal point and focal-length modes; clears the
// proposals, and drops a detection still in flight. False (logged) without such an image or
// photo.
bool StartLineDetection(AppState* state, Id image_id);
bool LineDetectionInFlight(const AppState& state);
// Once per frame, and wherever a result is needed: a finished detection becomes the
// proposals of its image (or logs why there are none); one still running counts a frame in
// flight, or with `wait` is waited for. Returns true when a detection was collected and made
// proposals.
bool CollectLineDetection(AppState* state, bool wait);
// The detection in flight is dropped: its result will never be shown (project closed or
// replaced).
void DropLineDetection(AppState* state);
// `lines hold on|off` (above).
void HoldLineDetection(AppState* state, bool hold);
// Called before the app frees or replaces a loaded photo: waits until the detection in
// flight has its own copy (at once, unless it started a moment ago).
void WaitForLineDetectionPhotoCopy(const AppState& state);
// StartLineDetection, then waits for it: the script command `lines detect`. False (logged)
// when either fails.
bool DetectLineProposals(AppState* state, Id image_id);
// Removes proposal `index` / gives it another family; false for a bad index.
bool RemoveLineProposal(AppState* state, int index);
bool AssignLineProposal(AppState* state, int index, Axis axis);
// Adds the proposals to the project as the image's segments, one edit labelled
// "Accept N detected lines", and clears them. False (nothing changes) without proposals or
// when their image left the project.
bool AcceptLineProposals(AppState* state);
void DiscardLineProposals(AppState* state);
// Drops proposals whose image is gone (called once per frame).
void ValidateLineProposals(AppState* state);

// The script command `lines ARGS` (app/state/input_script.h):
//   lines detect [IMAGE_INDEX]     DetectLineProposals on the image (default: the active one)
//   lines wait                     waits for the detection in flight (button, Add photo option)
//   lines remove I | lines assign I x|y|z | lines select I | lines accept | lines discard
//                                  (each first waits for the detection in flight)
//   lines on-add on|off            the Add photo option: detect lines on every added photo
//   lines hold on|off              detections started while held wait to begin until let go
//                                  (tests: frames drawn while the worker surely runs)
bool RunLinesCommand(AppState* state, const std::string& arg, std::string* error);

}  // namespace facet::app
