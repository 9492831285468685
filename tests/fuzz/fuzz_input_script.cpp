// The input script of `facet render --script` (app/state/input_script.h): any text either
// parses or is refused with "line N: ..." naming a line of the text. A parsed script's steps
// name lines of the text, in order, and carry finite positions; parsing is a function of the
// text (a second parse gives the same steps).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "app/state/input_script.h"
#include "tests/fuzz/fuzz_check.h"

namespace {

using facet::app::Script;
using facet::app::ScriptStep;
using facet::fuzz::Fail;
constexpr const char* kTarget = "fuzz_input_script";

bool SameStep(const ScriptStep& a, const ScriptStep& b) {
  return a.line == b.line && a.mouse_pos == b.mouse_pos && a.mouse_space == b.mouse_space &&
         a.mouse_item == b.mouse_item && a.mouse_vertex == b.mouse_vertex && a.drag_anchor == b.drag_anchor &&
         a.drag_fraction == b.drag_fraction && a.mouse_down == b.mouse_down && a.wheel == b.wheel &&
         a.key_press.has_value() == b.key_press.has_value() &&
         (!a.key_press || (a.key_press->key_code == b.key_press->key_code && a.key_press->ctrl == b.key_press->ctrl &&
                           a.key_press->shift == b.key_press->shift && a.key_press->alt == b.key_press->alt &&
                           a.key_press->character == b.key_press->character)) &&
         a.text == b.text && a.hold_shift == b.hold_shift && a.hold_ctrl == b.hold_ctrl && a.hold_alt == b.hold_alt &&
         a.command == b.command && a.command_args == b.command_args && a.dropped_paths == b.dropped_paths &&
         a.screenshot_path == b.screenshot_path;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  int line_count = 1;
  for (char c : text) line_count += c == '\n';

  Script script;
  std::string error;
  if (!facet::app::ParseScript(text, &script, &error)) {
    if (error.rfind("line ", 0) != 0) Fail(kTarget, "a refusal that names no line: " + error);
    const int line = std::atoi(error.c_str() + 5);
    if (line < 1 || line > line_count) Fail(kTarget, "a refusal names a line outside the text: " + error);
    return 0;
  }
  int previous_line = 0;
  for (const ScriptStep& step : script.steps) {
    if (step.line < previous_line || step.line < 1 || step.line > line_count) {
      Fail(kTarget, "step line " + std::to_string(step.line) + " out of order or outside the text");
    }
    previous_line = step.line;
    if (step.mouse_pos && (!std::isfinite((*step.mouse_pos)[0]) || !std::isfinite((*step.mouse_pos)[1]))) {
      Fail(kTarget, "a non-finite mouse position at line " + std::to_string(step.line));
    }
    if (step.drag_fraction && !(*step.drag_fraction >= 0.0f && *step.drag_fraction <= 1.0f)) {
      Fail(kTarget, "a drag fraction outside [0, 1] at line " + std::to_string(step.line));
    }
    if (!std::isfinite(step.wheel)) Fail(kTarget, "a non-finite wheel at line " + std::to_string(step.line));
  }
  if (script.ui_events < 0) Fail(kTarget, "a negative UI event count");

  Script again;
  std::string error_again;
  if (!facet::app::ParseScript(text, &again, &error_again)) Fail(kTarget, "a second parse refuses: " + error_again);
  if (again.steps.size() != script.steps.size() || again.ui_events != script.ui_events) {
    Fail(kTarget, "a second parse gives another script");
  }
  for (size_t i = 0; i < script.steps.size(); ++i) {
    if (!SameStep(script.steps[i], again.steps[i]))
      Fail(kTarget, "a second parse gives another step " + std::to_string(i));
  }
  return 0;
}
