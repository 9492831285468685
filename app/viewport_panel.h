// The 3D panel: the model rendered into an offscreen framebuffer shown as an ImGui image;
// orbit, pan and zoom; textured mesh (shaded while there is no texture), wireframe, each
// camera as a frustum with its photo on the image plane, ground grid and world axes.
#pragma once

#include "app/app_state.h"

namespace facet::app {

// Draws the panel's contents into the current ImGui window (the caller owns the window).
void DrawViewportPanel(AppState* state);
// Frees GL resources (before the context goes away).
void ShutdownViewportPanel();

// Requests carried out by the next DrawViewportPanel, for menus, shortcuts and the input
// script: frame the whole model (boxes and camera centres), or look through the camera of
// a calibrated image (ignored when it is not calibrated).
void RequestViewportFrame();
void RequestViewportViewFromPhoto(Id image_id);

}  // namespace facet::app
