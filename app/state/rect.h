// A rectangle on the screen, in screen pixels: origin at the top-left of the window, y down.
// The layout, the render report and the widget record all use it.
#pragma once

namespace facet::app {

struct Rect {
  float x = 0, y = 0, w = 0, h = 0;
  bool Contains(float px, float py) const { return px >= x && py >= y && px < x + w && py < y + h; }
};

}  // namespace facet::app
