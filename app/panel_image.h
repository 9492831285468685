// The properties panel's camera sections: the active image (its calibration modes and the
// vanishing-point result) and the solve figures.
#pragma once

#include <string>

#include "app/app_state.h"

namespace facet::app {

// Path, size, camera, calibration modes and the vanishing-point calibration's figures.
void DrawImageSection(AppState* state);
// The geometry and joint solves' figures, undetermined parameters and conflicts.
void DrawSolveSection(AppState* state);

// The script command `calibration KEY VALUE` on the active image (app/script.h).
bool RunCalibrationCommand(AppState* state, const std::string& arg, std::string* error);

}  // namespace facet::app
