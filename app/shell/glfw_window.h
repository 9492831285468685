// The windowed mode's platform layer: a GLFW window with an OpenGL 3.3 core context, the
// ImGui GLFW and OpenGL3 backends, and the frame loop around DrawFrame (app/shell/frame.h).
#pragma once

#include <string>

#include "app/shell/frame.h"
#include "app/state/app_state.h"

namespace facet::app {

// True when a display server is advertised (DISPLAY or WAYLAND_DISPLAY is set).
bool HasDisplay();

// Runs the window until shell->quit_now. Returns 0 after a normal quit, 2 when GLFW finds no
// display, 1 when the window cannot be created; prints the reason on failure.
// `imgui_ini_path` may be empty (no ImGui settings file).
int RunGlfwWindow(AppState* state, ShellState* shell, const std::string& imgui_ini_path);

}  // namespace facet::app
