#include "core/mesh/extrude.h"

#include <algorithm>
#include <cmath>

#include "core/geometry/camera.h"

namespace facet {

namespace {

// Vertices farther than this from the face's plane, relative to the face's size, make it
// non-planar: K-ops and primitives give planar faces up to rounding (~1e-16), so anything
// above is a face bent on purpose (e.g. a free vertex moved off its plane).
constexpr double kPlanarityTolerance = 1e-9;
constexpr double kDegenerateArea = 1e-12;

std::string FaceName(FaceId f) { return "extrude: face " + std::to_string(f); }

Eigen::Vector3d WorldOf(const PrimitiveShape& shape, const Eigen::Matrix3d& world_from_primitive,
                        const MeshVertex& vertex) {
  return world_from_primitive * vertex.LocalPosition(shape.params) + shape.translation;
}

// Corner UVs of side face i, in primitive-local units: u along the base edge, v along the
// extrusion (its length is |distance| whichever way the face was pushed).
void SetSideUvs(PolyMesh* mesh, const ExtrudeResult& x, size_t i, double base_length) {
  const size_t n = x.base_vertices.size();
  const double height = std::abs(x.distance);
  const HalfedgeId base = mesh->Next(PolyMesh::EdgeHalfedge(x.side_edges[i], 1));  // v_i -> v_{i+1}
  mesh->halfedge(base).uv = Eigen::Vector2d(0.0, 0.0);
  mesh->halfedge(PolyMesh::EdgeHalfedge(x.side_edges[(i + 1) % n], 0)).uv = Eigen::Vector2d(base_length, 0.0);
  mesh->halfedge(PolyMesh::EdgeHalfedge(x.cap_edges[i], 1)).uv = Eigen::Vector2d(base_length, height);
  mesh->halfedge(PolyMesh::EdgeHalfedge(x.side_edges[i], 1)).uv = Eigen::Vector2d(0.0, height);
}

double BaseLength(const PolyMesh& mesh, const PrimitiveShape& shape, const ExtrudeResult& x, size_t i) {
  const size_t n = x.base_vertices.size();
  return (mesh.vertex(x.base_vertices[(i + 1) % n]).LocalPosition(shape.params) -
          mesh.vertex(x.base_vertices[i]).LocalPosition(shape.params))
      .norm();
}

// True when the elements the extrusion created are alive and still form its ring: each new
// vertex has its three edges (side, two cap) and the face runs through the cap edges.
bool RingIntact(const PolyMesh& mesh, const ExtrudeResult& x, std::string* why) {
  const size_t n = x.base_vertices.size();
  if (n < 3 || x.new_vertices.size() != n || x.side_edges.size() != n || x.cap_edges.size() != n ||
      x.side_faces.size() != n || x.base_offsets.size() != n) {
    *why = "the extrusion record is incomplete";
    return false;
  }
  if (!mesh.IsFace(x.face)) {
    *why = "face " + std::to_string(x.face) + " no longer exists";
    return false;
  }
  for (size_t i = 0; i < n; ++i) {
    const size_t i1 = (i + 1) % n;
    if (!mesh.IsVertex(x.new_vertices[i]) || !mesh.IsVertex(x.base_vertices[i]) || !mesh.IsEdge(x.side_edges[i]) ||
        !mesh.IsEdge(x.cap_edges[i]) || !mesh.IsFace(x.side_faces[i])) {
      *why = "an element it created or extruded from no longer exists";
      return false;
    }
    const HalfedgeId up = PolyMesh::EdgeHalfedge(x.side_edges[i], 0);
    const HalfedgeId cap = PolyMesh::EdgeHalfedge(x.cap_edges[i], 0);
    if (mesh.Origin(up) != x.base_vertices[i] || mesh.Dest(up) != x.new_vertices[i] ||
        mesh.Origin(cap) != x.new_vertices[i] || mesh.Dest(cap) != x.new_vertices[i1] || mesh.Face(cap) != x.face ||
        mesh.Face(PolyMesh::Twin(cap)) != x.side_faces[i] || FaceDegree(mesh, x.side_faces[i]) != 4 ||
        VertexDegree(mesh, x.new_vertices[i]) != 3) {
      *why = "the mesh around it was edited since (its ring of side faces changed)";
      return false;
    }
  }
  if (FaceDegree(mesh, x.face) != static_cast<int>(n)) {
    *why = "face " + std::to_string(x.face) + " was edited since";
    return false;
  }
  return true;
}

// A face's corners in its primitive's frame, with its centroid and unit normal.
struct FacePlane {
  std::vector<Eigen::Vector3d> local;
  Eigen::Vector3d centroid;
  Eigen::Vector3d normal;
};

// False (message says why) when the face is degenerate or not planar.
bool MeasurePlanarFace(const PolyMesh& mesh, const PrimitiveShape& shape, const std::vector<HalfedgeId>& loop,
                       const std::string& name, FacePlane* plane, std::string* message) {
  const size_t n = loop.size();
  std::vector<Eigen::Vector3d>& local = plane->local;
  local.resize(n);
  Eigen::Vector3d& centroid = plane->centroid;
  centroid.setZero();
  for (size_t i = 0; i < n; ++i) {
    local[i] = mesh.vertex(mesh.Origin(loop[i])).LocalPosition(shape.params);
    centroid += local[i];
  }
  centroid /= static_cast<double>(n);
  // Newell's normal about the centroid: exact for planar faces, robust far from the origin.
  Eigen::Vector3d& normal = plane->normal;
  normal.setZero();
  double size = 0.0;
  for (size_t i = 0; i < n; ++i) {
    normal += (local[i] - centroid).cross(local[(i + 1) % n] - centroid);
    size = std::max(size, (local[i] - centroid).norm());
  }
  // Twice the area against the size squared: a sliver (e.g. V_connect between the two ends of
  // a split edge) has an area of rounding noise and no meaningful normal.
  if (!(size > 0.0) || !(normal.norm() > kDegenerateArea * size * size)) {
    *message = name + " is degenerate (no area)";
    return false;
  }
  normal.normalize();
  double off_plane = 0.0;
  for (size_t i = 0; i < n; ++i) off_plane = std::max(off_plane, std::abs((local[i] - centroid).dot(normal)));
  if (off_plane > kPlanarityTolerance * size) {
    *message = name + " is not planar (a vertex lies " + std::to_string(off_plane / size) +
               " of its size off its plane); only a planar face can be pushed or pulled";
    return false;
  }
  return true;
}

// The new vertices (each base vertex moved by distance along the normal), edges and side faces;
// their connectivity is LinkExtrusion's.
void CreateExtrudedElements(PolyMesh* mesh, const PrimitiveShape& shape, const std::vector<HalfedgeId>& loop,
                            const Eigen::Vector3d& normal, double distance, ExtrudeResult* r) {
  const size_t n = loop.size();
  const Eigen::Matrix3d world_from_primitive = RotationFromAngleAxis(shape.rotation);
  for (size_t i = 0; i < n; ++i) {
    const VertexId v = mesh->Origin(loop[i]);
    const MeshVertex base = mesh->vertex(v);
    const VertexId w = mesh->NewVertex();
    MeshVertex& vw = mesh->vertex(w);
    vw.primitive = base.primitive;
    vw.local = base.local;
    // The new vertex is a corner of the extruded solid: not on an edge (V_delete refuses it)
    // and not free (the offset is the user's distance, not a solve unknown).
    vw.local.on_edge = false;
    vw.local.free = false;
    vw.local.offset = base.local.offset + normal * distance;
    vw.position = WorldOf(shape, world_from_primitive, vw);
    r->base_vertices.push_back(v);
    r->new_vertices.push_back(w);
    r->base_offsets.push_back(base.local.offset);
  }
  for (size_t i = 0; i < n; ++i) r->side_edges.push_back(mesh->NewEdge());
  for (size_t i = 0; i < n; ++i) r->cap_edges.push_back(mesh->NewEdge());
  for (size_t i = 0; i < n; ++i) r->side_faces.push_back(mesh->NewFace());
}

// Links the new elements: the face moves to the cap ring, each base edge now bounds side face i.
void LinkExtrusion(PolyMesh* mesh, const std::vector<HalfedgeId>& loop, FaceId face, const MeshFace& face_before,
                   const ExtrudeResult& r) {
  const size_t n = loop.size();
  size_t first_corner = 0;
  for (size_t i = 0; i < n; ++i) {
    if (loop[i] == face_before.halfedge) first_corner = i;
  }
  for (size_t i = 0; i < n; ++i) {
    const size_t i1 = (i + 1) % n, im = (i + n - 1) % n;
    const HalfedgeId base = loop[i];
    const HalfedgeId up = PolyMesh::EdgeHalfedge(r.side_edges[i], 0);     // v_i -> w_i, in side i-1
    const HalfedgeId down = PolyMesh::EdgeHalfedge(r.side_edges[i], 1);   // w_i -> v_i, in side i
    const HalfedgeId up1 = PolyMesh::EdgeHalfedge(r.side_edges[i1], 0);   // v_{i+1} -> w_{i+1}, in side i
    const HalfedgeId cap = PolyMesh::EdgeHalfedge(r.cap_edges[i], 0);     // w_i -> w_{i+1}, in face
    const HalfedgeId cap_in = PolyMesh::EdgeHalfedge(r.cap_edges[i], 1);  // w_{i+1} -> w_i, in side i
    const HalfedgeId cap_prev = PolyMesh::EdgeHalfedge(r.cap_edges[im], 0);
    const HalfedgeId cap_next = PolyMesh::EdgeHalfedge(r.cap_edges[i1], 0);
    const FaceId side = r.side_faces[i];

    MeshHalfedge& hc = mesh->halfedge(cap);
    hc.origin = r.new_vertices[i];
    hc.face = face;
    hc.next = cap_next;
    hc.prev = cap_prev;
    hc.uv = mesh->halfedge(base).uv;  // the face's corner i keeps its UV

    MeshHalfedge& hu = mesh->halfedge(up);
    hu.origin = r.base_vertices[i];
    hu.face = r.side_faces[im];
    hu.next = PolyMesh::EdgeHalfedge(r.cap_edges[im], 1);
    hu.prev = loop[im];

    MeshHalfedge& hd = mesh->halfedge(down);
    hd.origin = r.new_vertices[i];
    hd.face = side;
    hd.next = base;
    hd.prev = cap_in;

    MeshHalfedge& hi = mesh->halfedge(cap_in);
    hi.origin = r.new_vertices[i1];
    hi.face = side;
    hi.next = down;
    hi.prev = up1;

    MeshHalfedge& hb = mesh->halfedge(base);
    hb.face = side;
    hb.next = up1;
    hb.prev = down;

    mesh->vertex(r.new_vertices[i]).halfedge = cap;
    MeshFace& fs = mesh->face(side);
    fs.halfedge = base;
    fs.primitive = face_before.primitive;
    fs.material = face_before.material;
  }
  mesh->face(face).halfedge = PolyMesh::EdgeHalfedge(r.cap_edges[first_corner], 0);
}

}  // namespace

ExtrudeResult ExtrudeFace(PolyMesh* mesh, const PrimitiveShape& shape, FaceId face, double distance) {
  ExtrudeResult r;
  const std::string name = FaceName(face);
  if (!mesh->IsFace(face)) {
    r.message = name + " does not exist";
    return r;
  }
  if (mesh->face(face).primitive != shape.id) {
    r.message = name + " belongs to primitive " + std::to_string(mesh->face(face).primitive) + ", not " +
                std::to_string(shape.id);
    return r;
  }
  if (!std::isfinite(distance) || distance == 0.0) {
    r.message = "extrude: the distance must be non-zero and finite (got " + std::to_string(distance) + ")";
    return r;
  }
  const std::vector<HalfedgeId> loop = FaceHalfedges(*mesh, face);
  const size_t n = loop.size();
  FacePlane plane;
  if (!MeasurePlanarFace(*mesh, shape, loop, name, &plane, &r.message)) return r;
  const std::vector<Eigen::Vector3d>& local = plane.local;
  const Eigen::Vector3d& normal = plane.normal;

  r.face = face;
  r.distance = distance;
  r.direction_in_primitive = normal;
  MeshUndo& undo = r.undo;
  const MeshFace face_before = mesh->face(face);
  undo.faces.emplace_back(face, face_before);
  for (HalfedgeId h : loop) undo.halfedges.emplace_back(h, mesh->halfedge(h));

  CreateExtrudedElements(mesh, shape, loop, normal, distance, &r);
  LinkExtrusion(mesh, loop, face, face_before, r);
  for (size_t i = 0; i < n; ++i) SetSideUvs(mesh, r, i, (local[(i + 1) % n] - local[i]).norm());

  undo.created_vertices = r.new_vertices;
  undo.created_edges = r.side_edges;
  undo.created_edges.insert(undo.created_edges.end(), r.cap_edges.begin(), r.cap_edges.end());
  undo.created_faces = r.side_faces;
  r.ok = true;
  return r;
}

bool UndoExtrudeFace(PolyMesh* mesh, const ExtrudeResult& extrusion, std::string* message) {
  std::string why;
  if (!extrusion.ok || !RingIntact(*mesh, extrusion, &why)) {
    if (message != nullptr) *message = "undo extrude: " + (extrusion.ok ? why : std::string("the extrusion failed"));
    return false;
  }
  ApplyUndo(mesh, extrusion.undo);
  return true;
}

ExtrusionDistanceResult SetExtrusionDistance(PolyMesh* mesh, const PrimitiveShape& shape, ExtrudeResult* extrusion,
                                             double distance) {
  ExtrusionDistanceResult r;
  r.previous_distance = extrusion->distance;
  if (!std::isfinite(distance) || distance == 0.0) {
    r.message = "push/pull: the distance must be non-zero and finite (got " + std::to_string(distance) + ")";
    return r;
  }
  std::string why;
  if (!extrusion->ok || !RingIntact(*mesh, *extrusion, &why)) {
    r.message = "push/pull: " + (extrusion->ok ? why : std::string("the extrusion failed"));
    return r;
  }
  const size_t n = extrusion->base_vertices.size();
  for (size_t i = 0; i < n; ++i) {
    const VertexId w = extrusion->new_vertices[i];
    r.undo.vertices.emplace_back(w, mesh->vertex(w));
    for (HalfedgeId h :
         {mesh->Next(PolyMesh::EdgeHalfedge(extrusion->side_edges[i], 1)),
          PolyMesh::EdgeHalfedge(extrusion->side_edges[(i + 1) % n], 0),
          PolyMesh::EdgeHalfedge(extrusion->cap_edges[i], 1), PolyMesh::EdgeHalfedge(extrusion->side_edges[i], 1)})
      r.undo.halfedges.emplace_back(h, mesh->halfedge(h));
  }
  extrusion->distance = distance;
  const Eigen::Matrix3d world_from_primitive = RotationFromAngleAxis(shape.rotation);
  for (size_t i = 0; i < n; ++i) {
    MeshVertex& w = mesh->vertex(extrusion->new_vertices[i]);
    w.local.offset = extrusion->base_offsets[i] + extrusion->direction_in_primitive * distance;
    w.position = WorldOf(shape, world_from_primitive, w);
  }
  for (size_t i = 0; i < n; ++i) SetSideUvs(mesh, *extrusion, i, BaseLength(*mesh, shape, *extrusion, i));
  r.ok = true;
  return r;
}

}  // namespace facet
