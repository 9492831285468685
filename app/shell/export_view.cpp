#include "app/shell/export_view.h"

#include <epoxy/gl.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include <imgui.h>
#include <imgui_impl_opengl3.h>

#include "app/platform/egl_context.h"
#include "core/image/image_io.h"

namespace facet::app {
namespace {

// Enough frames for a fresh panel to settle (the 3D panel makes one photo texture per frame)
// and for the window to be sized so that the canvas is the asked size exactly.
constexpr int kMinFrames = 4;
constexpr int kMaxFrames = 12;

bool ParseSize(const std::string& text, int* width, int* height) {
  const size_t x = text.find('x');
  if (x == std::string::npos) return false;
  char* end = nullptr;
  const long w = std::strtol(text.c_str(), &end, 10);
  if (end != text.c_str() + x) return false;
  const long h = std::strtol(text.c_str() + x + 1, &end, 10);
  if (*end != '\0') return false;
  *width = static_cast<int>(w);
  *height = static_cast<int>(h);
  return true;
}

// The input the export frames run with: no pointer, no buttons, no wheel, so that nothing is
// hovered, picked or dragged; restored afterwards.
struct SavedIo {
  ImVec2 display_size, framebuffer_scale, mouse_pos;
  bool mouse_down[5];
  float wheel, wheel_h;
  explicit SavedIo(ImGuiIO& io)
      : display_size(io.DisplaySize),
        framebuffer_scale(io.DisplayFramebufferScale),
        mouse_pos(io.MousePos),
        wheel(io.MouseWheel),
        wheel_h(io.MouseWheelH) {
    std::copy(std::begin(io.MouseDown), std::end(io.MouseDown), mouse_down);
    io.MousePos = ImVec2(-FLT_MAX, -FLT_MAX);
    std::fill(std::begin(io.MouseDown), std::end(io.MouseDown), false);
    io.MouseWheel = io.MouseWheelH = 0.0f;
    io.DisplayFramebufferScale = ImVec2(1.0f, 1.0f);
  }
  void Restore(ImGuiIO& io) const {
    io.DisplaySize = display_size;
    io.DisplayFramebufferScale = framebuffer_scale;
    io.MousePos = mouse_pos;
    std::copy(std::begin(mouse_down), std::end(mouse_down), io.MouseDown);
    io.MouseWheel = wheel;
    io.MouseWheelH = wheel_h;
  }
};

}  // namespace

std::string ParseExportViewArgs(const std::string& args, const ShellState& shell, ExportViewRequest* request) {
  std::istringstream in(args);
  std::string first;
  in >> first;
  if (first == "image" || first == "3d") {
    std::string size;
    in >> size;
    if (!ParseSize(size, &request->width_px, &request->height_px))
      return "export-view: expected 'export-view image|3d WxH PATH', the size as e.g. 1920x1080";
    request->panel = first == "image" ? PanelId::kImage : PanelId::kViewport;
    std::getline(in >> std::ws, request->path);
  } else {
    request->panel = shell.export_view_panel;
    request->width_px = shell.export_view_width;
    request->height_px = shell.export_view_height;
    request->path = args;
  }
  if (request->path.empty()) return "export-view: no file given";
  constexpr int kMinSide = 64, kMaxSide = 8192;
  if (request->width_px < kMinSide || request->height_px < kMinSide || request->width_px > kMaxSide ||
      request->height_px > kMaxSide)
    return "export-view: the size " + std::to_string(request->width_px) + "x" + std::to_string(request->height_px) +
           " is outside 64..8192 px";
  return "";
}

std::string ExportView(AppState* state, ShellState* shell, const ExportViewRequest& request, double time_s) {
  if (request.panel != PanelId::kImage && request.panel != PanelId::kViewport)
    return "export-view: only the image panel and the 3D panel can be exported";
  if (request.panel == PanelId::kImage && state->document.project().FindImage(state->active_image_id) == nullptr)
    return "export-view: there is no photo to show in the image panel";
  FinishBake(state);  // the picture shows the finished texture
  ImGuiIO& io = ImGui::GetIO();
  const SavedIo saved(io);
  ImagePanelState image_panel;
  ViewportPanelState viewport_panel;
  if (request.panel == PanelId::kImage) {
    RequestImageViewLike(&image_panel, LastImageViewReport(shell->image_panel));
    shell->export_image_panel = &image_panel;
  } else {
    CopyViewportView(shell->viewport_panel, &viewport_panel);
    ShowViewportPictureOnly(&viewport_panel);  // the model, not "drag: orbit ..."
    shell->export_viewport_panel = &viewport_panel;
  }
  // The panel's bars (tabs, toolbar, status line) are measured in the first frame; the window
  // then grows by them so that the canvas is the asked size.
  float window_w = static_cast<float>(request.width_px), window_h = static_cast<float>(request.height_px);
  std::string error = "export-view: the panel's canvas never reached the asked size";
  for (int frame = 0; frame < kMaxFrames; ++frame) {
    io.DisplaySize = ImVec2(window_w, window_h);
    OffscreenTarget target;
    std::string target_error;
    if (!target.Create(static_cast<int>(window_w), static_cast<int>(window_h), &target_error)) {
      error = "export-view: " + target_error;
      break;
    }
    shell->export_canvas = Rect();
    ImGui_ImplOpenGL3_NewFrame();
    ImGui::NewFrame();
    DrawFrame(state, shell, time_s);
    ImGui::Render();
    target.Bind();
    glClearColor(0.075f, 0.08f, 0.09f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    const Rect canvas = shell->export_canvas;
    const int x = static_cast<int>(std::lround(canvas.x)), y = static_cast<int>(std::lround(canvas.y));
    const int w = static_cast<int>(std::lround(canvas.w)), h = static_cast<int>(std::lround(canvas.h));
    if (w == request.width_px && h == request.height_px && x >= 0 && y >= 0 && frame + 1 >= kMinFrames) {
      const ImageRgba8 window = target.Read();
      if (x + w > window.width || y + h > window.height) break;
      ImageRgba8 picture;
      picture.width = w;
      picture.height = h;
      picture.pixels.resize(static_cast<size_t>(w) * h * 4);
      for (int row = 0; row < h; ++row)
        std::copy_n(&window.pixels[(static_cast<size_t>(y + row) * window.width + x) * 4], static_cast<size_t>(w) * 4,
                    &picture.pixels[static_cast<size_t>(row) * w * 4]);
      error = WritePng(request.path, picture);
      break;
    }
    if (w > 0 && h > 0) {
      window_w += static_cast<float>(request.width_px - w);
      window_h += static_cast<float>(request.height_px - h);
    } else if (frame > 1) {
      error = "export-view: the panel drew no canvas";
      break;
    }
  }
  shell->export_image_panel = nullptr;
  shell->export_viewport_panel = nullptr;
  ShutdownImagePanel(&image_panel);
  ShutdownViewportPanel(&viewport_panel);
  saved.Restore(io);
  return error;
}

std::string RunPendingExportView(AppState* state, ShellState* shell, double time_s) {
  if (!shell->pending_export_view) return "";
  const std::string args = std::move(*shell->pending_export_view);
  shell->pending_export_view.reset();
  ExportViewRequest request;
  std::string error = ParseExportViewArgs(args, *shell, &request);
  if (error.empty()) error = ExportView(state, shell, request, time_s);
  if (error.empty()) {
    state->Log(LogLevel::kInfo, "Exported the " + std::string(request.panel == PanelId::kImage ? "image" : "3D") +
                                    " view (" + std::to_string(request.width_px) + " x " +
                                    std::to_string(request.height_px) + " px) to " + request.path);
  } else {
    state->Log(LogLevel::kError, error);
  }
  return error;
}

}  // namespace facet::app
