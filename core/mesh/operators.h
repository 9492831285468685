// The paper's topology operators (K-op, section 2) in two inverse pairs on a PolyMesh:
//   E_split (add a vertex on an edge)         <-> V_delete (remove such a vertex)
//   V_connect (split a face by a new edge)    <-> E_delete (merge the two faces of an edge)
//
// Each operator runs in time proportional to the faces it touches (never the whole mesh),
// refuses anything that would break the mesh with a readable message and then changes
// nothing, and returns the ids it created or removed plus a MeshUndo holding the previous
// records of every element it touched.
//
// Exact inverses
// - Applied right after its partner, the inverse operator restores the mesh identically
//   (operator==: same ids, links, positions and attributes): V_delete removes the newer of
//   the vertex's two edges and keeps the older one's half-edges, E_delete keeps the face with
//   the smaller id, and E_split / V_connect never move the pointers those rules rely on.
// - V_delete and E_delete used as forward operators are undone by UndoVDelete / UndoEDelete:
//   the partner operator re-creates the removed elements under their old ids and puts back
//   the recorded attributes. ApplyUndo restores any operator's MeshUndo directly.
//
// Positions: a vertex made by E_split is defined in its primitive's local coordinates as
// (endpoint definitions, t) (core/mesh/mesh.h, LocalDefinition), so UpdatePrimitivePositions keeps
// it on the edge at the same t when the primitive's dimensions change.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "core/mesh/mesh.h"

namespace facet {

// Element records as they were before an operator, and the ids it created.
struct MeshUndo {
  std::vector<std::pair<VertexId, MeshVertex>> vertices;
  std::vector<std::pair<HalfedgeId, MeshHalfedge>> halfedges;
  std::vector<std::pair<FaceId, MeshFace>> faces;
  std::vector<VertexId> created_vertices;
  std::vector<EdgeId> created_edges;
  std::vector<FaceId> created_faces;
};

// Kills the created elements and writes the recorded ones back (reviving dead ids).
void ApplyUndo(PolyMesh* mesh, const MeshUndo& undo);

struct ESplitResult {
  bool ok = false;
  std::string message;
  VertexId vertex = kNoElement;  // the new vertex
  EdgeId new_edge = kNoElement;  // from the new vertex to the split half-edge's destination
  MeshUndo undo;
};

// E_split: adds a vertex on `edge` at parameter t in (0, 1) measured from the origin of its
// half-edge 2 * edge; both faces beside the edge (or the boundary) gain the vertex. Corner UVs
// are interpolated linearly; world position = (1 - t) * a + t * b.
ESplitResult ESplit(PolyMesh* mesh, EdgeId edge, double t);

struct VDeleteResult {
  bool ok = false;
  std::string message;
  VertexId vertex = kNoElement;           // removed
  EdgeId removed_edge = kNoElement;       // the newer of the vertex's two edges
  EdgeId kept_edge = kNoElement;          // now spans the vertex's two neighbours
  HalfedgeId kept_halfedge = kNoElement;  // of kept_edge, the one whose origin did not change
  double t = 0.0;                         // the vertex's parameter along kept_halfedge
  MeshUndo undo;
};

// V_delete: removes a vertex created by E_split that has exactly two edges, joining its
// neighbours by the older edge. Refuses primitive corners, vertices of degree other than 2,
// a vertex of a triangle, and neighbours already joined by an edge.
VDeleteResult VDelete(PolyMesh* mesh, VertexId vertex);

struct VConnectResult {
  bool ok = false;
  std::string message;
  EdgeId edge = kNoElement;   // half-edge 2 * edge runs from v1 to v2
  FaceId new_face = kNoFace;  // the part of `face` that does not hold face.halfedge
  MeshUndo undo;
};

// V_connect: adds an edge between two non-adjacent vertices of one face, splitting it in two;
// the new face copies the material and primitive, the new corners copy the UVs of v1 and v2
// in that face. Convex faces give convex parts. Refuses a self-loop, vertices not both on the
// face, adjacent vertices, and vertices already joined by an edge.
VConnectResult VConnect(PolyMesh* mesh, FaceId face, VertexId v1, VertexId v2);

struct EDeleteResult {
  bool ok = false;
  std::string message;
  EdgeId edge = kNoElement;    // removed
  FaceId kept_face = kNoFace;  // the smaller id of the two faces
  FaceId removed_face = kNoFace;
  int removed_side = 0;      // removed_face was the face of half-edge 2 * edge + side
  VertexId v1 = kNoElement;  // origin of half-edge 2 * edge
  VertexId v2 = kNoElement;
  MeshUndo undo;
};

// E_delete: removes an interior edge and merges its two faces. Refuses boundary edges, an
// edge with the same face on both sides, an endpoint that would be left with one edge, and
// faces that share more than this edge (the merged loop would not be simple).
EDeleteResult EDelete(PolyMesh* mesh, EdgeId edge);

// The inverses, for an undo stack whose "do" is "redo".
VDeleteResult UndoESplit(PolyMesh* mesh, const ESplitResult& split);
ESplitResult UndoVDelete(PolyMesh* mesh, const VDeleteResult& deleted);
EDeleteResult UndoVConnect(PolyMesh* mesh, const VConnectResult& connect);
VConnectResult UndoEDelete(PolyMesh* mesh, const EDeleteResult& deleted);

}  // namespace facet
