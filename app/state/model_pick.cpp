#include "app/state/model_pick.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "app/platform/gl_camera.h"
#include "core/mesh/triangulate.h"

namespace facet::app {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// Ray-triangle intersection (Moller-Trumbore); the ray parameter or +infinity.
double RayTriangle(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& a,
                   const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d e1 = b - a, e2 = c - a;
  const Eigen::Vector3d p = d.cross(e2);
  const double det = e1.dot(p);
  if (std::abs(det) < 1e-18) return kInfinity;
  const Eigen::Vector3d s = o - a;
  const double u = s.dot(p) / det;
  if (u < 0.0 || u > 1.0) return kInfinity;
  const Eigen::Vector3d q = s.cross(e1);
  const double v = d.dot(q) / det;
  if (v < 0.0 || u + v > 1.0) return kInfinity;
  const double t = e2.dot(q) / det;
  return t > 0.0 ? t : kInfinity;
}

Eigen::Vector3d FaceCentroid(const PolyMesh& mesh, FaceId f) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  const std::vector<VertexId> vs = FaceVertices(mesh, f);
  for (VertexId v : vs) c += mesh.vertex(v).position;
  return vs.empty() ? c : Eigen::Vector3d(c / static_cast<double>(vs.size()));
}

// The faces around a vertex (those it bounds).
std::vector<FaceId> FacesAroundVertex(const PolyMesh& mesh, VertexId v) {
  std::vector<FaceId> faces;
  const HalfedgeId first = mesh.vertex(v).halfedge;
  if (!mesh.IsHalfedge(first)) return faces;
  HalfedgeId h = first;
  for (int guard = 0; guard < 1000; ++guard) {
    if (!mesh.IsBoundary(h)) faces.push_back(mesh.Face(h));
    h = mesh.Next(PolyMesh::Twin(h));
    if (h == first) break;
  }
  return faces;
}

// Whether a face crosses the line of sight from `eye` to `p`, other than the faces `p` lies
// on (`own_faces` of primitive `own_primitive`).
bool Occluded(const Project& project, const Eigen::Vector3d& eye, const Eigen::Vector3d& p, Id own_primitive,
              const std::vector<FaceId>& own_faces) {
  const Eigen::Vector3d to_p = p - eye;
  const double length = to_p.norm();
  if (!(length > 0.0)) return false;
  const Eigen::Vector3d direction = to_p / length;
  // Relative: a face that meets the line within this fraction of its end touches p.
  constexpr double kTouching = 1e-6;
  for (const Primitive& primitive : project.primitives) {
    const PolyMesh& mesh = primitive.mesh;
    for (FaceId f = 0; f < mesh.FaceIdEnd(); ++f) {
      if (!mesh.IsFace(f)) continue;
      if (primitive.id == own_primitive && std::find(own_faces.begin(), own_faces.end(), f) != own_faces.end())
        continue;
      for (const CornerTriangle& tri : TriangulateFace(mesh, f)) {
        const double t =
            RayTriangle(eye, direction, mesh.vertex(mesh.Origin(tri[0])).position,
                        mesh.vertex(mesh.Origin(tri[1])).position, mesh.vertex(mesh.Origin(tri[2])).position);
        if (t < length * (1.0 - kTouching)) return true;
      }
    }
  }
  return false;
}

}  // namespace

std::vector<ProjectedPrimitive> ProjectModel(const Project& project, const Image& image) {
  std::vector<ProjectedPrimitive> result;
  if (!image.camera_calibrated) return result;
  const Camera& camera = image.camera;
  for (const Primitive& primitive : project.primitives) {
    ProjectedPrimitive p;
    p.primitive_id = primitive.id;
    const std::uint32_t n = primitive.mesh.VertexIdEnd();
    p.uv_px.assign(n, Eigen::Vector2d::Zero());
    p.depth.assign(n, 0.0);
    p.in_front.assign(n, 0);
    for (VertexId v = 0; v < n; ++v) {
      if (!primitive.mesh.IsVertex(v)) continue;
      const Eigen::Vector3d x = primitive.mesh.vertex(v).position;
      const Eigen::Vector3d p_in_cam = camera.CamFromWorld(x);
      p.depth[v] = p_in_cam.z();
      p.in_front[v] = p_in_cam.z() > kNearDepth;
      if (p.in_front[v]) p.uv_px[v] = camera.Project(x);
    }
    result.push_back(std::move(p));
  }
  return result;
}

PickFilter PickFilterOf(Tool tool) {
  switch (tool) {
    case Tool::kSelect: return {true, true, true};
    case Tool::kPin:
    case Tool::kDeleteVertex:
    case Tool::kConnectVertices:
    case Tool::kMeasure: return {true, false, false};
    case Tool::kSplitEdge:
    case Tool::kDeleteEdge:
    case Tool::kLinePin: return {false, true, false};
    case Tool::kPushPull: return {false, false, true};
    case Tool::kMove: return {true, true, true};
    default: return {false, false, false};
  }
}

bool PointInPolygon(const Eigen::Vector2d& p, const std::vector<Eigen::Vector2d>& polygon) {
  bool inside = false;
  const size_t n = polygon.size();
  for (size_t i = 0, j = n - 1; i < n; j = i++) {
    const Eigen::Vector2d& a = polygon[i];
    const Eigen::Vector2d& b = polygon[j];
    if ((a.y() > p.y()) != (b.y() > p.y()) && p.x() < (b.x() - a.x()) * (p.y() - a.y()) / (b.y() - a.y()) + a.x()) {
      inside = !inside;
    }
  }
  return inside;
}

double ClosestEdgeParameter(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& ray_origin,
                            const Eigen::Vector3d& ray_direction) {
  // Closest points of the lines a + t (b - a) and o + s d.
  const Eigen::Vector3d u = b - a, v = ray_direction, w = a - ray_origin;
  const double uu = u.dot(u), uv = u.dot(v), vv = v.dot(v), uw = u.dot(w), vw = v.dot(w);
  const double denom = uu * vv - uv * uv;
  if (uu <= 0.0 || denom <= 1e-18 * uu * vv) return 0.5;  // parallel: any point, take the middle
  const double t = (uv * vw - vv * uw) / denom;
  return std::clamp(t, 0.0, 1.0);
}

ElementPick PickInImage(const Project& project, const std::vector<ProjectedPrimitive>& projected, const Camera& camera,
                        double zoom, const Eigen::Vector2d& origin_screen, const Eigen::Vector2d& mouse_screen,
                        const PickFilter& filter, double radius_px) {
  auto screen = [&](const Eigen::Vector2d& uv) -> Eigen::Vector2d { return origin_screen + zoom * uv; };
  const Eigen::Vector3d eye = camera.CenterInWorld();
  const Eigen::Vector2d mouse_uv = (mouse_screen - origin_screen) / zoom;
  // Candidates on the back of a primitive (every face beside them turned away) lose to a
  // front face under the cursor: a click on a face the user sees never picks what it hides.
  struct Candidate {
    ElementPick pick;
    bool front = false;
  };
  Candidate vertex_pick, edge_pick;
  double best_vertex = radius_px, best_edge = radius_px, best_face_depth = kInfinity;
  ElementPick face_pick;
  for (const ProjectedPrimitive& pp : projected) {
    const Primitive* primitive = project.FindPrimitive(pp.primitive_id);
    if (primitive == nullptr) continue;
    const PolyMesh& mesh = primitive->mesh;
    std::vector<char> front(mesh.FaceIdEnd(), 0);
    for (FaceId f = 0; f < mesh.FaceIdEnd(); ++f) {
      if (mesh.IsFace(f)) front[f] = FaceNormal(mesh, f).dot(eye - FaceCentroid(mesh, f)) > 0.0;
    }
    auto front_halfedge = [&](HalfedgeId h) { return mesh.IsBoundary(h) || front[mesh.Face(h)]; };
    if (filter.vertices) {
      for (VertexId v = 0; v < pp.uv_px.size(); ++v) {
        if (!pp.in_front[v]) continue;
        const double d = (screen(pp.uv_px[v]) - mouse_screen).norm();
        if (d >= best_vertex) continue;
        best_vertex = d;
        vertex_pick.pick.element = {ElementKind::kVertex, pp.primitive_id, v};
        vertex_pick.pick.distance_px = d;
        vertex_pick.front = false;
        const HalfedgeId first = mesh.vertex(v).halfedge;
        HalfedgeId h = first;
        for (int guard = 0; guard < 1000; ++guard) {
          vertex_pick.front = vertex_pick.front || front_halfedge(h);
          h = mesh.Next(PolyMesh::Twin(h));
          if (h == first) break;
        }
      }
    }
    if (filter.edges) {
      for (EdgeId e = 0; e < mesh.EdgeIdEnd(); ++e) {
        if (!mesh.IsEdge(e)) continue;
        const VertexId a = mesh.Origin(2 * e), b = mesh.Dest(2 * e);
        if (!pp.in_front[a] || !pp.in_front[b]) continue;
        const double d = DistanceToSegment(mouse_screen, screen(pp.uv_px[a]), screen(pp.uv_px[b]));
        if (d >= best_edge) continue;
        best_edge = d;
        edge_pick.pick.element = {ElementKind::kEdge, pp.primitive_id, e};
        edge_pick.pick.distance_px = d;
        edge_pick.front = front_halfedge(2 * e) || front_halfedge(2 * e + 1);
        edge_pick.pick.t = ClosestEdgeParameter(mesh.vertex(a).position, mesh.vertex(b).position, eye,
                                                camera.RayDirectionInWorld(mouse_uv));
        const Eigen::Vector2d mid = screen(camera.Project(0.5 * (mesh.vertex(a).position + mesh.vertex(b).position)));
        if ((mid - mouse_screen).norm() <= kMidpointSnapPx) edge_pick.pick.t = 0.5;
      }
    }
    // Faces are looked for whatever the filter: a front face under the cursor hides back
    // vertices and edges.
    for (FaceId f = 0; f < mesh.FaceIdEnd(); ++f) {
      if (!mesh.IsFace(f) || !front[f]) continue;
      std::vector<Eigen::Vector2d> polygon;
      bool visible = true;
      for (VertexId v : FaceVertices(mesh, f)) {
        if (!pp.in_front[v]) visible = false;
        polygon.push_back(screen(pp.uv_px[v]));
      }
      if (!visible || !PointInPolygon(mouse_screen, polygon)) continue;
      const double depth = camera.CamFromWorld(FaceCentroid(mesh, f)).z();
      if (depth < best_face_depth) {
        best_face_depth = depth;
        face_pick.element = {ElementKind::kFace, pp.primitive_id, f};
      }
    }
  }
  const bool covered = !face_pick.element.Empty();
  if (!vertex_pick.pick.element.Empty() && (vertex_pick.front || !covered)) return vertex_pick.pick;
  if (!edge_pick.pick.element.Empty() && (edge_pick.front || !covered)) return edge_pick.pick;
  if (filter.faces) return face_pick;
  return {};
}

bool ProjectToPanel(const PickRay& ray, const Eigen::Vector3d& p_in_world, Eigen::Vector2d* px) {
  const glm::dvec4 clip = ray.clip_from_world * HomogeneousGlm(p_in_world);
  if (clip.w <= 1e-9) return false;
  *px = Eigen::Vector2d((clip.x / clip.w + 1.0) * 0.5 * ray.width_px, (1.0 - clip.y / clip.w) * 0.5 * ray.height_px);
  return true;
}

ElementPick PickByRay(const Project& project, const PickRay& ray, const PickFilter& filter, double radius_px) {
  // The face under the cursor: the nearest surface along the ray.
  double hit_t = kInfinity;
  ElementPick face_pick;
  for (const Primitive& primitive : project.primitives) {
    const PolyMesh& mesh = primitive.mesh;
    for (FaceId f = 0; f < mesh.FaceIdEnd(); ++f) {
      if (!mesh.IsFace(f)) continue;
      for (const CornerTriangle& tri : TriangulateFace(mesh, f)) {
        const double t =
            RayTriangle(ray.origin, ray.direction, mesh.vertex(mesh.Origin(tri[0])).position,
                        mesh.vertex(mesh.Origin(tri[1])).position, mesh.vertex(mesh.Origin(tri[2])).position);
        if (t < hit_t) {
          hit_t = t;
          // Only a face seen from outside is pickable; from inside the hit still hides.
          const bool front = FaceNormal(mesh, f).dot(ray.direction) < 0.0;
          face_pick.element = front ? ElementRef{ElementKind::kFace, primitive.id, f} : ElementRef{};
        }
      }
    }
  }
  // A vertex or edge near the cursor is tested on its own line of sight, not against the
  // face under the cursor: the corner of a box lies behind the point where the cursor's ray
  // meets the face it bounds (that face slopes away), yet nothing hides it.
  ElementPick vertex_pick, edge_pick;
  double best_vertex = radius_px, best_edge = radius_px;
  for (const Primitive& primitive : project.primitives) {
    const PolyMesh& mesh = primitive.mesh;
    if (filter.vertices) {
      for (VertexId v = 0; v < mesh.VertexIdEnd(); ++v) {
        if (!mesh.IsVertex(v)) continue;
        Eigen::Vector2d px;
        const Eigen::Vector3d& p = mesh.vertex(v).position;
        if (!ProjectToPanel(ray, p, &px)) continue;
        const double d = (px - ray.mouse_px).norm();
        if (d < best_vertex && !Occluded(project, ray.origin, p, primitive.id, FacesAroundVertex(mesh, v))) {
          best_vertex = d;
          vertex_pick.element = {ElementKind::kVertex, primitive.id, v};
          vertex_pick.distance_px = d;
        }
      }
    }
    if (filter.edges) {
      for (EdgeId e = 0; e < mesh.EdgeIdEnd(); ++e) {
        if (!mesh.IsEdge(e)) continue;
        const Eigen::Vector3d& a = mesh.vertex(mesh.Origin(2 * e)).position;
        const Eigen::Vector3d& b = mesh.vertex(mesh.Dest(2 * e)).position;
        Eigen::Vector2d pa, pb;
        if (!ProjectToPanel(ray, a, &pa) || !ProjectToPanel(ray, b, &pb)) continue;
        const double d = DistanceToSegment(ray.mouse_px, pa, pb);
        if (d >= best_edge) continue;
        double t = ClosestEdgeParameter(a, b, ray.origin, ray.direction);
        const std::vector<FaceId> sides = {mesh.Face(2 * e), mesh.Face(2 * e + 1)};
        if (Occluded(project, ray.origin, a + t * (b - a), primitive.id, sides)) continue;
        Eigen::Vector2d mid;
        if (ProjectToPanel(ray, 0.5 * (a + b), &mid) && (mid - ray.mouse_px).norm() <= kMidpointSnapPx) t = 0.5;
        best_edge = d;
        edge_pick.element = {ElementKind::kEdge, primitive.id, e};
        edge_pick.distance_px = d;
        edge_pick.t = t;
      }
    }
  }
  if (!vertex_pick.element.Empty()) return vertex_pick;
  if (!edge_pick.element.Empty()) return edge_pick;
  if (filter.faces) return face_pick;
  return {};
}

double DistanceToSegment(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b, double* t) {
  const Eigen::Vector2d d = b - a;
  const double len2 = d.squaredNorm();
  double s = len2 > 0.0 ? (p - a).dot(d) / len2 : 0.0;
  s = std::clamp(s, 0.0, 1.0);
  if (t != nullptr) *t = s;
  return (p - (a + s * d)).norm();
}

}  // namespace facet::app
