// V_op: the Move tool drags a model vertex or a whole primitive in the 3D panel; the drag
// moves it directly and the solve that follows starts from there (the paper's "V-ops help the
// solver").
#pragma once

#include <string>

#include "app/app_state.h"

namespace facet::app {

// The script command `move-selection ARGS` on the selected vertex or primitive.
bool RunMoveCommand(AppState* state, const std::string& arg, std::string* error);

}  // namespace facet::app
