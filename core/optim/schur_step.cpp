#include "core/optim/schur_step.h"

#include <utility>

#include <Eigen/Dense>

#include "core/util/eigen_decompositions.h"

namespace facet {

void SchurNormalEquations::Reset(int num_camera_parameters, std::vector<std::vector<int>> rows,
                                 std::vector<bool> used) {
  camera_rows = std::move(rows);
  point_used = std::move(used);
  const size_t m = camera_rows.size();
  u.resize(num_camera_parameters, num_camera_parameters);
  g_c.resize(num_camera_parameters);
  v.resize(m);
  g_p.resize(m);
  w.assign(m, Eigen::MatrixXd());
  SetZero();
}

void SchurNormalEquations::SetZero() {
  u.setZero();
  g_c.setZero();
  for (int j = 0; j < NumPoints(); ++j) {
    v[j].setZero();
    g_p[j].setZero();
    if (point_used[j]) w[j].setZero(NumCameraParameters(), 3);
  }
}

double SchurStep::SquaredNorm() const {
  double sum = camera.squaredNorm();
  for (const Eigen::Vector3d& dp : points) sum += dp.squaredNorm();
  return sum;
}

bool SolveDampedSchurStep(const SchurNormalEquations& eq, double lambda, SchurStep* step) {
  const int m = eq.NumPoints();
  Eigen::MatrixXd& s = step->reduced;
  Eigen::VectorXd& rhs = step->rhs;
  step->v_inverse.resize(m);
  s = eq.u;
  s.diagonal() += lambda * (eq.u.diagonal().array() + 1e-12 * eq.u.diagonal().maxCoeff()).matrix();
  rhs = -eq.g_c;
  for (int j = 0; j < m; ++j) {
    if (!eq.point_used[j]) continue;
    Eigen::Matrix3d vj = eq.v[j];
    vj.diagonal() += lambda * (eq.v[j].diagonal().array() + 1e-12 * eq.v[j].diagonal().maxCoeff()).matrix();
    step->v_inverse[j] = vj.inverse();
    const Eigen::MatrixXd w = eq.w[j](eq.camera_rows[j], Eigen::all);
    const Eigen::MatrixXd y = w * step->v_inverse[j];
    s(eq.camera_rows[j], eq.camera_rows[j]) -= y * w.transpose();
    rhs(eq.camera_rows[j]) += y * eq.g_p[j];
  }
  step->camera = s.ldlt().solve(rhs);
  if (!step->camera.allFinite()) return false;
  step->points.assign(m, Eigen::Vector3d::Zero());
  for (int j = 0; j < m; ++j) {
    if (!eq.point_used[j]) continue;
    // The full W_j^T dc: the rows outside camera_rows add exact zeros, and a row subset would
    // sum in another order (the bundle adjustments' results would move by rounding).
    step->points[j] = step->v_inverse[j] * (-eq.g_p[j] - eq.w[j].transpose() * step->camera);
  }
  return true;
}

}  // namespace facet
