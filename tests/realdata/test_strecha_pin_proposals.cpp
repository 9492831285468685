// Pins proposed across photos (core/solve/pin_proposals.h, issue 26) on the real fountain
// photos with their ground-truth cameras, at a quarter of their size. Well-textured points:
// SIFT matches between 0004 and 0007 that agree with the ground-truth epipolar geometry,
// triangulated with those cameras. Each is pinned in 0004 at its projection, the model's
// estimate of it put 4 % off in depth (alternately nearer and farther), and proposed in 0005
// and 0006 (each the other's third photo). Prints the pixel error's median and 90th
// percentile, the share proposed and the share more than 3 px wrong.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/image/gray_image.h"
#include "core/solve/pin_proposals.h"
#include "tests/realdata/strecha_cameras.h"

using namespace facet;
using facet::testing::GroundTruthCamera;

namespace {

constexpr double kScale = 0.25;

struct View {
  Camera camera;
  cv::Mat gray;  // CV_8U, at the working size
  GrayImage image;
};

// The photo at a quarter of its width and a quarter times fx / fy of its height, so that the
// ground truth's non-square pixels become square ones (Camera has one focal length).
View LoadView(const std::string& name) {
  const GroundTruthCamera gt = facet::testing::ReadStrechaCamera(name);
  const cv::Mat photo =
      cv::imread((facet::testing::StrechaFountainDir() / "images" / (name + ".jpg")).string(), cv::IMREAD_GRAYSCALE);
  REQUIRE_MESSAGE(!photo.empty(), "cannot read photo " << name);
  const double sx = kScale, sy = kScale * gt.K(0, 0) / gt.K(1, 1);
  View v;
  cv::resize(photo, v.gray, cv::Size(), sx, sy, cv::INTER_AREA);
  v.camera.width_px = v.gray.cols;
  v.camera.height_px = v.gray.rows;
  v.camera.focal_px = gt.K(0, 0) * sx;
  v.camera.principal_point_px = Eigen::Vector2d((gt.K(0, 2) + 0.5) * sx - 0.5, (gt.K(1, 2) + 0.5) * sy - 0.5);
  v.camera.cam_from_world_rotation = gt.cam_from_world_rotation;
  v.camera.cam_from_world_translation = gt.cam_from_world_translation;
  v.image.width = v.gray.cols;
  v.image.height = v.gray.rows;
  v.image.pixels.resize(static_cast<size_t>(v.gray.total()));
  for (int y = 0; y < v.gray.rows; ++y)
    for (int x = 0; x < v.gray.cols; ++x)
      v.image.pixels[static_cast<size_t>(y) * v.gray.cols + x] = v.gray.at<uchar>(y, x);
  return v;
}

// Linear triangulation of two views' pixels.
Eigen::Vector3d Triangulate(const Camera& a, const Eigen::Vector2d& uv_a, const Camera& b,
                            const Eigen::Vector2d& uv_b) {
  Eigen::Matrix4d m;
  const Eigen::Matrix<double, 3, 4> pa = a.ProjectionMatrix(), pb = b.ProjectionMatrix();
  m.row(0) = uv_a.x() * pa.row(2) - pa.row(0);
  m.row(1) = uv_a.y() * pa.row(2) - pa.row(1);
  m.row(2) = uv_b.x() * pb.row(2) - pb.row(0);
  m.row(3) = uv_b.y() * pb.row(2) - pb.row(1);
  const Eigen::Vector4d x = Eigen::JacobiSVD<Eigen::Matrix4d>(m, Eigen::ComputeFullV).matrixV().col(3);
  return x.head<3>() / x.w();
}

double Percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<size_t>(q * (v.size() - 1) + 0.5))];
}

}  // namespace

TEST_CASE("Strecha fountain: pins in 0004 proposed in 0005 and 0006 against the ground truth") {
  const View v4 = LoadView("0004"), v5 = LoadView("0005"), v6 = LoadView("0006"), v7 = LoadView("0007");
  // Ground-truth points from SIFT matches 0004 - 0007 on the ground-truth epipolar geometry.
  cv::Ptr<cv::SIFT> sift = cv::SIFT::create(1500);
  std::vector<cv::KeyPoint> k4, k7;
  cv::Mat d4, d7;
  sift->detectAndCompute(v4.gray, cv::noArray(), k4, d4);
  sift->detectAndCompute(v7.gray, cv::noArray(), k7, d7);
  std::vector<std::vector<cv::DMatch>> knn;
  cv::BFMatcher(cv::NORM_L2).knnMatch(d4, d7, knn, 2);
  std::vector<Eigen::Vector3d> points;
  for (const auto& m : knn) {
    if (m.size() < 2 || m[0].distance > 0.7f * m[1].distance) continue;
    const Eigen::Vector2d a(k4[m[0].queryIdx].pt.x, k4[m[0].queryIdx].pt.y);
    const Eigen::Vector2d b(k7[m[0].trainIdx].pt.x, k7[m[0].trainIdx].pt.y);
    const Eigen::Vector3d x = Triangulate(v4.camera, a, v7.camera, b);
    constexpr double kAgreePx = 0.5;  // both reprojections (quarter-size px)
    if (!(v4.camera.CamFromWorld(x).z() > 0.0 && v7.camera.CamFromWorld(x).z() > 0.0)) continue;
    if ((v4.camera.Project(x) - a).norm() > kAgreePx || (v7.camera.Project(x) - b).norm() > kAgreePx) continue;
    points.push_back(x);
    if (points.size() >= 300) break;
  }
  MESSAGE(points.size() << " ground-truth points from " << knn.size() << " SIFT matches");
  REQUIRE(points.size() >= 100);

  const PinProposalOptions options;
  std::vector<double> errors_px;
  int tried = 0, proposed = 0, wrong = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d& x = points[i];
    const Eigen::Vector2d pin = v4.camera.Project(x);
    const Eigen::Vector3d c4 = v4.camera.CenterInWorld();
    const Eigen::Vector3d estimate = c4 + (i % 2 == 0 ? 1.04 : 0.96) * (x - c4);
    for (const View* target : {&v5, &v6}) {
      const View* other = target == &v5 ? &v6 : &v5;
      const Eigen::Vector2d truth = target->camera.Project(x);
      if (!(truth.x() >= 10 && truth.y() >= 10 && truth.x() < target->camera.width_px - 10 &&
            truth.y() < target->camera.height_px - 10))
        continue;
      ++tried;
      const ProposalView a{4, &v4.camera, &v4.image, pin};
      const ProposalView b{5, &target->camera, &target->image, std::nullopt};
      const ProposalView c{6, &other->camera, &other->image, std::nullopt};
      const PointMatch match = MatchPointAlongEpipolar(a, b, {c}, estimate, {}, options);
      if (!match.Proposed()) continue;
      ++proposed;
      const double error_px = (match.uv_px - truth).norm();
      errors_px.push_back(error_px);
      if (error_px > 3.0) ++wrong;
    }
  }
  REQUIRE(tried > 0);
  REQUIRE(proposed > 0);
  const double median = Percentile(errors_px, 0.5), p90 = Percentile(errors_px, 0.9);
  const double share_proposed = static_cast<double>(proposed) / tried;
  const double share_wrong = static_cast<double>(wrong) / proposed;
  char line[256];
  std::snprintf(line, sizeof(line),
                "fountain 0004 -> 0005/0006 (quarter size, 768 px wide): %d tried, %.1f %% proposed, error median "
                "%.2f px, 90th percentile %.2f px, %.1f %% wrong by > 3 px",
                tried, 100.0 * share_proposed, median, p90, 100.0 * share_wrong);
  MESSAGE(line);
  // Measured (quarter size): 88.3 % of 316 proposed, median 0.18 px, 90th percentile 0.51 px,
  // none wrong by more than 3 px (1.1 % with one-dimensional parabolas instead of the 3 x 3
  // quadratic); the bounds leave a margin over those.
  CHECK(median < 0.5);
  CHECK(p90 < 1.5);
  CHECK(share_wrong < 0.05);
  CHECK(share_proposed > 0.7);
}
