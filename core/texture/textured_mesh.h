// The model as a triangle mesh with a texture atlas: what the 3D panel draws and the
// exporters write. Every face of every primitive's mesh (any planar polygon, convex or not)
// gets a rectangle of texels in its own plane, packed (stb_rect_pack) into one atlas page, or
// more when max_atlas_pages allows. Each texel's world point is tested against a z-buffer of
// the model per calibrated photo (core/texture/depth_map.h) and takes its colour from the
// photos that see it: blended with exposure levelling and feathered weights
// (core/texture/view_blend.h), or from the face's best view (the paper's rule), a hidden texel
// then coming from the next view that sees it; photos are sampled through their mip pyramid
// (core/texture/photo_pyramid.h) so a texel larger than a photo pixel does not alias.
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
  ImageRgba8 atlas;  // page 0 of the atlas; empty when no face is textured
  // Pages 1, 2, ... (only when TextureBakeOptions::max_atlas_pages > 1 and one page is too
  // small), and per triangle the page its UVs refer to (0 for untextured triangles; empty
  // means every triangle is on page 0).
  std::vector<ImageRgba8> more_atlas_pages;
  std::vector<std::uint8_t> triangle_page;

  int AtlasPageCount() const { return atlas.empty() ? 0 : 1 + static_cast<int>(more_atlas_pages.size()); }
  const ImageRgba8& AtlasPage(int page) const { return page == 0 ? atlas : more_atlas_pages[page - 1]; }
  int TrianglePage(size_t triangle) const { return triangle < triangle_page.size() ? triangle_page[triangle] : 0; }
};

// Triangle mesh of all primitives' live faces, without texture: per face, one vertex per
// corner (in FaceHalfedges order) with the face's Newell normal (FaceNormal), and the
// triangles of TriangulateFace. Faces are in project order, then by face id.
TexturedMesh BuildUntexturedMesh(const Project& project);

// Where a texel's colour comes from.
enum class TextureSource {
  kBlended,   // every photo that sees it, weighted (ViewQuality x FeatherWeight), the default
  kBestView,  // the face's best view; a texel hidden there from the next view (the paper's rule)
};

struct TextureBakeOptions {
  double texels_per_image_px = 1.0;  // face resolution relative to its size in its best photo
  int max_face_texels = 2048;        // per side
  // Face resolution in texels per project unit (per metre when the units are m) instead of
  // texels_per_image_px: a face whose bounding rectangle is W x H units gets round(W x
  // texels_per_unit) + 1 by round(H x texels_per_unit) + 1 texels (texel centres on its
  // outline, so W x texels_per_unit texel steps across it), each side capped by the atlas page
  // (max_atlas_size - 2 x padding_texels; max_face_texels does not apply), and then, as always,
  // every face shrunk by one factor when max_atlas_pages pages cannot hold them. 0: the rule
  // of texels_per_image_px.
  double texels_per_unit = 0.0;
  // Texels around each face, and any texel of its rectangle outside the polygon or hidden
  // from every photo, dilated from the face's own texels (nearest first) against bleeding.
  int padding_texels = 4;
  int max_atlas_size = 8192;  // per page side
  // Pages before faces are shrunk: 1 shrinks every face until one page holds them (what the
  // app draws today); more adds max_atlas_size pages first (the exporters write them all).
  int max_atlas_pages = 1;
  TextureSource source = TextureSource::kBlended;
  // Per-photo, per-channel gains fitted where photos see the same texels (FitExposureGains),
  // applied before blending or choosing; with one photo nothing changes.
  bool compensate_exposure = true;
  // Sample photos through their mip pyramid at the texel's footprint; false: bilinear only.
  bool filter_footprint = true;
  double depth_map_scale = 0.5;  // z-buffer pixels per photo pixel
  // A texel is seen when nothing in the z-buffer is nearer than its depth by more than
  // depth_tolerance x depth plus the depth its own plane spans over two z-buffer pixels.
  double depth_tolerance = 0.01;
  // Blended: a view's weight rises from 0 at its visibility boundary (photo border, silhouette,
  // occluder) to full at this fraction of the photo's diagonal (0.02: 100 px in a 12 MP photo).
  double feather_fraction = 0.02;
  double blend_sharpness = 2.0;  // exponent of ViewQuality: higher favours the best view more
  // Threads for the z-buffers (one per photo) and the sampling (one face at a time); 0: one
  // per core. The result is the same for any count.
  int max_threads = 0;

  bool Check(std::string* error) const;
};

// One photo's part in a face's texture.
struct TextureSourceShare {
  Id image_id = kNoId;
  // Of the face's texels that a photo coloured, the part this photo gave: each such texel
  // counts 1, split between the blended photos by their normalised weights.
  double share = 0.0;
};

// Which photos textured one face of the mesh, and how the user's override fared.
struct FaceTextureReport {
  Id primitive_id = kNoId;
  FaceId face = kNoFace;
  std::vector<TextureSourceShare> sources;  // largest share first; empty when untextured
  int width_texels = 0;                     // as packed into its atlas page; 0 when untextured
  int height_texels = 0;
  bool size_capped = false;  // texels_per_unit asked for more than an atlas page holds
  // The override's forced photo (Primitive::face_textures) when the bake honoured it: the face
  // takes its texels from that photo alone (never blended), except those the photo does not
  // see (its frame, an occluder), which come from the next view that sees them.
  Id forced_image = kNoId;
  long forced_fallback_texels = 0;
  // The override forces a photo that cannot texture the face at all (not calibrated or not
  // loaded, excluded, behind or edge-on to the face): the face was textured as if unforced.
  bool forced_unavailable = false;
};

// The shape every step's summary shares (core/optim/solver_summary.h), so the app reports a
// bake like a solve; a bake has no cost or iterations, those stay 0. termination kConverged when the bake ran (also
// when nothing could be textured: the message says why), kInvalidInput for bad options or photos, kFailed when the
// atlas overflows; iterations and costs are unused.
struct TextureBakeSummary : SolverSummary {
  int faces_textured = 0;
  int faces_untextured = 0;
  int atlas_width = 0;  // page 0
  int atlas_height = 0;
  int atlas_pages = 0;
  // Texels whose colour came from another photo than their face's best one (best view: hidden
  // there; blended: any texel with a weight from another photo).
  long texels_from_other_views = 0;
  long texels_hidden = 0;  // seen by no photo (occluded): dilated from the face's texels
  // Per project image: the exposure gain (R, G, B) applied to it; 1 where none was fitted.
  std::vector<Eigen::Vector3d> exposure_gains;
  // Per face of the mesh, in BuildUntexturedMesh's order (one entry per face, also when the
  // bake fails or a face stays untextured): the photos that textured it.
  std::vector<FaceTextureReport> faces;
  int images_excluded = 0;          // calibrated images whose use_for_texture is off
  long texels_forced_fallback = 0;  // over all faces: texels a forced photo did not see
  int faces_forced_unavailable = 0;
  int faces_size_capped = 0;
  // Where the time went, ms.
  double depth_maps_ms = 0.0;
  double selection_ms = 0.0;  // face scores and texel sizes
  double exposure_ms = 0.0;
  double packing_ms = 0.0;
  double sampling_ms = 0.0;  // visibility per texel, sampling, blending, dilation
};

// Bakes a textured mesh, honouring the user's choices: an image whose use_for_texture is off,
// and an image a face's override excludes, gives that face no colour and no weight; a face's
// forced source photo is its only source where it sees the face (FaceTextureReport says what
// came from elsewhere, and the summary's message names such faces). `photos[i]` points to the
// pixels of project.images[i] (nullptr or an empty image for a photo that is not loaded); the
// bake only reads them, never copies them, and the caller keeps them alive and unchanged until
// it returns (the app bakes on a worker thread from photos it shares read-only). A face's best
// view is the calibrated image in front of which it lies, facing it, with the largest
// projected area times cosine of the view angle times the fraction of the face the z-buffer
// shows (a 4 x 4 grid over the face's rectangle, kept inside the polygon); its texel size
// comes from that view (or from the forced photo). A face no view sees stays
// untextured. A texel no photo sees because something hides it is dilated from the face's
// seen texels; one outside every photo's frame is opaque grey (128).
// Face frame: u along the first edge (face.halfedge) projected into the face's plane, v the
// in-plane perpendicular (normal x u), so the texture reads upright as seen from outside; the
// whole bounding rectangle is rectified, and the corners' UVs pick the polygon out of it. A
// face that is not planar (a solved free vertex) is rectified through its best-fit plane
// (Newell normal through the corners' centroid): approximate there. A degenerate face (zero
// area) stays untextured. On failure (bad options, photos.size() != images.size(), atlas
// overflow) *mesh is the untextured mesh and the summary says why. The result depends only
// on the arguments (no shared state; the bake's own threads write disjoint parts), so a bake
// on another thread, or with another max_threads, is bit-identical.
TextureBakeSummary BakeTexturedMesh(const Project& project, const std::vector<const ImageRgba8*>& photos,
                                    const TextureBakeOptions& options, TexturedMesh* mesh);

// The same for callers that own their photos in one vector (tests, one-shot tools): bakes
// from pointers into `photos`, copying no pixels.
TextureBakeSummary BakeTexturedMesh(const Project& project, const std::vector<ImageRgba8>& photos,
                                    const TextureBakeOptions& options, TexturedMesh* mesh);

}  // namespace facet
