// Triangulation of a PolyMesh's faces for rendering and baking, with a stable face-to-
// triangle map: triangles are stored per face id, so an operator's changed faces can be
// re-triangulated alone (RetriangulateFaces) while every other face keeps its triangles.
//
// Each face of n corners gives n - 2 triangles of corner half-edges (a corner carries its
// vertex and UV), counter-clockwise about the face's Newell normal. Ear clipping in the face's
// plane: convex and simple non-convex faces are handled; a clipped ear never has a straight
// tip, so the collinear vertices left by E_split do not produce slivers. A degenerate face
// (no ear found, e.g. zero area) falls back to a fan.
#pragma once

#include <array>
#include <vector>

#include "core/mesh/mesh.h"

namespace facet {

using CornerTriangle = std::array<HalfedgeId, 3>;

struct MeshTriangulation {
  std::vector<std::vector<CornerTriangle>> by_face;  // indexed by face id; empty if dead
};

std::vector<CornerTriangle> TriangulateFace(const PolyMesh& mesh, FaceId face);
MeshTriangulation TriangulateMesh(const PolyMesh& mesh);
// Re-triangulates the listed faces (live or dead: a dead face's triangles are cleared).
void RetriangulateFaces(const PolyMesh& mesh, const std::vector<FaceId>& faces, MeshTriangulation* triangulation);

// A flat triangle list for GPU upload: triangle i uses vertices triangles[i] and corners
// corners[i] and belongs to triangle_face[i]; face f's triangles are the range
// [first_triangle[f], first_triangle[f] + by_face[f].size()).
struct FlatTriangles {
  std::vector<std::array<VertexId, 3>> triangles;
  std::vector<CornerTriangle> corners;
  std::vector<FaceId> triangle_face;
  std::vector<int> first_triangle;  // indexed by face id
};
FlatTriangles Flatten(const PolyMesh& mesh, const MeshTriangulation& triangulation);

}  // namespace facet
