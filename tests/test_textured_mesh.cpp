// Texture baking on primitive meshes: a synthetic photo is ray-cast from a known camera with
// every face painted in its own colour (solid or a checker in the face's frame); the baked
// atlas must reproduce each visible face's paint, whatever the face's shape (box quads, wedge
// triangles, faces split by E_split + V_connect, a non-convex face).
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <set>

#include <doctest/doctest.h>

#include "core/mesh/operators.h"
#include "core/mesh/primitives.h"
#include "core/texture/textured_mesh.h"
#include "synthetic_scene.h"
#include "tests/polygon_2d.h"

using facet::Camera;
using facet::FaceId;
using facet::ImageRgba8;
using facet::PolyMesh;
using facet::Project;
using facet::TexturedMesh;

namespace {

using Rgb = std::array<int, 3>;
constexpr int kCells = 4;  // checker cells per face side
constexpr std::array<Rgb, 12> kPalette = {{{220, 60, 60},
                                           {60, 220, 60},
                                           {60, 60, 220},
                                           {220, 220, 60},
                                           {220, 60, 220},
                                           {60, 220, 220},
                                           {240, 140, 40},
                                           {140, 40, 240},
                                           {40, 240, 140},
                                           {200, 200, 200},
                                           {120, 80, 40},
                                           {40, 120, 80}}};
constexpr Rgb kBackground = {20, 20, 20};

// A face of the scene as the tests see it, independent of the bake's own frame: corners in
// FaceHalfedges order and a frame with s along the first edge, t across it, both scaled to
// [0, 1] over the face's bounding rectangle (for a box face: the face itself, corner 0 at
// (0, 0)).
struct TestFace {
  size_t index = 0;  // in SceneFaces' list: picks the paint
  facet::Id primitive_id = facet::kNoId;
  FaceId face = facet::kNoFace;
  std::vector<Eigen::Vector3d> corners;
  Eigen::Vector3d normal, c0, u_hat, v_hat;
  Eigen::Vector2d st_min, st_max;        // unscaled frame coordinates of the bounding rectangle
  std::vector<Eigen::Vector2d> polygon;  // corners in unscaled frame coordinates

  Eigen::Vector2d Unscaled(const Eigen::Vector3d& p) const { return {(p - c0).dot(u_hat), (p - c0).dot(v_hat)}; }
  Eigen::Vector2d FaceCoords(const Eigen::Vector3d& p) const {
    return (Unscaled(p) - st_min).cwiseQuotient(st_max - st_min);
  }
  Eigen::Vector3d InWorld(const Eigen::Vector2d& st) const {
    const Eigen::Vector2d q = st_min + st.cwiseProduct(st_max - st_min);
    return c0 + q.x() * u_hat + q.y() * v_hat;
  }
  Eigen::Vector3d Centroid() const {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (const auto& p : corners) c += p;
    return c / static_cast<double>(corners.size());
  }
  bool Faces(const Camera& cam) const { return normal.dot(cam.CenterInWorld() - Centroid()) > 0; }
};

std::vector<TestFace> SceneFaces(const Project& project) {
  std::vector<TestFace> faces;
  for (const facet::Primitive& primitive : project.primitives) {
    const PolyMesh& mesh = primitive.mesh;
    for (FaceId f = 0; f < mesh.FaceIdEnd(); ++f) {
      if (!mesh.IsFace(f)) continue;
      TestFace tf;
      tf.index = faces.size();
      tf.primitive_id = primitive.id;
      tf.face = f;
      for (facet::VertexId v : facet::FaceVertices(mesh, f)) tf.corners.push_back(mesh.vertex(v).position);
      tf.normal = facet::FaceNormal(mesh, f);
      tf.c0 = tf.corners[0];
      const Eigen::Vector3d e = tf.corners[1] - tf.corners[0];
      tf.u_hat = (e - e.dot(tf.normal) * tf.normal).normalized();
      tf.v_hat = tf.normal.cross(tf.u_hat);
      tf.st_min = Eigen::Vector2d::Constant(1e300);
      tf.st_max = -tf.st_min;
      for (const auto& p : tf.corners) {
        tf.polygon.push_back(tf.Unscaled(p));
        tf.st_min = tf.st_min.cwiseMin(tf.polygon.back());
        tf.st_max = tf.st_max.cwiseMax(tf.polygon.back());
      }
      faces.push_back(tf);
    }
  }
  return faces;
}

enum class Paint { kSolid, kChecker, kInvertedChecker };

Rgb PaintColour(const TestFace& face, const Eigen::Vector2d& st, Paint paint) {
  Rgb c = kPalette[face.index % kPalette.size()];
  if (paint == Paint::kSolid) return c;
  const double s = std::clamp(st.x(), 0.0, 0.999999), t = std::clamp(st.y(), 0.0, 0.999999);
  const int cell = (static_cast<int>(std::floor(s * kCells)) + static_cast<int>(std::floor(t * kCells))) & 1;
  for (int& v : c) {
    if (cell == 1) v = v * 2 / 5;
    if (paint == Paint::kInvertedChecker) v = 255 - v;
  }
  return c;
}

// The face the ray through pixel uv_px hits first (ray-plane hit, then the even-odd test in
// the face's plane, so this does not depend on the triangulation under test), or nullptr.
const TestFace* FirstHit(const std::vector<TestFace>& faces, const Camera& cam, const Eigen::Vector2d& uv_px,
                         Eigen::Vector2d* st) {
  const Eigen::Vector3d center = cam.CenterInWorld();
  const Eigen::Vector3d dir = cam.RayDirectionInWorld(uv_px);
  double best = std::numeric_limits<double>::infinity();
  const TestFace* hit = nullptr;
  for (const TestFace& face : faces) {
    const double denominator = dir.dot(face.normal);
    if (std::abs(denominator) < 1e-12) continue;
    const double depth = (face.c0 - center).dot(face.normal) / denominator;
    if (!(depth > 0.0) || depth >= best) continue;
    const Eigen::Vector3d p = center + depth * dir;
    if (!facet::testing::InsidePolygon2d(face.polygon, face.Unscaled(p))) continue;
    best = depth;
    hit = &face;
    if (st != nullptr) *st = face.FaceCoords(p);
  }
  return hit;
}

// Ray-casts the faces: each pixel shows the paint of the face its centre ray hits first.
ImageRgba8 RenderPhoto(const std::vector<TestFace>& faces, const Camera& cam, Paint paint) {
  ImageRgba8 photo;
  photo.width = cam.width_px;
  photo.height = cam.height_px;
  photo.pixels.resize(static_cast<size_t>(photo.width) * photo.height * 4);
  for (int y = 0; y < photo.height; ++y) {
    for (int x = 0; x < photo.width; ++x) {
      Eigen::Vector2d st;
      const TestFace* hit = FirstHit(faces, cam, Eigen::Vector2d(x, y), &st);
      const Rgb colour = hit != nullptr ? PaintColour(*hit, st, paint) : kBackground;
      std::uint8_t* px = photo.At(x, y);
      for (int c = 0; c < 3; ++c) px[c] = static_cast<std::uint8_t>(colour[c]);
      px[3] = 255;
    }
  }
  return photo;
}

// Where one face landed in the atlas, read back from the mesh's UVs: texel = A * (s, t, 1),
// affine because the bake rectifies the face's plane.
struct FaceInAtlas {
  bool textured = false;
  int triangles = 0;
  Eigen::Matrix<double, 2, 3> texel_from_st;
  double affine_residual_texels = 0.0;             // how far the corners' UVs are from one affine map
  std::vector<Eigen::Vector2d> outline;            // the corners in texels
  int x_min = 0, x_max = 0, y_min = 0, y_max = 0;  // texel bounds of the outline

  Eigen::Vector2d Texel(double s, double t) const { return texel_from_st * Eigen::Vector3d(s, t, 1.0); }
  Eigen::Vector2d FaceCoords(const Eigen::Vector2d& texel) const {
    return texel_from_st.leftCols<2>().inverse() * (texel - texel_from_st.col(2));
  }
};

FaceInAtlas FindFace(const TexturedMesh& mesh, const TestFace& face) {
  FaceInAtlas out;
  std::set<std::uint32_t> vertices;
  for (size_t tri = 0; tri < mesh.triangle_face.size(); ++tri) {
    if (mesh.triangle_primitive[tri] != face.primitive_id || mesh.triangle_face[tri] != face.face) continue;
    out.textured = mesh.triangle_textured[tri] != 0;
    ++out.triangles;
    for (int k = 0; k < 3; ++k) vertices.insert(mesh.indices[tri * 3 + k]);
  }
  REQUIRE(vertices.size() == face.corners.size());
  std::vector<Eigen::Vector2d> texels(face.corners.size());
  std::vector<bool> found(face.corners.size(), false);
  for (std::uint32_t v : vertices) {
    for (size_t c = 0; c < face.corners.size(); ++c) {
      if ((mesh.positions[v].cast<double>() - face.corners[c]).norm() < 1e-4) {
        texels[c] =
            Eigen::Vector2d(mesh.uvs[v].x() * mesh.atlas.width - 0.5, mesh.uvs[v].y() * mesh.atlas.height - 0.5);
        found[c] = true;
      }
    }
  }
  REQUIRE(std::count(found.begin(), found.end(), true) == static_cast<long>(found.size()));
  // Least-squares affine fit; exact up to float UVs for a planar face.
  Eigen::MatrixXd a(face.corners.size(), 3), b(face.corners.size(), 2);
  for (size_t c = 0; c < face.corners.size(); ++c) {
    a.row(c) << face.FaceCoords(face.corners[c]).transpose(), 1.0;
    b.row(c) = texels[c].transpose();
  }
  out.texel_from_st = a.colPivHouseholderQr().solve(b).transpose();
  for (size_t c = 0; c < face.corners.size(); ++c) {
    out.affine_residual_texels =
        std::max(out.affine_residual_texels, (out.texel_from_st * a.row(c).transpose() - texels[c]).norm());
  }
  out.outline = texels;
  Eigen::Vector2d lo = texels[0], hi = texels[0];
  for (const auto& t : texels) {
    lo = lo.cwiseMin(t);
    hi = hi.cwiseMax(t);
  }
  out.x_min = static_cast<int>(std::lround(lo.x()));
  out.x_max = static_cast<int>(std::lround(hi.x()));
  out.y_min = static_cast<int>(std::lround(lo.y()));
  out.y_max = static_cast<int>(std::lround(hi.y()));
  return out;
}

// Compares a face's atlas texels with its paint, over the texels whose point on the face
// projects into `cam`'s photo at least kMarginPx inside the face's projected outline: nearer
// the outline the photo's pixels blend with the neighbour face or the background (bilinear).
struct PaintCheck {
  int checked = 0;
  int mismatched = 0;  // texels off by more than the tolerance
  int worst = 0;       // largest channel difference, grey levels
  double mean_abs = 0.0;
};

// With `scene` given, texels whose point another face hides from `cam` (or comes within
// kMarginPx of hiding) are skipped too.
PaintCheck CheckPaint(const TexturedMesh& mesh, const TestFace& face, const FaceInAtlas& fa, const Camera& cam,
                      Paint paint, int tolerance, const std::vector<TestFace>* scene = nullptr) {
  constexpr double kMarginPx = 1.5;
  std::vector<Eigen::Vector2d> outline_px;
  for (const auto& p : face.corners) outline_px.push_back(cam.Project(p));
  PaintCheck check;
  double sum = 0.0;
  for (int y = fa.y_min; y <= fa.y_max; ++y) {
    for (int x = fa.x_min; x <= fa.x_max; ++x) {
      const Eigen::Vector2d st = fa.FaceCoords(Eigen::Vector2d(x, y));
      const Eigen::Vector2d uv = cam.Project(face.InWorld(st));
      if (!facet::testing::InsidePolygon2d(outline_px, uv) ||
          facet::testing::DistanceToPolygonOutline(outline_px, uv) < kMarginPx)
        continue;
      if (uv.x() < kMarginPx || uv.y() < kMarginPx || uv.x() > cam.width_px - 1 - kMarginPx ||
          uv.y() > cam.height_px - 1 - kMarginPx) {
        continue;
      }
      if (scene != nullptr) {
        bool visible = true;
        for (int k = 0; k < 9 && visible; ++k) {
          const Eigen::Vector2d probe = uv + kMarginPx * Eigen::Vector2d(k % 3 - 1, k / 3 - 1);
          const TestFace* hit = FirstHit(*scene, cam, probe, nullptr);
          visible = hit != nullptr && hit->index == face.index;
        }
        if (!visible) continue;
      }
      const Rgb want = PaintColour(face, st, paint);
      const std::uint8_t* got = mesh.atlas.At(x, y);
      int diff = 0;
      for (int c = 0; c < 3; ++c) {
        diff = std::max(diff, std::abs(got[c] - want[c]));
        sum += std::abs(got[c] - want[c]);
      }
      diff = std::max(diff, 255 - got[3]);
      check.worst = std::max(check.worst, diff);
      check.mismatched += diff > tolerance;
      ++check.checked;
    }
  }
  check.mean_abs = check.checked > 0 ? sum / (3.0 * check.checked) : 0.0;
  return check;
}

int Brightness(const std::uint8_t* p) { return p[0] + p[1] + p[2]; }
bool IsPowerOfTwo(int n) { return n > 0 && (n & (n - 1)) == 0; }

struct Baked {
  facet::testing::SyntheticScene scene;
  std::vector<TestFace> faces;
  TexturedMesh mesh;
  facet::TextureBakeSummary summary;
};

Baked BakeBox(const facet::testing::SyntheticSceneOptions& o, const facet::TextureBakeOptions& options = {},
              Paint paint = Paint::kChecker) {
  Baked b;
  b.scene = facet::testing::MakeBoxScene(o);
  b.faces = SceneFaces(b.scene.project);
  b.summary =
      facet::BakeTexturedMesh(b.scene.project, {RenderPhoto(b.faces, b.scene.true_camera, paint)}, options, &b.mesh);
  return b;
}

// Bakes the project from a solid-colour photo of it taken by `cam` and checks every face:
// textured exactly when it faces the camera (the whole model is in the frame), and then
// every texel away from the outline equal to the face's colour.
void CheckSolidBake(const Project& project, const Camera& cam) {
  const std::vector<TestFace> faces = SceneFaces(project);
  for (const TestFace& face : faces) {
    for (const auto& p : face.corners) {
      const Eigen::Vector2d uv = cam.Project(p);
      REQUIRE((uv.x() > 0 && uv.x() < cam.width_px - 1 && uv.y() > 0 && uv.y() < cam.height_px - 1));
    }
  }
  TexturedMesh mesh;
  const auto summary = facet::BakeTexturedMesh(project, {RenderPhoto(faces, cam, Paint::kSolid)}, {}, &mesh);
  REQUIRE_MESSAGE(summary.IsUsable(), summary.message);
  MESSAGE(summary.message);
  int facing = 0;
  for (const TestFace& face : faces) {
    CAPTURE(face.index);
    CAPTURE(face.face);
    CAPTURE(face.corners.size());
    const FaceInAtlas fa = FindFace(mesh, face);
    CHECK(fa.triangles == static_cast<int>(face.corners.size()) - 2);
    CHECK(fa.textured == face.Faces(cam));
    if (!fa.textured) continue;
    ++facing;
    constexpr double kAffineToleranceTexels = 1e-2;  // float UVs times the atlas size
    CHECK(fa.affine_residual_texels < kAffineToleranceTexels);
    // Solid paint: bilinear sampling between equal pixels is exact, up to rounding.
    constexpr int kSolidTolerance = 1;  // grey levels
    const PaintCheck check = CheckPaint(mesh, face, fa, cam, Paint::kSolid, kSolidTolerance);
    CAPTURE(check.checked);
    CAPTURE(check.worst);
    CHECK(check.checked > 100);
    CHECK(check.mismatched == 0);
  }
  CHECK(summary.faces_textured == facing);
  CHECK(summary.faces_untextured == static_cast<int>(faces.size()) - facing);
}

// Moves a vertex to a new primitive-local position through the free-vertex offset, as the
// solve does, and refreshes the world positions.
void MoveVertexLocal(Project* project, facet::Primitive* primitive, facet::VertexId v, const Eigen::Vector3d& local) {
  facet::MeshVertex& vertex = primitive->mesh.vertex(v);
  vertex.local.free = true;
  vertex.local.offset = Eigen::Vector3d::Zero();
  vertex.local.offset = local - vertex.local.LocalPosition(primitive->shape.params);
  facet::RefreshPrimitive(project, primitive);
}

// The box face whose outward normal is `normal`.
FaceId FaceWithNormal(const PolyMesh& mesh, const Eigen::Vector3d& normal) {
  for (FaceId f = 0; f < mesh.FaceIdEnd(); ++f) {
    if (mesh.IsFace(f) && (facet::FaceNormal(mesh, f) - normal).norm() < 1e-9) return f;
  }
  return facet::kNoFace;
}

// The paper's rule: each face from its best view, no exposure levelling. The tests of view
// choice use it; their photos differ on purpose (inverted checkers), which blending would mix.
facet::TextureBakeOptions BestViewOnly() {
  facet::TextureBakeOptions options;
  options.source = facet::TextureSource::kBestView;
  options.compensate_exposure = false;
  return options;
}

}  // namespace

TEST_CASE("untextured mesh: per face, its corners, n - 2 counter-clockwise triangles and its normal") {
  auto scene = facet::testing::MakeBoxScene();
  facet::PrimitiveShape tilted = facet::MakeBox(facet::kNoId, Eigen::Vector3d(1.0, 2.0, 3.0));
  tilted.rotation = Eigen::Vector3d(0.3, -0.2, 0.7);
  tilted.translation = Eigen::Vector3d(10, 2, 1);
  std::string message;
  REQUIRE(facet::AddPrimitiveToProject(&scene.project, tilted, "tilted", nullptr, &message));
  facet::PrimitiveShape wedge = facet::MakeWedge(facet::kNoId, Eigen::Vector3d(4.0, 3.0, 1.5));
  wedge.translation = Eigen::Vector3d(-6, 0, 0);
  REQUIRE(facet::AddPrimitiveToProject(&scene.project, wedge, "wedge", nullptr, &message));

  const TexturedMesh mesh = facet::BuildUntexturedMesh(scene.project);
  size_t expected_vertices = 0, expected_triangles = 0;
  for (const auto& face : SceneFaces(scene.project)) {
    expected_vertices += face.corners.size();
    expected_triangles += face.corners.size() - 2;
  }
  CHECK(expected_triangles == 12 + 12 + 8);  // two boxes, a wedge (2 triangles, 3 quads)
  REQUIRE(mesh.indices.size() == 3 * expected_triangles);
  CHECK(mesh.positions.size() == expected_vertices);
  CHECK(mesh.normals.size() == mesh.positions.size());
  CHECK(mesh.uvs.size() == mesh.positions.size());
  REQUIRE(mesh.triangle_primitive.size() == expected_triangles);
  REQUIRE(mesh.triangle_face.size() == expected_triangles);
  CHECK(mesh.triangle_textured.size() == expected_triangles);
  CHECK(mesh.atlas.empty());
  constexpr double kNormalTolerance = 1e-5;  // float positions
  for (size_t tri = 0; tri < expected_triangles; ++tri) {
    CAPTURE(tri);
    const facet::Primitive* primitive = scene.project.FindPrimitive(mesh.triangle_primitive[tri]);
    REQUIRE(primitive != nullptr);
    const FaceId face = mesh.triangle_face[tri];
    REQUIRE(primitive->mesh.IsFace(face));
    CHECK(mesh.triangle_textured[tri] == 0);
    const Eigen::Vector3d a = mesh.positions[mesh.indices[tri * 3]].cast<double>();
    const Eigen::Vector3d b = mesh.positions[mesh.indices[tri * 3 + 1]].cast<double>();
    const Eigen::Vector3d c = mesh.positions[mesh.indices[tri * 3 + 2]].cast<double>();
    const Eigen::Vector3d n = (b - a).cross(c - a).normalized();
    const Eigen::Vector3d expected = facet::FaceNormal(primitive->mesh, face);
    CAPTURE(n.transpose());
    CAPTURE(expected.transpose());
    CHECK((n - expected).norm() < kNormalTolerance);
    // Outward: away from the primitive's centroid (the primitives are convex).
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (facet::VertexId v = 0; v < primitive->mesh.VertexIdEnd(); ++v) centroid += primitive->mesh.vertex(v).position;
    centroid /= primitive->mesh.VertexIdEnd();
    CHECK(n.dot((a + b + c) / 3.0 - centroid) > 0);
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = mesh.indices[tri * 3 + k];
      CHECK((mesh.normals[v].cast<double>() - expected).norm() < kNormalTolerance);
      CHECK(mesh.uvs[v].isZero());
    }
  }
}

TEST_CASE("bake: exactly the faces facing the camera are textured, each with its checker, upright") {
  const Baked b = BakeBox({});
  const Camera& cam = b.scene.true_camera;
  REQUIRE_MESSAGE(b.summary.IsUsable(), b.summary.message);
  MESSAGE("bake of the 1024x768 synthetic box: " << b.summary.time_ms << " ms, atlas " << b.summary.atlas_width << "x"
                                                 << b.summary.atlas_height << "; " << b.summary.message);
  REQUIRE(b.faces.size() == 6);
  // The whole box is inside the photo, so facing the camera is the whole visibility test.
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector2d uv = cam.Project(b.scene.true_box.mesh.vertex(c).position);
    REQUIRE((uv.x() > 0 && uv.x() < cam.width_px - 1 && uv.y() > 0 && uv.y() < cam.height_px - 1));
  }
  std::set<size_t> expected, textured;
  for (const TestFace& face : b.faces) {
    if (face.Faces(cam)) expected.insert(face.index);
    if (FindFace(b.mesh, face).textured) textured.insert(face.index);
  }
  CHECK(expected.size() == 3);
  CHECK(textured == expected);
  CHECK(b.summary.faces_textured == 3);
  CHECK(b.summary.faces_untextured == 3);
  CHECK(IsPowerOfTwo(b.mesh.atlas.width));
  CHECK(IsPowerOfTwo(b.mesh.atlas.height));
  CHECK(b.summary.atlas_width == b.mesh.atlas.width);
  CHECK(b.summary.atlas_height == b.mesh.atlas.height);
  for (const auto& uv : b.mesh.uvs) CHECK((uv.x() >= 0 && uv.x() <= 1 && uv.y() >= 0 && uv.y() <= 1));
  CHECK(b.mesh.triangle_face.size() == 12);

  for (const TestFace& face : b.faces) {
    CAPTURE(face.index);
    const FaceInAtlas fa = FindFace(b.mesh, face);
    if (!fa.textured) {
      for (size_t tri = 0; tri < 12; ++tri) {
        if (b.mesh.triangle_face[tri] != face.face) continue;
        for (int k = 0; k < 3; ++k) CHECK(b.mesh.uvs[b.mesh.indices[tri * 3 + k]].isZero());
      }
      continue;
    }
    // Upright as seen from outside: s (the first edge) runs right in the atlas, t up.
    const Eigen::Vector2d du = fa.texel_from_st.col(0), dv = fa.texel_from_st.col(1);
    CAPTURE(du.transpose());
    CAPTURE(dv.transpose());
    constexpr double kAxisToleranceTexels = 1e-2;
    CHECK(du.x() > 0);
    CHECK(dv.y() < 0);
    CHECK(std::abs(du.y()) < kAxisToleranceTexels);
    CHECK(std::abs(dv.x()) < kAxisToleranceTexels);

    // Per texel against the checker, away from the face outline; only texels within about a
    // photo pixel of a cell edge may differ (bilinear blur, aliasing).
    constexpr int kTexelTolerance = 30;
    const PaintCheck check = CheckPaint(b.mesh, face, fa, cam, Paint::kChecker, kTexelTolerance);
    const double fraction = 1.0 - static_cast<double>(check.mismatched) / check.checked;
    CAPTURE(check.checked);
    CAPTURE(fraction);
    constexpr double kMinMatchingFraction = 0.93;
    CHECK(check.checked > 1000);
    CHECK(fraction > kMinMatchingFraction);

    // Checker edges: along the middle of each cell row, the brightness crosses the midway
    // level at s = k / kCells; likewise along the columns.
    const Rgb light = PaintColour(face, {0.01, 0.01}, Paint::kChecker);
    const Rgb dark = PaintColour(face, {0.01 + 1.0 / kCells, 0.01}, Paint::kChecker);
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
            const Eigen::Vector2d at =
                direction == 0 ? fa.Texel(crossing_along, across) : fa.Texel(across, crossing_along);
            const Eigen::Vector2d want =
                direction == 0 ? fa.Texel(nearest_edge, across) : fa.Texel(across, nearest_edge);
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
        const std::uint8_t* edge =
            b.mesh.atlas.At(std::clamp(x, fa.x_min, fa.x_max), std::clamp(y, fa.y_min, fa.y_max));
        padding_mismatches += !std::equal(got, got + 4, edge);
      }
    }
    CHECK(padding_mismatches == 0);
  }
}

TEST_CASE("bake: a wedge, every visible face in its own colour") {
  auto scene = facet::testing::MakeBoxScene();
  scene.project.primitives.clear();
  scene.project.pins.clear();
  std::string message;
  REQUIRE_MESSAGE(facet::AddPrimitiveToProject(&scene.project, facet::MakeWedge(facet::kNoId, {4.0, 3.0, 2.5}), "wedge",
                                               nullptr, &message),
                  message);
  CheckSolidBake(scene.project, scene.true_camera);
}

TEST_CASE("bake: a box after E_split + V_connect, every visible face in its own colour") {
  auto scene = facet::testing::MakeBoxScene();
  facet::Primitive& box = scene.project.primitives[0];
  PolyMesh& mesh = box.mesh;
  // Split the -Y face (seen by the camera) across the middle: E_split two opposite sides,
  // then V_connect the new vertices. Its neighbours gain a straight corner each.
  const FaceId front = FaceWithNormal(mesh, -Eigen::Vector3d::UnitY());
  REQUIRE(front != facet::kNoFace);
  const std::vector<facet::HalfedgeId> sides = facet::FaceHalfedges(mesh, front);
  const auto split_a = facet::ESplit(&mesh, PolyMesh::EdgeOf(sides[0]), 0.5);
  const auto split_b = facet::ESplit(&mesh, PolyMesh::EdgeOf(sides[2]), 0.5);
  REQUIRE_MESSAGE(split_a.ok, split_a.message);
  REQUIRE_MESSAGE(split_b.ok, split_b.message);
  const auto connect = facet::VConnect(&mesh, front, split_a.vertex, split_b.vertex);
  REQUIRE_MESSAGE(connect.ok, connect.message);
  // And a triangle off the top face: E_split one of its edges at 0.3, V_connect to a far corner.
  const FaceId top = FaceWithNormal(mesh, Eigen::Vector3d::UnitZ());
  REQUIRE(top != facet::kNoFace);
  const std::vector<facet::HalfedgeId> top_sides = facet::FaceHalfedges(mesh, top);
  const facet::HalfedgeId along = top_sides[facet::FaceDegree(mesh, top) - 1];
  const auto split_c = facet::ESplit(&mesh, PolyMesh::EdgeOf(along), 0.3);
  REQUIRE_MESSAGE(split_c.ok, split_c.message);
  // The farthest vertex from a point on a rectangle's side is a corner of the opposite side.
  facet::VertexId far = facet::kNoElement;
  double farthest = 0.0;
  for (facet::VertexId v : facet::FaceVertices(mesh, top)) {
    const double d = (mesh.vertex(v).position - mesh.vertex(split_c.vertex).position).norm();
    if (d > farthest) {
      farthest = d;
      far = v;
    }
  }
  const auto connect_top = facet::VConnect(&mesh, top, split_c.vertex, far);
  REQUIRE_MESSAGE(connect_top.ok, connect_top.message);
  REQUIRE(facet::Validate(mesh).empty());
  CHECK(mesh.NumFaces() == 8);
  CheckSolidBake(scene.project, scene.true_camera);
}

TEST_CASE("bake: a non-convex face (V_connect, then a free vertex moved inside) textures correctly") {
  auto scene = facet::testing::MakeBoxScene();
  scene.project.primitives.clear();
  scene.project.pins.clear();
  std::string message;
  facet::Id plane_id = facet::kNoId;
  // A 4 x 3 ground plane where the box stood, seen from above.
  REQUIRE_MESSAGE(facet::AddPrimitiveToProject(&scene.project, facet::MakePlane(facet::kNoId, 4.0, 3.0), "ground",
                                               &plane_id, &message),
                  message);
  facet::Primitive& plane = scene.project.primitives[0];
  PolyMesh& mesh = plane.mesh;
  FaceId face = facet::kNoFace;
  for (FaceId f = 0; f < mesh.FaceIdEnd(); ++f) {
    if (mesh.IsFace(f)) face = f;
  }
  const std::vector<facet::HalfedgeId> sides = facet::FaceHalfedges(mesh, face);
  const auto split_a = facet::ESplit(&mesh, PolyMesh::EdgeOf(sides[0]), 0.5);
  const auto split_b = facet::ESplit(&mesh, PolyMesh::EdgeOf(sides[2]), 0.5);
  REQUIRE(split_a.ok);
  REQUIRE(split_b.ok);
  const auto connect = facet::VConnect(&mesh, face, split_a.vertex, split_b.vertex);
  REQUIRE_MESSAGE(connect.ok, connect.message);
  // Pull the first split vertex towards one side, past the line to the opposite split
  // vertex's neighbour: one of the two parts gets a reflex corner.
  const Eigen::Vector3d a_local = mesh.vertex(split_a.vertex).LocalPosition(plane.shape.params);
  const Eigen::Vector3d b_local = mesh.vertex(split_b.vertex).LocalPosition(plane.shape.params);
  MoveVertexLocal(&scene.project, &plane, split_a.vertex,
                  a_local + 0.5 * (b_local - a_local) + Eigen::Vector3d(-1.5, 0, 0));
  REQUIRE(facet::Validate(mesh).empty());
  int reflex_faces = 0;
  for (const TestFace& f : SceneFaces(scene.project)) {
    const size_t n = f.polygon.size();
    bool reflex = false;
    for (size_t k = 0; k < n; ++k) {
      const Eigen::Vector2d e1 = f.polygon[k] - f.polygon[(k + n - 1) % n];
      const Eigen::Vector2d e2 = f.polygon[(k + 1) % n] - f.polygon[k];
      reflex = reflex || e1.x() * e2.y() - e1.y() * e2.x() < -1e-9;
    }
    reflex_faces += reflex;
  }
  REQUIRE(reflex_faces == 1);
  CheckSolidBake(scene.project, scene.true_camera);
}

TEST_CASE("bake: a non-planar face (a free vertex moved off its edge) is baked through its best-fit plane") {
  auto scene = facet::testing::MakeBoxScene();
  facet::Primitive& box = scene.project.primitives[0];
  PolyMesh& mesh = box.mesh;
  const FaceId front = FaceWithNormal(mesh, -Eigen::Vector3d::UnitY());
  REQUIRE(front != facet::kNoFace);
  const auto split = facet::ESplit(&mesh, PolyMesh::EdgeOf(facet::FaceHalfedges(mesh, front)[0]), 0.5);
  REQUIRE_MESSAGE(split.ok, split.message);
  // Out of the front face's plane by 0.2 (the box is 4 x 3 x 2.5): the front face and its
  // neighbour across the split edge are no longer planar.
  constexpr double kBulge = 0.2;
  MoveVertexLocal(&scene.project, &box, split.vertex,
                  mesh.vertex(split.vertex).LocalPosition(box.shape.params) - kBulge * Eigen::Vector3d::UnitY());
  const std::vector<TestFace> faces = SceneFaces(scene.project);
  const TestFace* bent = nullptr;
  for (const TestFace& f : faces) {
    if (f.face == front) bent = &f;
  }
  REQUIRE(bent != nullptr);
  double off_plane = 0.0;
  for (const auto& p : bent->corners)
    off_plane = std::max(off_plane, std::abs((p - bent->Centroid()).dot(bent->normal)));
  CAPTURE(off_plane);
  REQUIRE(off_plane > 0.05);

  TexturedMesh baked;
  const auto summary =
      facet::BakeTexturedMesh(scene.project, {RenderPhoto(faces, scene.true_camera, Paint::kSolid)}, {}, &baked);
  REQUIRE_MESSAGE(summary.IsUsable(), summary.message);
  CHECK(summary.faces_textured == 3);
  const FaceInAtlas fa = FindFace(baked, *bent);
  REQUIRE(fa.textured);
  for (const auto& uv : baked.uvs) CHECK((uv.x() >= 0 && uv.x() <= 1 && uv.y() >= 0 && uv.y() <= 1));
  // Approximate: the texels are the best-fit plane's, the photo shows the bent face (itself
  // rendered through a plane here), so only most interior texels carry the face's colour.
  constexpr int kSolidTolerance = 1;
  const PaintCheck check = CheckPaint(baked, *bent, fa, scene.true_camera, Paint::kSolid, kSolidTolerance);
  const double fraction = 1.0 - static_cast<double>(check.mismatched) / check.checked;
  CAPTURE(check.checked);
  CAPTURE(fraction);
  constexpr double kMinMatchingFraction = 0.9;
  CHECK(check.checked > 1000);
  CHECK(fraction > kMinMatchingFraction);
}

TEST_CASE("bake: face texels that fall outside the photo are opaque neutral grey") {
  facet::testing::SyntheticSceneOptions o;
  o.camera_center = {5.0, -1.5, 2.0};  // close enough that the box overflows the frame
  const Baked b = BakeBox(o);
  REQUIRE_MESSAGE(b.summary.IsUsable(), b.summary.message);
  const Camera& cam = b.scene.true_camera;
  int outside_texels = 0, grey = 0;
  for (const TestFace& face : b.faces) {
    const FaceInAtlas fa = FindFace(b.mesh, face);
    if (!fa.textured) continue;
    for (int y = fa.y_min; y <= fa.y_max; ++y) {
      for (int x = fa.x_min; x <= fa.x_max; ++x) {
        const Eigen::Vector2d uv = cam.Project(face.InWorld(fa.FaceCoords(Eigen::Vector2d(x, y))));
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
  const std::vector<TestFace> faces = SceneFaces(scene.project);
  const Camera far_cam = facet::testing::MakeLookAtCamera(far_o);
  facet::Image far_image = scene.project.images[0];
  far_image.id = scene.project.NewId();
  far_image.path = "far.png";
  far_image.camera = far_cam;
  // Far view first, so that picking the first candidate would fail.
  scene.project.images.insert(scene.project.images.begin(), far_image);
  const ImageRgba8 far_photo = RenderPhoto(faces, far_cam, Paint::kInvertedChecker);
  const ImageRgba8 near_photo = RenderPhoto(faces, scene.true_camera, Paint::kChecker);
  constexpr double kMaxMeanDiff = 12.0;  // grey levels, cell-edge texels included
  constexpr int kTexelTolerance = 30;

  TexturedMesh mesh;
  auto summary = facet::BakeTexturedMesh(scene.project, {far_photo, near_photo}, BestViewOnly(), &mesh);
  REQUIRE_MESSAGE(summary.IsUsable(), summary.message);
  CHECK(summary.faces_textured == 3);
  for (const TestFace& face : faces) {
    if (!face.Faces(scene.true_camera)) continue;
    CAPTURE(face.index);
    const PaintCheck check =
        CheckPaint(mesh, face, FindFace(mesh, face), scene.true_camera, Paint::kChecker, kTexelTolerance);
    CAPTURE(check.mean_abs);
    CHECK(check.checked > 1000);
    CHECK(check.mean_abs < kMaxMeanDiff);
  }

  summary = facet::BakeTexturedMesh(scene.project, {far_photo, ImageRgba8()}, BestViewOnly(), &mesh);
  REQUIRE_MESSAGE(summary.IsUsable(), summary.message);
  CHECK(summary.faces_textured == 3);
  for (const TestFace& face : faces) {
    if (!face.Faces(far_cam)) continue;
    CAPTURE(face.index);
    const PaintCheck check =
        CheckPaint(mesh, face, FindFace(mesh, face), far_cam, Paint::kInvertedChecker, kTexelTolerance);
    CAPTURE(check.mean_abs);
    CHECK(check.checked > 500);
    CHECK(check.mean_abs < kMaxMeanDiff);
  }
}

TEST_CASE("bake from photo pointers: bit-identical to the owning overload; nullptr is an unloaded photo") {
  facet::testing::SyntheticSceneOptions near_o;
  facet::testing::SyntheticSceneOptions far_o;
  far_o.camera_center = near_o.look_at + 1.8 * (near_o.camera_center - near_o.look_at);
  auto scene = facet::testing::MakeBoxScene(near_o);
  const std::vector<TestFace> faces = SceneFaces(scene.project);
  const Camera far_cam = facet::testing::MakeLookAtCamera(far_o);
  facet::Image far_image = scene.project.images[0];
  far_image.id = scene.project.NewId();
  far_image.camera = far_cam;
  scene.project.images.insert(scene.project.images.begin(), far_image);
  const std::vector<ImageRgba8> owned = {RenderPhoto(faces, far_cam, Paint::kInvertedChecker),
                                         RenderPhoto(faces, scene.true_camera, Paint::kChecker)};
  // The photos live elsewhere (as in the app's photo store); the bake reads them in place.
  const std::vector<const ImageRgba8*> pointers = {&owned[0], &owned[1]};

  auto same_mesh = [](const TexturedMesh& a, const TexturedMesh& b) {
    return a.positions == b.positions && a.normals == b.normals && a.uvs == b.uvs && a.indices == b.indices &&
           a.triangle_primitive == b.triangle_primitive && a.triangle_face == b.triangle_face &&
           a.triangle_textured == b.triangle_textured && a.atlas.width == b.atlas.width &&
           a.atlas.height == b.atlas.height && a.atlas.pixels == b.atlas.pixels;
  };
  TexturedMesh from_owned, from_pointers;
  const auto owned_summary = facet::BakeTexturedMesh(scene.project, owned, {}, &from_owned);
  const auto pointer_summary = facet::BakeTexturedMesh(scene.project, pointers, {}, &from_pointers);
  REQUIRE_MESSAGE(owned_summary.IsUsable(), owned_summary.message);
  REQUIRE_MESSAGE(pointer_summary.IsUsable(), pointer_summary.message);
  REQUIRE(from_pointers.atlas.pixels.size() > 1000);
  CHECK(same_mesh(from_owned, from_pointers));

  // nullptr behaves as an empty (unloaded) photo: the far view textures every face then,
  // which differs from the bake with both views.
  TexturedMesh with_null, with_empty;
  const auto null_summary = facet::BakeTexturedMesh(scene.project, {&owned[0], nullptr}, {}, &with_null);
  const auto empty_summary = facet::BakeTexturedMesh(scene.project, {owned[0], ImageRgba8()}, {}, &with_empty);
  REQUIRE_MESSAGE(null_summary.IsUsable(), null_summary.message);
  REQUIRE_MESSAGE(empty_summary.IsUsable(), empty_summary.message);
  CHECK(null_summary.faces_textured == 3);
  CHECK(same_mesh(with_null, with_empty));
  CHECK_FALSE(same_mesh(with_null, from_pointers));

  // Every photo missing: untextured, not a failure; a wrong count is a failure.
  TexturedMesh none;
  const auto none_summary = facet::BakeTexturedMesh(scene.project, {nullptr, nullptr}, {}, &none);
  CHECK(none_summary.IsUsable());
  CHECK(none_summary.faces_textured == 0);
  CHECK(none.atlas.empty());
  const auto short_summary = facet::BakeTexturedMesh(scene.project, {&owned[0]}, {}, &none);
  CHECK_FALSE(short_summary.IsUsable());
  CHECK(short_summary.message.find("photos") != std::string::npos);
}

TEST_CASE("bake: a primitive in front of a face makes an unobstructed view win") {
  // Box A at the origin; box B hides most of A's -Y face from view 1, not from view 2.
  auto scene = facet::testing::MakeBoxScene();
  facet::PrimitiveShape blocker = facet::MakeBox(facet::kNoId, Eigen::Vector3d(4.0, 0.5, 2.5));
  blocker.translation = Eigen::Vector3d(0.0, -2.5, 0.0);
  std::string message;
  REQUIRE(facet::AddPrimitiveToProject(&scene.project, blocker, "blocker", nullptr, &message));
  facet::testing::SyntheticSceneOptions o1, o2;
  o1.camera_center = {2.0, -12.0, 1.5};  // straight in front of the -Y face: large but blocked
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
  const std::vector<TestFace> faces = SceneFaces(scene.project);
  const ImageRgba8 photo1 = RenderPhoto(faces, cam1, Paint::kChecker);
  const ImageRgba8 photo2 = RenderPhoto(faces, cam2, Paint::kInvertedChecker);

  const TestFace* front = nullptr;
  for (const TestFace& f : faces) {
    if (f.primitive_id == scene.box_id && (f.normal + Eigen::Vector3d::UnitY()).norm() < 1e-9) front = &f;
  }
  REQUIRE(front != nullptr);
  // View 1 sees the face larger and more frontally: without occlusion it would win.
  auto weighted_area = [&](const Camera& cam) {
    double twice_area = 0.0;
    for (size_t k = 0; k < front->corners.size(); ++k) {
      const Eigen::Vector2d a = cam.Project(front->corners[k]);
      const Eigen::Vector2d b = cam.Project(front->corners[(k + 1) % front->corners.size()]);
      twice_area += a.x() * b.y() - a.y() * b.x();
    }
    const Eigen::Vector3d to_camera = (cam.CenterInWorld() - front->Centroid()).normalized();
    return 0.5 * std::abs(twice_area) * front->normal.dot(to_camera);
  };
  CHECK(front->Faces(cam1));
  CHECK(front->Faces(cam2));
  CHECK(weighted_area(cam1) > 2.0 * weighted_area(cam2));

  TexturedMesh mesh;
  const auto summary = facet::BakeTexturedMesh(scene.project, {photo1, photo2}, BestViewOnly(), &mesh);
  REQUIRE_MESSAGE(summary.IsUsable(), summary.message);
  const FaceInAtlas fa = FindFace(mesh, *front);
  REQUIRE(fa.textured);
  // The face shows view 2's inverted checker wherever view 2 sees it (the blocker still
  // hides a corner of it there), not the blocker.
  constexpr int kTexelTolerance = 30;
  const PaintCheck check = CheckPaint(mesh, *front, fa, cam2, Paint::kInvertedChecker, kTexelTolerance, &faces);
  const double fraction = 1.0 - static_cast<double>(check.mismatched) / check.checked;
  CAPTURE(check.checked);
  CAPTURE(fraction);
  constexpr double kMinMatchingFraction = 0.9;
  CHECK(check.checked > 500);
  CHECK(fraction > kMinMatchingFraction);

  // With view 2 unloaded: view 1 sees none of the face's occlusion samples, so the face is
  // left untextured rather than painted with the blocker; the blocker's own front is textured.
  TexturedMesh only_one;
  const auto single = facet::BakeTexturedMesh(scene.project, {photo1, ImageRgba8()}, BestViewOnly(), &only_one);
  REQUIRE_MESSAGE(single.IsUsable(), single.message);
  CHECK_FALSE(FindFace(only_one, *front).textured);
  for (const TestFace& f : faces) {
    if (f.primitive_id != scene.box_id && (f.normal + Eigen::Vector3d::UnitY()).norm() < 1e-9) {
      CHECK(FindFace(only_one, f).textured);
    }
  }
}

TEST_CASE("bake: a small atlas limit shrinks the faces instead of failing") {
  facet::TextureBakeOptions options;
  options.max_atlas_size = 128;
  const Baked b = BakeBox({}, options);
  REQUIRE_MESSAGE(b.summary.IsUsable(), b.summary.message);
  CHECK(b.summary.faces_textured == 3);
  CHECK(b.mesh.atlas.width <= 128);
  CHECK(b.mesh.atlas.height <= 128);
  for (const auto& uv : b.mesh.uvs) CHECK((uv.x() >= 0 && uv.x() <= 1 && uv.y() >= 0 && uv.y() <= 1));

  // A higher texel density gives a bigger atlas than the default one.
  facet::TextureBakeOptions dense;
  dense.texels_per_image_px = 2.0;
  const Baked d = BakeBox({}, dense);
  const Baked n = BakeBox({});
  CHECK(static_cast<long>(d.mesh.atlas.width) * d.mesh.atlas.height >
        static_cast<long>(n.mesh.atlas.width) * n.mesh.atlas.height);
}

// Speed is measured in tests/bench/bench_bake.cpp; this checks what the resolution does.
TEST_CASE("bake: faces are sized by the loaded photo's resolution (1024x768 and 12 MP)") {
  auto scene = facet::testing::MakeBoxScene();
  const ImageRgba8 small = RenderPhoto(SceneFaces(scene.project), scene.true_camera, Paint::kChecker);
  // 12 MP at the same 4:3 aspect, by nearest-neighbour upsampling: the bake maps the
  // intrinsics (given for 1024x768) to the loaded photo's resolution.
  ImageRgba8 large;
  large.width = 4000;
  large.height = 3000;
  large.pixels.resize(static_cast<size_t>(large.width) * large.height * 4);
  for (int y = 0; y < large.height; ++y) {
    for (int x = 0; x < large.width; ++x) {
      const std::uint8_t* src = small.At(x * small.width / large.width, y * small.height / large.height);
      std::copy(src, src + 4, large.At(x, y));
    }
  }
  int small_width = 0;
  for (const ImageRgba8* photo : std::array<const ImageRgba8*, 2>{&small, &large}) {
    TexturedMesh mesh;
    const facet::TextureBakeSummary summary = facet::BakeTexturedMesh(scene.project, {*photo}, {}, &mesh);
    REQUIRE_MESSAGE(summary.IsUsable(), summary.message);
    CHECK(summary.faces_textured == 3);
    MESSAGE("bake from a " << photo->width << "x" << photo->height << " photo: atlas " << summary.atlas_width << "x"
                           << summary.atlas_height);
    if (photo == &small) small_width = summary.atlas_width;
    // Faces sized by their extent in the loaded photo: about 3.9x the texels per side.
    if (photo == &large) CHECK(summary.atlas_width >= 3.5 * small_width);
  }
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
  CHECK_FALSE(summary.IsUsable());
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

  summary = facet::BakeTexturedMesh(scene.project, std::vector<ImageRgba8>{}, {}, &mesh);
  CHECK_FALSE(summary.IsUsable());
  CHECK_FALSE(summary.message.empty());

  summary = facet::BakeTexturedMesh(scene.project, {ImageRgba8()}, {}, &mesh);
  CHECK(summary.IsUsable());
  CHECK(summary.faces_textured == 0);
  CHECK(summary.faces_untextured == 6);
  CHECK(mesh.atlas.empty());
  for (auto t : mesh.triangle_textured) CHECK(t == 0);

  // An uncalibrated image is not used even with pixels.
  const ImageRgba8 photo = RenderPhoto(SceneFaces(scene.project), scene.true_camera, Paint::kChecker);
  scene.project.images[0].camera_calibrated = false;
  summary = facet::BakeTexturedMesh(scene.project, {photo}, {}, &mesh);
  CHECK(summary.IsUsable());
  CHECK(summary.faces_textured == 0);

  // An empty project: success, nothing to texture.
  Project empty;
  summary = facet::BakeTexturedMesh(empty, std::vector<const ImageRgba8*>{}, {}, &mesh);
  CHECK(summary.IsUsable());
  CHECK(mesh.indices.empty());
}
