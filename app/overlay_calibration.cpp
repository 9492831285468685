#include "app/overlay_calibration.h"

namespace facet::app {

void DrawCalibrationOverlay(ImDrawList* /*draw_list*/, const AppState& /*state*/, const Image& /*image*/,
                            const ViewTransform& /*view*/, ImVec2 /*clip_min*/, ImVec2 /*clip_max*/,
                            const Eigen::Vector2d* /*mouse_uv*/) {}

}  // namespace facet::app
