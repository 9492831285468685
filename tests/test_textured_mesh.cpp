// Texture baking: a synthetic photo is ray-cast from the true camera with a distinct checker
// on every box face; the baked atlas must reproduce each visible face's pattern.
#include <algorithm>
#include <array>
#include <cmath>
#include <set>

#include <doctest/doctest.h>

#include "core/box.h"
#include "core/textured_mesh.h"
#include "synthetic_scene.h"

using facet::Box;
using facet::Camera;
using facet::ImageRgba8;
using facet::TexturedMesh;

namespace {

constexpr int kCells = 4;  // checker cells per face side
using Rgb = std::array<int, 3>;
constexpr std::array<Rgb, 6> kFaceColours = {{{220, 60, 60}, {60, 220, 60}, {60, 60, 220},
                                              {220, 220, 60}, {220, 60, 220}, {60, 220, 220}}};
constexpr Rgb kBackground = {20, 20, 20};

Rgb PatternColour(int face, double s, double t, bool inverted) {
  const int cell = (static_cast<int>(std::floor(s * kCells)) + static_cast<int>(std::floor(t * kCells))) & 1;
  Rgb c = kFaceColours[face];
  for (int& v : c) {
    if (cell == 1) v = v * 2 / 5;
    if (inverted) v = 255 - v;
  }
  return c;
}

struct FaceFrame {
  Eigen::Vector3d c0, eu, ev;
};

FaceFrame FrameOf(const Box& box, int face) {
  const auto corners = facet::BoxCornersInWorld(box);
  const auto& idx = facet::BoxFaces()[face];
  return {corners[idx[0]], corners[idx[1]] - corners[idx[0]], corners[idx[3]] - corners[idx[0]]};
}

// Ray-casts the boxes: each pixel shows the face its centre ray hits first.
ImageRgba8 RenderPhoto(const std::vector<Box>& boxes, const Camera& cam, bool inverted = false) {
  ImageRgba8 photo;
  photo.width = cam.width_px;
  photo.height = cam.height_px;
  photo.pixels.resize(static_cast<size_t>(photo.width) * photo.height * 4);
  const Eigen::Vector3d center = cam.CenterInWorld();
  for (int y = 0; y < photo.height; ++y) {
    for (int x = 0; x < photo.width; ++x) {
      const Eigen::Vector3d dir = cam.RayDirectionInWorld(Eigen::Vector2d(x, y));
      double best = std::numeric_limits<double>::infinity();
      Rgb colour = kBackground;
      for (const Box& box : boxes) {
        const Eigen::Matrix3d box_from_world = facet::RotationFromAngleAxis(box.rotation).transpose();
        const Eigen::Vector3d o = box_from_world * (center - box.translation);
        const Eigen::Vector3d d = box_from_world * dir;
        double lo = 0.0, hi = std::numeric_limits<double>::infinity();
        int entry_face = -1;
        for (int k = 0; k < 3; ++k) {
          if (std::abs(d[k]) < 1e-15) {
            if (o[k] < 0 || o[k] > box.size[k]) lo = hi + 1;
            continue;
          }
          double t0 = (0 - o[k]) / d[k], t1 = (box.size[k] - o[k]) / d[k];
          int face = 2 * k;  // entering through the low side
          if (t0 > t1) {
            std::swap(t0, t1);
            face = 2 * k + 1;
          }
          if (t0 > lo) {
            lo = t0;
            entry_face = face;
          }
          hi = std::min(hi, t1);
        }
        if (entry_face < 0 || lo > hi || lo >= best) continue;
        best = lo;
        const Eigen::Vector3d p = center + lo * dir;
        const FaceFrame fr = FrameOf(box, entry_face);
        const double s = (p - fr.c0).dot(fr.eu) / fr.eu.squaredNorm();
        const double t = (p - fr.c0).dot(fr.ev) / fr.ev.squaredNorm();
        colour = PatternColour(entry_face, std::clamp(s, 0.0, 0.999999), std::clamp(t, 0.0, 0.999999), inverted);
      }
      std::uint8_t* px = photo.At(x, y);
      for (int c = 0; c < 3; ++c) px[c] = static_cast<std::uint8_t>(colour[c]);
      px[3] = 255;
    }
  }
  return photo;
}

// The atlas placement of one face as read back from the mesh: the texel position of face
// point (s, t) is t0 + s * du + t * dv (affine, since each face is a parallelogram in UV).
struct FaceInAtlas {
  bool textured = false;
  Eigen::Vector2d t0, du, dv;
  Eigen::Vector2d Texel(double s, double t) const { return t0 + s * du + t * dv; }
  Eigen::Vector2d FaceCoords(const Eigen::Vector2d& texel) const {
    Eigen::Matrix2d m;
    m << du, dv;
    return m.inverse() * (texel - t0);
  }
  // Inclusive texel rectangle of the face (centres of its corner texels).
  int x_min, x_max, y_min, y_max;
};

FaceInAtlas FindFace(const TexturedMesh& mesh, const Box& box, int face) {
  FaceInAtlas out;
  const auto corners = facet::BoxCornersInWorld(box);
  std::array<Eigen::Vector2d, 4> texel;
  std::array<bool, 4> found = {false, false, false, false};
  for (size_t tri = 0; tri < mesh.triangle_box.size(); ++tri) {
    if (mesh.triangle_box[tri] != box.id || mesh.triangle_face[tri] != face) continue;
    out.textured = mesh.triangle_textured[tri] != 0;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = mesh.indices[tri * 3 + k];
      for (int c = 0; c < 4; ++c) {
        if ((mesh.positions[v].cast<double>() - corners[facet::BoxFaces()[face][c]]).norm() < 1e-4) {
          texel[c] = Eigen::Vector2d(mesh.uvs[v].x() * mesh.atlas.width - 0.5, mesh.uvs[v].y() * mesh.atlas.height - 0.5);
          found[c] = true;
        }
      }
    }
  }
  REQUIRE((found[0] && found[1] && found[2] && found[3]));
  out.t0 = texel[0];
  out.du = texel[1] - texel[0];
  out.dv = texel[3] - texel[0];
  auto lo = [&](int axis) { return std::min({texel[0][axis], texel[1][axis], texel[2][axis], texel[3][axis]}); };
  auto hi = [&](int axis) { return std::max({texel[0][axis], texel[1][axis], texel[2][axis], texel[3][axis]}); };
  out.x_min = static_cast<int>(std::lround(lo(0)));
  out.x_max = static_cast<int>(std::lround(hi(0)));
  out.y_min = static_cast<int>(std::lround(lo(1)));
  out.y_max = static_cast<int>(std::lround(hi(1)));
  return out;
}

bool FacesCamera(const Box& box, int face, const Camera& cam) {
  const FaceFrame fr = FrameOf(box, face);
  const Eigen::Vector3d centroid = fr.c0 + 0.5 * (fr.eu + fr.ev);
  return fr.eu.cross(fr.ev).dot(cam.CenterInWorld() - centroid) > 0;
}

int Brightness(const std::uint8_t* p) { return p[0] + p[1] + p[2]; }

bool IsPowerOfTwo(int n) { return n > 0 && (n & (n - 1)) == 0; }

struct Baked {
  facet::testing::SyntheticScene scene;
  TexturedMesh mesh;
  facet::TextureBakeSummary summary;
};

Baked BakeScene(const facet::testing::SyntheticSceneOptions& o, const facet::TextureBakeOptions& options = {}) {
  Baked b;
  b.scene = facet::testing::MakeBoxScene(o);
  std::vector<ImageRgba8> photos = {RenderPhoto(b.scene.project.boxes, b.scene.true_camera)};
  b.summary = facet::BakeTexturedMesh(b.scene.project, photos, options, &b.mesh);
  return b;
}

}  // namespace

TEST_CASE("untextured mesh: 12 counter-clockwise triangles per box with face normals") {
  auto scene = facet::testing::MakeBoxScene();
  Box tilted = scene.true_box;
  tilted.id = scene.project.NewId();
  tilted.rotation = Eigen::Vector3d(0.3, -0.2, 0.7);
  tilted.translation = Eigen::Vector3d(10, 2, 1);
  scene.project.boxes.push_back(tilted);
  const TexturedMesh mesh = facet::BuildUntexturedMesh(scene.project);
  REQUIRE(mesh.indices.size() == 2 * 12 * 3);
  CHECK(mesh.positions.size() == 2 * 24);
  CHECK(mesh.normals.size() == mesh.positions.size());
  CHECK(mesh.uvs.size() == mesh.positions.size());
  REQUIRE(mesh.triangle_box.size() == 24);
  CHECK(mesh.triangle_face.size() == 24);
  CHECK(mesh.atlas.empty());
  constexpr double kNormalTolerance = 1e-5;  // float positions
  for (size_t tri = 0; tri < 24; ++tri) {
    CAPTURE(tri);
    const Box& box = *scene.project.FindBox(mesh.triangle_box[tri]);
    const int face = mesh.triangle_face[tri];
    CHECK(mesh.triangle_textured[tri] == 0);
    const Eigen::Vector3d a = mesh.positions[mesh.indices[tri * 3]].cast<double>();
    const Eigen::Vector3d b = mesh.positions[mesh.indices[tri * 3 + 1]].cast<double>();
    const Eigen::Vector3d c = mesh.positions[mesh.indices[tri * 3 + 2]].cast<double>();
    const Eigen::Vector3d n = (b - a).cross(c - a).normalized();
    const Eigen::Vector3d expected = facet::BoxFaceNormalInWorld(box, face);
    CAPTURE(n.transpose());
    CAPTURE(expected.transpose());
    CHECK((n - expected).norm() < kNormalTolerance);
    // The outward normal points away from the box centre.
    const Eigen::Vector3d box_center = facet::RotationFromAngleAxis(box.rotation) * (0.5 * box.size) + box.translation;
    CHECK(n.dot((a + b + c) / 3.0 - box_center) > 0);
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = mesh.indices[tri * 3 + k];
      CHECK((mesh.normals[v].cast<double>() - expected).norm() < kNormalTolerance);
      CHECK(mesh.uvs[v].isZero());
    }
  }
}

TEST_CASE("bake: exactly the faces facing the camera are textured, each with its pattern") {
  const Baked b = BakeScene({});
  const Camera& cam = b.scene.true_camera;
  const Box& box = b.scene.project.boxes[0];
  REQUIRE_MESSAGE(b.summary.success, b.summary.message);
  MESSAGE("bake of the 1024x768 synthetic scene: " << b.summary.time_ms << " ms, atlas " << b.summary.atlas_width
                                                   << "x" << b.summary.atlas_height << "; " << b.summary.message);
  // The whole box is inside the photo, so facing the camera is the whole visibility test.
  for (const auto& corner : facet::BoxCornersInWorld(box)) {
    const Eigen::Vector2d uv = cam.Project(corner);
    REQUIRE((uv.x() > 0 && uv.x() < cam.width_px - 1 && uv.y() > 0 && uv.y() < cam.height_px - 1));
  }
  std::set<int> expected, textured;
  for (int f = 0; f < 6; ++f) {
    if (FacesCamera(box, f, cam)) expected.insert(f);
    if (FindFace(b.mesh, box, f).textured) textured.insert(f);
  }
  CHECK(expected.size() == 3);
  CHECK(textured == expected);
  CHECK(b.summary.faces_textured == 3);
  CHECK(b.summary.faces_untextured == 3);
  CHECK(IsPowerOfTwo(b.mesh.atlas.width));
  CHECK(IsPowerOfTwo(b.mesh.atlas.height));
  CHECK(b.summary.atlas_width == b.mesh.atlas.width);
  CHECK(b.summary.atlas_height == b.mesh.atlas.height);
  for (const auto& uv : b.mesh.uvs) {
    CHECK((uv.x() >= 0 && uv.x() <= 1 && uv.y() >= 0 && uv.y() <= 1));
  }
  CHECK(b.mesh.triangle_box.size() == 12);

  for (int f = 0; f < 6; ++f) {
    CAPTURE(f);
    const FaceInAtlas fa = FindFace(b.mesh, box, f);
    if (!fa.textured) {
      for (size_t tri = 0; tri < 12; ++tri) {
        if (b.mesh.triangle_face[tri] != f) continue;
        for (int k = 0; k < 3; ++k) CHECK(b.mesh.uvs[b.mesh.indices[tri * 3 + k]].isZero());
      }
      continue;
    }
    // Per-texel comparison with the pattern at the texel's face coordinates, and the face's
    // mean colour against the pattern's mean over the same texels.
    int matching = 0, total = 0;
    Eigen::Vector3d measured_sum = Eigen::Vector3d::Zero(), expected_sum = Eigen::Vector3d::Zero();
    for (int y = fa.y_min; y <= fa.y_max; ++y) {
      for (int x = fa.x_min; x <= fa.x_max; ++x) {
        const Eigen::Vector2d st = fa.FaceCoords(Eigen::Vector2d(x, y));
        const Rgb want = PatternColour(f, std::clamp(st.x(), 0.0, 0.999999), std::clamp(st.y(), 0.0, 0.999999), false);
        const std::uint8_t* got = b.mesh.atlas.At(x, y);
        CHECK(got[3] == 255);
        int diff = 0;
        for (int c = 0; c < 3; ++c) {
          diff = std::max(diff, std::abs(got[c] - want[c]));
          measured_sum[c] += got[c];
          expected_sum[c] += want[c];
        }
        constexpr int kTexelTolerance = 30;
        matching += diff <= kTexelTolerance;
        ++total;
      }
    }
    const double fraction = static_cast<double>(matching) / total;
    const Eigen::Vector3d mean_error = (measured_sum - expected_sum) / total;
    CAPTURE(total);
    CAPTURE(fraction);
    CAPTURE(mean_error.transpose());
    // Only texels within about a pixel of a cell edge may differ (bilinear blur, aliasing).
    constexpr double kMinMatchingFraction = 0.93;
    constexpr double kMeanColourTolerance = 4.0;  // grey levels
    CHECK(total > 1000);
    CHECK(fraction > kMinMatchingFraction);
    CHECK(mean_error.cwiseAbs().maxCoeff() < kMeanColourTolerance);

    // Checker edges: along the middle of each cell row, the brightness crosses the midway
    // level at s = k / kCells; likewise along the columns.
    const Rgb light = PatternColour(f, 0.01, 0.01, false), dark = PatternColour(f, 0.01 + 1.0 / kCells, 0.01, false);
    const double mid = 0.5 * ((light[0] + light[1] + light[2]) + (dark[0] + dark[1] + dark[2]));
    constexpr double kEdgeTolerancePx = 1.0;
    int edges_checked = 0;
    for (int direction = 0; direction < 2; ++direction) {
      for (int row = 0; row < kCells; ++row) {
        const double across = (row + 0.5) / kCells;
        double prev_value = 0, prev_along = 0;
        // From the middle of the first cell to the middle of the last: the face's outer
        // edges blend with the neighbouring face or the background and are not cell edges.
        for (int step = 0; step <= 2000; ++step) {
          const double along = (0.5 + (kCells - 1) * step / 2000.0) / kCells;
          const Eigen::Vector2d texel = direction == 0 ? fa.Texel(along, across) : fa.Texel(across, along);
          const int x = static_cast<int>(std::lround(texel.x())), y = static_cast<int>(std::lround(texel.y()));
          const double value = Brightness(b.mesh.atlas.At(x, y)) - mid;
          if (step > 0 && (value > 0) != (prev_value > 0)) {
            const double crossing_along = prev_along + (along - prev_along) * prev_value / (prev_value - value);
            const double nearest_edge = std::round(crossing_along * kCells) / kCells;
            const Eigen::Vector2d at = direction == 0 ? fa.Texel(crossing_along, across) : fa.Texel(across, crossing_along);
            const Eigen::Vector2d want = direction == 0 ? fa.Texel(nearest_edge, across) : fa.Texel(across, nearest_edge);
            CAPTURE(direction);
            CAPTURE(row);
            CAPTURE(crossing_along);
            CHECK((at - want).norm() <= kEdgeTolerancePx + 0.5);  // + half a texel of rounding
            ++edges_checked;
          }
          prev_value = value;
          prev_along = along;
        }
      }
    }
    CHECK(edges_checked == 2 * kCells * (kCells - 1));

    // Padding: every texel up to padding_texels outside the face rectangle repeats the
    // nearest edge texel.
    const int pad = facet::TextureBakeOptions().padding_texels;
    int padding_mismatches = 0;
    for (int y = fa.y_min - pad; y <= fa.y_max + pad; ++y) {
      for (int x = fa.x_min - pad; x <= fa.x_max + pad; ++x) {
        if (x >= fa.x_min && x <= fa.x_max && y >= fa.y_min && y <= fa.y_max) continue;
        REQUIRE((x >= 0 && y >= 0 && x < b.mesh.atlas.width && y < b.mesh.atlas.height));
        const std::uint8_t* got = b.mesh.atlas.At(x, y);
        const std::uint8_t* edge = b.mesh.atlas.At(std::clamp(x, fa.x_min, fa.x_max), std::clamp(y, fa.y_min, fa.y_max));
        padding_mismatches += !std::equal(got, got + 4, edge);
      }
    }
    CHECK(padding_mismatches == 0);
  }
}

TEST_CASE("bake: face texels that fall outside the photo are opaque neutral grey") {
  facet::testing::SyntheticSceneOptions o;
  o.camera_center = {5.0, -1.5, 2.0};  // close enough that the box overflows the frame
  const Baked b = BakeScene(o);
  REQUIRE_MESSAGE(b.summary.success, b.summary.message);
  const Camera& cam = b.scene.true_camera;
  const Box& box = b.scene.project.boxes[0];
  int outside_texels = 0, grey = 0;
  for (int f = 0; f < 6; ++f) {
    const FaceInAtlas fa = FindFace(b.mesh, box, f);
    if (!fa.textured) continue;
    const FaceFrame fr = FrameOf(box, f);
    for (int y = fa.y_min; y <= fa.y_max; ++y) {
      for (int x = fa.x_min; x <= fa.x_max; ++x) {
        const Eigen::Vector2d st = fa.FaceCoords(Eigen::Vector2d(x, y));
        const Eigen::Vector2d uv = cam.Project(fr.c0 + st.x() * fr.eu + st.y() * fr.ev);
        constexpr double kMarginPx = 1.5;  // clear of the bilinear border
        if (uv.x() > -0.5 - kMarginPx && uv.x() < cam.width_px - 0.5 + kMarginPx && uv.y() > -0.5 - kMarginPx &&
            uv.y() < cam.height_px - 0.5 + kMarginPx) {
          continue;
        }
        ++outside_texels;
        const std::uint8_t* p = b.mesh.atlas.At(x, y);
        grey += p[0] == 128 && p[1] == 128 && p[2] == 128 && p[3] == 255;
      }
    }
  }
  CAPTURE(outside_texels);
  CHECK(outside_texels > 100);
  CHECK(grey == outside_texels);
}

TEST_CASE("bake: the nearer of two views textures the faces; an unloaded photo is skipped") {
  facet::testing::SyntheticSceneOptions near_o;
  facet::testing::SyntheticSceneOptions far_o;
  far_o.camera_center = near_o.look_at + 1.8 * (near_o.camera_center - near_o.look_at);
  auto scene = facet::testing::MakeBoxScene(near_o);
  const Camera far_cam = facet::testing::MakeLookAtCamera(far_o);
  facet::Image far_image = scene.project.images[0];
  far_image.id = scene.project.NewId();
  far_image.path = "far.png";
  far_image.camera = far_cam;
  // Far view first, so that picking the first candidate would fail.
  scene.project.images.insert(scene.project.images.begin(), far_image);
  const ImageRgba8 far_photo = RenderPhoto(scene.project.boxes, far_cam, /*inverted=*/true);
  const ImageRgba8 near_photo = RenderPhoto(scene.project.boxes, scene.true_camera, false);

  auto mean_diff_to = [&](const TexturedMesh& mesh, int face, bool inverted) {
    const FaceInAtlas fa = FindFace(mesh, scene.project.boxes[0], face);
    double sum = 0;
    int n = 0;
    for (int y = fa.y_min; y <= fa.y_max; ++y) {
      for (int x = fa.x_min; x <= fa.x_max; ++x) {
        const Eigen::Vector2d st = fa.FaceCoords(Eigen::Vector2d(x, y));
        const Rgb want = PatternColour(face, std::clamp(st.x(), 0.0, 0.999999), std::clamp(st.y(), 0.0, 0.999999), inverted);
        for (int c = 0; c < 3; ++c) sum += std::abs(mesh.atlas.At(x, y)[c] - want[c]);
        ++n;
      }
    }
    return sum / (3.0 * n);
  };
  constexpr double kMaxMeanDiff = 12.0;  // grey levels, edge texels included

  TexturedMesh mesh;
  auto summary = facet::BakeTexturedMesh(scene.project, {far_photo, near_photo}, {}, &mesh);
  REQUIRE_MESSAGE(summary.success, summary.message);
  CHECK(summary.faces_textured == 3);
  for (int f = 0; f < 6; ++f) {
    if (!FacesCamera(scene.project.boxes[0], f, scene.true_camera)) continue;
    CAPTURE(f);
    const double diff = mean_diff_to(mesh, f, false);
    CAPTURE(diff);
    CHECK(diff < kMaxMeanDiff);
  }

  summary = facet::BakeTexturedMesh(scene.project, {far_photo, ImageRgba8()}, {}, &mesh);
  REQUIRE_MESSAGE(summary.success, summary.message);
  CHECK(summary.faces_textured == 3);
  for (int f = 0; f < 6; ++f) {
    if (!FacesCamera(scene.project.boxes[0], f, far_cam)) continue;
    CAPTURE(f);
    const double diff = mean_diff_to(mesh, f, true);
    CAPTURE(diff);
    CHECK(diff < kMaxMeanDiff);
  }
}

TEST_CASE("bake: a box in front of a face makes an unobstructed view win") {
  // Box A at the origin; box B hides most of A's -Y face from view 1, not from view 2.
  facet::testing::SyntheticSceneOptions o;
  auto scene = facet::testing::MakeBoxScene(o);
  const Box a = scene.project.boxes[0];
  Box blocker;
  blocker.id = scene.project.NewId();
  blocker.size = Eigen::Vector3d(4.0, 0.5, 2.5);
  blocker.translation = Eigen::Vector3d(0.0, -2.5, 0.0);
  scene.project.boxes.push_back(blocker);
  facet::testing::SyntheticSceneOptions o1 = o, o2 = o;
  o1.camera_center = {2.0, -12.0, 1.5};   // straight in front of the -Y face: large but blocked
  o1.look_at = {2.0, 0.0, 1.0};
  o2.camera_center = {14.0, -9.0, 3.0};  // oblique, over the blocker's end
  o2.look_at = {2.0, 0.0, 1.0};
  const Camera cam1 = facet::testing::MakeLookAtCamera(o1);
  const Camera cam2 = facet::testing::MakeLookAtCamera(o2);
  scene.project.images[0].camera = cam1;
  facet::Image second = scene.project.images[0];
  second.id = scene.project.NewId();
  second.camera = cam2;
  scene.project.images.push_back(second);
  const ImageRgba8 photo1 = RenderPhoto(scene.project.boxes, cam1, false);
  const ImageRgba8 photo2 = RenderPhoto(scene.project.boxes, cam2, true);

  TexturedMesh mesh;
  const auto summary = facet::BakeTexturedMesh(scene.project, {photo1, photo2}, {}, &mesh);
  REQUIRE_MESSAGE(summary.success, summary.message);
  const FaceInAtlas fa = FindFace(mesh, a, 2);  // -Y
  REQUIRE(fa.textured);
  // The centre of the face shows the inverted pattern of view 2, not the blocker.
  const Eigen::Vector2d centre = fa.Texel(0.6, 0.6);
  const std::uint8_t* p = mesh.atlas.At(static_cast<int>(std::lround(centre.x())), static_cast<int>(std::lround(centre.y())));
  const Rgb want = PatternColour(2, 0.6, 0.6, true);
  CAPTURE(int(p[0]));
  CAPTURE(int(p[1]));
  CAPTURE(int(p[2]));
  constexpr int kColourTolerance = 10;
  for (int c = 0; c < 3; ++c) CHECK(std::abs(p[c] - want[c]) <= kColourTolerance);
}

TEST_CASE("bake: a small atlas limit shrinks the faces instead of failing") {
  facet::TextureBakeOptions options;
  options.max_atlas_size = 128;
  const Baked b = BakeScene({}, options);
  REQUIRE_MESSAGE(b.summary.success, b.summary.message);
  CHECK(b.summary.faces_textured == 3);
  CHECK(b.mesh.atlas.width <= 128);
  CHECK(b.mesh.atlas.height <= 128);
  for (const auto& uv : b.mesh.uvs) CHECK((uv.x() >= 0 && uv.x() <= 1 && uv.y() >= 0 && uv.y() <= 1));

  // A higher texel density gives a bigger atlas than the default one.
  facet::TextureBakeOptions dense;
  dense.texels_per_image_px = 2.0;
  const Baked d = BakeScene({}, dense);
  const Baked n = BakeScene({});
  CHECK(static_cast<long>(d.mesh.atlas.width) * d.mesh.atlas.height >
        static_cast<long>(n.mesh.atlas.width) * n.mesh.atlas.height);
}

TEST_CASE("bake: bad options and mismatched photos fail with a message; no photos leave it untextured") {
  auto scene = facet::testing::MakeBoxScene();
  TexturedMesh mesh;
  std::string error;
  facet::TextureBakeOptions bad;
  bad.texels_per_image_px = 0.0;
  CHECK_FALSE(bad.Check(&error));
  CHECK_FALSE(error.empty());
  auto summary = facet::BakeTexturedMesh(scene.project, {ImageRgba8()}, bad, &mesh);
  CHECK_FALSE(summary.success);
  CHECK(summary.message.find("texels_per_image_px") != std::string::npos);
  CHECK(mesh.indices.size() == 36);  // still the untextured geometry

  for (auto tweak : {+[](facet::TextureBakeOptions& o) { o.max_face_texels = 1; },
                     +[](facet::TextureBakeOptions& o) { o.padding_texels = -1; },
                     +[](facet::TextureBakeOptions& o) { o.max_atlas_size = 0; }}) {
    facet::TextureBakeOptions o;
    tweak(o);
    CHECK_FALSE(o.Check(&error));
  }
  CHECK(facet::TextureBakeOptions().Check(&error));

  summary = facet::BakeTexturedMesh(scene.project, {}, {}, &mesh);
  CHECK_FALSE(summary.success);
  CHECK_FALSE(summary.message.empty());

  summary = facet::BakeTexturedMesh(scene.project, {ImageRgba8()}, {}, &mesh);
  CHECK(summary.success);
  CHECK(summary.faces_textured == 0);
  CHECK(summary.faces_untextured == 6);
  CHECK(mesh.atlas.empty());
  for (auto t : mesh.triangle_textured) CHECK(t == 0);

  // An uncalibrated image is not used even with pixels.
  scene.project.images[0].camera_calibrated = false;
  summary = facet::BakeTexturedMesh(scene.project, {RenderPhoto(scene.project.boxes, scene.true_camera)}, {}, &mesh);
  CHECK(summary.success);
  CHECK(summary.faces_textured == 0);
}
