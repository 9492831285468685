// A pinhole camera: intrinsics (focal length, principal point) and pose (cam_from_world).
// Conventions in core/conventions.h.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace facet {

struct Camera {
  int width_px = 0;   // image size the intrinsics refer to
  int height_px = 0;
  double focal_px = 1000.0;
  Eigen::Vector2d principal_point_px = Eigen::Vector2d::Zero();
  Eigen::Matrix3d cam_from_world_rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d cam_from_world_translation = Eigen::Vector3d::Zero();
  // Radial lens distortion, OpenCV's model (radial part): for p_in_cam = (X, Y, Z), Z > 0,
  // x = X / Z, y = Y / Z, r^2 = x^2 + y^2, d = 1 + k1 r^2 + k2 r^4, uv = (f x d + cx, f y d + cy).
  // Zero for a pinhole camera (the default).
  double k1 = 0.0;
  double k2 = 0.0;

  // 3x3 intrinsic matrix.
  Eigen::Matrix3d K() const;
  // 3x4 projection matrix K [R | t].
  Eigen::Matrix<double, 3, 4> ProjectionMatrix() const;
  Eigen::Vector3d CamFromWorld(const Eigen::Vector3d& p_in_world) const;
  Eigen::Vector3d CenterInWorld() const;
  // Pixel of a world point. Points behind the camera project through the centre too;
  // check CamFromWorld(p).z() > 0 where that matters.
  Eigen::Vector2d Project(const Eigen::Vector3d& p_in_world) const;
  // Unit ray direction in world through pixel uv.
  Eigen::Vector3d RayDirectionInWorld(const Eigen::Vector2d& uv_px) const;
  // Sets the pose from a camera centre and rotation.
  void SetPose(const Eigen::Matrix3d& cam_from_world_rotation, const Eigen::Vector3d& center_in_world);
};

// Angle-axis vector (radians) <-> rotation matrix, stable near zero angle.
Eigen::Matrix3d RotationFromAngleAxis(const Eigen::Vector3d& angle_axis);
Eigen::Vector3d AngleAxisFromRotation(const Eigen::Matrix3d& rotation);

}  // namespace facet
