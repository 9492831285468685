// The OpenCV-to-OpenGL camera conversion (app/platform/gl_camera.h): a world point taken through
// the GL matrices (glm::dmat4), the perspective divide and the viewport transform lands on the pixel
// Camera::Project gives, for an off-centre principal point, in a viewport of the image's
// size and in one of another aspect (image fitted and centred).
#include <doctest/doctest.h>

#include <cmath>
#include <random>

#include "app/platform/gl_camera.h"
#include "tests/synthetic_scene.h"

namespace facet::app {
namespace {

constexpr double kPixelTolerancePx = 1e-6;
constexpr double kDepthTolerance = 1e-9;

struct ViewportHit {
  Eigen::Vector2d uv_px;  // viewport pixel, OpenCV convention (top-left origin, centres at integers)
  double ndc_depth = 0.0;
  double clip_w = 0.0;
};

// What GL does: clip = P * V * p, divide by w, viewport transform to window coordinates
// (origin at the bottom-left corner, pixel centres at +0.5), then read back as an image whose
// top row is the framebuffer's last row.
// In double (glm::dmat4), as the matrices are: float would not hold 1e-6 px.
ViewportHit ProjectLikeGl(const GlCameraMatrices& gl, const Eigen::Vector3d& p_in_world, int w, int h) {
  const glm::dvec4 clip = gl.projection * gl.view * HomogeneousGlm(p_in_world);
  const glm::dvec3 ndc = glm::dvec3(clip) / clip.w;
  const double x_window = (ndc.x + 1.0) * 0.5 * w;
  const double y_window = (ndc.y + 1.0) * 0.5 * h;
  ViewportHit hit;
  hit.uv_px = Eigen::Vector2d(x_window - 0.5, (h - y_window) - 0.5);
  hit.ndc_depth = ndc.z;
  hit.clip_w = clip.w;
  return hit;
}

Camera OffCentreCamera() {
  testing::SyntheticSceneOptions options;
  options.width_px = 1200;
  options.height_px = 800;
  options.focal_px = 1100.0;
  options.principal_point_offset_px = {57.25, -31.5};  // far from the image centre
  return testing::MakeLookAtCamera(options);
}

std::vector<Eigen::Vector3d> PointsInFront(const Camera& camera, int count) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.2, 1.2);
  std::uniform_real_distribution<double> depth(2.0, 30.0);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector2d uv{u(rng) * camera.width_px, u(rng) * camera.height_px};
    points.push_back(camera.CenterInWorld() + depth(rng) * camera.RayDirectionInWorld(uv));
  }
  return points;
}

TEST_CASE("GL matrices reproduce Camera::Project in a viewport of the image size") {
  const Camera camera = OffCentreCamera();
  const Eigen::Vector2d centre((camera.width_px - 1) / 2.0, (camera.height_px - 1) / 2.0);
  REQUIRE((camera.principal_point_px - centre).norm() > 50.0);  // the offset is really exercised
  const GlCameraMatrices gl = GlMatricesFromCamera(camera, camera.width_px, camera.height_px, 0.5, 100.0);
  CHECK(gl.image_scale == 1.0);

  double max_error_px = 0.0;
  for (const Eigen::Vector3d& p : PointsInFront(camera, 200)) {
    const ViewportHit hit = ProjectLikeGl(gl, p, camera.width_px, camera.height_px);
    const Eigen::Vector2d expected = camera.Project(p);
    const double error_px = (hit.uv_px - expected).norm();
    max_error_px = std::max(max_error_px, error_px);
    CAPTURE(expected.transpose());
    CAPTURE(hit.uv_px.transpose());
    CHECK(error_px < kPixelTolerancePx);
    // Clip w is the OpenCV depth, so GL's perspective divide matches the camera's.
    CHECK(std::abs(hit.clip_w - camera.CamFromWorld(p).z()) < 1e-9 * hit.clip_w);
    CHECK(hit.ndc_depth > -1.0);
    CHECK(hit.ndc_depth < 1.0);
  }
  MESSAGE("max reprojection difference " << max_error_px << " px");
}

TEST_CASE("The principal point lands on its pixel and the image corners on the viewport's") {
  const Camera camera = OffCentreCamera();
  const GlCameraMatrices gl = GlMatricesFromCamera(camera, camera.width_px, camera.height_px, 0.5, 100.0);
  const Eigen::Vector3d on_axis = camera.CenterInWorld() + 10.0 * camera.RayDirectionInWorld(camera.principal_point_px);
  const ViewportHit hit = ProjectLikeGl(gl, on_axis, camera.width_px, camera.height_px);
  CAPTURE(hit.uv_px.transpose());
  CHECK((hit.uv_px - camera.principal_point_px).norm() < kPixelTolerancePx);

  // The top-left corner of the first pixel is the NDC corner (-1, +1).
  const Eigen::Vector3d corner = camera.CenterInWorld() + 10.0 * camera.RayDirectionInWorld({-0.5, -0.5});
  const glm::dvec4 clip = gl.projection * gl.view * HomogeneousGlm(corner);
  CAPTURE(clip.x);
  CAPTURE(clip.y);
  CAPTURE(clip.w);
  CHECK(std::abs(clip.x / clip.w + 1.0) < 1e-9);
  CHECK(std::abs(clip.y / clip.w - 1.0) < 1e-9);
}

TEST_CASE("Near and far depths map to GL depth -1 and +1") {
  const Camera camera = OffCentreCamera();
  const double near_depth = 0.25;
  const double far_depth = 40.0;
  const GlCameraMatrices gl = GlMatricesFromCamera(camera, camera.width_px, camera.height_px, near_depth, far_depth);
  const Eigen::Vector3d axis = camera.cam_from_world_rotation.row(2).transpose();
  const ViewportHit at_near =
      ProjectLikeGl(gl, camera.CenterInWorld() + near_depth * axis, camera.width_px, camera.height_px);
  const ViewportHit at_far =
      ProjectLikeGl(gl, camera.CenterInWorld() + far_depth * axis, camera.width_px, camera.height_px);
  CAPTURE(at_near.ndc_depth);
  CAPTURE(at_far.ndc_depth);
  CHECK(std::abs(at_near.ndc_depth + 1.0) < kDepthTolerance);
  CHECK(std::abs(at_far.ndc_depth - 1.0) < kDepthTolerance);
}

TEST_CASE("In a viewport of another aspect the image is fitted, centred and unstretched") {
  const Camera camera = OffCentreCamera();  // 1200 x 800
  for (const Eigen::Vector2i viewport : {Eigen::Vector2i(900, 900), Eigen::Vector2i(1600, 500)}) {
    const int w = viewport.x();
    const int h = viewport.y();
    const GlCameraMatrices gl = GlMatricesFromCamera(camera, w, h, 0.5, 100.0);
    const double s = std::min(double(w) / camera.width_px, double(h) / camera.height_px);
    const Eigen::Vector2d offset((w - s * camera.width_px) / 2.0, (h - s * camera.height_px) / 2.0);
    CHECK(std::abs(gl.image_scale - s) < 1e-12);
    CHECK((ToEigen(gl.image_offset_px) - offset).norm() < 1e-12);
    double max_error_px = 0.0;
    for (const Eigen::Vector3d& p : PointsInFront(camera, 100)) {
      const ViewportHit hit = ProjectLikeGl(gl, p, w, h);
      const Eigen::Vector2d expected =
          s * (camera.Project(p).array() + 0.5).matrix() + offset - Eigen::Vector2d(0.5, 0.5);
      max_error_px = std::max(max_error_px, (hit.uv_px - expected).norm());
    }
    CAPTURE(w);
    CAPTURE(h);
    CAPTURE(max_error_px);
    CHECK(max_error_px < kPixelTolerancePx);
  }
}

}  // namespace
}  // namespace facet::app
