// The shell's side panels: tools, properties, history and log. Each Draw*Panel draws into the
// current ImGui window (the caller, DrawFrame, owns the window) and changes the project only
// through the edit functions of app/state/app_state.h.
#pragma once

#include <map>
#include <string>

#include "app/panels/camera_sections.h"
#include "app/state/app_state.h"
#include "app/state/rect.h"

namespace facet::app {

// The kinds the tools panel and the Edit menu offer to add, in menu order.
constexpr PrimitiveKind kPrimitiveKinds[] = {PrimitiveKind::kBox,     PrimitiveKind::kWedge,    PrimitiveKind::kPrism,
                                             PrimitiveKind::kPyramid, PrimitiveKind::kCylinder, PrimitiveKind::kPlane};

// Tool buttons with their shortcuts, the kind to add, the selection actions and Solve.
void DrawToolsPanel(AppState* state);
// What the properties panel keeps between frames; owned by the shell.
struct PropertiesPanelState {
  ExifFeedback exif_feedback;
};

// Active image, calibration and solve figures, and the selected primitive (and its vertex,
// edge or face), pin or segment.
void DrawPropertiesPanel(AppState* state, PropertiesPanelState* panel);
// The undo stack; clicking an entry undoes or redoes to it.
void DrawHistoryPanel(AppState* state);
// The log, coloured by level.
void DrawLogPanel(AppState* state);

// Tool shortcuts (V, X, Y, Z, P, B, E, D, C, R) and the selection actions (T: free vertex,
// K: keep face planar) when no text field is active and no modifier is down.
void HandleToolShortcuts(AppState* state);
// Switches tool (forgetting V_connect's first vertex).
void SetTool(AppState* state, Tool tool);
// K_create of state->add_kind as one history entry, on top of the selected box when the kind
// allows it and add_on_top holds; selects it and switches to the pin tool.
void AddPrimitiveAction(AppState* state);
// Re-runs calibration and the geometry solve on the current project (one history entry
// when the solve changes anything).
void SolveNow(AppState* state);

}  // namespace facet::app
