// The shell's own panels and menu bar. Each Draw*Panel draws into the current ImGui window
// (the caller, DrawFrame, owns the window) and changes the project only through the edit
// functions of app/app_state.h.
#pragma once

#include <map>
#include <string>

#include "app/app_state.h"
#include "app/frame.h"

namespace facet::app {

// The main menu bar (File, Edit, View, Help). Returns the bar's height in px.
float DrawMenuBar(AppState* state, ShellState* shell);
// Tool buttons with their shortcuts, Add box and Solve.
void DrawToolsPanel(AppState* state);
// Active image, calibration and solve figures, and the selected box, pin or segment.
void DrawPropertiesPanel(AppState* state);
// The undo stack; clicking an entry undoes or redoes to it.
void DrawHistoryPanel(AppState* state);
// The log, coloured by level.
void DrawLogPanel(AppState* state);

// Screen rectangles of the shell panels' main widgets in the last frame, by name (e.g.
// "tool.Pin", "box.size", "box.name", "history.2"), for the render report and tests.
const std::map<std::string, Rect>& LastItemRects();
// Starts a new frame's record (DrawFrame calls it).
void ClearItemRects();

// Tool shortcuts (V, X, Y, Z, P, B) when no text field is active and no modifier is down.
void HandleToolShortcuts(AppState* state);
// Adds a unit box (K_create) as one history entry and selects it.
void AddBox(AppState* state);
// Re-runs calibration and the geometry solve on the current project (one history entry
// when the solve changes anything).
void SolveNow(AppState* state);

}  // namespace facet::app
