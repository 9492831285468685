// The panels' parts of the user's texture choices (app/state/texture_choices.h): the selected
// face's "Texture from" combo, per-photo exclusions and the photos that textured it; a photo's
// "Use for texture" checkbox; the legend of View > Texture sources over the 3D panel.
#pragma once

#include <imgui.h>

#include "app/state/app_state.h"

namespace facet::app {

// Properties panel, a face selected. Records "texture.source" (the combo),
// "texture.source/auto", "texture.source/I" (its entries, when open) and "texture.exclude.I"
// for image index I.
void DrawFaceTextureSection(AppState* state, const Primitive& primitive, FaceId face);
// Image section: the active photo's "Use for texture" (recorded as "texture.use_photo").
void DrawPhotoTextureOption(AppState* state, const Image& image);
// The legend in the 3D panel's top-right corner (panel rectangle origin, size in screen
// px): a swatch and label per row of TextureLegend, and the grey of untextured faces.
void DrawTextureSourceLegend(ImDrawList* draw, const AppState& state, ImVec2 origin, ImVec2 size);

}  // namespace facet::app
