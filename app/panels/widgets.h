// Widgets and colours the properties panels share: label/value rows, wrapped coloured text,
// the undo pattern for continuous widgets and the per-frame record of widget rectangles
// (AppState::item_rects, read by the render report and tests).
#pragma once

#include <functional>
#include <map>
#include <string>

#include <imgui.h>

#include "app/state/app_state.h"
#include "app/state/rect.h"

namespace facet::app {

constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;
inline const ImVec4 kDimText(0.55f, 0.57f, 0.62f, 1.0f);
inline const ImVec4 kWarningText(0.98f, 0.78f, 0.30f, 1.0f);
inline const ImVec4 kErrorText(1.00f, 0.42f, 0.40f, 1.0f);
inline const ImVec4 kGoodText(0.45f, 0.85f, 0.50f, 1.0f);

// Shortcuts of the actions on the selection, shown in their labels (side_panels.cpp handles the keys).
constexpr const char* kFreeVertexShortcut = "T";
constexpr const char* kPlanarFaceShortcut = "K";

// Records the last ImGui item's rectangle under `name` in state->item_rects.
void RecordItem(AppState* state, const std::string& name);
ImVec4 AxisColor(Axis axis);
// A dim label and a value in a second column.
void LabelValue(const char* label, const char* fmt, ...) IM_FMTARGS(2);
void WrappedColored(const ImVec4& color, const std::string& text);
// The undo pattern for continuous widgets: activation snapshots the project, every change
// previews the edited copy, deactivation after an edit records the whole interaction as one
// history entry. `changed` is the widget's return value; `apply` edits a project copy.
void TrackEdit(AppState* state, const std::string& label, bool changed, const std::function<void(Project*)>& apply);
bool DragDoubles(const char* label, double* values, int count, float speed, const char* format);
// DragDoubles laid out as ImGui's DragScalarN (one group: IsItemActivated and the undo hooks
// see the whole row), with each component's rectangle recorded as `item_name`.0, .1, ... so
// that an input script can click the one it types into (e.g. a rotation's z).
bool DragDoublesRecorded(AppState* state, const char* label, double* values, int count, float speed, const char* format,
                         const std::string& item_name);

}  // namespace facet::app
