#include "app/state/input_queue.h"

#include <algorithm>

namespace facet::app {
namespace {

// ImGui asserts a positive frame time; a frame replaying events that happened together
// advances the UI clock by this much.
constexpr double kMinFrameDeltaS = 1e-4;

bool ValidButton(int b) { return b >= 0 && b < kQueuedMouseButtons; }
bool ValidKey(int k) { return k >= 0 && k < kQueuedKeys; }

}  // namespace

void InputQueue::Push(const InputEvent& event) {
  if (event.kind == InputEvent::Kind::kMouseButton && !ValidButton(event.code)) return;
  if (event.kind == InputEvent::Kind::kKey && !ValidKey(event.code)) return;
  switch (event.kind) {
    case InputEvent::Kind::kMouseButton: latest_buttons_[event.code] = event.down; break;
    case InputEvent::Kind::kKey: latest_keys_[event.code] = event.down; break;
    default: break;
  }
  events_.push_back(event);
}

void InputQueue::MouseMove(double time_s, float x, float y) {
  Push({.kind = InputEvent::Kind::kMouseMove, .time_s = time_s, .x = x, .y = y});
}

void InputQueue::MouseButton(double time_s, int button, bool down) {
  Push({.kind = InputEvent::Kind::kMouseButton, .time_s = time_s, .code = button, .down = down});
}

void InputQueue::Wheel(double time_s, float dx, float dy) {
  Push({.kind = InputEvent::Kind::kWheel, .time_s = time_s, .x = dx, .y = dy});
}

void InputQueue::Key(double time_s, int key, bool down) {
  Push({.kind = InputEvent::Kind::kKey, .time_s = time_s, .code = key, .down = down});
}

void InputQueue::Char(double time_s, unsigned character) {
  Push({.kind = InputEvent::Kind::kChar, .time_s = time_s, .character = character});
}

void InputQueue::ReleaseAll(double time_s) {
  for (int b = 0; b < kQueuedMouseButtons; ++b) {
    if (latest_buttons_[b]) MouseButton(time_s, b, false);
  }
  for (int k = 0; k < kQueuedKeys; ++k) {
    if (latest_keys_[k]) Key(time_s, k, false);
  }
}

InputFrame InputQueue::NextFrame(double now_s) {
  state_.wheel_x = state_.wheel_y = 0.0f;
  state_.characters.clear();
  unsigned buttons_changed = 0;
  std::bitset<kQueuedKeys> keys_changed;
  bool typed = false;
  double last_taken_s = now_s;
  while (!events_.empty()) {
    const InputEvent& e = events_.front();
    bool wait = false;
    switch (e.kind) {
      case InputEvent::Kind::kMouseMove:
        // After a press or release, the pointer stays where it happened for this frame.
        wait = buttons_changed != 0;
        if (!wait) {
          state_.mouse_x = e.x;
          state_.mouse_y = e.y;
        }
        break;
      case InputEvent::Kind::kMouseButton:
        wait = (buttons_changed & (1u << e.code)) != 0;
        if (!wait && state_.mouse_down[e.code] != e.down) {
          state_.mouse_down[e.code] = e.down;
          buttons_changed |= 1u << e.code;
        }
        break;
      case InputEvent::Kind::kWheel:
        wait = buttons_changed != 0;
        if (!wait) {
          state_.wheel_x += e.x;
          state_.wheel_y += e.y;
        }
        break;
      case InputEvent::Kind::kKey:
        // Text typed before a key (Enter after a name) reaches the field first.
        wait = keys_changed[e.code] || typed;
        if (!wait && state_.keys_down[e.code] != e.down) {
          state_.keys_down[e.code] = e.down;
          keys_changed[e.code] = true;
        }
        break;
      case InputEvent::Kind::kChar:
        // Text after a click goes to the field the click activates, a frame later.
        wait = buttons_changed != 0;
        if (!wait) {
          state_.characters.push_back(e.character);
          typed = true;
        }
        break;
    }
    if (wait) break;
    last_taken_s = e.time_s;
    events_.pop_front();
  }
  // A frame that leaves events waiting happened, as far as the UI can tell, when its last
  // event did; the frames that replay the rest follow at the events' own times.
  const double frame_time_s = events_.empty() ? now_s : last_taken_s;
  state_.delta_s = std::max(frame_time_s - ui_time_s_, kMinFrameDeltaS);
  ui_time_s_ += state_.delta_s;
  return state_;
}

}  // namespace facet::app
