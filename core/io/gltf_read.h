// Reading a glTF 2.0 file (binary .glb or JSON .gltf) back: the triangles of every mesh node in the scene's
// frame (node transforms applied), their texture coordinates, base-colour textures and
// factors, and every camera node. Used to check what ExportGlb wrote as other tools read it
// (the render of the exported file through its own cameras, tests/app/test_cli.cpp) and to
// import a mesh as reference geometry.
//
// Frames: positions stay in the file's frame (glTF: Y up; for a file of ours, world (x, y, z)
// is (x, -z, y) of it, core/io/export.h). A camera node is returned as the Camera that a
// glTF viewer looking through it sees, in that same frame (OpenCV camera convention,
// core/geometry/conventions.h): the node looks down its local -Z with +Y up, its vertical
// field of view and aspect ratio fix the focal length, and the principal point is the image
// centre unless the camera's `extras` give `principal_point_px` (what ExportGlb writes, since
// glTF cameras cannot say it).
//
// Supported: a GLB file with its BIN chunk, or a JSON .gltf file (ReadGltf); either's buffers
// and images may also be data: URIs (base64) or files beside it (relative URIs, %XX escapes
// decoded; never http: or another scheme), TRIANGLES
// primitives, float positions / normals / texture coordinates (any byte stride), indices of
// 8, 16 or 32 bits or none, node hierarchies with matrix or TRS, perspective cameras. Anything
// else is refused with a message naming it, never read wrongly: every count, offset and
// stride is checked against its buffer before anything is allocated or read, every JSON field
// against the type it must have, and positions, normals and texture coordinates must be
// finite (NaN and infinities are refused by name).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/geometry/camera.h"
#include "core/image/image_io.h"

namespace facet {

struct GltfCamera {
  std::string name;           // the node's name, else the camera's
  double yfov_rad = 0.0;      // vertical field of view
  double aspect_ratio = 0.0;  // width / height; 0 when the file does not give it
  double znear = 0.0;
  bool has_principal_point = false;  // extras.principal_point_px was there
  // The camera a viewer looking through the node sees, in the file's frame (see above), at
  // image_size: extras.image_size_px when present, else `default_height_px` high and
  // aspect_ratio * that wide. focal_px comes from yfov, never from extras.
  Camera camera;
};

// One material's triangles: indices into GltfScene::positions (3 per triangle).
struct GltfBatch {
  int image = -1;  // index into GltfScene::images of the base-colour texture, -1 when untextured
  Eigen::Vector4f base_color = Eigen::Vector4f::Ones();  // linear RGBA factor
  std::vector<std::uint32_t> indices;
};

struct GltfScene {
  std::vector<Eigen::Vector3f> positions;  // file frame, node transforms applied
  std::vector<Eigen::Vector3f> normals;    // unit; zero when the file has none
  std::vector<Eigen::Vector2f> uvs;        // TEXCOORD_0, (0, 0) when absent; v down as glTF's
  std::vector<GltfBatch> batches;
  std::vector<ImageRgba8> images;   // decoded embedded images, by glTF image index
  std::vector<GltfCamera> cameras;  // one per camera node, in node order
};

struct GltfReadOptions {
  int default_height_px = 1000;  // image height of a camera without extras.image_size_px
  bool decode_images = true;     // false: GltfScene::images stays empty (geometry only)
  // Caps checked before anything is allocated or read: a file over one is refused with the
  // limit named. A mesh used by several nodes counts once per node (its triangles are copied
  // under each node's transform).
  size_t max_vertices = 16'000'000;   // GltfScene::positions
  size_t max_triangles = 32'000'000;  // over all batches
  size_t max_primitives = 100'000;    // primitive instances (one GltfBatch each)
  size_t max_nodes = 1'000'000;       // the file's `nodes` array
};

// Reads a glTF held in memory: GLB when `bytes` start with the GLB magic, else JSON text.
// `name` (the file's path, for the wrappers below) starts every error message. `folder` is
// where buffers and images with a relative URI are read from; such a URI must stay inside it
// after %XX decoding (no absolute path, no `..` component, no symbolic link leading out),
// else it is refused without opening or describing anything outside. An empty `folder` allows
// data: URIs and a GLB's BIN chunk only. Returns an empty string on success, else the error
// (and *scene is left empty); never throws.
std::string ReadGltfBytes(const std::vector<std::uint8_t>& bytes, const std::string& name, const std::string& folder,
                          const GltfReadOptions& options, GltfScene* scene);

// Reads `path` (its folder as ReadGltfBytes's `folder`). Returns an empty string on success,
// else the error naming the file and what is wrong or unsupported (and *scene is left empty).
// ReadGlb refuses a file that is not a GLB.
std::string ReadGlb(const std::string& path, const GltfReadOptions& options, GltfScene* scene);

// Reads `path` as ReadGlb does when it starts with the GLB magic, else as a JSON glTF (.gltf)
// whose buffers are files beside it or data: URIs. Errors as ReadGlb's; a buffer that is
// missing, shorter than its byteLength or not base64 is named ("buffer 1: ...").
std::string ReadGltf(const std::string& path, const GltfReadOptions& options, GltfScene* scene);

}  // namespace facet
