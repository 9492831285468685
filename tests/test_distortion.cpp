// Radial lens distortion (Camera::k1, k2, OpenCV's radial model) end to end: the camera's
// projection / ray round trip, the joint solve's residual derivatives through the distortion,
// the model update's plumb-line estimate before the vanishing-point calibration, and the
// texture bake through a distorted photo. The joint solve's recovery of k1, k2 is in
// tests/test_joint_solve.cpp (it reuses that file's scenes).
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "core/geometry/camera.h"
#include "core/mesh/box.h"
#include "core/solve/joint_solve_internal.h"
#include "core/solve/model_update.h"
#include "core/texture/textured_mesh.h"
#include "tests/synthetic_scene.h"

namespace facet {
namespace {

using namespace joint_solve_internal;
using testing::MakeLookAtCamera;
using testing::SyntheticSceneOptions;

constexpr double kJacobianTolerance = 1e-6;  // relative, per column
constexpr double kTrueK1 = -0.15;
constexpr double kTrueK2 = 0.03;

Camera DistortedCamera(double k1, double k2) {
  Camera camera = MakeLookAtCamera(SyntheticSceneOptions{});
  camera.k1 = k1;
  camera.k2 = k2;
  return camera;
}

CameraState StateOf(const Camera& camera) {
  CameraState s;
  s.focal_px = camera.focal_px;
  s.principal_point_px = camera.principal_point_px;
  s.cam_from_world_rotation = camera.cam_from_world_rotation;
  s.center_in_world = camera.CenterInWorld();
  s.k1 = camera.k1;
  s.k2 = camera.k2;
  return s;
}

// A camera-state parameter moved by `step` in block order (focal, principal point 2,
// rotation 3, centre 3, k1, k2).
CameraState Moved(const CameraState& camera, int k, double step) {
  CameraState c = camera;
  if (k == 0)
    c.focal_px += step;
  else if (k < 3)
    c.principal_point_px(k - 1) += step;
  else if (k < 6)
    c.cam_from_world_rotation = RotationFromAngleAxis(step * Eigen::Vector3d::Unit(k - 3)) * c.cam_from_world_rotation;
  else if (k < 9)
    c.center_in_world(k - 6) += step;
  else if (k == 9)
    c.k1 += step;
  else
    c.k2 += step;
  return c;
}

double StepFor(int k) { return k < 3 ? 1e-3 : 1e-6; }

TEST_CASE("distortion: Project and RayDirectionInWorld invert each other over the image") {
  // Absolute, in normalised coordinates (x = X / Z) and in px: rounding of ~1000 px values.
  constexpr double kNormalizedTolerance = 1e-12;
  constexpr double kPixelTolerance = 1e-12 * 1024;
  for (double k1 : {-0.3, -0.1, 0.1, 0.2}) {
    const double k2 = k1 < 0.0 ? 0.05 : -0.04;
    const Camera camera = DistortedCamera(k1, k2);
    double worst_px = 0.0, worst_normalized = 0.0, largest_shift = 0.0;
    for (int v = 0; v <= camera.height_px; v += 16) {
      for (int u = 0; u <= camera.width_px; u += 16) {
        const Eigen::Vector2d uv(std::min(u, camera.width_px - 1), std::min(v, camera.height_px - 1));
        const Eigen::Vector3d ray = camera.RayDirectionInWorld(uv);
        const Eigen::Vector3d x = camera.CenterInWorld() + 7.0 * ray;
        worst_px = std::max(worst_px, (camera.Project(x) - uv).norm());
        const Eigen::Vector2d xd = (uv - camera.principal_point_px) / camera.focal_px;
        const Eigen::Vector2d xu = camera.UndistortNormalized(xd);
        worst_normalized = std::max(worst_normalized, (camera.DistortNormalized(xu) - xd).norm());
        largest_shift = std::max(largest_shift, (camera.UndistortPixel(uv) - uv).norm());
        CHECK((camera.DistortPixel(camera.UndistortPixel(uv)) - uv).norm() <= kPixelTolerance);
      }
    }
    CAPTURE(k1);
    CAPTURE(k2);
    MESSAGE("k1 " << k1 << ", k2 " << k2 << ": round trip " << worst_px << " px, " << worst_normalized
                  << " normalised; largest undistortion shift " << largest_shift << " px");
    CHECK(largest_shift > 5.0);  // the distortion is not negligible: the test means something
    CHECK(worst_px <= kPixelTolerance);
    CHECK(worst_normalized <= kNormalizedTolerance);
  }
}

TEST_CASE("distortion: beyond the fold the undistortion stops at the fold radius; k = 0 is the pinhole") {
  // k1 = -0.5, k2 = 0: r (1 - 0.5 r^2) increases up to r = sqrt(2/3), where it reaches 0.544.
  const double fold = std::sqrt(2.0 / 3.0);
  const Eigen::Vector2d beyond = UndistortNormalized(Eigen::Vector2d(0.0, 0.6), -0.5, 0.0);
  CHECK(std::abs(beyond.y() - fold) <= 1e-15);
  CHECK(beyond.x() == 0.0);
  // Just inside the fold's image it still inverts.
  const Eigen::Vector2d inside(0.3, 0.4);  // r_d = 0.5 < 0.544
  CHECK((DistortNormalized(UndistortNormalized(inside, -0.5, 0.0), -0.5, 0.0) - inside).norm() <= 1e-14);
  const Camera pinhole = DistortedCamera(0.0, 0.0);
  const Eigen::Vector3d x(1.0, 2.0, 0.5);
  const Eigen::Vector3d p = pinhole.CamFromWorld(x);
  const Eigen::Vector2d expected(pinhole.focal_px * p.x() / p.z() + pinhole.principal_point_px.x(),
                                 pinhole.focal_px * p.y() / p.z() + pinhole.principal_point_px.y());
  CHECK((pinhole.Project(x) - expected).norm() == 0.0);
}

TEST_CASE("distortion: pin residual derivatives (point, camera, k1, k2) match central differences") {
  const Camera camera = DistortedCamera(kTrueK1, kTrueK2);
  const CameraState cam = StateOf(camera);
  // A point towards the image corner, where r is large and every term matters.
  const Eigen::Vector3d x = camera.CenterInWorld() + 9.0 * camera.RayDirectionInWorld({950.0, 700.0});
  const Eigen::Vector2d uv(940.0, 690.0);
  Eigen::Vector2d r;
  Eigen::Matrix<double, 2, 3> d_point;
  Eigen::Matrix<double, 2, 9> d_camera;
  Eigen::Matrix<double, 2, 2> d_k;
  REQUIRE(PinResidual(cam, x, uv, &r, &d_point, &d_camera, &d_k));
  CHECK((r - (camera.Project(x) - uv)).norm() <= 1e-9);
  for (int i = 0; i < 3; ++i) {
    const double h = 1e-6;
    Eigen::Vector2d rp, rm;
    PinResidual(cam, x + h * Eigen::Vector3d::Unit(i), uv, &rp, nullptr, nullptr);
    PinResidual(cam, x - h * Eigen::Vector3d::Unit(i), uv, &rm, nullptr, nullptr);
    const Eigen::Vector2d fd = (rp - rm) / (2 * h);
    CAPTURE(i);
    CHECK((fd - d_point.col(i)).norm() <= kJacobianTolerance * d_point.col(i).norm());
  }
  for (int k = 0; k < 11; ++k) {
    auto at = [&](double s) {
      Eigen::Vector2d out;
      PinResidual(Moved(cam, k, s), x, uv, &out, nullptr, nullptr);
      return out;
    };
    const Eigen::Vector2d fd = (at(StepFor(k)) - at(-StepFor(k))) / (2 * StepFor(k));
    const Eigen::Vector2d analytic = k < 9 ? Eigen::Vector2d(d_camera.col(k)) : Eigen::Vector2d(d_k.col(k - 9));
    CAPTURE(k);
    CAPTURE(fd.transpose());
    CAPTURE(analytic.transpose());
    CHECK(analytic.norm() > 0.0);
    CHECK((fd - analytic).norm() <= kJacobianTolerance * analytic.norm());
  }
}

TEST_CASE("distortion: segment residual on drawn endpoints, derivatives through the undistortion") {
  const Camera camera = DistortedCamera(kTrueK1, kTrueK2);
  const CameraState cam = StateOf(camera);
  // Endpoints off the true line, so the residual is not zero and its derivatives are generic.
  const Eigen::Vector2d a(130.0, 610.0), b(420.0, 540.0);
  for (int axis = 0; axis < 3; ++axis) {
    Eigen::Matrix<double, 1, 8> d;
    const double r = DistortedSegmentResidual(cam, a, b, axis, &d);
    CAPTURE(axis);
    CHECK(std::abs(r) > 1e-3);
    for (int i = 0; i < 8; ++i) {
      const int k = i < 6 ? i : i + 3;  // block order without the centre
      auto at = [&](double s) { return DistortedSegmentResidual(Moved(cam, k, s), a, b, axis, nullptr); };
      const double fd = (at(StepFor(k)) - at(-StepFor(k))) / (2 * StepFor(k));
      CAPTURE(i);
      CAPTURE(fd);
      CAPTURE(d(i));
      CHECK(std::abs(fd - d(i)) <= kJacobianTolerance * std::max(std::abs(d(i)), 1e-9 * d.norm()));
    }
    // At k = 0 it is the pinhole residual, derivatives included (k's columns are not zero).
    CameraState pinhole = cam;
    pinhole.k1 = pinhole.k2 = 0.0;
    const Eigen::Vector2d mid = 0.5 * (a + b);
    const Eigen::Vector3d g = Eigen::Vector3d(a.x(), a.y(), 1.0).cross(Eigen::Vector3d(mid.x(), mid.y(), 1.0));
    Eigen::Matrix<double, 2, 3> m;
    m << 0.0, -1.0, mid.y(), 1.0, 0.0, -mid.x();
    Eigen::Matrix<double, 1, 6> d_pinhole;
    Eigen::Matrix<double, 1, 8> d_zero;
    const double r_pinhole = SegmentResidual(pinhole, g, m, axis, &d_pinhole);
    const double r_zero = DistortedSegmentResidual(pinhole, a, b, axis, &d_zero);
    CHECK(std::abs(r_pinhole - r_zero) <= 1e-9 * std::abs(r_pinhole));
    CHECK((d_pinhole - d_zero.head<6>()).norm() <= 1e-9 * d_pinhole.norm());
    CHECK(d_zero.tail<2>().norm() > 0.0);
  }
}

TEST_CASE("distortion: edge-on-image-line residual undistorts its line, derivatives with respect to k1, k2") {
  testing::SyntheticScene s = testing::MakeBoxScene();
  Project& p = s.project;
  Image& image = p.images[0];
  image.camera.k1 = kTrueK1;
  image.camera.k2 = kTrueK2;
  image.distortion_locked = false;
  image.focal_locked = false;
  image.principal_point_locked = false;
  Constraint c;
  c.id = p.NewId();
  c.kind = ConstraintKind::kEdgeOnImageLine;
  c.vertices = {{s.box_id, 0}, {s.box_id, 1}};
  c.image_id = image.id;
  c.line_a_px = image.camera.Project(s.true_box.mesh.vertex(0).position) + Eigen::Vector2d(3.0, -2.0);
  c.line_b_px = image.camera.Project(s.true_box.mesh.vertex(1).position) + Eigen::Vector2d(-1.0, 4.0);
  p.constraints.push_back(c);
  JointState state;
  JointProblem problem = BuildJointProblem(p, BuildOptions{}, &state);
  REQUIRE(problem.constraints.size() == 1);
  const ConstraintTerm& term = problem.constraints[0];
  std::vector<Eigen::Vector3d> points;
  for (int v : term.vertices) points.push_back(problem.vertices[v].position);
  const CameraState& cam = state.cameras[term.camera];
  Eigen::VectorXd r;
  Eigen::MatrixXd d_points, d_camera;
  REQUIRE(ConstraintResidual(term, points, &cam, &r, &d_points, &d_camera));
  CHECK(r.norm() > 1e-4);
  for (int k = 0; k < 11; ++k) {
    auto at = [&](double step) {
      Eigen::VectorXd out;
      const CameraState moved = Moved(cam, k, step);
      ConstraintResidual(term, points, &moved, &out, nullptr, nullptr);
      return out;
    };
    const Eigen::VectorXd fd = (at(StepFor(k)) - at(-StepFor(k))) / (2 * StepFor(k));
    CAPTURE(k);
    CHECK((fd - d_camera.col(k)).norm() <= kJacobianTolerance * std::max(d_camera.col(k).norm(), 1e-12));
  }
  for (int i = 0; i < 6; ++i) {
    std::vector<Eigen::Vector3d> plus = points, minus = points;
    plus[i / 3](i % 3) += 1e-6;
    minus[i / 3](i % 3) -= 1e-6;
    Eigen::VectorXd rp, rm;
    ConstraintResidual(term, plus, &cam, &rp, nullptr, nullptr);
    ConstraintResidual(term, minus, &cam, &rm, nullptr, nullptr);
    CAPTURE(i);
    CHECK(((rp - rm) / 2e-6 - d_points.col(i)).norm() <= kJacobianTolerance * d_points.col(i).norm());
  }
}

// --- The model update's plumb-line estimate ---------------------------------------------

// The box of MakeBoxScene photographed through k1 = -0.15, k2 = 0.03: three line families on
// its three visible faces (5 lines per face and direction), each straight 3-D line cut into 4
// pieces, each piece a segment whose endpoints are the distorted projections of the piece's
// ends (what a user clicks: points on the curved image of the line), and the 8 corner pins.
Project DistortedLineScene(Camera* true_camera) {
  const SyntheticSceneOptions o;
  testing::SyntheticScene s = testing::MakeBoxScene(o);
  Project p = s.project;
  Camera& truth = p.images[0].camera;
  truth.k1 = kTrueK1;
  truth.k2 = kTrueK2;
  *true_camera = truth;
  p.segments.clear();
  const Eigen::Vector3d sz = o.box_size;
  auto add_line = [&](Axis axis, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    constexpr int kPieces = 4;
    for (int k = 0; k < kPieces; ++k) {
      Segment seg;
      seg.id = p.NewId();
      seg.image_id = p.images[0].id;
      seg.axis = axis;
      seg.a_px = truth.Project(a + (b - a) * k / kPieces);
      seg.b_px = truth.Project(a + (b - a) * (k + 1) / kPieces);
      p.segments.push_back(seg);
    }
  };
  for (int i = 0; i <= 4; ++i) {
    const double f = i / 4.0;
    // Front face y = 0, side face x = sx, top face z = sz.
    add_line(Axis::kX, {0, 0, f * sz.z()}, {sz.x(), 0, f * sz.z()});
    add_line(Axis::kX, {0, f * sz.y(), sz.z()}, {sz.x(), f * sz.y(), sz.z()});
    add_line(Axis::kY, {sz.x(), 0, f * sz.z()}, {sz.x(), sz.y(), f * sz.z()});
    add_line(Axis::kY, {f * sz.x(), 0, sz.z()}, {f * sz.x(), sz.y(), sz.z()});
    add_line(Axis::kZ, {f * sz.x(), 0, 0}, {f * sz.x(), 0, sz.z()});
    add_line(Axis::kZ, {sz.x(), f * sz.y(), 0}, {sz.x(), f * sz.y(), sz.z()});
  }
  for (Pin& pin : p.pins) pin.uv_px = truth.Project(s.true_box.mesh.vertex(pin.vertex.vertex).position);
  // The calibration starts from nothing: an uncalibrated pinhole camera.
  Image& image = p.images[0];
  image.camera = Camera();
  image.camera.SetPose(Eigen::Matrix3d::Identity(), truth.CenterInWorld());
  image.camera_calibrated = false;
  return p;
}

TEST_CASE(
    "distortion: the model update's plumb-line estimate recovers the focal length that pinhole calibration misses") {
  Camera truth;
  const Project edited = DistortedLineScene(&truth);
  ModelUpdateOptions options;
  Project off, on;
  const ModelUpdateSummary without = UpdateModel(edited, options, &off);
  Project estimating = edited;
  estimating.images[0].estimate_distortion = true;
  const ModelUpdateSummary with = UpdateModel(estimating, options, &on);
  REQUIRE(without.ok);
  REQUIRE(with.ok);
  REQUIRE(with.distortion.count(edited.images[0].id) == 1);
  const PlumbLineSummary& plumb = with.distortion.at(edited.images[0].id);
  REQUIRE_MESSAGE(plumb.IsUsable(), plumb.message);
  const Camera& c_off = off.images[0].camera;
  const Camera& c_on = on.images[0].camera;
  const double error_off = std::abs(c_off.focal_px - truth.focal_px);
  const double error_on = std::abs(c_on.focal_px - truth.focal_px);
  MESSAGE("focal " << truth.focal_px << " px: without the distortion estimate " << c_off.focal_px << " (error "
                   << error_off << " px), with it " << c_on.focal_px << " (error " << error_on << " px); k1 " << c_on.k1
                   << " (true " << truth.k1 << "), k2 " << c_on.k2 << " (true " << truth.k2
                   << "); plumb-line straightness " << plumb.initial_rms_px << " -> " << plumb.final_rms_px
                   << " px; pin RMS " << without.joint.reprojection_rms_px << " -> " << with.joint.reprojection_rms_px
                   << " px");
  CHECK(c_off.k1 == 0.0);  // estimation off: the file's k (0) stays
  // Noise-free lines: what is left comes from the two radial models' conversion and from
  // the distortion centre (the image centre) not being the principal point (12, -9 px off).
  constexpr double kFocalToleranceFraction = 0.005;
  CHECK(error_on <= kFocalToleranceFraction * truth.focal_px);
  CHECK(error_off > 4.0 * error_on);
  constexpr double kK1Tolerance = 0.01;
  CHECK(std::abs(c_on.k1 - truth.k1) <= kK1Tolerance);
  CHECK(with.joint.reprojection_rms_px < without.joint.reprojection_rms_px);
}

TEST_CASE("distortion: with estimation off, a non-zero k from the file straightens the segments before calibration") {
  Camera truth;
  Project edited = DistortedLineScene(&truth);
  edited.images[0].camera.k1 = truth.k1;  // as if read from the project file; f not yet known
  edited.images[0].camera.k2 = truth.k2;
  // A known principal point: the default prior pulling a solved one towards the image centre
  // would bias f even on exact data.
  edited.images[0].principal_point_mode = PrincipalPointMode::kFixed;
  edited.images[0].fixed_principal_point_px = truth.principal_point_px;
  Project updated;
  const ModelUpdateSummary summary = UpdateModel(edited, ModelUpdateOptions{}, &updated);
  REQUIRE(summary.ok);
  const Camera& c = updated.images[0].camera;
  MESSAGE("focal with the true k given: " << c.focal_px << " px (true " << truth.focal_px << ")");
  CHECK(c.k1 == truth.k1);
  CHECK(c.k2 == truth.k2);
  // Exact data and the exact model: only the calibration's solver tolerance remains.
  constexpr double kFocalTolerancePx = 1e-6;
  CHECK(std::abs(c.focal_px - truth.focal_px) <= kFocalTolerancePx * truth.focal_px);
}

// --- The texture bake --------------------------------------------------------------------

constexpr int kCheckerCells = 8;

// The checker colour (0 or 255 grey) at a point of a box face, in the face's corner frame.
int CheckerAt(const std::array<Eigen::Vector3d, 4>& quad, const Eigen::Vector3d& p) {
  const Eigen::Vector3d e1 = quad[1] - quad[0], e2 = quad[3] - quad[0];
  const double s = std::clamp((p - quad[0]).dot(e1) / e1.squaredNorm(), 0.0, 0.999999);
  const double t = std::clamp((p - quad[0]).dot(e2) / e2.squaredNorm(), 0.0, 0.999999);
  return ((static_cast<int>(s * kCheckerCells) + static_cast<int>(t * kCheckerCells)) & 1) ? 40 : 215;
}

TEST_CASE("distortion: a face baked from a distorted photo shows its checker undistorted") {
  testing::SyntheticScene s = testing::MakeBoxScene();
  Camera camera = s.true_camera;
  // Stronger than the other tests' lens, so that the box (near the image centre) moves by
  // more than a few px between the distorted and the pinhole image.
  camera.k1 = -0.3;
  camera.k2 = 0.05;
  s.project.images[0].camera = camera;
  const Primitive& box = s.project.primitives[0];
  // The box's faces as quads (corners in face order), for the ray cast and the checker.
  std::vector<std::pair<FaceId, std::array<Eigen::Vector3d, 4>>> faces;
  for (FaceId f = 0; f < box.mesh.FaceIdEnd(); ++f) {
    if (!box.mesh.IsFace(f)) continue;
    const std::vector<VertexId> v = FaceVertices(box.mesh, f);
    REQUIRE(v.size() == 4);
    faces.push_back({f,
                     {box.mesh.vertex(v[0]).position, box.mesh.vertex(v[1]).position, box.mesh.vertex(v[2]).position,
                      box.mesh.vertex(v[3]).position}});
  }
  // Ray-cast photo through the distortion: each pixel shows the checker of the first face hit.
  ImageRgba8 photo;
  photo.width = camera.width_px;
  photo.height = camera.height_px;
  photo.pixels.assign(static_cast<size_t>(photo.width) * photo.height * 4, 255);
  const Eigen::Vector3d center = camera.CenterInWorld();
  for (int y = 0; y < photo.height; ++y) {
    for (int x = 0; x < photo.width; ++x) {
      const Eigen::Vector3d dir = camera.RayDirectionInWorld(Eigen::Vector2d(x, y));
      double best = 1e300;
      int grey = 128;
      for (const auto& [f, quad] : faces) {
        const Eigen::Vector3d n = (quad[1] - quad[0]).cross(quad[3] - quad[0]).normalized();
        const double den = dir.dot(n);
        if (std::abs(den) < 1e-12) continue;
        const double depth = (quad[0] - center).dot(n) / den;
        if (!(depth > 0.0) || depth >= best) continue;
        const Eigen::Vector3d p = center + depth * dir;
        const Eigen::Vector3d e1 = quad[1] - quad[0], e2 = quad[3] - quad[0];
        const double u = (p - quad[0]).dot(e1) / e1.squaredNorm(), v = (p - quad[0]).dot(e2) / e2.squaredNorm();
        if (u < 0 || u > 1 || v < 0 || v > 1) continue;
        best = depth;
        grey = CheckerAt(quad, p);
      }
      std::uint8_t* px = photo.At(x, y);
      px[0] = px[1] = px[2] = static_cast<std::uint8_t>(grey);
    }
  }
  // Per baked texel of a textured face (barycentric within its triangles, away from the
  // outline by 5 % of the face): the grey it shows against the checker at its face point.
  auto compare = [&](const Project& project, double* mismatch_fraction) {
    TexturedMesh mesh;
    const TextureBakeSummary summary = BakeTexturedMesh(project, {photo}, {}, &mesh);
    REQUIRE_MESSAGE(summary.IsUsable(), summary.message);
    int checked = 0, mismatched = 0;
    for (size_t tri = 0; tri < mesh.triangle_face.size(); ++tri) {
      if (!mesh.triangle_textured[tri]) continue;
      const auto& quad = std::find_if(faces.begin(), faces.end(), [&](const auto& f) {
                           return f.first == mesh.triangle_face[tri];
                         })->second;
      std::array<Eigen::Vector2d, 3> t;
      std::array<Eigen::Vector3d, 3> w;
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t i = mesh.indices[3 * tri + k];
        t[k] = Eigen::Vector2d(mesh.uvs[i].x() * mesh.atlas.width - 0.5, mesh.uvs[i].y() * mesh.atlas.height - 0.5);
        w[k] = mesh.positions[i].cast<double>();
      }
      Eigen::Matrix2d m;
      m.col(0) = t[1] - t[0];
      m.col(1) = t[2] - t[0];
      const Eigen::Matrix2d m_inv = m.inverse();
      const Eigen::Vector2d lo = t[0].cwiseMin(t[1]).cwiseMin(t[2]), hi = t[0].cwiseMax(t[1]).cwiseMax(t[2]);
      for (int y = static_cast<int>(std::ceil(lo.y())); y <= static_cast<int>(hi.y()); ++y) {
        for (int x = static_cast<int>(std::ceil(lo.x())); x <= static_cast<int>(hi.x()); ++x) {
          const Eigen::Vector2d bc = m_inv * (Eigen::Vector2d(x, y) - t[0]);
          if (bc.minCoeff() < 0.0 || bc.sum() > 1.0) continue;
          const Eigen::Vector3d p = w[0] + bc.x() * (w[1] - w[0]) + bc.y() * (w[2] - w[0]);
          const Eigen::Vector3d e1 = quad[1] - quad[0], e2 = quad[3] - quad[0];
          const double u = (p - quad[0]).dot(e1) / e1.squaredNorm(), v = (p - quad[0]).dot(e2) / e2.squaredNorm();
          constexpr double kMargin = 0.05;
          if (std::min(u, v) < kMargin || std::max(u, v) > 1.0 - kMargin) continue;
          // Away from the checker's cell edges by 6 % of a cell (1.5 to 3 photo px): the
          // bilinear blur.
          const double cu = u * kCheckerCells, cv = v * kCheckerCells;
          const double edge = std::min(std::abs(cu - std::round(cu)), std::abs(cv - std::round(cv)));
          if (edge < 0.06) continue;
          ++checked;
          constexpr int kGreyTolerance = 30;
          if (std::abs(mesh.atlas.At(x, y)[0] - CheckerAt(quad, p)) > kGreyTolerance) ++mismatched;
        }
      }
    }
    REQUIRE(checked > 10000);
    *mismatch_fraction = static_cast<double>(mismatched) / checked;
  };
  double with_k = 1.0, without_k = 0.0;
  compare(s.project, &with_k);
  Project pinhole = s.project;
  pinhole.images[0].camera.k1 = pinhole.images[0].camera.k2 = 0.0;
  compare(pinhole, &without_k);
  MESSAGE("texels off their checker grey by more than 30: " << 100.0 * with_k << " % through the distortion, "
                                                            << 100.0 * without_k << " % baked as a pinhole");
  constexpr double kMaxMismatchFraction = 0.005;
  CHECK(with_k <= kMaxMismatchFraction);
  CHECK(without_k > 4.0 * kMaxMismatchFraction);  // the distortion path is what makes it match
}

TEST_CASE(
    "distortion: on a pinhole photo with 0.5 px clicks the estimate is not significant and the camera stays a "
    "pinhole") {
  // The same lines through a lens without distortion, each endpoint off by 0.5 px (seeded):
  // the plumb-line k1 is within 3 of its standard deviations of 0, so it is not applied.
  constexpr double kNoisePx = 0.5;
  Camera truth;
  Project edited = DistortedLineScene(&truth);
  truth.k1 = truth.k2 = 0.0;
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, kNoisePx);
  // Re-project the segments' 3-D ends through the pinhole truth: undistort the distorted pixels.
  for (Segment& s : edited.segments) {
    Camera distorted = truth;
    distorted.k1 = kTrueK1;
    distorted.k2 = kTrueK2;
    s.a_px = distorted.UndistortPixel(s.a_px) + Eigen::Vector2d{noise(rng), noise(rng)};
    s.b_px = distorted.UndistortPixel(s.b_px) + Eigen::Vector2d{noise(rng), noise(rng)};
  }
  edited.images[0].estimate_distortion = true;
  Project updated;
  const ModelUpdateSummary summary = UpdateModel(edited, ModelUpdateOptions(), &updated);
  REQUIRE(summary.distortion.count(edited.images[0].id) == 1);
  const PlumbLineSummary& plumb = summary.distortion.at(edited.images[0].id);
  REQUIRE(plumb.IsUsable());
  MESSAGE("pinhole photo: plumb-line k1 " << plumb.distortion.k1 << " +- " << plumb.k1_std);
  CHECK(std::abs(plumb.distortion.k1) <= 3.0 * plumb.k1_std);
  CHECK(updated.images[0].camera.k1 == 0.0);
  CHECK(updated.images[0].camera.k2 == 0.0);
  bool said = false;
  for (const std::string& m : summary.messages) said = said || m.find("not significant") != std::string::npos;
  CHECK(said);
}

}  // namespace
}  // namespace facet
