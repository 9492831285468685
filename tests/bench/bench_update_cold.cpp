// The whole model update from a truly cold start (issue 5: "full solve from a cold start for
// the larger scene under 200 ms"): cameras know only their rotations and intrinsics (what
// vanishing-point calibration gives), every camera centre sits at the world origin and every
// box is a unit cube at the origin except the gauge box (primitive 0 keeps its translation and
// height). core/solve/model_update.h then runs the geometry solve's linear initialisation + LM and
// the joint solve, as after the first edit that makes a scene solvable. Counters: the final
// RMS (px) and the largest box-dimension error against the truth (m). The small scene has
// 12 pins per box (the joint-solve bench's 6 leave some boxes seen in one image only, which
// no cold start can size: only a warm start near the answer solves those).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "core/estimators/calibrate_vp.h"
#include "core/mesh/box.h"
#include "core/solve/model_update.h"
#include "tests/bench/joint_scene.h"

namespace {

facet::Project ColdStart(const facet::Project& truth) {
  facet::Project cold = truth;
  for (facet::Image& image : cold.images)
    image.camera.SetPose(image.camera.cam_from_world_rotation, Eigen::Vector3d::Zero());
  for (size_t i = 1; i < cold.primitives.size(); ++i) {
    facet::Primitive& p = cold.primitives[i];
    for (int k = 0; k < facet::kMaxPrimitiveParams; ++k)
      if (!p.param_locked[k] && p.shape.params[k] > 0.0) p.shape.params[k] = 1.0;
    if (!p.translation_locked) p.shape.translation.setZero();
  }
  facet::RefreshAllPrimitives(&cold);
  return cold;
}

void BM_UpdateModelCold(benchmark::State& state) {
  const facet::testing::JointScene scene = facet::testing::MakeJointScene(facet::testing::JointSceneSize(
      static_cast<int>(state.range(0)), static_cast<int>(state.range(1)), static_cast<int>(state.range(2))));
  const facet::Project cold = ColdStart(scene.truth);
  facet::ModelUpdateOptions options;
  options.calibrate = false;  // no line families in the scene: rotations are given
  options.solve.warm_start = false;
  options.joint.compute_diagnostics = false;
  facet::ModelUpdateSummary summary;
  facet::Project updated;
  for (auto _ : state) {
    summary = facet::UpdateModel(cold, options, &updated);
    if (!summary.ok) {
      state.SkipWithError(summary.messages.empty() ? "update failed" : summary.messages.front().c_str());
      return;
    }
  }
  double max_dimension_error_m = 0.0;
  for (size_t i = 0; i < std::min(updated.primitives.size(), scene.truth.primitives.size()); ++i)
    for (int k = 0; k < 3; ++k)
      max_dimension_error_m = std::max(max_dimension_error_m, std::abs(updated.primitives[i].shape.params[k] -
                                                                       scene.truth.primitives[i].shape.params[k]));
  state.counters["rms_px"] =
      summary.joint.IsUsable() ? summary.joint.reprojection_rms_px : summary.solve.reprojection_rms_px;
  state.counters["linear_init"] = summary.solve.linear_initialization_used ? 1 : 0;
  state.counters["geometry_ms"] = summary.solve.time_ms;
  state.counters["joint_ms"] = summary.joint.time_ms;
  state.counters["max_dim_err_m"] = max_dimension_error_m;
}
BENCHMARK(BM_UpdateModelCold)
    ->ArgNames({"primitives", "images", "pins"})
    ->Args({10, 3, 120})
    ->Args({100, 10, 1000})
    ->Unit(benchmark::kMillisecond);

// One drag frame of the app as a whole (DragFrameUpdateOptions, core/solve/model_update.h: calibration and
// the joint solve, warm on the 5-iteration budget, no diagnostics; the geometry solve only
// when the joint result does not hold),
// after the scene converged, with one pin moved by 2 px: what the user waits for per frame,
// not only the joint solve that bench_joint_solve times.
void BM_UpdateModelDragFrame(benchmark::State& state) {
  const facet::testing::JointScene scene = facet::testing::MakeJointScene(facet::testing::JointSceneSize(
      static_cast<int>(state.range(0)), static_cast<int>(state.range(1)), static_cast<int>(state.range(2))));
  facet::ModelUpdateOptions full;
  full.calibrate = false;
  full.joint.compute_diagnostics = false;
  facet::Project converged;
  const facet::ModelUpdateSummary first = facet::UpdateModel(scene.start, full, &converged);
  if (!first.ok) {
    state.SkipWithError("the scene did not converge");
    return;
  }
  facet::Project dragged = converged;
  dragged.pins[0].uv_px += Eigen::Vector2d(2.0, 0.0);
  const facet::ModelUpdateOptions frame = facet::DragFrameUpdateOptions();
  facet::ModelUpdateSummary summary;
  facet::Project updated;
  for (auto _ : state) {
    summary = facet::UpdateModel(dragged, frame, &updated);
    if (!summary.ok) {
      state.SkipWithError("update failed");
      return;
    }
  }
  state.counters["geometry_ms"] = summary.solve.time_ms;
  state.counters["joint_ms"] = summary.joint.time_ms;
  state.counters["rms_px"] = summary.joint.reprojection_rms_px;
}
BENCHMARK(BM_UpdateModelDragFrame)
    ->ArgNames({"primitives", "images", "pins"})
    ->Args({10, 3, 60})
    ->Args({100, 10, 1000})
    ->Unit(benchmark::kMillisecond);

// The drag frame with line families drawn, so that the calibration is part of the frame, and
// the app's calibration cache (ModelUpdateCache): each image gets `segments` segments (a third
// per axis) along box edges it sees, with the pins' 0.5 px noise (only the images the
// calibration orients like the truth: 2 of 3, 5 of 10; counter lined_images). The frames are chained as in
// the app: each frame's project is the previous frame's result with the dragged pin moved
// kDragStepPx (back and forth), so the cache only helps when the calibration inputs really
// are unchanged. Args: cache 0/1; distortion 0 = locked, 1 = unlocked (Image::distortion_locked
// false: k1, k2 of every camera free in the joint solve), 2 = unlocked and estimated from the
// lines (Image::estimate_distortion); 3 and 4 = 1 and 2 with the drag frames keeping every
// camera's intrinsics (JointSolveOptions::refine_intrinsics false; a released drag refines
// them), the proposed cure for the cost of unlocked distortion per frame. Counters per
// frame: calibration_ms, joint_ms (wall time: on a loaded machine read the CPU column), and
// how many images were calibrated or taken from the cache.
facet::Project WithSegments(const facet::Project& project, int segments_per_image, double noise_px, unsigned seed) {
  facet::Project out = project;
  std::mt19937 rng(seed);
  std::normal_distribution<double> gaussian(0.0, 1.0);
  const auto& edges = facet::BoxEdges();
  for (const facet::Image& image : project.images) {
    std::vector<facet::Segment> segments;
    for (int axis = 0; axis < 3; ++axis) {
      std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> seen;
      for (const facet::Primitive& box : project.primitives) {
        for (int e = 4 * axis; e < 4 * axis + 4; ++e) {
          const Eigen::Vector3d a = box.mesh.vertex(edges[e][0]).position;
          const Eigen::Vector3d b = box.mesh.vertex(edges[e][1]).position;
          if (facet::testing::joint_scene_detail::Visible(image.camera, a) &&
              facet::testing::joint_scene_detail::Visible(image.camera, b))
            seen.emplace_back(a, b);
        }
      }
      std::shuffle(seen.begin(), seen.end(), rng);
      const int wanted = segments_per_image / 3 + (axis < segments_per_image % 3 ? 1 : 0);
      for (int k = 0; k < std::min<int>(wanted, static_cast<int>(seen.size())); ++k) {
        facet::Segment segment;
        segment.id = out.NewId();
        segment.image_id = image.id;
        segment.axis = static_cast<facet::Axis>(axis);
        segment.a_px = image.camera.Project(seen[k].first) + noise_px * Eigen::Vector2d{gaussian(rng), gaussian(rng)};
        segment.b_px = image.camera.Project(seen[k].second) + noise_px * Eigen::Vector2d{gaussian(rng), gaussian(rng)};
        segments.push_back(segment);
      }
    }
    // The calibration orients x and y towards the vanishing points in front of the camera, so
    // a camera on the far side of the ring gets the world turned 180 degrees about z: its
    // lines would contradict the other images' frames. Only the images whose calibrated frame
    // is the truth's keep their lines.
    facet::VpCalibrationOptions options;
    options.width_px = image.width_px;
    options.height_px = image.height_px;
    const facet::VpCalibrationSummary vp = facet::CalibrateFromVanishingLines(segments, options);
    if (!vp.IsUsable() ||
        Eigen::AngleAxisd(vp.cam_from_world_rotation * image.camera.cam_from_world_rotation.transpose()).angle() >
            0.5 * M_PI)
      continue;
    out.segments.insert(out.segments.end(), segments.begin(), segments.end());
  }
  return out;
}

void BM_UpdateModelDragFrameLines(benchmark::State& state) {
  const int segments_per_image = static_cast<int>(state.range(3));
  const int distortion = static_cast<int>(state.range(4));
  const bool use_cache = state.range(5) != 0;
  const facet::testing::JointSceneOptions size = facet::testing::JointSceneSize(
      static_cast<int>(state.range(0)), static_cast<int>(state.range(1)), static_cast<int>(state.range(2)));
  const facet::testing::JointScene scene = facet::testing::MakeJointScene(size);
  // The segments come from the true cameras; the solve starts from the perturbed ones.
  facet::Project start = WithSegments(scene.truth, segments_per_image, size.noise_px, size.seed + 1);
  start.images = scene.start.images;
  start.primitives = scene.start.primitives;
  for (facet::Image& image : start.images) {
    image.distortion_locked = distortion == 0;
    image.estimate_distortion = distortion == 2 || distortion == 4;
  }
  facet::ModelUpdateOptions full;
  full.joint.compute_diagnostics = false;
  facet::Project converged;
  const facet::ModelUpdateSummary first = facet::UpdateModel(start, full, &converged);
  if (!first.ok) {
    state.SkipWithError(first.messages.empty() ? "the scene did not converge" : first.messages.front().c_str());
    return;
  }
  facet::ModelUpdateOptions frame = facet::DragFrameUpdateOptions(facet::testing::kFrameIterations);
  frame.joint.refine_intrinsics = distortion < 3;
  facet::ModelUpdateCache cache;
  facet::ModelUpdateSummary summary;
  facet::Project current = converged;
  double direction = 1.0;
  double calibration_ms = 0.0;
  double joint_ms = 0.0;
  int calibrated = 0;
  int reused = 0;
  for (auto _ : state) {
    facet::Project edited = current;  // as the app builds the next frame's project
    edited.pins[0].uv_px.x() += direction * facet::testing::kDragStepPx;
    direction = -direction;
    summary = facet::UpdateModel(edited, frame, &current, use_cache ? &cache : nullptr);
    if (!summary.ok) {
      state.SkipWithError(summary.messages.empty() ? "update failed" : summary.messages.front().c_str());
      return;
    }
    calibration_ms += summary.calibration_ms;
    joint_ms += summary.joint.time_ms;
    calibrated += summary.images_calibrated;
    reused += summary.images_reused;
  }
  const double frames = static_cast<double>(std::max<benchmark::IterationCount>(1, state.iterations()));
  state.counters["segments"] = static_cast<double>(start.segments.size());
  state.counters["lined_images"] = static_cast<double>(first.calibration.size());
  state.counters["calibration_ms"] = calibration_ms / frames;
  state.counters["joint_ms"] = joint_ms / frames;
  state.counters["calibrated"] = calibrated / frames;
  state.counters["reused"] = reused / frames;
  state.counters["rms_px"] = summary.joint.reprojection_rms_px;
}
BENCHMARK(BM_UpdateModelDragFrameLines)
    ->ArgNames({"primitives", "images", "pins", "segments", "distortion", "cache"})
    ->ArgsProduct({{10}, {3}, {60}, {30}, {0, 1, 2}, {0, 1}})
    ->ArgsProduct({{100}, {10}, {1000}, {30}, {0, 1, 2}, {0, 1}})
    ->ArgsProduct({{100}, {10}, {1000}, {30}, {3, 4}, {1}})
    ->ArgsProduct({{100}, {10}, {1000}, {0}, {0, 1, 3}, {0}})
    ->Unit(benchmark::kMillisecond);

}  // namespace
