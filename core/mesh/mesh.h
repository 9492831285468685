// A half-edge polygon mesh with stable ids: the paper's M = (K, V, D, S) with topology K,
// vertex positions V (world, cached, and their primitive-local definitions), per-face
// discrete attributes D (material id) and per-corner continuous attributes S (UV).
//
// Storage and ids
// - Every element lives in a slot vector indexed by its id, with an alive flag: lookup is
//   O(1), ids survive deletions and are never handed out again except when an undo record
//   revives the very element it removed (core/mesh/operators.h).
// - Half-edges come in pairs: edge e owns half-edges 2e and 2e + 1, so Twin(h) = h ^ 1 and
//   an edge id is h / 2. Boundary half-edges have face kNoFace and are linked into
//   boundary loops like face loops.
// - A scene is ONE mesh holding several primitives: each vertex and face records the id of
//   the primitive it belongs to (core/mesh/primitives.h); primitives are disjoint components.
// - Corner attributes (UV) live on the half-edge that leaves the corner's vertex in the face.
//
// Equality (operator==) compares live elements only, with all their ids, links, positions
// and attributes; dead slots and the next-id counters are not compared.
#pragma once

#include <cassert>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace facet {

using VertexId = std::uint32_t;
using HalfedgeId = std::uint32_t;
using EdgeId = std::uint32_t;
using FaceId = std::uint32_t;
using PrimitiveId = std::uint64_t;  // same id space as core/scene/project.h's Id
constexpr std::uint32_t kNoElement = 0xffffffffu;
constexpr FaceId kNoFace = kNoElement;

// Largest number of shape parameters a primitive has (core/mesh/primitives.h).
constexpr int kMaxPrimitiveParams = 4;
using PrimitiveParams = Eigen::Matrix<double, kMaxPrimitiveParams, 1>;
// Local position as a linear function of the parameters: p_in_primitive = C * params.
using ParamCoefficients = Eigen::Matrix<double, 3, kMaxPrimitiveParams>;

// A vertex position in primitive-local coordinates (the paper's section 3.2, after Facade):
// p_in_primitive = ((1 - t) * a + t * b) * params. A primitive corner has a == b, t == 0; a
// vertex made by E_split on an edge stores its endpoints' definitions (collapsed to their
// coefficients, by value, so later deletions cannot dangle) and t, so it stays on that
// edge at the same t whatever the primitive's dimensions become.
// A free vertex (the issue-5 solve's "free vertices", e.g. a split vertex pinned to a roof
// ridge above its edge) adds a local offset that the solve estimates:
// p_in_primitive = Collapsed() * params + offset. For a vertex that is not free the offset is
// fixed: zero for primitive corners, the push/pull displacement for extruded vertices
// (core/mesh/extrude.h), so the vertex follows its definition exactly.
struct LocalDefinition {
  ParamCoefficients a = ParamCoefficients::Zero();
  ParamCoefficients b = ParamCoefficients::Zero();
  double t = 0.0;
  bool on_edge = false;                              // true for a vertex created by E_split
  bool free = false;                                 // the solve may move it off its definition through `offset`
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();  // primitive-local units

  ParamCoefficients Collapsed() const { return (1.0 - t) * a + t * b; }
  Eigen::Vector3d LocalPosition(const PrimitiveParams& params) const { return Collapsed() * params + offset; }
  static LocalDefinition Corner(const ParamCoefficients& c) {
    LocalDefinition d;
    d.a = c;
    d.b = c;
    return d;
  }
};

struct MeshVertex {
  bool alive = false;
  HalfedgeId halfedge = kNoElement;  // one outgoing half-edge
  PrimitiveId primitive = 0;
  LocalDefinition local;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // world, cached from local and pose

  Eigen::Vector3d LocalPosition(const PrimitiveParams& params) const { return local.LocalPosition(params); }
};

struct MeshHalfedge {
  bool alive = false;
  VertexId origin = kNoElement;
  HalfedgeId next = kNoElement;
  HalfedgeId prev = kNoElement;
  FaceId face = kNoFace;                         // kNoFace on the boundary
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();  // corner attribute at origin in face
};

struct MeshFace {
  bool alive = false;
  HalfedgeId halfedge = kNoElement;  // any half-edge of the face's loop
  PrimitiveId primitive = 0;
  int material = 0;
};

class PolyMesh {
 public:
  // Element access by id; the id must have been handed out (asserted in debug builds). A
  // dead element's record stays readable until its id is revived.
  const MeshVertex& vertex(VertexId v) const { return assert(v < vertices_.size()), vertices_[v]; }
  const MeshHalfedge& halfedge(HalfedgeId h) const { return assert(h < halfedges_.size()), halfedges_[h]; }
  const MeshFace& face(FaceId f) const { return assert(f < faces_.size()), faces_[f]; }
  MeshVertex& vertex(VertexId v) { return assert(v < vertices_.size()), vertices_[v]; }
  MeshHalfedge& halfedge(HalfedgeId h) { return assert(h < halfedges_.size()), halfedges_[h]; }
  MeshFace& face(FaceId f) { return assert(f < faces_.size()), faces_[f]; }

  bool IsVertex(VertexId v) const { return v < vertices_.size() && vertices_[v].alive; }
  bool IsHalfedge(HalfedgeId h) const { return h < halfedges_.size() && halfedges_[h].alive; }
  bool IsEdge(EdgeId e) const { return IsHalfedge(2 * e); }
  bool IsFace(FaceId f) const { return f < faces_.size() && faces_[f].alive; }

  static HalfedgeId Twin(HalfedgeId h) { return h ^ 1u; }
  static EdgeId EdgeOf(HalfedgeId h) { return h / 2; }
  static HalfedgeId EdgeHalfedge(EdgeId e, int side) { return 2 * e + side; }
  HalfedgeId Next(HalfedgeId h) const { return halfedges_[h].next; }
  HalfedgeId Prev(HalfedgeId h) const { return halfedges_[h].prev; }
  VertexId Origin(HalfedgeId h) const { return halfedges_[h].origin; }
  VertexId Dest(HalfedgeId h) const { return halfedges_[Twin(h)].origin; }
  FaceId Face(HalfedgeId h) const { return halfedges_[h].face; }
  bool IsBoundary(HalfedgeId h) const { return halfedges_[h].face == kNoFace; }

  // Live element counts.
  int NumVertices() const { return num_vertices_; }
  int NumEdges() const { return num_edges_; }
  int NumFaces() const { return num_faces_; }
  // One past the largest id ever handed out: iterate ids in [0, End) and skip dead ones.
  std::uint32_t VertexIdEnd() const { return static_cast<std::uint32_t>(vertices_.size()); }
  std::uint32_t EdgeIdEnd() const { return static_cast<std::uint32_t>(halfedges_.size() / 2); }
  std::uint32_t FaceIdEnd() const { return static_cast<std::uint32_t>(faces_.size()); }

  // Allocation. New* hands out a fresh id; Revive* brings a dead id back (for undo).
  VertexId NewVertex();
  EdgeId NewEdge();
  FaceId NewFace();
  void ReviveVertex(VertexId v);
  void ReviveEdge(EdgeId e);
  void ReviveFace(FaceId f);
  // Extends the id space with dead slots up to the given ends (never shrinks): for readers
  // that restore a mesh with its ids, holes included.
  void GrowIdSpace(std::uint32_t vertex_end, std::uint32_t edge_end, std::uint32_t face_end);
  void KillVertex(VertexId v);
  void KillEdge(EdgeId e);
  void KillFace(FaceId f);

 private:
  std::vector<MeshVertex> vertices_;
  std::vector<MeshHalfedge> halfedges_;
  std::vector<MeshFace> faces_;
  int num_vertices_ = 0;
  int num_edges_ = 0;
  int num_faces_ = 0;
};

bool operator==(const PolyMesh& a, const PolyMesh& b);

// Builds the faces' half-edge loops from vertex-index polygons (counter-clockwise seen from
// outside). `vertex_ids` maps polygon indices to existing vertex ids; each polygon gives
// material `materials[i]` (or 0 if empty) and the primitive id. Edges are matched by their
// endpoints; unmatched sides become boundary half-edges linked into boundary loops.
// Returns the new face ids in polygon order, or an empty vector (mesh unchanged) and a
// message if the polygons are not an oriented manifold.
std::vector<FaceId> AddPolygons(PolyMesh* mesh, const std::vector<VertexId>& vertex_ids,
                                const std::vector<std::vector<int>>& polygons, const std::vector<int>& materials,
                                PrimitiveId primitive, std::string* message);

// Number of vertices (= half-edges) in a face loop.
int FaceDegree(const PolyMesh& mesh, FaceId f);
// The face's vertices in loop order starting at face.halfedge's origin.
std::vector<VertexId> FaceVertices(const PolyMesh& mesh, FaceId f);
// The face's half-edges (corners) in loop order starting at face.halfedge.
std::vector<HalfedgeId> FaceHalfedges(const PolyMesh& mesh, FaceId f);
// Number of edges at a vertex.
int VertexDegree(const PolyMesh& mesh, VertexId v);
// The half-edge from a to b, or kNoElement.
HalfedgeId FindHalfedge(const PolyMesh& mesh, VertexId a, VertexId b);

// V - E + F over live elements (2 per closed genus-0 component, 1 per disc).
int EulerCharacteristic(const PolyMesh& mesh);

// Area-weighted (Newell) normal of a face in world, unit length; zero for a degenerate face.
Eigen::Vector3d FaceNormal(const PolyMesh& mesh, FaceId f);

// Everything structurally wrong with the mesh, one human-readable line each (dangling twin,
// next/prev inconsistency, face with fewer than 3 vertices, face loop that does not close,
// inconsistent orientation, non-manifold edge or vertex, dead references). Empty if valid.
std::vector<std::string> Validate(const PolyMesh& mesh);

}  // namespace facet
