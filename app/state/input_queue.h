// The platform's input events in the order they happened, handed to the UI one frame at a
// time so that no press or release is lost and each is seen where it happened, however long
// a frame takes. Dear ImGui 1.86 reads input as a state per frame (io.MouseDown, io.KeysDown,
// io.MousePos): a key pressed and released within one slow frame, or a double-click, would
// never be seen, and a release followed by a move would be seen where the pointer went. The
// queue "trickles" instead: a frame takes events up to the first one that would change a
// button or key already changed in that frame (or move the pointer after a button changed);
// the rest wait for the next frames. The window (GLFW callbacks) and the offscreen input
// script both feed it (app/shell/app.cpp, app/shell/glfw_window.cpp).
#pragma once

#include <array>
#include <bitset>
#include <cfloat>
#include <deque>
#include <vector>

namespace facet::app {

constexpr int kQueuedMouseButtons = 5;
constexpr int kQueuedKeys = 512;  // io.KeysDown's size; GLFW key codes

struct InputEvent {
  enum class Kind { kMouseMove, kMouseButton, kWheel, kKey, kChar };
  Kind kind = Kind::kMouseMove;
  double time_s = 0.0;       // when the platform delivered it (the frame clock's seconds)
  float x = 0.0f, y = 0.0f;  // kMouseMove: screen px (-FLT_MAX: no pointer); kWheel: dx, dy
  int code = 0;              // kMouseButton: 0 left, 1 right, 2 middle; kKey: GLFW key code
  bool down = false;         // kMouseButton, kKey: pressed (true) or released
  unsigned character = 0;    // kChar: a Unicode code point
};

// The input state one frame sees.
struct InputFrame {
  float mouse_x = -FLT_MAX, mouse_y = -FLT_MAX;  // no pointer until one moves
  std::array<bool, kQueuedMouseButtons> mouse_down{};
  std::bitset<kQueuedKeys> keys_down;
  float wheel_x = 0.0f, wheel_y = 0.0f;  // this frame's turns
  std::vector<unsigned> characters;      // typed this frame, in order
  // Seconds of UI time since the frame before (io.DeltaTime): the real frame time, except
  // when the frame replays events that waited, where it is the time between those events
  // (so a double-click spread over several frames is still a double-click).
  double delta_s = 1.0 / 60.0;
};

class InputQueue {
 public:
  void Push(const InputEvent& event);
  void MouseMove(double time_s, float x, float y);
  void MouseButton(double time_s, int button, bool down);
  void Wheel(double time_s, float dx, float dy);
  void Key(double time_s, int key, bool down);
  void Char(double time_s, unsigned character);
  // Releases every button and key still down (the window lost the focus: their releases
  // will not come).
  void ReleaseAll(double time_s);

  // The input of the next frame at time `now_s`: the queued events it may take, applied in
  // order. Events that must wait stay queued for the following frames.
  InputFrame NextFrame(double now_s);

  bool Pending() const { return !events_.empty(); }
  const InputFrame& State() const { return state_; }  // after all events taken so far

 private:
  std::deque<InputEvent> events_;
  InputFrame state_;
  // The buttons and keys down after every queued event (what ReleaseAll releases).
  std::array<bool, kQueuedMouseButtons> latest_buttons_{};
  std::bitset<kQueuedKeys> latest_keys_;
  double ui_time_s_ = 0.0;  // the UI clock after the last frame (the sum of its deltas)
};

}  // namespace facet::app
