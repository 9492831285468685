#include "app/platform/egl_context.h"

#include <epoxy/gl.h>

#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <dlfcn.h>
#include <link.h>

#include <cstring>
#include <vector>

namespace facet::app {
namespace {

std::string EglErrorName(EGLint code) {
  switch (code) {
    case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
    case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
    case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
    default: return "EGL error 0x" + std::to_string(code);
  }
}

bool HasExtension(const char* list, const char* name) {
  if (!list) return false;
  const size_t n = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += n) {
    if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
  }
  return false;
}

// The checked build (ASan): LeakSanitizer looks for leaks at exit, after the EGL vendor library
// has unloaded Mesa's driver, and a block the driver never freed then has an allocation stack
// without a library name, which no suppression (scripts/lsan-suppressions.txt) can match.
// Holding every library the context loaded until exit keeps their names in the reports.
#if defined(__SANITIZE_ADDRESS__)
#define FACET_KEEP_LIBRARIES_LOADED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define FACET_KEEP_LIBRARIES_LOADED 1
#endif
#endif

void KeepLoadedLibrariesUntilExit() {
#ifdef FACET_KEEP_LIBRARIES_LOADED
  std::vector<std::string> names;
  dl_iterate_phdr(
      [](dl_phdr_info* info, size_t, void* out) {
        if (info->dlpi_name != nullptr && info->dlpi_name[0] != '\0')
          static_cast<std::vector<std::string>*>(out)->push_back(info->dlpi_name);
        return 0;
      },
      &names);
  // Outside the iteration, which holds the loader's lock. The handles are never closed.
  for (const std::string& name : names) dlopen(name.c_str(), RTLD_NOW | RTLD_NOLOAD | RTLD_NODELETE);
#endif
}

}  // namespace

EglContext::~EglContext() {
  if (display_) {
    EGLDisplay display = static_cast<EGLDisplay>(display_);
    eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    if (context_) eglDestroyContext(display, static_cast<EGLContext>(context_));
    eglTerminate(display);
  }
}

bool EglContext::Create(std::string* error) {
  const char* client_extensions = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  if (!HasExtension(client_extensions, "EGL_MESA_platform_surfaceless")) {
    *error =
        "EGL: the surfaceless platform (EGL_MESA_platform_surfaceless) is not available; install Mesa's EGL "
        "driver (libegl-mesa0)";
    return false;
  }
  auto get_platform_display =
      reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
  if (!get_platform_display) {
    *error = "EGL: eglGetPlatformDisplayEXT is missing";
    return false;
  }
  // The surfaceless platform needs no display server: Mesa renders with the GPU's render
  // node when there is one and with llvmpipe otherwise.
  EGLDisplay display = get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
  if (display == EGL_NO_DISPLAY) {
    *error = "EGL: no surfaceless display (" + EglErrorName(eglGetError()) + ")";
    return false;
  }
  EGLint major = 0, minor = 0;
  if (!eglInitialize(display, &major, &minor)) {
    *error = "EGL: eglInitialize failed (" + EglErrorName(eglGetError()) + ")";
    return false;
  }
  display_ = display;
  if (!eglBindAPI(EGL_OPENGL_API)) {
    *error = "EGL: desktop OpenGL is not supported (" + EglErrorName(eglGetError()) + ")";
    return false;
  }
  const char* display_extensions = eglQueryString(display, EGL_EXTENSIONS);
  if (!HasExtension(display_extensions, "EGL_KHR_surfaceless_context")) {
    *error = "EGL: EGL_KHR_surfaceless_context is not supported";
    return false;
  }
  EGLConfig config = nullptr;
  const EGLint config_attribs[] = {
      EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_RED_SIZE, 8, EGL_GREEN_SIZE, 8, EGL_BLUE_SIZE, 8, EGL_NONE};
  EGLint num_configs = 0;
  if (!eglChooseConfig(display, config_attribs, &config, 1, &num_configs) || num_configs < 1) {
    if (!HasExtension(display_extensions, "EGL_KHR_no_config_context")) {
      *error = "EGL: no OpenGL-capable config";
      return false;
    }
    config = EGL_NO_CONFIG_KHR;
  }
  const EGLint context_attribs[] = {
      EGL_CONTEXT_MAJOR_VERSION,           3,       EGL_CONTEXT_MINOR_VERSION, 3, EGL_CONTEXT_OPENGL_PROFILE_MASK,
      EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
  EGLContext context = eglCreateContext(display, config, EGL_NO_CONTEXT, context_attribs);
  if (context == EGL_NO_CONTEXT) {
    *error = "EGL: cannot create an OpenGL 3.3 core context (" + EglErrorName(eglGetError()) + ")";
    return false;
  }
  context_ = context;
  if (!eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context)) {
    *error = "EGL: eglMakeCurrent failed (" + EglErrorName(eglGetError()) + ")";
    return false;
  }
  KeepLoadedLibrariesUntilExit();
  if (epoxy_gl_version() < 33) {
    *error = "EGL: the context provides OpenGL " + std::to_string(epoxy_gl_version() / 10) + "." +
             std::to_string(epoxy_gl_version() % 10) + ", 3.3 is needed";
    return false;
  }
  return true;
}

std::string EglContext::Renderer() const {
  const GLubyte* renderer = glGetString(GL_RENDERER);
  return renderer ? reinterpret_cast<const char*>(renderer) : "";
}

OffscreenTarget::~OffscreenTarget() {
  if (fbo_) glDeleteFramebuffers(1, &fbo_);
  if (color_) glDeleteRenderbuffers(1, &color_);
  if (depth_) glDeleteRenderbuffers(1, &depth_);
}

bool OffscreenTarget::Create(int width, int height, std::string* error) {
  GLint max_size = 0;
  glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_size);
  if (width < 1 || height < 1 || width > max_size || height > max_size) {
    *error = "image size " + std::to_string(width) + "x" + std::to_string(height) + " is outside 1.." +
             std::to_string(max_size);
    return false;
  }
  width_ = width;
  height_ = height;
  glGenFramebuffers(1, &fbo_);
  glGenRenderbuffers(1, &color_);
  glGenRenderbuffers(1, &depth_);
  glBindRenderbuffer(GL_RENDERBUFFER, color_);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, width, height);
  glBindRenderbuffer(GL_RENDERBUFFER, depth_);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH24_STENCIL8, width, height);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, color_);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_STENCIL_ATTACHMENT, GL_RENDERBUFFER, depth_);
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
    *error = "the offscreen framebuffer is incomplete";
    return false;
  }
  return true;
}

void OffscreenTarget::Bind() const {
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
  glViewport(0, 0, width_, height_);
}

ImageRgba8 OffscreenTarget::Read(bool keep_alpha) const {
  ImageRgba8 image;
  image.width = width_;
  image.height = height_;
  image.pixels.resize(static_cast<size_t>(width_) * height_ * 4);
  std::vector<std::uint8_t> rows(image.pixels.size());
  glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo_);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, width_, height_, GL_RGBA, GL_UNSIGNED_BYTE, rows.data());
  const size_t stride = static_cast<size_t>(width_) * 4;
  for (int y = 0; y < height_; ++y) {
    std::memcpy(&image.pixels[y * stride], &rows[(height_ - 1 - y) * stride], stride);
  }
  if (keep_alpha) return image;
  for (size_t i = 3; i < image.pixels.size(); i += 4) image.pixels[i] = 255;  // an opaque screenshot
  return image;
}

}  // namespace facet::app
