#include "core/geometry/camera.h"

#include <algorithm>
#include <cmath>
#include <limits>

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
  const Eigen::Vector2d xy(p.x() / p.z(), p.y() / p.z());
  return focal_px * DistortNormalized(xy) + principal_point_px;
}

Eigen::Vector3d Camera::RayDirectionInWorld(const Eigen::Vector2d& uv_px) const {
  const Eigen::Vector2d xy = UndistortNormalized((uv_px - principal_point_px) / focal_px);
  const Eigen::Vector3d d_in_cam(xy.x(), xy.y(), 1.0);
  return (cam_from_world_rotation.transpose() * d_in_cam).normalized();
}

Eigen::Vector2d Camera::DistortNormalized(const Eigen::Vector2d& xy_undistorted) const {
  return facet::DistortNormalized(xy_undistorted, k1, k2);
}

Eigen::Vector2d Camera::UndistortNormalized(const Eigen::Vector2d& xy_distorted) const {
  return facet::UndistortNormalized(xy_distorted, k1, k2);
}

Eigen::Vector2d Camera::UndistortPixel(const Eigen::Vector2d& uv_px) const {
  if (!HasDistortion()) return uv_px;
  return focal_px * UndistortNormalized((uv_px - principal_point_px) / focal_px) + principal_point_px;
}

Eigen::Vector2d Camera::DistortPixel(const Eigen::Vector2d& uv_pinhole_px) const {
  if (!HasDistortion()) return uv_pinhole_px;
  return focal_px * DistortNormalized((uv_pinhole_px - principal_point_px) / focal_px) + principal_point_px;
}

Eigen::Vector2d DistortNormalized(const Eigen::Vector2d& xy, double k1, double k2) {
  const double r2 = xy.squaredNorm();
  return xy * (1.0 + r2 * (k1 + k2 * r2));
}

Eigen::Vector2d UndistortNormalized(const Eigen::Vector2d& xy_distorted, double k1, double k2) {
  const double rd = xy_distorted.norm();
  if ((k1 == 0.0 && k2 == 0.0) || !(rd > 0.0) || !std::isfinite(rd)) return xy_distorted;
  auto radius = [&](double r) {
    const double s = r * r;
    return r * (1.0 + s * (k1 + k2 * s));
  };
  // Fold: smallest positive s = r^2 with 1 + 3 k1 s + 5 k2 s^2 = 0; D(r) increases on [0, fold].
  double fold = std::numeric_limits<double>::infinity();
  {
    const double a = 5.0 * k2, b = 3.0 * k1;
    double s = std::numeric_limits<double>::infinity();
    if (a == 0.0) {
      if (b < 0.0) s = -1.0 / b;
    } else {
      const double disc = b * b - 4.0 * a;
      if (disc >= 0.0) {
        const double sq = std::sqrt(disc);
        for (double root : {(-b - sq) / (2.0 * a), (-b + sq) / (2.0 * a)}) {
          if (root > 0.0) s = std::min(s, root);
        }
      }
    }
    if (std::isfinite(s)) fold = std::sqrt(s);
  }
  if (std::isfinite(fold) && rd >= radius(fold)) return xy_distorted * (fold / rd);
  // Bracket [lo, hi] with D(lo) <= rd <= D(hi).
  double lo = 0.0;
  double hi = fold;
  if (!std::isfinite(hi)) {
    hi = std::max(rd, 1e-300);
    for (int i = 0; i < 2100 && radius(hi) < rd; ++i) hi *= 2.0;
  }
  double r = std::clamp(rd, lo, hi);
  for (int it = 0; it < 100; ++it) {
    const double f = radius(r) - rd;
    if (f == 0.0) break;
    if (f < 0.0)
      lo = r;
    else
      hi = r;
    const double s = r * r;
    const double slope = 1.0 + s * (3.0 * k1 + 5.0 * k2 * s);
    double next = slope > 0.0 ? r - f / slope : 0.5 * (lo + hi);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    if (std::abs(next - r) <= 1e-16 * r) {
      r = next;
      break;
    }
    r = next;
  }
  return xy_distorted * (r / rd);
}

void Camera::SetPose(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& center_in_world) {
  cam_from_world_rotation = rotation;
  cam_from_world_translation = -rotation * center_in_world;
}

Eigen::Matrix3d CamFromWorldLookingAlong(const Eigen::Vector3d& forward) {
  const Eigen::Vector3d right = forward.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d down = forward.cross(right);
  Eigen::Matrix3d cam_from_world;
  cam_from_world.row(0) = right.transpose();
  cam_from_world.row(1) = down.transpose();
  cam_from_world.row(2) = forward.transpose();
  return cam_from_world;
}

Eigen::Matrix3d RotationFromAngleAxis(const Eigen::Vector3d& angle_axis) {
  const double angle = angle_axis.norm();
  if (angle < 1e-12) {
    // First-order expansion keeps the map smooth at zero.
    Eigen::Matrix3d skew;
    skew << 0, -angle_axis.z(), angle_axis.y(), angle_axis.z(), 0, -angle_axis.x(), -angle_axis.y(), angle_axis.x(), 0;
    return Eigen::Matrix3d::Identity() + skew;
  }
  return Eigen::AngleAxisd(angle, angle_axis / angle).toRotationMatrix();
}

Eigen::Vector3d AngleAxisFromRotation(const Eigen::Matrix3d& rotation) {
  const Eigen::AngleAxisd aa(rotation);
  return aa.angle() * aa.axis();
}

}  // namespace facet
