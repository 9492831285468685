// The image panel's part of "Detect lines" (app/state/line_proposals.h): the button, the bar of
// the proposals (counts, accept all, discard; the selected proposal's family and removal),
// picking a proposal with a click, and drawing them: dashed in their family's colour, distinct
// from accepted segments (solid with end squares); the left-out segments faint grey.
#pragma once

#include <imgui.h>

#include "app/platform/image_tiles.h"
#include "app/state/app_state.h"

namespace facet::app {

// One toolbar row above the view.
void DrawLineProposalsBar(AppState* state, Id image_id);
// A left press on the view near a proposal of this image selects it. Returns true when the
// press was taken (the panel then starts no other interaction with it).
bool ClickLineProposal(AppState* state, Id image_id, const ViewTransform& view, bool view_hovered);
void DrawLineProposals(ImDrawList* draw_list, const AppState& state, Id image_id, const ViewTransform& view,
                       ImVec2 clip_min, ImVec2 clip_max);

}  // namespace facet::app
