// The damped Schur-complement step of the bundle adjustments (core/optim/schur_step.h): on
// small random problems it must equal the step of the full damped normal equations.
#include <doctest/doctest.h>

#include <algorithm>
#include <random>
#include <vector>

#include <Eigen/Dense>

#include "core/optim/schur_step.h"

namespace facet {
namespace {

constexpr int kCameraBlock = 6;

// A random bundle-adjustment-shaped problem: num_cameras blocks of 6 parameters plus
// num_shared parameters every camera has (a shared focal length, a principal point), points
// seen by random subsets of at least 2 cameras, the last point seen by none. Each observation
// contributes 2 residual rows with random Jacobian entries in its camera's rows, the shared
// rows and its point's 3 columns. The full Jacobian is returned too.
struct RandomProblem {
  SchurNormalEquations equations;
  Eigen::MatrixXd jacobian;  // observations x (nc + 3 m)
  Eigen::VectorXd residuals;
};

RandomProblem MakeRandomProblem(int num_cameras, int num_shared, int num_points, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::uniform_int_distribution<int> coin(0, 1);
  const int nc = kCameraBlock * num_cameras + num_shared;
  std::vector<std::vector<int>> cameras_of(num_points);
  for (int j = 0; j + 1 < num_points; ++j) {
    for (int c = 0; c < num_cameras; ++c)
      if (coin(rng)) cameras_of[j].push_back(c);
    for (int c = 0; static_cast<int>(cameras_of[j].size()) < 2; ++c)
      if (std::find(cameras_of[j].begin(), cameras_of[j].end(), c) == cameras_of[j].end()) cameras_of[j].push_back(c);
  }
  std::vector<std::vector<int>> rows(num_points);
  std::vector<bool> used(num_points, false);
  int num_observations = 0;
  for (int j = 0; j < num_points; ++j) {
    for (int c : cameras_of[j])
      for (int k = 0; k < kCameraBlock; ++k) rows[j].push_back(kCameraBlock * c + k);
    for (int k = kCameraBlock * num_cameras; k < nc && !cameras_of[j].empty(); ++k) rows[j].push_back(k);
    used[j] = !cameras_of[j].empty();
    num_observations += static_cast<int>(cameras_of[j].size());
  }
  RandomProblem p;
  p.equations.Reset(nc, rows, used);
  p.jacobian = Eigen::MatrixXd::Zero(2 * num_observations, nc + 3 * num_points);
  p.residuals.resize(2 * num_observations);
  int row = 0;
  for (int j = 0; j < num_points; ++j) {
    for (int c : cameras_of[j]) {
      Eigen::MatrixXd jc = Eigen::MatrixXd::Zero(2, nc);
      for (int k = 0; k < kCameraBlock; ++k) jc.col(kCameraBlock * c + k) << gauss(rng), gauss(rng);
      for (int k = kCameraBlock * num_cameras; k < nc; ++k) jc.col(k) << gauss(rng), gauss(rng);
      Eigen::Matrix<double, 2, 3> jp;
      for (int k = 0; k < 3; ++k) jp.col(k) << gauss(rng), gauss(rng);
      const Eigen::Vector2d r{gauss(rng), gauss(rng)};
      p.jacobian.block(row, 0, 2, nc) = jc;
      p.jacobian.block<2, 3>(row, nc + 3 * j) = jp;
      p.residuals.segment<2>(row) = r;
      row += 2;
      SchurNormalEquations& eq = p.equations;
      eq.u += jc.transpose() * jc;
      eq.g_c += jc.transpose() * r;
      eq.w[j] += jc.transpose() * jp;
      eq.v[j] += jp.transpose() * jp;
      eq.g_p[j] += jp.transpose() * r;
    }
  }
  return p;
}

// The step of the full damped normal equations over the used points, with the damping the
// header defines (per block: lambda (d + 1e-12 max d) on the diagonal).
Eigen::VectorXd FullDampedStep(const RandomProblem& p, double lambda) {
  const SchurNormalEquations& eq = p.equations;
  const int nc = eq.NumCameraParameters();
  const Eigen::MatrixXd h = p.jacobian.transpose() * p.jacobian;
  const Eigen::VectorXd g = p.jacobian.transpose() * p.residuals;
  Eigen::MatrixXd damped = h;
  const double u_floor = 1e-12 * h.diagonal().head(nc).maxCoeff();
  for (int k = 0; k < nc; ++k) damped(k, k) += lambda * (h(k, k) + u_floor);
  for (int j = 0; j < eq.NumPoints(); ++j) {
    const double v_floor = 1e-12 * h.diagonal().segment<3>(nc + 3 * j).maxCoeff();
    for (int k = nc + 3 * j; k < nc + 3 * j + 3; ++k) damped(k, k) += lambda * (h(k, k) + v_floor);
  }
  // Unused points have no rows: their block is left out of the solve and their step is zero.
  std::vector<int> keep;
  for (int k = 0; k < nc; ++k) keep.push_back(k);
  for (int j = 0; j < eq.NumPoints(); ++j)
    if (eq.point_used[j])
      for (int k = 0; k < 3; ++k) keep.push_back(nc + 3 * j + k);
  const Eigen::MatrixXd reduced = damped(keep, keep);
  const Eigen::VectorXd solution = reduced.fullPivLu().solve(-g(keep));
  Eigen::VectorXd step = Eigen::VectorXd::Zero(h.rows());
  step(keep) = solution;
  return step;
}

Eigen::VectorXd Stacked(const SchurStep& step) {
  Eigen::VectorXd out(step.camera.size() + 3 * static_cast<Eigen::Index>(step.points.size()));
  out.head(step.camera.size()) = step.camera;
  for (size_t j = 0; j < step.points.size(); ++j) out.segment<3>(step.camera.size() + 3 * j) = step.points[j];
  return out;
}

TEST_CASE(
    "the damped Schur step equals the step of the full damped normal "
    "equations") {
  // Relative to the step's norm. With 40 points every block is overdetermined (each point has
  // 4 or more residuals for its 3 parameters, the cameras share the surplus), so the systems are
  // well conditioned even nearly undamped and the two solves agree to rounding.
  constexpr double kRelativeTolerance = 1e-10;
  for (unsigned seed = 1; seed <= 5; ++seed) {
    const RandomProblem p = MakeRandomProblem(4, 3, 40, seed);
    REQUIRE_FALSE(p.equations.point_used.back());
    SchurStep step;
    for (double lambda : {1e-6, 1e-2, 1.0, 1e3}) {
      CAPTURE(seed);
      CAPTURE(lambda);
      REQUIRE(SolveDampedSchurStep(p.equations, lambda, &step));
      const Eigen::VectorXd expected = FullDampedStep(p, lambda);
      const Eigen::VectorXd got = Stacked(step);
      const double error = (got - expected).norm() / expected.norm();
      CAPTURE(error);
      CHECK(error < kRelativeTolerance);
      CHECK(step.points.back().isZero(0.0));
      CHECK(step.SquaredNorm() == doctest::Approx(expected.squaredNorm()).epsilon(1e-9));
    }
  }
}

TEST_CASE("SetZero clears the accumulated blocks and keeps the sizes") {
  RandomProblem p = MakeRandomProblem(3, 1, 6, 7);
  p.equations.SetZero();
  CHECK(p.equations.u.isZero(0.0));
  CHECK(p.equations.g_c.isZero(0.0));
  CHECK(p.equations.u.rows() == 3 * kCameraBlock + 1);
  for (int j = 0; j < p.equations.NumPoints(); ++j) {
    CHECK(p.equations.v[j].isZero(0.0));
    if (p.equations.point_used[j]) CHECK(p.equations.w[j].rows() == 3 * kCameraBlock + 1);
  }
}

}  // namespace
}  // namespace facet
