// V_op: the Move tool drags a model vertex or a whole primitive in the 3D panel; the drag
// moves it directly and the solve that follows starts from there (the paper's "V-ops help the
// solver"). The geometry is core/solve/vertex_move.h; this file is the interaction.
//
// Press on a vertex and drag: the vertex follows the mouse in the plane through it facing the
// camera (with Shift: along the world z axis through it), and lands on a vertex of a visible
// reference mesh that shows within 8 px of the mouse (not with Alt). Press on an edge or a face: the
// whole primitive follows in the horizontal plane through the pressed point (Shift: along z).
// Each frame previews the moved project WITHOUT a solve (the user sees the geometry where
// they put it); the release commits one undoable edit, "Move vertex" or "Move primitive",
// through EndDrag, whose full model update is warm-started from the moved state. A refused
// move (a lock, a dimension through zero) keeps the last accepted preview and shows why;
// a drag with no accepted move, or Escape, cancels.
#pragma once

#include <string>

#include <Eigen/Core>

#include "app/state/app_state.h"
#include "app/state/model_pick.h"

namespace facet::app {

// What the Move tool picks: vertices, edges and faces.
PickFilter MoveToolPickFilter();

// The tool's state between frames, held by the 3D panel that drives it (ViewportPanelState).
struct MoveDrag {
  bool tracking = false;  // the left button was pressed on an element and is still down
  bool started = false;   // BeginDrag ran (the mouse moved)
  bool vertex = false;    // a vertex, or the whole primitive
  VertexRef ref;
  Id primitive_id = kNoId;
  Eigen::Vector3d anchor = Eigen::Vector3d::Zero();         // world point under the mouse at the press
  Eigen::Vector3d plane_normal = Eigen::Vector3d::UnitZ();  // the drag plane through the anchor
  Eigen::Vector2d press_px = Eigen::Vector2d::Zero();
  bool cancelled = false;  // Escape: the rest of the press does nothing (no orbit either)
  bool accepted = false;   // some frame's move was accepted into the preview
  std::string accepted_message;
  std::string hint;  // last result or refusal
};

// One frame of the 3D panel's input for the Move tool.
struct MoveToolInput {
  PickRay ray;             // through the mouse, with the frame's projection
  ElementPick pressed_on;  // what the left press hit (valid when `pressed`)
  bool pressed = false;    // the left button went down on the panel this frame
  bool released = false;   // the left button went up this frame
  bool shift = false;      // along the world z axis
  bool no_snap = false;    // Alt: a dragged vertex does not snap to reference vertices
  bool cancel = false;     // Escape
};

// Advances the tool; call every frame while the Move tool is active or a move drag runs.
void MoveToolFrame(AppState* state, MoveDrag* drag, const MoveToolInput& input);
// Whether a press on an element is being dragged: the panel then neither orbits nor clicks.
bool MoveToolOwnsMouse(const MoveDrag& drag);
// One line for the 3D panel: the tool's help, or the current drag's result or refusal.
std::string MoveToolHint(const MoveDrag& drag);

// The script command `move-selection ARGS` on the selection, one undoable edit each:
//   vertex X Y Z         the selected vertex to world position (X, Y, Z)
//   primitive DX DY DZ   the selected primitive by the world delta (DX, DY, DZ)
// Returns false with *error on bad arguments, a missing selection or a refused move.
bool RunMoveCommand(AppState* state, const std::string& arg, std::string* error);

}  // namespace facet::app
