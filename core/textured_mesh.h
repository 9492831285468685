// The model as a triangle mesh with one texture atlas: what the 3D panel draws and the
// exporters write. Texture per face from the best view, rectified by the inverse of the
// face-to-image homography, packed into one atlas (stb_rect_pack) with padding.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/image_io.h"
#include "core/project.h"

namespace facet {

struct TexturedMesh {
  // Per vertex, world coordinates (core/conventions.h, z up). Vertices are not shared
  // between faces, so each face has its own normals and UVs.
  std::vector<Eigen::Vector3f> positions;
  std::vector<Eigen::Vector3f> normals;
  // Atlas coordinates in [0, 1]^2, u right, v down from the atlas' top-left (glTF's convention).
  std::vector<Eigen::Vector2f> uvs;
  std::vector<std::uint32_t> indices;  // triangles, counter-clockwise seen from outside
  // Per triangle: the box id and face index (0..5, core/box.h) it came from.
  std::vector<Id> triangle_box;
  std::vector<int> triangle_face;
  // Per triangle: whether it has texture (faces no image sees keep uv = 0 and no texture).
  std::vector<std::uint8_t> triangle_textured;
  ImageRgba8 atlas;  // empty when no face is textured
};

// Triangle mesh of all boxes, without texture.
TexturedMesh BuildUntexturedMesh(const Project& project);

struct TextureBakeOptions {
  double texels_per_image_px = 1.0;  // face resolution relative to its size in the photo
  int max_face_texels = 2048;        // per side
  int padding_texels = 4;            // border replicated around each face against bleeding
  int max_atlas_size = 8192;

  bool Check(std::string* error) const;
};

struct TextureBakeSummary {
  bool success = false;
  std::string message;
  int faces_textured = 0;
  int faces_untextured = 0;
  int atlas_width = 0;
  int atlas_height = 0;
  double time_ms = 0.0;
};

// Bakes a textured mesh. `photos[i]` holds the pixels of project.images[i] (an empty image
// for a photo that is not loaded). A face is textured from the calibrated image that sees
// it best: in front of the camera, facing it, and largest projected area times cosine of
// the view angle. Boxes other than the face's own hide parts of it (sampled), lowering the
// score. On failure (bad options, photos.size() != images.size(), atlas overflow) *mesh is the
// untextured mesh and the summary says why.
TextureBakeSummary BakeTexturedMesh(const Project& project, const std::vector<ImageRgba8>& photos,
                                    const TextureBakeOptions& options, TexturedMesh* mesh);

}  // namespace facet
