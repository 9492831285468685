// The properties panel's camera sections: the active image (its calibration modes and the
// vanishing-point result) and the solve figures.
#pragma once

#include <string>

#include "app/state/app_state.h"

namespace facet::app {

// Path, size, the calibration modes (principal point, focal length solved / known / prior with
// "From EXIF", horizon, distortion; each change one undoable edit followed by the re-solve)
// and the vanishing-point calibration's figures (focal +- std, residual sigma, outliers; per
// family VP RMS and the degeneracy figures under "Details").
void DrawImageSection(AppState* state);
// The joint solve's figures (with per-image pin RMS / max) when it ran, the geometry solve's
// folded under "Geometry solve (start)"; otherwise the geometry solve's. Undetermined
// parameters and conflicts.
void DrawSolveSection(AppState* state);

// The script command `calibration KEY VALUE` on the active image (app/state/input_script.h documents the
// keys). Each command is one undoable edit; false with a message for bad arguments or, for
// `focal exif`, a photo without an EXIF focal length.
bool RunCalibrationCommand(AppState* state, const std::string& arg, std::string* error);

}  // namespace facet::app
