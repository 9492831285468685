// Facet's geometric conventions, fixed once for the whole code base. Comments only.
//
// Units and frames
// - World frame: right-handed, metres or the user's units, Z axis up. The three Manhattan
//   line families of an image are named after the world axes they are parallel to:
//   "x" and "y" are horizontal, "z" is vertical.
// - Camera frame (OpenCV): X right, Y down, Z forward along the optical axis.
// - Transforms are named b_from_a: p_in_b = b_from_a * p_in_a. A camera stores
//   cam_from_world as a rotation matrix R and a translation t: p_in_cam = R * p_in_world + t.
//   The camera centre in world is -R^T t.
// - Rotations in files and solver parameters are angle-axis vectors (radians); in memory
//   they are Eigen::Matrix3d.
//
// Pixels (OpenCV convention)
// - Origin at the top-left of the image, u to the right, v down, in pixels.
// - Pixel centres lie at integer coordinates: the first pixel covers [-0.5, 0.5]^2.
// - A pixel coordinate is named uv_* or *_px. Points may lie outside the image bounds.
// - Intrinsics: K = [[f, 0, cx], [0, f, cy], [0, 0, 1]]: square pixels, zero skew.
//   uv = (f * X / Z + cx, f * Y / Z + cy) for p_in_cam = (X, Y, Z) with Z > 0.
//
// The conversion of a camera to OpenGL's view and projection matrices (Y up, looking down
// -Z) happens in exactly one place: app/platform/gl_camera.h.
#pragma once
