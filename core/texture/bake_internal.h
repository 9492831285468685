// The texture bake's shared pieces between its steps (textured_mesh.cpp: faces, scores and
// packing; texel_sampling.cpp: visibility per texel, exposure, blending, dilation). Internal
// to core/texture; not for other layers.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "core/geometry/camera.h"
#include "core/image/image_io.h"
#include "core/texture/depth_map.h"
#include "core/texture/photo_pyramid.h"
#include "core/texture/textured_mesh.h"

namespace facet::bake {

// Grey for texels whose point lies outside every photo: neutral under any lighting, and opaque
// so the face shows no hole.
constexpr std::uint8_t kOutsideGrey = 128;

// A face as the bake sees it: its corners in world, its plane frame and where its vertices
// and texture go in the TexturedMesh.
struct FaceGeometry {
  size_t primitive_index = 0;
  Id primitive_id = kNoId;
  FaceId face_id = kNoFace;
  std::vector<Eigen::Vector3d> corners;  // counter-clockwise from outside, FaceHalfedges order
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  // Plane frame: p = origin + s * axis_u + t * axis_v for face coordinates (s, t).
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis_u = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis_v = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector2d> corners_st;           // corners in the face frame
  Eigen::Vector2d st_min = Eigen::Vector2d::Zero();  // bounding rectangle in the face frame
  Eigen::Vector2d st_max = Eigen::Vector2d::Zero();
  std::vector<Eigen::Vector3d> occlusion_samples;  // points on the face, world
  std::uint32_t first_vertex = 0;                  // in the TexturedMesh
  size_t first_triangle = 0;
  size_t triangle_count = 0;
  bool valid = false;  // false for a degenerate face, which stays untextured

  Eigen::Vector3d InWorld(const Eigen::Vector2d& st) const { return origin + st.x() * axis_u + st.y() * axis_v; }
  // The bounding rectangle's corners: (s_min, t_min), (s_max, t_min), (s_max, t_max), (s_min, t_max).
  std::array<Eigen::Vector3d, 4> RectangleInWorld() const {
    return {InWorld(st_min), InWorld({st_max.x(), st_min.y()}), InWorld(st_max), InWorld({st_min.x(), st_max.y()})};
  }
};

// A calibrated camera with its loaded photo (which may have been loaded at another resolution
// than the intrinsics refer to), its z-buffer, its pyramid and its exposure gain.
struct ViewContext {
  size_t image_index = 0;
  const Camera* camera = nullptr;
  const ImageRgba8* photo = nullptr;
  Eigen::Vector2d photo_px_per_camera_px = Eigen::Vector2d::Ones();
  Eigen::Vector3d center_in_world = Eigen::Vector3d::Zero();
  DepthMap depth;
  PhotoPyramid pyramid;
  Eigen::Vector3d gain = Eigen::Vector3d::Ones();
  double feather_px = 0.0;
  double half_diagonal_px = 1.0;  // photo px

  // Photo pixel of a camera-frame point, through the camera's distortion.
  Eigen::Vector2d ProjectCam(const Eigen::Vector3d& p_in_cam) const {
    return PhotoFromPinhole(Eigen::Vector2d(camera->focal_px * p_in_cam.x() / p_in_cam.z(),
                                            camera->focal_px * p_in_cam.y() / p_in_cam.z()) +
                            camera->principal_point_px);
  }
  Eigen::Vector2d PhotoFromPinhole(const Eigen::Vector2d& uv_pinhole_px) const {
    const Eigen::Vector2d uv = camera->HasDistortion() ? camera->DistortPixel(uv_pinhole_px) : uv_pinhole_px;
    return uv.cwiseProduct(photo_px_per_camera_px);
  }
  // The z-buffer test's tolerance for a point at depth z whose face is seen at cos_angle.
  double DepthTolerance(double z, double cos_angle, double relative) const;
};

struct FaceTexture {
  int view = -1;  // best view (index into the ViewContext list), -1 when untextured
  double score = 0.0;
  std::vector<int> candidates;  // views in front of and facing the face, best first
  // The user's forced source photo is `view` (and candidates[0]): sampled alone, not blended.
  bool forced = false;
  bool forced_unavailable = false;
  bool size_capped = false;
  int width = 0;                // texels at full resolution, before any atlas shrinking
  int height = 0;
  int packed_width = 0;
  int packed_height = 0;
  int page = 0;
  int x = 0;  // top-left texel of the face inside its page (padding excluded)
  int y = 0;
};

// Even-odd rule; the polygon may be non-convex.
bool InsidePolygon(const std::vector<Eigen::Vector2d>& polygon, const Eigen::Vector2d& p);

// Face coordinates (s, t) of texel (i, j) of a w x h face texture: texel (0, 0) is the
// rectangle's (s_min, t_max) and texel (w - 1, h - 1) its (s_max, t_min), so the face reads
// upright as seen from outside. Returns the 3x3 map from (i, j, 1) to (s, t, 1).
Eigen::Matrix3d FaceFromTexel(const FaceGeometry& face, int width, int height);

// Fits each view's exposure gain on sparse texels of the textured faces that several views
// see (view_blend.h's FitExposureGains) and stores it in views[v].gain.
void FitViewGains(const std::vector<FaceGeometry>& geometry, const std::vector<FaceTexture>& faces,
                  const std::vector<int>& textured, const TextureBakeOptions& options, std::vector<ViewContext>* views);

struct SamplingCounts {
  long from_other_views = 0;
  long hidden = 0;
  long forced_fallback = 0;  // a forced face's texels taken from another view than the forced one
  // Per candidate view of the face (FaceTexture::candidates order): its part of the texels
  // the face's views coloured, each texel counting 1 split by normalised weight.
  std::vector<double> view_share;
};

// Fills face f's packed rectangle and its padding in `page`: each texel inside the polygon
// seen by a view gets its colour (options.source), outside every photo grey, and every other
// texel of the rectangle and the padding the colour of the nearest such texel (4-neighbour
// breadth-first dilation).
void SampleFace(const FaceGeometry& g, int face_index, const FaceTexture& t, const std::vector<ViewContext>& views,
                const TextureBakeOptions& options, ImageRgba8* page, SamplingCounts* counts);

}  // namespace facet::bake
