// The whole model update from a truly cold start (issue 5: "full solve from a cold start for
// the larger scene under 200 ms"): cameras know only their rotations and intrinsics (what
// vanishing-point calibration gives), every camera centre sits at the world origin and every
// box is a unit cube at the origin except the gauge box (primitive 0 keeps its translation and
// height). core/model_update.h then runs the geometry solve's linear initialisation + LM and
// the joint solve, as after the first edit that makes a scene solvable. Counters: the final
// RMS (px) and the largest box-dimension error against the truth (m). The small scene has
// 12 pins per box (the joint-solve bench's 6 leave some boxes seen in one image only, which
// no cold start can size: only a warm start near the answer solves those).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>

#include "core/model_update.h"
#include "tests/bench/joint_scene.h"

namespace {

facet::Project ColdStart(const facet::Project& truth) {
  facet::Project cold = truth;
  for (facet::Image& image : cold.images) image.camera.SetPose(image.camera.cam_from_world_rotation, Eigen::Vector3d::Zero());
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
  state.counters["rms_px"] = summary.joint.IsUsable() ? summary.joint.reprojection_rms_px : summary.solve.reprojection_rms_px;
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

// One drag frame of the app as a whole (app/app_state.cpp DragUpdateOptions: calibration and
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
  facet::ModelUpdateOptions frame;
  frame.solve.warm_start = true;
  frame.solve.max_iterations = 5;
  frame.joint.max_iterations = 5;
  frame.joint.compute_diagnostics = false;
  frame.joint.polish_constraints = false;
  frame.initialize_from_pins = false;
  frame.geometry_solve_when_warm = false;
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

}  // namespace
