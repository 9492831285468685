// The joint solve's problem built in Ceres Solver, timed in the same run as ours
// (tests/bench/bench_joint_solve.cpp) on the same scenes, budgets and tolerances (issue 5:
// no slower than Ceres on the interactive problem, the same final cost).
//
// Same parameters as core/solve/joint_solve.h for these scenes: per camera a small rotation applied
// on the left of the start rotation (angle-axis, 3) and the centre (3), intrinsics fixed; per
// box its three dimensions and translation (6, rotation fixed), the locked entries held by a
// SubsetManifold. Same residual: projection of the pinned vertex minus the pin, in px, so
// final_cost (0.5 * sum of squares) compares directly with ours. Derivatives by
// AutoDiffCostFunction. Linear solvers: SPARSE_SCHUR (boxes eliminated first),
// SPARSE_NORMAL_CHOLESKY (SuiteSparse), DENSE_SCHUR; the README quotes the fastest.
// Built only with -DFACET_BENCH_CERES=ON (FACET_HAVE_CERES).
#if defined(FACET_HAVE_CERES)

#include <benchmark/benchmark.h>
#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <cmath>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include "core/solve/joint_solve.h"
#include "tests/bench/joint_scene.h"

namespace {

using facet::Project;
using facet::testing::JointScene;
using facet::testing::JointSceneOptions;

struct CeresPin {
  int primitive = 0;
  int camera = 0;
  Eigen::Matrix3d coefficients = Eigen::Matrix3d::Zero();  // local = coefficients * dims + constant
  Eigen::Vector3d constant = Eigen::Vector3d::Zero();
  Eigen::Vector2d uv_px = Eigen::Vector2d::Zero();
};

// Parameter storage; the cost functors point into it, so it is not resized once built.
struct CeresModel {
  std::vector<std::array<double, 6>> primitives;  // sx, sy, sz, tx, ty, tz
  std::vector<Eigen::Matrix3d> world_from_primitive;
  std::vector<std::vector<int>> primitive_locked;  // indices into the 6 entries
  std::vector<std::array<double, 6>> cameras;      // small rotation (angle-axis), centre in world
  std::vector<Eigen::Matrix3d> cam_from_world_start;
  std::vector<double> focal_px;
  std::vector<Eigen::Vector2d> principal_point_px;
  std::vector<bool> camera_locked;
  std::vector<CeresPin> pins;
};

bool ModelFromProject(const Project& project, CeresModel* m, std::string* error) {
  std::map<facet::Id, int> primitive_index;
  std::map<facet::Id, int> camera_index;
  for (const facet::Primitive& p : project.primitives) {
    if (p.shape.kind != facet::PrimitiveKind::kBox || !p.rotation_locked || p.attached_to != facet::kNoId) {
      *error = "the Ceres comparison handles free-standing boxes with locked rotations only";
      return false;
    }
    primitive_index[p.id] = static_cast<int>(m->primitives.size());
    m->primitives.push_back({p.shape.params[0], p.shape.params[1], p.shape.params[2], p.shape.translation.x(),
                             p.shape.translation.y(), p.shape.translation.z()});
    m->world_from_primitive.push_back(facet::RotationFromAngleAxis(p.shape.rotation));
    std::vector<int> locked;
    for (int k = 0; k < 3; ++k) {
      if (p.param_locked[k]) locked.push_back(k);
    }
    if (p.translation_locked) locked.insert(locked.end(), {3, 4, 5});
    m->primitive_locked.push_back(locked);
  }
  for (const facet::Image& image : project.images) {
    if (!image.focal_locked || !image.principal_point_locked) {
      *error = "the Ceres comparison keeps the intrinsics fixed";
      return false;
    }
    camera_index[image.id] = static_cast<int>(m->cameras.size());
    const Eigen::Vector3d c = image.camera.CenterInWorld();
    m->cameras.push_back({0.0, 0.0, 0.0, c.x(), c.y(), c.z()});
    m->cam_from_world_start.push_back(image.camera.cam_from_world_rotation);
    m->focal_px.push_back(image.camera.focal_px);
    m->principal_point_px.push_back(image.camera.principal_point_px);
    m->camera_locked.push_back(image.pose_locked);
  }
  for (const facet::Pin& pin : project.pins) {
    const facet::Primitive* p = project.FindPrimitive(pin.vertex.primitive_id);
    const facet::MeshVertex* v = project.FindVertex(pin.vertex);
    if (p == nullptr || v == nullptr || camera_index.count(pin.image_id) == 0) {
      *error = "a pin refers to a missing vertex or image";
      return false;
    }
    CeresPin c;
    c.primitive = primitive_index[p->id];
    c.camera = camera_index[pin.image_id];
    const facet::ParamCoefficients coefficients = v->local.Collapsed();
    c.coefficients = coefficients.leftCols<3>();
    c.constant = coefficients.col(3) * p->shape.params[3] + v->local.offset;
    c.uv_px = pin.uv_px;
    m->pins.push_back(c);
  }
  return true;
}

struct PinCost {
  const CeresPin* pin;
  const Eigen::Matrix3d* world_from_primitive;
  const Eigen::Matrix3d* cam_from_world_start;
  double focal_px;
  Eigen::Vector2d principal_point_px;

  template <typename T>
  bool operator()(const T* primitive, const T* camera, T* residual) const {
    const Eigen::Matrix3d& c = pin->coefficients;
    const Eigen::Matrix3d& r = *world_from_primitive;
    const Eigen::Matrix3d& r0 = *cam_from_world_start;
    T local[3];
    for (int i = 0; i < 3; ++i) {
      local[i] = T(pin->constant(i)) + c(i, 0) * primitive[0] + c(i, 1) * primitive[1] + c(i, 2) * primitive[2];
    }
    T from_center[3];
    for (int i = 0; i < 3; ++i) {
      from_center[i] = primitive[3 + i] + r(i, 0) * local[0] + r(i, 1) * local[1] + r(i, 2) * local[2] - camera[3 + i];
    }
    T rotated_start[3];
    for (int i = 0; i < 3; ++i) {
      rotated_start[i] = r0(i, 0) * from_center[0] + r0(i, 1) * from_center[1] + r0(i, 2) * from_center[2];
    }
    T p_in_cam[3];
    ceres::AngleAxisRotatePoint(camera, rotated_start, p_in_cam);
    residual[0] = focal_px * p_in_cam[0] / p_in_cam[2] + principal_point_px.x() - pin->uv_px.x();
    residual[1] = focal_px * p_in_cam[1] / p_in_cam[2] + principal_point_px.y() - pin->uv_px.y();
    return true;
  }
};

void BuildProblem(CeresModel* m, ceres::Problem* problem) {
  for (const CeresPin& pin : m->pins) {
    auto* cost = new ceres::AutoDiffCostFunction<PinCost, 2, 6, 6>(
        new PinCost{&pin, &m->world_from_primitive[pin.primitive], &m->cam_from_world_start[pin.camera],
                    m->focal_px[pin.camera], m->principal_point_px[pin.camera]});
    problem->AddResidualBlock(cost, nullptr, m->primitives[pin.primitive].data(), m->cameras[pin.camera].data());
  }
  for (size_t i = 0; i < m->primitives.size(); ++i) {
    double* block = m->primitives[i].data();
    if (!problem->HasParameterBlock(block) || m->primitive_locked[i].empty()) continue;
    if (m->primitive_locked[i].size() == 6) {
      problem->SetParameterBlockConstant(block);
    } else {
      problem->SetManifold(block, new ceres::SubsetManifold(6, m->primitive_locked[i]));
    }
  }
  for (size_t j = 0; j < m->cameras.size(); ++j) {
    if (m->camera_locked[j] && problem->HasParameterBlock(m->cameras[j].data())) {
      problem->SetParameterBlockConstant(m->cameras[j].data());
    }
  }
}

enum LinearSolver { kSparseSchur = 0, kSparseNormalCholesky = 1, kDenseSchur = 2 };

ceres::Solver::Options SolverOptions(CeresModel* m, const ceres::Problem& problem, int linear_solver, int iterations) {
  ceres::Solver::Options o;
  o.minimizer_type = ceres::TRUST_REGION;
  o.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  o.linear_solver_type = linear_solver == kSparseSchur            ? ceres::SPARSE_SCHUR
                         : linear_solver == kSparseNormalCholesky ? ceres::SPARSE_NORMAL_CHOLESKY
                                                                  : ceres::DENSE_SCHUR;
  o.max_num_iterations = iterations;
  o.function_tolerance = facet::testing::kSolveTolerance;
  o.gradient_tolerance = facet::testing::kSolveTolerance;
  o.parameter_tolerance = facet::testing::kSolveTolerance;
  o.initial_trust_region_radius = 1.0 / facet::testing::kInitialLambda;
  o.num_threads = 1;
  o.logging_type = ceres::SILENT;
  o.minimizer_progress_to_stdout = false;
  if (linear_solver != kSparseNormalCholesky) {
    // Boxes first: the Schur complement is the small camera system.
    auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
    for (auto& block : m->primitives) {
      if (problem.HasParameterBlock(block.data())) ordering->AddElementToGroup(block.data(), 0);
    }
    for (auto& block : m->cameras) {
      if (problem.HasParameterBlock(block.data())) ordering->AddElementToGroup(block.data(), 1);
    }
    o.linear_solver_ordering = ordering;
  }
  return o;
}

const char* LinearSolverName(int linear_solver) {
  return linear_solver == kSparseSchur            ? "SPARSE_SCHUR"
         : linear_solver == kSparseNormalCholesky ? "SPARSE_NORMAL_CHOLESKY"
                                                  : "DENSE_SCHUR";
}

ceres::Solver::Summary SolveModel(CeresModel* m, int linear_solver, int iterations) {
  ceres::Problem problem;
  BuildProblem(m, &problem);
  ceres::Solver::Summary summary;
  ceres::Solve(SolverOptions(m, problem, linear_solver, iterations), &problem, &summary);
  return summary;
}

bool Usable(const ceres::Solver::Summary& s) {
  return s.termination_type == ceres::CONVERGENCE || s.termination_type == ceres::NO_CONVERGENCE;
}

void SetCounters(benchmark::State& state, const CeresModel& m, const ceres::Solver::Summary& s) {
  state.counters["final_cost"] = s.final_cost;
  state.counters["initial_cost"] = s.initial_cost;
  state.counters["iterations"] = static_cast<double>(s.iterations.size() > 0 ? s.iterations.size() - 1 : 0);
  state.counters["parameters"] = s.num_effective_parameters;
  state.counters["residuals"] = s.num_residuals;
  state.counters["primitives"] = static_cast<double>(m.primitives.size());
  state.counters["images"] = static_cast<double>(m.cameras.size());
  state.counters["pins"] = static_cast<double>(m.pins.size());
}

// Ceres's own converged solution of a scene (the drag's starting point), once per size.
const CeresModel* ConvergedModel(const JointSceneOptions& size, std::string* error) {
  static std::map<std::tuple<int, int, int>, std::unique_ptr<CeresModel>> cache;
  const auto key = std::make_tuple(size.num_primitives, size.num_images, size.num_pins);
  auto it = cache.find(key);
  if (it != cache.end()) return it->second.get();
  const JointScene scene = facet::testing::MakeJointScene(size);
  auto m = std::make_unique<CeresModel>();
  if (!ModelFromProject(scene.start, m.get(), error)) return nullptr;
  const ceres::Solver::Summary s = SolveModel(m.get(), kSparseSchur, facet::testing::kFullIterations);
  if (s.termination_type != ceres::CONVERGENCE) {
    *error = "Ceres's full solve did not converge: " + s.message;
    return nullptr;
  }
  return cache.emplace(key, std::move(m)).first->second.get();
}

// One frame of a drag, as in BM_JointInteractive. rebuild:1 builds the ceres::Problem every
// frame, as SolveJoint builds its problem on every call; rebuild:0 keeps one Problem and only
// moves the pin, Ceres's best case.
void RunInteractive(benchmark::State& state, const JointSceneOptions& size, int linear_solver, bool rebuild) {
  std::string error;
  const CeresModel* converged = ConvergedModel(size, &error);
  if (converged == nullptr) {
    state.SkipWithError(error.c_str());
    return;
  }
  // The counters come from one frame outside the timing, as in BM_JointInteractive.
  CeresModel first = *converged;
  first.pins[0].uv_px.x() += facet::testing::kDragStepPx;
  const ceres::Solver::Summary first_summary = SolveModel(&first, linear_solver, facet::testing::kFrameIterations);
  CeresModel m = *converged;
  ceres::Problem kept;
  if (!rebuild) BuildProblem(&m, &kept);
  const ceres::Solver::Options kept_options = SolverOptions(&m, kept, linear_solver, facet::testing::kFrameIterations);
  ceres::Solver::Summary summary;
  int step = 0;
  for (auto _ : state) {
    m.pins[0].uv_px.x() += (step++ % 2 == 0) ? facet::testing::kDragStepPx : -facet::testing::kDragStepPx;
    if (rebuild) {
      summary = SolveModel(&m, linear_solver, facet::testing::kFrameIterations);
    } else {
      ceres::Solve(kept_options, &kept, &summary);
    }
    if (!Usable(summary)) {
      state.SkipWithError(summary.message.c_str());
      return;
    }
  }
  SetCounters(state, first, first_summary);
  state.SetLabel(LinearSolverName(linear_solver));
}

void BM_CeresInteractive(benchmark::State& state) {
  RunInteractive(state,
                 facet::testing::JointSceneSize(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)),
                                                static_cast<int>(state.range(2))),
                 static_cast<int>(state.range(3)), state.range(4) != 0);
}
BENCHMARK(BM_CeresInteractive)
    ->ArgNames({"primitives", "images", "pins", "solver", "rebuild"})
    ->ArgsProduct({{10}, {3}, {60}, {kSparseSchur, kSparseNormalCholesky, kDenseSchur}, {0, 1}})
    ->ArgsProduct({{100}, {10}, {1000}, {kSparseSchur, kSparseNormalCholesky, kDenseSchur}, {0, 1}})
    ->Unit(benchmark::kMillisecond);

// Full solve from the cold start, as BM_JointCold (diagnostics off). Outside the timing our
// solve runs once on the same start, so the same-cost target reads off one line:
// rel_cost_vs_facet = (Ceres's final cost - ours) / ours, and facet_initial_cost equals
// initial_cost when both build the same problem.
void BM_CeresCold(benchmark::State& state) {
  const JointScene scene = facet::testing::MakeJointScene(facet::testing::JointSceneSize(
      static_cast<int>(state.range(0)), static_cast<int>(state.range(1)), static_cast<int>(state.range(2))));
  const int linear_solver = static_cast<int>(state.range(3));
  CeresModel start;
  std::string error;
  if (!ModelFromProject(scene.start, &start, &error)) {
    state.SkipWithError(error.c_str());
    return;
  }
  ceres::Solver::Summary summary;
  CeresModel m;
  for (auto _ : state) {
    m = start;
    summary = SolveModel(&m, linear_solver, facet::testing::kFullIterations);
    if (!Usable(summary)) {
      state.SkipWithError(summary.message.c_str());
      return;
    }
  }
  SetCounters(state, m, summary);
  state.SetLabel(LinearSolverName(linear_solver));
  state.counters["converged"] = summary.termination_type == ceres::CONVERGENCE ? 1 : 0;

  facet::JointSolveOptions ours;
  ours.max_iterations = facet::testing::kFullIterations;
  ours.function_tolerance = facet::testing::kSolveTolerance;
  ours.gradient_tolerance = facet::testing::kSolveTolerance;
  ours.parameter_tolerance = facet::testing::kSolveTolerance;
  ours.initial_lambda = facet::testing::kInitialLambda;
  ours.compute_diagnostics = false;
  Project solved;
  const facet::JointSolveSummary facet_summary = facet::SolveJoint(scene.start, ours, &solved);
  state.counters["facet_initial_cost"] = facet_summary.initial_cost;
  state.counters["facet_final_cost"] = facet_summary.final_cost;
  state.counters["rel_cost_vs_facet"] = (summary.final_cost - facet_summary.final_cost) / facet_summary.final_cost;
}
BENCHMARK(BM_CeresCold)
    ->ArgNames({"primitives", "images", "pins", "solver"})
    ->ArgsProduct({{10}, {3}, {60}, {kSparseSchur, kSparseNormalCholesky, kDenseSchur}})
    ->ArgsProduct({{100}, {10}, {1000}, {kSparseSchur, kSparseNormalCholesky, kDenseSchur}})
    ->Unit(benchmark::kMillisecond);

// Growth, as BM_JointScaling: the per-frame update with a Problem kept between frames.
void BM_CeresScaling(benchmark::State& state) {
  RunInteractive(state, facet::testing::ScalingSceneSize(static_cast<int>(state.range(0))),
                 static_cast<int>(state.range(1)), false);
}
BENCHMARK(BM_CeresScaling)
    ->ArgNames({"primitives", "solver"})
    ->ArgsProduct({{1, 3, 10, 30, 100, 300, 1000}, {kSparseSchur, kDenseSchur}})
    ->Unit(benchmark::kMillisecond);

}  // namespace

#endif  // FACET_HAVE_CERES
