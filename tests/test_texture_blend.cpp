// The texture bake from several photos (issue 13): per-texel visibility against each photo's
// z-buffer, blending with exposure levelling and feathered weights, footprint-aware sampling and
// atlas pages. Every scene is rendered inside the test from known cameras with a known paint
// (tests/textured_scene.h) and the baked atlas is read back through the mesh's UVs.
#include <algorithm>
#include <array>
#include <cmath>
#include <initializer_list>
#include <string>
#include <vector>

#include <doctest/doctest.h>

#include "core/mesh/operators.h"
#include "core/mesh/primitives.h"
#include "core/texture/depth_map.h"
#include "core/texture/photo_pyramid.h"
#include "core/texture/textured_mesh.h"
#include "core/texture/view_blend.h"
#include "synthetic_scene.h"
#include "textured_scene.h"

using facet::Camera;
using facet::ImageRgba8;
using facet::TextureBakeOptions;
using facet::TexturedMesh;
using facet::TextureSource;
using facet::testing::PaintedFace;

namespace {

// The default box (4 x 3 x 2.5 at the origin) and the look-at point of synthetic_scene.h.
facet::testing::SyntheticSceneOptions BoxOptions() { return {}; }

// A camera of the box scene at `azimuth_deg` around the box's vertical axis from the default one.
Camera CameraAround(double azimuth_deg, double distance_factor = 1.0) {
  facet::testing::SyntheticSceneOptions o = BoxOptions();
  const Eigen::Vector3d offset = (o.camera_center - o.look_at) * distance_factor;
  o.camera_center = o.look_at + Eigen::AngleAxisd(azimuth_deg * M_PI / 180.0, Eigen::Vector3d::UnitZ()) * offset;
  return facet::testing::MakeLookAtCamera(o);
}

// Adds a calibrated image seeing through `camera` (same size as the scene's first image).
void AddView(facet::Project* project, const Camera& camera) {
  facet::Image image = project->images[0];
  image.id = project->NewId();
  image.path = "view" + std::to_string(project->images.size()) + ".png";
  image.camera = camera;
  project->images.push_back(image);
}

// A smooth paint, different on every face, within [40, 215] so no gain clips it.
Eigen::Vector3d SmoothPaint(const PaintedFace& face, const Eigen::Vector3d& x) {
  static const Eigen::Vector3d kBase[6] = {{150, 90, 80},  {80, 150, 90},  {90, 80, 150},
                                           {140, 140, 70}, {140, 70, 140}, {70, 140, 140}};
  const double wave = 25.0 * std::sin(1.3 * x.x()) * std::cos(0.9 * x.y()) + 20.0 * std::sin(1.1 * x.z());
  return kBase[face.index % 6] + Eigen::Vector3d::Constant(wave);
}

double MaxChannelDiff(const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return (a - b).cwiseAbs().maxCoeff(); }

const PaintedFace* FaceWithNormal(const std::vector<PaintedFace>& faces, facet::Id primitive,
                                  const Eigen::Vector3d& normal) {
  for (const PaintedFace& f : faces) {
    if (f.primitive_id == primitive && (f.normal - normal).norm() < 1e-9) return &f;
  }
  return nullptr;
}

// Whether `camera` sees world point x on `face`, and every point within margin_px of it in its
// photo shows the same face (ray-cast, independent of the bake's z-buffer).
bool ClearlySeen(const std::vector<PaintedFace>& faces, const PaintedFace& face, const Camera& camera,
                 const Eigen::Vector3d& x, double margin_px) {
  const Eigen::Vector3d p_in_cam = camera.CamFromWorld(x);
  if (!(p_in_cam.z() > 0.0)) return false;
  const Eigen::Vector2d uv = camera.Project(x);
  for (int k = 0; k < 9; ++k) {
    const Eigen::Vector2d probe = uv + margin_px * Eigen::Vector2d(k % 3 - 1, k / 3 - 1);
    if (probe.x() < 0 || probe.y() < 0 || probe.x() > camera.width_px - 1 || probe.y() > camera.height_px - 1) {
      return false;
    }
    Eigen::Vector3d hit;
    const PaintedFace* first =
        facet::testing::FirstFaceHit(faces, camera.CenterInWorld(), camera.RayDirectionInWorld(probe), &hit);
    if (first == nullptr || first->index != face.index) return false;
  }
  return true;
}

struct Stats {
  int points = 0;
  int over = 0;  // beyond the tolerance
  double worst = 0.0;
  double mean = 0.0;
};

Stats Compare(const TexturedMesh& mesh, const PaintedFace& face, const std::vector<Eigen::Vector3d>& points,
              const facet::testing::Paint& paint, double tolerance) {
  Stats s;
  for (const Eigen::Vector3d& x : points) {
    Eigen::Vector3d baked;
    REQUIRE(facet::testing::BakedColourAt(mesh, face, x, &baked));
    const double d = MaxChannelDiff(baked, paint(face, x));
    ++s.points;
    s.over += d > tolerance;
    s.worst = std::max(s.worst, d);
    s.mean += d;
  }
  if (s.points > 0) s.mean /= s.points;
  return s;
}

// The box scene with one more photo per azimuth (CameraAround), every photo ray-cast with
// SmoothPaint, photo k at exposure gain first_gain + k x gain_step.
struct BoxSeenAround {
  facet::testing::SyntheticScene scene;
  std::vector<PaintedFace> faces;
  std::vector<ImageRgba8> photos;
};
BoxSeenAround MakeBoxSeenAround(std::initializer_list<double> azimuths, double first_gain = 1.0,
                                double gain_step = 0.0) {
  BoxSeenAround b{facet::testing::MakeBoxScene(BoxOptions()), {}, {}};
  for (double azimuth : azimuths) AddView(&b.scene.project, CameraAround(azimuth));
  b.faces = facet::testing::PaintedFaces(b.scene.project);
  for (const facet::Image& image : b.scene.project.images)
    b.photos.push_back(facet::testing::RenderTexturedPhoto(b.faces, image.camera, SmoothPaint,
                                                           first_gain + gain_step * b.photos.size()));
  return b;
}

}  // namespace

TEST_CASE("blended bake from four views: every face seen matches its known paint") {
  const auto [scene, faces, photos] = MakeBoxSeenAround({90.0, 180.0, 270.0});
  TexturedMesh mesh;
  const auto summary = facet::BakeTexturedMesh(scene.project, photos, TextureBakeOptions{}, &mesh);
  REQUIRE_MESSAGE(summary.IsUsable(), summary.message);
  MESSAGE(summary.message << "; " << summary.time_ms << " ms");
  CHECK(summary.faces_textured == 5);  // all but the bottom
  CHECK(summary.texels_from_other_views > 0);
  // Equal exposures: the fitted gains stay at 1 to within what bilinear sampling of the same
  // paint in different views differs by.
  constexpr double kGainTolerance = 0.01;
  for (const Eigen::Vector3d& gain : summary.exposure_gains) {
    CAPTURE(gain.transpose());
    CHECK((gain - Eigen::Vector3d::Ones()).cwiseAbs().maxCoeff() < kGainTolerance);
  }
  // The paint changes by at most ~1.5 levels per photo pixel; bilinear sampling of it and the
  // blend of views that agree stay within a few levels, plus 1 % of gain.
  constexpr double kTolerance = 6.0;    // grey levels, per channel
  constexpr double kInsetMetres = 0.1;  // ~9 photo px from each outline: clear of the neighbours
  constexpr double kMaxOverFraction = 0.01;
  for (const PaintedFace& face : faces) {
    CAPTURE(face.index);
    CAPTURE(face.normal.transpose());
    Eigen::Vector3d rgb;
    if (face.normal.z() < -0.5) {
      CHECK_FALSE(facet::testing::BakedColourAt(mesh, face, face.corners[0], &rgb));
      continue;
    }
    const Stats s = Compare(mesh, face, facet::testing::FaceGrid(face, 24, kInsetMetres), SmoothPaint, kTolerance);
    CAPTURE(s.worst);
    CAPTURE(s.mean);
    CHECK(s.points > 200);
    CHECK(s.over <= kMaxOverFraction * s.points);
    CHECK(s.mean < 2.0);
  }
}

TEST_CASE("occluder: texels hidden in the chosen view come from the other view, blended or best view") {
  auto scene = facet::testing::MakeBoxScene(BoxOptions());
  // A post in front of the -Y face, as seen from view 1 (frontal): it hides a band of the face.
  facet::PrimitiveShape post = facet::MakeBox(facet::kNoId, Eigen::Vector3d(0.6, 0.6, 3.0));
  post.translation = Eigen::Vector3d(1.2, -2.5, 0.0);
  std::string message;
  REQUIRE(facet::AddPrimitiveToProject(&scene.project, post, "post", nullptr, &message));
  facet::testing::SyntheticSceneOptions o1, o2;
  o1.camera_center = {2.0, -11.0, 1.6};
  o1.look_at = {2.0, 0.0, 1.2};
  o2.camera_center = {11.0, -8.0, 3.0};
  o2.look_at = {2.0, 0.0, 1.2};
  const Camera cam1 = facet::testing::MakeLookAtCamera(o1);
  const Camera cam2 = facet::testing::MakeLookAtCamera(o2);
  scene.project.images[0].camera = cam1;
  AddView(&scene.project, cam2);
  const std::vector<PaintedFace> faces = facet::testing::PaintedFaces(scene.project);
  const PaintedFace* front = FaceWithNormal(faces, scene.box_id, -Eigen::Vector3d::UnitY());
  REQUIRE(front != nullptr);
  // The post is magenta, everything else its smooth paint: a texel showing magenta is the post.
  const Eigen::Vector3d kPostColour(250, 0, 250);
  const facet::testing::Paint paint = [&](const PaintedFace& face, const Eigen::Vector3d& x) {
    return face.primitive_id == scene.box_id ? SmoothPaint(face, x) : kPostColour;
  };
  const std::vector<ImageRgba8> photos = {facet::testing::RenderTexturedPhoto(faces, cam1, paint),
                                          facet::testing::RenderTexturedPhoto(faces, cam2, paint)};

  // Points of the front face view 1 cannot see (the post hides them) but view 2 sees clearly,
  // and points view 1 sees clearly.
  constexpr double kMarginPx = 3.0;  // bilinear reach plus the z-buffer's pixel at half scale
  std::vector<Eigen::Vector3d> hidden_in_1, seen_in_1;
  for (const Eigen::Vector3d& x : facet::testing::FaceGrid(*front, 40, 0.1)) {
    const bool seen1 = ClearlySeen(faces, *front, cam1, x, 0.0);
    if (!seen1 && ClearlySeen(faces, *front, cam2, x, kMarginPx)) hidden_in_1.push_back(x);
    if (ClearlySeen(faces, *front, cam1, x, kMarginPx)) seen_in_1.push_back(x);
  }
  CAPTURE(hidden_in_1.size());
  CAPTURE(seen_in_1.size());
  REQUIRE(hidden_in_1.size() > 50);
  REQUIRE(seen_in_1.size() > 400);

  for (const TextureSource source : {TextureSource::kBestView, TextureSource::kBlended}) {
    CAPTURE(static_cast<int>(source));
    TextureBakeOptions options;
    options.source = source;
    TexturedMesh mesh;
    const auto summary = facet::BakeTexturedMesh(scene.project, photos, options, &mesh);
    REQUIRE_MESSAGE(summary.IsUsable(), summary.message);
    CHECK(summary.texels_from_other_views > 0);
    // View 1 is the front face's best view (frontal, near, mostly unoccluded).
    constexpr double kTolerance = 6.0;
    const Stats hidden = Compare(mesh, *front, hidden_in_1, paint, kTolerance);
    const Stats seen = Compare(mesh, *front, seen_in_1, paint, kTolerance);
    CAPTURE(hidden.worst);
    CAPTURE(seen.worst);
    CHECK(hidden.over == 0);  // the paint, not the post (>= 100 levels away in R or G)
    CHECK(seen.over == 0);
  }
  // Without view 2 the hidden texels have no source: they are dilated from the face's seen
  // texels, never painted with the post.
  TexturedMesh only_one;
  const auto single = facet::BakeTexturedMesh(scene.project, {photos[0], ImageRgba8()}, {}, &only_one);
  REQUIRE_MESSAGE(single.IsUsable(), single.message);
  CHECK(single.texels_hidden > 0);
  int magenta = 0;
  for (const Eigen::Vector3d& x : hidden_in_1) {
    Eigen::Vector3d rgb;
    REQUIRE(facet::testing::BakedColourAt(only_one, *front, x, &rgb));
    magenta += MaxChannelDiff(rgb, kPostColour) < 60.0;
  }
  CHECK(magenta == 0);
}

TEST_CASE("exposure: two photos at different gains meet without a seam when blended, with one when not") {
  auto scene = facet::testing::MakeBoxScene(BoxOptions());
  // View 1 frontal to the -Y face, view 2 frontal to the +X face; both see both faces, so the
  // best view changes at their shared edge x = 4, y = 0.
  facet::testing::SyntheticSceneOptions o1, o2;
  o1.camera_center = {6.0, -10.0, 3.0};
  o1.look_at = {3.0, 0.0, 1.2};
  o2.camera_center = {14.0, -3.0, 3.0};
  o2.look_at = {4.0, 1.0, 1.2};
  const Camera cam1 = facet::testing::MakeLookAtCamera(o1);
  const Camera cam2 = facet::testing::MakeLookAtCamera(o2);
  scene.project.images[0].camera = cam1;
  AddView(&scene.project, cam2);
  const std::vector<PaintedFace> faces = facet::testing::PaintedFaces(scene.project);
  const PaintedFace* front = FaceWithNormal(faces, scene.box_id, -Eigen::Vector3d::UnitY());
  const PaintedFace* side = FaceWithNormal(faces, scene.box_id, Eigen::Vector3d::UnitX());
  REQUIRE(front != nullptr);
  REQUIRE(side != nullptr);
  // One uniform paint everywhere: any step across the edge is a seam.
  const facet::testing::Paint paint = [](const PaintedFace&, const Eigen::Vector3d&) {
    return Eigen::Vector3d(170, 150, 130);
  };
  constexpr double kGain2 = 0.7;
  const std::vector<ImageRgba8> photos = {facet::testing::RenderTexturedPhoto(faces, cam1, paint, 1.0),
                                          facet::testing::RenderTexturedPhoto(faces, cam2, paint, kGain2)};

  // The step across the edge: mean colour at 0.15 m (~10 photo px) on each side along the
  // edge's middle 60 %, the largest channel difference.
  auto step_across_edge = [&](const TexturedMesh& mesh) {
    constexpr double kOffset = 0.15;
    Eigen::Vector3d sum_front = Eigen::Vector3d::Zero(), sum_side = Eigen::Vector3d::Zero();
    int n = 0;
    for (double z = 0.5; z <= 2.0; z += 0.05) {
      Eigen::Vector3d a, b;
      REQUIRE(facet::testing::BakedColourAt(mesh, *front, Eigen::Vector3d(4.0 - kOffset, 0.0, z), &a));
      REQUIRE(facet::testing::BakedColourAt(mesh, *side, Eigen::Vector3d(4.0, kOffset, z), &b));
      sum_front += a;
      sum_side += b;
      ++n;
    }
    return ((sum_front - sum_side) / n).cwiseAbs().maxCoeff();
  };

  TexturedMesh blended, best_view;
  const auto blended_summary = facet::BakeTexturedMesh(scene.project, photos, TextureBakeOptions{}, &blended);
  TextureBakeOptions paper;
  paper.source = TextureSource::kBestView;
  paper.compensate_exposure = false;
  const auto best_summary = facet::BakeTexturedMesh(scene.project, photos, paper, &best_view);
  REQUIRE_MESSAGE(blended_summary.IsUsable(), blended_summary.message);
  REQUIRE_MESSAGE(best_summary.IsUsable(), best_summary.message);
  // The fitted gains undo the exposure difference: g1 / g2 = 0.7 to within the fit's prior.
  const Eigen::Vector3d ratio = blended_summary.exposure_gains[0].cwiseQuotient(blended_summary.exposure_gains[1]);
  CAPTURE(ratio.transpose());
  constexpr double kRatioTolerance = 0.01;
  CHECK((ratio - Eigen::Vector3d::Constant(kGain2)).cwiseAbs().maxCoeff() < kRatioTolerance);

  const double blended_step = step_across_edge(blended);
  const double best_step = step_across_edge(best_view);
  MESSAGE("step across the edge: blended " << blended_step << ", best view without levelling " << best_step
                                           << " grey levels");
  // Unlevelled, the step is (1 - 0.7) x the paint: 51 levels in red.
  constexpr double kMaxBlendedStep = 2.0;  // grey levels
  constexpr double kMinVisibleStep = 30.0;
  CHECK(blended_step < kMaxBlendedStep);
  CHECK(best_step > kMinVisibleStep);
}

TEST_CASE("aliasing: a checkerboard at a grazing angle in a 12 MP photo bakes like its area average") {
  // A 4 x 3 m ground plane with a checker of 2 x 7 cm cells, seen from 1.5 m high (11 - 14
  // degrees of elevation) by a 4000 x 3000 camera, which resolves every cell (>= 4 px). Baked at
  // 1/32 texel per photo pixel, a texel spans about 3 cells across and 4 deep: averaged over
  // its footprint it shows about the cells' mean, sampled at one point it shows one cell (moire).
  facet::testing::SyntheticSceneOptions o;
  o.width_px = 4000;
  o.height_px = 3000;
  o.focal_px = 3600.0;
  o.principal_point_offset_px = {0.0, 0.0};
  o.roll_deg = 0.0;
  o.camera_center = {2.0, -6.0, 1.5};
  o.look_at = {2.0, 1.5, 0.0};
  auto scene = facet::testing::MakeBoxScene(o);
  scene.project.primitives.clear();
  scene.project.pins.clear();
  std::string message;
  REQUIRE(facet::AddPrimitiveToProject(&scene.project, facet::MakePlane(facet::kNoId, 4.0, 3.0), "ground", nullptr,
                                       &message));
  const std::vector<PaintedFace> faces = facet::testing::PaintedFaces(scene.project);
  REQUIRE(faces.size() == 1);
  constexpr double kCellX = 0.02, kCellY = 0.07;
  const facet::testing::Paint checker = [](const PaintedFace&, const Eigen::Vector3d& x) {
    const int parity =
        (static_cast<int>(std::floor(x.x() / kCellX)) + static_cast<int>(std::floor(x.y() / kCellY))) & 1;
    return Eigen::Vector3d::Constant(parity ? 220.0 : 40.0);
  };
  // The photo resolves the cells: at the far edge a cell is still this many pixels across and deep.
  const Camera& cam = scene.true_camera;
  const double far_cell_deep_px = (cam.Project({2.0, 3.0 - kCellY, 0.0}) - cam.Project({2.0, 3.0, 0.0})).norm();
  const double far_cell_wide_px = (cam.Project({2.0 + kCellX, 3.0, 0.0}) - cam.Project({2.0, 3.0, 0.0})).norm();
  CAPTURE(far_cell_deep_px);
  CAPTURE(far_cell_wide_px);
  REQUIRE(far_cell_deep_px > 4.0);
  REQUIRE(far_cell_wide_px > 4.0);
  const ImageRgba8 photo = facet::testing::RenderTexturedPhoto(faces, cam, checker, 1.0, 2);

  TextureBakeOptions options;
  options.texels_per_image_px = 1.0 / 32.0;
  TexturedMesh filtered, point_sampled;
  const auto summary = facet::BakeTexturedMesh(scene.project, {photo}, options, &filtered);
  REQUIRE_MESSAGE(summary.IsUsable(), summary.message);
  MESSAGE(summary.message << "; " << summary.time_ms << " ms");
  options.filter_footprint = false;
  REQUIRE(facet::BakeTexturedMesh(scene.project, {photo}, options, &point_sampled).IsUsable());

  // The reference: each texel's paint averaged over the texel's square on the plane (16 x 16
  // points), the texel read back from the UVs (affine on this single quad).
  const PaintedFace& face = faces[0];
  const TexturedMesh& m = filtered;
  REQUIRE(m.uvs.size() == 4);
  Eigen::Matrix<double, 4, 3> a;
  Eigen::Matrix<double, 4, 2> b;
  for (int k = 0; k < 4; ++k) {
    a.row(k) << m.positions[k].x(), m.positions[k].y(), 1.0;
    b.row(k) << m.uvs[k].x() * m.atlas.width - 0.5, m.uvs[k].y() * m.atlas.height - 0.5;
  }
  const Eigen::Matrix<double, 3, 2> texel_from_xy = a.colPivHouseholderQr().solve(b);
  const Eigen::Matrix2d linear = texel_from_xy.topRows<2>().transpose();
  const Eigen::Matrix2d xy_from_texel = linear.inverse();
  const Eigen::Vector2d offset = texel_from_xy.row(2).transpose();
  double sum_sq_filtered = 0.0, sum_sq_point = 0.0;
  int texels = 0;
  Eigen::Vector2d lo(1e9, 1e9), hi(-1e9, -1e9);
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector2d t = linear * Eigen::Vector2d(m.positions[k].x(), m.positions[k].y()) + offset;
    lo = lo.cwiseMin(t);
    hi = hi.cwiseMax(t);
  }
  constexpr int kInsetTexels = 2;
  for (int j = static_cast<int>(std::ceil(lo.y())) + kInsetTexels; j <= static_cast<int>(hi.y()) - kInsetTexels; ++j) {
    for (int i = static_cast<int>(std::ceil(lo.x())) + kInsetTexels; i <= static_cast<int>(hi.x()) - kInsetTexels;
         ++i) {
      double reference = 0.0;
      constexpr int kSub = 16;
      for (int q = 0; q < kSub * kSub; ++q) {
        const Eigen::Vector2d texel(i - 0.5 + (q % kSub + 0.5) / kSub, j - 0.5 + (q / kSub + 0.5) / kSub);
        const Eigen::Vector2d xy = xy_from_texel * (texel - offset);
        reference += checker(face, Eigen::Vector3d(xy.x(), xy.y(), 0.0))[0];
      }
      reference /= kSub * kSub;
      const double got = filtered.atlas.At(i, j)[0];
      const double point = point_sampled.atlas.At(i, j)[0];
      sum_sq_filtered += (got - reference) * (got - reference);
      sum_sq_point += (point - reference) * (point - reference);
      ++texels;
    }
  }
  REQUIRE(texels > 300);
  const double rms_filtered = std::sqrt(sum_sq_filtered / texels);
  const double rms_point = std::sqrt(sum_sq_point / texels);
  MESSAGE("RMS against the area average over " << texels << " texels: footprint-averaged " << rms_filtered
                                               << ", point-sampled " << rms_point << " grey levels");
  // The checker's contrast is 180 levels; the reference stays within ~15 of the mean (a
  // texel's partial cells). The footprint average blurs a little beyond the texel (a level
  // pixel, a quarter to half of the footprint), point sampling is off by up to 90 levels
  // wherever it lands on one cell.
  constexpr double kMaxRms = 8.0;
  CHECK(rms_filtered < kMaxRms);
  CHECK(rms_point > 4.0 * kMaxRms);
}

TEST_CASE("atlas pages: faces that overflow a page go to the next one, each face on its page") {
  const auto [scene, faces, photos] = MakeBoxSeenAround({90.0, 180.0, 270.0});
  // A small page stands for 8192: the packing does not depend on the size.
  TextureBakeOptions options;
  options.max_atlas_size = 512;
  options.max_atlas_pages = 4;
  TexturedMesh paged;
  const auto summary = facet::BakeTexturedMesh(scene.project, photos, options, &paged);
  REQUIRE_MESSAGE(summary.IsUsable(), summary.message);
  MESSAGE(summary.message);
  CHECK(summary.atlas_pages > 1);
  CHECK(paged.AtlasPageCount() == summary.atlas_pages);
  CHECK(summary.message.find("shrunk") == std::string::npos);
  REQUIRE(paged.triangle_page.size() == paged.triangle_face.size());
  for (const ImageRgba8& page : paged.more_atlas_pages) {
    CHECK(page.width <= 512);
    CHECK(page.height <= 512);
  }
  std::vector<int> pages_used;
  for (size_t t = 0; t < paged.triangle_page.size(); ++t) {
    if (paged.triangle_textured[t]) pages_used.push_back(paged.triangle_page[t]);
  }
  CHECK(*std::max_element(pages_used.begin(), pages_used.end()) == summary.atlas_pages - 1);
  for (const auto& uv : paged.uvs) CHECK((uv.x() >= 0 && uv.x() <= 1 && uv.y() >= 0 && uv.y() <= 1));

  // One page of the same size shrinks the faces instead; both match the paint.
  options.max_atlas_pages = 1;
  TexturedMesh shrunk;
  const auto one_page = facet::BakeTexturedMesh(scene.project, photos, options, &shrunk);
  REQUIRE_MESSAGE(one_page.IsUsable(), one_page.message);
  CHECK(one_page.atlas_pages == 1);
  CHECK(one_page.message.find("shrunk") != std::string::npos);
  constexpr double kTolerance = 6.0;
  for (const PaintedFace& face : faces) {
    if (face.normal.z() < -0.5) continue;  // the bottom: no view
    CAPTURE(face.index);
    const std::vector<Eigen::Vector3d> points = facet::testing::FaceGrid(face, 20, 0.1);
    const Stats s = Compare(paged, face, points, SmoothPaint, kTolerance);
    CAPTURE(s.worst);
    CHECK(s.over <= 0.01 * s.points);
  }
}

TEST_CASE("padding and hidden texels are dilated from the face's own texels, not the photo around it") {
  // An L-shaped (non-convex) face: a 4 x 3 plane split by V_connect, one split vertex pulled
  // in; the other part of the plane has another colour, as does the background.
  auto scene = facet::testing::MakeBoxScene(BoxOptions());
  scene.project.primitives.clear();
  scene.project.pins.clear();
  std::string message;
  REQUIRE(facet::AddPrimitiveToProject(&scene.project, facet::MakePlane(facet::kNoId, 4.0, 3.0), "ground", nullptr,
                                       &message));
  facet::Primitive& plane = scene.project.primitives[0];
  facet::PolyMesh& mesh = plane.mesh;
  facet::FaceId face_id = facet::kNoFace;
  for (facet::FaceId f = 0; f < mesh.FaceIdEnd(); ++f) {
    if (mesh.IsFace(f)) face_id = f;
  }
  const std::vector<facet::HalfedgeId> sides = facet::FaceHalfedges(mesh, face_id);
  const auto split_a = facet::ESplit(&mesh, facet::PolyMesh::EdgeOf(sides[0]), 0.5);
  const auto split_b = facet::ESplit(&mesh, facet::PolyMesh::EdgeOf(sides[2]), 0.5);
  REQUIRE(split_a.ok);
  REQUIRE(split_b.ok);
  REQUIRE(facet::VConnect(&mesh, face_id, split_a.vertex, split_b.vertex).ok);
  facet::MeshVertex& moved = mesh.vertex(split_a.vertex);
  const Eigen::Vector3d a_local = moved.LocalPosition(plane.shape.params);
  const Eigen::Vector3d b_local = mesh.vertex(split_b.vertex).LocalPosition(plane.shape.params);
  moved.local.free = true;
  moved.local.offset = Eigen::Vector3d::Zero();
  moved.local.offset =
      (a_local + 0.5 * (b_local - a_local) + Eigen::Vector3d(-1.5, 0, 0)) - moved.LocalPosition(plane.shape.params);
  facet::RefreshPrimitive(&scene.project, &plane);
  const std::vector<PaintedFace> faces = facet::testing::PaintedFaces(scene.project);
  REQUIRE(faces.size() == 2);
  const facet::testing::Paint paint = [](const PaintedFace& face, const Eigen::Vector3d&) {
    return face.index == 0 ? Eigen::Vector3d(200, 60, 60) : Eigen::Vector3d(60, 60, 200);
  };
  const ImageRgba8 photo = facet::testing::RenderTexturedPhoto(faces, scene.true_camera, paint);
  TexturedMesh baked;
  const auto summary = facet::BakeTexturedMesh(scene.project, {photo}, TextureBakeOptions{}, &baked);
  REQUIRE_MESSAGE(summary.IsUsable(), summary.message);
  // Every texel of each face's rectangle and padding, read from the atlas around the face's
  // UV bounds, carries that face's colour: nothing of the other face or the background.
  const int pad = TextureBakeOptions().padding_texels;
  for (const PaintedFace& face : faces) {
    CAPTURE(face.index);
    Eigen::Vector2d lo(1e9, 1e9), hi(-1e9, -1e9);
    for (size_t t = 0; t < baked.triangle_face.size(); ++t) {
      if (baked.triangle_face[t] != face.face) continue;
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector2f& uv = baked.uvs[baked.indices[3 * t + k]];
        const Eigen::Vector2d texel(uv.x() * baked.atlas.width - 0.5, uv.y() * baked.atlas.height - 0.5);
        lo = lo.cwiseMin(texel);
        hi = hi.cwiseMax(texel);
      }
    }
    const Eigen::Vector3d want = paint(face, face.corners[0]);
    int checked = 0, off = 0;
    for (int y = static_cast<int>(std::lround(lo.y())) - pad; y <= static_cast<int>(std::lround(hi.y())) + pad; ++y) {
      for (int x = static_cast<int>(std::lround(lo.x())) - pad; x <= static_cast<int>(std::lround(hi.x())) + pad; ++x) {
        const std::uint8_t* p = baked.atlas.At(x, y);
        ++checked;
        // Solid paint: bilinear between equal pixels is exact to rounding, except texels of
        // the outline's half-texel band, which the photo blends with the neighbour.
        off += MaxChannelDiff(Eigen::Vector3d(p[0], p[1], p[2]), want) > 70.0;
      }
    }
    CAPTURE(checked);
    CAPTURE(off);
    CHECK(checked > 1000);
    CHECK(off == 0);
  }
}

TEST_CASE("depth map: a known depth, the face ids, and boundary distances at a silhouette and a step") {
  // A 4 x 4 m square at z = 10 in front of a camera at the origin looking along +z (u, v in
  // [119.5, 279.5]), and a 1 x 1 m square at z = 5 over its right half (u in [199.5, 279.5],
  // v in [159.5, 239.5]).
  Camera cam;
  cam.width_px = 400;
  cam.height_px = 400;
  cam.focal_px = 400.0;
  cam.principal_point_px = {199.5, 199.5};
  std::vector<facet::DepthTriangle> tris;
  auto square = [&](double x0, double y0, double size, double z, int face) {
    const Eigen::Vector3d a(x0, y0, z), b(x0 + size, y0, z), c(x0 + size, y0 + size, z), d(x0, y0 + size, z);
    tris.push_back({{a, b, c}, face});
    tris.push_back({{a, c, d}, face});
  };
  square(-2.0, -2.0, 4.0, 10.0, 0);
  square(0.0, -0.5, 1.0, 5.0, 1);
  facet::DepthMapOptions options;
  options.scale = 1.0;
  const facet::DepthMap map = facet::RenderDepthMap(tris, cam, 400, 400, Eigen::Vector2d::Ones(), options);
  REQUIRE(map.width == 400);
  REQUIRE(map.height == 400);
  auto at = [&](double u, double v) {
    const Eigen::Vector2d m = map.MapFromPinhole({u, v});
    return static_cast<size_t>(m.y()) * map.width + static_cast<size_t>(m.x());
  };
  CHECK(map.face[at(150, 199.5)] == 0);
  CHECK(std::abs(map.depth[at(150, 199.5)] - 10.0f) < 1e-4f);
  CHECK(map.face[at(240, 199.5)] == 1);
  CHECK(std::abs(map.depth[at(240, 199.5)] - 5.0f) < 1e-4f);
  CHECK(map.face[at(20, 20)] == -1);
  // Seen: a point of the big square left of the small one; hidden: behind the small one.
  CHECK(map.Sees({150, 199.5}, 10.0, 0, 0.01));
  CHECK_FALSE(map.Sees({240, 199.5}, 10.0, 0, 0.01));
  // Boundary distance, in px (3-4 chamfer: within 8 %, plus the boundary pixel's own 1.5 px):
  // 20 px from the silhouette at u = 119.5, 20 px from the step at u = 199.5.
  CHECK(std::abs(map.BoundaryDistancePx({139.5, 199.5}) - 20.0f) < 0.08f * 20.0f + 1.5f);
  CHECK(std::abs(map.BoundaryDistancePx({179.5, 199.5}) - 20.0f) < 0.08f * 20.0f + 1.5f);
  CHECK(map.BoundaryDistancePx({159.5, 199.5}) > 35.0f);
}

TEST_CASE("exposure gains: Brown-Lowe's fit recovers known gain ratios; the pyramid averages a footprint") {
  // Three views of surfaces whose true colour is c: view v saw c / g_v. The fit must find
  // gains proportional to g_v.
  const Eigen::Vector3d true_gain[3] = {{1.0, 1.0, 1.0}, {1.25, 1.1, 0.9}, {0.8, 0.95, 1.2}};
  const Eigen::Vector3d colour(120, 100, 80);
  std::vector<facet::ExposureOverlap> overlaps;
  for (int a = 0; a < 3; ++a) {
    for (int b = a + 1; b < 3; ++b) {
      facet::ExposureOverlap o;
      o.view_a = a;
      o.view_b = b;
      o.count = 500;
      o.sum_a = o.count * colour.cwiseQuotient(true_gain[a]);
      o.sum_b = o.count * colour.cwiseQuotient(true_gain[b]);
      overlaps.push_back(o);
    }
  }
  const std::vector<Eigen::Vector3d> gains = facet::FitExposureGains(3, overlaps);
  REQUIRE(gains.size() == 3);
  constexpr double kRatioTolerance = 1e-3;  // the prior's pull on ratios, relative
  for (int v = 1; v < 3; ++v) {
    const Eigen::Vector3d want = true_gain[v].cwiseQuotient(true_gain[0]);
    const Eigen::Vector3d got = gains[v].cwiseQuotient(gains[0]);
    CAPTURE(v);
    CAPTURE(got.transpose());
    CHECK((got - want).cwiseQuotient(want).cwiseAbs().maxCoeff() < kRatioTolerance);
  }
  CHECK(facet::FitExposureGains(2, {})[1].isApprox(Eigen::Vector3d::Ones()));

  // A 1-px checker averaged over an 8 x 8 footprint is its mean; bilinear at a pixel centre is
  // the pixel.
  ImageRgba8 checker;
  checker.width = checker.height = 64;
  checker.pixels.resize(64 * 64 * 4);
  for (int y = 0; y < 64; ++y) {
    for (int x = 0; x < 64; ++x) {
      std::uint8_t* p = checker.At(x, y);
      p[0] = p[1] = p[2] = ((x + y) & 1) ? 200 : 40;
      p[3] = 255;
    }
  }
  const facet::PhotoPyramid pyramid(&checker, true);
  float rgba[4];
  REQUIRE(pyramid.Sample(31.5, 31.5, {8.0, 0.0}, {0.0, 8.0}, rgba));
  CHECK(std::abs(rgba[0] - 120.0f) < 1.0f);
  REQUIRE(pyramid.Sample(10.0, 11.0, Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero(), rgba));
  CHECK(rgba[0] == 200.0f);
  CHECK_FALSE(pyramid.Sample(-1.0, 5.0, Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero(), rgba));
}

TEST_CASE("the bake's threads do not change its result: one thread and two give the same atlas") {
  const auto [scene, faces, photos] = MakeBoxSeenAround({90.0, 180.0}, 0.8, 0.1);
  TextureBakeOptions one, two;
  one.max_threads = 1;
  two.max_threads = 2;
  TexturedMesh a, b;
  REQUIRE(facet::BakeTexturedMesh(scene.project, photos, one, &a).IsUsable());
  REQUIRE(facet::BakeTexturedMesh(scene.project, photos, two, &b).IsUsable());
  REQUIRE(a.atlas.pixels.size() > 1000);
  CHECK(a.atlas.pixels == b.atlas.pixels);
  CHECK(a.uvs == b.uvs);
}

namespace {

// The report of `face` in a bake's summary (REQUIREd present).
const facet::FaceTextureReport& ReportOf(const facet::TextureBakeSummary& summary, const PaintedFace& face) {
  for (const facet::FaceTextureReport& r : summary.faces) {
    if (r.primitive_id == face.primitive_id && r.face == face.face) return r;
  }
  FAIL("no report for face " << face.face);
  return summary.faces.front();
}

double ShareOf(const facet::FaceTextureReport& report, facet::Id image_id) {
  for (const facet::TextureSourceShare& s : report.sources) {
    if (s.image_id == image_id) return s.share;
  }
  return 0.0;
}

}  // namespace

TEST_CASE("the user's say: per-face sources, a forced photo, per-face and global exclusions") {
  // Three photos of the box, each at its own gain and without exposure levelling, so that a
  // texel's colour tells which photo it came from: view 1 frontal to the -Y face, view 2
  // frontal to the +X face and grazing the -Y face, view 3 a close-up of the -Y face's left
  // part (its frame ends near x = 2.4 m of the 4 m face).
  auto scene = facet::testing::MakeBoxScene(BoxOptions());
  facet::testing::SyntheticSceneOptions o1, o2, o3;
  o1.camera_center = {2.0, -11.0, 1.6};
  o1.look_at = {2.0, 0.0, 1.2};
  o2.camera_center = {14.0, -3.0, 3.0};
  o2.look_at = {4.0, 1.0, 1.2};
  o3.camera_center = {1.0, -2.5, 1.2};
  o3.look_at = {1.0, 0.0, 1.2};
  const std::array<Camera, 3> cams = {facet::testing::MakeLookAtCamera(o1), facet::testing::MakeLookAtCamera(o2),
                                      facet::testing::MakeLookAtCamera(o3)};
  scene.project.images[0].camera = cams[0];
  AddView(&scene.project, cams[1]);
  AddView(&scene.project, cams[2]);
  const std::array<facet::Id, 3> ids = {scene.project.images[0].id, scene.project.images[1].id,
                                        scene.project.images[2].id};
  const std::vector<PaintedFace> faces = facet::testing::PaintedFaces(scene.project);
  const PaintedFace* front = FaceWithNormal(faces, scene.box_id, -Eigen::Vector3d::UnitY());
  const PaintedFace* side = FaceWithNormal(faces, scene.box_id, Eigen::Vector3d::UnitX());
  REQUIRE(front != nullptr);
  REQUIRE(side != nullptr);
  const Eigen::Vector3d kPaint(170, 150, 130);
  const facet::testing::Paint paint = [&](const PaintedFace&, const Eigen::Vector3d&) { return kPaint; };
  const std::array<double, 3> gains = {1.0, 0.6, 0.8};
  std::vector<ImageRgba8> photos;
  std::array<Eigen::Vector3d, 3> photo_colour;
  for (int k = 0; k < 3; ++k) {
    photos.push_back(facet::testing::RenderTexturedPhoto(faces, cams[k], paint, gains[k]));
    photo_colour[k] = (gains[k] * kPaint).array().round();
  }
  // A uniform paint leaves only rounding in the photo, the pyramid and the atlas's 8 bits.
  constexpr double kTolerance = 2.0;                 // grey levels
  constexpr double kMarginPx = 3.0;                  // clear of the face's outline in the photo
  std::array<std::vector<Eigen::Vector3d>, 3> seen;  // front-face points each view sees clearly
  std::vector<Eigen::Vector3d> outside_3;            // ... that view 3 does not see at all
  for (const Eigen::Vector3d& x : facet::testing::FaceGrid(*front, 30, 0.1)) {
    for (int k = 0; k < 3; ++k) {
      if (ClearlySeen(faces, *front, cams[k], x, kMarginPx)) seen[k].push_back(x);
    }
    const Eigen::Vector2d uv3 = cams[2].Project(x);
    const bool outside_frame_3 = uv3.x() < -kMarginPx || uv3.y() < -kMarginPx ||
                                 uv3.x() > cams[2].width_px - 1 + kMarginPx ||
                                 uv3.y() > cams[2].height_px - 1 + kMarginPx;
    if (outside_frame_3 && ClearlySeen(faces, *front, cams[0], x, kMarginPx)) outside_3.push_back(x);
  }
  CAPTURE(seen[0].size());
  CAPTURE(seen[1].size());
  CAPTURE(seen[2].size());
  CAPTURE(outside_3.size());
  REQUIRE(seen[1].size() > 400);
  REQUIRE(seen[2].size() > 100);
  REQUIRE(outside_3.size() > 100);
  TextureBakeOptions options;
  options.compensate_exposure = false;
  options.texels_per_image_px = 0.5;  // view 3's close-up would give the front face 1441 x 901 texels
  auto bake = [&](const facet::Project& project, TexturedMesh* mesh) {
    const auto summary = facet::BakeTexturedMesh(project, photos, options, mesh);
    REQUIRE_MESSAGE(summary.IsUsable(), summary.message);
    return summary;
  };
  // How many of `points` bake within the tolerance of photo k's colour.
  auto near_photo = [&](const TexturedMesh& mesh, const std::vector<Eigen::Vector3d>& points, int k) {
    int n = 0;
    for (const Eigen::Vector3d& x : points) {
      Eigen::Vector3d rgb;
      REQUIRE(facet::testing::BakedColourAt(mesh, *front, x, &rgb));
      n += MaxChannelDiff(rgb, photo_colour[k]) <= kTolerance;
    }
    return n;
  };

  // No choices: view 3, much nearer, outweighs view 1 where it sees the front face.
  TexturedMesh free_mesh;
  const auto free_summary = bake(scene.project, &free_mesh);
  CHECK(free_summary.faces.size() == faces.size());
  CHECK(ShareOf(ReportOf(free_summary, *front), ids[2]) > 0.2);
  CHECK(near_photo(free_mesh, seen[2], 2) > 0.9 * seen[2].size());

  // The report names each face's photos: with view 3 out of texturing altogether, the front
  // face is view 1's, the side face view 2's, and view 3 has no weight anywhere: the atlas is
  // exactly the one baked without its photo.
  facet::Project no_3 = scene.project;
  no_3.images[2].use_for_texture = false;
  TexturedMesh no_3_mesh, unloaded_mesh;
  const auto no_3_summary = bake(no_3, &no_3_mesh);
  CHECK(no_3_summary.images_excluded == 1);
  const facet::FaceTextureReport& front_report = ReportOf(no_3_summary, *front);
  const facet::FaceTextureReport& side_report = ReportOf(no_3_summary, *side);
  REQUIRE_FALSE(front_report.sources.empty());
  REQUIRE_FALSE(side_report.sources.empty());
  MESSAGE("front face: view 1 " << ShareOf(front_report, ids[0]) << ", view 2 " << ShareOf(front_report, ids[1])
                                << "; side face: view 2 " << ShareOf(side_report, ids[1]));
  CHECK(front_report.sources.front().image_id == ids[0]);
  CHECK(front_report.sources.front().share > 0.5);
  CHECK(side_report.sources.front().image_id == ids[1]);
  for (const facet::FaceTextureReport& r : no_3_summary.faces) {
    double total = 0.0;
    for (const facet::TextureSourceShare& s : r.sources) total += s.share;
    CHECK((r.sources.empty() || std::abs(total - 1.0) < 1e-9));
    CHECK(ShareOf(r, ids[2]) == 0.0);
  }
  std::vector<ImageRgba8> without_3 = photos;
  without_3[2] = ImageRgba8();
  REQUIRE(facet::BakeTexturedMesh(scene.project, without_3, options, &unloaded_mesh).IsUsable());
  CHECK(no_3_mesh.atlas.pixels == unloaded_mesh.atlas.pixels);

  // Excluded for the front face only: view 3 gives it no weight and no colour, and still
  // textures nothing else it sees as before (it sees only the front face here).
  facet::Project excluded = scene.project;
  facet::SetFaceTextureOverride(excluded.FindPrimitive(scene.box_id), {front->face, facet::kNoId, {ids[2]}});
  TexturedMesh excluded_mesh;
  const auto excluded_summary = bake(excluded, &excluded_mesh);
  CHECK(ShareOf(ReportOf(excluded_summary, *front), ids[2]) == 0.0);
  CHECK(near_photo(excluded_mesh, seen[2], 2) == 0);

  // Forced to view 2 (grazing, which it sees whole): every texel it sees clearly is its
  // colour, and nothing came from elsewhere.
  facet::Project forced_2 = scene.project;
  facet::SetFaceTextureOverride(forced_2.FindPrimitive(scene.box_id), {front->face, ids[1], {}});
  TexturedMesh forced_2_mesh;
  const auto forced_2_summary = bake(forced_2, &forced_2_mesh);
  const facet::FaceTextureReport& forced_2_report = ReportOf(forced_2_summary, *front);
  CHECK(forced_2_report.forced_image == ids[1]);
  // At 76 degrees from frontal a texel on the outline may miss view 2's z-buffer test.
  constexpr double kMaxFallbackShare = 0.01;
  CHECK(forced_2_report.forced_fallback_texels <=
        kMaxFallbackShare * forced_2_report.width_texels * forced_2_report.height_texels);
  CHECK(ShareOf(forced_2_report, ids[1]) >= 1.0 - kMaxFallbackShare);
  const int forced_2_near = near_photo(forced_2_mesh, seen[1], 1);
  MESSAGE("forced view 2: " << forced_2_near << " of " << seen[1].size() << " points within " << kTolerance
                            << " grey levels of its photo");
  CHECK(forced_2_near == static_cast<int>(seen[1].size()));

  // Forced to view 3, which sees only part of the face: its part is view 3's colour, the rest
  // falls back to the next view (view 1 or 2, unblended), and the summary says so.
  facet::Project forced_3 = scene.project;
  facet::SetFaceTextureOverride(forced_3.FindPrimitive(scene.box_id), {front->face, ids[2], {}});
  TexturedMesh forced_3_mesh;
  const auto forced_3_summary = bake(forced_3, &forced_3_mesh);
  const facet::FaceTextureReport& forced_3_report = ReportOf(forced_3_summary, *front);
  CHECK(forced_3_report.forced_image == ids[2]);
  CHECK(forced_3_report.forced_fallback_texels > 0);
  CHECK(forced_3_summary.texels_forced_fallback == forced_3_report.forced_fallback_texels);
  CHECK(forced_3_summary.message.find("taken from the next view") != std::string::npos);
  MESSAGE(forced_3_summary.message);
  CHECK(near_photo(forced_3_mesh, seen[2], 2) == static_cast<int>(seen[2].size()));
  CHECK(near_photo(forced_3_mesh, outside_3, 0) + near_photo(forced_3_mesh, outside_3, 1) ==
        static_cast<int>(outside_3.size()));

  // A forced photo that may not texture (out of texturing altogether) is reported, not used.
  forced_3.images[2].use_for_texture = false;
  TexturedMesh unavailable_mesh;
  const auto unavailable = bake(forced_3, &unavailable_mesh);
  CHECK(ReportOf(unavailable, *front).forced_unavailable);
  CHECK(ReportOf(unavailable, *front).forced_image == facet::kNoId);
  CHECK(unavailable.faces_forced_unavailable == 1);
  CHECK(unavailable.message.find("chosen automatically") != std::string::npos);
}

TEST_CASE("texels per unit: a face of known size gets the asked texel count, capped by the atlas page") {
  auto scene = facet::testing::MakeBoxScene(BoxOptions());
  const std::vector<PaintedFace> faces = facet::testing::PaintedFaces(scene.project);
  const std::vector<ImageRgba8> photos = {
      facet::testing::RenderTexturedPhoto(faces, scene.project.images[0].camera, SmoothPaint)};
  // The box is 4 x 3 x 2.5 m: its -Y face 4 x 2.5, its +X face 3 x 2.5.
  const PaintedFace* front = FaceWithNormal(faces, scene.box_id, -Eigen::Vector3d::UnitY());
  const PaintedFace* side = FaceWithNormal(faces, scene.box_id, Eigen::Vector3d::UnitX());
  REQUIRE(front != nullptr);
  REQUIRE(side != nullptr);
  constexpr double kTexelsPerMetre = 50.0;
  TextureBakeOptions options;
  options.texels_per_unit = kTexelsPerMetre;
  TexturedMesh mesh;
  const auto summary = facet::BakeTexturedMesh(scene.project, photos, options, &mesh);
  REQUIRE_MESSAGE(summary.IsUsable(), summary.message);
  // Texel centres lie on the outline: a W m side spans W x 50 texel steps, W x 50 + 1 texels;
  // the UVs of the corners span exactly those steps of the atlas (no rounding for these sizes).
  auto span_in_texels = [&](const PaintedFace& face) {
    Eigen::Vector2d lo = Eigen::Vector2d::Constant(1e9), hi = -lo;
    for (size_t t = 0; t < mesh.triangle_face.size(); ++t) {
      if (mesh.triangle_primitive[t] != face.primitive_id || mesh.triangle_face[t] != face.face) continue;
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector2d uv = mesh.uvs[mesh.indices[3 * t + k]].cast<double>();
        lo = lo.cwiseMin(uv);
        hi = hi.cwiseMax(uv);
      }
    }
    const Eigen::Vector2d span = (hi - lo).cwiseProduct(Eigen::Vector2d(mesh.atlas.width, mesh.atlas.height));
    return std::array<double, 2>{std::min(span.x(), span.y()), std::max(span.x(), span.y())};
  };
  constexpr double kUvTolerance = 1e-3;  // texels: float UVs over a <= 1024 atlas
  struct KnownFace {
    const PaintedFace* face;
    double longer, shorter;  // m
  };
  for (const KnownFace& known : {KnownFace{front, 4.0, 2.5}, KnownFace{side, 3.0, 2.5}}) {
    const PaintedFace* face = known.face;
    const double longer = known.longer, shorter = known.shorter;
    const facet::FaceTextureReport& report = ReportOf(summary, *face);
    CAPTURE(face->face);
    CHECK(std::max(report.width_texels, report.height_texels) == static_cast<int>(longer * kTexelsPerMetre) + 1);
    CHECK(std::min(report.width_texels, report.height_texels) == static_cast<int>(shorter * kTexelsPerMetre) + 1);
    CHECK_FALSE(report.size_capped);
    const std::array<double, 2> span = span_in_texels(*face);
    CHECK(std::abs(span[1] - longer * kTexelsPerMetre) < kUvTolerance);
    CHECK(std::abs(span[0] - shorter * kTexelsPerMetre) < kUvTolerance);
  }
  CHECK(summary.faces_size_capped == 0);

  // 1000 texels/m asks 4001 for a side: a 512 page with 4 texels of padding caps it at 504,
  // and the six faces then shrink together to fit the one page.
  options.texels_per_unit = 1000.0;
  options.max_atlas_size = 512;
  TexturedMesh capped;
  const auto capped_summary = facet::BakeTexturedMesh(scene.project, photos, options, &capped);
  REQUIRE_MESSAGE(capped_summary.IsUsable(), capped_summary.message);
  MESSAGE(capped_summary.message);
  CHECK(capped_summary.faces_size_capped > 0);
  CHECK(capped_summary.message.find("capped at the atlas page") != std::string::npos);
  CHECK(capped_summary.atlas_width <= 512);
  CHECK(capped_summary.atlas_height <= 512);
  for (const facet::FaceTextureReport& r : capped_summary.faces) {
    CHECK(r.width_texels <= 512 - 2 * options.padding_texels);
    CHECK(r.height_texels <= 512 - 2 * options.padding_texels);
  }
  CHECK(ReportOf(capped_summary, *front).size_capped);

  // Bad values are refused by the options' check.
  options.texels_per_unit = -1.0;
  std::string error;
  CHECK_FALSE(options.Check(&error));
  CHECK(error.find("texels_per_unit") != std::string::npos);
}
