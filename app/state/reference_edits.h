// Reference geometry in the app (issue 13; core/scene/project.h, Reference): adding and
// removing a reference mesh (one undoable edit each, no re-solve: a reference is not part of
// the model), the meshes read from their files, and the snap of a dragged vertex onto a
// reference vertex.
#pragma once

#include <string>

#include <Eigen/Core>

#include "app/state/app_state.h"
#include "app/state/model_pick.h"

namespace facet::app {

// Reads `file_path` (.obj, .glb or .gltf) and, when it holds triangles, adds it to the project as a
// reference (stored relative to the project file, as photos are) in one undoable edit
// "Add reference NAME". A file that cannot be read is refused with the reason in the log and
// changes nothing. Returns whether it was added.
bool AddReferenceEdit(AppState* state, const std::string& file_path, bool y_up);
// Removes the reference `id` in one undoable edit. False (logged) when there is none.
bool RemoveReferenceEdit(AppState* state, Id id);
// Shows or hides the reference `id` (drawing and snapping) in one undoable edit; stored in the
// project. False (logged) when there is none; true without an edit when it is so already.
bool SetReferenceVisibleEdit(AppState* state, Id id, bool visible);

// Keeps state->references in step with the project's references: reads each new or changed
// one once (a missing or bad file logs one warning naming it and stays undrawn; the reference
// stays in the project) and drops those no longer there; reference_revision counts the
// changes. Called once per frame by RefreshDerived's caller.
void SyncReferenceMeshes(AppState* state);

// The visible reference vertex whose projection lies nearest the mouse of `ray`, within
// radius_px: true with its world position. What the Move tool snaps a dragged vertex to.
bool NearestReferenceVertex(const AppState& state, const PickRay& ray, double radius_px, Eigen::Vector3d* p_in_world);

}  // namespace facet::app
