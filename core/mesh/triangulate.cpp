#include "core/mesh/triangulate.h"

#include <cmath>

#include <Eigen/Geometry>

namespace facet {

namespace {

double Cross2(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  return (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
}

// Inside or on the boundary: a vertex on an ear's diagonal (the reflex corner of an L)
// forbids that ear, since the diagonal would pass through it.
bool InsideOrOn(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c,
                double eps) {
  return Cross2(a, b, p) >= -eps && Cross2(b, c, p) >= -eps && Cross2(c, a, p) >= -eps;
}

}  // namespace

std::vector<CornerTriangle> TriangulateFace(const PolyMesh& mesh, FaceId face) {
  const std::vector<HalfedgeId> corners = FaceHalfedges(mesh, face);
  const int n = static_cast<int>(corners.size());
  std::vector<CornerTriangle> out;
  out.reserve(n - 2);
  if (n == 3) {
    out.push_back({corners[0], corners[1], corners[2]});
    return out;
  }
  // Project into the face plane so that counter-clockwise in 2D is counter-clockwise about
  // the face normal.
  const Eigen::Vector3d normal = FaceNormal(mesh, face);
  const Eigen::Vector3d u = normal.unitOrthogonal();
  const Eigen::Vector3d v = normal.cross(u);
  std::vector<Eigen::Vector2d> p(n);
  double extent = 0.0;
  const Eigen::Vector3d& origin = mesh.vertex(mesh.Origin(corners[0])).position;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d d = mesh.vertex(mesh.Origin(corners[i])).position - origin;
    p[i] = Eigen::Vector2d(d.dot(u), d.dot(v));
    extent = std::max(extent, p[i].norm());
  }
  // Corners straighter than this (relative to the face size squared) are not ear tips.
  const double eps = 1e-12 * extent * extent;
  std::vector<int> ring(n);
  for (int i = 0; i < n; ++i) ring[i] = i;
  // In a convex face no vertex can lie in an ear, so the O(n) containment test per ear is
  // skipped and the common case (primitive faces and their V_connect parts) is linear.
  bool convex = true;
  for (int k = 0; k < n && convex; ++k) convex = Cross2(p[(k + n - 1) % n], p[k], p[(k + 1) % n]) >= -eps;
  int guard = 0;
  int i = 0;
  while (ring.size() > 3 && guard < 2 * static_cast<int>(ring.size()) + 2) {
    const int m = static_cast<int>(ring.size());
    const int ia = ring[(i + m - 1) % m], ib = ring[i % m], ic = ring[(i + 1) % m];
    bool ear = Cross2(p[ia], p[ib], p[ic]) > eps;
    for (int k = 0; ear && !convex && k < m; ++k) {
      const int q = ring[k];
      if (q != ia && q != ib && q != ic && InsideOrOn(p[q], p[ia], p[ib], p[ic], eps)) ear = false;
    }
    if (ear) {
      out.push_back({corners[ia], corners[ib], corners[ic]});
      ring.erase(ring.begin() + (i % m));
      guard = 0;
      if (i >= static_cast<int>(ring.size())) i = 0;
    } else {
      i = (i + 1) % m;
      ++guard;
    }
  }
  // Remaining ring: the last triangle, or a fan over a face with no ear (degenerate).
  for (std::size_t k = 1; k + 1 < ring.size(); ++k) {
    out.push_back({corners[ring[0]], corners[ring[k]], corners[ring[k + 1]]});
  }
  return out;
}

MeshTriangulation TriangulateMesh(const PolyMesh& mesh) {
  MeshTriangulation t;
  t.by_face.resize(mesh.FaceIdEnd());
  for (FaceId f = 0; f < mesh.FaceIdEnd(); ++f) {
    if (mesh.IsFace(f)) t.by_face[f] = TriangulateFace(mesh, f);
  }
  return t;
}

void RetriangulateFaces(const PolyMesh& mesh, const std::vector<FaceId>& faces, MeshTriangulation* triangulation) {
  if (triangulation->by_face.size() < mesh.FaceIdEnd()) triangulation->by_face.resize(mesh.FaceIdEnd());
  for (FaceId f : faces) {
    if (f >= triangulation->by_face.size()) continue;
    if (mesh.IsFace(f)) {
      triangulation->by_face[f] = TriangulateFace(mesh, f);
    } else {
      triangulation->by_face[f].clear();
    }
  }
}

FlatTriangles Flatten(const PolyMesh& mesh, const MeshTriangulation& triangulation) {
  FlatTriangles flat;
  flat.first_triangle.assign(triangulation.by_face.size(), 0);
  for (FaceId f = 0; f < triangulation.by_face.size(); ++f) {
    flat.first_triangle[f] = static_cast<int>(flat.triangles.size());
    for (const CornerTriangle& c : triangulation.by_face[f]) {
      flat.corners.push_back(c);
      flat.triangles.push_back({mesh.Origin(c[0]), mesh.Origin(c[1]), mesh.Origin(c[2])});
      flat.triangle_face.push_back(f);
    }
  }
  return flat;
}

}  // namespace facet
