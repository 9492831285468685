// The user's say over the texture (issue 13): which photo(s) textured each face, shown as a
// colour per photo in the 3D panel (View > Texture sources) with a legend; per face, a forced
// source photo or excluded photos; per photo, whether it textures at all; and the export's
// resolution in texels per project unit. The choices are undoable edits of the project
// (Image::use_for_texture, Primitive::face_textures, stored in the project file); the view
// toggle and the export resolution are view settings, not part of the project.
// Texture choices change no geometry, so their edits commit without a re-solve.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/scene/project.h"
#include "core/texture/textured_mesh.h"

namespace facet::app {

struct AppState;

// View and export settings of the texture, in AppState::texture.
struct TextureView {
  bool show_sources = false;            // tint each face by its dominant source photo, with a legend
  double export_texels_per_unit = 0.0;  // File > Export's resolution; 0: as the photos give it
};

// The colour of the photo at `image_index` in project.images (sRGB, 0-255): every photo its
// own hue (golden-ratio steps round the hue circle, never the selection's orange nor grey).
std::array<std::uint8_t, 3> TextureSourceColour(size_t image_index);
// "photo 2 (leuvenA.jpg)": the 1-based index the panels and the legend use, and the file name.
std::string PhotoLabel(const Project& project, size_t image_index);

// What the last bake reported for a face, or null (not baked yet, or not a face of the mesh).
const FaceTextureReport* BakedFaceSources(const AppState& state, Id primitive_id, FaceId face);

// One row of the legend: a photo that is the dominant source of at least one face, or that
// the user took out of texturing (then faces == 0 and used == false).
struct TextureLegendRow {
  size_t image_index = 0;
  std::array<std::uint8_t, 3> colour{};
  std::string label;  // PhotoLabel
  int faces = 0;      // faces whose largest share is this photo's
  bool used = true;   // Image::use_for_texture
};
std::vector<TextureLegendRow> TextureLegend(const AppState& state);

// The edits; each is one history entry, refused (logged as an error, nothing changed) for a
// face or photo that is not in the project. Forcing a photo re-admits it for that face;
// excluding the forced photo makes the face automatic again.
// Forces `image_id` as the face's source, or kNoId: the bake chooses.
bool SetFaceTextureSourceEdit(AppState* state, Id primitive_id, FaceId face, Id image_id);
// Excludes a photo from one face (or admits it again).
bool SetFaceTextureExcludedEdit(AppState* state, Id primitive_id, FaceId face, Id image_id, bool excluded);
// "Use for texture" of a photo.
bool SetPhotoUsedForTextureEdit(AppState* state, Id image_id, bool used);

// Atlas pages of an export (the 3D panel draws one page; the exporters write them all).
constexpr int kExportAtlasPages = 8;

// The mesh File > Export writes: the 3D panel's bake when the export resolution is 0 (after
// FinishBake), else a bake of the current project at export_texels_per_unit with up to 8 atlas
// pages, as `facet export --texels-per-unit` makes it (on this thread: the user waits for the
// file anyway). False with the bake's message when that bake fails.
bool MeshForExport(AppState* state, TexturedMesh* mesh, std::string* message);

// The script command `texture ARGS` (app/state/input_script.h); IMAGE_INDEX counts from 0:
//   source auto|IMAGE_INDEX            the selected face's forced photo
//   exclude IMAGE_INDEX on|off         exclude a photo from the selected face
//   use IMAGE_INDEX on|off             a photo's "Use for texture"
//   sources on|off                     View > Texture sources
//   export-resolution N                File > Export's texels per project unit (0: from the photos)
bool RunTextureCommand(AppState* state, const std::string& arg, std::string* error);

}  // namespace facet::app
