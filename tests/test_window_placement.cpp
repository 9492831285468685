// Issue 12: the main window opens at the monitor's work area, or at the saved window clamped
// into it (app/shell/window_placement.h), so that on a 1280 x 800 or 1366 x 768 screen no
// panel starts off-screen. A pure rule: no display needed.
#include <doctest/doctest.h>

#include "app/shell/window_placement.h"

using facet::app::InitialWindowRect;
using facet::app::WindowRect;

namespace {
bool Inside(const WindowRect& r, const WindowRect& area) {
  return r.x >= area.x && r.y >= area.y && r.x + r.width <= area.x + area.width &&
         r.y + r.height <= area.y + area.height;
}
}  // namespace

TEST_CASE("no saved window: the whole work area of each common screen") {
  for (const WindowRect area : {WindowRect{0, 0, 1280, 800}, WindowRect{0, 27, 1366, 741}, WindowRect{0, 0, 1920, 1040},
                                WindowRect{1920, 0, 2560, 1400}}) {
    CHECK(InitialWindowRect(std::nullopt, area) == area);
    CHECK(InitialWindowRect(WindowRect{10, 10, 0, 0}, area) == area);  // a degenerate file
  }
}

TEST_CASE("the old fixed 1600 x 900 window on small screens is clamped into the work area") {
  const WindowRect old_default{0, 0, 1600, 900};
  for (const WindowRect area : {WindowRect{0, 0, 1280, 800}, WindowRect{0, 27, 1366, 741}}) {
    const WindowRect r = InitialWindowRect(old_default, area);
    CAPTURE(area.width);
    CHECK(Inside(r, area));
    CHECK(r.width == area.width);
    CHECK(r.height == area.height);
  }
}

TEST_CASE("a saved window that fits keeps its size and place; one off the screen comes back") {
  const WindowRect area{0, 0, 1920, 1040};
  const WindowRect fits{100, 80, 1200, 700};
  CHECK(InitialWindowRect(fits, area) == fits);
  // Left on a second monitor that is gone: moved the least amount into this work area.
  const WindowRect off{2500, -300, 1200, 700};
  const WindowRect back = InitialWindowRect(off, area);
  CHECK(Inside(back, area));
  CHECK(back.width == 1200);
  CHECK(back.height == 700);
  CHECK(back.x == 1920 - 1200);
  CHECK(back.y == 0);
  // A tiny saved window grows to the minimum; a work area below the minimum is the limit.
  const WindowRect tiny = InitialWindowRect(WindowRect{5, 5, 100, 50}, area);
  CHECK(tiny.width == facet::app::kMinWindowWidth);
  CHECK(tiny.height == facet::app::kMinWindowHeight);
  const WindowRect small_area{0, 0, 600, 300};
  CHECK(InitialWindowRect(WindowRect{0, 0, 1600, 900}, small_area) == small_area);
}
