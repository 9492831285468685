// A camera's view of the model as a CPU z-buffer (core has no GL): per map pixel, the camera
// depth of the nearest triangle and the face it belongs to, plus each pixel's distance to the
// nearest visibility boundary (the photo's border, the model's silhouette, a depth step), which
// the texture bake uses to feather a view's weight. The map lives in the pinhole image of the
// camera's K (lens distortion does not bend the triangles' edges there): map pixel (i, j)
// covers map coordinates [i, i + 1) x [j, j + 1), and map = (uv_pinhole - origin) * scale for
// camera pixels uv_pinhole (core/geometry/conventions.h: pixel centres at integers).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "core/geometry/camera.h"

namespace facet {

struct DepthTriangle {
  std::array<Eigen::Vector3d, 3> corners_in_world;
  std::int32_t face = -1;  // the caller's face index, what DepthMap::face holds
};

struct DepthMapOptions {
  // Map pixels per photo pixel (0.5: a 4000 x 3000 photo gets a 2000 x 1500 map).
  double scale = 0.5;
  // Neighbouring map pixels whose depths differ by more than this fraction of the nearer one
  // are a depth step (an occluder's outline): a visibility boundary.
  double depth_step_relative = 0.05;
};

struct DepthMap {
  int width = 0;
  int height = 0;
  Eigen::Vector2d origin_px = Eigen::Vector2d::Zero();  // camera pinhole px of map coordinate (0, 0)
  Eigen::Vector2d scale = Eigen::Vector2d::Ones();      // map px per camera px, per axis
  double photo_px_per_map_px = 1.0;                     // for distances in photo pixels
  std::vector<float> depth;                             // camera z; +inf where no triangle
  std::vector<std::int32_t> face;                       // -1 where no triangle
  // Per pixel: distance in photo px to the nearest boundary pixel (outside the photo, no
  // triangle, or on either side of a depth step); 0 on a boundary pixel.
  std::vector<float> boundary_distance_px;

  Eigen::Vector2d MapFromPinhole(const Eigen::Vector2d& uv_pinhole_px) const {
    return (uv_pinhole_px - origin_px).cwiseProduct(scale);
  }
  // Whether a point of face `face_index` at camera depth `depth_z` and pinhole pixel
  // `uv_pinhole_px` is seen: each of the 2 x 2 map pixels a bilinear lookup at that spot
  // reads either shows the same face or nothing nearer than depth_z - tolerance. Conservative
  // by up to a map pixel at an occluder's outline, so the photo pixels a sample there blends
  // hold no occluder. False outside the map.
  // (Both are defined here, inline: the bake calls them for every texel and view.)
  bool Sees(const Eigen::Vector2d& uv_pinhole_px, double depth_z, std::int32_t face_index, double tolerance) const {
    const Eigen::Vector2d m = MapFromPinhole(uv_pinhole_px);
    if (!(m.x() >= 0.0 && m.y() >= 0.0 && m.x() < width && m.y() < height)) return false;
    // The 2 x 2 pixels whose centres surround m (clamped at the map's edge).
    const int i0 = std::clamp(static_cast<int>(std::floor(m.x() - 0.5)), 0, width - 1);
    const int j0 = std::clamp(static_cast<int>(std::floor(m.y() - 0.5)), 0, height - 1);
    const int i1 = std::min(i0 + 1, width - 1), j1 = std::min(j0 + 1, height - 1);
    const float limit = static_cast<float>(depth_z - tolerance);
    for (int j : {j0, j1}) {
      for (int i : {i0, i1}) {
        const size_t k = static_cast<size_t>(j) * width + i;
        if (face[k] != face_index && depth[k] < limit) return false;
      }
    }
    return true;
  }
  // boundary_distance_px at the map pixel holding the point (0 outside the map).
  float BoundaryDistancePx(const Eigen::Vector2d& uv_pinhole_px) const {
    const Eigen::Vector2d m = MapFromPinhole(uv_pinhole_px);
    if (!(m.x() >= 0.0 && m.y() >= 0.0 && m.x() < width && m.y() < height)) return 0.0f;
    return boundary_distance_px[static_cast<size_t>(m.y()) * width + static_cast<size_t>(m.x())];
  }
};

// Renders the triangles seen by `camera` into a map covering the photo of
// photo_width_px x photo_height_px at options.scale of its resolution. The loaded photo may
// have another size than the one the intrinsics refer to: photo_px_per_camera_px (x, y) maps
// camera pixels to the photo's.
// Triangles are rasterised at pixel centres, depth interpolated as 1/z (exact for planes),
// both orientations (an open surface seen from behind still hides what is behind it), clipped
// at a near plane of 1e-6 times the farthest corner depth. With lens distortion the map covers
// the pinhole image of the whole photo, and map pixels whose centre falls outside the photo
// are boundary pixels. The boundary distance is a 3-4 chamfer distance (within 8 % of the
// Euclidean one).
DepthMap RenderDepthMap(const std::vector<DepthTriangle>& triangles, const Camera& camera, int photo_width_px,
                        int photo_height_px, const Eigen::Vector2d& photo_px_per_camera_px,
                        const DepthMapOptions& options);

}  // namespace facet
