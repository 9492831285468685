// Lines found for the user in the app: "Detect lines" (the image panel's button, or the Add
// photo option) runs core/estimators/line_detection.h on the photo and shows its families as
// proposals, which are not yet part of the project. The user removes single proposals or
// re-assigns them to another family, then accepts them all as ONE undoable edit that adds
// them as the image's line segments (the calibration then runs as for drawn lines), or
// discards them. Proposals are view state: undo never sees them, and they go when the
// project or the image changes.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

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

// Detects lines on the image's photo (which must be loaded), with the image's principal
// point and focal-length modes, and makes them the proposals (replacing earlier ones). A
// failure (no photo, too few lines, one direction) logs the reason and leaves no proposals.
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
//   lines remove I | lines assign I x|y|z | lines select I | lines accept | lines discard
//   lines on-add on|off            the Add photo option: detect lines on every added photo
bool RunLinesCommand(AppState* state, const std::string& arg, std::string* error);

}  // namespace facet::app
