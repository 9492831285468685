#include "core/texture/depth_map.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace facet {
namespace {

constexpr float kInfinity = std::numeric_limits<float>::infinity();
constexpr double kNearFraction = 1e-6;
// Photo border samples per side when finding the pinhole image of a distorted photo.
constexpr int kBorderSamples = 64;
// Chamfer weights for orthogonal and diagonal steps (3-4: within 8 % of Euclidean).
constexpr float kOrthogonal = 3.0f;
constexpr float kDiagonal = 4.0f;

struct MapVertex {
  Eigen::Vector2d m;  // map coordinates
  double inv_z = 0.0;
};

double Edge(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& p) {
  return (b.x() - a.x()) * (p.y() - a.y()) - (b.y() - a.y()) * (p.x() - a.x());
}

void RasterizeTriangle(const MapVertex& v0, const MapVertex& v1, const MapVertex& v2, std::int32_t face,
                       DepthMap* map) {
  const double area = Edge(v0.m, v1.m, v2.m);
  if (!(std::abs(area) > 1e-12)) return;
  const double inv_area = 1.0 / area;
  const double x_lo = std::min({v0.m.x(), v1.m.x(), v2.m.x()});
  const double x_hi = std::max({v0.m.x(), v1.m.x(), v2.m.x()});
  const double y_lo = std::min({v0.m.y(), v1.m.y(), v2.m.y()});
  const double y_hi = std::max({v0.m.y(), v1.m.y(), v2.m.y()});
  // Pixel i's centre is at i + 0.5.
  const int i0 = std::max(0, static_cast<int>(std::ceil(x_lo - 0.5)));
  const int i1 = std::min(map->width - 1, static_cast<int>(std::floor(x_hi - 0.5)));
  const int j0 = std::max(0, static_cast<int>(std::ceil(y_lo - 0.5)));
  const int j1 = std::min(map->height - 1, static_cast<int>(std::floor(y_hi - 0.5)));
  if (i0 > i1 || j0 > j1) return;
  // Barycentric coordinates are affine in the pixel position: step them along a row.
  const Eigen::Vector2d start(i0 + 0.5, j0 + 0.5);
  const double b0_start = Edge(v1.m, v2.m, start) * inv_area, b1_start = Edge(v2.m, v0.m, start) * inv_area;
  const double b0_dx = -(v2.m.y() - v1.m.y()) * inv_area, b0_dy = (v2.m.x() - v1.m.x()) * inv_area;
  const double b1_dx = -(v0.m.y() - v2.m.y()) * inv_area, b1_dy = (v0.m.x() - v2.m.x()) * inv_area;
  constexpr double kInsideSlack = -1e-9;  // shared edges belong to both triangles
  for (int j = j0; j <= j1; ++j) {
    double b0 = b0_start + (j - j0) * b0_dy, b1 = b1_start + (j - j0) * b1_dy;
    float* depth = &map->depth[static_cast<size_t>(j) * map->width];
    std::int32_t* faces = &map->face[static_cast<size_t>(j) * map->width];
    for (int i = i0; i <= i1; ++i, b0 += b0_dx, b1 += b1_dx) {
      const double b2 = 1.0 - b0 - b1;
      if (b0 < kInsideSlack || b1 < kInsideSlack || b2 < kInsideSlack) continue;
      const double inv_z = b0 * v0.inv_z + b1 * v1.inv_z + b2 * v2.inv_z;
      if (!(inv_z > 0.0)) continue;
      const float z = static_cast<float>(1.0 / inv_z);
      if (z < depth[i]) {
        depth[i] = z;
        faces[i] = face;
      }
    }
  }
}

// Sutherland-Hodgman against z >= near in the camera frame.
std::vector<Eigen::Vector3d> ClipNear(const std::array<Eigen::Vector3d, 3>& tri, double near_z) {
  std::vector<Eigen::Vector3d> out;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d& a = tri[k];
    const Eigen::Vector3d& b = tri[(k + 1) % 3];
    const double da = a.z() - near_z, db = b.z() - near_z;
    if (da >= 0) out.push_back(a);
    if ((da < 0 && db > 0) || (da > 0 && db < 0)) out.push_back(a + (b - a) * (da / (da - db)));
  }
  return out;
}

// Seeds (outside the photo, no triangle, either side of a depth step) get 0, then two chamfer
// passes; the map's own border counts as a boundary just outside it. The passes run over a
// copy framed by one pixel of 0 (that border), so the inner loops carry no bounds tests: they
// were most of the depth-map step's time on a 2000 x 1500 map.
void BoundaryDistances(const std::vector<std::uint8_t>& outside_photo, double depth_step, DepthMap* map) {
  const int w = map->width, h = map->height;
  const int stride = w + 2;
  std::vector<float> framed(static_cast<size_t>(stride) * (h + 2), 0.0f);
  auto step = [&](float a, float b) {
    const float nearer = std::min(a, b);
    return std::abs(a - b) > depth_step * nearer;  // inf vs finite counts too
  };
  for (int j = 0; j < h; ++j) {
    const float* z_row = &map->depth[static_cast<size_t>(j) * w];
    const std::uint8_t* outside_row = &outside_photo[static_cast<size_t>(j) * w];
    float* d = &framed[static_cast<size_t>(j + 1) * stride + 1];
    for (int i = 0; i < w; ++i) {
      const float z = z_row[i];
      bool seed = outside_row[i] != 0 || z == kInfinity;
      if (!seed && i + 1 < w && step(z, z_row[i + 1])) seed = true;
      if (!seed && i > 0 && step(z, z_row[i - 1])) seed = true;
      if (!seed && j + 1 < h && step(z, z_row[i + w])) seed = true;
      if (!seed && j > 0 && step(z, z_row[i - w])) seed = true;
      d[i] = seed ? 0.0f : std::numeric_limits<float>::max();
    }
  }
  for (int j = 1; j <= h; ++j) {
    float* row = &framed[static_cast<size_t>(j) * stride];
    const float* above = row - stride;
    for (int i = 1; i <= w; ++i) {
      // The row before last: only the step from row[i - 1] waits for the previous pixel.
      float v = std::min(std::min(row[i], above[i] + kOrthogonal),
                         std::min(above[i - 1] + kDiagonal, above[i + 1] + kDiagonal));
      row[i] = std::min(v, row[i - 1] + kOrthogonal);
    }
  }
  for (int j = h; j >= 1; --j) {
    float* row = &framed[static_cast<size_t>(j) * stride];
    const float* below = row + stride;
    for (int i = w; i >= 1; --i) {
      float v = std::min(std::min(row[i], below[i] + kOrthogonal),
                         std::min(below[i + 1] + kDiagonal, below[i - 1] + kDiagonal));
      row[i] = std::min(v, row[i + 1] + kOrthogonal);
    }
  }
  const float to_photo_px = static_cast<float>(map->photo_px_per_map_px) / kOrthogonal;
  map->boundary_distance_px.resize(static_cast<size_t>(w) * h);
  for (int j = 0; j < h; ++j) {
    const float* d = &framed[static_cast<size_t>(j + 1) * stride + 1];
    float* out = &map->boundary_distance_px[static_cast<size_t>(j) * w];
    for (int i = 0; i < w; ++i) out[i] = d[i] * to_photo_px;
  }
}

}  // namespace

DepthMap RenderDepthMap(const std::vector<DepthTriangle>& triangles, const Camera& camera, int photo_width_px,
                        int photo_height_px, const Eigen::Vector2d& photo_px_per_camera_px,
                        const DepthMapOptions& options) {
  DepthMap map;
  if (photo_width_px <= 0 || photo_height_px <= 0 || !(options.scale > 0.0)) return map;
  // The photo in camera pixels.
  const Eigen::Vector2d camera_size(photo_width_px / photo_px_per_camera_px.x(),
                                    photo_height_px / photo_px_per_camera_px.y());
  Eigen::Vector2d lo(-0.5, -0.5);
  Eigen::Vector2d hi = camera_size - Eigen::Vector2d(0.5, 0.5);
  if (camera.HasDistortion()) {
    // The pinhole image of the photo's border, capped at three photo sizes around it (a model
    // fitted inside the photo may fold outside it).
    const Eigen::Vector2d photo_lo = lo, photo_hi = hi;
    lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
    hi = -lo;
    for (int k = 0; k <= kBorderSamples; ++k) {
      const double t = static_cast<double>(k) / kBorderSamples;
      for (const Eigen::Vector2d& p :
           {Eigen::Vector2d(photo_lo.x() + t * (photo_hi.x() - photo_lo.x()), photo_lo.y()),
            Eigen::Vector2d(photo_lo.x() + t * (photo_hi.x() - photo_lo.x()), photo_hi.y()),
            Eigen::Vector2d(photo_lo.x(), photo_lo.y() + t * (photo_hi.y() - photo_lo.y())),
            Eigen::Vector2d(photo_hi.x(), photo_lo.y() + t * (photo_hi.y() - photo_lo.y()))}) {
        const Eigen::Vector2d q = camera.UndistortPixel(p);
        lo = lo.cwiseMin(q);
        hi = hi.cwiseMax(q);
      }
    }
    lo = lo.cwiseMax(photo_lo - camera_size);
    hi = hi.cwiseMin(photo_hi + camera_size);
  }
  const Eigen::Vector2d extent = hi - lo;
  map.width = std::max(1, static_cast<int>(std::ceil(extent.x() * photo_px_per_camera_px.x() * options.scale)));
  map.height = std::max(1, static_cast<int>(std::ceil(extent.y() * photo_px_per_camera_px.y() * options.scale)));
  map.origin_px = lo;
  map.scale = Eigen::Vector2d(map.width / extent.x(), map.height / extent.y());
  map.photo_px_per_map_px = 1.0 / options.scale;
  const size_t pixels = static_cast<size_t>(map.width) * map.height;
  map.depth.assign(pixels, kInfinity);
  map.face.assign(pixels, -1);

  double far_z = 0.0;
  for (const DepthTriangle& tri : triangles) {
    for (const Eigen::Vector3d& p : tri.corners_in_world) far_z = std::max(far_z, camera.CamFromWorld(p).z());
  }
  const double near_z = kNearFraction * far_z;
  const Eigen::Matrix3d& r = camera.cam_from_world_rotation;
  const Eigen::Vector3d& t = camera.cam_from_world_translation;
  auto to_map = [&](const Eigen::Vector3d& p_in_cam) {
    MapVertex v;
    const Eigen::Vector2d uv(camera.focal_px * p_in_cam.x() / p_in_cam.z() + camera.principal_point_px.x(),
                             camera.focal_px * p_in_cam.y() / p_in_cam.z() + camera.principal_point_px.y());
    v.m = map.MapFromPinhole(uv);
    v.inv_z = 1.0 / p_in_cam.z();
    return v;
  };
  for (const DepthTriangle& tri : triangles) {
    const std::array<Eigen::Vector3d, 3> in_cam = {r * tri.corners_in_world[0] + t, r * tri.corners_in_world[1] + t,
                                                   r * tri.corners_in_world[2] + t};
    if (in_cam[0].z() < near_z && in_cam[1].z() < near_z && in_cam[2].z() < near_z) continue;
    const std::vector<Eigen::Vector3d> clipped = ClipNear(in_cam, near_z);
    if (clipped.size() < 3) continue;
    const MapVertex first = to_map(clipped[0]);
    for (size_t k = 1; k + 1 < clipped.size(); ++k) {
      RasterizeTriangle(first, to_map(clipped[k]), to_map(clipped[k + 1]), tri.face, &map);
    }
  }

  std::vector<std::uint8_t> outside_photo(pixels, 0);
  if (camera.HasDistortion()) {
    const Eigen::Vector2d photo_hi = camera_size - Eigen::Vector2d(0.5, 0.5);
    for (int j = 0; j < map.height; ++j) {
      for (int i = 0; i < map.width; ++i) {
        const Eigen::Vector2d pinhole = lo + Eigen::Vector2d(i + 0.5, j + 0.5).cwiseQuotient(map.scale);
        const Eigen::Vector2d uv = camera.DistortPixel(pinhole);
        outside_photo[static_cast<size_t>(j) * map.width + i] =
            !(uv.x() >= -0.5 && uv.y() >= -0.5 && uv.x() <= photo_hi.x() && uv.y() <= photo_hi.y());
      }
    }
  }
  BoundaryDistances(outside_photo, options.depth_step_relative, &map);
  return map;
}

}  // namespace facet
