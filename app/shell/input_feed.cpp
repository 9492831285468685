#include "app/shell/input_feed.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>  // key codes

namespace facet::app {

void ApplyInputFrame(const InputFrame& frame, ImGuiIO* io) {
  io->MousePos = ImVec2(frame.mouse_x, frame.mouse_y);
  for (int b = 0; b < kQueuedMouseButtons && b < IM_ARRAYSIZE(io->MouseDown); ++b)
    io->MouseDown[b] = frame.mouse_down[b];
  for (int k = 0; k < kQueuedKeys && k < IM_ARRAYSIZE(io->KeysDown); ++k) io->KeysDown[k] = frame.keys_down[k];
  const auto down = [&](int key) { return frame.keys_down[key]; };
  io->KeyCtrl = down(GLFW_KEY_LEFT_CONTROL) || down(GLFW_KEY_RIGHT_CONTROL);
  io->KeyShift = down(GLFW_KEY_LEFT_SHIFT) || down(GLFW_KEY_RIGHT_SHIFT);
  io->KeyAlt = down(GLFW_KEY_LEFT_ALT) || down(GLFW_KEY_RIGHT_ALT);
  io->KeySuper = down(GLFW_KEY_LEFT_SUPER) || down(GLFW_KEY_RIGHT_SUPER);
  io->MouseWheel = frame.wheel_y;
  io->MouseWheelH = frame.wheel_x;
  for (unsigned c : frame.characters) io->AddInputCharacter(c);
  io->DeltaTime = static_cast<float>(frame.delta_s);
}

}  // namespace facet::app
