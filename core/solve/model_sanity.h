// Whether a change of the model (a solve's result, a dragged vertex) left a model at all
// (issue 14: degenerate geometry gives a named error, never a number that looks like an
// answer). Cheap: sizes, vertex centroids and camera centres, linear in their count, so that
// it runs after every solve and every drag frame.
#pragma once

#include <string>

#include "core/scene/project.h"

namespace facet {

enum class ModelChangeFault {
  kNone,
  kNonPositive,  // a size at or below zero
  kCollapsed,    // a size shrunk a millionfold, to a millionth of the primitive's reach
  kGrew,         // a size grown a thousandfold beyond the primitive's reach and any length given
  kRanAway,      // the primitive's centroid moved a million times its reach before the change
};

// The primitive's reach in `project`: its largest size, or its distance from the nearest
// camera centre when that is larger (world units). What a size or a move is measured against.
double PrimitiveReach(const Primitive& primitive, const Project& project);

struct ModelChangeCheck {
  ModelChangeFault fault = ModelChangeFault::kNone;
  // The first fault found, named: "Size x of 'box' would go from 3.973 to 3.98e+08"; "" when
  // there is none.
  std::string what;
  // Whether the user fixed the scale (a known length, a locked size or a fixed point): a
  // runaway then means the observations contradict each other; without, nothing holds it.
  bool scale_given = false;
  bool Ok() const { return fault == ModelChangeFault::kNone; }
};

// Compares each primitive of `after` with the same-id, same-kind primitive of `before`
// (new primitives and changed kinds are not compared; an unchanged size never faults, so an
// old fault is not blamed on this change). Rules:
// - a size <= 0 (or NaN);
// - collapse: now < 1e-6 * was and now < 1e-6 * reach(after) (shrinking from an absurd start,
//   a size of 4e8 back to 4, is a recovery, not a collapse);
// - growth: now > 1e3 * max(reach(before), the largest length the user gave in `after`: known
//   lengths, locked sizes, fixed points) (a box of 4 m seen from 12 m becomes 7e4 m wide by
//   no observation: a solve ran its cameras and sizes off towards infinity together, along
//   the scale the observations do not hold; a typed length of 5 km raises the bound with it);
// - runaway: the vertex centroid moved by more than 1e6 * reach(before).
ModelChangeCheck CheckModelChange(const Project& before, const Project& after);

}  // namespace facet
