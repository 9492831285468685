// Teach mode's drawing (View > Teach; what is drawn is computed in app/state/teach.h): the
// vanishing-point construction and the epipolar geometry over a photo, the vanishing
// directions as rays in the 3D panel, the Numbers window (K, R, t, F with copy buttons) and
// the modelling state's counts in the History panel.
#pragma once

#include <functional>

#include <imgui.h>
#include <Eigen/Core>

#include "app/platform/image_tiles.h"
#include "app/state/app_state.h"

namespace facet::app {

// Over `image` in the screen rectangle [clip_min, clip_max] of the image panel, after the
// other overlays. `texture_of` gives another image's photo texture (or null) for the insets
// that show the pointer's epipolar lines in the other photos. Returns the top of its text
// boxes (screen y), which stack up from the rectangle's bottom; clip_max.y when it drew none.
float DrawTeachImageOverlay(ImDrawList* draw_list, const AppState& state, const Image& image, const ViewTransform& view,
                            ImVec2 clip_min, ImVec2 clip_max, const std::function<const TiledTexture*(Id)>& texture_of);

// In the 3D panel: each calibrated image's vanishing directions as rays from its camera
// centre, `length` world units long; the rays of the epipolar overlay (DrawTeachRays); a note
// while the Solver steps window shows a stepped state. `to_screen` maps a world point to the screen (false
// when it is behind the view).
void DrawTeachViewportOverlay(ImDrawList* draw_list, const AppState& state, double length,
                              const std::function<bool(const Eigen::Vector3d&, ImVec2*)>& to_screen);

// In the 3D panel, with the epipolar overlay on: the two rays of each selected vertex's pins
// in two calibrated photos, their closest points and the gap between them (TeachRayPairs).
// Called by DrawTeachViewportOverlay.
void DrawTeachRays(ImDrawList* draw_list, const AppState& state,
                   const std::function<bool(const Eigen::Vector3d&, ImVec2*)>& to_screen);

// The floating Solver steps window (Step, Reset, the start, plots of cost, damping and step
// norm per trial, the constraint violations), while TeachView::solver_steps is on.
void DrawTeachStepsWindow(AppState* state);

// The floating Numbers window, while TeachView::numbers is on.
void DrawTeachNumbersWindow(AppState* state);

// The History panel's (K, F) table, one row per state, while TeachView::modelling_state is
// on; `target` receives the position of a clicked row (else it is left as it is).
void DrawTeachHistory(AppState* state, int* target);

}  // namespace facet::app
