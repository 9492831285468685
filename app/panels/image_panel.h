// The image panel: one tab per photo; zoom about the cursor, pan, fit, loupe; draws the
// line families, vanishing points, pins, line pins and the projected model over the photo,
// and turns mouse input into edits (draw and drag segments, place and drag pins, drag a line
// pin's end handle with a live re-solve, select a line pin by its line and delete it).
#pragma once

#include <memory>

#include "app/state/app_state.h"

namespace facet::app {

// Image-to-screen transform of the visible image view, for tests and the render report.
struct ImageViewReport {
  Id image_id = kNoId;
  float origin_x = 0, origin_y = 0;                      // screen position of image pixel (0, 0)'s centre
  float zoom = 1;                                        // screen px per image px
  float rect_x = 0, rect_y = 0, rect_w = 0, rect_h = 0;  // the view's screen rectangle
};

// Everything one image panel keeps between frames: each image's zoom and pan, the photos' GL
// textures, the drag in progress, the overlay and loupe options and the last frame's report.
// Owned by the shell (ShellState); two panels, or a test, each hold their own. The contents
// are private to image_panel.cpp and made on the first draw; ShutdownImagePanel frees its GL
// textures, and must run while the GL context is current.
struct ImagePanelState {
  struct Impl;
  std::unique_ptr<Impl> impl;
  ImagePanelState();
  ~ImagePanelState();
};

// Draws the panel's contents into the current ImGui window (the caller owns the window).
void DrawImagePanel(AppState* state, ImagePanelState* panel);
// The transform used in the last frame.
ImageViewReport LastImageViewReport(const ImagePanelState& panel);
// Fits the active image to the panel on the next frame (the F key does the same).
void RequestImageFit(ImagePanelState* panel);
// Shows `like`'s view (another panel's report) from the next frame on, scaled about the
// canvas centres so that what it showed fills this panel's canvas (File > Export view).
void RequestImageViewLike(ImagePanelState* panel, const ImageViewReport& like);
// Frees GL resources (before the context goes away).
void ShutdownImagePanel(ImagePanelState* panel);

}  // namespace facet::app
