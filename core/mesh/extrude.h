// Face extrusion (push/pull, as SketchUp users expect): a face moves out along its normal
// and a ring of side quads joins it to where it was.
//
// Topology: for a face of n vertices v_0..v_{n-1}, ExtrudeFace adds n vertices w_i, n side
// edges v_i - w_i, n cap edges w_i - w_{i+1} and n side faces (V += n, E += 2n, F += n, so the
// Euler characteristic is unchanged). The extruded face keeps its id, material and corner
// UVs and now runs through the w_i; its old half-edges (v_i -> v_{i+1}) and their twins keep
// their ids and now border side face i, so the neighbours of the face do not change at all.
//
// Positions: w_i is defined in primitive-local coordinates as v_i's LocalDefinition plus a
// local offset `direction * distance`, with `direction` the face's unit normal in the
// primitive's frame when it was extruded (core/mesh/mesh.h, LocalDefinition::offset). Resizing or
// moving the primitive (UpdatePrimitivePositions) therefore keeps the extrusion on its face:
// a box's extruded top rises with the box, and stays `distance` above it. A negative
// distance pushes the face in (a pocket); the side faces then face inwards, as the half-edge
// orientation demands.
//
// Side faces take the extruded face's material and primitive; their corner UVs are in
// primitive-local units, u along the base edge and v along the extrusion (as AddPrimitive
// lays out a face).
//
// Exact inverses: UndoExtrudeFace (or ApplyUndo on the result's undo) restores the mesh
// identically (operator==); SetExtrusionDistance back to the original distance restores the
// extruded mesh identically too.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/mesh/mesh.h"
#include "core/mesh/operators.h"
#include "core/mesh/primitives.h"

namespace facet {

struct ExtrudeResult {
  bool ok = false;
  std::string message;
  FaceId face = kNoFace;                                             // the extruded face (same id before and after)
  double distance = 0.0;                                             // along `direction`, primitive-local units
  Eigen::Vector3d direction_in_primitive = Eigen::Vector3d::Zero();  // unit face normal
  // Index i in these lists is the face's corner i, starting at the face's first half-edge.
  std::vector<VertexId> base_vertices;        // v_i
  std::vector<VertexId> new_vertices;         // w_i
  std::vector<Eigen::Vector3d> base_offsets;  // v_i's local offset when extruded
  std::vector<EdgeId> side_edges;             // v_i - w_i; half-edge 2e runs v_i -> w_i
  std::vector<EdgeId> cap_edges;              // w_i - w_{i+1}; half-edge 2e runs w_i -> w_{i+1}, in `face`
  std::vector<FaceId> side_faces;             // side face i holds v_i -> v_{i+1}
  MeshUndo undo;
};

// Extrudes `face` of the primitive `shape` (the face's primitive must be shape.id) by
// `distance` primitive-local units along its outward normal, and places the new vertices in
// world from the shape's pose. O(n) in the face's degree. Refuses a dead face, a face of
// another primitive, a degenerate face, a face whose vertices are not on one plane (more than
// 1e-9 of its size off it), and a zero or non-finite distance; the mesh is then unchanged.
ExtrudeResult ExtrudeFace(PolyMesh* mesh, const PrimitiveShape& shape, FaceId face, double distance);

// The exact inverse of ExtrudeFace, applied to the mesh as the extrusion left it (possibly
// after SetExtrusionDistance). Refuses (message, mesh unchanged) when the elements the
// extrusion created are gone or no longer form its ring.
bool UndoExtrudeFace(PolyMesh* mesh, const ExtrudeResult& extrusion, std::string* message);

struct ExtrusionDistanceResult {
  bool ok = false;
  std::string message;
  double previous_distance = 0.0;
  MeshUndo undo;  // ApplyUndo reverts the change exactly
};

// Push/pull again: moves an extrusion's new vertices to `distance` along its direction
// (offset_i = base_offset_i + direction * distance), updates their world positions and the
// side faces' UVs, and records the distance in *extrusion. Refuses a zero or non-finite
// distance and an extrusion whose vertices are gone; the mesh is then unchanged.
ExtrusionDistanceResult SetExtrusionDistance(PolyMesh* mesh, const PrimitiveShape& shape, ExtrudeResult* extrusion,
                                             double distance);

}  // namespace facet
