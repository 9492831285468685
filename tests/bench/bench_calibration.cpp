// Calibration routines against OpenCV's equivalents in the same run: the fundamental matrix
// (8-point and refined vs cv::findFundamentalMat) and calibration from known 3D points (DLT
// with refinement vs cv::calibrateCamera on one view, and the linear step's decomposition vs
// cv::decomposeProjectionMatrix), and single-image calibration from three vanishing points
// (50 segments; the issue asks for well under a millisecond).
#include <benchmark/benchmark.h>

#include <random>

#include <opencv2/calib3d.hpp>

#include "core/estimators/calibrate_dlt.h"
#include "core/estimators/calibrate_vp.h"
#include "core/estimators/two_view.h"
#include "tests/synthetic_scene.h"

namespace {

using facet::testing::MakeLookAtCamera;
using facet::testing::SyntheticSceneOptions;

struct TwoViewScene {
  std::vector<Eigen::Vector2d> uv1, uv2;
  std::vector<cv::Point2d> cv1, cv2;
};

// `count` random points in a 6 m cube seen by two cameras, with 0.5 px noise.
TwoViewScene MakeTwoViewScene(int count) {
  SyntheticSceneOptions o1, o2;
  o2.camera_center = {4.0, -11.0, 4.5};
  const facet::Camera c1 = MakeLookAtCamera(o1), c2 = MakeLookAtCamera(o2);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coord(-1.0, 5.0);
  std::normal_distribution<double> noise(0.0, 0.5);
  TwoViewScene s;
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector3d x{coord(rng), coord(rng), coord(rng) * 0.6};
    const Eigen::Vector2d a = c1.Project(x) + Eigen::Vector2d{noise(rng), noise(rng)};
    const Eigen::Vector2d b = c2.Project(x) + Eigen::Vector2d{noise(rng), noise(rng)};
    s.uv1.push_back(a);
    s.uv2.push_back(b);
    s.cv1.emplace_back(a.x(), a.y());
    s.cv2.emplace_back(b.x(), b.y());
  }
  return s;
}

void BM_FundamentalEightPointAndRefine(benchmark::State& state) {
  const TwoViewScene s = MakeTwoViewScene(static_cast<int>(state.range(0)));
  facet::FundamentalOptions options;
  options.use_ransac = false;
  facet::FundamentalSummary summary;
  for (auto _ : state) benchmark::DoNotOptimize(summary = facet::EstimateFundamentalMatrix(s.uv1, s.uv2, options));
  state.counters["refine_iterations"] = summary.iterations;
  state.counters["ransac_iterations"] = summary.ransac_iterations;
}
BENCHMARK(BM_FundamentalEightPointAndRefine)->Arg(30)->Arg(200)->Unit(benchmark::kMicrosecond);

void BM_FundamentalRansacAndRefine(benchmark::State& state) {
  const TwoViewScene s = MakeTwoViewScene(static_cast<int>(state.range(0)));
  facet::FundamentalOptions options;
  facet::FundamentalSummary summary;
  for (auto _ : state) benchmark::DoNotOptimize(summary = facet::EstimateFundamentalMatrix(s.uv1, s.uv2, options));
  state.counters["refine_iterations"] = summary.iterations;
  state.counters["ransac_iterations"] = summary.ransac_iterations;
}
BENCHMARK(BM_FundamentalRansacAndRefine)->Arg(30)->Arg(200)->Unit(benchmark::kMicrosecond);

void BM_OpenCvFindFundamentalMat8Point(benchmark::State& state) {
  const TwoViewScene s = MakeTwoViewScene(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(cv::findFundamentalMat(s.cv1, s.cv2, cv::FM_8POINT));
}
BENCHMARK(BM_OpenCvFindFundamentalMat8Point)->Arg(30)->Arg(200)->Unit(benchmark::kMicrosecond);

void BM_OpenCvFindFundamentalMatRansac(benchmark::State& state) {
  const TwoViewScene s = MakeTwoViewScene(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(cv::findFundamentalMat(s.cv1, s.cv2, cv::FM_RANSAC, 3.0, 0.9999));
}
BENCHMARK(BM_OpenCvFindFundamentalMatRansac)->Arg(30)->Arg(200)->Unit(benchmark::kMicrosecond);

struct PointsScene {
  std::vector<facet::PointCorrespondence> points;
  std::vector<cv::Point3f> object;
  std::vector<cv::Point2f> image;
  facet::Camera camera;
};

// `count` random non-coplanar points in front of the default synthetic camera, 0.5 px noise.
PointsScene MakePointsScene(int count) {
  PointsScene s;
  s.camera = MakeLookAtCamera(SyntheticSceneOptions{});
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> coord(-1.0, 5.0);
  std::normal_distribution<double> noise(0.0, 0.5);
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector3d x{coord(rng), coord(rng), coord(rng) * 0.6};
    const Eigen::Vector2d uv = s.camera.Project(x) + Eigen::Vector2d{noise(rng), noise(rng)};
    s.points.push_back({x, uv});
    s.object.emplace_back(static_cast<float>(x.x()), static_cast<float>(x.y()), static_cast<float>(x.z()));
    s.image.emplace_back(static_cast<float>(uv.x()), static_cast<float>(uv.y()));
  }
  return s;
}

void BM_CalibrateFromPoints(benchmark::State& state) {
  const PointsScene s = MakePointsScene(40);
  facet::DltCalibrationOptions options;
  options.width_px = s.camera.width_px;
  options.height_px = s.camera.height_px;
  for (auto _ : state) benchmark::DoNotOptimize(facet::CalibrateFromPoints(s.points, options));
}
BENCHMARK(BM_CalibrateFromPoints)->Unit(benchmark::kMicrosecond);

// OpenCV needs an initial K for non-planar points; it gets the true one, and the same free
// parameters as ours (one focal length, principal point, no distortion).
void BM_OpenCvCalibrateCameraOneView(benchmark::State& state) {
  const PointsScene s = MakePointsScene(40);
  const Eigen::Matrix3d k = s.camera.K();
  const std::vector<std::vector<cv::Point3f>> object = {s.object};
  const std::vector<std::vector<cv::Point2f>> image = {s.image};
  const int flags = cv::CALIB_USE_INTRINSIC_GUESS | cv::CALIB_FIX_ASPECT_RATIO | cv::CALIB_ZERO_TANGENT_DIST |
                    cv::CALIB_FIX_K1 | cv::CALIB_FIX_K2 | cv::CALIB_FIX_K3;
  for (auto _ : state) {
    cv::Matx33d camera(k(0, 0), 0, k(0, 2), 0, k(1, 1), k(1, 2), 0, 0, 1);
    cv::Mat dist = cv::Mat::zeros(5, 1, CV_64F);
    std::vector<cv::Mat> rvecs, tvecs;
    benchmark::DoNotOptimize(cv::calibrateCamera(object, image, cv::Size(s.camera.width_px, s.camera.height_px), camera,
                                                 dist, rvecs, tvecs, flags));
  }
}
BENCHMARK(BM_OpenCvCalibrateCameraOneView)->Unit(benchmark::kMicrosecond);

void BM_DltLinearOnly(benchmark::State& state) {
  const PointsScene s = MakePointsScene(40);
  facet::DltCalibrationOptions options;
  options.width_px = s.camera.width_px;
  options.height_px = s.camera.height_px;
  options.refine = false;
  for (auto _ : state) benchmark::DoNotOptimize(facet::CalibrateFromPoints(s.points, options));
}
BENCHMARK(BM_DltLinearOnly)->Unit(benchmark::kMicrosecond);

// The decomposition alone, on a known projection matrix (our linear step includes the DLT
// solve and the RQ decomposition, so this is a lower bound for comparison).
void BM_OpenCvDecomposeProjectionMatrix(benchmark::State& state) {
  const PointsScene s = MakePointsScene(40);
  const Eigen::Matrix<double, 3, 4> p = s.camera.ProjectionMatrix();
  cv::Mat projection(3, 4, CV_64F);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) projection.at<double>(r, c) = p(r, c);
  for (auto _ : state) {
    cv::Mat k, r, t;
    cv::decomposeProjectionMatrix(projection, k, r, t);
    benchmark::DoNotOptimize(k.data);
  }
}
BENCHMARK(BM_OpenCvDecomposeProjectionMatrix)->Unit(benchmark::kMicrosecond);

// 50 segments of the synthetic box (17, 17 and 16 per family) with 0.5 px noise.
std::vector<facet::Segment> FiftySegments(facet::VpCalibrationOptions* options) {
  SyntheticSceneOptions o;
  o.noise_px = 0.5;
  o.extra_lines_per_axis = 13;
  const auto scene = facet::testing::MakeBoxScene(o);
  std::vector<facet::Segment> segments = scene.project.segments;
  segments.resize(50);
  options->width_px = o.width_px;
  options->height_px = o.height_px;
  return segments;
}

// Arg 0: defaults (outliers flagged, refit when any); 1: no refit; 2: warm-started from the
// previous result, as while a segment is dragged.
void BM_CalibrateVanishingPoints50(benchmark::State& state) {
  facet::VpCalibrationOptions options;
  const std::vector<facet::Segment> segments = FiftySegments(&options);
  options.refit_without_outliers = state.range(0) != 1;
  if (state.range(0) == 2) {
    const facet::VpCalibrationSummary previous = facet::CalibrateFromVanishingLines(segments, options);
    options.warm_start = true;
    options.warm_start_focal_px = previous.focal_px;
    options.warm_start_principal_point_px = previous.principal_point_px;
    options.warm_start_rotation = previous.cam_from_world_rotation;
  }
  for (auto _ : state) benchmark::DoNotOptimize(facet::CalibrateFromVanishingLines(segments, options));
}
BENCHMARK(BM_CalibrateVanishingPoints50)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond);

}  // namespace
