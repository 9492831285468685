// Timings of the joint solve (core/solve/joint_solve.h, issue 5 "Speed") on the scenes of
// tests/bench/joint_scene.h: the per-frame update while a pin is dragged (warm start, the
// app's iteration budget, no diagnostics), the full solve from a cold start, and the growth
// with the number of primitives. tests/bench/ceres_joint_solve.cpp times the same problems in
// Ceres Solver in the same run. Counters: final_cost (0.5 * sum of squared px residuals, the
// same definition as Ceres's) of a solve, its iterations, and the problem's size.
#include <benchmark/benchmark.h>

#include <cstdint>
#include <map>
#include <tuple>

#include "core/solve/joint_solve.h"
#include "tests/bench/joint_scene.h"

namespace {

using facet::JointSolveOptions;
using facet::JointSolveSummary;
using facet::Project;
using facet::testing::JointScene;
using facet::testing::JointSceneOptions;

JointSolveOptions FullSolveOptions(bool diagnostics) {
  JointSolveOptions o;
  o.max_iterations = facet::testing::kFullIterations;
  o.function_tolerance = facet::testing::kSolveTolerance;
  o.gradient_tolerance = facet::testing::kSolveTolerance;
  o.parameter_tolerance = facet::testing::kSolveTolerance;
  o.initial_lambda = facet::testing::kInitialLambda;
  o.compute_diagnostics = diagnostics;
  o.polish_constraints = false;
  return o;
}

JointSolveOptions FrameSolveOptions(JointSolveOptions::LinearSolver linear_solver) {
  JointSolveOptions o = FullSolveOptions(false);
  o.linear_solver = linear_solver;
  o.max_iterations = facet::testing::kFrameIterations;
  o.warm_start = true;
  return o;
}

void SetCounters(benchmark::State& state, const Project& project, const JointSolveSummary& summary) {
  state.counters["final_cost"] = summary.final_cost;
  state.counters["initial_cost"] = summary.initial_cost;
  state.counters["iterations"] = summary.iterations;
  state.counters["parameters"] = summary.num_parameters;
  state.counters["residuals"] = summary.num_residuals;
  state.counters["primitives"] = static_cast<double>(project.primitives.size());
  state.counters["images"] = static_cast<double>(project.images.size());
  state.counters["pins"] = static_cast<double>(project.pins.size());
}

// The converged solution of a scene, the drag's starting point; computed once per size
// because the benchmark library calls a benchmark function several times.
const Project* ConvergedScene(const JointSceneOptions& size, std::string* error) {
  static std::map<std::tuple<int, int, int>, Project> cache;
  const auto key = std::make_tuple(size.num_primitives, size.num_images, size.num_pins);
  auto it = cache.find(key);
  if (it != cache.end()) return &it->second;
  const JointScene scene = facet::testing::MakeJointScene(size);
  Project solved;
  const JointSolveSummary summary = facet::SolveJoint(scene.start, FullSolveOptions(false), &solved);
  if (summary.termination != facet::SolverTermination::kConverged) {
    *error = std::string("the full solve did not converge: ") + facet::SolverTerminationName(summary.termination) +
             ": " + summary.message;
    return nullptr;
  }
  return &cache.emplace(key, std::move(solved)).first->second;
}

// One frame of a drag: pin 0 moved by 2 px (back and forth), then the warm-started solve
// with the per-frame budget, exactly what the app runs while the mouse moves.
void RunInteractive(benchmark::State& state, const JointSceneOptions& size,
                    JointSolveOptions::LinearSolver linear_solver) {
  std::string error;
  const Project* converged = ConvergedScene(size, &error);
  if (converged == nullptr) {
    state.SkipWithError(error.c_str());
    return;
  }
  const JointSolveOptions options = FrameSolveOptions(linear_solver);
  // The counters come from one frame outside the timing, the pin moved by +2 px from the
  // converged state, so they do not depend on how many frames the library ran.
  Project current = *converged;
  current.pins[0].uv_px.x() += facet::testing::kDragStepPx;
  Project frame;
  const JointSolveSummary first = facet::SolveJoint(current, options, &frame);
  current = *converged;
  JointSolveSummary summary;
  int step = 0;
  for (auto _ : state) {
    current.pins[0].uv_px.x() += (step++ % 2 == 0) ? facet::testing::kDragStepPx : -facet::testing::kDragStepPx;
    Project next;
    summary = facet::SolveJoint(current, options, &next);
    if (!summary.IsUsable()) {
      state.SkipWithError(summary.message.c_str());
      return;
    }
    current = std::move(next);
  }
  SetCounters(state, frame, first);
}

JointSolveOptions::LinearSolver LinearSolverArg(std::int64_t arg) {
  return arg == 0 ? JointSolveOptions::LinearSolver::kSchur : JointSolveOptions::LinearSolver::kSparseLdlt;
}
const char* LinearSolverName(std::int64_t arg) { return arg == 0 ? "Schur" : "sparse LDLT"; }

// solver:0 is the default Schur complement on primitive groups, solver:1 the sparse LDL^T
// of the whole normal equations.
void BM_JointInteractive(benchmark::State& state) {
  RunInteractive(state,
                 facet::testing::JointSceneSize(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)),
                                                static_cast<int>(state.range(2))),
                 LinearSolverArg(state.range(3)));
  state.SetLabel(LinearSolverName(state.range(3)));
}
BENCHMARK(BM_JointInteractive)
    ->ArgNames({"primitives", "images", "pins", "solver"})
    ->ArgsProduct({{10}, {3}, {60}, {0, 1}})
    ->ArgsProduct({{100}, {10}, {1000}, {0, 1}})
    ->Unit(benchmark::kMillisecond);

// Full solve from the perturbed start (a few % off: sizes, translations, camera centres,
// 0.3 degree camera rotations) to convergence, the same start Ceres gets (warm_start stays
// true: the solver's own linear initialisation applies to 300 parameters at most).
// diagnostics:1 adds the rank analysis the app runs when a drag ends; the solver skips it
// above 600 parameters and says so in a warning (counter "warnings").
void BM_JointCold(benchmark::State& state) {
  const JointScene scene = facet::testing::MakeJointScene(facet::testing::JointSceneSize(
      static_cast<int>(state.range(0)), static_cast<int>(state.range(1)), static_cast<int>(state.range(2))));
  const JointSolveOptions options = FullSolveOptions(state.range(3) != 0);
  JointSolveSummary summary;
  Project solved;
  for (auto _ : state) {
    summary = facet::SolveJoint(scene.start, options, &solved);
    if (!summary.IsUsable()) {
      state.SkipWithError(summary.message.c_str());
      return;
    }
  }
  SetCounters(state, solved, summary);
  state.counters["converged"] = summary.termination == facet::SolverTermination::kConverged ? 1 : 0;
  state.counters["rms_px"] = summary.reprojection_rms_px;
  state.counters["warnings"] = static_cast<double>(summary.warnings.size());
}
BENCHMARK(BM_JointCold)
    ->ArgNames({"primitives", "images", "pins", "diagnostics"})
    ->Args({10, 3, 60, 0})
    ->Args({10, 3, 60, 1})
    ->Args({100, 10, 1000, 0})
    ->Args({100, 10, 1000, 1})
    ->Unit(benchmark::kMillisecond);

// Growth: the per-frame update for 1 to 1,000 primitives, 10 pins each, about one image per
// three primitives (2 to 10).
void BM_JointScaling(benchmark::State& state) {
  RunInteractive(state, facet::testing::ScalingSceneSize(static_cast<int>(state.range(0))),
                 JointSolveOptions::LinearSolver::kSchur);
}
BENCHMARK(BM_JointScaling)
    ->ArgName("primitives")
    ->Arg(1)
    ->Arg(3)
    ->Arg(10)
    ->Arg(30)
    ->Arg(100)
    ->Arg(300)
    ->Arg(1000)
    ->Unit(benchmark::kMillisecond);

}  // namespace
