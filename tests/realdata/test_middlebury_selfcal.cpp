// Self-calibration on the Middlebury temple (sparse ring): SIFT matches from OpenCV stand in
// for the user's clicks; the focal length and relative rotations are compared with the
// dataset's calibration (templeSR_par.txt, P = K [R | t]). Issue 3's target: the focal length
// within 2 %.
//
// Two cases. The 6 consecutive views (about 23 degrees apart), matched with their
// neighbours and second neighbours in file order. The full ring of 16 views, matched all
// pairs with all pairs (the files are not in ring order: the views at latitude +82 degrees
// are those at -82 seen from the opposite longitude, upside down), registered incrementally.
// The data set itself limits what is reachable: a bundle adjustment started from the true
// cameras on the same kind of tracks settles 1.0 % (the 6 views) to 1.7 % (15 views of the
// ring) above the calibrated focal length, so this pinhole fit and the calibration differ by
// about that much.
#include <doctest/doctest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <map>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/estimators/self_calibration.h"
#include "core/estimators/two_view.h"

namespace facet {
namespace {

const std::string kDir = std::string(FACET_SHARED_DATA) + "/middlebury-temple-sparse-ring/";
// The accuracy target for the self-calibrated focal length.
constexpr double kFocalTolerance = 0.02;
// Lowe's ratio test, and the epipolar threshold that filters each pair's matches (px).
constexpr float kRatio = 0.75f;
constexpr int kSiftFeatures = 4000;
constexpr double kPairThresholdPx = 1.5;
// A pair contributes its matches when at least this many are epipolar inliers.
constexpr int kMinPairInliers = 30;

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

struct Matched {
  std::vector<SelfCalibrationView> views;
  std::vector<Track> tracks;
};

// SIFT in every image; for each listed pair, the ratio test, then our fundamental matrix with
// RANSAC drops the wrong matches; union-find joins the pairs' inliers into tracks, and tracks
// that reach one view twice are dropped. `required` pairs must match well.
Matched MatchViews(const std::vector<std::string>& names, const std::vector<std::pair<int, int>>& pairs,
                   const std::vector<std::pair<int, int>>& required) {
  const int n = static_cast<int>(names.size());
  Matched out;
  cv::Ptr<cv::SIFT> sift = cv::SIFT::create(kSiftFeatures);
  std::vector<std::vector<cv::KeyPoint>> keypoints(n);
  std::vector<cv::Mat> descriptors(n);
  out.views.resize(n);
  for (int v = 0; v < n; ++v) {
    const cv::Mat image = cv::imread(kDir + names[v], cv::IMREAD_GRAYSCALE);
    REQUIRE_MESSAGE(!image.empty(), names[v]);
    sift->detectAndCompute(image, cv::noArray(), keypoints[v], descriptors[v]);
    out.views[v] = {image.cols, image.rows, 0.0};
  }
  std::vector<int> offset(n + 1, 0);
  for (int v = 0; v < n; ++v) offset[v + 1] = offset[v] + static_cast<int>(keypoints[v].size());
  std::vector<int> parent(offset[n]);
  std::iota(parent.begin(), parent.end(), 0);
  cv::BFMatcher matcher(cv::NORM_L2);
  int pair_matches = 0, pairs_used = 0;
  for (const auto& [a, b] : pairs) {
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
    const bool usable = f.IsUsable() && f.num_inliers >= kMinPairInliers;
    if (usable || std::find(required.begin(), required.end(), std::make_pair(a, b)) != required.end())
      MESSAGE("views " << a << "-" << b << ": " << good.size() << " ratio-test matches, " << f.num_inliers
                       << " epipolar inliers, RMS " << f.symmetric_epipolar_rms_px << " px");
    if (std::find(required.begin(), required.end(), std::make_pair(a, b)) != required.end()) {
      REQUIRE_MESSAGE(f.IsUsable(), f.message);
      CHECK(f.num_inliers >= kMinPairInliers);
    }
    if (!usable) continue;
    ++pairs_used;
    for (size_t i = 0; i < good.size(); ++i) {
      if (!f.inliers[i]) continue;
      parent[Find(parent, offset[a] + good[i].queryIdx)] = Find(parent, offset[b] + good[i].trainIdx);
      ++pair_matches;
    }
  }
  std::map<int, Track> by_root;
  for (int v = 0; v < n; ++v)
    for (int k = 0; k < static_cast<int>(keypoints[v].size()); ++k) {
      const int root = Find(parent, offset[v] + k);
      const cv::Point2f p = keypoints[v][k].pt;
      by_root[root].push_back({v, Eigen::Vector2d(p.x, p.y)});
    }
  for (auto& [root, track] : by_root) {
    if (track.size() < 2) continue;
    std::vector<int> seen(n, 0);
    bool consistent = true;
    for (const auto& o : track) consistent = consistent && seen[o.view]++ == 0;
    if (consistent) out.tracks.push_back(track);
  }
  size_t observations = 0;
  for (const auto& t : out.tracks) observations += t.size();
  MESSAGE(out.tracks.size() << " tracks with " << observations << " observations from " << pair_matches
                            << " pairwise matches of " << pairs_used << " pairs");
  return out;
}

struct Figures {
  int registered = 0;
  double focal_error = 0.0;  // relative, of the reference view
  double focal_std_rel = 0.0;
  double max_rotation_deg = 0.0;  // relative rotations to the reference view
};

// Compares a result with the ground truth and prints it.
Figures Evaluate(const std::vector<std::string>& names, const SelfCalibrationSummary& r, const std::string& label) {
  const auto truth = ReadGroundTruth();
  REQUIRE(truth.size() == 16);
  Figures fig;
  const int ref = r.initial_view_a;
  const GroundTruth& g0 = truth.at(names[ref]);
  const double true_focal = 0.5 * (g0.K(0, 0) + g0.K(1, 1));
  fig.focal_error = r.cameras[ref].focal_px / true_focal - 1.0;
  fig.focal_std_rel = r.focal_std_px[ref] / true_focal;
  std::string rotations, missing;
  for (size_t v = 0; v < names.size(); ++v) {
    if (!r.registered[v]) {
      missing += " " + names[v];
      continue;
    }
    ++fig.registered;
    const Eigen::Matrix3d rel_true = truth.at(names[v]).R * g0.R.transpose();
    const Eigen::Matrix3d rel_est =
        r.cameras[v].cam_from_world_rotation * r.cameras[ref].cam_from_world_rotation.transpose();
    const double e = RotationErrorDeg(rel_true, rel_est);
    fig.max_rotation_deg = std::max(fig.max_rotation_deg, e);
    rotations += " " + std::to_string(v) + ":" + std::to_string(e);
  }
  for (const auto& w : r.warnings) MESSAGE("warning: " << w);
  MESSAGE(label << ": " << r.message << "; " << fig.registered << " of " << names.size() << " views registered"
                << (missing.empty() ? "" : " (not:" + missing + ")") << "; focal " << r.cameras[ref].focal_px
                << " px +- " << r.focal_std_px[ref] << " (truth " << true_focal << "), linear "
                << r.linear_focal_px[ref] << " px; principal point " << r.cameras[ref].principal_point_px.transpose()
                << " (truth " << g0.K(0, 2) << " " << g0.K(1, 2) << "); rotation errors to view " << ref
                << " (deg):" << rotations << "; " << r.num_observations << " observations, " << r.time_ms << " ms");
  MESSAGE("focal error " << 100 * fig.focal_error << " % (" << fig.focal_error / fig.focal_std_rel
                         << " reported sigma); issue target " << 100 * kFocalTolerance << " %");
  return fig;
}

TEST_CASE("Middlebury temple: self-calibrated focal length from SIFT tracks in 6 views") {
  const std::vector<std::string> names = {"templeSR0006.png", "templeSR0007.png", "templeSR0008.png",
                                          "templeSR0009.png", "templeSR0010.png", "templeSR0011.png"};
  const int n = static_cast<int>(names.size());
  // Neighbours (23 degrees apart) must match well; second neighbours only add what they can.
  std::vector<std::pair<int, int>> pairs, neighbours;
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < std::min(n, a + 3); ++b) {
      pairs.emplace_back(a, b);
      if (b == a + 1) neighbours.emplace_back(a, b);
    }
  const Matched m = MatchViews(names, pairs, neighbours);
  REQUIRE(m.tracks.size() >= 100);

  // Both principal-point modes a user can pick: held at the image centre (17 px off the truth
  // here), or solved under the default weak prior at the centre (std 2.5 % of the image).
  for (PrincipalPointMode mode : {PrincipalPointMode::kImageCenter, PrincipalPointMode::kSolve}) {
    SelfCalibrationOptions options;
    options.principal_point_mode = mode;
    const SelfCalibrationSummary r = SelfCalibrate(m.views, m.tracks, options);
    REQUIRE_MESSAGE(r.IsUsable(), r.message);
    const Figures fig = Evaluate(
        names, r, mode == PrincipalPointMode::kSolve ? "principal point solved" : "principal point at the centre");
    // Every view registers (templeSR0006 used to fail a plain DLT resection on 6 wrong tracks).
    CHECK(fig.registered == n);
    // Measured: +1.63 % (centre) and +1.76 % (solved, prior), each +- 1.06 % reported (before
    // the projective adjustments during the registration: +1.71 % and +1.91 %).
    CHECK(std::abs(fig.focal_error) < kFocalTolerance);
    // The reported uncertainty is honest: the error is within 3 of its sigmas.
    CHECK(std::abs(fig.focal_error) < 3.0 * fig.focal_std_rel);
    CHECK(fig.max_rotation_deg < 1.5);
    CHECK(r.reprojection_rms_px < 1.0);
  }
}

TEST_CASE("Middlebury temple: the full ring of 16 views registers incrementally and self-calibrates") {
  // Measured (SIFT 4000, all 120 pairs matched, 22 kept): 13 of 16 views register, focal
  // +1.68 % (centre) and +1.62 % (solved) against the calibration, reported sigma 0.54 %;
  // rotation errors to the reference view up to 2.8 degrees; about 4 s per solve (the
  // matching takes 10 to 25 s more). templeSR0003, 0004 and 0014 stay out: the junctions of their
  // part of the ring with the rest (0002-0014 do not match at all, 0005-0013 share 80 matches
  // but only 3 of them reach a third view) carry too few three-view tracks for a projective
  // resection; they are named in the warnings. The start from the pair sharing the most
  // tracks (0003-0014) registers only that part (4 views); the attempt from the other part is
  // kept. The pair sharing the most tracks of all (0001-0011, taken from one place) is
  // skipped as a homography. The 2 % is met on the 13 views. Unlike the 6 views, the
  // error is not checked against the reported sigma: on 13 views the sigma is smaller than
  // the 1.7 % by which this pinhole fit and the data set's calibration differ (see the top).
  constexpr int kMinRegistered = 13;
  constexpr double kMaxRotationDeg = 4.0;
  std::vector<std::string> names;
  for (int i = 1; i <= 16; ++i)
    names.push_back("templeSR" + std::string(i < 10 ? "000" : "00") + std::to_string(i) + ".png");
  const int n = static_cast<int>(names.size());
  std::vector<std::pair<int, int>> pairs;
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b) pairs.emplace_back(a, b);
  const auto match_start = std::chrono::steady_clock::now();
  const Matched m = MatchViews(names, pairs, {});
  MESSAGE("matching: " << std::chrono::duration<double>(std::chrono::steady_clock::now() - match_start).count()
                       << " s");
  REQUIRE(m.tracks.size() >= 100);
  for (PrincipalPointMode mode : {PrincipalPointMode::kImageCenter, PrincipalPointMode::kSolve}) {
    SelfCalibrationOptions options;
    options.principal_point_mode = mode;
    const SelfCalibrationSummary r = SelfCalibrate(m.views, m.tracks, options);
    REQUIRE_MESSAGE(r.IsUsable(), r.message);
    const Figures fig = Evaluate(
        names, r, mode == PrincipalPointMode::kSolve ? "principal point solved" : "principal point at the centre");
    CHECK(fig.registered >= kMinRegistered);
    // No silent drop: every view left out is named in a warning.
    for (int v = 0; v < n; ++v) {
      if (r.registered[v]) continue;
      const std::string prefix = "view " + std::to_string(v) + " is not registered";
      CHECK_MESSAGE(std::any_of(r.warnings.begin(), r.warnings.end(),
                                [&](const std::string& w) { return w.rfind(prefix, 0) == 0; }),
                    prefix);
    }
    CHECK(std::abs(fig.focal_error) < kFocalTolerance);
    CHECK(fig.max_rotation_deg < kMaxRotationDeg);
    CHECK(r.reprojection_rms_px < 1.0);
  }
}

}  // namespace
}  // namespace facet
