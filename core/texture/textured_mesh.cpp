#include "core/texture/textured_mesh.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <thread>

#include <stb_rect_pack.h>
#include <Eigen/Geometry>

#include "core/mesh/triangulate.h"
#include "core/texture/bake_internal.h"

namespace facet {
namespace {

using bake::FaceGeometry;
using bake::FaceTexture;
using bake::ViewContext;

// Runs work(k) for k in [0, count) on up to `threads` threads (0: one per core), each taking
// the next k in turn; work must only touch what k owns, so the result does not depend on the
// thread count.
template <typename Work>
void ParallelFor(int count, int threads, Work work) {
  int n = threads > 0 ? threads : static_cast<int>(std::thread::hardware_concurrency());
  n = std::clamp(n, 1, std::max(1, count));
  std::atomic<int> next{0};
  auto run = [&] {
    for (int k = next++; k < count; k = next++) work(k);
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < n; ++t) pool.emplace_back(run);
  run();
  for (std::thread& t : pool) t.join();
}

// Below this many visible pixels a view carries no usable texture.
constexpr double kMinProjectedAreaPx2 = 16.0;
constexpr int kMinFaceTexels = 2;
constexpr int kMinAtlasSize = 16;
constexpr int kMaxAtlasPages = 64;
// A texel per micrometre in metres: beyond any photo, and far from overflowing a texel count.
constexpr double kMaxTexelsPerUnit = 1e6;
// Face samples tested for occlusion in the z-buffers, per side of the face's rectangle.
constexpr int kOcclusionSamples = 4;

double SignedArea(const std::vector<Eigen::Vector2d>& polygon) {
  double twice_area = 0.0;
  for (size_t i = 0; i < polygon.size(); ++i) {
    const Eigen::Vector2d& a = polygon[i];
    const Eigen::Vector2d& b = polygon[(i + 1) % polygon.size()];
    twice_area += a.x() * b.y() - a.y() * b.x();
  }
  return 0.5 * twice_area;
}

// Sutherland-Hodgman against one axis-aligned half-plane: keep coord(axis) * sign <= limit * sign.
// For a non-convex polygon the result may hold zero-width bridges along the clip line, which
// leave its area exact.
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

// Area of the polygon inside the photo's pixel area [-0.5, w - 0.5] x [-0.5, h - 0.5].
double VisibleArea(std::vector<Eigen::Vector2d> polygon, int width, int height) {
  polygon = ClipHalfPlane(polygon, 0, -0.5, -1.0);
  polygon = ClipHalfPlane(polygon, 0, width - 0.5, 1.0);
  polygon = ClipHalfPlane(polygon, 1, -0.5, -1.0);
  polygon = ClipHalfPlane(polygon, 1, height - 0.5, 1.0);
  return polygon.size() < 3 ? 0.0 : std::abs(SignedArea(polygon));
}

double ElapsedMs(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

// The face's plane frame, bounding rectangle and occlusion samples; valid stays false for a
// face without area.
void SetFaceFrame(const std::vector<std::array<Eigen::Vector3d, 3>>& triangles, FaceGeometry* g) {
  const size_t n = g->corners.size();
  if (n < 3 || g->normal.isZero()) return;
  // Best-fit plane: the Newell normal through the corners' centroid (exact for a planar face).
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : g->corners) centroid += p;
  centroid /= static_cast<double>(n);
  // u along the first edge; the longest edge instead when the first one has (almost) no
  // length in the plane.
  double radius = 0.0;
  for (const Eigen::Vector3d& p : g->corners) radius = std::max(radius, (p - centroid).norm());
  auto in_plane_edge = [&](size_t k) {
    const Eigen::Vector3d e = g->corners[(k + 1) % n] - g->corners[k];
    return Eigen::Vector3d(e - e.dot(g->normal) * g->normal);
  };
  Eigen::Vector3d u = in_plane_edge(0);
  if (!(u.norm() > 1e-9 * radius)) {
    for (size_t k = 1; k < n; ++k) {
      if (in_plane_edge(k).norm() > u.norm()) u = in_plane_edge(k);
    }
  }
  if (!(u.norm() > 0.0)) return;
  g->axis_u = u.normalized();
  g->axis_v = g->normal.cross(g->axis_u);
  g->origin = centroid;
  g->corners_st.resize(n);
  g->st_min = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  g->st_max = -g->st_min;
  for (size_t k = 0; k < n; ++k) {
    const Eigen::Vector3d d = g->corners[k] - centroid;
    g->corners_st[k] = Eigen::Vector2d(d.dot(g->axis_u), d.dot(g->axis_v));
    g->st_min = g->st_min.cwiseMin(g->corners_st[k]);
    g->st_max = g->st_max.cwiseMax(g->corners_st[k]);
  }
  const Eigen::Vector2d extent = g->st_max - g->st_min;
  const double size = extent.maxCoeff();
  if (!(extent.minCoeff() > 1e-12 * size) || !(std::abs(SignedArea(g->corners_st)) > 1e-12 * size * size)) return;
  g->valid = true;
  // A grid over the rectangle, kept where it falls inside the polygon; a sliver the grid
  // misses is sampled at its triangles' centroids instead.
  for (int i = 0; i < kOcclusionSamples; ++i) {
    for (int j = 0; j < kOcclusionSamples; ++j) {
      const Eigen::Vector2d st = g->st_min + Eigen::Vector2d((i + 0.5) / kOcclusionSamples * extent.x(),
                                                             (j + 0.5) / kOcclusionSamples * extent.y());
      if (bake::InsidePolygon(g->corners_st, st)) g->occlusion_samples.push_back(g->InWorld(st));
    }
  }
  if (g->occlusion_samples.empty()) {
    for (const auto& tri : triangles) g->occlusion_samples.push_back((tri[0] + tri[1] + tri[2]) / 3.0);
  }
}

// Builds the untextured mesh and, alongside, the bake's view of every face and the triangles
// the z-buffers draw (each tagged with its face's index in `geometry`).
TexturedMesh BuildMesh(const Project& project, std::vector<FaceGeometry>* geometry,
                       std::vector<DepthTriangle>* depth_triangles) {
  TexturedMesh mesh;
  for (size_t pi = 0; pi < project.primitives.size(); ++pi) {
    const Primitive& primitive = project.primitives[pi];
    const PolyMesh& poly = primitive.mesh;
    const MeshTriangulation triangulation = TriangulateMesh(poly);
    for (FaceId f = 0; f < poly.FaceIdEnd(); ++f) {
      if (!poly.IsFace(f)) continue;
      const std::vector<HalfedgeId> corners = FaceHalfedges(poly, f);
      FaceGeometry g;
      g.primitive_index = pi;
      g.primitive_id = primitive.id;
      g.face_id = f;
      g.normal = FaceNormal(poly, f);
      g.first_vertex = static_cast<std::uint32_t>(mesh.positions.size());
      g.first_triangle = mesh.triangle_face.size();
      const Eigen::Vector3f normal = g.normal.cast<float>();
      for (HalfedgeId h : corners) {
        const Eigen::Vector3d& p = poly.vertex(poly.Origin(h)).position;
        g.corners.push_back(p);
        mesh.positions.push_back(p.cast<float>());
        mesh.normals.push_back(normal);
        mesh.uvs.push_back(Eigen::Vector2f::Zero());
      }
      std::vector<std::array<Eigen::Vector3d, 3>> face_triangles;
      for (const CornerTriangle& tri : triangulation.by_face[f]) {
        std::array<Eigen::Vector3d, 3> world;
        for (int k = 0; k < 3; ++k) {
          const auto local = std::find(corners.begin(), corners.end(), tri[k]) - corners.begin();
          mesh.indices.push_back(g.first_vertex + static_cast<std::uint32_t>(local));
          world[k] = g.corners[local];
        }
        face_triangles.push_back(world);
        if (depth_triangles != nullptr && geometry != nullptr) {
          depth_triangles->push_back({world, static_cast<std::int32_t>(geometry->size())});
        }
        mesh.triangle_primitive.push_back(primitive.id);
        mesh.triangle_face.push_back(f);
        mesh.triangle_textured.push_back(0);
      }
      g.triangle_count = face_triangles.size();
      if (geometry != nullptr) {
        SetFaceFrame(face_triangles, &g);
        geometry->push_back(std::move(g));
      }
    }
  }
  return mesh;
}

// The fraction of the face's occlusion samples the view's z-buffer shows.
double VisibleFraction(const FaceGeometry& face, int face_index, const ViewContext& view, double depth_tolerance) {
  if (face.occlusion_samples.empty()) return 1.0;
  const Camera& cam = *view.camera;
  int visible = 0;
  for (const Eigen::Vector3d& p : face.occlusion_samples) {
    const Eigen::Vector3d p_in_cam = cam.CamFromWorld(p);
    if (!(p_in_cam.z() > 0.0)) continue;
    const Eigen::Vector2d uv(cam.focal_px * p_in_cam.x() / p_in_cam.z() + cam.principal_point_px.x(),
                             cam.focal_px * p_in_cam.y() / p_in_cam.z() + cam.principal_point_px.y());
    const Eigen::Vector3d to_camera = (view.center_in_world - p).normalized();
    const double tolerance = view.DepthTolerance(p_in_cam.z(), face.normal.dot(to_camera), depth_tolerance);
    visible += view.depth.Sees(uv, p_in_cam.z(), face_index, tolerance) ? 1 : 0;
  }
  return static_cast<double>(visible) / static_cast<double>(face.occlusion_samples.size());
}

// Scores the view of a face: visible projected area times the cosine of the view angle (the
// geometric score, 0 when the view cannot see the face at all) times the fraction its z-buffer
// shows (the score). Also returns the size in photo px of the face's bounding rectangle along
// u and v.
double ScoreView(const FaceGeometry& face, int face_index, const ViewContext& view, double depth_tolerance,
                 double* geometric_score, double* length_u_px, double* length_v_px) {
  *geometric_score = 0.0;
  const Camera& cam = *view.camera;
  std::vector<Eigen::Vector2d> uv(face.corners.size());
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (size_t k = 0; k < face.corners.size(); ++k) {
    const Eigen::Vector3d p_in_cam = cam.CamFromWorld(face.corners[k]);
    if (!(p_in_cam.z() > 0.0)) return 0.0;
    uv[k] = view.ProjectCam(p_in_cam);
    centroid += face.corners[k];
  }
  centroid /= static_cast<double>(face.corners.size());
  // The rectangle is what gets rectified; its corners lie outside a non-convex or slanted
  // polygon and, with a camera very close to the plane, may fall behind it: such a view
  // is skipped rather than sampled through a homography that flips sign.
  std::array<Eigen::Vector2d, 4> rect;
  const std::array<Eigen::Vector3d, 4> rect_in_world = face.RectangleInWorld();
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector3d p_in_cam = cam.CamFromWorld(rect_in_world[k]);
    if (!(p_in_cam.z() > 0.0)) return 0.0;
    rect[k] = view.ProjectCam(p_in_cam);
  }
  const Eigen::Vector3d to_camera = view.center_in_world - centroid;
  const double distance = to_camera.norm();
  if (!(distance > 0.0)) return 0.0;
  const double cosine = face.normal.dot(to_camera) / distance;
  if (!(cosine > 0.0)) return 0.0;
  const double area = VisibleArea(uv, view.photo->width, view.photo->height);
  if (!(area > kMinProjectedAreaPx2)) return 0.0;
  *geometric_score = area * cosine;
  *length_u_px = std::max((rect[1] - rect[0]).norm(), (rect[2] - rect[3]).norm());
  *length_v_px = std::max((rect[3] - rect[0]).norm(), (rect[2] - rect[1]).norm());
  return *geometric_score * VisibleFraction(face, face_index, view, depth_tolerance);
}

// Packs the padded rectangles of `ids` into the smallest power-of-two page (w = h or w = 2h)
// up to max_size; returns false if they do not fit. Sets x, y and page of each face on success.
bool PackOnePage(const std::vector<int>& ids, int padding, int max_size, int page, std::vector<FaceTexture>* faces,
                 int* page_width, int* page_height) {
  double total_area = 0.0;
  std::vector<stbrp_rect> rects(ids.size());
  for (size_t r = 0; r < ids.size(); ++r) {
    const FaceTexture& f = (*faces)[ids[r]];
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
      FaceTexture& f = (*faces)[ids[r.id]];
      f.x = r.x + padding;
      f.y = r.y + padding;
      f.page = page;
    }
    *page_width = w;
    *page_height = h;
    return true;
  }
  return false;
}

// Packs the faces into at most max_pages pages: one page when they fit; otherwise full
// max_size pages filled in turn (stb_rect_pack's partial packing), the last one as small as
// its faces allow. Returns false if they need more pages. page_sizes gets (w, h) per page.
bool PackFaces(const std::vector<int>& textured, int padding, int max_size, int max_pages,
               std::vector<FaceTexture>* faces, std::vector<std::pair<int, int>>* page_sizes) {
  page_sizes->clear();
  std::vector<int> remaining = textured;
  while (!remaining.empty()) {
    if (static_cast<int>(page_sizes->size()) >= max_pages) return false;
    const int page = static_cast<int>(page_sizes->size());
    int w = 0, h = 0;
    if (PackOnePage(remaining, padding, max_size, page, faces, &w, &h)) {
      page_sizes->emplace_back(w, h);
      return true;
    }
    if (page + 1 >= max_pages) return false;
    std::vector<stbrp_rect> rects(remaining.size());
    for (size_t r = 0; r < remaining.size(); ++r) {
      const FaceTexture& f = (*faces)[remaining[r]];
      rects[r].id = static_cast<int>(r);
      rects[r].w = f.packed_width + 2 * padding;
      rects[r].h = f.packed_height + 2 * padding;
    }
    std::vector<stbrp_node> nodes(max_size);
    stbrp_context context;
    stbrp_init_target(&context, max_size, max_size, nodes.data(), max_size);
    stbrp_pack_rects(&context, rects.data(), static_cast<int>(rects.size()));
    std::vector<int> left;
    for (const stbrp_rect& r : rects) {
      FaceTexture& f = (*faces)[remaining[r.id]];
      if (!r.was_packed) {
        left.push_back(remaining[r.id]);
        continue;
      }
      f.x = r.x + padding;
      f.y = r.y + padding;
      f.page = page;
    }
    if (left.size() == remaining.size()) return false;  // a face larger than a page
    page_sizes->emplace_back(max_size, max_size);
    remaining = std::move(left);
  }
  return true;
}

// The calibrated images with loaded pixels, with the scale from the camera's pixels to the
// photo's, each with its z-buffer and (when filtering) its pyramid.
// Images the user took out of texturing (use_for_texture off) are not views at all.
std::vector<ViewContext> UsableViews(const Project& project, const std::vector<const ImageRgba8*>& photos,
                                     const std::vector<DepthTriangle>& depth_triangles,
                                     const TextureBakeOptions& options, int* images_excluded) {
  std::vector<ViewContext> views;
  *images_excluded = 0;
  for (size_t i = 0; i < project.images.size(); ++i) {
    const Image& image = project.images[i];
    if (!image.use_for_texture) {
      *images_excluded += image.camera_calibrated ? 1 : 0;
      continue;
    }
    if (photos[i] == nullptr) continue;
    const ImageRgba8& photo = *photos[i];
    if (!image.camera_calibrated || photo.empty() ||
        photo.pixels.size() != static_cast<size_t>(photo.width) * photo.height * 4) {
      continue;
    }
    ViewContext view;
    view.image_index = i;
    view.camera = &image.camera;
    view.photo = &photo;
    const int ref_width = image.camera.width_px > 0 ? image.camera.width_px : image.width_px;
    const int ref_height = image.camera.height_px > 0 ? image.camera.height_px : image.height_px;
    if (ref_width > 0 && ref_height > 0) {
      view.photo_px_per_camera_px =
          Eigen::Vector2d(static_cast<double>(photo.width) / ref_width, static_cast<double>(photo.height) / ref_height);
    }
    view.center_in_world = image.camera.CenterInWorld();
    view.half_diagonal_px = 0.5 * std::hypot(photo.width, photo.height);
    view.feather_px = options.feather_fraction * 2.0 * view.half_diagonal_px;
    views.push_back(std::move(view));
  }
  DepthMapOptions depth_options;
  depth_options.scale = options.depth_map_scale;
  ParallelFor(static_cast<int>(views.size()), options.max_threads, [&](int v) {
    ViewContext& view = views[v];
    view.depth = RenderDepthMap(depth_triangles, *view.camera, view.photo->width, view.photo->height,
                                view.photo_px_per_camera_px, depth_options);
    view.pyramid = PhotoPyramid(view.photo, options.filter_footprint);
  });
  return views;
}

// Each face's candidate views (best first), best view and texel size; returns the faces some
// view sees. A face's override (Primitive::face_textures) drops the views it excludes and puts
// its forced view first, as the best view, when that view can see the face at all.
std::vector<int> ChooseFaceViews(const Project& project, const std::vector<FaceGeometry>& geometry,
                                 const std::vector<ViewContext>& views, const TextureBakeOptions& options,
                                 std::vector<FaceTexture>* faces_out) {
  std::vector<FaceTexture>& faces = *faces_out;
  std::vector<int> textured;
  for (size_t f = 0; f < geometry.size(); ++f) {
    if (!geometry[f].valid) continue;
    const FaceTextureOverride* user =
        FindFaceTextureOverride(project.primitives[geometry[f].primitive_index], geometry[f].face_id);
    auto excluded = [&](const ViewContext& view) {
      const Id id = project.images[view.image_index].id;
      return user != nullptr && std::binary_search(user->excluded_images.begin(), user->excluded_images.end(), id);
    };
    double best_u = 0.0, best_v = 0.0;
    double forced_u = 0.0, forced_v = 0.0;
    int forced = -1;
    std::vector<std::pair<double, int>> ranked;  // (score, view), then (geometric score, view) for hidden views
    for (size_t v = 0; v < views.size(); ++v) {
      if (excluded(views[v])) continue;
      double geometric = 0.0, length_u = 0.0, length_v = 0.0;
      const double score = ScoreView(geometry[f], static_cast<int>(f), views[v], options.depth_tolerance, &geometric,
                                     &length_u, &length_v);
      if (!(geometric > 0.0)) continue;
      if (user != nullptr && user->source_image != kNoId &&
          project.images[views[v].image_index].id == user->source_image) {
        forced = static_cast<int>(v);
        forced_u = length_u;
        forced_v = length_v;
      }
      // Views that see the face rank by score; those whose samples are all hidden come last
      // (they may still see some texels).
      ranked.emplace_back(score > 0.0 ? score : -1.0 / geometric, static_cast<int>(v));
      if (score > faces[f].score) {
        faces[f].score = score;
        faces[f].view = static_cast<int>(v);
        best_u = length_u;
        best_v = length_v;
      }
    }
    faces[f].forced_unavailable = user != nullptr && user->source_image != kNoId && forced < 0;
    if (forced >= 0) {
      faces[f].forced = true;
      faces[f].view = forced;
      best_u = forced_u;
      best_v = forced_v;
    }
    if (faces[f].view < 0) continue;
    std::stable_sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
    if (forced >= 0) faces[f].candidates.push_back(forced);
    for (const auto& [score, v] : ranked) {
      if (v != forced) faces[f].candidates.push_back(v);
    }
    if (options.texels_per_unit > 0.0) {
      // The asked density, capped so that the face with its padding fits one page.
      const double cap = std::max(kMinFaceTexels, options.max_atlas_size - 2 * options.padding_texels);
      const Eigen::Vector2d extent = geometry[f].st_max - geometry[f].st_min;
      auto texels = [&](double length) {
        const double n = std::round(length * options.texels_per_unit) + 1.0;
        faces[f].size_capped = faces[f].size_capped || n > cap;
        return static_cast<int>(std::clamp(n, static_cast<double>(kMinFaceTexels), cap));
      };
      faces[f].width = texels(extent.x());
      faces[f].height = texels(extent.y());
    } else {
      auto texels = [&](double length_px) {
        const double n = std::ceil(length_px * options.texels_per_image_px) + 1.0;
        return static_cast<int>(
            std::clamp(n, static_cast<double>(kMinFaceTexels), static_cast<double>(options.max_face_texels)));
      };
      faces[f].width = texels(best_u);
      faces[f].height = texels(best_v);
    }
    textured.push_back(static_cast<int>(f));
  }
  return textured;
}

// Allocates the pages, samples each textured face into its page and points its corners' UVs
// there.
// face_counts gets each textured face's counts, in `textured` order.
void WriteAtlas(const std::vector<FaceGeometry>& geometry, const std::vector<ViewContext>& views,
                const std::vector<int>& textured, const std::vector<FaceTexture>& faces,
                const TextureBakeOptions& options, const std::vector<std::pair<int, int>>& page_sizes,
                TexturedMesh* mesh, bake::SamplingCounts* counts, std::vector<bake::SamplingCounts>* face_counts_out) {
  std::vector<ImageRgba8> pages(page_sizes.size());
  for (size_t p = 0; p < pages.size(); ++p) {
    pages[p].width = page_sizes[p].first;
    pages[p].height = page_sizes[p].second;
    pages[p].pixels.assign(static_cast<size_t>(pages[p].width) * pages[p].height * 4, 0);
  }
  mesh->triangle_page.assign(mesh->triangle_face.size(), 0);
  // Faces write disjoint rectangles (padding included) of their pages: one face per task.
  std::vector<bake::SamplingCounts>& face_counts = *face_counts_out;
  face_counts.assign(textured.size(), {});
  // Largest faces first: the threads then finish together instead of one sampling the last big
  // face alone (what each face writes does not depend on the order).
  std::vector<int> order(textured.size());
  for (size_t k = 0; k < order.size(); ++k) order[k] = static_cast<int>(k);
  auto texels = [&](int k) {
    const FaceTexture& t = faces[textured[k]];
    return static_cast<long>(t.packed_width) * t.packed_height * static_cast<long>(t.candidates.size());
  };
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return texels(a) > texels(b); });
  ParallelFor(static_cast<int>(order.size()), options.max_threads, [&](int n) {
    const int k = order[n];
    const int f = textured[k];
    bake::SampleFace(geometry[f], f, faces[f], views, options, &pages[faces[f].page], &face_counts[k]);
  });
  for (const bake::SamplingCounts& c : face_counts) {
    counts->from_other_views += c.from_other_views;
    counts->hidden += c.hidden;
    counts->forced_fallback += c.forced_fallback;
  }
  for (int f : textured) {
    const FaceTexture& t = faces[f];
    const FaceGeometry& g = geometry[f];
    const ImageRgba8& page = pages[t.page];
    const Eigen::Matrix3d texel_from_face = bake::FaceFromTexel(g, t.packed_width, t.packed_height).inverse();
    for (size_t k = 0; k < g.corners_st.size(); ++k) {
      const Eigen::Vector3d texel = texel_from_face * g.corners_st[k].homogeneous();
      mesh->uvs[g.first_vertex + k] = Eigen::Vector2f(static_cast<float>((t.x + texel.x() + 0.5) / page.width),
                                                      static_cast<float>((t.y + texel.y() + 0.5) / page.height));
    }
    for (size_t tri = 0; tri < g.triangle_count; ++tri) {
      mesh->triangle_textured[g.first_triangle + tri] = 1;
      mesh->triangle_page[g.first_triangle + tri] = static_cast<std::uint8_t>(t.page);
    }
  }
  mesh->atlas = std::move(pages[0]);
  mesh->more_atlas_pages.assign(std::make_move_iterator(pages.begin() + 1), std::make_move_iterator(pages.end()));
}

// One report per face, untextured: what a bake that stops early returns.
std::vector<FaceTextureReport> EmptyReports(const std::vector<FaceGeometry>& geometry) {
  std::vector<FaceTextureReport> reports(geometry.size());
  for (size_t f = 0; f < geometry.size(); ++f) {
    reports[f].primitive_id = geometry[f].primitive_id;
    reports[f].face = geometry[f].face_id;
  }
  return reports;
}

// The per-face reports of a finished bake, and the summary's totals of the overrides.
void ReportFaces(const Project& project, const std::vector<FaceGeometry>& geometry,
                 const std::vector<ViewContext>& views, const std::vector<FaceTexture>& faces,
                 const std::vector<int>& textured, const std::vector<bake::SamplingCounts>& face_counts,
                 TextureBakeSummary* summary) {
  summary->faces = EmptyReports(geometry);
  for (size_t f = 0; f < geometry.size(); ++f) {
    if (faces[f].forced_unavailable) {
      summary->faces[f].forced_unavailable = true;
      ++summary->faces_forced_unavailable;
    }
  }
  for (size_t k = 0; k < textured.size(); ++k) {
    const int f = textured[k];
    const FaceTexture& t = faces[f];
    FaceTextureReport& report = summary->faces[f];
    report.width_texels = t.packed_width;
    report.height_texels = t.packed_height;
    report.size_capped = t.size_capped;
    summary->faces_size_capped += t.size_capped ? 1 : 0;
    if (t.forced) report.forced_image = project.images[views[t.view].image_index].id;
    report.forced_fallback_texels = face_counts[k].forced_fallback;
    const std::vector<double>& share = face_counts[k].view_share;
    double total = 0.0;
    for (double s : share) total += s;
    if (!(total > 0.0)) continue;
    for (size_t c = 0; c < share.size() && c < t.candidates.size(); ++c) {
      if (share[c] > 0.0) {
        report.sources.push_back({project.images[views[t.candidates[c]].image_index].id, share[c] / total});
      }
    }
    std::stable_sort(report.sources.begin(), report.sources.end(),
                     [](const TextureSourceShare& a, const TextureSourceShare& b) { return a.share > b.share; });
  }
}

// "box face 3" for the summary's message.
std::string FaceName(const Project& project, const FaceTextureReport& report) {
  const Primitive* primitive = project.FindPrimitive(report.primitive_id);
  return (primitive != nullptr ? primitive->name : std::string("?")) + " face " + std::to_string(report.face);
}

// What the user's choices did, for the summary's message: empty when nothing to say.
std::string OverrideNotes(const Project& project, const TextureBakeSummary& summary) {
  constexpr size_t kNamedFaces = 3;
  std::string notes;
  auto list = [&](auto pick, const std::string& what) {
    std::vector<std::string> names;
    for (const FaceTextureReport& r : summary.faces) {
      if (pick(r)) names.push_back(FaceName(project, r));
    }
    if (names.empty()) return;
    std::string text;
    for (size_t i = 0; i < names.size() && i < kNamedFaces; ++i) text += (i ? ", " : "") + names[i];
    if (names.size() > kNamedFaces) text += " and " + std::to_string(names.size() - kNamedFaces) + " more";
    notes += "; " + text + ": " + what;
  };
  list([](const FaceTextureReport& r) { return r.forced_fallback_texels > 0; },
       "the forced photo does not see some texels (" + std::to_string(summary.texels_forced_fallback) +
           " in all), taken from the next view");
  list([](const FaceTextureReport& r) { return r.forced_unavailable; },
       "the forced photo cannot texture it (not calibrated, excluded or not facing it), chosen automatically");
  if (summary.images_excluded > 0) {
    notes += "; " + std::to_string(summary.images_excluded) + " photo" + (summary.images_excluded > 1 ? "s" : "") +
             " not used for texture";
  }
  if (summary.faces_size_capped > 0) {
    notes += "; " + std::to_string(summary.faces_size_capped) + " face" + (summary.faces_size_capped > 1 ? "s" : "") +
             " capped at the atlas page size";
  }
  return notes;
}

}  // namespace

TexturedMesh BuildUntexturedMesh(const Project& project) { return BuildMesh(project, nullptr, nullptr); }

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
  } else if (max_atlas_pages < 1 || max_atlas_pages > kMaxAtlasPages) {
    message = "max_atlas_pages must be in [1, " + std::to_string(kMaxAtlasPages) + "], got " +
              std::to_string(max_atlas_pages);
  } else if (!(std::isfinite(depth_map_scale) && depth_map_scale >= 0.05 && depth_map_scale <= 1.0)) {
    message = "depth_map_scale must be in [0.05, 1], got " + std::to_string(depth_map_scale);
  } else if (!(std::isfinite(depth_tolerance) && depth_tolerance >= 0.0 && depth_tolerance <= 0.5)) {
    message = "depth_tolerance must be in [0, 0.5], got " + std::to_string(depth_tolerance);
  } else if (!(std::isfinite(feather_fraction) && feather_fraction >= 0.0 && feather_fraction <= 0.5)) {
    message = "feather_fraction must be in [0, 0.5], got " + std::to_string(feather_fraction);
  } else if (!(std::isfinite(blend_sharpness) && blend_sharpness >= 0.0 && blend_sharpness <= 16.0)) {
    message = "blend_sharpness must be in [0, 16], got " + std::to_string(blend_sharpness);
  } else if (!(std::isfinite(texels_per_unit) && texels_per_unit >= 0.0 && texels_per_unit <= kMaxTexelsPerUnit)) {
    message = "texels_per_unit must be in [0, " + std::to_string(static_cast<int>(kMaxTexelsPerUnit)) +
              "] (0: from the photos), got " + std::to_string(texels_per_unit);
  }
  if (error != nullptr) *error = message;
  return message.empty();
}

TextureBakeSummary BakeTexturedMesh(const Project& project, const std::vector<const ImageRgba8*>& photos,
                                    const TextureBakeOptions& options, TexturedMesh* mesh) {
  const auto start = std::chrono::steady_clock::now();
  TextureBakeSummary summary;
  std::vector<FaceGeometry> geometry;
  std::vector<DepthTriangle> depth_triangles;
  *mesh = BuildMesh(project, &geometry, &depth_triangles);
  const int face_count = static_cast<int>(geometry.size());
  summary.faces_untextured = face_count;
  summary.exposure_gains.assign(project.images.size(), Eigen::Vector3d::Ones());
  summary.faces = EmptyReports(geometry);
  auto fail = [&](const std::string& message, SolverTermination termination = SolverTermination::kFailed) {
    summary.termination = termination;
    summary.message = message;
    summary.time_ms = ElapsedMs(start);
    return summary;
  };
  std::string error;
  if (!options.Check(&error)) return fail("invalid texture options: " + error, SolverTermination::kInvalidInput);
  if (photos.size() != project.images.size()) {
    return fail(
        "got " + std::to_string(photos.size()) + " photos for " + std::to_string(project.images.size()) + " images",
        SolverTermination::kInvalidInput);
  }

  auto step_start = std::chrono::steady_clock::now();
  std::vector<ViewContext> views = UsableViews(project, photos, depth_triangles, options, &summary.images_excluded);
  summary.depth_maps_ms = ElapsedMs(step_start);

  step_start = std::chrono::steady_clock::now();
  std::vector<FaceTexture> faces(geometry.size());
  const std::vector<int> textured = ChooseFaceViews(project, geometry, views, options, &faces);
  summary.selection_ms = ElapsedMs(step_start);
  if (textured.empty()) {
    summary.termination = SolverTermination::kConverged;
    summary.message = geometry.empty() ? "the project has no primitives"
                      : views.empty()  ? "no calibrated image with loaded pixels and used for texture; the mesh is "
                                         "untextured"
                                       : "no face is seen by a calibrated image; the mesh is untextured";
    ReportFaces(project, geometry, views, faces, textured, {}, &summary);
    summary.message += OverrideNotes(project, summary);
    summary.time_ms = ElapsedMs(start);
    return summary;
  }

  // Shrink every face by the same factor until the pages hold them.
  step_start = std::chrono::steady_clock::now();
  double shrink = 1.0;
  std::vector<std::pair<int, int>> page_sizes;
  for (;;) {
    bool all_minimal = true;
    for (int f : textured) {
      FaceTexture& t = faces[f];
      t.packed_width = std::max(kMinFaceTexels, static_cast<int>(std::lround(t.width * shrink)));
      t.packed_height = std::max(kMinFaceTexels, static_cast<int>(std::lround(t.height * shrink)));
      all_minimal = all_minimal && t.packed_width == kMinFaceTexels && t.packed_height == kMinFaceTexels;
    }
    if (PackFaces(textured, options.padding_texels, options.max_atlas_size, options.max_atlas_pages, &faces,
                  &page_sizes)) {
      break;
    }
    if (all_minimal) {
      return fail(std::to_string(textured.size()) + " faces do not fit " + std::to_string(options.max_atlas_pages) +
                  " atlas page(s) of " + std::to_string(options.max_atlas_size) + " even at " +
                  std::to_string(kMinFaceTexels) + " texels per side");
    }
    shrink *= 0.85;
  }
  summary.packing_ms = ElapsedMs(step_start);

  step_start = std::chrono::steady_clock::now();
  if (options.compensate_exposure) bake::FitViewGains(geometry, faces, textured, options, &views);
  for (const ViewContext& view : views) summary.exposure_gains[view.image_index] = view.gain;
  summary.exposure_ms = ElapsedMs(step_start);

  step_start = std::chrono::steady_clock::now();
  bake::SamplingCounts counts;
  std::vector<bake::SamplingCounts> face_counts;
  WriteAtlas(geometry, views, textured, faces, options, page_sizes, mesh, &counts, &face_counts);
  summary.sampling_ms = ElapsedMs(step_start);
  ReportFaces(project, geometry, views, faces, textured, face_counts, &summary);
  summary.texels_forced_fallback = counts.forced_fallback;

  summary.termination = SolverTermination::kConverged;
  summary.faces_textured = static_cast<int>(textured.size());
  summary.faces_untextured = face_count - summary.faces_textured;
  summary.atlas_width = page_sizes[0].first;
  summary.atlas_height = page_sizes[0].second;
  summary.atlas_pages = static_cast<int>(page_sizes.size());
  summary.texels_from_other_views = counts.from_other_views;
  summary.texels_hidden = counts.hidden;
  summary.time_ms = ElapsedMs(start);
  summary.message = "textured " + std::to_string(summary.faces_textured) + " of " + std::to_string(face_count) +
                    " faces into " +
                    (page_sizes.size() > 1 ? std::to_string(page_sizes.size()) + " atlas pages, the first " : "a ") +
                    std::to_string(summary.atlas_width) + "x" + std::to_string(summary.atlas_height) + " atlas" +
                    (shrink < 1.0 ? " (faces shrunk to fit)" : "") + OverrideNotes(project, summary);
  return summary;
}

TextureBakeSummary BakeTexturedMesh(const Project& project, const std::vector<ImageRgba8>& photos,
                                    const TextureBakeOptions& options, TexturedMesh* mesh) {
  std::vector<const ImageRgba8*> pointers;
  pointers.reserve(photos.size());
  for (const ImageRgba8& photo : photos) pointers.push_back(&photo);
  return BakeTexturedMesh(project, pointers, options, mesh);
}

}  // namespace facet
