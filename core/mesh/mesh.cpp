#include "core/mesh/mesh.h"

#include <algorithm>
#include <cassert>
#include <map>
#include <sstream>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include <Eigen/Geometry>

namespace facet {

VertexId PolyMesh::NewVertex() {
  vertices_.emplace_back();
  vertices_.back().alive = true;
  ++num_vertices_;
  return static_cast<VertexId>(vertices_.size() - 1);
}

EdgeId PolyMesh::NewEdge() {
  halfedges_.emplace_back();
  halfedges_.emplace_back();
  halfedges_[halfedges_.size() - 2].alive = true;
  halfedges_.back().alive = true;
  ++num_edges_;
  return static_cast<EdgeId>(halfedges_.size() / 2 - 1);
}

FaceId PolyMesh::NewFace() {
  faces_.emplace_back();
  faces_.back().alive = true;
  ++num_faces_;
  return static_cast<FaceId>(faces_.size() - 1);
}

void PolyMesh::GrowIdSpace(std::uint32_t vertex_end, std::uint32_t edge_end, std::uint32_t face_end) {
  if (vertex_end > vertices_.size()) vertices_.resize(vertex_end);
  if (2 * static_cast<size_t>(edge_end) > halfedges_.size()) halfedges_.resize(2 * static_cast<size_t>(edge_end));
  if (face_end > faces_.size()) faces_.resize(face_end);
}

void PolyMesh::ReviveVertex(VertexId v) {
  assert(v < vertices_.size() && !vertices_[v].alive);
  vertices_[v] = MeshVertex();
  vertices_[v].alive = true;
  ++num_vertices_;
}

void PolyMesh::ReviveEdge(EdgeId e) {
  assert(2 * e + 1 < halfedges_.size() && !halfedges_[2 * e].alive);
  halfedges_[2 * e] = MeshHalfedge();
  halfedges_[2 * e + 1] = MeshHalfedge();
  halfedges_[2 * e].alive = true;
  halfedges_[2 * e + 1].alive = true;
  ++num_edges_;
}

void PolyMesh::ReviveFace(FaceId f) {
  assert(f < faces_.size() && !faces_[f].alive);
  faces_[f] = MeshFace();
  faces_[f].alive = true;
  ++num_faces_;
}

void PolyMesh::KillVertex(VertexId v) {
  assert(IsVertex(v));
  vertices_[v].alive = false;
  --num_vertices_;
}

void PolyMesh::KillEdge(EdgeId e) {
  assert(IsEdge(e));
  halfedges_[2 * e].alive = false;
  halfedges_[2 * e + 1].alive = false;
  --num_edges_;
}

void PolyMesh::KillFace(FaceId f) {
  assert(IsFace(f));
  faces_[f].alive = false;
  --num_faces_;
}

namespace {

bool SameVertex(const MeshVertex& a, const MeshVertex& b) {
  return a.halfedge == b.halfedge && a.primitive == b.primitive && a.local.a == b.local.a && a.local.b == b.local.b &&
         a.local.t == b.local.t && a.local.on_edge == b.local.on_edge && a.local.free == b.local.free &&
         a.local.offset == b.local.offset && a.position == b.position;
}

bool SameHalfedge(const MeshHalfedge& a, const MeshHalfedge& b) {
  return a.origin == b.origin && a.next == b.next && a.prev == b.prev && a.face == b.face && a.uv == b.uv;
}

bool SameFace(const MeshFace& a, const MeshFace& b) {
  return a.halfedge == b.halfedge && a.primitive == b.primitive && a.material == b.material;
}

}  // namespace

bool operator==(const PolyMesh& a, const PolyMesh& b) {
  if (a.NumVertices() != b.NumVertices() || a.NumEdges() != b.NumEdges() || a.NumFaces() != b.NumFaces()) {
    return false;
  }
  for (VertexId v = 0; v < std::max(a.VertexIdEnd(), b.VertexIdEnd()); ++v) {
    if (a.IsVertex(v) != b.IsVertex(v)) return false;
    if (a.IsVertex(v) && !SameVertex(a.vertex(v), b.vertex(v))) return false;
  }
  for (EdgeId e = 0; e < std::max(a.EdgeIdEnd(), b.EdgeIdEnd()); ++e) {
    if (a.IsEdge(e) != b.IsEdge(e)) return false;
    if (!a.IsEdge(e)) continue;
    for (int side = 0; side < 2; ++side) {
      const HalfedgeId h = PolyMesh::EdgeHalfedge(e, side);
      if (!SameHalfedge(a.halfedge(h), b.halfedge(h))) return false;
    }
  }
  for (FaceId f = 0; f < std::max(a.FaceIdEnd(), b.FaceIdEnd()); ++f) {
    if (a.IsFace(f) != b.IsFace(f)) return false;
    if (a.IsFace(f) && !SameFace(a.face(f), b.face(f))) return false;
  }
  return true;
}

std::vector<FaceId> AddPolygons(PolyMesh* mesh, const std::vector<VertexId>& vertex_ids,
                                const std::vector<std::vector<int>>& polygons, const std::vector<int>& materials,
                                PrimitiveId primitive, std::string* message) {
  auto fail = [&](const std::string& text) {
    if (message) *message = text;
    return std::vector<FaceId>();
  };
  // Dry run first so that a bad input leaves the mesh unchanged.
  std::map<std::pair<int, int>, int> directed;
  const int n = static_cast<int>(vertex_ids.size());
  for (std::size_t p = 0; p < polygons.size(); ++p) {
    const auto& poly = polygons[p];
    if (poly.size() < 3) return fail("polygon " + std::to_string(p) + " has fewer than 3 vertices");
    for (std::size_t i = 0; i < poly.size(); ++i) {
      const int a = poly[i], b = poly[(i + 1) % poly.size()];
      if (a < 0 || a >= n || b < 0 || b >= n) return fail("polygon index out of range");
      if (a == b) return fail("polygon " + std::to_string(p) + " repeats a vertex");
      if (!directed.emplace(std::make_pair(a, b), 1).second) {
        return fail(
            "edge used twice in the same direction: non-manifold or inconsistent "
            "orientation");
      }
    }
  }
  std::vector<int> boundary_out(n, 0);
  for (const auto& [ab, unused] : directed) {
    if (!directed.count({ab.second, ab.first})) {
      if (++boundary_out[ab.second] > 1) return fail("non-manifold vertex on the boundary");
    }
  }

  std::map<std::pair<int, int>, HalfedgeId> made;
  std::vector<FaceId> faces;
  for (std::size_t p = 0; p < polygons.size(); ++p) {
    const auto& poly = polygons[p];
    const FaceId f = mesh->NewFace();
    mesh->face(f).primitive = primitive;
    mesh->face(f).material = p < materials.size() ? materials[p] : 0;
    std::vector<HalfedgeId> loop;
    for (std::size_t i = 0; i < poly.size(); ++i) {
      const int a = poly[i], b = poly[(i + 1) % poly.size()];
      HalfedgeId h;
      auto it = made.find({b, a});
      if (it != made.end()) {
        h = PolyMesh::Twin(it->second);
      } else {
        h = PolyMesh::EdgeHalfedge(mesh->NewEdge(), 0);
        // The twin stays a boundary half-edge unless a later polygon claims it.
        mesh->halfedge(PolyMesh::Twin(h)).origin = vertex_ids[b];
      }
      made[{a, b}] = h;
      MeshHalfedge& he = mesh->halfedge(h);
      he.origin = vertex_ids[a];
      he.face = f;
      if (mesh->vertex(vertex_ids[a]).halfedge == kNoElement) mesh->vertex(vertex_ids[a]).halfedge = h;
      loop.push_back(h);
    }
    for (std::size_t i = 0; i < loop.size(); ++i) {
      mesh->halfedge(loop[i]).next = loop[(i + 1) % loop.size()];
      mesh->halfedge(loop[(i + 1) % loop.size()]).prev = loop[i];
    }
    mesh->face(f).halfedge = loop.front();
    faces.push_back(f);
  }
  // Link boundary half-edges: the boundary half-edge into w continues with the one out of w.
  std::unordered_map<VertexId, HalfedgeId> boundary_from;
  std::vector<HalfedgeId> boundary;
  for (const auto& [ab, h] : made) {
    if (!made.count({ab.second, ab.first})) {
      const HalfedgeId b = PolyMesh::Twin(h);
      boundary.push_back(b);
      boundary_from[mesh->Origin(b)] = b;
    }
  }
  for (HalfedgeId b : boundary) {
    const HalfedgeId next = boundary_from.at(mesh->Dest(b));
    mesh->halfedge(b).next = next;
    mesh->halfedge(next).prev = b;
    // A boundary vertex keeps its boundary half-edge as its outgoing one: walks start there.
    mesh->vertex(mesh->Origin(b)).halfedge = b;
  }
  return faces;
}

int FaceDegree(const PolyMesh& mesh, FaceId f) {
  int n = 0;
  HalfedgeId h = mesh.face(f).halfedge;
  do {
    ++n;
    h = mesh.Next(h);
  } while (h != mesh.face(f).halfedge);
  return n;
}

std::vector<HalfedgeId> FaceHalfedges(const PolyMesh& mesh, FaceId f) {
  std::vector<HalfedgeId> out;
  HalfedgeId h = mesh.face(f).halfedge;
  do {
    out.push_back(h);
    h = mesh.Next(h);
  } while (h != mesh.face(f).halfedge);
  return out;
}

std::vector<VertexId> FaceVertices(const PolyMesh& mesh, FaceId f) {
  std::vector<VertexId> out;
  for (HalfedgeId h : FaceHalfedges(mesh, f)) out.push_back(mesh.Origin(h));
  return out;
}

int VertexDegree(const PolyMesh& mesh, VertexId v) {
  const HalfedgeId start = mesh.vertex(v).halfedge;
  if (start == kNoElement) return 0;
  int n = 0;
  HalfedgeId h = start;
  do {
    ++n;
    h = mesh.Next(PolyMesh::Twin(h));
  } while (h != start);
  return n;
}

HalfedgeId FindHalfedge(const PolyMesh& mesh, VertexId a, VertexId b) {
  const HalfedgeId start = mesh.vertex(a).halfedge;
  if (start == kNoElement) return kNoElement;
  HalfedgeId h = start;
  do {
    if (mesh.Dest(h) == b) return h;
    h = mesh.Next(PolyMesh::Twin(h));
  } while (h != start);
  return kNoElement;
}

int EulerCharacteristic(const PolyMesh& mesh) { return mesh.NumVertices() - mesh.NumEdges() + mesh.NumFaces(); }

Eigen::Vector3d FaceNormal(const PolyMesh& mesh, FaceId f) {
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  HalfedgeId h = mesh.face(f).halfedge;
  do {
    const Eigen::Vector3d& p = mesh.vertex(mesh.Origin(h)).position;
    const Eigen::Vector3d& q = mesh.vertex(mesh.Dest(h)).position;
    n += p.cross(q);
    h = mesh.Next(h);
  } while (h != mesh.face(f).halfedge);
  const double norm = n.norm();
  return norm > 0.0 ? Eigen::Vector3d(n / norm) : Eigen::Vector3d::Zero();
}

std::vector<std::string> Validate(const PolyMesh& mesh) {
  std::vector<std::string> report;
  constexpr std::size_t kMaxReport = 200;
  auto add = [&](const std::string& line) {
    if (report.size() < kMaxReport) report.push_back(line);
  };
  auto he_name = [](HalfedgeId h) {
    return "half-edge " + std::to_string(h) + " (edge " + std::to_string(h / 2) + ")";
  };
  const std::uint32_t num_halfedges = 2 * mesh.EdgeIdEnd();

  std::unordered_map<VertexId, int> outgoing, boundary_outgoing;
  std::unordered_set<std::uint64_t> vertex_pairs;
  std::unordered_map<FaceId, int> face_halfedges;
  bool links_ok = true;
  for (HalfedgeId h = 0; h < num_halfedges; ++h) {
    if (!mesh.IsHalfedge(h)) continue;
    const std::string name = he_name(h);
    const MeshHalfedge& he = mesh.halfedge(h);
    if (!mesh.IsHalfedge(PolyMesh::Twin(h))) {
      add(name + ": dangling twin");
      links_ok = false;
      continue;
    }
    if (!mesh.IsVertex(he.origin)) {
      add(name + ": origin " + std::to_string(he.origin) + " is not a live vertex");
      links_ok = false;
      continue;
    }
    if (!mesh.IsHalfedge(he.next) || !mesh.IsHalfedge(he.prev)) {
      add(name + ": next or prev is not a live half-edge");
      links_ok = false;
      continue;
    }
    if (mesh.Prev(he.next) != h) add(name + ": prev(next) is not itself (next/prev inconsistency)"), links_ok = false;
    if (mesh.Next(he.prev) != h) add(name + ": next(prev) is not itself (next/prev inconsistency)"), links_ok = false;
    if (mesh.Face(he.next) != he.face) add(name + ": next lies in another face"), links_ok = false;
    if (he.face != kNoFace && !mesh.IsFace(he.face)) {
      add(name + ": face " + std::to_string(he.face) + " is not a live face");
      links_ok = false;
    }
    const VertexId dest = mesh.Origin(PolyMesh::Twin(h));
    if (dest == he.origin) add(name + ": self-loop or inconsistent orientation with its twin");
    if (mesh.IsHalfedge(he.next) && mesh.Origin(he.next) != dest) {
      add(name + ": next does not start where the twin starts (inconsistent orientation)");
    }
    ++outgoing[he.origin];
    if (he.face == kNoFace) {
      ++boundary_outgoing[he.origin];
      if ((h & 1u) == 1u && mesh.IsBoundary(PolyMesh::Twin(h))) {
        add("edge " + std::to_string(h / 2) + ": no face on either side (non-manifold edge)");
      }
    } else {
      ++face_halfedges[he.face];
    }
    if ((h & 1u) == 0u) {
      const VertexId lo = std::min(he.origin, dest), hi = std::max(he.origin, dest);
      if (!vertex_pairs.insert((std::uint64_t(lo) << 32) | hi).second) {
        add("edge " + std::to_string(h / 2) + ": a second edge between vertices " + std::to_string(lo) + " and " +
            std::to_string(hi) + " (non-manifold edge)");
      }
    }
  }
  if (!links_ok) return report;  // loop walks below need sound next links

  for (FaceId f = 0; f < mesh.FaceIdEnd(); ++f) {
    if (!mesh.IsFace(f)) continue;
    const std::string name = "face " + std::to_string(f);
    const HalfedgeId start = mesh.face(f).halfedge;
    if (!mesh.IsHalfedge(start) || mesh.Face(start) != f) {
      add(name + ": its half-edge is dead or belongs to another face");
      continue;
    }
    int n = 0;
    HalfedgeId h = start;
    do {
      ++n;
      h = mesh.Next(h);
    } while (h != start && n <= static_cast<int>(num_halfedges));
    if (h != start) {
      add(name + ": loop does not close");
      continue;
    }
    if (n < 3) add(name + ": fewer than 3 vertices (" + std::to_string(n) + ")");
    if (face_halfedges[f] != n) add(name + ": half-edges outside its loop claim this face");
  }
  for (const auto& [f, count] : face_halfedges) {
    (void)count;
    if (mesh.IsFace(f) && mesh.face(f).halfedge == kNoElement) add("face " + std::to_string(f) + ": no half-edge");
  }

  for (VertexId v = 0; v < mesh.VertexIdEnd(); ++v) {
    if (!mesh.IsVertex(v)) continue;
    const std::string name = "vertex " + std::to_string(v);
    const HalfedgeId start = mesh.vertex(v).halfedge;
    if (start == kNoElement) {
      add(name + ": isolated");
      continue;
    }
    if (!mesh.IsHalfedge(start) || mesh.Origin(start) != v) {
      add(name + ": its outgoing half-edge is dead or starts elsewhere");
      continue;
    }
    int fan = 0;
    HalfedgeId h = start;
    do {
      ++fan;
      h = mesh.Next(PolyMesh::Twin(h));
    } while (h != start && fan <= static_cast<int>(num_halfedges));
    if (fan != outgoing[v]) {
      add(name + ": its fan has " + std::to_string(fan) + " of " + std::to_string(outgoing[v]) +
          " outgoing half-edges (non-manifold vertex)");
    }
    if (boundary_outgoing[v] > 1) add(name + ": on two boundary loops (non-manifold vertex)");
  }
  return report;
}

}  // namespace facet
