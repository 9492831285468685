// A camera: intrinsics (focal length, principal point, radial distortion k1, k2) and pose
// (cam_from_world). Conventions in core/geometry/conventions.h; with k1 = k2 = 0 it is a pinhole.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace facet {

struct Camera {
  int width_px = 0;  // image size the intrinsics refer to
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

  // 3x3 intrinsic matrix (the pinhole part: distortion is not in it).
  Eigen::Matrix3d K() const;
  // 3x4 projection matrix K [R | t] of the pinhole part: exact for the pixels of
  // UndistortPixel, not for the photo's pixels when k1 or k2 is non-zero.
  Eigen::Matrix<double, 3, 4> ProjectionMatrix() const;
  bool HasDistortion() const { return k1 != 0.0 || k2 != 0.0; }
  Eigen::Vector3d CamFromWorld(const Eigen::Vector3d& p_in_world) const;
  Eigen::Vector3d CenterInWorld() const;
  // Pixel of a world point, distortion applied. Points behind the camera project through the
  // centre too; check CamFromWorld(p).z() > 0 where that matters.
  Eigen::Vector2d Project(const Eigen::Vector3d& p_in_world) const;
  // Unit ray direction in world through pixel uv of the photo (distortion inverted by
  // UndistortNormalized, so Project(centre + t * ray) == uv inside the image).
  Eigen::Vector3d RayDirectionInWorld(const Eigen::Vector2d& uv_px) const;
  // Normalised coordinates x = X / Z, y = Y / Z: undistorted -> distorted, (x, y) d.
  Eigen::Vector2d DistortNormalized(const Eigen::Vector2d& xy_undistorted) const;
  // Distorted -> undistorted normalised coordinates: the free UndistortNormalized below says
  // how it converges and what it returns beyond the model's fold.
  Eigen::Vector2d UndistortNormalized(const Eigen::Vector2d& xy_distorted) const;
  // Photo pixel -> the pixel a pinhole camera with the same K would see (K undistort K^-1),
  // and back. The identity when HasDistortion() is false. Line families drawn on the photo
  // are straight after UndistortPixel.
  Eigen::Vector2d UndistortPixel(const Eigen::Vector2d& uv_px) const;
  Eigen::Vector2d DistortPixel(const Eigen::Vector2d& uv_pinhole_px) const;
  // Sets the pose from a camera centre and rotation.
  void SetPose(const Eigen::Matrix3d& cam_from_world_rotation, const Eigen::Vector3d& center_in_world);
};

// The radial model of Camera for given coefficients (free functions so that solvers holding
// their own parameter copies use the same code). Distort: xy (1 + k1 r^2 + k2 r^4).
Eigen::Vector2d DistortNormalized(const Eigen::Vector2d& xy_undistorted, double k1, double k2);
// Inverse of DistortNormalized: the radius r_u with r_u (1 + k1 r_u^2 + k2 r_u^4) = r_d by
// safeguarded Newton (bisection inside a bracket), to ~1e-15 relative, i.e. 1e-12 px for
// |k1| <= 0.5 over an image whose half-diagonal is about the focal length. The model is
// monotonic in r_u only up to the fold radius where 1 + 3 k1 r^2 + 5 k2 r^4 = 0 (k1 < 0 or
// k2 < 0): a distorted radius beyond the fold's image has no inverse and gets the fold
// radius (the point is reported on the fold; that only happens far outside a photo whose
// distortion was fitted inside it).
Eigen::Vector2d UndistortNormalized(const Eigen::Vector2d& xy_distorted, double k1, double k2);

// Angle-axis vector (radians) <-> rotation matrix, stable near zero angle.
// The rotation of a camera looking along the unit vector `forward` (not along world z) with
// world z up in the image: rows are the camera axes in world, x right, y down, z forward
// (core/geometry/conventions.h).
Eigen::Matrix3d CamFromWorldLookingAlong(const Eigen::Vector3d& forward);

Eigen::Matrix3d RotationFromAngleAxis(const Eigen::Vector3d& angle_axis);
Eigen::Vector3d AngleAxisFromRotation(const Eigen::Matrix3d& rotation);

}  // namespace facet
