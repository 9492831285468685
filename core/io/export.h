// Writing the textured model: binary glTF 2.0 (.glb, with the cameras as glTF camera nodes)
// and Wavefront OBJ + MTL + PNG. glTF is Y up: world (x, y, z) is written as (x, z, -y).
#pragma once

#include <string>

#include "core/scene/project.h"
#include "core/texture/textured_mesh.h"

namespace facet {

// Not a solver: what a file export did (success, the error or what was written, the files).
struct ExportSummary {
  bool success = false;
  std::string message;  // the error, or what was written
  std::vector<std::string> files_written;
};

// Which images an export gives a camera: calibrated, with a size and a positive focal length.
// True with the size the camera's intrinsics refer to (the image's when the camera has none).
bool ExportedCameraSize(const Image& image, int* width_px, int* height_px);

// One .glb holding mesh, UVs, each atlas page as an embedded PNG (one image, texture, material
// and mesh primitive per page: "facet_textured", then "facet_textured_pageK") and one camera
// node per calibrated image (perspective, yfov from the focal length, at the camera's pose).
// Writes atomically (temporary file, then rename). Refuses (writes nothing) when an exported
// camera is not one by core/geometry/camera_checks.h (a focal length outside any lens).
// Names that are not UTF-8 (a photo's path) are written with U+FFFD.
ExportSummary ExportGlb(const TexturedMesh& mesh, const Project& project, const std::string& path);
// FILE.obj, FILE.mtl and FILE.png (the atlas; page K > 0 of a paged atlas in FILE_pageK.png with
// material facet_textured_pageK) side by side; OBJ's v runs upwards, so v is flipped.
// Positions and normals use the same Y-up axes as the GLB. `path` may end in .obj or not.
ExportSummary ExportObj(const TexturedMesh& mesh, const std::string& path);

}  // namespace facet
