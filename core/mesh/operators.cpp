#include "core/mesh/operators.h"

#include <algorithm>
#include <cmath>

namespace facet {

namespace {

using M = PolyMesh;

// Copies each touched element's record once, before the operator modifies it.
class Recorder {
 public:
  Recorder(const PolyMesh& mesh, MeshUndo* undo) : mesh_(mesh), undo_(undo) {}
  void Vertex(VertexId v) {
    if (!Has(undo_->vertices, v)) undo_->vertices.emplace_back(v, mesh_.vertex(v));
  }
  void Halfedge(HalfedgeId h) {
    if (!Has(undo_->halfedges, h)) undo_->halfedges.emplace_back(h, mesh_.halfedge(h));
  }
  void Face(FaceId f) {
    if (f != kNoFace && !Has(undo_->faces, f)) undo_->faces.emplace_back(f, mesh_.face(f));
  }

 private:
  template <typename T>
  static bool Has(const std::vector<std::pair<std::uint32_t, T>>& records, std::uint32_t id) {
    return std::any_of(records.begin(), records.end(), [id](const auto& r) { return r.first == id; });
  }
  const PolyMesh& mesh_;
  MeshUndo* undo_;
};

VertexId AllocVertex(PolyMesh* mesh, VertexId reuse) {
  if (reuse == kNoElement) return mesh->NewVertex();
  mesh->ReviveVertex(reuse);
  return reuse;
}
EdgeId AllocEdge(PolyMesh* mesh, EdgeId reuse) {
  if (reuse == kNoElement) return mesh->NewEdge();
  mesh->ReviveEdge(reuse);
  return reuse;
}
FaceId AllocFace(PolyMesh* mesh, FaceId reuse) {
  if (reuse == kNoElement) return mesh->NewFace();
  mesh->ReviveFace(reuse);
  return reuse;
}

// The half-edge of face f leaving vertex v, or kNoElement.
HalfedgeId CornerOf(const PolyMesh& mesh, FaceId f, VertexId v) {
  const HalfedgeId start = mesh.face(f).halfedge;
  HalfedgeId h = start;
  do {
    if (mesh.Origin(h) == v) return h;
    h = mesh.Next(h);
  } while (h != start);
  return kNoElement;
}

// Splits half-edge h0 (a -> b) at t: h0 becomes a -> m, its twin m -> a, and the new edge's
// half-edges run m -> b (in h0's face) and b -> m (in the twin's face).
ESplitResult SplitHalfedge(PolyMesh* mesh, HalfedgeId h0, double t, VertexId reuse_vertex, EdgeId reuse_edge) {
  ESplitResult r;
  const HalfedgeId h1 = M::Twin(h0);
  const VertexId a = mesh->Origin(h0), b = mesh->Origin(h1);
  const HalfedgeId n0 = mesh->Next(h0), p1 = mesh->Prev(h1), nh1 = mesh->Next(h1);
  Recorder record(*mesh, &r.undo);
  record.Halfedge(h0);
  record.Halfedge(h1);
  record.Halfedge(n0);
  record.Halfedge(p1);
  record.Vertex(b);

  const Eigen::Vector2d uv_g0 = (1.0 - t) * mesh->halfedge(h0).uv + t * mesh->halfedge(n0).uv;
  const Eigen::Vector2d uv_h1 = (1.0 - t) * mesh->halfedge(nh1).uv + t * mesh->halfedge(h1).uv;
  const Eigen::Vector2d uv_g1 = mesh->halfedge(h1).uv;

  const VertexId m = AllocVertex(mesh, reuse_vertex);
  const EdgeId n = AllocEdge(mesh, reuse_edge);
  const HalfedgeId g0 = M::EdgeHalfedge(n, 0), g1 = M::EdgeHalfedge(n, 1);
  {
    const MeshVertex& va = mesh->vertex(a);
    const MeshVertex& vb = mesh->vertex(b);
    MeshVertex& vm = mesh->vertex(m);
    vm.halfedge = g0;
    vm.primitive = va.primitive;
    vm.local.a = va.local.Collapsed();
    vm.local.b = vb.local.Collapsed();
    vm.local.t = t;
    vm.local.on_edge = true;
    // Free endpoints keep their current offsets here; the new vertex does not follow later
    // changes of them (it is not free itself).
    vm.local.offset = (1.0 - t) * va.local.offset + t * vb.local.offset;
    vm.position = (1.0 - t) * va.position + t * vb.position;
  }
  MeshHalfedge& e0 = mesh->halfedge(g0);
  e0.origin = m;
  e0.face = mesh->Face(h0);
  e0.uv = uv_g0;
  e0.next = n0;
  e0.prev = h0;
  mesh->halfedge(h0).next = g0;
  mesh->halfedge(n0).prev = g0;

  MeshHalfedge& e1 = mesh->halfedge(g1);
  e1.origin = b;
  e1.face = mesh->Face(h1);
  e1.uv = uv_g1;
  e1.next = h1;
  e1.prev = p1;
  mesh->halfedge(p1).next = g1;
  mesh->halfedge(h1).prev = g1;
  mesh->halfedge(h1).origin = m;
  mesh->halfedge(h1).uv = uv_h1;
  if (mesh->vertex(b).halfedge == h1) mesh->vertex(b).halfedge = g1;

  r.ok = true;
  r.vertex = m;
  r.new_edge = n;
  r.undo.created_vertices.push_back(m);
  r.undo.created_edges.push_back(n);
  return r;
}

// Splits face f by a new edge v1 -> v2 (half-edge 2e); new_face_side says which new
// half-edge's loop becomes the new face (-1: the loop without face.halfedge).
VConnectResult ConnectVertices(PolyMesh* mesh, FaceId f, VertexId v1, VertexId v2, EdgeId reuse_edge, FaceId reuse_face,
                               int new_face_side) {
  VConnectResult r;
  const HalfedgeId h1 = CornerOf(*mesh, f, v1), h2 = CornerOf(*mesh, f, v2);
  const HalfedgeId p1 = mesh->Prev(h1), p2 = mesh->Prev(h2);
  // Loop B (n1 side) is n1, h1, ..., p2; loop A (n0 side) is n0, h2, ..., p1.
  std::vector<HalfedgeId> loop_a, loop_b;
  for (HalfedgeId h = h2; h != h1; h = mesh->Next(h)) loop_a.push_back(h);
  for (HalfedgeId h = h1; h != h2; h = mesh->Next(h)) loop_b.push_back(h);
  if (new_face_side < 0) {
    const HalfedgeId keep = mesh->face(f).halfedge;
    new_face_side = std::find(loop_b.begin(), loop_b.end(), keep) != loop_b.end() ? 0 : 1;
  }
  const std::vector<HalfedgeId>& moved = new_face_side == 0 ? loop_a : loop_b;

  Recorder record(*mesh, &r.undo);
  record.Halfedge(h1);
  record.Halfedge(h2);
  record.Halfedge(p1);
  record.Halfedge(p2);
  for (HalfedgeId h : moved) record.Halfedge(h);
  record.Face(f);

  const EdgeId e = AllocEdge(mesh, reuse_edge);
  const FaceId g = AllocFace(mesh, reuse_face);
  const HalfedgeId n0 = M::EdgeHalfedge(e, 0), n1 = M::EdgeHalfedge(e, 1);
  MeshHalfedge& e0 = mesh->halfedge(n0);
  e0.origin = v1;
  e0.uv = mesh->halfedge(h1).uv;
  e0.next = h2;
  e0.prev = p1;
  MeshHalfedge& e1 = mesh->halfedge(n1);
  e1.origin = v2;
  e1.uv = mesh->halfedge(h2).uv;
  e1.next = h1;
  e1.prev = p2;
  mesh->halfedge(p1).next = n0;
  mesh->halfedge(h2).prev = n0;
  mesh->halfedge(p2).next = n1;
  mesh->halfedge(h1).prev = n1;
  mesh->halfedge(n0).face = new_face_side == 0 ? g : f;
  mesh->halfedge(n1).face = new_face_side == 0 ? f : g;
  for (HalfedgeId h : moved) mesh->halfedge(h).face = g;
  MeshFace& face_g = mesh->face(g);
  face_g.halfedge = new_face_side == 0 ? n0 : n1;
  face_g.primitive = mesh->face(f).primitive;
  face_g.material = mesh->face(f).material;

  r.ok = true;
  r.edge = e;
  r.new_face = g;
  r.undo.created_edges.push_back(e);
  r.undo.created_faces.push_back(g);
  return r;
}

}  // namespace

void ApplyUndo(PolyMesh* mesh, const MeshUndo& undo) {
  for (FaceId f : undo.created_faces) {
    if (mesh->IsFace(f)) mesh->KillFace(f);
  }
  for (EdgeId e : undo.created_edges) {
    if (mesh->IsEdge(e)) mesh->KillEdge(e);
  }
  for (VertexId v : undo.created_vertices) {
    if (mesh->IsVertex(v)) mesh->KillVertex(v);
  }
  for (const auto& [v, record] : undo.vertices) {
    if (!mesh->IsVertex(v)) mesh->ReviveVertex(v);
    mesh->vertex(v) = record;
  }
  for (const auto& [h, record] : undo.halfedges) {
    if (!mesh->IsHalfedge(h)) mesh->ReviveEdge(M::EdgeOf(h));
    mesh->halfedge(h) = record;
  }
  for (const auto& [f, record] : undo.faces) {
    if (!mesh->IsFace(f)) mesh->ReviveFace(f);
    mesh->face(f) = record;
  }
}

ESplitResult ESplit(PolyMesh* mesh, EdgeId edge, double t) {
  ESplitResult r;
  if (!mesh->IsEdge(edge)) {
    r.message = "E_split: edge " + std::to_string(edge) + " does not exist";
    return r;
  }
  if (!(t > 0.0 && t < 1.0)) {
    r.message = "E_split: t must lie strictly between 0 and 1 (got " + std::to_string(t) + ")";
    return r;
  }
  return SplitHalfedge(mesh, M::EdgeHalfedge(edge, 0), t, kNoElement, kNoElement);
}

VDeleteResult VDelete(PolyMesh* mesh, VertexId m) {
  VDeleteResult r;
  const std::string name = "V_delete: vertex " + std::to_string(m);
  if (!mesh->IsVertex(m)) {
    r.message = name + " does not exist";
    return r;
  }
  if (!mesh->vertex(m).local.on_edge) {
    r.message = name + " is a corner of its primitive, not a vertex added by E_split";
    return r;
  }
  const int degree = VertexDegree(*mesh, m);
  if (degree != 2) {
    r.message = name + " has " + std::to_string(degree) + " edges; only a vertex with 2 can be deleted";
    return r;
  }
  const HalfedgeId o1 = mesh->vertex(m).halfedge;
  const HalfedgeId o2 = mesh->Next(M::Twin(o1));
  const bool remove_first = M::EdgeOf(o1) > M::EdgeOf(o2);
  const HalfedgeId ro = remove_first ? o1 : o2, ko = remove_first ? o2 : o1;
  const HalfedgeId ri = M::Twin(ro), ki = M::Twin(ko);
  const VertexId x = mesh->Dest(ro), y = mesh->Dest(ko);
  if (x == y) {
    r.message = name + ": both its edges lead to the same vertex";
    return r;
  }
  if (FindHalfedge(*mesh, x, y) != kNoElement) {
    r.message =
        name + ": its neighbours " + std::to_string(x) + " and " + std::to_string(y) + " are already joined by an edge";
    return r;
  }
  for (HalfedgeId h : {ro, ri}) {
    const FaceId f = mesh->Face(h);
    if (f != kNoFace && FaceDegree(*mesh, f) <= 3) {
      r.message = name + " belongs to triangle " + std::to_string(f) + ", which would keep only 2 vertices";
      return r;
    }
  }
  const HalfedgeId next_ro = mesh->Next(ro), prev_ri = mesh->Prev(ri);
  Recorder record(*mesh, &r.undo);
  record.Vertex(m);
  record.Vertex(x);
  for (HalfedgeId h : {ro, ri, ko, ki, next_ro, prev_ri}) record.Halfedge(h);
  record.Face(mesh->Face(ro));
  record.Face(mesh->Face(ri));

  mesh->halfedge(ki).next = next_ro;
  mesh->halfedge(next_ro).prev = ki;
  mesh->halfedge(prev_ri).next = ko;
  mesh->halfedge(ko).prev = prev_ri;
  mesh->halfedge(ko).origin = x;
  mesh->halfedge(ko).uv = mesh->halfedge(ri).uv;
  if (mesh->vertex(x).halfedge == ri) mesh->vertex(x).halfedge = ko;
  const FaceId f_ro = mesh->Face(ro), f_ri = mesh->Face(ri);
  if (f_ro != kNoFace && mesh->face(f_ro).halfedge == ro) mesh->face(f_ro).halfedge = ki;
  if (f_ri != kNoFace && mesh->face(f_ri).halfedge == ri) mesh->face(f_ri).halfedge = ko;

  r.ok = true;
  r.vertex = m;
  r.removed_edge = M::EdgeOf(ro);
  r.kept_edge = M::EdgeOf(ko);
  r.kept_halfedge = ki;
  r.t = mesh->vertex(m).local.t;
  mesh->KillEdge(r.removed_edge);
  mesh->KillVertex(m);
  return r;
}

VConnectResult VConnect(PolyMesh* mesh, FaceId face, VertexId v1, VertexId v2) {
  VConnectResult r;
  const std::string name = "V_connect: ";
  if (!mesh->IsFace(face)) {
    r.message = name + "face " + std::to_string(face) + " does not exist";
    return r;
  }
  if (!mesh->IsVertex(v1) || !mesh->IsVertex(v2)) {
    r.message = name + "vertex " + std::to_string(mesh->IsVertex(v1) ? v2 : v1) + " does not exist";
    return r;
  }
  if (v1 == v2) {
    r.message = name + "an edge from vertex " + std::to_string(v1) + " to itself would be a self-loop";
    return r;
  }
  const HalfedgeId h1 = CornerOf(*mesh, face, v1), h2 = CornerOf(*mesh, face, v2);
  if (h1 == kNoElement || h2 == kNoElement) {
    r.message = name + "vertex " + std::to_string(h1 == kNoElement ? v1 : v2) + " is not on face " +
                std::to_string(face) + ": both vertices must belong to the same face";
    return r;
  }
  if (mesh->Dest(h1) == v2 || mesh->Dest(h2) == v1) {
    r.message = name + "vertices " + std::to_string(v1) + " and " + std::to_string(v2) + " are adjacent on face " +
                std::to_string(face) + ": the edge exists already";
    return r;
  }
  if (FindHalfedge(*mesh, v1, v2) != kNoElement) {
    r.message = name + "vertices " + std::to_string(v1) + " and " + std::to_string(v2) +
                " are already joined by an edge of another face";
    return r;
  }
  return ConnectVertices(mesh, face, v1, v2, kNoElement, kNoElement, -1);
}

EDeleteResult EDelete(PolyMesh* mesh, EdgeId edge) {
  EDeleteResult r;
  const std::string name = "E_delete: edge " + std::to_string(edge);
  if (!mesh->IsEdge(edge)) {
    r.message = name + " does not exist";
    return r;
  }
  const HalfedgeId h0 = M::EdgeHalfedge(edge, 0), h1 = M::EdgeHalfedge(edge, 1);
  const FaceId fa = mesh->Face(h0), fb = mesh->Face(h1);
  if (fa == kNoFace || fb == kNoFace) {
    r.message = name + " lies on the boundary: there is no second face to merge with";
    return r;
  }
  if (fa == fb) {
    r.message = name + " has face " + std::to_string(fa) + " on both sides";
    return r;
  }
  const VertexId a = mesh->Origin(h0), b = mesh->Origin(h1);
  for (VertexId v : {a, b}) {
    if (VertexDegree(*mesh, v) <= 2) {
      r.message = name + ": its vertex " + std::to_string(v) + " would be left with a single edge";
      return r;
    }
  }
  std::vector<VertexId> va = FaceVertices(*mesh, fa), vb = FaceVertices(*mesh, fb);
  std::sort(va.begin(), va.end());
  std::sort(vb.begin(), vb.end());
  std::vector<VertexId> shared;
  std::set_intersection(va.begin(), va.end(), vb.begin(), vb.end(), std::back_inserter(shared));
  if (shared.size() != 2) {
    r.message = name + ": faces " + std::to_string(fa) + " and " + std::to_string(fb) +
                " share more than this edge; merging them would not give a simple polygon";
    return r;
  }
  const FaceId keep = std::min(fa, fb), removed = std::max(fa, fb);
  const HalfedgeId ph0 = mesh->Prev(h0), nh0 = mesh->Next(h0), ph1 = mesh->Prev(h1), nh1 = mesh->Next(h1);
  const std::vector<HalfedgeId> moved = FaceHalfedges(*mesh, removed);
  Recorder record(*mesh, &r.undo);
  for (HalfedgeId h : {h0, h1, ph0, nh0, ph1, nh1}) record.Halfedge(h);
  for (HalfedgeId h : moved) record.Halfedge(h);
  record.Vertex(a);
  record.Vertex(b);
  record.Face(fa);
  record.Face(fb);

  mesh->halfedge(ph0).next = nh1;
  mesh->halfedge(nh1).prev = ph0;
  mesh->halfedge(ph1).next = nh0;
  mesh->halfedge(nh0).prev = ph1;
  for (HalfedgeId h : moved) mesh->halfedge(h).face = keep;
  if (mesh->face(keep).halfedge == h0) mesh->face(keep).halfedge = nh0;
  if (mesh->face(keep).halfedge == h1) mesh->face(keep).halfedge = nh1;
  if (mesh->vertex(a).halfedge == h0) mesh->vertex(a).halfedge = nh1;
  if (mesh->vertex(b).halfedge == h1) mesh->vertex(b).halfedge = nh0;
  mesh->KillEdge(edge);
  mesh->KillFace(removed);

  r.ok = true;
  r.edge = edge;
  r.kept_face = keep;
  r.removed_face = removed;
  r.removed_side = removed == fa ? 0 : 1;
  r.v1 = a;
  r.v2 = b;
  return r;
}

VDeleteResult UndoESplit(PolyMesh* mesh, const ESplitResult& split) { return VDelete(mesh, split.vertex); }

ESplitResult UndoVDelete(PolyMesh* mesh, const VDeleteResult& deleted) {
  if (!deleted.ok) {
    ESplitResult r;
    r.message = "E_split: nothing to undo, the V_delete had failed";
    return r;
  }
  // Re-create the removed elements under their old ids, then put back every recorded field
  // (the structural split already matches them when the vertex came from that very split).
  ESplitResult r = SplitHalfedge(mesh, deleted.kept_halfedge, deleted.t, deleted.vertex, deleted.removed_edge);
  ApplyUndo(mesh, MeshUndo{deleted.undo.vertices, deleted.undo.halfedges, deleted.undo.faces, {}, {}, {}});
  return r;
}

EDeleteResult UndoVConnect(PolyMesh* mesh, const VConnectResult& connect) { return EDelete(mesh, connect.edge); }

VConnectResult UndoEDelete(PolyMesh* mesh, const EDeleteResult& deleted) {
  if (!deleted.ok) {
    VConnectResult r;
    r.message = "V_connect: nothing to undo, the E_delete had failed";
    return r;
  }
  VConnectResult r = ConnectVertices(mesh, deleted.kept_face, deleted.v1, deleted.v2, deleted.edge,
                                     deleted.removed_face, deleted.removed_side);
  ApplyUndo(mesh, MeshUndo{deleted.undo.vertices, deleted.undo.halfedges, deleted.undo.faces, {}, {}, {}});
  return r;
}

}  // namespace facet
