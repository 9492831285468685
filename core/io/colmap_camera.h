// COLMAP's cameras <-> Facet's (core/geometry/camera.h), exactly or not at all.
//
// Pixels: COLMAP puts the centre of the top-left pixel at (0.5, 0.5), Facet at (0, 0)
// (core/geometry/conventions.h), so a COLMAP pixel coordinate is Facet's + 0.5. This file is
// the one place that offset is applied (principal points here, 2D points through
// FacetPixelFromColmap).
//
// Models: Facet's camera is one focal length (square pixels, no skew), a principal point and
// OpenCV's radial k1, k2. Mapped exactly:
//   SIMPLE_PINHOLE  f, cx, cy                  -> k1 = k2 = 0
//   PINHOLE         fx, fy, cx, cy             with fx == fy
//   SIMPLE_RADIAL   f, cx, cy, k               -> k1 = k, k2 = 0
//   RADIAL          f, cx, cy, k1, k2
//   OPENCV          fx, fy, cx, cy, k1, k2, p1, p2   with fx == fy and p1 == p2 == 0
// Every other model (the fisheyes, FOV, FULL_OPENCV, THIN_PRISM) and a PINHOLE or OPENCV
// camera outside those conditions is refused, by name and reason.
#pragma once

#include <string>

#include <Eigen/Core>

#include "core/geometry/camera.h"
#include "core/io/colmap_model.h"

namespace facet {

// Relative difference between fx and fy up to which a PINHOLE or OPENCV camera counts as having
// square pixels: the rounding of a text file's 17 digits, not a photo's aspect error.
constexpr double kColmapSquarePixelTolerance = 1e-12;

inline Eigen::Vector2d FacetPixelFromColmap(const Eigen::Vector2d& xy_colmap) {
  return xy_colmap - Eigen::Vector2d(0.5, 0.5);
}
inline Eigen::Vector2d ColmapPixelFromFacet(const Eigen::Vector2d& uv_px) { return uv_px + Eigen::Vector2d(0.5, 0.5); }

// The intrinsics of `colmap` (width, height, focal, principal point, k1, k2) written into
// *camera; its pose is left as it was. "" on success, else why the model cannot be mapped
// (naming it); *camera is then unchanged.
std::string FacetIntrinsicsFromColmap(const ColmapCamera& colmap, Camera* camera);

// The pose of `image` as Facet's cam_from_world rotation and translation, written into *camera.
void SetFacetPoseFromColmap(const ColmapImage& image, Camera* camera);

// The COLMAP camera for Facet's intrinsics: SIMPLE_PINHOLE without distortion, SIMPLE_RADIAL
// with k2 == 0, RADIAL otherwise (so it reads back exactly).
ColmapCamera ColmapCameraFromFacet(const Camera& camera, std::uint32_t camera_id);

}  // namespace facet
