#include <epoxy/gl.h>

#include "app/platform/image_tiles.h"

#include <algorithm>
#include <cstdint>
#include <cstdlib>

namespace facet::app {
namespace {

constexpr int kMaxTilePx = 4096;
constexpr int kMinTilePx = 16;  // below this the one-pixel padding dominates

// Sampler objects override the textures' own filter per draw call, so the main view and
// the loupe can show the same texture with different filters in one frame.
void CreateSamplers(TiledTexture* texture) {
  GLuint samplers[2] = {0, 0};
  glGenSamplers(2, samplers);
  texture->linear_sampler = samplers[0];
  texture->nearest_sampler = samplers[1];
  for (GLuint s : samplers) {
    glSamplerParameteri(s, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glSamplerParameteri(s, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  }
  glSamplerParameteri(samplers[0], GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
  glSamplerParameteri(samplers[0], GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glSamplerParameteri(samplers[1], GL_TEXTURE_MIN_FILTER, GL_NEAREST_MIPMAP_NEAREST);
  glSamplerParameteri(samplers[1], GL_TEXTURE_MAG_FILTER, GL_NEAREST);
}

// Runs inside the renderer backend, which keeps texture unit 0 active while drawing.
void BindSamplerCallback(const ImDrawList*, const ImDrawCmd* cmd) {
  glBindSampler(0, static_cast<GLuint>(reinterpret_cast<std::uintptr_t>(cmd->UserCallbackData)));
}

void* SamplerAsUserData(GLuint sampler) { return reinterpret_cast<void*>(static_cast<std::uintptr_t>(sampler)); }

}  // namespace

int ImageTileSizePx() {
  GLint max_texture_px = 0;
  glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_texture_px);
  int tile_px = std::min<int>(max_texture_px > 0 ? max_texture_px : 2048, kMaxTilePx);
  if (const char* forced = std::getenv("FACET_IMAGE_TILE_PX")) {
    const int value = std::atoi(forced);
    if (value >= kMinTilePx) tile_px = std::min(value, tile_px);
  }
  return tile_px;
}

TiledTexture CreateTiledTexture(const ImageRgba8& image) {
  TiledTexture result;
  if (image.empty() || image.pixels.size() < static_cast<size_t>(image.width) * image.height * 4) return result;
  result.width = image.width;
  result.height = image.height;
  // The padding pixel on each interior side leaves tile_px - 2 drawn pixels per tile.
  const int tile_px = ImageTileSizePx();
  const int step_px = (image.width <= tile_px && image.height <= tile_px) ? tile_px : tile_px - 2;

  GLint last_texture = 0, last_row_length = 0, last_skip_pixels = 0, last_skip_rows = 0, last_alignment = 0;
  glGetIntegerv(GL_TEXTURE_BINDING_2D, &last_texture);
  glGetIntegerv(GL_UNPACK_ROW_LENGTH, &last_row_length);
  glGetIntegerv(GL_UNPACK_SKIP_PIXELS, &last_skip_pixels);
  glGetIntegerv(GL_UNPACK_SKIP_ROWS, &last_skip_rows);
  glGetIntegerv(GL_UNPACK_ALIGNMENT, &last_alignment);
  glPixelStorei(GL_UNPACK_ROW_LENGTH, image.width);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);

  for (int y0 = 0; y0 < image.height; y0 += step_px) {
    for (int x0 = 0; x0 < image.width; x0 += step_px) {
      ImageTile tile;
      tile.x0 = x0;
      tile.y0 = y0;
      tile.w = std::min(step_px, image.width - x0);
      tile.h = std::min(step_px, image.height - y0);
      tile.tex_x0 = std::max(0, x0 - 1);
      tile.tex_y0 = std::max(0, y0 - 1);
      tile.tex_w = std::min(image.width, x0 + tile.w + 1) - tile.tex_x0;
      tile.tex_h = std::min(image.height, y0 + tile.h + 1) - tile.tex_y0;
      glGenTextures(1, &tile.texture);
      glBindTexture(GL_TEXTURE_2D, tile.texture);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
      glPixelStorei(GL_UNPACK_SKIP_PIXELS, tile.tex_x0);
      glPixelStorei(GL_UNPACK_SKIP_ROWS, tile.tex_y0);
      glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, tile.tex_w, tile.tex_h, 0, GL_RGBA, GL_UNSIGNED_BYTE,
                   image.pixels.data());
      glGenerateMipmap(GL_TEXTURE_2D);
      result.tiles.push_back(tile);
    }
  }

  glPixelStorei(GL_UNPACK_ROW_LENGTH, last_row_length);
  glPixelStorei(GL_UNPACK_SKIP_PIXELS, last_skip_pixels);
  glPixelStorei(GL_UNPACK_SKIP_ROWS, last_skip_rows);
  glPixelStorei(GL_UNPACK_ALIGNMENT, last_alignment);
  glBindTexture(GL_TEXTURE_2D, static_cast<GLuint>(last_texture));
  CreateSamplers(&result);
  return result;
}

void DestroyTiledTexture(TiledTexture* texture) {
  for (ImageTile& tile : texture->tiles) {
    if (tile.texture != 0) glDeleteTextures(1, &tile.texture);
  }
  if (texture->linear_sampler != 0) {
    const GLuint samplers[2] = {texture->linear_sampler, texture->nearest_sampler};
    glDeleteSamplers(2, samplers);
  }
  *texture = TiledTexture();
}

void DrawTiledTexture(ImDrawList* draw_list, const TiledTexture& texture, const ViewTransform& view, ImVec2 clip_min,
                      ImVec2 clip_max, ImU32 tint) {
  if (texture.Empty() || view.zoom <= 0.0f) return;
  draw_list->AddCallback(BindSamplerCallback,
                         SamplerAsUserData(view.zoom > 1.0f ? texture.nearest_sampler : texture.linear_sampler));
  for (const ImageTile& tile : texture.tiles) {
    // The tile's drawn pixels cover [x0 - 0.5, x0 + w - 0.5] in image coordinates.
    const ImVec2 tile_min = view.ToScreen(tile.x0 - 0.5, tile.y0 - 0.5);
    const ImVec2 tile_max = view.ToScreen(tile.x0 + tile.w - 0.5, tile.y0 + tile.h - 0.5);
    const ImVec2 p_min(std::max(tile_min.x, clip_min.x), std::max(tile_min.y, clip_min.y));
    const ImVec2 p_max(std::min(tile_max.x, clip_max.x), std::min(tile_max.y, clip_max.y));
    if (p_min.x >= p_max.x || p_min.y >= p_max.y) continue;
    double u0, v0, u1, v1;
    view.ToImage(p_min, &u0, &v0);
    view.ToImage(p_max, &u1, &v1);
    const ImVec2 uv_min(static_cast<float>((u0 + 0.5 - tile.tex_x0) / tile.tex_w),
                        static_cast<float>((v0 + 0.5 - tile.tex_y0) / tile.tex_h));
    const ImVec2 uv_max(static_cast<float>((u1 + 0.5 - tile.tex_x0) / tile.tex_w),
                        static_cast<float>((v1 + 0.5 - tile.tex_y0) / tile.tex_h));
    draw_list->AddImage(reinterpret_cast<ImTextureID>(static_cast<std::uintptr_t>(tile.texture)), p_min, p_max, uv_min,
                        uv_max, tint);
  }
  // Back to the texture's own state (the backend's default) for everything drawn later.
  draw_list->AddCallback(BindSamplerCallback, SamplerAsUserData(0));
}

}  // namespace facet::app
