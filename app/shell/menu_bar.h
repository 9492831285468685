// The main menu bar (File, Edit, View, Help) with the tool and solve status on its right.
#pragma once

#include "app/shell/frame.h"
#include "app/state/app_state.h"

namespace facet::app {

// Draws the bar; menu items run app commands or open the shell's dialogs. Returns the bar's
// height in px.
float DrawMenuBar(AppState* state, ShellState* shell);

}  // namespace facet::app
