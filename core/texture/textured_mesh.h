// The model as a triangle mesh with one texture atlas: what the 3D panel draws and the
// exporters write. Every face of every primitive's mesh (any planar polygon, convex or not)
// is textured from its best view: the face's bounding rectangle in its own plane is rectified
// through the plane-to-photo homography and packed into one atlas (stb_rect_pack) with padding.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/image/image_io.h"
#include "core/mesh/mesh.h"
#include "core/optim/solver_summary.h"
#include "core/scene/project.h"

namespace facet {

struct TexturedMesh {
  // Per vertex, world coordinates (core/geometry/conventions.h, z up). Vertices are not shared
  // between faces, so each face has its own normals and UVs.
  std::vector<Eigen::Vector3f> positions;
  std::vector<Eigen::Vector3f> normals;
  // Atlas coordinates in [0, 1]^2, u right, v down from the atlas' top-left (glTF's convention).
  std::vector<Eigen::Vector2f> uvs;
  std::vector<std::uint32_t> indices;  // triangles, counter-clockwise seen from outside
  // Per triangle: the primitive (Project::primitives id) and the face of that primitive's
  // mesh it came from. A face's triangles are consecutive, in the order of its triangulation
  // (core/mesh/triangulate.h).
  std::vector<Id> triangle_primitive;
  std::vector<FaceId> triangle_face;
  // Per triangle: whether it has texture (faces no image sees keep uv = 0 and no texture).
  std::vector<std::uint8_t> triangle_textured;
  ImageRgba8 atlas;  // empty when no face is textured
};

// Triangle mesh of all primitives' live faces, without texture: per face, one vertex per
// corner (in FaceHalfedges order) with the face's Newell normal (FaceNormal), and the
// triangles of TriangulateFace. Faces are in project order, then by face id.
TexturedMesh BuildUntexturedMesh(const Project& project);

struct TextureBakeOptions {
  double texels_per_image_px = 1.0;  // face resolution relative to its size in the photo
  int max_face_texels = 2048;        // per side
  int padding_texels = 4;            // border replicated around each face against bleeding
  int max_atlas_size = 8192;

  bool Check(std::string* error) const;
};

// The shape every step's summary shares (core/optim/solver_summary.h), so the app reports a
// bake like a solve; a bake has no cost or iterations, those stay 0. termination kConverged when the bake ran (also when nothing could be
// textured: the message says why), kInvalidInput for bad options or photos, kFailed when the
// atlas overflows; iterations and costs are unused.
struct TextureBakeSummary : SolverSummary {
  int faces_textured = 0;
  int faces_untextured = 0;
  int atlas_width = 0;
  int atlas_height = 0;
};

// Bakes a textured mesh. `photos[i]` points to the pixels of project.images[i] (nullptr or an
// empty image for a photo that is not loaded); the bake only reads them, never copies them, and
// the caller keeps them alive and unchanged until it returns (the app bakes on a worker thread
// from photos it shares read-only). A face is textured from the calibrated image that sees
// it best: in front of the camera, facing it, and largest projected area times cosine of
// the view angle times the fraction of the face no other primitive hides (a 4 x 4 grid over
// the face's rectangle, kept inside the polygon, each point's ray to the camera centre tested
// against the other primitives' triangles). A face hidden from every view stays untextured.
// Face frame: u along the first edge (face.halfedge) projected into the face's plane, v the
// in-plane perpendicular (normal x u), so the texture reads upright as seen from outside; the
// whole bounding rectangle is rectified, and the corners' UVs pick the polygon out of it. A
// face that is not planar (a solved free vertex) is rectified through its best-fit plane
// (Newell normal through the corners' centroid): approximate there. A degenerate face (zero
// area) stays untextured. On failure (bad options, photos.size() != images.size(), atlas
// overflow) *mesh is the untextured mesh and the summary says why. The result depends only
// on the arguments (no shared state), so a bake on another thread is bit-identical.
TextureBakeSummary BakeTexturedMesh(const Project& project, const std::vector<const ImageRgba8*>& photos,
                                    const TextureBakeOptions& options, TexturedMesh* mesh);

// The same for callers that own their photos in one vector (tests, one-shot tools): bakes
// from pointers into `photos`, copying no pixels.
TextureBakeSummary BakeTexturedMesh(const Project& project, const std::vector<ImageRgba8>& photos,
                                    const TextureBakeOptions& options, TexturedMesh* mesh);

}  // namespace facet
