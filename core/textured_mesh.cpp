#include "core/textured_mesh.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>

#include <Eigen/Geometry>
#include <stb_rect_pack.h>

#include "core/box.h"

namespace facet {
namespace {

// Grey for texels whose ray leaves the photo: neutral under any lighting, and opaque so the
// face shows no hole.
constexpr std::uint8_t kOutsideGrey = 128;
// Below this many visible pixels a view carries no usable texture.
constexpr double kMinProjectedAreaPx2 = 16.0;
constexpr int kMinFaceTexels = 2;
constexpr int kMinAtlasSize = 16;
// Face samples tested for occlusion by other boxes, per side.
constexpr int kOcclusionSamples = 4;

struct FaceGeometry {
  size_t box_index = 0;
  int face = 0;
  std::array<Eigen::Vector3d, 4> corners;  // counter-clockwise from outside, core/box.h
  Eigen::Vector3d normal;
};

// A calibrated camera mapped to the pixels of its loaded photo (which may have been loaded
// at another resolution than the intrinsics refer to).
struct PhotoView {
  size_t image_index = 0;
  const Camera* camera = nullptr;
  const ImageRgba8* photo = nullptr;
  double scale_x = 1.0;
  double scale_y = 1.0;

  Eigen::Vector2d ProjectCam(const Eigen::Vector3d& p_in_cam) const {
    return {(camera->focal_px * p_in_cam.x() / p_in_cam.z() + camera->principal_point_px.x()) * scale_x,
            (camera->focal_px * p_in_cam.y() / p_in_cam.z() + camera->principal_point_px.y()) * scale_y};
  }
};

struct FaceTexture {
  int view = -1;  // index into the PhotoView list, -1 when untextured
  double score = 0.0;
  int width = 0;  // texels at full resolution, before any atlas shrinking
  int height = 0;
  int packed_width = 0;
  int packed_height = 0;
  int x = 0;  // top-left texel of the face inside the atlas (padding excluded)
  int y = 0;
};

double PolygonArea(const std::vector<Eigen::Vector2d>& polygon) {
  double twice_area = 0.0;
  for (size_t i = 0; i < polygon.size(); ++i) {
    const Eigen::Vector2d& a = polygon[i];
    const Eigen::Vector2d& b = polygon[(i + 1) % polygon.size()];
    twice_area += a.x() * b.y() - a.y() * b.x();
  }
  return std::abs(0.5 * twice_area);
}

// Sutherland-Hodgman against one axis-aligned half-plane: keep coord(axis) * sign <= limit * sign.
std::vector<Eigen::Vector2d> ClipHalfPlane(const std::vector<Eigen::Vector2d>& polygon, int axis, double limit,
                                           double sign) {
  std::vector<Eigen::Vector2d> out;
  for (size_t i = 0; i < polygon.size(); ++i) {
    const Eigen::Vector2d& a = polygon[i];
    const Eigen::Vector2d& b = polygon[(i + 1) % polygon.size()];
    const double da = (a[axis] - limit) * sign;
    const double db = (b[axis] - limit) * sign;
    if (da <= 0) out.push_back(a);
    if ((da < 0 && db > 0) || (da > 0 && db < 0)) out.push_back(a + (b - a) * (da / (da - db)));
  }
  return out;
}

// Area of the quad inside the photo's pixel area [-0.5, w - 0.5] x [-0.5, h - 0.5].
double VisibleArea(const std::array<Eigen::Vector2d, 4>& quad, int width, int height) {
  std::vector<Eigen::Vector2d> polygon(quad.begin(), quad.end());
  polygon = ClipHalfPlane(polygon, 0, -0.5, -1.0);
  polygon = ClipHalfPlane(polygon, 0, width - 0.5, 1.0);
  polygon = ClipHalfPlane(polygon, 1, -0.5, -1.0);
  polygon = ClipHalfPlane(polygon, 1, height - 0.5, 1.0);
  return polygon.size() < 3 ? 0.0 : PolygonArea(polygon);
}

// Whether the open segment a -> b passes through the inside of the box.
bool SegmentHitsBox(const Box& box, const Eigen::Matrix3d& box_from_world, const Eigen::Vector3d& a,
                    const Eigen::Vector3d& b) {
  const Eigen::Vector3d a_in_box = box_from_world * (a - box.translation);
  const Eigen::Vector3d d_in_box = box_from_world * (b - a);
  // Shrink the interval slightly so touching faces and shared corners do not occlude.
  double lo = 1e-6, hi = 1.0 - 1e-6;
  for (int k = 0; k < 3; ++k) {
    const double margin = 1e-9 * std::max(1.0, box.size[k]);
    if (std::abs(d_in_box[k]) < 1e-15) {
      if (a_in_box[k] <= margin || a_in_box[k] >= box.size[k] - margin) return false;
      continue;
    }
    double t0 = (margin - a_in_box[k]) / d_in_box[k];
    double t1 = (box.size[k] - margin - a_in_box[k]) / d_in_box[k];
    if (t0 > t1) std::swap(t0, t1);
    lo = std::max(lo, t0);
    hi = std::min(hi, t1);
    if (lo >= hi) return false;
  }
  return true;
}

double UnoccludedFraction(const FaceGeometry& face, const Eigen::Vector3d& center, const Project& project,
                          const std::vector<Eigen::Matrix3d>& box_from_world) {
  if (project.boxes.size() < 2) return 1.0;  // a convex box never hides its own front faces
  int visible = 0;
  const Eigen::Vector3d eu = face.corners[1] - face.corners[0];
  const Eigen::Vector3d ev = face.corners[3] - face.corners[0];
  for (int i = 0; i < kOcclusionSamples; ++i) {
    for (int j = 0; j < kOcclusionSamples; ++j) {
      const Eigen::Vector3d p = face.corners[0] + (i + 0.5) / kOcclusionSamples * eu + (j + 0.5) / kOcclusionSamples * ev;
      bool hidden = false;
      for (size_t b = 0; b < project.boxes.size() && !hidden; ++b) {
        if (b != face.box_index) hidden = SegmentHitsBox(project.boxes[b], box_from_world[b], p, center);
      }
      visible += hidden ? 0 : 1;
    }
  }
  return static_cast<double>(visible) / (kOcclusionSamples * kOcclusionSamples);
}

// Scores the view of a face: visible projected area times the cosine of the view angle
// times the unoccluded fraction; 0 when unusable. Also returns the face's size in photo px.
double ScoreView(const FaceGeometry& face, const PhotoView& view, const Project& project,
                 const std::vector<Eigen::Matrix3d>& box_from_world, double* length_u_px, double* length_v_px) {
  const Camera& cam = *view.camera;
  std::array<Eigen::Vector2d, 4> uv;
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector3d p_in_cam = cam.CamFromWorld(face.corners[k]);
    if (!(p_in_cam.z() > 0.0)) return 0.0;
    uv[k] = view.ProjectCam(p_in_cam);
  }
  const Eigen::Vector3d centroid = 0.25 * (face.corners[0] + face.corners[1] + face.corners[2] + face.corners[3]);
  const Eigen::Vector3d center = cam.CenterInWorld();
  const Eigen::Vector3d to_camera = center - centroid;
  const double distance = to_camera.norm();
  if (!(distance > 0.0)) return 0.0;
  const double cosine = face.normal.dot(to_camera) / distance;
  if (!(cosine > 0.0)) return 0.0;
  const double area = VisibleArea(uv, view.photo->width, view.photo->height);
  if (!(area > kMinProjectedAreaPx2)) return 0.0;
  const double unoccluded = UnoccludedFraction(face, center, project, box_from_world);
  *length_u_px = std::max((uv[1] - uv[0]).norm(), (uv[2] - uv[3]).norm());
  *length_v_px = std::max((uv[3] - uv[0]).norm(), (uv[2] - uv[1]).norm());
  return area * cosine * unoccluded;
}

void SampleBilinear(const ImageRgba8& photo, double x, double y, std::uint8_t* out) {
  // Pixel centres are at integer coordinates; the photo covers [-0.5, w - 0.5].
  if (!(x >= -0.5 && x <= photo.width - 0.5 && y >= -0.5 && y <= photo.height - 0.5)) {
    out[0] = out[1] = out[2] = kOutsideGrey;
    out[3] = 255;
    return;
  }
  const double fx0 = std::floor(x), fy0 = std::floor(y);
  const double ax = x - fx0, ay = y - fy0;
  const int x0 = std::clamp(static_cast<int>(fx0), 0, photo.width - 1);
  const int y0 = std::clamp(static_cast<int>(fy0), 0, photo.height - 1);
  const int x1 = std::clamp(static_cast<int>(fx0) + 1, 0, photo.width - 1);
  const int y1 = std::clamp(static_cast<int>(fy0) + 1, 0, photo.height - 1);
  const std::uint8_t* p00 = photo.At(x0, y0);
  const std::uint8_t* p10 = photo.At(x1, y0);
  const std::uint8_t* p01 = photo.At(x0, y1);
  const std::uint8_t* p11 = photo.At(x1, y1);
  for (int c = 0; c < 4; ++c) {
    const double top = p00[c] + ax * (p10[c] - p00[c]);
    const double bottom = p01[c] + ax * (p11[c] - p01[c]);
    out[c] = static_cast<std::uint8_t>(std::clamp(top + ay * (bottom - top) + 0.5, 0.0, 255.0));
  }
}

// Texel (i, j) of a w x h face texture sits at face coordinates s = i / (w - 1) and
// t = (h - 1 - j) / (h - 1): corner 0 bottom-left, corner 1 bottom-right, corner 2 top-right,
// corner 3 top-left, so the face reads upright (as seen from outside) in the atlas.
Eigen::Vector2i CornerTexel(int corner, int width, int height) {
  static constexpr int kI[4] = {0, 1, 1, 0};
  static constexpr int kJ[4] = {1, 1, 0, 0};
  return {kI[corner] * (width - 1), kJ[corner] * (height - 1)};
}

// Rectifies the face into the atlas by the face-to-photo homography
// H = K [R | t] [e_u, e_v, c_0; 0, 0, 1], then replicates the border into the padding.
void RasterizeFace(const FaceGeometry& face, const PhotoView& view, const FaceTexture& tex, int padding,
                   ImageRgba8* atlas) {
  const Camera& cam = *view.camera;
  const Eigen::Matrix<double, 3, 4> projection = cam.ProjectionMatrix();
  Eigen::Matrix3d photo_from_face;
  photo_from_face.col(0) = projection.leftCols<3>() * (face.corners[1] - face.corners[0]);
  photo_from_face.col(1) = projection.leftCols<3>() * (face.corners[3] - face.corners[0]);
  photo_from_face.col(2) = projection * face.corners[0].homogeneous();
  const Eigen::Matrix3d scale = Eigen::Vector3d(view.scale_x, view.scale_y, 1.0).asDiagonal();
  photo_from_face = scale * photo_from_face;

  const int w = tex.packed_width, h = tex.packed_height;
  for (int j = 0; j < h; ++j) {
    const double t = static_cast<double>(h - 1 - j) / (h - 1);
    for (int i = 0; i < w; ++i) {
      const double s = static_cast<double>(i) / (w - 1);
      const Eigen::Vector3d q = photo_from_face * Eigen::Vector3d(s, t, 1.0);
      SampleBilinear(*view.photo, q.x() / q.z(), q.y() / q.z(), atlas->At(tex.x + i, tex.y + j));
    }
  }
  for (int j = -padding; j < h + padding; ++j) {
    for (int i = -padding; i < w + padding; ++i) {
      if (i >= 0 && i < w && j >= 0 && j < h) continue;
      const std::uint8_t* src = atlas->At(tex.x + std::clamp(i, 0, w - 1), tex.y + std::clamp(j, 0, h - 1));
      std::copy(src, src + 4, atlas->At(tex.x + i, tex.y + j));
    }
  }
}

// Packs the padded rectangles into the smallest power-of-two atlas (w = h or w = 2h) up to
// max_size; returns false if they do not fit. Sets x, y of each face on success.
bool PackFaces(const std::vector<int>& textured, int padding, int max_size, std::vector<FaceTexture>* faces,
               int* atlas_width, int* atlas_height) {
  double total_area = 0.0;
  std::vector<stbrp_rect> rects(textured.size());
  for (size_t r = 0; r < textured.size(); ++r) {
    const FaceTexture& f = (*faces)[textured[r]];
    rects[r].id = static_cast<int>(r);
    rects[r].w = f.packed_width + 2 * padding;
    rects[r].h = f.packed_height + 2 * padding;
    total_area += static_cast<double>(rects[r].w) * rects[r].h;
  }
  std::vector<std::pair<int, int>> sizes;
  for (long s = kMinAtlasSize; s <= max_size; s *= 2) {
    if (s / 2 >= kMinAtlasSize) sizes.emplace_back(static_cast<int>(s), static_cast<int>(s / 2));
    sizes.emplace_back(static_cast<int>(s), static_cast<int>(s));
  }
  if (sizes.empty() || sizes.back().second != max_size) sizes.emplace_back(max_size, max_size);
  for (const auto& [w, h] : sizes) {
    if (static_cast<double>(w) * h < total_area) continue;
    std::vector<stbrp_node> nodes(w);
    stbrp_context context;
    stbrp_init_target(&context, w, h, nodes.data(), w);
    if (stbrp_pack_rects(&context, rects.data(), static_cast<int>(rects.size())) != 1) continue;
    for (const stbrp_rect& r : rects) {
      FaceTexture& f = (*faces)[textured[r.id]];
      f.x = r.x + padding;
      f.y = r.y + padding;
    }
    *atlas_width = w;
    *atlas_height = h;
    return true;
  }
  return false;
}

double ElapsedMs(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

TexturedMesh BuildUntexturedMesh(const Project& project) {
  TexturedMesh mesh;
  const size_t faces = project.boxes.size() * 6;
  mesh.positions.reserve(faces * 4);
  mesh.normals.reserve(faces * 4);
  mesh.uvs.reserve(faces * 4);
  mesh.indices.reserve(faces * 6);
  for (const Box& box : project.boxes) {
    const std::array<Eigen::Vector3d, 8> corners = BoxCornersInWorld(box);
    for (int f = 0; f < 6; ++f) {
      const auto base = static_cast<std::uint32_t>(mesh.positions.size());
      const Eigen::Vector3f normal = BoxFaceNormalInWorld(box, f).cast<float>();
      for (int k = 0; k < 4; ++k) {
        mesh.positions.push_back(corners[BoxFaces()[f][k]].cast<float>());
        mesh.normals.push_back(normal);
        mesh.uvs.push_back(Eigen::Vector2f::Zero());
      }
      // The face's corners run counter-clockwise from outside; so do both halves.
      for (std::uint32_t index : {0u, 1u, 2u, 0u, 2u, 3u}) mesh.indices.push_back(base + index);
      for (int tri = 0; tri < 2; ++tri) {
        mesh.triangle_box.push_back(box.id);
        mesh.triangle_face.push_back(f);
        mesh.triangle_textured.push_back(0);
      }
    }
  }
  return mesh;
}

bool TextureBakeOptions::Check(std::string* error) const {
  std::string message;
  if (!(std::isfinite(texels_per_image_px) && texels_per_image_px > 0.0 && texels_per_image_px <= 16.0)) {
    message = "texels_per_image_px must be in (0, 16], got " + std::to_string(texels_per_image_px);
  } else if (max_face_texels < kMinFaceTexels) {
    message = "max_face_texels must be at least " + std::to_string(kMinFaceTexels) + ", got " +
              std::to_string(max_face_texels);
  } else if (padding_texels < 0 || padding_texels > 64) {
    message = "padding_texels must be in [0, 64], got " + std::to_string(padding_texels);
  } else if (max_atlas_size < kMinAtlasSize || max_atlas_size > 16384) {
    message = "max_atlas_size must be in [" + std::to_string(kMinAtlasSize) + ", 16384], got " +
              std::to_string(max_atlas_size);
  }
  if (error != nullptr) *error = message;
  return message.empty();
}

TextureBakeSummary BakeTexturedMesh(const Project& project, const std::vector<ImageRgba8>& photos,
                                    const TextureBakeOptions& options, TexturedMesh* mesh) {
  const auto start = std::chrono::steady_clock::now();
  TextureBakeSummary summary;
  *mesh = BuildUntexturedMesh(project);
  const int face_count = static_cast<int>(project.boxes.size() * 6);
  summary.faces_untextured = face_count;
  auto fail = [&](const std::string& message) {
    summary.success = false;
    summary.message = message;
    summary.time_ms = ElapsedMs(start);
    return summary;
  };
  std::string error;
  if (!options.Check(&error)) return fail("invalid texture options: " + error);
  if (photos.size() != project.images.size()) {
    return fail("got " + std::to_string(photos.size()) + " photos for " + std::to_string(project.images.size()) +
                " images");
  }

  std::vector<PhotoView> views;
  for (size_t i = 0; i < project.images.size(); ++i) {
    const Image& image = project.images[i];
    const ImageRgba8& photo = photos[i];
    if (!image.camera_calibrated || photo.empty() ||
        photo.pixels.size() != static_cast<size_t>(photo.width) * photo.height * 4) {
      continue;
    }
    PhotoView view;
    view.image_index = i;
    view.camera = &image.camera;
    view.photo = &photo;
    const int ref_width = image.camera.width_px > 0 ? image.camera.width_px : image.width_px;
    const int ref_height = image.camera.height_px > 0 ? image.camera.height_px : image.height_px;
    if (ref_width > 0 && ref_height > 0) {
      view.scale_x = static_cast<double>(photo.width) / ref_width;
      view.scale_y = static_cast<double>(photo.height) / ref_height;
    }
    views.push_back(view);
  }

  std::vector<Eigen::Matrix3d> box_from_world;
  std::vector<FaceGeometry> geometry;
  for (size_t b = 0; b < project.boxes.size(); ++b) {
    const Box& box = project.boxes[b];
    box_from_world.push_back(RotationFromAngleAxis(box.rotation).transpose());
    const std::array<Eigen::Vector3d, 8> corners = BoxCornersInWorld(box);
    for (int f = 0; f < 6; ++f) {
      FaceGeometry g;
      g.box_index = b;
      g.face = f;
      for (int k = 0; k < 4; ++k) g.corners[k] = corners[BoxFaces()[f][k]];
      g.normal = BoxFaceNormalInWorld(box, f);
      geometry.push_back(g);
    }
  }

  std::vector<FaceTexture> faces(geometry.size());
  std::vector<int> textured;
  for (size_t f = 0; f < geometry.size(); ++f) {
    double best_u = 0.0, best_v = 0.0;
    for (size_t v = 0; v < views.size(); ++v) {
      double length_u = 0.0, length_v = 0.0;
      const double score = ScoreView(geometry[f], views[v], project, box_from_world, &length_u, &length_v);
      if (score > faces[f].score) {
        faces[f].score = score;
        faces[f].view = static_cast<int>(v);
        best_u = length_u;
        best_v = length_v;
      }
    }
    if (faces[f].view < 0) continue;
    auto texels = [&](double length_px) {
      const double n = std::ceil(length_px * options.texels_per_image_px) + 1.0;
      return static_cast<int>(std::clamp(n, static_cast<double>(kMinFaceTexels), static_cast<double>(options.max_face_texels)));
    };
    faces[f].width = texels(best_u);
    faces[f].height = texels(best_v);
    textured.push_back(static_cast<int>(f));
  }
  if (textured.empty()) {
    summary.success = true;
    summary.message = geometry.empty() ? "the project has no boxes"
                      : views.empty()  ? "no calibrated image with loaded pixels; the mesh is untextured"
                                       : "no face is seen by a calibrated image; the mesh is untextured";
    summary.time_ms = ElapsedMs(start);
    return summary;
  }

  // Shrink every face by the same factor until the atlas fits.
  double shrink = 1.0;
  int atlas_width = 0, atlas_height = 0;
  for (;;) {
    bool all_minimal = true;
    for (int f : textured) {
      FaceTexture& t = faces[f];
      t.packed_width = std::max(kMinFaceTexels, static_cast<int>(std::lround(t.width * shrink)));
      t.packed_height = std::max(kMinFaceTexels, static_cast<int>(std::lround(t.height * shrink)));
      all_minimal = all_minimal && t.packed_width == kMinFaceTexels && t.packed_height == kMinFaceTexels;
    }
    if (PackFaces(textured, options.padding_texels, options.max_atlas_size, &faces, &atlas_width, &atlas_height)) break;
    if (all_minimal) {
      return fail(std::to_string(textured.size()) + " faces do not fit a " + std::to_string(options.max_atlas_size) +
                  " atlas even at " + std::to_string(kMinFaceTexels) + " texels per side");
    }
    shrink *= 0.85;
  }

  ImageRgba8& atlas = mesh->atlas;
  atlas.width = atlas_width;
  atlas.height = atlas_height;
  atlas.pixels.assign(static_cast<size_t>(atlas_width) * atlas_height * 4, 0);
  for (int f : textured) {
    const FaceTexture& t = faces[f];
    RasterizeFace(geometry[f], views[t.view], t, options.padding_texels, &atlas);
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector2i texel = CornerTexel(k, t.packed_width, t.packed_height);
      mesh->uvs[f * 4 + k] = Eigen::Vector2f(static_cast<float>((t.x + texel.x() + 0.5) / atlas_width),
                                             static_cast<float>((t.y + texel.y() + 0.5) / atlas_height));
    }
    mesh->triangle_textured[f * 2] = 1;
    mesh->triangle_textured[f * 2 + 1] = 1;
  }

  summary.success = true;
  summary.faces_textured = static_cast<int>(textured.size());
  summary.faces_untextured = face_count - summary.faces_textured;
  summary.atlas_width = atlas_width;
  summary.atlas_height = atlas_height;
  summary.time_ms = ElapsedMs(start);
  summary.message = "textured " + std::to_string(summary.faces_textured) + " of " + std::to_string(face_count) +
                    " faces into a " + std::to_string(atlas_width) + "x" + std::to_string(atlas_height) + " atlas" +
                    (shrink < 1.0 ? " (faces shrunk to fit)" : "");
  return summary;
}

}  // namespace facet
