// Facet's cameras as a nerfstudio / instant-ngp transforms.json, for the NeRF and Gaussian
// splatting trainers, where structure from motion fails: few photos, little texture.
//
// Conventions of the format (docs.nerf.studio, "Data conventions"), applied here only:
// - transform_matrix: camera-to-world, 4 x 4, with the camera's axes as OpenGL's (x right,
//   y up, looking down -z): Facet's (OpenCV's) camera axes with y and z negated. The world
//   frame is Facet's own (z up, the project's units), which is also nerfstudio's up.
// - Pixels: the first pixel's centre is (0.5, 0.5), as in COLMAP, so cx, cy are Facet's
//   principal point + 0.5 (core/io/colmap_camera.h applies the same offset).
// - Intrinsics fl_x = fl_y = f, cx, cy, w, h, and OpenCV's k1, k2, p1 = p2 = 0 (Facet's radial
//   model is OpenCV's with k3 = 0): at the top level when every exported photo has the same,
//   else in each frame. camera_model "OPENCV" when a camera has distortion, else "PINHOLE".
// - file_path: the photo relative to the folder of the transforms.json (forward slashes), or
//   absolute when the two share no folder below the root.
#pragma once

#include <string>

#include <Eigen/Core>

#include "core/geometry/camera.h"
#include "core/scene/project.h"

namespace facet {

// camera-to-world of `camera` with OpenGL's camera axes: [R^T diag(1, -1, -1) | centre].
Eigen::Matrix4d NerfTransformFromCamera(const Camera& camera);

// The transforms.json text for the calibrated photos of `project` (core/io/camera_export.h),
// photo paths resolved against `project_path`'s folder (as the project file stores them) and
// written relative to `json_path`'s folder. "" on success, else why not (no calibrated photo,
// a camera that is no camera, a photo path that is not UTF-8); *text is then empty.
std::string FormatTransformsJson(const Project& project, const std::string& project_path, const std::string& json_path,
                                 std::string* text);

// FormatTransformsJson written to `json_path` atomically (core/util/file_write.h). "" on
// success, else what failed; nothing is written on failure.
std::string WriteTransformsJson(const Project& project, const std::string& project_path, const std::string& json_path);

}  // namespace facet
