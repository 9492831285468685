// The input queue (app/state/input_queue.h) without a window: what each frame sees when the
// platform delivers several presses and releases between two frames, and the UI clock it
// gives ImGui, so that a double-click spread over slow frames is still a double-click.
#include <doctest/doctest.h>

#include "app/state/input_queue.h"

using facet::app::InputFrame;
using facet::app::InputQueue;

namespace {
constexpr int kKeyB = 66;  // GLFW_KEY_B
// ImGui's default io.MouseDoubleClickTime.
constexpr double kDoubleClickTimeS = 0.30;
}  // namespace

TEST_CASE("input queue: a double-click within one slow frame reaches the UI as four changes, 0.3 s apart at most") {
  InputQueue queue;
  queue.MouseMove(0.0, 10.0f, 20.0f);
  queue.NextFrame(0.0);
  // One frame of 1 s: the platform delivered press, release, press, release at ~1.0 s.
  for (bool down : {true, false, true, false}) queue.MouseButton(1.0, 0, down);
  std::vector<bool> seen;
  double clock_at_first_press = -1.0, clock = 0.0;
  double between_presses = -1.0;
  for (int frame = 0; frame < 6; ++frame) {
    const InputFrame f = queue.NextFrame(2.0 + frame);  // every frame slow too
    clock += f.delta_s;
    if (seen.empty() || seen.back() != f.mouse_down[0]) {
      seen.push_back(f.mouse_down[0]);
      if (f.mouse_down[0] && clock_at_first_press < 0.0) {
        clock_at_first_press = clock;
      } else if (f.mouse_down[0]) {
        between_presses = clock - clock_at_first_press;
      }
    }
    CHECK(f.delta_s > 0.0);
  }
  CHECK(seen == std::vector<bool>{true, false, true, false});
  CHECK_FALSE(queue.Pending());
  CAPTURE(between_presses);
  CHECK(between_presses >= 0.0);
  CHECK(between_presses < kDoubleClickTimeS);
}

TEST_CASE("input queue: a release then a move in one frame: the release frame has the release position") {
  InputQueue queue;
  queue.MouseMove(0.0, 100.0f, 50.0f);
  queue.MouseButton(0.0, 0, true);
  InputFrame f = queue.NextFrame(0.016);
  CHECK(f.mouse_down[0]);
  queue.MouseButton(0.02, 0, false);
  queue.MouseMove(0.021, 300.0f, 90.0f);
  f = queue.NextFrame(0.033);
  CHECK_FALSE(f.mouse_down[0]);
  CHECK(f.mouse_x == 100.0f);
  CHECK(f.mouse_y == 50.0f);
  f = queue.NextFrame(0.05);
  CHECK(f.mouse_x == 300.0f);
  CHECK(f.mouse_y == 90.0f);
}

TEST_CASE("input queue: a key tapped within one frame is down for one frame, with its character") {
  InputQueue queue;
  queue.Key(0.5, kKeyB, true);
  queue.Char(0.5, 'b');
  queue.Key(0.5, kKeyB, false);
  InputFrame f = queue.NextFrame(0.5);
  CHECK(f.keys_down[kKeyB]);
  REQUIRE(f.characters.size() == 1);
  CHECK(f.characters[0] == 'b');
  f = queue.NextFrame(0.6);
  CHECK_FALSE(f.keys_down[kKeyB]);
  CHECK(f.characters.empty());
  CHECK_FALSE(queue.Pending());
}

TEST_CASE("input queue: ordinary input (one change per frame) passes at once, at the real frame time") {
  InputQueue queue;
  queue.MouseMove(1.0, 5.0f, 6.0f);
  queue.MouseButton(1.0, 1, true);
  queue.Key(1.0, kKeyB, true);
  queue.Wheel(1.0, 0.0f, 2.0f);  // after a press: waits a frame
  InputFrame f = queue.NextFrame(1.0);
  CHECK(f.mouse_down[1]);
  CHECK(f.keys_down[kKeyB]);
  CHECK(f.wheel_y == 0.0f);
  f = queue.NextFrame(1.25);
  CHECK(f.wheel_y == 2.0f);
  CHECK(f.delta_s == doctest::Approx(0.25));
  // Focus lost with the button and key down: both released.
  queue.ReleaseAll(1.3);
  f = queue.NextFrame(1.3);
  CHECK_FALSE(f.mouse_down[1]);
  CHECK_FALSE(f.keys_down[kKeyB]);
}
