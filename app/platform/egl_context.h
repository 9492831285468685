// A headless OpenGL 3.3 core context for the offscreen mode: EGL on Mesa's surfaceless
// platform (llvmpipe when there is no GPU, no display server needed), rendering into a
// framebuffer object that is read back as an RGBA image.
#pragma once

#include <string>

#include "core/image/image_io.h"

namespace facet::app {

class EglContext {
 public:
  EglContext() = default;
  ~EglContext();
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;

  // Creates the context and makes it current. Returns false with a readable *error.
  bool Create(std::string* error);
  // GL_RENDERER of the current context, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)".
  std::string Renderer() const;

 private:
  void* display_ = nullptr;  // EGLDisplay
  void* context_ = nullptr;  // EGLContext
};

// A colour + depth framebuffer of a fixed size in the current context.
class OffscreenTarget {
 public:
  OffscreenTarget() = default;
  ~OffscreenTarget();
  OffscreenTarget(const OffscreenTarget&) = delete;
  OffscreenTarget& operator=(const OffscreenTarget&) = delete;

  bool Create(int width, int height, std::string* error);
  void Bind() const;
  // Reads the framebuffer, top row first (GL's rows run bottom-up, so they are flipped).
  // Opaque (alpha 255) unless keep_alpha, which returns the alpha that was drawn.
  ImageRgba8 Read(bool keep_alpha = false) const;

 private:
  unsigned fbo_ = 0, color_ = 0, depth_ = 0;
  int width_ = 0, height_ = 0;
};

}  // namespace facet::app
