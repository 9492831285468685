#include "app/platform/gl_util.h"

#include <algorithm>
#include <cstdint>
#include <vector>

namespace facet::app {
namespace {

GLuint CompileShader(GLenum stage, const char* source, std::string* error) {
  const GLuint shader = glCreateShader(stage);
  glShaderSource(shader, 1, &source, nullptr);
  glCompileShader(shader);
  GLint ok = GL_FALSE;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (ok == GL_TRUE) return shader;
  GLint length = 0;
  glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &length);
  std::string log(std::max(length, 1), '\0');
  glGetShaderInfoLog(shader, length, nullptr, log.data());
  if (error) {
    *error =
        std::string(stage == GL_VERTEX_SHADER ? "vertex" : "fragment") + " shader does not compile: " + log.c_str();
  }
  glDeleteShader(shader);
  return 0;
}

}  // namespace

GLuint BuildGlProgram(const char* vertex_source, const char* fragment_source, std::string* error) {
  const GLuint vs = CompileShader(GL_VERTEX_SHADER, vertex_source, error);
  if (vs == 0) return 0;
  const GLuint fs = CompileShader(GL_FRAGMENT_SHADER, fragment_source, error);
  if (fs == 0) {
    glDeleteShader(vs);
    return 0;
  }
  const GLuint program = glCreateProgram();
  glAttachShader(program, vs);
  glAttachShader(program, fs);
  glLinkProgram(program);
  // The program keeps the compiled stages; the shader objects can go now.
  glDetachShader(program, vs);
  glDetachShader(program, fs);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = GL_FALSE;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (ok == GL_TRUE) return program;
  GLint length = 0;
  glGetProgramiv(program, GL_INFO_LOG_LENGTH, &length);
  std::string log(std::max(length, 1), '\0');
  glGetProgramInfoLog(program, length, nullptr, log.data());
  if (error) *error = std::string("program does not link: ") + log.c_str();
  glDeleteProgram(program);
  return 0;
}

GLuint UploadGlTextureRgba8(const ImageRgba8& image, bool mipmaps) {
  if (image.empty() || image.pixels.size() < static_cast<size_t>(image.width) * image.height * 4) return 0;
  GLint previous_texture = 0;
  GLint previous_alignment = 4;
  glGetIntegerv(GL_TEXTURE_BINDING_2D, &previous_texture);
  glGetIntegerv(GL_UNPACK_ALIGNMENT, &previous_alignment);
  GLuint texture = 0;
  glGenTextures(1, &texture);
  glBindTexture(GL_TEXTURE_2D, texture);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, image.width, image.height, 0, GL_RGBA, GL_UNSIGNED_BYTE,
               image.pixels.data());
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  if (mipmaps) {
    glGenerateMipmap(GL_TEXTURE_2D);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
  } else {
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  }
  glPixelStorei(GL_UNPACK_ALIGNMENT, previous_alignment);
  glBindTexture(GL_TEXTURE_2D, static_cast<GLuint>(previous_texture));
  return texture;
}

ImageRgba8 DownsampleRgba8(const ImageRgba8& image, int max_side_px) {
  const int longer = std::max(image.width, image.height);
  if (image.empty() || max_side_px <= 0 || longer <= max_side_px) return image;
  const double scale = static_cast<double>(max_side_px) / longer;
  ImageRgba8 out;
  out.width = std::max(1, static_cast<int>(image.width * scale + 0.5));
  out.height = std::max(1, static_cast<int>(image.height * scale + 0.5));
  out.pixels.resize(static_cast<size_t>(out.width) * out.height * 4);
  // Each output pixel averages the source pixels whose centres fall in its footprint, so
  // fine detail (text, brick) does not alias.
  for (int y = 0; y < out.height; ++y) {
    const int y0 = static_cast<int>(static_cast<int64_t>(y) * image.height / out.height);
    const int y1 = std::max(y0 + 1, static_cast<int>(static_cast<int64_t>(y + 1) * image.height / out.height));
    for (int x = 0; x < out.width; ++x) {
      const int x0 = static_cast<int>(static_cast<int64_t>(x) * image.width / out.width);
      const int x1 = std::max(x0 + 1, static_cast<int>(static_cast<int64_t>(x + 1) * image.width / out.width));
      uint32_t sum[4] = {0, 0, 0, 0};
      for (int sy = y0; sy < y1; ++sy) {
        const uint8_t* row = image.At(0, sy);
        for (int sx = x0; sx < x1; ++sx) {
          for (int c = 0; c < 4; ++c) sum[c] += row[sx * 4 + c];
        }
      }
      const uint32_t count = static_cast<uint32_t>((y1 - y0) * (x1 - x0));
      uint8_t* dst = out.At(x, y);
      for (int c = 0; c < 4; ++c) dst[c] = static_cast<uint8_t>((sum[c] + count / 2) / count);
    }
  }
  return out;
}

bool GlRenderTarget::Ensure(int width_px, int height_px, int samples, std::string* error) {
  width_px = std::max(1, width_px);
  height_px = std::max(1, height_px);
  samples = std::max(1, samples);
  if (resolve_fbo_ != 0 && width_px == width_px_ && height_px == height_px_ && samples == requested_samples_) {
    return true;
  }
  Release();
  GLint previous_fbo = 0;
  GLint previous_rb = 0;
  GLint previous_texture = 0;
  glGetIntegerv(GL_FRAMEBUFFER_BINDING, &previous_fbo);
  glGetIntegerv(GL_RENDERBUFFER_BINDING, &previous_rb);
  glGetIntegerv(GL_TEXTURE_BINDING_2D, &previous_texture);
  auto restore = [&] {
    glBindFramebuffer(GL_FRAMEBUFFER, static_cast<GLuint>(previous_fbo));
    glBindRenderbuffer(GL_RENDERBUFFER, static_cast<GLuint>(previous_rb));
    glBindTexture(GL_TEXTURE_2D, static_cast<GLuint>(previous_texture));
  };

  width_px_ = width_px;
  height_px_ = height_px;
  requested_samples_ = samples;
  GLint max_samples = 1;
  glGetIntegerv(GL_MAX_SAMPLES, &max_samples);
  samples_ = std::min(samples, std::max(1, static_cast<int>(max_samples)));

  glGenTextures(1, &color_texture_);
  glBindTexture(GL_TEXTURE_2D, color_texture_);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, width_px, height_px, 0, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glGenFramebuffers(1, &resolve_fbo_);
  glBindFramebuffer(GL_FRAMEBUFFER, resolve_fbo_);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, color_texture_, 0);

  if (samples_ > 1) {
    glGenFramebuffers(1, &msaa_fbo_);
    glBindFramebuffer(GL_FRAMEBUFFER, msaa_fbo_);
    glGenRenderbuffers(1, &msaa_color_rb_);
    glBindRenderbuffer(GL_RENDERBUFFER, msaa_color_rb_);
    glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples_, GL_RGBA8, width_px, height_px);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, msaa_color_rb_);
    glGenRenderbuffers(1, &depth_rb_);
    glBindRenderbuffer(GL_RENDERBUFFER, depth_rb_);
    glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples_, GL_DEPTH_COMPONENT24, width_px, height_px);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth_rb_);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
      // Multisampling is a nicety: fall back to one sample rather than fail.
      glBindFramebuffer(GL_FRAMEBUFFER, resolve_fbo_);
      glDeleteFramebuffers(1, &msaa_fbo_);
      glDeleteRenderbuffers(1, &msaa_color_rb_);
      glDeleteRenderbuffers(1, &depth_rb_);
      msaa_fbo_ = msaa_color_rb_ = depth_rb_ = 0;
      samples_ = 1;
    }
  }
  if (samples_ <= 1) {
    glBindFramebuffer(GL_FRAMEBUFFER, resolve_fbo_);
    glGenRenderbuffers(1, &depth_rb_);
    glBindRenderbuffer(GL_RENDERBUFFER, depth_rb_);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, width_px, height_px);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth_rb_);
  }
  glBindFramebuffer(GL_FRAMEBUFFER, resolve_fbo_);
  const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  restore();
  if (status != GL_FRAMEBUFFER_COMPLETE) {
    if (error) *error = "offscreen framebuffer incomplete (status " + std::to_string(status) + ")";
    Release();
    return false;
  }
  return true;
}

void GlRenderTarget::BindForDrawing() const {
  glBindFramebuffer(GL_FRAMEBUFFER, msaa_fbo_ != 0 ? msaa_fbo_ : resolve_fbo_);
  glViewport(0, 0, width_px_, height_px_);
}

void GlRenderTarget::Resolve() const {
  if (msaa_fbo_ == 0) return;
  glBindFramebuffer(GL_READ_FRAMEBUFFER, msaa_fbo_);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, resolve_fbo_);
  glBlitFramebuffer(0, 0, width_px_, height_px_, 0, 0, width_px_, height_px_, GL_COLOR_BUFFER_BIT, GL_NEAREST);
}

void GlRenderTarget::Release() {
  if (msaa_fbo_) glDeleteFramebuffers(1, &msaa_fbo_);
  if (msaa_color_rb_) glDeleteRenderbuffers(1, &msaa_color_rb_);
  if (depth_rb_) glDeleteRenderbuffers(1, &depth_rb_);
  if (resolve_fbo_) glDeleteFramebuffers(1, &resolve_fbo_);
  if (color_texture_) glDeleteTextures(1, &color_texture_);
  msaa_fbo_ = msaa_color_rb_ = depth_rb_ = resolve_fbo_ = color_texture_ = 0;
  width_px_ = height_px_ = samples_ = requested_samples_ = 0;
}

SavedGlState SavedGlState::Capture() {
  SavedGlState s;
  glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &s.draw_framebuffer);
  glGetIntegerv(GL_READ_FRAMEBUFFER_BINDING, &s.read_framebuffer);
  glGetIntegerv(GL_VIEWPORT, s.viewport);
  glGetIntegerv(GL_CURRENT_PROGRAM, &s.program);
  glGetIntegerv(GL_VERTEX_ARRAY_BINDING, &s.vertex_array);
  glGetIntegerv(GL_ARRAY_BUFFER_BINDING, &s.array_buffer);
  glGetIntegerv(GL_ACTIVE_TEXTURE, &s.active_texture);
  glActiveTexture(GL_TEXTURE0);
  glGetIntegerv(GL_TEXTURE_BINDING_2D, &s.texture_2d);
  glGetIntegerv(GL_BLEND_SRC_RGB, &s.blend_src_rgb);
  glGetIntegerv(GL_BLEND_DST_RGB, &s.blend_dst_rgb);
  glGetIntegerv(GL_BLEND_SRC_ALPHA, &s.blend_src_alpha);
  glGetIntegerv(GL_BLEND_DST_ALPHA, &s.blend_dst_alpha);
  glGetIntegerv(GL_BLEND_EQUATION_RGB, &s.blend_equation_rgb);
  glGetIntegerv(GL_BLEND_EQUATION_ALPHA, &s.blend_equation_alpha);
  s.blend = glIsEnabled(GL_BLEND);
  s.depth_test = glIsEnabled(GL_DEPTH_TEST);
  s.cull_face = glIsEnabled(GL_CULL_FACE);
  s.scissor_test = glIsEnabled(GL_SCISSOR_TEST);
  s.polygon_offset_fill = glIsEnabled(GL_POLYGON_OFFSET_FILL);
  s.multisample = glIsEnabled(GL_MULTISAMPLE);
  glGetBooleanv(GL_DEPTH_WRITEMASK, &s.depth_mask);
  glGetIntegerv(GL_DEPTH_FUNC, &s.depth_func);
  glGetFloatv(GL_COLOR_CLEAR_VALUE, s.clear_color);
  return s;
}

void SavedGlState::Restore() const {
  auto set_enabled = [](GLenum cap, GLboolean on) { on ? glEnable(cap) : glDisable(cap); };
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, static_cast<GLuint>(draw_framebuffer));
  glBindFramebuffer(GL_READ_FRAMEBUFFER, static_cast<GLuint>(read_framebuffer));
  glViewport(viewport[0], viewport[1], viewport[2], viewport[3]);
  glUseProgram(static_cast<GLuint>(program));
  glBindVertexArray(static_cast<GLuint>(vertex_array));
  glBindBuffer(GL_ARRAY_BUFFER, static_cast<GLuint>(array_buffer));
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, static_cast<GLuint>(texture_2d));
  glActiveTexture(static_cast<GLenum>(active_texture));
  glBlendEquationSeparate(static_cast<GLenum>(blend_equation_rgb), static_cast<GLenum>(blend_equation_alpha));
  glBlendFuncSeparate(static_cast<GLenum>(blend_src_rgb), static_cast<GLenum>(blend_dst_rgb),
                      static_cast<GLenum>(blend_src_alpha), static_cast<GLenum>(blend_dst_alpha));
  set_enabled(GL_BLEND, blend);
  set_enabled(GL_DEPTH_TEST, depth_test);
  set_enabled(GL_CULL_FACE, cull_face);
  set_enabled(GL_SCISSOR_TEST, scissor_test);
  set_enabled(GL_POLYGON_OFFSET_FILL, polygon_offset_fill);
  set_enabled(GL_MULTISAMPLE, multisample);
  glDepthMask(depth_mask);
  glDepthFunc(static_cast<GLenum>(depth_func));
  glClearColor(clear_color[0], clear_color[1], clear_color[2], clear_color[3]);
}

}  // namespace facet::app
