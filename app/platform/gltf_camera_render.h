// A glTF file seen through one of its own camera nodes, drawn by the 3D panel's mesh shader
// (app/platform/viewport_shaders.h) with the camera converted to GL by gl_camera.h, the one
// conversion the panel uses. What `facet render-glb` writes, so a test can lay an exported
// model over its photo exactly as a glTF viewer would show it (tests/app/test_cli.cpp).
#pragma once

#include <string>

#include "core/image/image_io.h"
#include "core/io/gltf_read.h"

namespace facet::app {

// Renders `scene` through scene.cameras[camera_index] at that camera's image size (the view
// is the camera's image exactly: OpenCV pixel (u, v) of the camera is pixel (u, v) of *out).
// Textured batches show their texture as the 3D panel shows the atlas, the others its grey.
// Pixels no triangle covers have alpha 0, covered ones 255. Needs a current OpenGL 3.3 core
// context (EglContext). False with *error on a bad camera index or a GL failure.
bool RenderGltfThroughCamera(const GltfScene& scene, int camera_index, ImageRgba8* out, std::string* error);

}  // namespace facet::app
