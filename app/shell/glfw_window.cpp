#include "app/shell/glfw_window.h"

#include <epoxy/gl.h>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <algorithm>
#include <cfloat>
#include <cstdio>
#include <cstdlib>

#include <imgui.h>
#include <imgui_impl_glfw.h>
#include <imgui_impl_opengl3.h>

#include "app/panels/image_panel.h"
#include "app/panels/viewport_panel.h"
#include "app/shell/export_view.h"
#include "app/shell/input_feed.h"
#include "app/shell/window_placement.h"

namespace facet::app {
namespace {

constexpr char kNoDisplayMessage[] =
    "facet: no display found; use 'facet render PROJECT -o SHOT.png' for offscreen rendering\n";

void PrintGlfwError(int code, const char* description) {
  // GLFW reports "no display" through glfwInit's failure, which RunGlfwWindow explains.
  if (code != GLFW_PLATFORM_ERROR) std::fprintf(stderr, "facet: GLFW: %s\n", description);
}

// Files dropped onto the window wait in the shell state for the next frame, which handles
// them like the script's `drop` (HandleDroppedFiles, app/shell/file_actions.h).
void QueueDroppedFiles(GLFWwindow* window, int count, const char** paths) {
  auto* shell = static_cast<ShellState*>(glfwGetWindowUserPointer(window));
  for (int i = 0; i < count; ++i) shell->dropped_paths.emplace_back(paths[i]);
}

// The input callbacks queue the events for the frames (app/state/input_queue.h) instead of
// setting ImGui's state directly, so a press and release within one frame both arrive.
InputQueue& QueueOf(GLFWwindow* window) {
  return static_cast<ShellState*>(glfwGetWindowUserPointer(window))->input_queue;
}

void QueueCursorPos(GLFWwindow* window, double x, double y) {
  QueueOf(window).MouseMove(glfwGetTime(), static_cast<float>(x), static_cast<float>(y));
}

void QueueCursorEnter(GLFWwindow* window, int entered) {
  ImGui_ImplGlfw_CursorEnterCallback(window, entered);
  InputQueue& queue = QueueOf(window);
  const auto& buttons = queue.State().mouse_down;
  const bool dragging = std::any_of(buttons.begin(), buttons.end(), [](bool down) { return down; });
  if (!entered && !dragging) queue.MouseMove(glfwGetTime(), -FLT_MAX, -FLT_MAX);
}

void QueueMouseButton(GLFWwindow* window, int button, int action, int mods) {
  // The queued pointer is where the platform's motion events left it when the button went
  // (glfwGetCursorPos would ask where it is now, after any later motion).
  if (action == GLFW_PRESS || action == GLFW_RELEASE) {
    QueueOf(window).MouseButton(glfwGetTime(), button, action == GLFW_PRESS);
  }
}

void QueueScroll(GLFWwindow* window, double dx, double dy) {
  QueueOf(window).Wheel(glfwGetTime(), static_cast<float>(dx), static_cast<float>(dy));
}

void QueueKey(GLFWwindow* window, int key, int scancode, int action, int mods) {
  if (action == GLFW_PRESS || action == GLFW_RELEASE) QueueOf(window).Key(glfwGetTime(), key, action == GLFW_PRESS);
}

void QueueChar(GLFWwindow* window, unsigned int c) { QueueOf(window).Char(glfwGetTime(), c); }

void QueueFocus(GLFWwindow* window, int focused) {
  ImGui_ImplGlfw_WindowFocusCallback(window, focused);
  if (!focused) QueueOf(window).ReleaseAll(glfwGetTime());  // their releases go elsewhere
}

}  // namespace

bool HasDisplay() {
  const char* x11 = std::getenv("DISPLAY");
  const char* wayland = std::getenv("WAYLAND_DISPLAY");
  return (x11 && *x11) || (wayland && *wayland);
}

int RunGlfwWindow(AppState* state, ShellState* shell, const std::string& imgui_ini_path) {
  glfwSetErrorCallback(PrintGlfwError);
  if (!HasDisplay() || !glfwInit()) {
    std::fputs(kNoDisplayMessage, stderr);
    return 2;
  }
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  // Hidden until it has its place: the work area of the screen, or the last session's
  // window clamped into it (a fixed size left the properties panel off small screens).
  glfwWindowHint(GLFW_VISIBLE, GLFW_FALSE);
  WindowRect work_area{0, 0, 1600, 900};
  if (GLFWmonitor* monitor = glfwGetPrimaryMonitor()) {
    glfwGetMonitorWorkarea(monitor, &work_area.x, &work_area.y, &work_area.width, &work_area.height);
    if (work_area.width <= 0 || work_area.height <= 0) work_area = WindowRect{0, 0, 1600, 900};
  }
  const std::string window_file = WindowRectFilePath();
  const WindowRect outer =
      InitialWindowRect(window_file.empty() ? std::nullopt : LoadWindowRect(window_file), work_area);
  std::string title = WindowTitle(*state);
  GLFWwindow* window = glfwCreateWindow(outer.width, outer.height, title.c_str(), nullptr, nullptr);
  if (!window) {
    std::fputs("facet: cannot create a window with an OpenGL 3.3 core context\n", stderr);
    glfwTerminate();
    return 1;
  }
  {
    // The rectangle is the outer frame: the decorations come off the content size.
    int left = 0, top = 0, right = 0, bottom = 0;
    glfwGetWindowFrameSize(window, &left, &top, &right, &bottom);
    glfwSetWindowSize(window, std::max(1, outer.width - left - right), std::max(1, outer.height - top - bottom));
    glfwSetWindowPos(window, outer.x + left, outer.y + top);
    glfwShowWindow(window);
  }
  glfwMakeContextCurrent(window);
  glfwSwapInterval(1);  // vsync: the loop never spins faster than the display

  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  // Fonts and sizes follow the monitor's content scale (e.g. 2 on a HiDPI screen).
  float scale_x = 1.0f, scale_y = 1.0f;
  glfwGetWindowContentScale(window, &scale_x, &scale_y);
  // Where the framebuffer is already denser than window coordinates (Wayland, macOS), ImGui's
  // framebuffer scale does that part; only the rest enlarges the UI.
  int window_w = 0, window_h = 0, fb_w = 0, fb_h = 0;
  glfwGetWindowSize(window, &window_w, &window_h);
  glfwGetFramebufferSize(window, &fb_w, &fb_h);
  const float framebuffer_scale = window_w > 0 ? static_cast<float>(fb_w) / window_w : 1.0f;
  ConfigureImGui(/*offscreen=*/false, std::max(scale_x, scale_y) / std::max(1.0f, framebuffer_scale));
  ImGui::GetIO().IniFilename = imgui_ini_path.empty() ? nullptr : imgui_ini_path.c_str();
  ImGui_ImplGlfw_InitForOpenGL(window, /*install_callbacks=*/true);
  glfwSetWindowUserPointer(window, shell);
  glfwSetDropCallback(window, QueueDroppedFiles);
  // After the backend's: ours replace its input callbacks (it keeps the monitor one).
  glfwSetCursorPosCallback(window, QueueCursorPos);
  glfwSetCursorEnterCallback(window, QueueCursorEnter);
  glfwSetMouseButtonCallback(window, QueueMouseButton);
  glfwSetScrollCallback(window, QueueScroll);
  glfwSetKeyCallback(window, QueueKey);
  glfwSetCharCallback(window, QueueChar);
  glfwSetWindowFocusCallback(window, QueueFocus);
  ImGui_ImplOpenGL3_Init("#version 330");

  while (!shell->quit_now) {
    // An iconified window needs no frames; wait for events instead of spinning.
    if (glfwGetWindowAttrib(window, GLFW_ICONIFIED)) {
      glfwWaitEventsTimeout(0.25);
      continue;
    }
    glfwPollEvents();
    if (glfwWindowShouldClose(window)) {
      glfwSetWindowShouldClose(window, GLFW_FALSE);
      RequestQuit(state, shell);
    }
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();  // display size, cursor shape, gamepads
    ApplyInputFrame(shell->input_queue.NextFrame(glfwGetTime()), &ImGui::GetIO());
    ImGui::NewFrame();
    DrawFrame(state, shell, glfwGetTime());
    ImGui::Render();

    int fb_width = 0, fb_height = 0;
    glfwGetFramebufferSize(window, &fb_width, &fb_height);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glViewport(0, 0, fb_width, fb_height);
    glClearColor(0.075f, 0.08f, 0.09f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT);
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    glfwSwapBuffers(window);
    RunPendingExportView(state, shell, glfwGetTime());  // File > Export view, between frames

    const std::string new_title = WindowTitle(*state);
    if (new_title != title) {
      title = new_title;
      glfwSetWindowTitle(window, title.c_str());
    }
  }

  if (!window_file.empty() && !glfwGetWindowAttrib(window, GLFW_ICONIFIED)) {
    // The outer frame, as InitialWindowRect reads it next time.
    WindowRect last;
    int left = 0, top = 0, right = 0, bottom = 0;
    glfwGetWindowFrameSize(window, &left, &top, &right, &bottom);
    glfwGetWindowPos(window, &last.x, &last.y);
    glfwGetWindowSize(window, &last.width, &last.height);
    last = {last.x - left, last.y - top, last.width + left + right, last.height + top + bottom};
    if (!SaveWindowRect(window_file, last)) std::fprintf(stderr, "facet: cannot save %s\n", window_file.c_str());
  }

  ShutdownImagePanel(&shell->image_panel);
  ShutdownViewportPanel(&shell->viewport_panel);
  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
  glfwDestroyWindow(window);
  glfwTerminate();
  return 0;
}

}  // namespace facet::app
