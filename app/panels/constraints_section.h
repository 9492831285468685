// The properties panel's model sections: the selected vertex, edge or face with the
// constraint builder, and the list of every constraint with its residual.
#pragma once

#include "app/state/app_state.h"

namespace facet::app {

// The selected element of `primitive`: position, freedom, pins, and the constraints that can
// be built on it.
void DrawElementSection(AppState* state, const Primitive& primitive, const ElementRef& element);
// One row per constraint: kind, vertices, residual of the last joint solve, remove.
void DrawConstraintsSection(AppState* state);

}  // namespace facet::app
