// The application's two modes, both running the same per-frame UI (app/shell/frame.h): the
// interactive window (GLFW) and the offscreen renderer (EGL surfaceless, no display
// needed) that draws the UI into a PNG, optionally driven by an input script
// (app/state/input_script.h), for screenshots and tests.
#pragma once

#include <string>

namespace facet::app {

struct GuiOptions {
  std::string project_path;  // project to open at start; empty: an empty project
};

// Opens the window and runs until the user quits. Returns the exit code: 0 on a normal
// quit, 2 when there is no display (with a hint about offscreen rendering), 1 when the
// window or its OpenGL 3.3 context cannot be created.
int RunGui(const GuiOptions& options);

struct RenderOptions {
  std::string project_path;  // empty: an empty project
  std::string output_png;    // the final frame
  int width = 1600;          // window size in px
  int height = 900;
  std::string script_path;  // optional input script
  std::string report_path;  // optional JSON report of the final frame (panel rectangles,
                            // image view transform, undo stack, project)
  std::string config_dir;   // where recent files are read and kept; empty: in memory only
  bool snapping = true;     // the image panel's Snap option (AppState::snapping)
  // Autosave and the recovery offer as in the GUI (app/state/autosave.h). Off by default so
  // that renders of shared projects (the samples, tests running side by side) never write
  // or offer recovery files beside them.
  bool autosave = false;
  // "image" or "3d": the PNG is that panel alone, its canvas width x height px, drawn after
  // the script (File > Export view headless, app/shell/export_view.h); the app then runs in
  // the default window size. Empty: the whole window.
  std::string panel;
  int panel_width = 0, panel_height = 0;  // set by RunOffscreen from width, height
};

// Renders the default layout (never the user's saved layout) offscreen at a fixed 60 Hz
// frame time: warm-up frames, the script, settling frames, then writes the PNG and the
// report. Returns 0, or prints a clear error to stderr and returns 1.
int RunOffscreen(const RenderOptions& options);

}  // namespace facet::app
