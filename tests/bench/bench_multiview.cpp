// Multi-view routines: the stratified two-view upgrade (projective from F, affine from three
// vanishing points, metric from K) and self-calibration of several views with the bundle
// adjustment. OpenCV has no equivalent of either; the figures are absolute.
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>

#include "core/estimators/projective_upgrade.h"
#include "core/estimators/self_calibration.h"
#include "core/estimators/two_view.h"
#include "tests/synthetic_scene.h"

namespace {

using facet::testing::MakeLookAtCamera;
using facet::testing::SyntheticSceneOptions;

std::vector<facet::Camera> RingCameras(int count) {
  std::vector<facet::Camera> cameras;
  for (int v = 0; v < count; ++v) {
    SyntheticSceneOptions o;
    const double angle = -1.2 + 2.6 * v / std::max(1, count - 1);
    o.camera_center = {2.0 + 10.0 * std::cos(angle), 1.5 + 10.0 * std::sin(angle), 4.0 + 2.0 * (v % 3)};
    o.look_at = {2.0, 1.5, 1.2};
    o.roll_deg = 5.0 * std::sin(1.7 * v);
    cameras.push_back(MakeLookAtCamera(o));
  }
  return cameras;
}

// `num_points` random points in the box, seen by every camera, 0.5 px noise.
void MakeTracks(const std::vector<facet::Camera>& cameras, int num_points, std::vector<facet::Track>* tracks) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> ux(-1.0, 5.0), uy(-1.0, 4.0), uz(0.0, 3.0);
  std::normal_distribution<double> noise(0.0, 0.5);
  for (int i = 0; i < num_points; ++i) {
    const Eigen::Vector3d x{ux(rng), uy(rng), uz(rng)};
    facet::Track track;
    for (int v = 0; v < static_cast<int>(cameras.size()); ++v)
      track.push_back({v, cameras[v].Project(x) + Eigen::Vector2d{noise(rng), noise(rng)}});
    tracks->push_back(track);
  }
}

void BM_SelfCalibrate(benchmark::State& state) {
  const std::vector<facet::Camera> cameras = RingCameras(static_cast<int>(state.range(0)));
  std::vector<facet::Track> tracks;
  MakeTracks(cameras, static_cast<int>(state.range(1)), &tracks);
  std::vector<facet::SelfCalibrationView> views;
  for (const auto& c : cameras) views.push_back({c.width_px, c.height_px, 0.0});
  for (auto _ : state) benchmark::DoNotOptimize(facet::SelfCalibrate(views, tracks, facet::SelfCalibrationOptions()));
}
BENCHMARK(BM_SelfCalibrate)->Args({4, 100})->Args({8, 300})->Args({16, 300})->Unit(benchmark::kMillisecond);

void BM_StratifiedTwoViewUpgrade(benchmark::State& state) {
  const std::vector<facet::Camera> cameras = RingCameras(4);
  const facet::Camera& c1 = cameras[0];
  const facet::Camera& c2 = cameras[2];
  std::vector<facet::Track> tracks;
  MakeTracks({c1, c2}, 100, &tracks);
  std::vector<Eigen::Vector2d> uv1, uv2;
  for (const auto& t : tracks) {
    uv1.push_back(t[0].uv_px);
    uv2.push_back(t[1].uv_px);
  }
  std::vector<std::vector<Eigen::Vector3d>> vanishing;
  for (int axis = 0; axis < 3; ++axis)
    vanishing.push_back({c1.K() * c1.cam_from_world_rotation * Eigen::Vector3d::Unit(axis),
                         c2.K() * c2.cam_from_world_rotation * Eigen::Vector3d::Unit(axis)});
  const facet::FundamentalSummary f = facet::EstimateFundamentalMatrix(uv1, uv2, facet::FundamentalOptions());
  for (auto _ : state) {
    const auto proj = facet::ReconstructProjective(f.F, uv1, uv2, {});
    const auto affine = facet::UpgradeToAffine({proj.P1, proj.P2}, vanishing, {});
    const auto points = facet::TransformPoints(affine.affine_from_projective, proj.points);
    benchmark::DoNotOptimize(facet::UpgradeToMetric(affine.cameras, {c1.K(), c2.K()}, points, {}));
  }
}
BENCHMARK(BM_StratifiedTwoViewUpgrade)->Unit(benchmark::kMicrosecond);

}  // namespace
