#include "core/io/colmap_camera.h"

#include <cmath>
#include <limits>

#include <Eigen/Geometry>

namespace facet {
namespace {

bool SquarePixels(double fx, double fy) {
  return std::abs(fx - fy) <= kColmapSquarePixelTolerance * std::max(std::abs(fx), std::abs(fy));
}

}  // namespace

std::string FacetIntrinsicsFromColmap(const ColmapCamera& colmap, Camera* camera) {
  const std::string name =
      std::string(ColmapCameraModelName(colmap.model)) + " camera " + std::to_string(colmap.camera_id);
  const std::vector<double>& p = colmap.params;
  if (static_cast<int>(p.size()) != ColmapCameraModelNumParams(colmap.model))
    return name + " has " + std::to_string(p.size()) + " parameters";
  constexpr std::uint64_t kMaxSide = std::numeric_limits<int>::max();
  if (colmap.width_px == 0 || colmap.height_px == 0 || colmap.width_px > kMaxSide || colmap.height_px > kMaxSide)
    return name + " has an image size Facet cannot hold";
  double f = 0.0, cx = 0.0, cy = 0.0, k1 = 0.0, k2 = 0.0;
  switch (colmap.model) {
    case ColmapCameraModel::kSimplePinhole: f = p[0], cx = p[1], cy = p[2]; break;
    case ColmapCameraModel::kPinhole:
      if (!SquarePixels(p[0], p[1]))
        return name + " has fx != fy (" + std::to_string(p[0]) + ", " + std::to_string(p[1]) +
               "): Facet's cameras have square pixels";
      f = p[0], cx = p[2], cy = p[3];
      break;
    case ColmapCameraModel::kSimpleRadial: f = p[0], cx = p[1], cy = p[2], k1 = p[3]; break;
    case ColmapCameraModel::kRadial: f = p[0], cx = p[1], cy = p[2], k1 = p[3], k2 = p[4]; break;
    case ColmapCameraModel::kOpenCv:
      if (!SquarePixels(p[0], p[1]))
        return name + " has fx != fy (" + std::to_string(p[0]) + ", " + std::to_string(p[1]) +
               "): Facet's cameras have square pixels";
      if (p[6] != 0.0 || p[7] != 0.0)
        return name + " has tangential distortion (p1 = " + std::to_string(p[6]) + ", p2 = " + std::to_string(p[7]) +
               "): Facet's lens model is radial only";
      f = p[0], cx = p[2], cy = p[3], k1 = p[4], k2 = p[5];
      break;
    default:
      return name +
             ": Facet's camera (a focal length, a principal point, radial k1, k2) cannot represent this "
             "model; re-run COLMAP with SIMPLE_RADIAL, RADIAL or OPENCV";
  }
  for (double x : p)
    if (!std::isfinite(x)) return name + " has a parameter that is not a number";
  if (!(f > 0.0)) return name + " has a focal length that is not positive";
  camera->width_px = static_cast<int>(colmap.width_px);
  camera->height_px = static_cast<int>(colmap.height_px);
  camera->focal_px = f;
  camera->principal_point_px = FacetPixelFromColmap(Eigen::Vector2d(cx, cy));
  camera->k1 = k1;
  camera->k2 = k2;
  return "";
}

void SetFacetPoseFromColmap(const ColmapImage& image, Camera* camera) {
  camera->cam_from_world_rotation = image.cam_from_world_rotation.normalized().toRotationMatrix();
  camera->cam_from_world_translation = image.cam_from_world_translation;
}

ColmapCamera ColmapCameraFromFacet(const Camera& camera, std::uint32_t camera_id) {
  ColmapCamera colmap;
  colmap.camera_id = camera_id;
  colmap.width_px = static_cast<std::uint64_t>(std::max(camera.width_px, 0));
  colmap.height_px = static_cast<std::uint64_t>(std::max(camera.height_px, 0));
  const Eigen::Vector2d c = ColmapPixelFromFacet(camera.principal_point_px);
  if (!camera.HasDistortion()) {
    colmap.model = ColmapCameraModel::kSimplePinhole;
    colmap.params = {camera.focal_px, c.x(), c.y()};
  } else if (camera.k2 == 0.0) {
    colmap.model = ColmapCameraModel::kSimpleRadial;
    colmap.params = {camera.focal_px, c.x(), c.y(), camera.k1};
  } else {
    colmap.model = ColmapCameraModel::kRadial;
    colmap.params = {camera.focal_px, c.x(), c.y(), camera.k1, camera.k2};
  }
  return colmap;
}

}  // namespace facet
