// The properties panel's camera sections: the active image (its calibration modes and the
// vanishing-point result) and the solve figures.
#pragma once

#include <string>

#include "app/state/app_state.h"

namespace facet::app {

// The last "From EXIF" outcome (button or script command), shown under the button until
// another image is active. UI feedback, not document state: the properties panel's own state
// (PropertiesPanelState, app/panels/side_panels.h) holds it.
struct ExifFeedback {
  Id image_id = kNoId;
  bool found = false;
  std::string message;
};

// Path, size, the calibration modes (principal point, focal length solved / known / prior with
// "From EXIF", horizon, distortion; each change one undoable edit followed by the re-solve)
// and the vanishing-point calibration's figures (focal +- std, residual sigma, outliers; per
// family VP RMS and the degeneracy figures under "Details").
void DrawImageSection(AppState* state, ExifFeedback* exif_feedback);
// The joint solve's figures (with per-image pin RMS / max) when it ran, the geometry solve's
// folded under "Geometry solve (start)"; otherwise the geometry solve's. Undetermined
// parameters and conflicts.
void DrawSolveSection(AppState* state);

// The script command `calibration KEY VALUE` on the active image (app/state/input_script.h
// documents the keys). Each command is one undoable edit; false with a message for bad
// arguments or, for `focal exif`, a photo without an EXIF focal length (*exif_feedback then
// says why, as the button does).
bool RunCalibrationCommand(AppState* state, ExifFeedback* exif_feedback, const std::string& arg, std::string* error);

}  // namespace facet::app
