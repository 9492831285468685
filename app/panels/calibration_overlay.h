// Calibration overlays of the image panel that teach what the solver sees: the user's horizon
// (the 1-VP + horizon mode, dashed and labelled "horizon (given)", distinct from the fitted
// horizon app/panels/image_overlay.h draws), the segments the calibration flagged as outliers
// (crossed out), and the epipolar lines in this image of the selected vertices' pins in the
// other calibrated images (core/solve/multiview_init.h).
#pragma once

#include <imgui.h>

#include "app/platform/image_tiles.h"
#include "app/state/app_state.h"

namespace facet::app {

// Draws over `image` in the screen rectangle [clip_min, clip_max], after the model overlays.
// `mouse_uv` is the cursor in the image's pixels when it is over the view (else null).
void DrawCalibrationOverlay(ImDrawList* draw_list, const AppState& state, const Image& image, const ViewTransform& view,
                            ImVec2 clip_min, ImVec2 clip_max, const Eigen::Vector2d* mouse_uv);

}  // namespace facet::app
