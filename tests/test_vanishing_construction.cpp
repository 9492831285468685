// The vanishing-point construction of teach mode (core/geometry/vanishing_construction.h) on
// synthetic cameras: what it draws is the truth, not only a picture. The orthocentre of the
// true vanishing triangle is the principal point, each circle is on its pair as diameter and
// carries the turned camera centre at a right angle, |p s| is f, the horizon is the ground's
// vanishing line K^-T R e_z and the directions are R e_axis; also with two points (principal
// point given) and one (f given), and at x1e-3 and x1e3 of the pixel scale.
#include <doctest/doctest.h>

#include <cmath>
#include <random>

#include <Eigen/Geometry>

#include "core/geometry/camera.h"
#include "core/geometry/vanishing_construction.h"
#include "tests/synthetic_scene.h"

namespace facet {
namespace {

// Noise-free: a few divisions and square roots of exact points, relative to the image size
// or the focal length.
constexpr double kNoiseFreeRelative = 1e-9;

struct TrueCamera {
  Eigen::Matrix3d K;
  Eigen::Matrix3d R;  // cam_from_world
  double f;
  Eigen::Vector2d p;
  double size_px;  // the image diagonal: the scale of the absolute tolerances
};

// A random camera that sees all three vanishing points finite: heading, a downward tilt of
// 5-40 deg, a roll within 10 deg; f 0.5-3 image widths; principal point within 5 % of the
// size from the centre. `scale` multiplies every pixel length.
TrueCamera RandomCamera(std::mt19937* rng, double scale) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double width = 1000.0 * scale, height = 750.0 * scale;
  TrueCamera c;
  const double heading = (20.0 + 50.0 * unit(*rng)) * M_PI / 180.0;
  const double tilt = (5.0 + 35.0 * unit(*rng)) * M_PI / 180.0;
  const double roll = (-10.0 + 20.0 * unit(*rng)) * M_PI / 180.0;
  const Eigen::Vector3d forward(std::cos(tilt) * std::cos(heading), std::cos(tilt) * std::sin(heading),
                                -std::sin(tilt));
  c.R = Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitZ()).toRotationMatrix() * CamFromWorldLookingAlong(forward);
  c.f = width * (0.5 + 2.5 * unit(*rng));
  const double dx = (unit(*rng) - 0.5) * 0.1 * width;
  const double dy = (unit(*rng) - 0.5) * 0.1 * height;
  c.p = Eigen::Vector2d(width / 2 + dx, height / 2 + dy);
  c.K << c.f, 0, c.p.x(), 0, c.f, c.p.y(), 0, 0, 1;
  c.size_px = std::hypot(width, height);
  return c;
}

VanishingConstructionInput TrueInput(const TrueCamera& c) {
  VanishingConstructionInput input;
  for (int a = 0; a < 3; ++a) input.vanishing_points_px[a] = (c.K * c.R.col(a)).normalized();
  return input;
}

// The angle between two lines or directions, sign-free.
double SignFreeDistance(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::min((a.normalized() - b.normalized()).norm(), (a.normalized() + b.normalized()).norm());
}

void CheckPairConstruction(const FocalConstruction& c, const Eigen::Vector2d& vi, const Eigen::Vector2d& vj,
                           const TrueCamera& truth, const Eigen::Vector2d& p) {
  const double tol = kNoiseFreeRelative * truth.size_px;
  REQUIRE(c.valid);
  CHECK((c.circle_center_px - 0.5 * (vi + vj)).norm() < tol);
  CHECK(std::abs(c.circle_radius_px - 0.5 * (vi - vj).norm()) < tol);
  // The foot h is on the line v_i v_j and h p is perpendicular to it.
  const Eigen::Vector2d side = (vj - vi).normalized();
  CHECK(std::abs((c.altitude_foot_px - vi).x() * side.y() - (c.altitude_foot_px - vi).y() * side.x()) < tol);
  CHECK(std::abs((p - c.altitude_foot_px).dot(side)) < tol);
  // q on the circle, seeing v_i v_j at a right angle (Thales), on the ray h -> p.
  CHECK(std::abs((c.turned_center_px - c.circle_center_px).norm() - c.circle_radius_px) < tol);
  CHECK(std::abs((vi - c.turned_center_px).normalized().dot((vj - c.turned_center_px).normalized())) <
        kNoiseFreeRelative);
  // s: |h s| = |h q| and |p s| = f.
  CHECK(std::abs((c.focal_end_px - c.altitude_foot_px).norm() - (c.turned_center_px - c.altitude_foot_px).norm()) <
        tol);
  CHECK(std::abs((c.focal_end_px - p).norm() - truth.f) < kNoiseFreeRelative * truth.f);
  CHECK(std::abs(c.focal_px - truth.f) < kNoiseFreeRelative * truth.f);
}

void CheckThreePointConstruction(const TrueCamera& truth) {
  const VanishingConstructionInput input = TrueInput(truth);
  const VanishingConstruction out = ConstructFromVanishingPoints(input);
  const double tol = kNoiseFreeRelative * truth.size_px;
  REQUIRE(out.kind == VanishingConstructionKind::kThreePoints);
  CHECK_FALSE(out.principal_point_assumed);
  CAPTURE(truth.f);
  CAPTURE(truth.p.transpose());
  CAPTURE(out.principal_point_px.transpose());
  CHECK((out.principal_point_px - truth.p).norm() < tol);
  CHECK(std::abs(out.focal_px - truth.f) < kNoiseFreeRelative * truth.f);
  CHECK_FALSE(out.focal_assumed);
  REQUIRE(out.focal_constructions.size() == 3u);
  for (const FocalConstruction& c : out.focal_constructions)
    CheckPairConstruction(c, out.points_px[c.axes[0]], out.points_px[c.axes[1]], truth, truth.p);
  // Each altitude foot is on its side and on the line from its vertex through p.
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector2d& v = out.points_px[k];
    const Eigen::Vector2d side = (out.points_px[(k + 2) % 3] - out.points_px[(k + 1) % 3]).normalized();
    CHECK(std::abs((out.altitude_feet_px[k] - v).dot(side)) < tol);
    CHECK(std::abs((truth.p - v).dot(side)) < tol);
  }
  // The horizon: K^-T R e_z, through the x and y vanishing points.
  const Eigen::Vector3d true_horizon = truth.K.inverse().transpose() * truth.R.col(2);
  CHECK(SignFreeDistance(out.horizon, true_horizon) < kNoiseFreeRelative * truth.size_px);
  for (int a = 0; a < 2; ++a)
    CHECK(std::abs(out.horizon.dot(Eigen::Vector3d(out.points_px[a].x(), out.points_px[a].y(), 1.0))) < tol);
  for (int a = 0; a < 3; ++a) CHECK(SignFreeDistance(out.directions_in_cam[a], truth.R.col(a)) < kNoiseFreeRelative);
}

TEST_CASE("three vanishing points: orthocentre = principal point, circles, f, horizon, directions") {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 50; ++trial) {
    CAPTURE(trial);
    CheckThreePointConstruction(RandomCamera(&rng, 1.0));
  }
}

TEST_CASE("the construction is scale-free: the same cameras at x1e-3 and x1e3 pixel scale") {
  for (const double scale : {1e-3, 1e3}) {
    CAPTURE(scale);
    std::mt19937 rng(11);
    for (int trial = 0; trial < 20; ++trial) CheckThreePointConstruction(RandomCamera(&rng, scale));
  }
}

TEST_CASE("the box scene's camera: the construction gives the synthetic camera") {
  const testing::SyntheticScene scene = testing::MakeBoxScene();
  const Camera& cam = scene.true_camera;
  TrueCamera truth{cam.K(), cam.cam_from_world_rotation, cam.focal_px, cam.principal_point_px,
                   std::hypot(double(cam.width_px), double(cam.height_px))};
  CheckThreePointConstruction(truth);
}

TEST_CASE("two vanishing points with the principal point given give f; the horizon from omega v_z") {
  std::mt19937 rng(3);
  for (int trial = 0; trial < 30; ++trial) {
    CAPTURE(trial);
    const TrueCamera truth = RandomCamera(&rng, 1.0);
    for (int missing = 0; missing < 3; ++missing) {
      CAPTURE(missing);
      VanishingConstructionInput input = TrueInput(truth);
      input.vanishing_points_px[missing].setZero();
      input.assumed_principal_point_px = truth.p;
      const VanishingConstruction out = ConstructFromVanishingPoints(input);
      REQUIRE(out.kind == VanishingConstructionKind::kTwoPoints);
      CHECK(out.principal_point_assumed);
      REQUIRE(out.focal_constructions.size() == 1u);
      const FocalConstruction& c = out.focal_constructions[0];
      CheckPairConstruction(c, out.points_px[c.axes[0]], out.points_px[c.axes[1]], truth, truth.p);
      CHECK(std::abs(out.focal_px - truth.f) < kNoiseFreeRelative * truth.f);
      const Eigen::Vector3d true_horizon = truth.K.inverse().transpose() * truth.R.col(2);
      CHECK(SignFreeDistance(out.horizon, true_horizon) < kNoiseFreeRelative * truth.size_px);
      for (int a = 0; a < 3; ++a) {
        if (a == missing) {
          CHECK(out.directions_in_cam[a].isZero());
        } else {
          CHECK(SignFreeDistance(out.directions_in_cam[a], truth.R.col(a)) < kNoiseFreeRelative);
        }
      }
    }
  }
}

TEST_CASE("one vanishing point: principal point and focal length assumed, the direction follows") {
  std::mt19937 rng(5);
  const TrueCamera truth = RandomCamera(&rng, 1.0);
  VanishingConstructionInput input = TrueInput(truth);
  input.vanishing_points_px[1].setZero();
  input.vanishing_points_px[2].setZero();
  input.assumed_principal_point_px = truth.p;
  input.assumed_focal_px = truth.f;
  const VanishingConstruction out = ConstructFromVanishingPoints(input);
  CHECK(out.kind == VanishingConstructionKind::kOnePoint);
  CHECK(out.principal_point_assumed);
  CHECK(out.focal_assumed);
  CHECK(out.focal_constructions.empty());
  CHECK(out.horizon.isZero());  // one horizontal point alone does not fix the horizon
  CHECK(SignFreeDistance(out.directions_in_cam[0], truth.R.col(0)) < kNoiseFreeRelative);
}

TEST_CASE("a point at infinity takes no part in the triangle; p outside a pair's circle is no camera") {
  VanishingConstructionInput input;
  input.vanishing_points_px[0] = Eigen::Vector3d(-400.0, 300.0, 1.0);
  input.vanishing_points_px[1] = Eigen::Vector3d(1400.0, 300.0, 1.0);
  input.vanishing_points_px[2] = Eigen::Vector3d(0.0, 1.0, 0.0);  // vertical lines parallel in the image
  input.assumed_principal_point_px = Eigen::Vector2d(500.0, 400.0);
  VanishingConstruction out = ConstructFromVanishingPoints(input);
  CHECK(out.kind == VanishingConstructionKind::kTwoPoints);
  CHECK_FALSE(out.finite[2]);
  CHECK(out.present[2]);
  REQUIRE(out.focal_constructions.size() == 1u);
  // f^2 = -(v_x - p).(v_y - p) = 900 * 900 - 100 * 100.
  CHECK(std::abs(out.focal_px - std::sqrt(900.0 * 900.0 - 100.0 * 100.0)) < 1e-9 * 900.0);
  // The horizon is the row through both points.
  CHECK(SignFreeDistance(out.horizon, Eigen::Vector3d(0.0, 1.0, -300.0)) < 1e-12);

  input.assumed_principal_point_px = Eigen::Vector2d(500.0, 2000.0);  // outside the circle
  out = ConstructFromVanishingPoints(input);
  REQUIRE(out.focal_constructions.size() == 1u);
  CHECK_FALSE(out.focal_constructions[0].valid);
  CHECK(out.focal_px == 0.0);
}

TEST_CASE("a triangle without a camera falls back to two points and the assumed principal point") {
  std::mt19937 rng(13);
  const TrueCamera truth = RandomCamera(&rng, 1.0);
  VanishingConstructionInput input = TrueInput(truth);
  input.assumed_principal_point_px = truth.p;
  // The z point moved so that the triangle is obtuse at it: its orthocentre lies outside.
  const Eigen::Vector2d vx = input.vanishing_points_px[0].head<2>() / input.vanishing_points_px[0].z();
  const Eigen::Vector2d vy = input.vanishing_points_px[1].head<2>() / input.vanishing_points_px[1].z();
  const Eigen::Vector2d between = 0.5 * (vx + vy) + 0.01 * Eigen::Vector2d(-(vy - vx).y(), (vy - vx).x());
  input.vanishing_points_px[2] = between.homogeneous();
  VanishingConstruction out = ConstructFromVanishingPoints(input);
  CHECK(out.triangle_failed);
  CHECK(out.kind == VanishingConstructionKind::kTwoPoints);
  CHECK(out.principal_point_assumed);
  CHECK((out.principal_point_px - truth.p).norm() == 0.0);
  // The (x, y) pair is untouched: it still gives the true f about the true p.
  REQUIRE(!out.focal_constructions.empty());
  CHECK(out.focal_constructions[0].axes == std::array<int, 2>{0, 1});
  REQUIRE(out.focal_constructions[0].valid);
  CHECK(std::abs(out.focal_constructions[0].focal_px - truth.f) < kNoiseFreeRelative * truth.f);

  // A point the caller calls at infinity leaves the triangle: two points, no failure.
  input = TrueInput(truth);
  input.assumed_principal_point_px = truth.p;
  input.at_infinity[0] = true;
  out = ConstructFromVanishingPoints(input);
  CHECK_FALSE(out.triangle_failed);
  CHECK(out.kind == VanishingConstructionKind::kTwoPoints);
  CHECK_FALSE(out.finite[0]);
  REQUIRE(out.focal_constructions.size() == 1u);
  CHECK(out.focal_constructions[0].axes == std::array<int, 2>{1, 2});
  CHECK(std::abs(out.focal_px - truth.f) < kNoiseFreeRelative * truth.f);
}

}  // namespace
}  // namespace facet
