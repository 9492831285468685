// The bundled sample project (assets/samples/leuven, a version-2 file; the version-1
// migration has its own fixture, tests/fixtures/project_v1.facet): it loads with three line
// families drawn along the buildings' edges, a box primitive and its vertex pins; every
// segment lies on an edge of the photo; its stored solution is what the model update
// computes from its lines and pins, and the geometry solve alone stays near it; the box it
// fits lies on the building's edges in the photo. How close the lines' focal length comes to
// the photo's reference K (OpenCV's data, in ../shared/data) is tests/realdata/test_leuven_focal.cpp.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/io/project_io.h"
#include "core/mesh/box.h"
#include "core/solve/model_update.h"

namespace {

const std::string kSamplePath = std::string(FACET_SOURCE_DIR) + "/assets/samples/leuven/leuven.facet";

// Mean Sobel gradient magnitude along the segment a-b, shifted by `offset_px` along its normal.
double MeanGradientAlong(const cv::Mat& gradient, const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                         double offset_px) {
  const Eigen::Vector2d dir = (b - a).normalized();
  const Eigen::Vector2d normal(-dir.y(), dir.x());
  const int samples = std::max(2, static_cast<int>((b - a).norm()));
  double sum = 0.0;
  int count = 0;
  for (int i = 0; i <= samples; ++i) {
    const Eigen::Vector2d p = a + (b - a) * (static_cast<double>(i) / samples) + offset_px * normal;
    const int x = static_cast<int>(std::lround(p.x())), y = static_cast<int>(std::lround(p.y()));
    if (x < 0 || y < 0 || x >= gradient.cols || y >= gradient.rows) continue;
    sum += gradient.at<float>(y, x);
    ++count;
  }
  return count > 0 ? sum / count : 0.0;
}

// Mean Sobel gradient magnitude along the segment, sampled bilinearly at pixel steps and
// shifted by `offset_px` along its normal (sub-pixel: the segments' endpoints are).
double SubPixelGradientAlong(const cv::Mat& gradient, const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                             double offset_px) {
  const Eigen::Vector2d dir = (b - a).normalized();
  const Eigen::Vector2d normal(-dir.y(), dir.x());
  const int samples = std::max(2, static_cast<int>((b - a).norm()));
  double sum = 0.0;
  for (int i = 0; i <= samples; ++i) {
    const Eigen::Vector2d p = a + (b - a) * (static_cast<double>(i) / samples) + offset_px * normal;
    cv::Mat value;
    cv::getRectSubPix(gradient, cv::Size(1, 1), cv::Point2f(static_cast<float>(p.x()), static_cast<float>(p.y())),
                      value);
    sum += value.at<float>(0, 0);
  }
  return sum / (samples + 1);
}

cv::Mat SobelMagnitude(const cv::Mat& gray) {
  cv::Mat gx, gy, gradient;
  cv::Sobel(gray, gx, CV_32F, 1, 0);
  cv::Sobel(gray, gy, CV_32F, 0, 1);
  cv::magnitude(gx, gy, gradient);
  return gradient;
}

}  // namespace

TEST_CASE("the Leuven sample is a version-2 file with three line families, a box primitive and its pins") {
  std::ifstream file(kSamplePath);
  std::stringstream text;
  text << file.rdbuf();
  CHECK(text.str().find("\"version\": 2,") != std::string::npos);
  const facet::ProjectLoadResult loaded = facet::LoadProject(kSamplePath);
  INFO(loaded.error);
  REQUIRE(loaded.ok());
  CHECK(loaded.warnings.empty());
  const facet::Project& p = loaded.project;
  REQUIRE(p.images.size() == 1);
  // A careful user's lines: several per family, so that one badly placed segment can be
  // flagged and the vanishing points do not rest on two segments.
  constexpr int kMinSegmentsPerFamily = 6;
  int per_axis[3] = {0, 0, 0};
  for (const auto& s : p.segments) ++per_axis[static_cast<int>(s.axis)];
  for (int count : per_axis) CHECK(count >= kMinSegmentsPerFamily);
  REQUIRE(p.primitives.size() == 1);
  CHECK(p.primitives[0].shape.kind == facet::PrimitiveKind::kBox);
  CHECK(p.primitives[0].mesh.NumVertices() == 8);
  CHECK(p.pins.size() >= 4);
  for (const facet::Pin& pin : p.pins) CHECK(p.FindVertex(pin.vertex) != nullptr);
  CHECK(p.images[0].camera_calibrated);
  // The intrinsics come from the lines alone (the four pins cannot refine them).
  CHECK(p.images[0].focal_locked);
  CHECK(p.images[0].principal_point_locked);
}

TEST_CASE("every segment of the sample lies on an edge of the photo") {
  const facet::ProjectLoadResult loaded = facet::LoadProject(kSamplePath);
  REQUIRE(loaded.ok());
  const facet::Project& p = loaded.project;
  const cv::Mat photo = cv::imread(facet::ResolveImagePath(kSamplePath, p.images[0].path), cv::IMREAD_GRAYSCALE);
  REQUIRE_FALSE(photo.empty());
  const cv::Mat gradient = SobelMagnitude(photo);
  // On an edge: across the segment, the gradient profile (sampled every 0.25 px within
  // kSearchPx) peaks within kMaxPeakOffsetPx of it, and there the response stands out from
  // the flatter of its two sides at kBesideOffsetPx (the other side may hold a parallel
  // edge: a transom's top and bottom are 4 px apart). A segment a pixel off its edge, or on
  // brick texture, fails one of the two.
  constexpr double kSearchPx = 3.0;
  constexpr double kMaxPeakOffsetPx = 0.5;
  constexpr double kBesideOffsetPx = 4.0;
  constexpr double kMinEdgeContrast = 1.5;
  double min_contrast = 1e9, max_peak_offset_px = 0.0;
  for (const facet::Segment& s : p.segments) {
    double peak = -1.0, peak_offset_px = 0.0;
    for (double offset_px = -kSearchPx; offset_px <= kSearchPx + 1e-9; offset_px += 0.25) {
      const double g = SubPixelGradientAlong(gradient, s.a_px, s.b_px, offset_px);
      if (g > peak) peak = g, peak_offset_px = offset_px;
    }
    const double on = SubPixelGradientAlong(gradient, s.a_px, s.b_px, 0.0);
    const double flatter_side = std::min(SubPixelGradientAlong(gradient, s.a_px, s.b_px, -kBesideOffsetPx),
                                         SubPixelGradientAlong(gradient, s.a_px, s.b_px, kBesideOffsetPx));
    INFO("segment " << s.id << " (" << std::string(facet::AxisName(s.axis)) << "): gradient " << on
                    << " on it, profile peak at " << peak_offset_px << " px, " << flatter_side << " at "
                    << kBesideOffsetPx << " px on the flatter side");
    CHECK(std::abs(peak_offset_px) <= kMaxPeakOffsetPx);
    CHECK(on > kMinEdgeContrast * flatter_side);
    min_contrast = std::min(min_contrast, on / flatter_side);
    max_peak_offset_px = std::max(max_peak_offset_px, std::abs(peak_offset_px));
  }
  MESSAGE("Leuven sample: " << p.segments.size() << " segments; gradient peaks at most " << max_peak_offset_px
                            << " px from a segment; lowest on-edge / flatter-side ratio " << min_contrast);
}

TEST_CASE("the sample's stored solution is what the model update computes") {
  const facet::ProjectLoadResult loaded = facet::LoadProject(kSamplePath);
  REQUIRE(loaded.ok());
  facet::ModelUpdateOptions options;
  options.solve.warm_start = false;
  facet::Project updated;
  const facet::ModelUpdateSummary summary = facet::UpdateModel(loaded.project, options, &updated);
  INFO(summary.solve.message << " / " << summary.joint.message);
  REQUIRE(summary.ok);
  REQUIRE(summary.joint.IsUsable());
  // The pins are a user's clicks on a real photo: about a pixel of disagreement is expected.
  constexpr double kMaxSampleRmsPx = 2.0;
  CHECK(summary.solve.reprojection_rms_px < kMaxSampleRmsPx);
  CHECK(summary.joint.reprojection_rms_px < kMaxSampleRmsPx);
  // The same solves from the same start reach the same minimum; 1e-6 relative leaves room
  // for the tolerances at which LM stops.
  constexpr double kRelativeTolerance = 1e-6;
  const Eigen::Vector4d stored = loaded.project.primitives[0].shape.params;
  const Eigen::Vector4d solved = updated.primitives[0].shape.params;
  CHECK((stored - solved).norm() < kRelativeTolerance * stored.norm());
  const Eigen::Vector3d stored_center = loaded.project.images[0].camera.CenterInWorld();
  CHECK((stored_center - updated.images[0].camera.CenterInWorld()).norm() < kRelativeTolerance * stored_center.norm());
  const facet::Camera& stored_camera = loaded.project.images[0].camera;
  CHECK(std::abs(updated.images[0].camera.focal_px - stored_camera.focal_px) <
        kRelativeTolerance * stored_camera.focal_px);
  // Intrinsics locked: the joint solve keeps what calibration gave.
  CHECK(updated.images[0].camera.focal_px == summary.calibration.at(updated.images[0].id).focal_px);
  MESSAGE("Leuven sample: focal " << updated.images[0].camera.focal_px << " px; pin RMS "
                                  << summary.joint.reprojection_rms_px << " px (geometry solve "
                                  << summary.solve.reprojection_rms_px << " px)");
}

TEST_CASE("the geometry solve alone stays near the sample's solution") {
  const facet::ProjectLoadResult loaded = facet::LoadProject(kSamplePath);
  REQUIRE(loaded.ok());
  facet::ModelUpdateOptions options;
  options.solve.warm_start = false;
  options.joint_solve = false;
  facet::Project updated;
  const facet::ModelUpdateSummary summary = facet::UpdateModel(loaded.project, options, &updated);
  INFO(summary.solve.message);
  REQUIRE(summary.ok);
  REQUIRE(summary.solve.IsUsable());
  // The joint solve also fits the rotation to the lines and the pins together, so the
  // geometry-only box differs from the stored one by a few percent at most.
  constexpr double kMaxRelativeChange = 0.05;
  const Eigen::Vector4d stored = loaded.project.primitives[0].shape.params;
  const double change = (updated.primitives[0].shape.params - stored).norm() / stored.norm();
  MESSAGE("Leuven sample, geometry solve only: pin RMS " << summary.solve.reprojection_rms_px << " px, box change "
                                                         << 100.0 * change << " %");
  CHECK(change < kMaxRelativeChange);
}

TEST_CASE("the sample box's projected front-face edges lie on edges of the photo") {
  const facet::ProjectLoadResult loaded = facet::LoadProject(kSamplePath);
  REQUIRE(loaded.ok());
  const facet::Project& p = loaded.project;
  const cv::Mat photo = cv::imread(facet::ResolveImagePath(kSamplePath, p.images[0].path), cv::IMREAD_GRAYSCALE);
  REQUIRE_FALSE(photo.empty());
  const cv::Mat gradient = SobelMagnitude(photo);

  const facet::Camera& camera = p.images[0].camera;
  const facet::PolyMesh& box = p.primitives[0].mesh;  // vertex i is corner i
  // The front face (-Y, facing the camera): its four edges are on the building's outline and
  // on a timber beam.
  const auto& face = facet::BoxFaces()[2];
  double on_edges = 0.0, beside_edges = 0.0, left_edge_contrast = 0.0;
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector2d a = camera.Project(box.vertex(face[k]).position);
    const Eigen::Vector2d b = camera.Project(box.vertex(face[(k + 1) % 4]).position);
    // Best response within a pixel of the projected edge, against 8 px to either side.
    double on = 0.0;
    for (double d : {-1.0, 0.0, 1.0}) on = std::max(on, MeanGradientAlong(gradient, a, b, d));
    const double beside = 0.5 * (MeanGradientAlong(gradient, a, b, -8.0) + MeanGradientAlong(gradient, a, b, 8.0));
    MESSAGE("front-face edge " << k << ": gradient " << on << " on the edge, " << beside << " 8 px beside it");
    on_edges += on;
    beside_edges += beside;
    if (k == 3) left_edge_contrast = on / beside;
  }
  // Brick gives a strong background gradient (50-80 here), and the bottom edge runs behind a
  // wall, so the contrast is ~1.9; a box off by 8 px scores ~1 by construction.
  constexpr double kMinContrast = 1.6;
  CHECK(on_edges > kMinContrast * beside_edges);
  // The strongest outline, the house's left corner (edge 3), must stand out on its own.
  CHECK(left_edge_contrast > 2.0);
}
