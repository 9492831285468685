// The 3D panel: the model rendered into an offscreen framebuffer shown as an ImGui image;
// orbit, pan and zoom; textured mesh (shaded while there is no texture), wireframe, each
// camera as a frustum with its photo on the image plane, ground grid and world axes.
#pragma once

#include <array>
#include <memory>

#include "app/state/app_state.h"

namespace facet::app {

// Everything one 3D panel keeps between frames: its GL resources, the orbit camera, display
// toggles, the mouse interaction (with the Move tool's drag) and the last frame's report.
// Owned by the shell (ShellState); two panels, or a test, each hold their own. The contents
// are private to viewport_panel.cpp and made on the first draw; ShutdownViewportPanel frees
// the GL resources, and must run while the GL context is current.
struct ViewportPanelState {
  struct Impl;
  std::unique_ptr<Impl> impl;
  ViewportPanelState();
  ~ViewportPanelState();
};

// Draws the panel's contents into the current ImGui window (the caller owns the window).
// Needs a current OpenGL 3.3 core context (epoxy). Reads state->document, mesh, photos,
// active_image_id; writes only state->selection.box_id / box_corner (a click on or near a
// projected box corner picks it, a click on a box face picks the box, elsewhere clears both).
// Mouse and the F key act only while the panel is hovered or being dragged.
void DrawViewportPanel(AppState* state, ViewportPanelState* panel);
// From now on the panel draws the picture alone, without the UI's help, counts and tool
// hints over it (File > Export view's panel).
void ShowViewportPictureOnly(ViewportPanelState* panel);
// The last frame's view, for the render report and tests: a world point X shows at panel
// pixel ((ndc.x + 1) / 2 * width_px, (1 - ndc.y) / 2 * height_px) with ndc = clip_from_world X
// (divided by w), i.e. at screen (origin + that / framebuffer scale).
struct ViewportReport {
  bool drawn = false;
  float origin_x = 0, origin_y = 0;          // screen position of the panel's top-left
  int width_px = 0, height_px = 0;           // framebuffer px
  std::array<double, 16> clip_from_world{};  // column-major
};
ViewportReport LastViewportReport(const ViewportPanelState& panel);
// Frees GL resources (before the context goes away).
void ShutdownViewportPanel(ViewportPanelState* panel);

// Requests carried out by the next DrawViewportPanel, for menus, shortcuts and the input
// script: frame the model (its primitives; the camera centres when there are none), or look
// through the camera of a calibrated image (ignored when it is not calibrated).
void RequestViewportFrame(ViewportPanelState* panel);
void RequestViewportViewFromPhoto(ViewportPanelState* panel, Id image_id);
// Gives `to` the view of `from` (orbit or photo view, display toggles, what was framed), so
// that it shows the same picture at its own size (File > Export view).
void CopyViewportView(const ViewportPanelState& from, ViewportPanelState* to);

}  // namespace facet::app
