// Where the main window opens: the monitor's work area (the screen without task bars and
// docks), or the size and position the user left it at, clamped into that work area, so that
// no panel of a fixed-size window starts off a small screen (1280 x 800, 1366 x 768).
// Rectangles are in the window system's screen coordinates, the window's outer frame
// (decorations included). The rule is pure, so tests need no display.
#pragma once

#include <algorithm>
#include <optional>
#include <string>

namespace facet::app {

struct WindowRect {
  int x = 0, y = 0;  // top-left
  int width = 0, height = 0;
  friend bool operator==(const WindowRect&, const WindowRect&) = default;
};

// The smallest window Facet opens at, when the work area allows it.
constexpr int kMinWindowWidth = 640;
constexpr int kMinWindowHeight = 400;

// No saved window (or a degenerate one): the whole work area. A saved one: its size, at most
// the work area's and at least the minimum (or the work area when that is smaller), moved by
// the least amount that brings it wholly inside the work area.
inline WindowRect InitialWindowRect(const std::optional<WindowRect>& saved, const WindowRect& work_area) {
  if (!saved || saved->width <= 0 || saved->height <= 0) return work_area;
  WindowRect r;
  r.width = std::clamp(saved->width, std::min(kMinWindowWidth, work_area.width), work_area.width);
  r.height = std::clamp(saved->height, std::min(kMinWindowHeight, work_area.height), work_area.height);
  r.x = std::clamp(saved->x, work_area.x, work_area.x + work_area.width - r.width);
  r.y = std::clamp(saved->y, work_area.y, work_area.y + work_area.height - r.height);
  return r;
}

// The saved window: ConfigDirectory()/window.json (app/shell/layout.h). Reading gives nothing
// for a missing or malformed file; writing returns false when the file cannot be written.
std::optional<WindowRect> LoadWindowRect(const std::string& path);
bool SaveWindowRect(const std::string& path, const WindowRect& rect);
std::string WindowRectFilePath();

}  // namespace facet::app
