#include "core/scene/modelling_state.h"

namespace facet {

ModellingStateCounts CountModellingState(const Project& project) {
  ModellingStateCounts counts;
  counts.primitives = static_cast<int>(project.primitives.size());
  for (const Primitive& primitive : project.primitives) {
    counts.vertices += primitive.mesh.NumVertices();
    counts.edges += primitive.mesh.NumEdges();
    counts.faces += primitive.mesh.NumFaces();
  }
  counts.pins = static_cast<int>(project.pins.size());
  counts.spatial_constraints = static_cast<int>(project.constraints.size());
  counts.images = static_cast<int>(project.images.size());
  counts.segments = static_cast<int>(project.segments.size());
  return counts;
}

std::vector<ModellingStateCounts> HistoryStateCounts(const Document& document) {
  const std::vector<Edit>& undo = document.undo_stack();
  const std::vector<Edit>& redo = document.redo_stack();
  std::vector<ModellingStateCounts> out(undo.size() + 1 + redo.size());
  Project project = document.project();
  out[undo.size()] = CountModellingState(project);
  for (size_t k = undo.size(); k-- > 0;) {
    RevertEdit(undo[k], &project);
    out[k] = CountModellingState(project);
  }
  project = document.project();
  // The redo stack holds the next redo last.
  for (size_t k = 0; k < redo.size(); ++k) {
    ApplyEdit(redo[redo.size() - 1 - k], &project);
    out[undo.size() + 1 + k] = CountModellingState(project);
  }
  return out;
}

}  // namespace facet
