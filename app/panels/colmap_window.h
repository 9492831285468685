// The window of File > Cameras from all photos (app/state/colmap_cameras.h): before a run, what
// it does, its option and Start; during one, a progress bar naming COLMAP's stage and Cancel;
// after, the outcome (photos placed, the alignment, or why nothing changed) and the path of
// COLMAP's log. Shown while the window is open or a run is in flight.
#pragma once

#include "app/state/app_state.h"

namespace facet::app {

void DrawColmapWindow(AppState* state);

}  // namespace facet::app
