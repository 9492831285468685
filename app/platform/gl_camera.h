// The one conversion between core's cameras and vectors (Eigen, double, OpenCV frame: X right,
// Y down, Z forward; pixel centres at integer coordinates, core/geometry/conventions.h) and
// the GL side's GLM types (OpenGL's eye frame: X right, Y up, looking down -Z; clip space with
// w = depth; matrices column-major, m[column][row], as glUniformMatrix4fv expects). Nothing
// else in app/ converts between Eigen and GLM: rendering code includes this header.
//
// Precision: the matrices are glm::dmat4 (double): float's relative precision (6e-8) is already
// ~7e-5 px across a 1200 px viewport, far above the 1e-6 px round trip that
// tests/test_gl_camera.cpp checks. They become float (glm::mat4) only for the uniform upload.
//
// Header-only and free of GL so that tests can check it without a context: a world point
// taken through projection * view, the perspective divide and the GL viewport transform
// lands on the pixel Camera::Project gives, principal point offset included.
#pragma once

#include <algorithm>

#include <Eigen/Core>
#include <glm/glm.hpp>

#include "core/geometry/camera.h"

namespace facet::app {

// Eigen <-> GLM, element by element (no arithmetic, so exact).
inline glm::dvec3 ToGlm(const Eigen::Vector3d& v) { return glm::dvec3(v.x(), v.y(), v.z()); }
inline Eigen::Vector3d ToEigen(const glm::dvec3& v) { return Eigen::Vector3d(v.x, v.y, v.z); }
inline glm::dvec2 ToGlm(const Eigen::Vector2d& v) { return glm::dvec2(v.x(), v.y()); }
inline Eigen::Vector2d ToEigen(const glm::dvec2& v) { return Eigen::Vector2d(v.x, v.y); }
// A world point (Eigen, as core stores it) as GL's homogeneous column (w = 1).
inline glm::dvec4 HomogeneousGlm(const Eigen::Vector3d& p) { return glm::dvec4(p.x(), p.y(), p.z(), 1.0); }

struct GlCameraMatrices {
  glm::dmat4 view = glm::dmat4(1.0);        // gl_eye_from_world
  glm::dmat4 projection = glm::dmat4(1.0);  // clip_from_gl_eye
  // Where the camera's image lies in the viewport, in viewport pixels from the top-left:
  // viewport_px = image_scale * (uv_px + 0.5) + image_offset_px - 0.5 (pixel centres).
  double image_scale = 1.0;
  glm::dvec2 image_offset_px = glm::dvec2(0.0);
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
inline GlCameraMatrices GlMatricesFromCamera(const Camera& camera, int viewport_width_px, int viewport_height_px,
                                             double near_depth, double far_depth) {
  GlCameraMatrices out;
  const double viewport_w = std::max(1, viewport_width_px);
  const double viewport_h = std::max(1, viewport_height_px);
  const double image_w = camera.width_px > 0 ? camera.width_px : viewport_w;
  const double image_h = camera.height_px > 0 ? camera.height_px : viewport_h;

  // Fit the image in the viewport; in viewport pixel edges (origin at the top-left corner
  // of the first pixel) the image maps by x_edge = s * u_edge + offset.
  const double s = std::min(viewport_w / image_w, viewport_h / image_h);
  out.image_scale = s;
  out.image_offset_px = glm::dvec2((viewport_w - s * image_w) / 2.0, (viewport_h - s * image_h) / 2.0);

  // The GL eye frame is the OpenCV camera frame turned half a turn about X: row r of
  // cam_from_world [R | t] is multiplied by (1, -1, -1)[r].
  const double gl_eye_from_cam[3] = {1.0, -1.0, -1.0};
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out.view[c][r] = gl_eye_from_cam[r] * camera.cam_from_world_rotation(r, c);
    out.view[3][r] = gl_eye_from_cam[r] * camera.cam_from_world_translation(r);
  }

  // In pixel edges of the viewport the camera has focal s*f and principal point
  // s*(c + 0.5) + offset (OpenCV puts pixel centres, not edges, at integers). From there:
  // ndc_x = 2 * x_edge / W - 1, ndc_y = 1 - 2 * y_edge / H (the viewport's top row is GL's
  // last), with (x_edge, y_edge) = (fx * X / Z + px, fy * Y / Z + py) and, in the GL eye
  // frame, X = x_gl, Y = -y_gl, Z = -z_gl = clip w.
  const double f = s * camera.focal_px;
  const double px = s * (camera.principal_point_px.x() + 0.5) + out.image_offset_px.x;
  const double py = s * (camera.principal_point_px.y() + 0.5) + out.image_offset_px.y;
  const double n = near_depth;
  const double fa = far_depth;
  glm::dmat4& p = out.projection;  // p[column][row]
  p = glm::dmat4(0.0);
  p[0][0] = 2.0 * f / viewport_w;
  p[2][0] = 1.0 - 2.0 * px / viewport_w;
  p[1][1] = 2.0 * f / viewport_h;
  p[2][1] = 2.0 * py / viewport_h - 1.0;
  p[2][2] = -(fa + n) / (fa - n);
  p[3][2] = -2.0 * fa * n / (fa - n);
  p[2][3] = -1.0;
  return out;
}

}  // namespace facet::app
