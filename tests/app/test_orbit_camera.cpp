// Issue 12: the 3D view cannot orbit, pan or zoom below the ground plane, and reframes after
// large edits only (app/state/orbit_camera.h). Pure functions of the orbit: no window.
#include <doctest/doctest.h>

#include <cmath>

#include "app/state/orbit_camera.h"

using namespace facet::app;

namespace {
constexpr int kWidth = 800, kHeight = 600;
// The eye's height above the ground over the eye's distance to the target.
double Clearance(const OrbitCamera& orbit) { return EyeOf(orbit).z() / orbit.distance; }
}  // namespace

TEST_CASE("orbiting down stops with the eye above the ground, whatever the target's height") {
  for (const double target_z : {0.0, 1.5, -0.5}) {
    OrbitCamera orbit;
    orbit.target = Eigen::Vector3d(2.0, -1.0, target_z);
    orbit.distance = 10.0;
    // A long drag upwards on the screen tilts the eye down (OrbitRotate: dy > 0 raises the pitch,
    // so drag the other way).
    for (int i = 0; i < 200; ++i) OrbitRotate(&orbit, 0.0, -20.0, kWidth, kHeight);
    CAPTURE(target_z);
    CHECK(Clearance(orbit) >= kGroundClearance - 1e-12);
    CHECK(Clearance(orbit) < kGroundClearance + 1e-9);  // it did go down to the limit
    // Back up works as before.
    const double before = orbit.pitch_rad;
    OrbitRotate(&orbit, 0.0, 50.0, kWidth, kHeight);
    CHECK(orbit.pitch_rad > before);
  }
}

TEST_CASE("panning or zooming cannot take the eye below the ground either") {
  OrbitCamera orbit;
  orbit.target = Eigen::Vector3d(0.0, 0.0, 0.5);
  orbit.distance = 10.0;
  orbit.pitch_rad = 0.05;
  // Pan the target down: the view tilts up rather than sink.
  for (int i = 0; i < 50; ++i) OrbitPan(&orbit, 0.0, -40.0, kWidth, kHeight);
  CHECK(EyeOf(orbit).z() >= kGroundClearance * orbit.distance - 1e-9);
  for (int i = 0; i < 20; ++i) OrbitZoom(&orbit, -3.0, kWidth, kHeight);
  CHECK(EyeOf(orbit).z() >= kGroundClearance * orbit.distance - 1e-9);
  // MinPitchAboveGround: exact on the ground, the pole's limit when nothing works.
  CHECK(std::abs(std::sin(MinPitchAboveGround(0.0, 4.0)) - kGroundClearance) < 1e-12);
  CHECK(MinPitchAboveGround(-100.0, 1.0) > 1.5);
}

TEST_CASE("reframe only after large changes of the model") {
  const SceneBounds framed{Eigen::Vector3d(1.0, 2.0, 0.5), 3.0};
  CHECK_FALSE(NeedsReframe(framed, framed));
  CHECK_FALSE(NeedsReframe(framed, {Eigen::Vector3d(1.2, 2.1, 0.5), 3.3}));  // a solve's change
  CHECK(NeedsReframe(framed, {framed.center, 3.0 * kReframeRatio * 1.1}));   // grew
  CHECK(NeedsReframe(framed, {framed.center, 3.0 / (kReframeRatio * 1.1)}));  // shrank
  CHECK(NeedsReframe(framed, {framed.center + Eigen::Vector3d(4.0, 0.0, 0.0), 3.0}));  // moved away
}
