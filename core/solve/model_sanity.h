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
  kGrew,         // a size grown to a million times the primitive's reach before the change
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
  bool Ok() const { return fault == ModelChangeFault::kNone; }
};

// Compares each primitive of `after` with the same-id, same-kind primitive of `before`
// (new primitives and changed kinds are not compared; an unchanged size never faults, so an
// old fault is not blamed on this change). Rules, ratios 1e6 both ways:
// - a size <= 0 (or NaN);
// - collapse: now < 1e-6 * was and now < 1e-6 * reach(after) (shrinking from an absurd start,
//   a size of 4e8 back to 4, is a recovery, not a collapse);
// - growth: now > 1e6 * reach(before) (a box of 4 m seen from 12 m does not become 4e8 m wide
//   by any observation; seen when a solve ran its cameras and sizes off to infinity together);
// - runaway: the vertex centroid moved by more than 1e6 * reach(before).
ModelChangeCheck CheckModelChange(const Project& before, const Project& after);

}  // namespace facet
