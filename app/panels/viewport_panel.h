// The 3D panel: the model rendered into an offscreen framebuffer shown as an ImGui image;
// orbit, pan and zoom; textured mesh (shaded while there is no texture), wireframe, each
// camera as a frustum with its photo on the image plane, ground grid and world axes.
#pragma once

#include <array>

#include "app/state/app_state.h"

namespace facet::app {

// Draws the panel's contents into the current ImGui window (the caller owns the window).
// Needs a current OpenGL 3.3 core context (epoxy). Reads state->document, mesh, photos,
// active_image_id; writes only state->selection.box_id / box_corner (a click on or near a
// projected box corner picks it, a click on a box face picks the box, elsewhere clears both).
// Mouse and the F key act only while the panel is hovered or being dragged.
void DrawViewportPanel(AppState* state);
// The last frame's view, for the render report and tests: a world point X shows at panel
// pixel ((ndc.x + 1) / 2 * width_px, (1 - ndc.y) / 2 * height_px) with ndc = clip_from_world X
// (divided by w), i.e. at screen (origin + that / framebuffer scale).
struct ViewportReport {
  bool drawn = false;
  float origin_x = 0, origin_y = 0;  // screen position of the panel's top-left
  int width_px = 0, height_px = 0;   // framebuffer px
  std::array<double, 16> clip_from_world{};  // column-major
};
ViewportReport LastViewportReport();
// Frees GL resources (before the context goes away).
void ShutdownViewportPanel();

// Requests carried out by the next DrawViewportPanel, for menus, shortcuts and the input
// script: frame the model (its primitives; the camera centres when there are none), or look
// through the camera of a calibrated image (ignored when it is not calibrated).
void RequestViewportFrame();
void RequestViewportViewFromPhoto(Id image_id);

}  // namespace facet::app
