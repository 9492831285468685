#include "core/camera.h"

namespace facet {

Eigen::Matrix3d Camera::K() const {
  Eigen::Matrix3d k = Eigen::Matrix3d::Identity();
  k(0, 0) = focal_px;
  k(1, 1) = focal_px;
  k(0, 2) = principal_point_px.x();
  k(1, 2) = principal_point_px.y();
  return k;
}

Eigen::Matrix<double, 3, 4> Camera::ProjectionMatrix() const {
  Eigen::Matrix<double, 3, 4> rt;
  rt.leftCols<3>() = cam_from_world_rotation;
  rt.col(3) = cam_from_world_translation;
  return K() * rt;
}

Eigen::Vector3d Camera::CamFromWorld(const Eigen::Vector3d& p_in_world) const {
  return cam_from_world_rotation * p_in_world + cam_from_world_translation;
}

Eigen::Vector3d Camera::CenterInWorld() const {
  return -cam_from_world_rotation.transpose() * cam_from_world_translation;
}

Eigen::Vector2d Camera::Project(const Eigen::Vector3d& p_in_world) const {
  const Eigen::Vector3d p = CamFromWorld(p_in_world);
  return {focal_px * p.x() / p.z() + principal_point_px.x(),
          focal_px * p.y() / p.z() + principal_point_px.y()};
}

Eigen::Vector3d Camera::RayDirectionInWorld(const Eigen::Vector2d& uv_px) const {
  const Eigen::Vector3d d_in_cam((uv_px.x() - principal_point_px.x()) / focal_px,
                                 (uv_px.y() - principal_point_px.y()) / focal_px, 1.0);
  return (cam_from_world_rotation.transpose() * d_in_cam).normalized();
}

void Camera::SetPose(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& center_in_world) {
  cam_from_world_rotation = rotation;
  cam_from_world_translation = -rotation * center_in_world;
}

Eigen::Matrix3d RotationFromAngleAxis(const Eigen::Vector3d& angle_axis) {
  const double angle = angle_axis.norm();
  if (angle < 1e-12) {
    // First-order expansion keeps the map smooth at zero.
    Eigen::Matrix3d skew;
    skew << 0, -angle_axis.z(), angle_axis.y(), angle_axis.z(), 0, -angle_axis.x(),
        -angle_axis.y(), angle_axis.x(), 0;
    return Eigen::Matrix3d::Identity() + skew;
  }
  return Eigen::AngleAxisd(angle, angle_axis / angle).toRotationMatrix();
}

Eigen::Vector3d AngleAxisFromRotation(const Eigen::Matrix3d& rotation) {
  const Eigen::AngleAxisd aa(rotation);
  return aa.angle() * aa.axis();
}

}  // namespace facet
