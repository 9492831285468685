#include "core/texture/textured_mesh.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>

#include <stb_rect_pack.h>
#include <Eigen/Geometry>

#include "core/mesh/triangulate.h"

namespace facet {
namespace {

// Grey for texels whose ray leaves the photo: neutral under any lighting, and opaque so the
// face shows no hole.
constexpr std::uint8_t kOutsideGrey = 128;
// Below this many visible pixels a view carries no usable texture.
constexpr double kMinProjectedAreaPx2 = 16.0;
constexpr int kMinFaceTexels = 2;
constexpr int kMinAtlasSize = 16;
// Face samples tested for occlusion by other primitives, per side of the face's rectangle.
constexpr int kOcclusionSamples = 4;
// Ends of an occlusion ray that do not count as hits, as a fraction of its length: the ray
// starts on the face (which may touch a neighbour, e.g. a roof on a box) and ends at the
// camera centre.
constexpr double kRayEndMargin = 1e-6;

// A face as the bake sees it: its corners in world, its plane frame and where its vertices
// and texture go in the TexturedMesh.
struct FaceGeometry {
  size_t primitive_index = 0;
  std::vector<Eigen::Vector3d> corners;  // counter-clockwise from outside, FaceHalfedges order
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  // Plane frame: p = origin + s * axis_u + t * axis_v for face coordinates (s, t).
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis_u = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis_v = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector2d> corners_st;           // corners in the face frame
  Eigen::Vector2d st_min = Eigen::Vector2d::Zero();  // bounding rectangle in the face frame
  Eigen::Vector2d st_max = Eigen::Vector2d::Zero();
  std::vector<Eigen::Vector3d> occlusion_samples;  // points on the face, world
  std::uint32_t first_vertex = 0;                  // in the TexturedMesh
  size_t first_triangle = 0;
  size_t triangle_count = 0;
  bool valid = false;  // false for a degenerate face, which stays untextured

  Eigen::Vector3d InWorld(const Eigen::Vector2d& st) const { return origin + st.x() * axis_u + st.y() * axis_v; }
  // The bounding rectangle's corners: (s_min, t_min), (s_max, t_min), (s_max, t_max), (s_min, t_max).
  std::array<Eigen::Vector3d, 4> RectangleInWorld() const {
    return {InWorld(st_min), InWorld({st_max.x(), st_min.y()}), InWorld(st_max), InWorld({st_min.x(), st_max.y()})};
  }
};

// World triangles of one primitive with their bounding box: the occluders of other
// primitives' faces.
struct Occluder {
  std::vector<std::array<Eigen::Vector3d, 3>> triangles;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity());
};

// A calibrated camera mapped to the pixels of its loaded photo (which may have been loaded
// at another resolution than the intrinsics refer to).
struct PhotoView {
  size_t image_index = 0;
  const Camera* camera = nullptr;
  const ImageRgba8* photo = nullptr;
  double scale_x = 1.0;
  double scale_y = 1.0;

  // Photo pixel of a camera-frame point, through the camera's distortion.
  Eigen::Vector2d ProjectCam(const Eigen::Vector3d& p_in_cam) const {
    Eigen::Vector2d xy(p_in_cam.x() / p_in_cam.z(), p_in_cam.y() / p_in_cam.z());
    if (camera->HasDistortion()) xy = camera->DistortNormalized(xy);
    return {(camera->focal_px * xy.x() + camera->principal_point_px.x()) * scale_x,
            (camera->focal_px * xy.y() + camera->principal_point_px.y()) * scale_y};
  }
};

struct FaceTexture {
  int view = -1;  // index into the PhotoView list, -1 when untextured
  double score = 0.0;
  int width = 0;  // texels at full resolution, before any atlas shrinking
  int height = 0;
  int packed_width = 0;
  int packed_height = 0;
  int x = 0;  // top-left texel of the face inside the atlas (padding excluded)
  int y = 0;
};

double SignedArea(const std::vector<Eigen::Vector2d>& polygon) {
  double twice_area = 0.0;
  for (size_t i = 0; i < polygon.size(); ++i) {
    const Eigen::Vector2d& a = polygon[i];
    const Eigen::Vector2d& b = polygon[(i + 1) % polygon.size()];
    twice_area += a.x() * b.y() - a.y() * b.x();
  }
  return 0.5 * twice_area;
}

// Sutherland-Hodgman against one axis-aligned half-plane: keep coord(axis) * sign <= limit * sign.
// For a non-convex polygon the result may hold zero-width bridges along the clip line, which
// leave its area exact.
std::vector<Eigen::Vector2d> ClipHalfPlane(const std::vector<Eigen::Vector2d>& polygon, int axis, double limit,
                                           double sign) {
  std::vector<Eigen::Vector2d> out;
  for (size_t i = 0; i < polygon.size(); ++i) {
    const Eigen::Vector2d& a = polygon[i];
    const Eigen::Vector2d& b = polygon[(i + 1) % polygon.size()];
    const double da = (a[axis] - limit) * sign;
    const double db = (b[axis] - limit) * sign;
    if (da <= 0) out.push_back(a);
    if ((da < 0 && db > 0) || (da > 0 && db < 0)) out.push_back(a + (b - a) * (da / (da - db)));
  }
  return out;
}

// Area of the polygon inside the photo's pixel area [-0.5, w - 0.5] x [-0.5, h - 0.5].
double VisibleArea(std::vector<Eigen::Vector2d> polygon, int width, int height) {
  polygon = ClipHalfPlane(polygon, 0, -0.5, -1.0);
  polygon = ClipHalfPlane(polygon, 0, width - 0.5, 1.0);
  polygon = ClipHalfPlane(polygon, 1, -0.5, -1.0);
  polygon = ClipHalfPlane(polygon, 1, height - 0.5, 1.0);
  return polygon.size() < 3 ? 0.0 : std::abs(SignedArea(polygon));
}

// Even-odd rule; the polygon may be non-convex.
bool InsidePolygon(const std::vector<Eigen::Vector2d>& polygon, const Eigen::Vector2d& p) {
  bool inside = false;
  for (size_t i = 0, j = polygon.size() - 1; i < polygon.size(); j = i++) {
    const Eigen::Vector2d& a = polygon[i];
    const Eigen::Vector2d& b = polygon[j];
    if ((a.y() > p.y()) != (b.y() > p.y()) && p.x() < a.x() + (p.y() - a.y()) * (b.x() - a.x()) / (b.y() - a.y())) {
      inside = !inside;
    }
  }
  return inside;
}

// Slab test: whether the segment a -> b meets the (slightly grown) box at all.
bool SegmentMeetsBox(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& lo,
                     const Eigen::Vector3d& hi) {
  const Eigen::Vector3d d = b - a;
  const double grow = 1e-9 * std::max(1.0, (hi - lo).norm());
  double t_lo = 0.0, t_hi = 1.0;
  for (int k = 0; k < 3; ++k) {
    if (std::abs(d[k]) < 1e-300) {
      if (a[k] < lo[k] - grow || a[k] > hi[k] + grow) return false;
      continue;
    }
    double t0 = (lo[k] - grow - a[k]) / d[k];
    double t1 = (hi[k] + grow - a[k]) / d[k];
    if (t0 > t1) std::swap(t0, t1);
    t_lo = std::max(t_lo, t0);
    t_hi = std::min(t_hi, t1);
    if (t_lo > t_hi) return false;
  }
  return true;
}

// Moller-Trumbore: whether the segment a -> b crosses the triangle strictly between its
// ends (kRayEndMargin), so a ray starting on a face that touches the triangle is not hidden.
bool SegmentHitsTriangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                         const std::array<Eigen::Vector3d, 3>& tri) {
  const Eigen::Vector3d d = b - a;
  const Eigen::Vector3d e1 = tri[1] - tri[0];
  const Eigen::Vector3d e2 = tri[2] - tri[0];
  const Eigen::Vector3d p = d.cross(e2);
  const double det = e1.dot(p);
  // A segment in the triangle's plane grazes it: not an occlusion.
  if (std::abs(det) <= 1e-14 * d.norm() * e1.norm() * e2.norm()) return false;
  const double inv_det = 1.0 / det;
  const Eigen::Vector3d s = a - tri[0];
  const double u = s.dot(p) * inv_det;
  if (u < 0.0 || u > 1.0) return false;
  const Eigen::Vector3d q = s.cross(e1);
  const double v = d.dot(q) * inv_det;
  if (v < 0.0 || u + v > 1.0) return false;
  const double t = e2.dot(q) * inv_det;
  return t > kRayEndMargin && t < 1.0 - kRayEndMargin;
}

double UnoccludedFraction(const FaceGeometry& face, const Eigen::Vector3d& center,
                          const std::vector<Occluder>& occluders) {
  if (face.occlusion_samples.empty()) return 1.0;
  int visible = 0;
  for (const Eigen::Vector3d& p : face.occlusion_samples) {
    bool hidden = false;
    for (size_t o = 0; o < occluders.size() && !hidden; ++o) {
      // Only other primitives: a primitive's own faces facing the camera are not hidden by
      // the rest of it as long as it is convex, which the primitives are up to free vertices.
      if (o == face.primitive_index || occluders[o].triangles.empty() ||
          !SegmentMeetsBox(p, center, occluders[o].lo, occluders[o].hi))
        continue;
      for (const auto& tri : occluders[o].triangles) {
        if (SegmentHitsTriangle(p, center, tri)) {
          hidden = true;
          break;
        }
      }
    }
    visible += hidden ? 0 : 1;
  }
  return static_cast<double>(visible) / static_cast<double>(face.occlusion_samples.size());
}

// Scores the view of a face: visible projected area times the cosine of the view angle
// times the unoccluded fraction; 0 when unusable. Also returns the size in photo px of the
// face's bounding rectangle along u and v.
double ScoreView(const FaceGeometry& face, const PhotoView& view, const std::vector<Occluder>& occluders,
                 double* length_u_px, double* length_v_px) {
  const Camera& cam = *view.camera;
  std::vector<Eigen::Vector2d> uv(face.corners.size());
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (size_t k = 0; k < face.corners.size(); ++k) {
    const Eigen::Vector3d p_in_cam = cam.CamFromWorld(face.corners[k]);
    if (!(p_in_cam.z() > 0.0)) return 0.0;
    uv[k] = view.ProjectCam(p_in_cam);
    centroid += face.corners[k];
  }
  centroid /= static_cast<double>(face.corners.size());
  // The rectangle is what gets rectified; its corners lie outside a non-convex or slanted
  // polygon and, with a camera very close to the plane, may fall behind it: such a view
  // is skipped rather than sampled through a homography that flips sign.
  std::array<Eigen::Vector2d, 4> rect;
  const std::array<Eigen::Vector3d, 4> rect_in_world = face.RectangleInWorld();
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector3d p_in_cam = cam.CamFromWorld(rect_in_world[k]);
    if (!(p_in_cam.z() > 0.0)) return 0.0;
    rect[k] = view.ProjectCam(p_in_cam);
  }
  const Eigen::Vector3d center = cam.CenterInWorld();
  const Eigen::Vector3d to_camera = center - centroid;
  const double distance = to_camera.norm();
  if (!(distance > 0.0)) return 0.0;
  const double cosine = face.normal.dot(to_camera) / distance;
  if (!(cosine > 0.0)) return 0.0;
  const double area = VisibleArea(uv, view.photo->width, view.photo->height);
  if (!(area > kMinProjectedAreaPx2)) return 0.0;
  const double unoccluded = UnoccludedFraction(face, center, occluders);
  *length_u_px = std::max((rect[1] - rect[0]).norm(), (rect[2] - rect[3]).norm());
  *length_v_px = std::max((rect[3] - rect[0]).norm(), (rect[2] - rect[1]).norm());
  return area * cosine * unoccluded;
}

void SampleBilinear(const ImageRgba8& photo, double x, double y, std::uint8_t* out) {
  // Pixel centres are at integer coordinates; the photo covers [-0.5, w - 0.5].
  if (!(x >= -0.5 && x <= photo.width - 0.5 && y >= -0.5 && y <= photo.height - 0.5)) {
    out[0] = out[1] = out[2] = kOutsideGrey;
    out[3] = 255;
    return;
  }
  const double fx0 = std::floor(x), fy0 = std::floor(y);
  const double ax = x - fx0, ay = y - fy0;
  const int x0 = std::clamp(static_cast<int>(fx0), 0, photo.width - 1);
  const int y0 = std::clamp(static_cast<int>(fy0), 0, photo.height - 1);
  const int x1 = std::clamp(static_cast<int>(fx0) + 1, 0, photo.width - 1);
  const int y1 = std::clamp(static_cast<int>(fy0) + 1, 0, photo.height - 1);
  const std::uint8_t* p00 = photo.At(x0, y0);
  const std::uint8_t* p10 = photo.At(x1, y0);
  const std::uint8_t* p01 = photo.At(x0, y1);
  const std::uint8_t* p11 = photo.At(x1, y1);
  for (int c = 0; c < 4; ++c) {
    const double top = p00[c] + ax * (p10[c] - p00[c]);
    const double bottom = p01[c] + ax * (p11[c] - p01[c]);
    out[c] = static_cast<std::uint8_t>(std::clamp(top + ay * (bottom - top) + 0.5, 0.0, 255.0));
  }
}

// Face coordinates (s, t) of texel (i, j) of a w x h face texture: texel (0, 0) is the
// rectangle's (s_min, t_max) and texel (w - 1, h - 1) its (s_max, t_min), so the face reads
// upright as seen from outside. Returns the 3x3 map from (i, j, 1) to (s, t, 1).
Eigen::Matrix3d FaceFromTexel(const FaceGeometry& face, int width, int height) {
  const Eigen::Vector2d extent = face.st_max - face.st_min;
  Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
  m(0, 0) = extent.x() / (width - 1);
  m(0, 2) = face.st_min.x();
  m(1, 1) = -extent.y() / (height - 1);
  m(1, 2) = face.st_max.y();
  m(2, 2) = 1.0;
  return m;
}

// Rectifies the face's bounding rectangle into the atlas through the plane-to-photo
// homography H = P [axis_u, axis_v, origin; 0, 0, 1], then replicates the border into the
// padding. With lens distortion the homography gives the pinhole pixel of each texel, which
// is then distorted (Camera::DistortPixel, a polynomial: cheap per texel) before sampling.
void RasterizeFace(const FaceGeometry& face, const PhotoView& view, const FaceTexture& tex, int padding,
                   ImageRgba8* atlas) {
  const Eigen::Matrix<double, 3, 4> projection = view.camera->ProjectionMatrix();
  Eigen::Matrix3d photo_from_face;
  photo_from_face.col(0) = projection.leftCols<3>() * face.axis_u;
  photo_from_face.col(1) = projection.leftCols<3>() * face.axis_v;
  photo_from_face.col(2) = projection * face.origin.homogeneous();
  const Eigen::Matrix3d scale = Eigen::Vector3d(view.scale_x, view.scale_y, 1.0).asDiagonal();
  const int w = tex.packed_width, h = tex.packed_height;
  const Eigen::Matrix3d photo_from_texel = scale * photo_from_face * FaceFromTexel(face, w, h);

  if (view.camera->HasDistortion()) {
    const Eigen::Matrix3d pinhole_from_texel = photo_from_face * FaceFromTexel(face, w, h);
    for (int j = 0; j < h; ++j) {
      std::uint8_t* row = atlas->At(tex.x, tex.y + j);
      for (int i = 0; i < w; ++i) {
        const Eigen::Vector3d q = pinhole_from_texel * Eigen::Vector3d(i, j, 1.0);
        const Eigen::Vector2d uv = view.camera->DistortPixel(q.hnormalized());
        SampleBilinear(*view.photo, uv.x() * view.scale_x, uv.y() * view.scale_y, row + 4 * i);
      }
    }
  }
  for (int j = 0; j < h && !view.camera->HasDistortion(); ++j) {
    // Incremental along a row: q(i) = q(0) + i * column 0.
    Eigen::Vector3d q = photo_from_texel * Eigen::Vector3d(0.0, j, 1.0);
    const Eigen::Vector3d step = photo_from_texel.col(0);
    std::uint8_t* row = atlas->At(tex.x, tex.y + j);
    for (int i = 0; i < w; ++i, q += step) SampleBilinear(*view.photo, q.x() / q.z(), q.y() / q.z(), row + 4 * i);
  }
  for (int j = -padding; j < h + padding; ++j) {
    for (int i = -padding; i < w + padding; ++i) {
      if (i >= 0 && i < w && j >= 0 && j < h) continue;
      const std::uint8_t* src = atlas->At(tex.x + std::clamp(i, 0, w - 1), tex.y + std::clamp(j, 0, h - 1));
      std::copy(src, src + 4, atlas->At(tex.x + i, tex.y + j));
    }
  }
}

// Packs the padded rectangles into the smallest power-of-two atlas (w = h or w = 2h) up to
// max_size; returns false if they do not fit. Sets x, y of each face on success.
bool PackFaces(const std::vector<int>& textured, int padding, int max_size, std::vector<FaceTexture>* faces,
               int* atlas_width, int* atlas_height) {
  double total_area = 0.0;
  std::vector<stbrp_rect> rects(textured.size());
  for (size_t r = 0; r < textured.size(); ++r) {
    const FaceTexture& f = (*faces)[textured[r]];
    rects[r].id = static_cast<int>(r);
    rects[r].w = f.packed_width + 2 * padding;
    rects[r].h = f.packed_height + 2 * padding;
    total_area += static_cast<double>(rects[r].w) * rects[r].h;
  }
  std::vector<std::pair<int, int>> sizes;
  for (long s = kMinAtlasSize; s <= max_size; s *= 2) {
    if (s / 2 >= kMinAtlasSize) sizes.emplace_back(static_cast<int>(s), static_cast<int>(s / 2));
    sizes.emplace_back(static_cast<int>(s), static_cast<int>(s));
  }
  if (sizes.empty() || sizes.back().second != max_size) sizes.emplace_back(max_size, max_size);
  for (const auto& [w, h] : sizes) {
    if (static_cast<double>(w) * h < total_area) continue;
    std::vector<stbrp_node> nodes(w);
    stbrp_context context;
    stbrp_init_target(&context, w, h, nodes.data(), w);
    if (stbrp_pack_rects(&context, rects.data(), static_cast<int>(rects.size())) != 1) continue;
    for (const stbrp_rect& r : rects) {
      FaceTexture& f = (*faces)[textured[r.id]];
      f.x = r.x + padding;
      f.y = r.y + padding;
    }
    *atlas_width = w;
    *atlas_height = h;
    return true;
  }
  return false;
}

double ElapsedMs(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

// The face's plane frame, bounding rectangle and occlusion samples; valid stays false for a
// face without area.
void SetFaceFrame(const std::vector<std::array<Eigen::Vector3d, 3>>& triangles, FaceGeometry* g) {
  const size_t n = g->corners.size();
  if (n < 3 || g->normal.isZero()) return;
  // Best-fit plane: the Newell normal through the corners' centroid (exact for a planar face).
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : g->corners) centroid += p;
  centroid /= static_cast<double>(n);
  // u along the first edge; the longest edge instead when the first one has (almost) no
  // length in the plane.
  double radius = 0.0;
  for (const Eigen::Vector3d& p : g->corners) radius = std::max(radius, (p - centroid).norm());
  auto in_plane_edge = [&](size_t k) {
    const Eigen::Vector3d e = g->corners[(k + 1) % n] - g->corners[k];
    return Eigen::Vector3d(e - e.dot(g->normal) * g->normal);
  };
  Eigen::Vector3d u = in_plane_edge(0);
  if (!(u.norm() > 1e-9 * radius)) {
    for (size_t k = 1; k < n; ++k) {
      if (in_plane_edge(k).norm() > u.norm()) u = in_plane_edge(k);
    }
  }
  if (!(u.norm() > 0.0)) return;
  g->axis_u = u.normalized();
  g->axis_v = g->normal.cross(g->axis_u);
  g->origin = centroid;
  g->corners_st.resize(n);
  g->st_min = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  g->st_max = -g->st_min;
  for (size_t k = 0; k < n; ++k) {
    const Eigen::Vector3d d = g->corners[k] - centroid;
    g->corners_st[k] = Eigen::Vector2d(d.dot(g->axis_u), d.dot(g->axis_v));
    g->st_min = g->st_min.cwiseMin(g->corners_st[k]);
    g->st_max = g->st_max.cwiseMax(g->corners_st[k]);
  }
  const Eigen::Vector2d extent = g->st_max - g->st_min;
  const double size = extent.maxCoeff();
  if (!(extent.minCoeff() > 1e-12 * size) || !(std::abs(SignedArea(g->corners_st)) > 1e-12 * size * size)) return;
  g->valid = true;
  // A grid over the rectangle, kept where it falls inside the polygon; a sliver the grid
  // misses is sampled at its triangles' centroids instead.
  for (int i = 0; i < kOcclusionSamples; ++i) {
    for (int j = 0; j < kOcclusionSamples; ++j) {
      const Eigen::Vector2d st = g->st_min + Eigen::Vector2d((i + 0.5) / kOcclusionSamples * extent.x(),
                                                             (j + 0.5) / kOcclusionSamples * extent.y());
      if (InsidePolygon(g->corners_st, st)) g->occlusion_samples.push_back(g->InWorld(st));
    }
  }
  if (g->occlusion_samples.empty()) {
    for (const auto& tri : triangles) g->occlusion_samples.push_back((tri[0] + tri[1] + tri[2]) / 3.0);
  }
}

// Builds the untextured mesh and, alongside, the bake's view of every face and the
// occluders (one per primitive, in project order).
TexturedMesh BuildMesh(const Project& project, std::vector<FaceGeometry>* geometry, std::vector<Occluder>* occluders) {
  TexturedMesh mesh;
  for (size_t pi = 0; pi < project.primitives.size(); ++pi) {
    const Primitive& primitive = project.primitives[pi];
    const PolyMesh& poly = primitive.mesh;
    const MeshTriangulation triangulation = TriangulateMesh(poly);
    Occluder occluder;
    for (FaceId f = 0; f < poly.FaceIdEnd(); ++f) {
      if (!poly.IsFace(f)) continue;
      const std::vector<HalfedgeId> corners = FaceHalfedges(poly, f);
      FaceGeometry g;
      g.primitive_index = pi;
      g.normal = FaceNormal(poly, f);
      g.first_vertex = static_cast<std::uint32_t>(mesh.positions.size());
      g.first_triangle = mesh.triangle_face.size();
      const Eigen::Vector3f normal = g.normal.cast<float>();
      for (HalfedgeId h : corners) {
        const Eigen::Vector3d& p = poly.vertex(poly.Origin(h)).position;
        g.corners.push_back(p);
        mesh.positions.push_back(p.cast<float>());
        mesh.normals.push_back(normal);
        mesh.uvs.push_back(Eigen::Vector2f::Zero());
      }
      std::vector<std::array<Eigen::Vector3d, 3>> face_triangles;
      for (const CornerTriangle& tri : triangulation.by_face[f]) {
        std::array<Eigen::Vector3d, 3> world;
        for (int k = 0; k < 3; ++k) {
          const auto local = std::find(corners.begin(), corners.end(), tri[k]) - corners.begin();
          mesh.indices.push_back(g.first_vertex + static_cast<std::uint32_t>(local));
          world[k] = g.corners[local];
          occluder.lo = occluder.lo.cwiseMin(world[k]);
          occluder.hi = occluder.hi.cwiseMax(world[k]);
        }
        face_triangles.push_back(world);
        occluder.triangles.push_back(world);
        mesh.triangle_primitive.push_back(primitive.id);
        mesh.triangle_face.push_back(f);
        mesh.triangle_textured.push_back(0);
      }
      g.triangle_count = face_triangles.size();
      if (geometry != nullptr) {
        SetFaceFrame(face_triangles, &g);
        geometry->push_back(std::move(g));
      }
    }
    if (occluders != nullptr) occluders->push_back(std::move(occluder));
  }
  return mesh;
}

// The calibrated images with loaded pixels, with the scale from the camera's pixels to the photo's.
std::vector<PhotoView> UsableViews(const Project& project, const std::vector<const ImageRgba8*>& photos) {
  std::vector<PhotoView> views;
  for (size_t i = 0; i < project.images.size(); ++i) {
    const Image& image = project.images[i];
    if (photos[i] == nullptr) continue;
    const ImageRgba8& photo = *photos[i];
    if (!image.camera_calibrated || photo.empty() ||
        photo.pixels.size() != static_cast<size_t>(photo.width) * photo.height * 4) {
      continue;
    }
    PhotoView view;
    view.image_index = i;
    view.camera = &image.camera;
    view.photo = &photo;
    const int ref_width = image.camera.width_px > 0 ? image.camera.width_px : image.width_px;
    const int ref_height = image.camera.height_px > 0 ? image.camera.height_px : image.height_px;
    if (ref_width > 0 && ref_height > 0) {
      view.scale_x = static_cast<double>(photo.width) / ref_width;
      view.scale_y = static_cast<double>(photo.height) / ref_height;
    }
    views.push_back(view);
  }
  return views;
}

// Each face's best-scoring view and its texel size; returns the faces some view sees.
std::vector<int> ChooseFaceViews(const std::vector<FaceGeometry>& geometry, const std::vector<PhotoView>& views,
                                 const std::vector<Occluder>& occluders, const TextureBakeOptions& options,
                                 std::vector<FaceTexture>* faces_out) {
  std::vector<FaceTexture>& faces = *faces_out;
  std::vector<int> textured;
  for (size_t f = 0; f < geometry.size(); ++f) {
    if (!geometry[f].valid) continue;
    double best_u = 0.0, best_v = 0.0;
    for (size_t v = 0; v < views.size(); ++v) {
      double length_u = 0.0, length_v = 0.0;
      const double score = ScoreView(geometry[f], views[v], occluders, &length_u, &length_v);
      if (score > faces[f].score) {
        faces[f].score = score;
        faces[f].view = static_cast<int>(v);
        best_u = length_u;
        best_v = length_v;
      }
    }
    if (faces[f].view < 0) continue;
    auto texels = [&](double length_px) {
      const double n = std::ceil(length_px * options.texels_per_image_px) + 1.0;
      return static_cast<int>(
          std::clamp(n, static_cast<double>(kMinFaceTexels), static_cast<double>(options.max_face_texels)));
    };
    faces[f].width = texels(best_u);
    faces[f].height = texels(best_v);
    textured.push_back(static_cast<int>(f));
  }
  return textured;
}

// Rasterises each textured face into its packed rectangle and points its corners' UVs there.
void WriteAtlas(const std::vector<FaceGeometry>& geometry, const std::vector<PhotoView>& views,
                const std::vector<int>& textured, const std::vector<FaceTexture>& faces,
                const TextureBakeOptions& options, int atlas_width, int atlas_height, TexturedMesh* mesh) {
  ImageRgba8& atlas = mesh->atlas;
  atlas.width = atlas_width;
  atlas.height = atlas_height;
  atlas.pixels.assign(static_cast<size_t>(atlas_width) * atlas_height * 4, 0);
  for (int f : textured) {
    const FaceTexture& t = faces[f];
    const FaceGeometry& g = geometry[f];
    RasterizeFace(g, views[t.view], t, options.padding_texels, &atlas);
    const Eigen::Matrix3d texel_from_face = FaceFromTexel(g, t.packed_width, t.packed_height).inverse();
    for (size_t k = 0; k < g.corners_st.size(); ++k) {
      const Eigen::Vector3d texel = texel_from_face * g.corners_st[k].homogeneous();
      mesh->uvs[g.first_vertex + k] = Eigen::Vector2f(static_cast<float>((t.x + texel.x() + 0.5) / atlas_width),
                                                      static_cast<float>((t.y + texel.y() + 0.5) / atlas_height));
    }
    for (size_t tri = 0; tri < g.triangle_count; ++tri) mesh->triangle_textured[g.first_triangle + tri] = 1;
  }
}

}  // namespace

TexturedMesh BuildUntexturedMesh(const Project& project) { return BuildMesh(project, nullptr, nullptr); }

bool TextureBakeOptions::Check(std::string* error) const {
  std::string message;
  if (!(std::isfinite(texels_per_image_px) && texels_per_image_px > 0.0 && texels_per_image_px <= 16.0)) {
    message = "texels_per_image_px must be in (0, 16], got " + std::to_string(texels_per_image_px);
  } else if (max_face_texels < kMinFaceTexels) {
    message = "max_face_texels must be at least " + std::to_string(kMinFaceTexels) + ", got " +
              std::to_string(max_face_texels);
  } else if (padding_texels < 0 || padding_texels > 64) {
    message = "padding_texels must be in [0, 64], got " + std::to_string(padding_texels);
  } else if (max_atlas_size < kMinAtlasSize || max_atlas_size > 16384) {
    message = "max_atlas_size must be in [" + std::to_string(kMinAtlasSize) + ", 16384], got " +
              std::to_string(max_atlas_size);
  }
  if (error != nullptr) *error = message;
  return message.empty();
}

TextureBakeSummary BakeTexturedMesh(const Project& project, const std::vector<const ImageRgba8*>& photos,
                                    const TextureBakeOptions& options, TexturedMesh* mesh) {
  const auto start = std::chrono::steady_clock::now();
  TextureBakeSummary summary;
  std::vector<FaceGeometry> geometry;
  std::vector<Occluder> occluders;
  *mesh = BuildMesh(project, &geometry, &occluders);
  const int face_count = static_cast<int>(geometry.size());
  summary.faces_untextured = face_count;
  auto fail = [&](const std::string& message, SolverTermination termination = SolverTermination::kFailed) {
    summary.termination = termination;
    summary.message = message;
    summary.time_ms = ElapsedMs(start);
    return summary;
  };
  std::string error;
  if (!options.Check(&error)) return fail("invalid texture options: " + error, SolverTermination::kInvalidInput);
  if (photos.size() != project.images.size()) {
    return fail("got " + std::to_string(photos.size()) + " photos for " + std::to_string(project.images.size()) +
                " images",
                SolverTermination::kInvalidInput);
  }

  const std::vector<PhotoView> views = UsableViews(project, photos);

  std::vector<FaceTexture> faces(geometry.size());
  const std::vector<int> textured = ChooseFaceViews(geometry, views, occluders, options, &faces);
  if (textured.empty()) {
    summary.termination = SolverTermination::kConverged;
    summary.message = geometry.empty() ? "the project has no primitives"
                      : views.empty()  ? "no calibrated image with loaded pixels; the mesh is untextured"
                                       : "no face is seen by a calibrated image; the mesh is untextured";
    summary.time_ms = ElapsedMs(start);
    return summary;
  }

  // Shrink every face by the same factor until the atlas fits.
  double shrink = 1.0;
  int atlas_width = 0, atlas_height = 0;
  for (;;) {
    bool all_minimal = true;
    for (int f : textured) {
      FaceTexture& t = faces[f];
      t.packed_width = std::max(kMinFaceTexels, static_cast<int>(std::lround(t.width * shrink)));
      t.packed_height = std::max(kMinFaceTexels, static_cast<int>(std::lround(t.height * shrink)));
      all_minimal = all_minimal && t.packed_width == kMinFaceTexels && t.packed_height == kMinFaceTexels;
    }
    if (PackFaces(textured, options.padding_texels, options.max_atlas_size, &faces, &atlas_width, &atlas_height)) break;
    if (all_minimal) {
      return fail(std::to_string(textured.size()) + " faces do not fit a " + std::to_string(options.max_atlas_size) +
                  " atlas even at " + std::to_string(kMinFaceTexels) + " texels per side");
    }
    shrink *= 0.85;
  }

  WriteAtlas(geometry, views, textured, faces, options, atlas_width, atlas_height, mesh);

  summary.termination = SolverTermination::kConverged;
  summary.faces_textured = static_cast<int>(textured.size());
  summary.faces_untextured = face_count - summary.faces_textured;
  summary.atlas_width = atlas_width;
  summary.atlas_height = atlas_height;
  summary.time_ms = ElapsedMs(start);
  summary.message = "textured " + std::to_string(summary.faces_textured) + " of " + std::to_string(face_count) +
                    " faces into a " + std::to_string(atlas_width) + "x" + std::to_string(atlas_height) + " atlas" +
                    (shrink < 1.0 ? " (faces shrunk to fit)" : "");
  return summary;
}

TextureBakeSummary BakeTexturedMesh(const Project& project, const std::vector<ImageRgba8>& photos,
                                    const TextureBakeOptions& options, TexturedMesh* mesh) {
  std::vector<const ImageRgba8*> pointers;
  pointers.reserve(photos.size());
  for (const ImageRgba8& photo : photos) pointers.push_back(&photo);
  return BakeTexturedMesh(project, pointers, options, mesh);
}

}  // namespace facet
