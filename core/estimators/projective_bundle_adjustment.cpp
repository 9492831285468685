#include "core/estimators/projective_bundle_adjustment.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <Eigen/Dense>

#include "core/optim/levenberg_marquardt.h"
#include "core/util/format.h"
#include "core/util/timer.h"

namespace facet {
namespace {

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
  if (!options.Check(&error)) {
    summary.message = "bad options: " + error;
    return summary;
  }
  const int n = static_cast<int>(cameras->size());
  const int m = static_cast<int>(points->size());
  if (observations.empty() || static_cast<int>(pixel_from_normalised.size()) != n) {
    summary.message = observations.empty() ? "nothing to adjust" : "one pixel_from_normalised per camera is needed";
    return summary;
  }
  for (const auto& o : observations) {
    if (o.view < 0 || o.view >= n || o.point < 0 || o.point >= m) {
      summary.message = "an observation's view or point is out of range";
      return summary;
    }
    if (!o.uv_px.allFinite()) {
      summary.message = "an observation is not finite";
      return summary;
    }
  }
  std::vector<Matrix34d> cams = *cameras;
  std::vector<Eigen::Vector4d> pts = *points;
  // Cameras and points without observations are left as they are (e.g. zero for views that
  // are not registered).
  std::vector<bool> point_used(m, false), camera_used(n, false);
  for (const auto& o : observations) {
    point_used[o.point] = true;
    camera_used[o.view] = true;
  }
  for (int v = 0; v < n; ++v)
    if (camera_used[v]) cams[v].normalize();
  for (int j = 0; j < m; ++j)
    if (point_used[j]) pts[j].normalize();

  auto cost_of = [&](const std::vector<Matrix34d>& cs, const std::vector<Eigen::Vector4d>& ps) {
    double cost = 0.0;
    for (const auto& o : observations) {
      const Eigen::Vector3d y = pixel_from_normalised[o.view] * cs[o.view] * ps[o.point];
      const double e = (y.head<2>() / y.z() - o.uv_px).squaredNorm();
      cost += std::isfinite(e) ? e : 1e300;
    }
    return cost;
  };

  const int nc = kCameraDof * n;
  std::vector<std::vector<int>> point_rows(m);  // per point, the parameter rows of its cameras
  for (const auto& o : observations) {
    std::vector<int>& rows = point_rows[o.point];
    if (std::find(rows.begin(), rows.end(), kCameraDof * o.view) != rows.end()) continue;
    for (int k = 0; k < kCameraDof; ++k) rows.push_back(kCameraDof * o.view + k);
  }
  Eigen::MatrixXd u(nc, nc);
  Eigen::VectorXd g_c(nc);
  std::vector<Eigen::Matrix3d> v_blocks(m);
  std::vector<Eigen::Vector3d> g_p(m);
  std::vector<Eigen::MatrixXd> w_blocks(m);
  std::vector<Eigen::Matrix<double, 12, kCameraDof>> cam_basis(n);
  std::vector<Eigen::Matrix<double, 4, 3>> point_basis(m);

  auto build = [&]() {
    u.setZero();
    g_c.setZero();
    for (int v = 0; v < n; ++v)
      if (camera_used[v]) cam_basis[v] = OrthogonalComplement<12>(RowMajor(cams[v]));
    for (int j = 0; j < m; ++j) {
      v_blocks[j].setZero();
      g_p[j].setZero();
      if (!point_used[j]) continue;
      w_blocks[j].setZero(nc, 3);
      point_basis[j] = OrthogonalComplement<4>(pts[j]);
    }
    for (const auto& o : observations) {
      const Eigen::Matrix3d& k = pixel_from_normalised[o.view];
      const Eigen::Vector4d& x = pts[o.point];
      const Eigen::Vector3d y = k * cams[o.view] * x;
      if (!(std::abs(y.z()) > 0)) continue;
      const Eigen::Vector2d r = y.head<2>() / y.z() - o.uv_px;
      Eigen::Matrix<double, 2, 3> dy;
      dy << 1.0 / y.z(), 0.0, -y.x() / (y.z() * y.z()), 0.0, 1.0 / y.z(), -y.y() / (y.z() * y.z());
      // d(N P X) / d vec(P), row-major vec: entry (r, c) of P moves y by N.col(r) X(c).
      Eigen::Matrix<double, 3, 12> dp;
      for (int row = 0; row < 3; ++row)
        for (int c = 0; c < 4; ++c) dp.col(4 * row + c) = k.col(row) * x(c);
      const Eigen::Matrix<double, 2, kCameraDof> jc = dy * dp * cam_basis[o.view];
      const Eigen::Matrix<double, 2, 3> jp = dy * k * cams[o.view] * point_basis[o.point];
      const int base = kCameraDof * o.view;
      u.block<kCameraDof, kCameraDof>(base, base) += jc.transpose() * jc;
      g_c.segment<kCameraDof>(base) += jc.transpose() * r;
      w_blocks[o.point].block<kCameraDof, 3>(base, 0) += jc.transpose() * jp;
      v_blocks[o.point] += jp.transpose() * jp;
      g_p[o.point] += jp.transpose() * r;
    }
  };

  double cost = cost_of(cams, pts);
  const double initial_cost = cost;
  summary.initial_rms_px = std::sqrt(cost / (2.0 * observations.size()));
  Eigen::MatrixXd s(nc, nc);
  Eigen::VectorXd rhs(nc);
  std::vector<Eigen::Matrix3d> v_inv(m);
  std::vector<Matrix34d> cams_new;
  std::vector<Eigen::Vector4d> pts_new;
  // Marquardt damping (scaled by the diagonal) also regularises the projective gauge.
  auto step = [&](double lambda, double* cost_new, double* step_sq) {
    s = u;
    s.diagonal() += lambda * (u.diagonal().array() + 1e-12 * u.diagonal().maxCoeff()).matrix();
    rhs = -g_c;
    for (int j = 0; j < m; ++j) {
      if (!point_used[j]) continue;
      Eigen::Matrix3d vj = v_blocks[j];
      vj.diagonal() += lambda * (v_blocks[j].diagonal().array() + 1e-12 * v_blocks[j].diagonal().maxCoeff()).matrix();
      v_inv[j] = vj.inverse();
      // Only the rows of the cameras that see the point are non-zero in W_j.
      const Eigen::MatrixXd w = w_blocks[j](point_rows[j], Eigen::all);
      const Eigen::MatrixXd y = w * v_inv[j];
      s(point_rows[j], point_rows[j]) -= y * w.transpose();
      rhs(point_rows[j]) += y * g_p[j];
    }
    const Eigen::VectorXd dc = s.ldlt().solve(rhs);
    if (!dc.allFinite()) return false;
    cams_new = cams;
    pts_new = pts;
    for (int v = 0; v < n; ++v)
      if (camera_used[v])
        cams_new[v] = FromRowMajor(RowMajor(cams[v]) + cam_basis[v] * dc.segment<kCameraDof>(kCameraDof * v)).normalized();
    *step_sq = dc.squaredNorm();
    for (int j = 0; j < m; ++j) {
      if (!point_used[j]) continue;
      const Eigen::Vector3d dx = v_inv[j] * (-g_p[j] - w_blocks[j].transpose() * dc);
      pts_new[j] = (pts[j] + point_basis[j] * dx).normalized();
      *step_sq += dx.squaredNorm();
    }
    *cost_new = cost_of(cams_new, pts_new);
    return true;
  };
  auto accept = [&]() {
    cams = std::move(cams_new);
    pts = std::move(pts_new);
  };
  LmOptions lm;
  lm.max_iterations = options.max_iterations;
  lm.relative_decrease_tolerance = 1e-12;
  const LmResult lm_result = MinimizeLevenbergMarquardt(cost, lm, build, step, accept);
  cost = lm_result.final_cost;
  summary.iterations = lm_result.iterations;
  summary.final_rms_px = std::sqrt(cost / (2.0 * observations.size()));
  summary.success = std::isfinite(cost) && cost <= initial_cost;
  if (summary.success) {
    *cameras = cams;
    *points = pts;
  }
  summary.message = summary.success ? "projective bundle adjustment: RMS " + internal::FormatNumber(summary.initial_rms_px) +
                                          " -> " + internal::FormatNumber(summary.final_rms_px) + " px in " +
                                          std::to_string(summary.iterations) + " iterations"
                                    : "projective bundle adjustment diverged";
  summary.time_ms = internal::MsSince(start);
  return summary;
}

}  // namespace facet
