#include "app/state/orbit_camera.h"

#include <algorithm>
#include <cmath>

namespace facet::app {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kMaxPitchRad = 89.0 * kPi / 180.0;
constexpr double kRotateRadPerPx = 0.008;
constexpr double kZoomPerStep = 0.15;

Eigen::Vector3d EyeDirection(double yaw_rad, double pitch_rad) {
  return {std::cos(pitch_rad) * std::cos(yaw_rad), std::cos(pitch_rad) * std::sin(yaw_rad), std::sin(pitch_rad)};
}

double FocalPx(double fov_y_deg, int height_px) {
  return 0.5 * std::max(1, height_px) / std::tan(0.5 * fov_y_deg * kPi / 180.0);
}

}  // namespace

Eigen::Vector3d EyeOf(const OrbitCamera& orbit) {
  if (orbit.photo_image_id != kNoId) return orbit.photo_camera.CenterInWorld();
  return orbit.target + orbit.distance * EyeDirection(orbit.yaw_rad, orbit.pitch_rad);
}

Camera ViewCameraOf(const OrbitCamera& orbit, int width_px, int height_px) {
  if (orbit.photo_image_id != kNoId) return orbit.photo_camera;
  Camera camera;
  camera.width_px = std::max(1, width_px);
  camera.height_px = std::max(1, height_px);
  camera.focal_px = FocalPx(orbit.fov_y_deg, camera.height_px);
  camera.principal_point_px = Eigen::Vector2d((camera.width_px - 1) / 2.0, (camera.height_px - 1) / 2.0);
  // The pitch clamp keeps forward off world Z, so the camera's right axis is well defined.
  const Eigen::Vector3d forward = -EyeDirection(orbit.yaw_rad, orbit.pitch_rad);
  const Eigen::Matrix3d cam_from_world = CamFromWorldLookingAlong(forward);
  camera.SetPose(cam_from_world, EyeOf(orbit));
  return camera;
}

void OrbitLeavePhotoView(OrbitCamera* orbit, int width_px, int height_px) {
  if (orbit->photo_image_id == kNoId) return;
  const Camera& photo = orbit->photo_camera;
  // Keep the photo's apparent scale: its focal length as the panel shows it (fitted).
  const double image_w = photo.width_px > 0 ? photo.width_px : std::max(1, width_px);
  const double image_h = photo.height_px > 0 ? photo.height_px : std::max(1, height_px);
  const double fit = std::min(std::max(1, width_px) / image_w, std::max(1, height_px) / image_h);
  const double focal_in_panel_px = std::max(1e-6, fit * photo.focal_px);
  orbit->fov_y_deg =
      std::clamp(2.0 * std::atan(0.5 * std::max(1, height_px) / focal_in_panel_px) * 180.0 / kPi, 5.0, 120.0);
  orbit->photo_image_id = kNoId;
}

void OrbitRotate(OrbitCamera* orbit, double dx_px, double dy_px, int width_px, int height_px) {
  OrbitLeavePhotoView(orbit, width_px, height_px);
  // As if grabbing the model: dragging right turns its front to the right.
  orbit->yaw_rad = std::remainder(orbit->yaw_rad - dx_px * kRotateRadPerPx, 2.0 * kPi);
  orbit->pitch_rad = std::clamp(orbit->pitch_rad + dy_px * kRotateRadPerPx, -kMaxPitchRad, kMaxPitchRad);
  ClampAboveGround(orbit);
}

double MinPitchAboveGround(double target_z, double distance) {
  if (!(distance > 0.0)) return -kMaxPitchRad;
  // eye z = target_z + distance * sin(pitch) >= kGroundClearance * distance
  const double sine = kGroundClearance - target_z / distance;
  if (sine >= std::sin(kMaxPitchRad)) return kMaxPitchRad;
  return std::max(-kMaxPitchRad, std::asin(std::max(-1.0, sine)));
}

void ClampAboveGround(OrbitCamera* orbit) {
  if (orbit->photo_image_id != kNoId) return;
  // A target so deep that even the steepest view from above is below the ground comes up.
  const double lowest_target = orbit->distance * (kGroundClearance - std::sin(kMaxPitchRad)) * (1.0 - 1e-9);
  orbit->target.z() = std::max(orbit->target.z(), lowest_target);
  orbit->pitch_rad = std::max(orbit->pitch_rad, MinPitchAboveGround(orbit->target.z(), orbit->distance));
}

bool NeedsReframe(const SceneBounds& framed, const SceneBounds& now) {
  const double ratio = now.radius / std::max(framed.radius, 1e-12);
  if (ratio > kReframeRatio || ratio < 1.0 / kReframeRatio) return true;
  return (now.center - framed.center).norm() > std::max(framed.radius, now.radius);
}

void OrbitPan(OrbitCamera* orbit, double dx_px, double dy_px, int width_px, int height_px) {
  OrbitLeavePhotoView(orbit, width_px, height_px);
  const Camera view = ViewCameraOf(*orbit, width_px, height_px);
  // World units per pixel at the target's depth.
  const double units_per_px = orbit->distance / view.focal_px;
  const Eigen::Vector3d right = view.cam_from_world_rotation.row(0).transpose();
  const Eigen::Vector3d down = view.cam_from_world_rotation.row(1).transpose();
  orbit->target -= units_per_px * (dx_px * right + dy_px * down);
  ClampAboveGround(orbit);
}

void OrbitZoom(OrbitCamera* orbit, double steps, int width_px, int height_px) {
  OrbitLeavePhotoView(orbit, width_px, height_px);
  orbit->distance = std::clamp(orbit->distance * std::exp(-steps * kZoomPerStep), 1e-6, 1e9);
  ClampAboveGround(orbit);
}

void OrbitFrame(OrbitCamera* orbit, const SceneBounds& bounds, int width_px, int height_px) {
  OrbitLeavePhotoView(orbit, width_px, height_px);
  const double half_fov_y = 0.5 * orbit->fov_y_deg * kPi / 180.0;
  const double aspect = static_cast<double>(std::max(1, width_px)) / std::max(1, height_px);
  const double half_fov_x = std::atan(std::tan(half_fov_y) * aspect);
  const double half_fov = std::min(half_fov_x, half_fov_y);
  const double radius = std::max(bounds.radius, 1e-6);
  orbit->target = bounds.center;
  orbit->distance = 1.05 * radius / std::sin(half_fov);
  ClampAboveGround(orbit);
}

void OrbitViewFromPhoto(OrbitCamera* orbit, Id image_id, const Camera& camera, const SceneBounds& bounds) {
  orbit->photo_image_id = image_id;
  orbit->photo_camera = camera;
  const Eigen::Vector3d center = camera.CenterInWorld();
  const Eigen::Vector3d forward = camera.cam_from_world_rotation.row(2).transpose();
  const double depth = std::max((bounds.center - center).dot(forward), 0.1 * bounds.radius);
  orbit->target = center + depth * forward;
  orbit->distance = depth;
  orbit->yaw_rad = std::atan2(-forward.y(), -forward.x());
  orbit->pitch_rad = std::clamp(std::asin(std::clamp(-forward.z(), -1.0, 1.0)), -kMaxPitchRad, kMaxPitchRad);
}

}  // namespace facet::app
