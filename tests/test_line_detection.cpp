// Lines found for the user (core/estimators/line_detection.h): the detector's pixel convention,
// the grouping on exact synthetic segments with outliers, detection and calibration on a
// rendered Manhattan scene with a known camera, and degenerate photos.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Geometry>
#include "core/estimators/line_detection.h"
#include "core/estimators/vanishing_point.h"
#include "tests/line_image.h"

namespace facet {
namespace {

using testing::LookAt;
using testing::Renderer;
using testing::RenderRoomCorner;
using testing::TestCamera;

TEST_CASE("the detector's endpoints are sub-pixel, pixel centres at integers") {
  // A dark quadrilateral with sides at known sub-pixel positions; every long detected segment
  // must lie on one of its four sides.
  const int w = 320, h = 240;
  Renderer renderer(w, h, 200);
  const std::vector<Eigen::Vector2d> quad = {{60.3, 50.7}, {250.6, 62.2}, {240.1, 190.4}, {70.8, 180.9}};
  renderer.Fill(quad, 40);
  const std::vector<Eigen::Vector4d> segments = DetectLineSegments(renderer.Image(), LineDetectionOptions{});
  REQUIRE(segments.size() >= 4);
  int on_sides = 0;
  double worst = 0.0;
  for (const Eigen::Vector4d& s : segments) {
    double best = 1e9;
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector3d line = quad[k].homogeneous().cross(quad[(k + 1) % 4].homogeneous());
      const double n = line.head<2>().norm();
      best = std::min(best, std::max(std::abs(line.dot(s.head<2>().homogeneous())) / n,
                                     std::abs(line.dot(s.tail<2>().homogeneous())) / n));
    }
    worst = std::max(worst, best);
    if (best < 0.25) ++on_sides;
  }
  MESSAGE("segments: " << segments.size() << ", worst endpoint distance to a side: " << worst << " px");
  // LSD on a clean edge is accurate to about a tenth of a pixel; an offset of half a pixel
  // (a corner-based convention) would fail this.
  CHECK(on_sides == static_cast<int>(segments.size()));
  CHECK(worst < 0.25);
}

// Exact segments of the three axis directions (inside a box seen by `camera`), plus outliers
// that pass no true vanishing point within twice the inlier distance.
struct SyntheticSegments {
  std::vector<Eigen::Vector4d> segments_px;
  std::vector<int> true_family;  // 0, 1, 2 for world x, y, z; -1 for an outlier
  std::array<Eigen::Vector3d, 3> vps;
};

// The inlier distance the grouping uses by default on a w x h image.
double DefaultInlierDistancePx(int w, int h) {
  return std::max(1.0, ManhattanLinesOptions{}.inlier_distance_rel_diagonal * std::hypot(w, h));
}

// The family the grouping must give a segment when the camera is recovered exactly: its own,
// or none when it also passes within the inlier distance of another vanishing point
// (ambiguous); outliers none.
int ExpectedFamily(const SyntheticSegments& data, size_t i, double inlier_px) {
  const int truth = data.true_family[i];
  if (truth < 0) return -1;
  for (int a = 0; a < 3; ++a)
    if (a != truth && SegmentVanishingPointResidualPx(data.segments_px[i], data.vps[a]) < inlier_px) return -1;
  return truth;
}

SyntheticSegments MakeSegments(const TestCamera& camera, int w, int h, int per_family, int outliers,
                               std::uint32_t seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  SyntheticSegments out;
  std::array<Eigen::Vector3d, 3>& vps = out.vps;
  for (int a = 0; a < 3; ++a) {
    Eigen::Matrix3d k = Eigen::Matrix3d::Identity();
    k(0, 0) = k(1, 1) = camera.focal_px;
    k.block<2, 1>(0, 2) = camera.pp_px;
    vps[a] = k * camera.cam_from_world.col(a);
  }
  auto inside = [&](const Eigen::Vector2d& p) { return p.x() >= 0 && p.y() >= 0 && p.x() <= w - 1 && p.y() <= h - 1; };
  for (int a = 0; a < 3; ++a) {
    int made = 0;
    while (made < per_family) {
      const Eigen::Vector3d start{4.0 * unit(random), 4.0 * unit(random), 3.0 * unit(random)};
      Eigen::Vector3d end = start;
      end[a] += 0.3 + 1.2 * unit(random);
      if (camera.ToCamera(start).z() < 0.5 || camera.ToCamera(end).z() < 0.5) continue;
      const Eigen::Vector2d p = camera.Project(start), q = camera.Project(end);
      if (!inside(p) || !inside(q) || (q - p).norm() < 30.0) continue;
      out.segments_px.push_back(Eigen::Vector4d(p.x(), p.y(), q.x(), q.y()));
      out.true_family.push_back(a);
      ++made;
    }
  }
  int made = 0;
  while (made < outliers) {
    const Eigen::Vector2d p{unit(random) * (w - 1), unit(random) * (h - 1)};
    const double angle = unit(random) * M_PI, length = 30.0 + 120.0 * unit(random);
    const Eigen::Vector2d q = p + length * Eigen::Vector2d(std::cos(angle), std::sin(angle));
    if (!inside(q)) continue;
    const Eigen::Vector4d s(p.x(), p.y(), q.x(), q.y());
    bool near_vp = false;
    for (const Eigen::Vector3d& v : vps)
      near_vp |= SegmentVanishingPointResidualPx(s, v) < 2.0 * DefaultInlierDistancePx(w, h);
    if (near_vp) continue;
    out.segments_px.push_back(s);
    out.true_family.push_back(-1);
    ++made;
  }
  return out;
}

TEST_CASE("grouping exact segments with 30 % outliers recovers the families and the camera to 1e-9") {
  const int w = 1024, h = 768;
  const TestCamera camera = LookAt({7.0, 5.5, 1.7}, {1.0, 1.5, 1.0}, 850.0, w, h);
  const SyntheticSegments data = MakeSegments(camera, w, h, 40, 51, 7);
  ManhattanLinesOptions options;
  options.calibration.width_px = w;
  options.calibration.height_px = h;
  const ManhattanLinesSummary s = GroupManhattanLines(data.segments_px, options);
  REQUIRE_MESSAGE(s.IsUsable(), s.message);
  MESSAGE(s.message);

  // The naming rule: z the most vertical direction, here world z. The detected labels must
  // map the true families one to one, and each segment get exactly its expected family.
  const double inlier_px = DefaultInlierDistancePx(w, h);
  std::array<int, 3> label_of_family = {-2, -2, -2};
  int mismatches = 0, ambiguous = 0;
  for (size_t i = 0; i < data.segments_px.size(); ++i) {
    const int expected = ExpectedFamily(data, i, inlier_px), got = s.segment_family[i];
    if (data.true_family[i] >= 0 && expected < 0) ++ambiguous;
    if (expected >= 0 && got >= 0 && label_of_family[expected] == -2) label_of_family[expected] = got;
    if ((expected < 0) != (got < 0) || (expected >= 0 && label_of_family[expected] != got)) ++mismatches;
  }
  MESSAGE(ambiguous << " of 120 true inliers are ambiguous at " << inlier_px << " px");
  CHECK(mismatches == 0);
  CHECK(label_of_family[2] == 2);
  CHECK(label_of_family[0] != label_of_family[1]);
  CHECK(label_of_family[0] >= 0);
  CHECK(label_of_family[1] >= 0);
  // Noise-free data: the fit is exact up to rounding.
  CHECK(std::abs(s.calibration.focal_px - camera.focal_px) / camera.focal_px < 1e-9);
  CHECK((s.calibration.principal_point_px - camera.pp_px).norm() < 1e-6);
}

TEST_CASE("grouping with the focal length fixed or under a prior finds the same families") {
  const int w = 1024, h = 768;
  const TestCamera camera = LookAt({6.0, 7.5, 2.2}, {1.5, 1.0, 0.8}, 700.0, w, h);
  const SyntheticSegments data = MakeSegments(camera, w, h, 30, 30, 11);
  for (int mode = 0; mode < 2; ++mode) {
    ManhattanLinesOptions options;
    options.calibration.width_px = w;
    options.calibration.height_px = h;
    if (mode == 0) {
      options.calibration.fixed_focal_px = 700.0;
    } else {
      options.calibration.focal_prior_px = 730.0;  // 4 % off, std 3 %: the segments decide
      options.calibration.focal_prior_std_px = 21.0;
    }
    const ManhattanLinesSummary s = GroupManhattanLines(data.segments_px, options);
    REQUIRE_MESSAGE(s.IsUsable(), s.message);
    int wrong = 0;
    for (size_t i = 0; i < data.segments_px.size(); ++i)
      if ((ExpectedFamily(data, i, DefaultInlierDistancePx(w, h)) < 0) != (s.segment_family[i] < 0)) ++wrong;
    CHECK(wrong == 0);
    // Exact segments: with the prior the fit is pulled off the truth by prior / data weight,
    // which the exact data make vanishing; the robust noise floor of calibrate_vp keeps it
    // finite, so 1e-6 relative.
    CHECK(std::abs(s.calibration.focal_px - 700.0) / 700.0 < (mode == 0 ? 1e-12 : 1e-6));
  }
}

TEST_CASE("detection and calibration on a rendered room corner recover the known camera") {
  const int w = 1200, h = 900;
  const TestCamera camera = LookAt({5.0, 4.2, 1.6}, {0.0, 0.0, 1.1}, 1000.0, w, h);
  const ImageRgba8 image = RenderRoomCorner(camera, w, h);
  ManhattanLinesOptions options;
  const ManhattanLinesSummary s = DetectManhattanLines(image, options);
  REQUIRE_MESSAGE(s.IsUsable(), s.message);
  const double focal_error = std::abs(s.calibration.focal_px - camera.focal_px) / camera.focal_px;
  const double pp_error = (s.calibration.principal_point_px - camera.pp_px).norm();
  MESSAGE(s.message << "; focal error " << 100.0 * focal_error << " %, principal point error " << pp_error
                    << " px, residual sigma " << s.calibration.residual_sigma_px << " px");
  for (int a = 0; a < 3; ++a) CHECK(s.segments_per_family[a] >= 10);
  // LSD's endpoints on these area-sampled edges are good to ~0.1 px (first test case); over
  // segments hundreds of px long spread across the image, that fixes each vanishing
  // direction to a few hundredths of a degree, and f to a few tenths of a percent. 1 % and
  // 1 % of the image diagonal (15 px) leave room for the detector's bias at corners.
  CHECK(focal_error < 0.01);
  CHECK(pp_error < 15.0);
}

TEST_CASE("a large photo is detected in bands: lines crossing the band boundaries come out whole") {
  // 2400 x 1500 = 3.6 MP, above the 2 MP of the banded path (four bands of 375 rows). A dark
  // slanted stripe from the top to the bottom: its two long edges cross all three boundaries.
  const int w = 2400, h = 1500;
  Renderer renderer(w, h, 190, 2);
  const std::vector<Eigen::Vector2d> stripe = {{1000.3, -20.0}, {1080.3, -20.0}, {1380.7, 1520.0}, {1300.7, 1520.0}};
  renderer.Fill(stripe, 40);
  const std::vector<Eigen::Vector4d> segments = DetectLineSegments(renderer.Image(), LineDetectionOptions{});
  // Each edge is one segment reaching (within LSD's few border pixels) from the top row to
  // the bottom one, and lies on its true line: its midpoint (far from any border) within
  // 0.5 px (cv::fillPoly fills every fine cell an edge touches, which moves the edge out by
  // up to half a fine cell, 0.25 px at factor 2, plus LSD's ~0.2 px), its ends, which LSD
  // places less well at the image border, within 1 px.
  REQUIRE(segments.size() == 2);
  const Eigen::Vector3d left = stripe[0].homogeneous().cross(stripe[3].homogeneous());
  const Eigen::Vector3d right = stripe[1].homogeneous().cross(stripe[2].homogeneous());
  for (const Eigen::Vector4d& s : segments) {
    CHECK(std::min(s[1], s[3]) < 4.0);
    CHECK(std::max(s[1], s[3]) > h - 5.0);
    const Eigen::Vector2d mid = 0.5 * (s.head<2>() + s.tail<2>());
    const Eigen::Vector3d line =
        std::abs(left.dot(mid.homogeneous())) < std::abs(right.dot(mid.homogeneous())) ? left : right;
    const double n = line.head<2>().norm();
    CHECK(std::abs(line.dot(mid.homogeneous())) / n < 0.5);
    CHECK(std::abs(line.dot(s.head<2>().homogeneous())) / n < 1.0);
    CHECK(std::abs(line.dot(s.tail<2>().homogeneous())) / n < 1.0);
  }
  CHECK((segments[0] - segments[1]).norm() > 100.0);  // the two edges, not one twice
}

TEST_CASE("detection and calibration on a 4.3 MP room corner (banded) recover the known camera") {
  const int w = 2400, h = 1800;
  const TestCamera camera = LookAt({5.0, 4.2, 1.6}, {0.0, 0.0, 1.1}, 2000.0, w, h);
  const ManhattanLinesSummary s = DetectManhattanLines(RenderRoomCorner(camera, w, h, 2), ManhattanLinesOptions{});
  REQUIRE_MESSAGE(s.IsUsable(), s.message);
  const double focal_error = std::abs(s.calibration.focal_px - camera.focal_px) / camera.focal_px;
  MESSAGE(s.message << "; focal error " << 100.0 * focal_error << " %");
  CHECK(focal_error < 0.01);  // as at 1200 x 900 (the scene is the same, twice the pixels)
}

TEST_CASE("degenerate photos give a clear failure, never a crash") {
  SUBCASE("an empty image") {
    const ManhattanLinesSummary s = DetectManhattanLines(ImageRgba8{}, ManhattanLinesOptions{});
    CHECK_FALSE(s.IsUsable());
    CHECK(s.termination == SolverTermination::kInvalidInput);
    CHECK(s.message == "the image is empty");
  }
  SUBCASE("a blank image") {
    Renderer renderer(640, 480, 128);
    const ManhattanLinesSummary s = DetectManhattanLines(renderer.Image(), ManhattanLinesOptions{});
    CHECK_FALSE(s.IsUsable());
    CHECK(s.segments_px.empty());
    CHECK(s.message.find("too few line segments") == 0);
  }
  SUBCASE("one set of parallel lines: only one direction") {
    Renderer renderer(640, 480, 200);
    for (int i = 0; i < 12; ++i) {
      const double x = 30.0 + 50.0 * i;
      renderer.Fill({{x, -10.0}, {x + 20.0, -10.0}, {x + 20.0, 490.0}, {x, 490.0}}, 50);  // no end edges
    }
    const ManhattanLinesSummary s = DetectManhattanLines(renderer.Image(), ManhattanLinesOptions{});
    CHECK_FALSE(s.IsUsable());
    CHECK(s.message.find("only one vanishing direction") == 0);
    CHECK(s.labelled_segments.empty());
  }
  SUBCASE("a non-finite segment is rejected") {
    ManhattanLinesOptions options;
    options.calibration.width_px = 640;
    options.calibration.height_px = 480;
    std::vector<Eigen::Vector4d> segments(6, Eigen::Vector4d(0, 0, 100, 100));
    segments[3].x() = std::nan("");
    const ManhattanLinesSummary s = GroupManhattanLines(segments, options);
    CHECK(s.termination == SolverTermination::kInvalidInput);
  }
}

}  // namespace
}  // namespace facet
