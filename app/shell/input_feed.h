// Hands one frame of queued input (app/state/input_queue.h) to ImGui 1.86's per-frame state,
// the same way in the window and in the offscreen renderer.
#pragma once

#include <imgui.h>

#include "app/state/input_queue.h"

namespace facet::app {

// Sets io's pointer, buttons, keys (and the Ctrl/Shift/Alt/Super flags from them), wheel,
// typed characters and DeltaTime from `frame`.
void ApplyInputFrame(const InputFrame& frame, ImGuiIO* io);

}  // namespace facet::app
