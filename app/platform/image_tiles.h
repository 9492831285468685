// A photo as a grid of GL textures, so that images larger than GL_MAX_TEXTURE_SIZE display,
// and the ImDrawList calls that draw it under an image-to-screen transform with the filter
// the zoom asks for (mipmapped linear when zoomed out, nearest past 1:1).
// Needs a current GL context for every function except the plain queries.
#pragma once

#include <cstdint>
#include <vector>

#include <imgui.h>

#include "core/image/image_io.h"

namespace facet::app {

// One tile: the texture holds image pixels [x0 - pad_left, x0 + w + pad_right) x (same in y),
// of which only [x0, x0 + w) x [y0, y0 + h) is drawn; the one-pixel padding lets bilinear
// filtering blend across tile seams.
struct ImageTile {
  unsigned int texture = 0;  // GLuint
  int x0 = 0, y0 = 0, w = 0, h = 0;
  int tex_x0 = 0, tex_y0 = 0, tex_w = 0, tex_h = 0;  // the texture's pixel rectangle
};

struct TiledTexture {
  int width = 0;
  int height = 0;
  std::vector<ImageTile> tiles;
  // Sampler objects (GLuint) that override the tiles' filter per draw: linear (mipmapped) when
  // zoomed out, nearest past 1:1. Made with the texture, deleted with it.
  unsigned int linear_sampler = 0;
  unsigned int nearest_sampler = 0;
  bool Empty() const { return tiles.empty(); }
};

// The tile size used for new textures (asked of GL at each call): min(GL_MAX_TEXTURE_SIZE,
// 4096), or the value of the environment variable FACET_IMAGE_TILE_PX when set (to test
// tiling with small tiles).
int ImageTileSizePx();

// Uploads `image` (RGBA8) as tiles with mipmaps, and makes the texture's two samplers. An
// empty image gives an empty result.
TiledTexture CreateTiledTexture(const ImageRgba8& image);
void DestroyTiledTexture(TiledTexture* texture);

// Image-to-screen transform: screen = origin + zoom * uv_px, where origin is the screen
// position of pixel (0, 0)'s centre (core/geometry/conventions.h: that pixel covers [-0.5, 0.5]^2).
struct ViewTransform {
  ImVec2 origin{0, 0};
  float zoom = 1.0f;  // screen px per image px
  ImVec2 ToScreen(double u_px, double v_px) const {
    return ImVec2(static_cast<float>(origin.x + zoom * u_px), static_cast<float>(origin.y + zoom * v_px));
  }
  // Image pixel coordinates (double precision) of a screen position.
  void ToImage(ImVec2 screen, double* u_px, double* v_px) const {
    *u_px = (static_cast<double>(screen.x) - origin.x) / zoom;
    *v_px = (static_cast<double>(screen.y) - origin.y) / zoom;
  }
};

// Draws the visible part of the texture into `clip` (screen rectangle, min/max corners),
// with nearest filtering when zoom > 1 and trilinear otherwise. Only the visible part of
// each tile becomes vertices, so extreme zooms keep float coordinates small.
void DrawTiledTexture(ImDrawList* draw_list, const TiledTexture& texture, const ViewTransform& view, ImVec2 clip_min,
                      ImVec2 clip_max, ImU32 tint = IM_COL32_WHITE);

}  // namespace facet::app
