// Self-calibration on the Middlebury temple (sparse ring): SIFT matches from OpenCV stand in
// for the user's clicks among 6 consecutive views (about 23 degrees apart); the focal length
// and relative rotations are compared with the dataset's calibration (templeSR_par.txt,
// P = K [R | t]). Issue 3's target: the focal length within 2 %. The data set itself limits
// what is reachable: a bundle adjustment started from the true cameras on the same kind of
// tracks settles 1.0 % (these 6 views) to 1.7 % (15 views of the ring) above the calibrated
// focal length, so this pinhole fit and the calibration differ by about that much. Adding
// the ring's neighbours does not help for that reason: 15,06..11 gives +2.4 % and
// 16,15,06..11 +3.0 % (reported sigma 1.0 %), so the 6 views of the issue are kept.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <numeric>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/self_calibration.h"
#include "core/two_view.h"

namespace facet {
namespace {

const std::string kDir = std::string(FACET_SHARED_DATA) + "/middlebury-temple-sparse-ring/";
// The accuracy target for the self-calibrated focal length.
constexpr double kFocalTolerance = 0.02;
// Lowe's ratio test, and the epipolar threshold that filters each pair's matches (px).
constexpr float kRatio = 0.75f;
constexpr double kPairThresholdPx = 1.5;

struct GroundTruth {
  Eigen::Matrix3d K, R;
  Eigen::Vector3d t;
};

std::map<std::string, GroundTruth> ReadGroundTruth() {
  std::map<std::string, GroundTruth> out;
  std::ifstream in(kDir + "templeSR_par.txt");
  int count = 0;
  in >> count;
  for (int i = 0; i < count; ++i) {
    std::string name;
    GroundTruth g;
    in >> name;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) in >> g.K(r, c);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) in >> g.R(r, c);
    in >> g.t(0) >> g.t(1) >> g.t(2);
    out[name] = g;
  }
  return out;
}

int Find(std::vector<int>& parent, int x) {
  while (parent[x] != x) x = parent[x] = parent[parent[x]];
  return x;
}

double RotationErrorDeg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a * b.transpose()).angle() * 180.0 / M_PI;
}

TEST_CASE("Middlebury temple: self-calibrated focal length from SIFT tracks in 6 views") {
  const std::vector<std::string> names = {"templeSR0006.png", "templeSR0007.png", "templeSR0008.png",
                                          "templeSR0009.png", "templeSR0010.png", "templeSR0011.png"};
  const int n = static_cast<int>(names.size());
  const auto truth = ReadGroundTruth();
  REQUIRE(truth.size() == 16);

  cv::Ptr<cv::SIFT> sift = cv::SIFT::create(4000);
  std::vector<std::vector<cv::KeyPoint>> keypoints(n);
  std::vector<cv::Mat> descriptors(n);
  std::vector<SelfCalibrationView> views(n);
  for (int v = 0; v < n; ++v) {
    const cv::Mat image = cv::imread(kDir + names[v], cv::IMREAD_GRAYSCALE);
    REQUIRE_MESSAGE(!image.empty(), names[v]);
    sift->detectAndCompute(image, cv::noArray(), keypoints[v], descriptors[v]);
    views[v] = {image.cols, image.rows, 0.0};
  }

  // Pairwise matches (neighbours and second neighbours on the ring), ratio test, then our
  // fundamental matrix with RANSAC drops the wrong ones; union-find joins them into tracks.
  std::vector<int> offset(n + 1, 0);
  for (int v = 0; v < n; ++v) offset[v + 1] = offset[v] + static_cast<int>(keypoints[v].size());
  std::vector<int> parent(offset[n]);
  std::iota(parent.begin(), parent.end(), 0);
  cv::BFMatcher matcher(cv::NORM_L2);
  int pair_matches = 0;
  for (int a = 0; a < n; ++a) {
    for (int b = a + 1; b < std::min(n, a + 3); ++b) {
      std::vector<std::vector<cv::DMatch>> knn;
      matcher.knnMatch(descriptors[a], descriptors[b], knn, 2);
      std::vector<Eigen::Vector2d> uv1, uv2;
      std::vector<cv::DMatch> good;
      for (const auto& m : knn) {
        if (m.size() < 2 || m[0].distance > kRatio * m[1].distance) continue;
        good.push_back(m[0]);
        const cv::Point2f p = keypoints[a][m[0].queryIdx].pt, q = keypoints[b][m[0].trainIdx].pt;
        uv1.emplace_back(p.x, p.y);
        uv2.emplace_back(q.x, q.y);
      }
      FundamentalOptions f_options;
      f_options.inlier_threshold_px = kPairThresholdPx;
      const FundamentalSummary f = EstimateFundamentalMatrix(uv1, uv2, f_options);
      MESSAGE("views " << a << "-" << b << ": " << good.size() << " ratio-test matches, " << f.num_inliers
                       << " epipolar inliers, RMS " << f.symmetric_epipolar_rms_px << " px");
      // Neighbours (23 degrees apart) must match well; second neighbours only add what they can.
      if (b == a + 1) {
        REQUIRE_MESSAGE(f.success, f.message);
        CHECK(f.num_inliers >= 30);
      }
      if (!f.success || f.num_inliers < 30) continue;
      for (size_t i = 0; i < good.size(); ++i) {
        if (!f.inliers[i]) continue;
        parent[Find(parent, offset[a] + good[i].queryIdx)] = Find(parent, offset[b] + good[i].trainIdx);
        ++pair_matches;
      }
    }
  }
  std::map<int, Track> by_root;
  for (int v = 0; v < n; ++v)
    for (int k = 0; k < static_cast<int>(keypoints[v].size()); ++k) {
      const int root = Find(parent, offset[v] + k);
      const cv::Point2f p = keypoints[v][k].pt;
      by_root[root].push_back({v, Eigen::Vector2d(p.x, p.y)});
    }
  std::vector<Track> tracks;
  for (auto& [root, track] : by_root) {
    if (track.size() < 2) continue;
    std::vector<int> seen(n, 0);
    bool consistent = true;
    for (const auto& o : track) consistent = consistent && seen[o.view]++ == 0;
    if (consistent) tracks.push_back(track);
  }
  size_t observations = 0;
  for (const auto& t : tracks) observations += t.size();
  MESSAGE(tracks.size() << " tracks with " << observations << " observations from " << pair_matches
                        << " pairwise matches");
  REQUIRE(tracks.size() >= 100);

  const double true_focal = 0.5 * (truth.at(names[0]).K(0, 0) + truth.at(names[0]).K(1, 1));
  // Both principal-point modes a user can pick: held at the image centre (17 px off the truth
  // here), or solved under the default weak prior at the centre (std 2.5 % of the image).
  for (PrincipalPointMode mode : {PrincipalPointMode::kImageCenter, PrincipalPointMode::kSolve}) {
    SelfCalibrationOptions options;
    options.principal_point_mode = mode;
    const SelfCalibrationSummary r = SelfCalibrate(views, tracks, options);
    REQUIRE_MESSAGE(r.success, r.message);
    for (const auto& w : r.warnings) MESSAGE("warning: " << w);
    const int ref = r.initial_view_a;
    const GroundTruth& g0 = truth.at(names[ref]);
    const double focal_error = r.cameras[ref].focal_px / true_focal - 1.0;
    double max_rotation_deg = 0.0;
    std::string rotations;
    int registered = 0;
    for (int v = 0; v < n; ++v) {
      if (!r.registered[v]) continue;
      ++registered;
      const Eigen::Matrix3d rel_true = truth.at(names[v]).R * g0.R.transpose();
      const Eigen::Matrix3d rel_est =
          r.cameras[v].cam_from_world_rotation * r.cameras[ref].cam_from_world_rotation.transpose();
      const double e = RotationErrorDeg(rel_true, rel_est);
      max_rotation_deg = std::max(max_rotation_deg, e);
      rotations += " " + std::to_string(v) + ":" + std::to_string(e);
    }
    const std::string mode_name = mode == PrincipalPointMode::kSolve ? "solved" : "at the centre";
    const double focal_std_px = r.focal_std_px[ref];
    MESSAGE("principal point " << mode_name << ": " << r.message << "; focal " << r.cameras[ref].focal_px
                               << " px +- " << focal_std_px << " (truth " << true_focal << "), linear "
                               << r.linear_focal_px[ref] << " px; principal point "
                               << r.cameras[ref].principal_point_px.transpose() << " (truth " << g0.K(0, 2) << " "
                               << g0.K(1, 2) << "); rotation errors to view " << ref << " (deg):" << rotations << "; "
                               << r.num_observations << " observations, " << r.time_ms << " ms");
    MESSAGE("focal error " << 100 * focal_error << " % (" << focal_error * true_focal / focal_std_px
                           << " reported sigma); issue target " << 100 * kFocalTolerance << " %");
    // Every view registers (templeSR0006 used to fail a plain DLT resection on 6 wrong tracks).
    CHECK(registered == n);
    // Measured: +1.71 % (centre) and +1.91 % (solved, prior), each +- 1.05 % reported.
    CHECK(std::abs(focal_error) < kFocalTolerance);
    // The reported uncertainty is honest: the error is within 3 of its sigmas.
    CHECK(std::abs(focal_error) * true_focal < 3.0 * focal_std_px);
    CHECK(max_rotation_deg < 1.5);
    CHECK(r.reprojection_rms_px < 1.0);
  }
}

}  // namespace
}  // namespace facet
