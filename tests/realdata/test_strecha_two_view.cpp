// Two-view geometry (core/estimators/two_view.h) on Strecha's fountain-P11 (pairs among 0004-0007):
// 30 SIFT matches per pair, spread over the image, stand in for the user's clicks; with the
// ground-truth K the relative pose is compared with the ground-truth cameras, and the
// symmetric epipolar RMS with cv::findFundamentalMat's on the same matches.
// Data: FACET_SHARED_DATA/strecha-fountain-p11-subset (PROVENANCE.md there). Camera files:
// K (3 rows), "0 0 0", R (camera -> world, 3 rows), C (centre), "w h"; P = K [R^T | -R^T C].
#include <doctest/doctest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <Eigen/Geometry>

#include "core/estimators/two_view.h"
#include "tests/realdata/strecha_cameras.h"

namespace facet {
namespace {

namespace fs = std::filesystem;
using Points = std::vector<Eigen::Vector2d>;

const fs::path kDataDir = testing::StrechaFountainDir();
// The bounds.
constexpr double kMaxRotationErrorDeg = 0.5;
constexpr double kMaxTranslationErrorDeg = 2.0;
constexpr int kMatchesPerPair = 30;
// SIFT runs on images downscaled by this factor (runtime); keypoints are scaled back.
constexpr double kDetectionScale = 0.5;
constexpr double kRatioTest = 0.75;
constexpr int kGridColumns = 6;
constexpr int kGridRows = 5;
constexpr double kRadToDeg = 180.0 / M_PI;

struct Features {
  std::vector<cv::KeyPoint> keypoints;  // in downscaled pixels
  cv::Mat descriptors;
};

Features Detect(const std::string& name) {
  const fs::path path = kDataDir / "images" / (name + ".jpg");
  const cv::Mat grey = cv::imread(path.string(), cv::IMREAD_GRAYSCALE);
  REQUIRE_MESSAGE(!grey.empty(), "cannot read " << path);
  cv::Mat small;
  cv::resize(grey, small, cv::Size(), kDetectionScale, kDetectionScale, cv::INTER_AREA);
  Features f;
  cv::SIFT::create(4000)->detectAndCompute(small, cv::noArray(), f.keypoints, f.descriptors);
  return f;
}

// Full-resolution pixel of a keypoint (pixel centres at integers in both images).
Eigen::Vector2d FullResolution(const cv::Point2f& p) {
  return {(p.x + 0.5) / kDetectionScale - 0.5, (p.y + 0.5) / kDetectionScale - 0.5};
}

// Ratio-test matches, then the best match of each grid cell of image 1 (best first), then
// the best remaining ones, up to kMatchesPerPair: clicks spread over the image.
void SelectMatches(const Features& a, const Features& b, int width_px, int height_px, Points* uv1, Points* uv2) {
  std::vector<std::vector<cv::DMatch>> knn;
  cv::BFMatcher(cv::NORM_L2).knnMatch(a.descriptors, b.descriptors, knn, 2);
  struct Candidate {
    double ratio;
    Eigen::Vector2d p1, p2;
  };
  std::vector<Candidate> candidates;
  for (const auto& m : knn) {
    if (m.size() < 2 || m[0].distance >= kRatioTest * m[1].distance) continue;
    candidates.push_back({m[0].distance / std::max(m[1].distance, 1e-6f), FullResolution(a.keypoints[m[0].queryIdx].pt),
                          FullResolution(b.keypoints[m[0].trainIdx].pt)});
  }
  std::sort(candidates.begin(), candidates.end(), [](const auto& x, const auto& y) { return x.ratio < y.ratio; });
  std::vector<bool> taken(candidates.size(), false);
  std::vector<bool> cell_used(kGridColumns * kGridRows, false);
  for (size_t i = 0; i < candidates.size() && static_cast<int>(uv1->size()) < kMatchesPerPair; ++i) {
    const int cx = std::clamp(static_cast<int>(candidates[i].p1.x() / width_px * kGridColumns), 0, kGridColumns - 1);
    const int cy = std::clamp(static_cast<int>(candidates[i].p1.y() / height_px * kGridRows), 0, kGridRows - 1);
    if (cell_used[cy * kGridColumns + cx]) continue;
    cell_used[cy * kGridColumns + cx] = true;
    taken[i] = true;
    uv1->push_back(candidates[i].p1);
    uv2->push_back(candidates[i].p2);
  }
  for (size_t i = 0; i < candidates.size() && static_cast<int>(uv1->size()) < kMatchesPerPair; ++i) {
    if (taken[i]) continue;
    uv1->push_back(candidates[i].p1);
    uv2->push_back(candidates[i].p2);
  }
}

Eigen::Matrix3d OpenCvFundamental(const Points& uv1, const Points& uv2, int method, const std::vector<bool>& use) {
  std::vector<cv::Point2d> p1, p2;
  for (size_t i = 0; i < uv1.size(); ++i) {
    if (!use.empty() && !use[i]) continue;
    p1.emplace_back(uv1[i].x(), uv1[i].y());
    p2.emplace_back(uv2[i].x(), uv2[i].y());
  }
  const cv::Mat f = cv::findFundamentalMat(p1, p2, method, 3.0, 0.99);
  Eigen::Matrix3d out = Eigen::Matrix3d::Zero();
  if (f.rows < 3) return out;  // no solution
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) out(r, c) = f.at<double>(r, c);
  return out;
}

TEST_CASE("Strecha fountain: relative pose and F from 30 SIFT matches per pair") {
  REQUIRE_MESSAGE(fs::exists(kDataDir), "missing " << kDataDir);
  const auto t_detect = std::chrono::steady_clock::now();
  const std::vector<std::string> names = {"0004", "0005", "0006", "0007"};
  std::map<std::string, Features> features;
  std::map<std::string, testing::GroundTruthCamera> cameras;
  for (const auto& name : names) {
    features[name] = Detect(name);
    cameras[name] = testing::ReadStrechaCamera(name);
  }
  const double detect_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t_detect).count();
  MESSAGE("SIFT on 4 images at scale " << kDetectionScale << ": " << detect_ms << " ms");

  const std::vector<std::pair<std::string, std::string>> pairs = {{"0004", "0005"}, {"0005", "0006"}, {"0006", "0007"},
                                                                  {"0004", "0006"}, {"0005", "0007"}, {"0004", "0007"}};
  for (const auto& [name1, name2] : pairs) {
    // Named copies: clang 14 cannot capture a structured binding, and CAPTURE is a lambda.
    const auto& first = name1;
    const auto& second = name2;
    CAPTURE(first);
    CAPTURE(second);
    const testing::GroundTruthCamera& c1 = cameras[name1];
    const testing::GroundTruthCamera& c2 = cameras[name2];
    Points uv1, uv2;
    SelectMatches(features[name1], features[name2], 3072, 2048, &uv1, &uv2);
    REQUIRE(static_cast<int>(uv1.size()) == kMatchesPerPair);

    const FundamentalSummary f = EstimateFundamentalMatrix(uv1, uv2, FundamentalOptions());
    REQUIRE_MESSAGE(f.IsUsable(), f.message);
    const RelativePoseSummary pose = EstimateRelativePose(f.F, c1.K, c2.K, uv1, uv2, f.inliers, RelativePoseOptions());
    REQUIRE_MESSAGE(pose.IsUsable(), pose.message);

    const Eigen::Matrix3d true_r = c2.cam_from_world_rotation * c1.cam_from_world_rotation.transpose();
    const Eigen::Vector3d true_t = c2.cam_from_world_translation - true_r * c1.cam_from_world_translation;
    const double rot_err_deg = Eigen::AngleAxisd(pose.cam2_from_cam1_rotation * true_r.transpose()).angle() * kRadToDeg;
    const Eigen::Vector3d& t = pose.cam2_from_cam1_translation;
    const double t_err_deg = std::atan2(t.cross(true_t).norm(), t.dot(true_t)) * kRadToDeg;

    // The ground-truth F judges the flags: a flagged match should be off its epipolar line.
    const Eigen::Vector3d u = true_t.normalized();
    Eigen::Matrix3d skew;
    skew << 0, -u.z(), u.y(), u.z(), 0, -u.x(), -u.y(), u.x(), 0;
    const Eigen::Matrix3d true_f = c2.K.inverse().transpose() * skew * true_r * c1.K.inverse();
    const double true_f_rms = SymmetricEpipolarRms(true_f, uv1, uv2, f.inliers);
    double closest_outlier_px = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < uv1.size(); ++i)
      if (!f.inliers[i])
        closest_outlier_px = std::min(closest_outlier_px, SymmetricEpipolarDistances(true_f, uv1[i], uv2[i]).norm());
    MESSAGE(name1 << "-" << name2 << ": ground-truth F RMS on our inliers " << true_f_rms << " px; "
                  << (f.num_inliers == static_cast<int>(uv1.size())
                          ? std::string("no match flagged")
                          : "flagged matches are at least " + std::to_string(closest_outlier_px) +
                                " px off the true epipolar lines"));
    CHECK(closest_outlier_px > 1.0);

    // OpenCV on the same matches, all judged by our metric on our inliers.
    const double ours = f.symmetric_epipolar_rms_px;
    const double cv_8point_inliers =
        SymmetricEpipolarRms(OpenCvFundamental(uv1, uv2, cv::FM_8POINT, f.inliers), uv1, uv2, f.inliers);
    const double cv_8point_all =
        SymmetricEpipolarRms(OpenCvFundamental(uv1, uv2, cv::FM_8POINT, {}), uv1, uv2, f.inliers);
    const double cv_ransac = SymmetricEpipolarRms(OpenCvFundamental(uv1, uv2, cv::FM_RANSAC, {}), uv1, uv2, f.inliers);
    const double cv_lmeds = SymmetricEpipolarRms(OpenCvFundamental(uv1, uv2, cv::FM_LMEDS, {}), uv1, uv2, f.inliers);
    MESSAGE(name1 << "-" << name2 << ": " << f.num_inliers << "/" << uv1.size() << " inliers, rotation error "
                  << rot_err_deg << " deg, translation direction error " << t_err_deg << " deg, points in front "
                  << pose.points_in_front << "/" << pose.num_points
                  << "; symmetric epipolar RMS (px, on our inliers): ours " << ours << " (8-point start "
                  << f.initial_symmetric_epipolar_rms_px << ", pose-constrained " << pose.symmetric_epipolar_rms_px
                  << "), OpenCV FM_8POINT on our inliers " << cv_8point_inliers << ", FM_8POINT on all 30 "
                  << cv_8point_all << ", FM_RANSAC " << cv_ransac << ", FM_LMEDS " << cv_lmeds << "; our time "
                  << f.time_ms + pose.time_ms << " ms");
    CHECK(f.num_inliers >= 25);
    CHECK(rot_err_deg < kMaxRotationErrorDeg);
    CHECK(t_err_deg < kMaxTranslationErrorDeg);
    CHECK(pose.points_in_front == pose.num_points);
    // Same metric, same matches: the refinement minimises it from the 8-point start.
    CHECK(ours <= cv_8point_inliers * (1 + 1e-9));
    CHECK(ours <= cv_8point_all * (1 + 1e-9));
    CHECK(ours <= cv_ransac * (1 + 1e-9));
    CHECK(ours <= cv_lmeds * (1 + 1e-9));
  }
}

}  // namespace
}  // namespace facet
