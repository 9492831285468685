// Synthetic textured scenes for the texture-bake tests: every face of a project carries a known
// paint (a colour as a function of the world point), photos are ray-cast from known pinhole
// cameras with n x n supersampling and an exposure gain, and the baked atlas is read back at
// world points through the mesh's own UVs. The scenes themselves come from synthetic_scene.h.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <vector>

#include <Eigen/Geometry>

#include "core/geometry/camera.h"
#include "core/image/image_io.h"
#include "core/mesh/mesh.h"
#include "core/scene/project.h"
#include "core/texture/textured_mesh.h"
#include "tests/polygon_2d.h"

namespace facet::testing {

// A face as the renderer sees it: its plane, and its polygon in a frame of that plane.
struct PaintedFace {
  size_t index = 0;  // in PaintedFaces' list
  Id primitive_id = kNoId;
  FaceId face = kNoFace;
  std::vector<Eigen::Vector3d> corners;
  Eigen::Vector3d normal, origin, axis_u, axis_v;
  std::vector<Eigen::Vector2d> polygon;  // corners in (axis_u, axis_v) coordinates from origin

  Eigen::Vector2d InPlane(const Eigen::Vector3d& p) const {
    return {(p - origin).dot(axis_u), (p - origin).dot(axis_v)};
  }
  Eigen::Vector3d InWorld(const Eigen::Vector2d& st) const { return origin + st.x() * axis_u + st.y() * axis_v; }
  bool Faces(const Camera& cam) const {
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (const auto& p : corners) centroid += p;
    return normal.dot(cam.CenterInWorld() - centroid / static_cast<double>(corners.size())) > 0.0;
  }
};

// The paint: RGB in grey levels (0-255) of a world point on a face.
using Paint = std::function<Eigen::Vector3d(const PaintedFace& face, const Eigen::Vector3d& x_in_world)>;

inline std::vector<PaintedFace> PaintedFaces(const Project& project) {
  std::vector<PaintedFace> faces;
  for (const Primitive& primitive : project.primitives) {
    const PolyMesh& mesh = primitive.mesh;
    for (FaceId f = 0; f < mesh.FaceIdEnd(); ++f) {
      if (!mesh.IsFace(f)) continue;
      PaintedFace pf;
      pf.index = faces.size();
      pf.primitive_id = primitive.id;
      pf.face = f;
      for (VertexId v : FaceVertices(mesh, f)) pf.corners.push_back(mesh.vertex(v).position);
      pf.normal = FaceNormal(mesh, f);
      pf.origin = pf.corners[0];
      const Eigen::Vector3d e = pf.corners[1] - pf.corners[0];
      pf.axis_u = (e - e.dot(pf.normal) * pf.normal).normalized();
      pf.axis_v = pf.normal.cross(pf.axis_u);
      for (const auto& p : pf.corners) pf.polygon.push_back(pf.InPlane(p));
      faces.push_back(pf);
    }
  }
  return faces;
}

// The face the ray from `center` along `dir` hits first, or nullptr; *hit gets the point.
inline const PaintedFace* FirstFaceHit(const std::vector<PaintedFace>& faces, const Eigen::Vector3d& center,
                                       const Eigen::Vector3d& dir, Eigen::Vector3d* hit) {
  double best = std::numeric_limits<double>::infinity();
  const PaintedFace* found = nullptr;
  for (const PaintedFace& face : faces) {
    const double denominator = dir.dot(face.normal);
    if (std::abs(denominator) < 1e-12) continue;
    const double depth = (face.origin - center).dot(face.normal) / denominator;
    if (!(depth > 0.0) || depth >= best) continue;
    const Eigen::Vector3d p = center + depth * dir;
    if (!InsidePolygon2d(face.polygon, face.InPlane(p))) continue;
    best = depth;
    found = &face;
    *hit = p;
  }
  return found;
}

// Ray-casts a pinhole photo (the camera must have no distortion) of cam.width_px x
// cam.height_px: each pixel is the mean of supersample x supersample rays spread over it, each
// ray showing gain x the paint of the first face it hits, or `background`.
inline ImageRgba8 RenderTexturedPhoto(const std::vector<PaintedFace>& faces, const Camera& cam, const Paint& paint,
                                      double gain = 1.0, int supersample = 1,
                                      const Eigen::Vector3d& background = Eigen::Vector3d(20, 20, 20)) {
  ImageRgba8 photo;
  photo.width = cam.width_px;
  photo.height = cam.height_px;
  photo.pixels.resize(static_cast<size_t>(photo.width) * photo.height * 4);
  const Eigen::Vector3d center = cam.CenterInWorld();
  const Eigen::Matrix3d world_from_cam = cam.cam_from_world_rotation.transpose();
  for (int y = 0; y < photo.height; ++y) {
    for (int x = 0; x < photo.width; ++x) {
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (int b = 0; b < supersample; ++b) {
        for (int a = 0; a < supersample; ++a) {
          const Eigen::Vector2d uv(x - 0.5 + (a + 0.5) / supersample, y - 0.5 + (b + 0.5) / supersample);
          const Eigen::Vector2d xy = (uv - cam.principal_point_px) / cam.focal_px;
          const Eigen::Vector3d dir = world_from_cam * Eigen::Vector3d(xy.x(), xy.y(), 1.0);
          Eigen::Vector3d hit;
          const PaintedFace* face = FirstFaceHit(faces, center, dir, &hit);
          sum += face != nullptr ? Eigen::Vector3d(gain * paint(*face, hit)) : background;
        }
      }
      sum /= static_cast<double>(supersample * supersample);
      std::uint8_t* px = photo.At(x, y);
      for (int c = 0; c < 3; ++c) px[c] = static_cast<std::uint8_t>(std::clamp(std::lround(sum[c]), 0l, 255l));
      px[3] = 255;
    }
  }
  return photo;
}

// The baked colour at world point x on `face`: the UVs of the face's triangle holding x
// (barycentric interpolation), then the nearest texel of its atlas page. False when the face
// is untextured or x is on none of its triangles.
inline bool BakedColourAt(const TexturedMesh& mesh, const PaintedFace& face, const Eigen::Vector3d& x,
                          Eigen::Vector3d* rgb) {
  for (size_t tri = 0; tri < mesh.triangle_face.size(); ++tri) {
    if (mesh.triangle_primitive[tri] != face.primitive_id || mesh.triangle_face[tri] != face.face) continue;
    if (!mesh.triangle_textured[tri]) return false;
    std::array<Eigen::Vector3d, 3> p;
    std::array<Eigen::Vector2d, 3> uv;
    for (int k = 0; k < 3; ++k) {
      p[k] = mesh.positions[mesh.indices[3 * tri + k]].cast<double>();
      uv[k] = mesh.uvs[mesh.indices[3 * tri + k]].cast<double>();
    }
    const Eigen::Vector3d n = (p[1] - p[0]).cross(p[2] - p[0]);
    const double area = n.squaredNorm();
    const double b1 = (x - p[0]).cross(p[2] - p[0]).dot(n) / area;
    const double b2 = (p[1] - p[0]).cross(x - p[0]).dot(n) / area;
    const double b0 = 1.0 - b1 - b2;
    constexpr double kSlack = -1e-6;
    if (b0 < kSlack || b1 < kSlack || b2 < kSlack) continue;
    const Eigen::Vector2d t = b0 * uv[0] + b1 * uv[1] + b2 * uv[2];
    const ImageRgba8& page = mesh.AtlasPage(mesh.TrianglePage(tri));
    const int i = std::clamp(static_cast<int>(std::lround(t.x() * page.width - 0.5)), 0, page.width - 1);
    const int j = std::clamp(static_cast<int>(std::lround(t.y() * page.height - 0.5)), 0, page.height - 1);
    const std::uint8_t* px = page.At(i, j);
    *rgb = Eigen::Vector3d(px[0], px[1], px[2]);
    return true;
  }
  return false;
}

// Points on a face on an n x n grid over its polygon's bounding box, kept where they lie inside
// the polygon at least `inset` (world units) from its outline.
inline std::vector<Eigen::Vector3d> FaceGrid(const PaintedFace& face, int n, double inset) {
  Eigen::Vector2d lo = face.polygon[0], hi = face.polygon[0];
  for (const auto& q : face.polygon) {
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  std::vector<Eigen::Vector3d> points;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector2d st = lo + (hi - lo).cwiseProduct(Eigen::Vector2d((i + 0.5) / n, (j + 0.5) / n));
      if (InsidePolygon2d(face.polygon, st) && DistanceToPolygonOutline(face.polygon, st) >= inset) {
        points.push_back(face.InWorld(st));
      }
    }
  }
  return points;
}

}  // namespace facet::testing
