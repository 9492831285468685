// V_op (issue 5): the user drags a model vertex or a whole primitive in 3D and the model moves
// there directly, so that the next solve starts from the moved state (the paper: "V-ops help
// the solver" out of a wrong local minimum or into an undetermined dimension).
//
// MoveVertex moves one vertex to a target world position by the smallest change of its
// primitive:
// - a free vertex (LocalDefinition::free) changes its own offset only: exact, nothing else moves;
// - otherwise the primitive's unlocked shape parameters and unlocked translation change, the
//   rotation stays. For a fixed rotation every vertex's world position is linear in
//   x = (params, translation): w_i = R (C_i params + offset_i) + translation = A_i x + c_i.
//   The step dx solves   min sum_{i != dragged} |A_i dx|^2   s.t.  A_d dx = target - w_d
//   (the other vertices of the primitive move as little as possible), by the nullspace method
//   on a rank-revealing decomposition of A_d. When the target is out of reach (A_d dx cannot
//   equal it: a locked dimension or translation, or a vertex whose position does not depend on
//   some direction), the vertex goes to the closest reachable point instead (A_d dx is the
//   projection of the wanted displacement onto A_d's range) and the summary names the locks
//   that limited it.
// Locks: a locked shape parameter (Primitive::param_locked) or a locked translation
// (translation_locked) does not change. A primitive attached on a box (attached_to) takes its
// footprint (params 0 and 1) and pose from its base, so only its own params from index 2 on
// change; moving the base's vertices moves the attached primitives along.
// Refusals (ok false, project unchanged, message says why): a missing primitive or vertex, a
// non-finite target, a move that would make a dimension <= 0 (the drag went through the
// opposite face) or leave nothing to change (everything locked; the message says what to
// unlock), and one that leaves no model by the check every solve's result passes
// (CheckModelChange, core/solve/model_sanity.h: a size dragged to a millionth of itself, or
// grown, or the primitive moved, far beyond its reach -- a drag ray grazing its plane).
//
// MovePrimitive translates a whole primitive by a world delta; refused when its translation
// is locked, it is attached to a base (move the base instead) or the model check refuses it.
//
// Units: the project's (world) units throughout; frames: world unless named _in_primitive.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/optim/solver_summary.h"
#include "core/scene/project.h"

namespace facet {

struct VertexMoveOptions {
  // Singular values of A_d (and of the objective restricted to A_d's nullspace) below this
  // times the largest count as zero: the direction is not reachable.
  double rank_tolerance = 1e-10;
  // The summary's `reached` holds when the vertex ends within this of the target, relative
  // to max(1, the primitive's size).
  double reach_tolerance = 1e-9;

  bool Check(std::string* error) const;
};

// Not a solver summary (core/optim/solver_summary.h): the move is one direct constrained
// least-squares step, with no iterations and no cost to report; `ok` and `message` say whether
// it was applied and why not, the rest what it did.
// SolverSummary: termination kConverged when the primitive moved (towards the target as far
// as its locks allow: see reached), kInvalidInput when the request was bad (no such vertex, a
// target not finite, bad options), kFailed when no free parameter moves the vertex that way;
// message: what changed ("box 'house': size y 3 -> 4"), or why the move was refused.
struct VertexMoveSummary : SolverSummary {
  bool reached = false;                                // the vertex is at the target (within reach_tolerance)
  bool moved_offset = false;                           // a free vertex: only its offset changed
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // the vertex's world position after the move
  double distance_to_target = 0.0;                     // |position - target|
  // Why the target was out of reach: one short phrase per lock or rule that kept a direction
  // fixed ("translation is locked", "Size z is locked", "footprint follows base 'box'"),
  // and what to unlock. Empty when reached.
  std::vector<std::string> limited_by;
  // Largest displacement of another vertex of the same primitive (world units).
  double max_other_displacement = 0.0;
  PrimitiveParams params_before = PrimitiveParams::Zero();
  PrimitiveParams params_after = PrimitiveParams::Zero();
  Eigen::Vector3d translation_before = Eigen::Vector3d::Zero();
  Eigen::Vector3d translation_after = Eigen::Vector3d::Zero();
};

// Moves `vertex` towards `target_in_world`. On success *moved is `project` with the
// primitive's shape (or the vertex's offset) changed and every primitive's cached positions
// refreshed (attached primitives follow); otherwise *moved is an unchanged copy.
// `moved` must not alias `project`.
VertexMoveSummary MoveVertex(const Project& project, const VertexRef& vertex, const Eigen::Vector3d& target_in_world,
                             const VertexMoveOptions& options, Project* moved);

// Not a solver summary either: a translation, applied or refused.
// SolverSummary: kConverged when it moved, kInvalidInput when refused (message says why).
struct PrimitiveMoveSummary : SolverSummary {};

// Translates the primitive by `delta_in_world` (its attached primitives follow). Refused when
// the primitive is missing, the delta is not finite, its translation is locked or it is
// attached to a base. *moved as for MoveVertex.
PrimitiveMoveSummary MovePrimitive(const Project& project, Id primitive_id, const Eigen::Vector3d& delta_in_world,
                                   Project* moved);

// Number of shape parameters a kind uses (core/mesh/primitives.h): 3 for box, wedge and
// pyramid, 2 for prism, cylinder and plane.
int ShapeParamCount(PrimitiveKind kind);
// The name of a kind's shape parameter as the properties panel shows it ("Size x", "Radius",
// "Height", ...), so that messages point at the field to edit or unlock.
const char* ShapeParamLabel(PrimitiveKind kind, int index);

}  // namespace facet
