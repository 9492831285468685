// The paper's modelling state (K, F) in numbers, per state of the history: the mesh's counts
// (K: primitives and their vertices, edges, faces) and the constraints' (F: pins, spatial
// constraints), with the images and line segments beside them. Teach mode shows one row per
// History entry. The degrees of freedom left need a solve (the rank of its Jacobian,
// JointSolveSummary::degrees_of_freedom_left), so they are the current state's only.
#pragma once

#include <vector>

#include "core/scene/document.h"

namespace facet {

struct ModellingStateCounts {
  int primitives = 0;
  int vertices = 0;  // live vertices of every primitive's mesh, summed
  int edges = 0;
  int faces = 0;
  int pins = 0;
  int spatial_constraints = 0;  // project.constraints (coplanar, distance, line pins, ...)
  int images = 0;
  int segments = 0;
  friend bool operator==(const ModellingStateCounts&, const ModellingStateCounts&) = default;
};

ModellingStateCounts CountModellingState(const Project& project);

// The counts of every state of the document's history, oldest first: entry k is the state
// after the first k undo entries (entry 0 before any edit, entry undo_stack().size() the
// current project), then one entry per redo state (after each redo in turn). Computed by
// reverting and re-applying the edits on one copy of the project.
std::vector<ModellingStateCounts> HistoryStateCounts(const Document& document);

}  // namespace facet
