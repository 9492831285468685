// Small OpenGL 3.3 core helpers for the app's panels: shader programs with readable build
// errors, RGBA8 texture upload, an offscreen render target (optionally multisampled) and a
// save/restore of the GL state that ImGui's OpenGL3 backend relies on.
// Include this (it includes epoxy) before any other GL header.
#pragma once

#include <epoxy/gl.h>

#include <string>

#include "core/image/image_io.h"

namespace facet::app {

// Compiles and links a program from GLSL sources ("#version 330 core"). Returns 0 and sets
// *error to the stage and the driver's log on failure.
GLuint BuildGlProgram(const char* vertex_source, const char* fragment_source, std::string* error);

// Uploads an image as a GL_RGBA8 2D texture, first row at t = 0 (so a texture coordinate in
// the image convention, v down from the top, samples directly). Clamp-to-edge; trilinear
// with mipmaps when `mipmaps`, else bilinear. Returns 0 for an empty image.
GLuint UploadGlTextureRgba8(const ImageRgba8& image, bool mipmaps);

// Box-filtered copy whose longer side is at most max_side_px (the image itself when it is
// already small enough). Used to keep photo textures small.
ImageRgba8 DownsampleRgba8(const ImageRgba8& image, int max_side_px);

// A colour texture + depth buffer to render into and show with ImGui::Image. With samples > 1
// it renders into multisampled renderbuffers and Resolve() blits them into the texture.
class GlRenderTarget {
 public:
  GlRenderTarget() = default;
  GlRenderTarget(const GlRenderTarget&) = delete;
  GlRenderTarget& operator=(const GlRenderTarget&) = delete;
  ~GlRenderTarget() { Release(); }

  // (Re)creates the buffers when the size or sample count changes. Falls back to one sample
  // when the multisampled framebuffer is incomplete. Returns false (with *error) on failure.
  bool Ensure(int width_px, int height_px, int samples, std::string* error);
  // Binds the framebuffer to draw into and sets the viewport to its size.
  void BindForDrawing() const;
  // Makes the colour texture hold the rendered frame (multisample resolve).
  void Resolve() const;
  void Release();

  GLuint color_texture() const { return color_texture_; }
  int width_px() const { return width_px_; }
  int height_px() const { return height_px_; }
  int samples() const { return samples_; }

 private:
  int width_px_ = 0;
  int height_px_ = 0;
  int samples_ = 0;
  int requested_samples_ = 0;
  GLuint resolve_fbo_ = 0;  // owns color_texture_ (and the depth buffer when single-sampled)
  GLuint color_texture_ = 0;
  GLuint msaa_fbo_ = 0;  // 0 when single-sampled
  GLuint msaa_color_rb_ = 0;
  GLuint depth_rb_ = 0;
};

// The GL state a panel touches while drawing in the middle of an ImGui frame, so that the
// ImGui backend (and the next panel) find it as they left it.
struct SavedGlState {
  GLint draw_framebuffer = 0;
  GLint read_framebuffer = 0;
  GLint viewport[4] = {0, 0, 0, 0};
  GLint program = 0;
  GLint vertex_array = 0;
  GLint array_buffer = 0;
  GLint active_texture = 0;
  GLint texture_2d = 0;
  GLint blend_src_rgb = 0, blend_dst_rgb = 0, blend_src_alpha = 0, blend_dst_alpha = 0;
  GLint blend_equation_rgb = 0, blend_equation_alpha = 0;
  GLint depth_func = GL_LESS;
  GLboolean blend = GL_FALSE, depth_test = GL_FALSE, cull_face = GL_FALSE, scissor_test = GL_FALSE;
  GLboolean polygon_offset_fill = GL_FALSE, multisample = GL_FALSE;
  GLboolean depth_mask = GL_TRUE;
  GLfloat clear_color[4] = {0, 0, 0, 0};

  static SavedGlState Capture();
  void Restore() const;
};

}  // namespace facet::app
