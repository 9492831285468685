// The one conversion of a Facet camera (OpenCV frame: X right, Y down, Z forward; pixel
// centres at integer coordinates, core/geometry/conventions.h) to OpenGL's view and projection
// matrices (eye frame: X right, Y up, looking down -Z; clip space with w = depth).
//
// Header-only and free of GL so that tests can check it without a context: a world point
// taken through projection * view, the perspective divide and the GL viewport transform
// lands on the pixel Camera::Project gives, principal point offset included.
#pragma once

#include <algorithm>

#include <Eigen/Core>

#include "core/geometry/camera.h"

namespace facet::app {

struct GlCameraMatrices {
  Eigen::Matrix4d view = Eigen::Matrix4d::Identity();        // gl_eye_from_world
  Eigen::Matrix4d projection = Eigen::Matrix4d::Identity();  // clip_from_gl_eye
  // Where the camera's image lies in the viewport, in viewport pixels from the top-left:
  // viewport_px = image_scale * (uv_px + 0.5) + image_offset_px - 0.5 (pixel centres).
  double image_scale = 1.0;
  Eigen::Vector2d image_offset_px = Eigen::Vector2d::Zero();
};

// View and projection matrices that show `camera` in a GL viewport of
// viewport_width_px x viewport_height_px pixels (glViewport(0, 0, w, h)) whose top row is
// the framebuffer's last row (as ImGui::Image shows a GL texture with uv0 = (0, 1),
// uv1 = (1, 0)). When the viewport has the image's size, OpenCV pixel (u, v) is the
// viewport pixel (u, v). Otherwise the image is scaled uniformly to fit inside the viewport
// and centred; the frustum widens to show the scene around it.
// near_depth and far_depth are positive distances along the optical axis (0 < near < far)
// and map to GL depth -1 and +1. A camera without size (width_px or height_px <= 0) is
// treated as filling the viewport.
inline GlCameraMatrices GlMatricesFromCamera(const Camera& camera, int viewport_width_px,
                                             int viewport_height_px, double near_depth,
                                             double far_depth) {
  GlCameraMatrices out;
  const double viewport_w = std::max(1, viewport_width_px);
  const double viewport_h = std::max(1, viewport_height_px);
  const double image_w = camera.width_px > 0 ? camera.width_px : viewport_w;
  const double image_h = camera.height_px > 0 ? camera.height_px : viewport_h;

  // Fit the image in the viewport; in viewport pixel edges (origin at the top-left corner
  // of the first pixel) the image maps by x_edge = s * u_edge + offset.
  const double s = std::min(viewport_w / image_w, viewport_h / image_h);
  out.image_scale = s;
  out.image_offset_px = Eigen::Vector2d((viewport_w - s * image_w) / 2.0, (viewport_h - s * image_h) / 2.0);

  // The GL eye frame is the OpenCV camera frame turned half a turn about X.
  Eigen::Matrix4d cam_from_world = Eigen::Matrix4d::Identity();
  cam_from_world.topLeftCorner<3, 3>() = camera.cam_from_world_rotation;
  cam_from_world.topRightCorner<3, 1>() = camera.cam_from_world_translation;
  const Eigen::Matrix4d gl_eye_from_cam = Eigen::Vector4d(1.0, -1.0, -1.0, 1.0).asDiagonal();
  out.view = gl_eye_from_cam * cam_from_world;

  // In pixel edges of the viewport the camera has focal s*f and principal point
  // s*(c + 0.5) + offset (OpenCV puts pixel centres, not edges, at integers). From there:
  // ndc_x = 2 * x_edge / W - 1, ndc_y = 1 - 2 * y_edge / H (the viewport's top row is GL's
  // last), with (x_edge, y_edge) = (fx * X / Z + px, fy * Y / Z + py) and, in the GL eye
  // frame, X = x_gl, Y = -y_gl, Z = -z_gl = clip w.
  const double f = s * camera.focal_px;
  const double px = s * (camera.principal_point_px.x() + 0.5) + out.image_offset_px.x();
  const double py = s * (camera.principal_point_px.y() + 0.5) + out.image_offset_px.y();
  const double n = near_depth;
  const double fa = far_depth;
  Eigen::Matrix4d& p = out.projection;
  p.setZero();
  p(0, 0) = 2.0 * f / viewport_w;
  p(0, 2) = 1.0 - 2.0 * px / viewport_w;
  p(1, 1) = 2.0 * f / viewport_h;
  p(1, 2) = 2.0 * py / viewport_h - 1.0;
  p(2, 2) = -(fa + n) / (fa - n);
  p(2, 3) = -2.0 * fa * n / (fa - n);
  p(3, 2) = -1.0;
  return out;
}

}  // namespace facet::app
