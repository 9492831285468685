#include "core/estimators/projective_bundle_adjustment.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <Eigen/Dense>

#include "core/optim/levenberg_marquardt.h"
#include "core/optim/schur_step.h"
#include "core/optim/solver_summary.h"
#include "core/util/format.h"
#include "core/util/timer.h"

namespace facet {
namespace {

using internal::FailedSummary;

constexpr int kCameraDof = 11;

// An orthonormal basis of the directions orthogonal to a (unit or not): the last D - 1
// columns of the Householder Q whose first column is along a.
template <int D>
Eigen::Matrix<double, D, D - 1> OrthogonalComplement(const Eigen::Matrix<double, D, 1>& a) {
  const Eigen::HouseholderQR<Eigen::Matrix<double, D, 1>> qr(a);
  const Eigen::Matrix<double, D, D> q = qr.householderQ();
  return q.template rightCols<D - 1>();
}

Eigen::Matrix<double, 12, 1> RowMajor(const Matrix34d& p) {
  Eigen::Matrix<double, 12, 1> v;
  for (int r = 0; r < 3; ++r) v.segment<4>(4 * r) = p.row(r).transpose();
  return v;
}

Matrix34d FromRowMajor(const Eigen::Matrix<double, 12, 1>& v) {
  Matrix34d p;
  for (int r = 0; r < 3; ++r) p.row(r) = v.segment<4>(4 * r).transpose();
  return p;
}

// Sum of squared reprojection errors (px^2); a non-finite one counts 1e300.
double ProjectiveCost(const std::vector<ProjectiveBundleObservation>& observations,
                      const std::vector<Eigen::Matrix3d>& pixel_from_normalised, const std::vector<Matrix34d>& cs,
                      const std::vector<Eigen::Vector4d>& ps) {
  double cost = 0.0;
  for (const auto& o : observations) {
    const Eigen::Vector3d y = pixel_from_normalised[o.view] * cs[o.view] * ps[o.point];
    const double e = (y.head<2>() / y.z() - o.uv_px).squaredNorm();
    cost += std::isfinite(e) ? e : 1e300;
  }
  return cost;
}

// The cameras and points being adjusted, with the bases of their tangent spaces (each moves
// orthogonally to itself).
struct ProjectiveState {
  std::vector<Matrix34d> cams;
  std::vector<Eigen::Vector4d> pts;
  std::vector<bool> camera_used, point_used;  // those with observations
  std::vector<Eigen::Matrix<double, 12, kCameraDof>> cam_basis;
  std::vector<Eigen::Matrix<double, 4, 3>> point_basis;
};

// The Gauss-Newton normal equations over the tangent spaces at the state (and their bases).
void LinearizeProjective(const std::vector<ProjectiveBundleObservation>& observations,
                         const std::vector<Eigen::Matrix3d>& pixel_from_normalised, ProjectiveState* state,
                         SchurNormalEquations* normal) {
  normal->SetZero();
  const std::vector<Matrix34d>& cams = state->cams;
  for (size_t v = 0; v < cams.size(); ++v)
    if (state->camera_used[v]) state->cam_basis[v] = OrthogonalComplement<12>(RowMajor(cams[v]));
  for (size_t j = 0; j < state->pts.size(); ++j)
    if (state->point_used[j]) state->point_basis[j] = OrthogonalComplement<4>(state->pts[j]);
  for (const auto& o : observations) {
    const Eigen::Matrix3d& k = pixel_from_normalised[o.view];
    const Eigen::Vector4d& x = state->pts[o.point];
    const Eigen::Vector3d y = k * cams[o.view] * x;
    if (!(std::abs(y.z()) > 0)) continue;
    const Eigen::Vector2d r = y.head<2>() / y.z() - o.uv_px;
    Eigen::Matrix<double, 2, 3> dy;
    dy << 1.0 / y.z(), 0.0, -y.x() / (y.z() * y.z()), 0.0, 1.0 / y.z(), -y.y() / (y.z() * y.z());
    // d(N P X) / d vec(P), row-major vec: entry (r, c) of P moves y by N.col(r) X(c).
    Eigen::Matrix<double, 3, 12> dp;
    for (int row = 0; row < 3; ++row)
      for (int c = 0; c < 4; ++c) dp.col(4 * row + c) = k.col(row) * x(c);
    const Eigen::Matrix<double, 2, kCameraDof> jc = dy * dp * state->cam_basis[o.view];
    const Eigen::Matrix<double, 2, 3> jp = dy * k * cams[o.view] * state->point_basis[o.point];
    const int base = kCameraDof * o.view;
    normal->u.block<kCameraDof, kCameraDof>(base, base) += jc.transpose() * jc;
    normal->g_c.segment<kCameraDof>(base) += jc.transpose() * r;
    normal->w[o.point].block<kCameraDof, 3>(base, 0) += jc.transpose() * jp;
    normal->v[o.point] += jp.transpose() * jp;
    normal->g_p[o.point] += jp.transpose() * r;
  }
}

// The state moved by a step along the tangent spaces, renormalised.
void ApplyProjectiveStep(const ProjectiveState& state, const SchurStep& step, std::vector<Matrix34d>* cams,
                         std::vector<Eigen::Vector4d>* pts) {
  *cams = state.cams;
  *pts = state.pts;
  for (size_t v = 0; v < cams->size(); ++v)
    if (state.camera_used[v])
      (*cams)[v] =
          FromRowMajor(RowMajor(state.cams[v]) + state.cam_basis[v] * step.camera.segment<kCameraDof>(kCameraDof * v))
              .normalized();
  for (size_t j = 0; j < pts->size(); ++j)
    if (state.point_used[j]) (*pts)[j] = (state.pts[j] + state.point_basis[j] * step.points[j]).normalized();
}

}  // namespace

bool ProjectiveBundleOptions::Check(std::string* error) const {
  if (max_iterations < 0) {
    *error = "max_iterations must not be negative";
    return false;
  }
  return true;
}

ProjectiveBundleSummary ProjectiveBundleAdjust(const std::vector<ProjectiveBundleObservation>& observations,
                                               const std::vector<Eigen::Matrix3d>& pixel_from_normalised,
                                               const ProjectiveBundleOptions& options, std::vector<Matrix34d>* cameras,
                                               std::vector<Eigen::Vector4d>* points) {
  const auto start = std::chrono::steady_clock::now();
  ProjectiveBundleSummary summary;
  std::string error;
  if (!options.Check(&error))
    return FailedSummary(summary, "bad options: " + error, start, SolverTermination::kInvalidInput);
  const int n = static_cast<int>(cameras->size());
  const int m = static_cast<int>(points->size());
  if (observations.empty())
    return FailedSummary(summary, "nothing to adjust", start, SolverTermination::kNothingToSolve);
  if (static_cast<int>(pixel_from_normalised.size()) != n)
    return FailedSummary(summary, "one pixel_from_normalised per camera is needed", start,
                         SolverTermination::kInvalidInput);
  for (const auto& o : observations) {
    if (o.view < 0 || o.view >= n || o.point < 0 || o.point >= m)
      return FailedSummary(summary, "an observation's view or point is out of range", start,
                           SolverTermination::kInvalidInput);
    if (!o.uv_px.allFinite())
      return FailedSummary(summary, "an observation is not finite", start, SolverTermination::kInvalidInput);
  }
  // Cameras and points without observations are left as they are (e.g. zero for views that
  // are not registered).
  ProjectiveState state{*cameras,
                        *points,
                        std::vector<bool>(n, false),
                        std::vector<bool>(m, false),
                        std::vector<Eigen::Matrix<double, 12, kCameraDof>>(n),
                        std::vector<Eigen::Matrix<double, 4, 3>>(m)};
  for (const auto& o : observations) {
    state.point_used[o.point] = true;
    state.camera_used[o.view] = true;
  }
  for (int v = 0; v < n; ++v)
    if (state.camera_used[v]) state.cams[v].normalize();
  for (int j = 0; j < m; ++j)
    if (state.point_used[j]) state.pts[j].normalize();

  std::vector<std::vector<int>> point_rows(m);  // per point, the parameter rows of its cameras
  for (const auto& o : observations) {
    std::vector<int>& rows = point_rows[o.point];
    if (std::find(rows.begin(), rows.end(), kCameraDof * o.view) != rows.end()) continue;
    for (int k = 0; k < kCameraDof; ++k) rows.push_back(kCameraDof * o.view + k);
  }
  SchurNormalEquations normal;
  normal.Reset(kCameraDof * n, std::move(point_rows), state.point_used);
  auto build = [&]() { LinearizeProjective(observations, pixel_from_normalised, &state, &normal); };

  double cost = ProjectiveCost(observations, pixel_from_normalised, state.cams, state.pts);
  const double initial_cost = cost;
  summary.initial_rms_px = std::sqrt(cost / (2.0 * observations.size()));
  SchurStep schur;
  std::vector<Matrix34d> cams_new;
  std::vector<Eigen::Vector4d> pts_new;
  // Marquardt damping (scaled by the diagonal) also regularises the projective gauge.
  auto step = [&](double lambda, double* cost_new, double* step_sq) {
    if (!SolveDampedSchurStep(normal, lambda, &schur)) return false;
    ApplyProjectiveStep(state, schur, &cams_new, &pts_new);
    *step_sq = schur.SquaredNorm();
    *cost_new = ProjectiveCost(observations, pixel_from_normalised, cams_new, pts_new);
    return true;
  };
  auto accept = [&]() {
    state.cams = std::move(cams_new);
    state.pts = std::move(pts_new);
  };
  LmOptions lm;
  lm.max_iterations = options.max_iterations;
  lm.relative_decrease_tolerance = 1e-12;
  const LmResult lm_result = MinimizeLevenbergMarquardt(cost, lm, build, step, accept);
  cost = lm_result.final_cost;
  summary.iterations = lm_result.iterations;
  summary.initial_cost = initial_cost;
  summary.final_cost = cost;
  summary.final_rms_px = std::sqrt(cost / (2.0 * observations.size()));
  const bool usable = std::isfinite(cost) && cost <= initial_cost;
  summary.termination = !usable                                                  ? SolverTermination::kFailed
                        : lm_result.termination == LmTermination::kMaxIterations ? SolverTermination::kMaxIterations
                                                                                 : SolverTermination::kConverged;
  if (usable) {
    *cameras = state.cams;
    *points = state.pts;
  }
  summary.message = usable ? "projective bundle adjustment: RMS " + internal::FormatNumber(summary.initial_rms_px) +
                                 " -> " + internal::FormatNumber(summary.final_rms_px) + " px in " +
                                 std::to_string(summary.iterations) + " iterations"
                           : "projective bundle adjustment diverged";
  summary.time_ms = internal::MsSince(start);
  return summary;
}

}  // namespace facet
