#include "core/estimators/projective_upgrade.h"
#include "core/geometry/cross_product_matrix.h"
#include "core/optim/levenberg_marquardt.h"
#include "core/optim/solver_summary.h"
#include "core/util/eigen_decompositions.h"
#include "core/util/format.h"
#include "core/util/timer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

#include <Eigen/Dense>

namespace facet {
namespace {

using Clock = std::chrono::steady_clock;

// Second-smallest singular value over the largest of the stacked vanishing points below which
// they span fewer than 3 dimensions: fewer than 3 independent directions.
constexpr double kIndependentDirectionsRatio = 1e-9;
// |pi . C1| / (|pi| |C1|) below which the plane at infinity passes through camera 1's centre.
constexpr double kPlaneThroughCentre = 1e-12;

using internal::FailedSummary;
using internal::MsSince;
using internal::Skew;
Eigen::Vector4d Canonical(Eigen::Vector4d x) {
  const double n = x.norm();
  if (!(n > 0)) return Eigen::Vector4d::Zero();
  x /= n;
  if (x(3) < 0) x = -x;
  return x;
}

// An orthonormal basis (4x3) of the complement of the unit vector x.
Eigen::Matrix<double, 4, 3> ComplementBasis(const Eigen::Vector4d& x) {
  Eigen::JacobiSVD<Eigen::Matrix<double, 1, 4>> svd(x.transpose(), Eigen::ComputeFullV);
  return svd.matrixV().rightCols<3>();
}

// Residuals (2 per view) of a homogeneous point and, optionally, their Jacobian on the basis.
bool PointResiduals(const std::vector<Matrix34d>& cameras, const std::vector<Eigen::Vector2d>& uv,
                    const Eigen::Vector4d& x, const Eigen::Matrix<double, 4, 3>* basis, Eigen::VectorXd* r,
                    Eigen::MatrixXd* j) {
  const int n = static_cast<int>(cameras.size());
  r->resize(2 * n);
  if (basis) j->resize(2 * n, 3);
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector3d y = cameras[k] * x;
    if (!(std::abs(y.z()) > 0)) return false;
    const Eigen::Vector2d p = y.head<2>() / y.z();
    r->segment<2>(2 * k) = p - uv[k];
    if (basis) {
      Eigen::Matrix<double, 2, 3> d;
      d << 1, 0, -p.x(), 0, 1, -p.y();
      j->block<2, 3>(2 * k, 0) = (d / y.z()) * cameras[k] * *basis;
    }
  }
  return r->allFinite();
}

}  // namespace

bool CanonicalCamerasFromFundamental(const Eigen::Matrix3d& F, Matrix34d* P1, Matrix34d* P2) {
  if (!F.allFinite() || !(F.norm() > 0)) return false;
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(F, Eigen::ComputeFullU);
  // The left epipole: F^T e' = 0, the left singular vector of the smallest singular value.
  const Eigen::Vector3d e2 = svd.matrixU().col(2);
  P1->setZero();
  P1->leftCols<3>().setIdentity();
  P2->leftCols<3>() = Skew(e2) * F;
  P2->col(3) = e2;
  return P1->allFinite() && P2->allFinite();
}

Eigen::Vector4d TriangulateLinear(const std::vector<Matrix34d>& cameras, const std::vector<Eigen::Vector3d>& x) {
  const int n = static_cast<int>(std::min(cameras.size(), x.size()));
  if (n < 2) return Eigen::Vector4d::Zero();
  Eigen::MatrixXd a(3 * n, 4);
  for (int k = 0; k < n; ++k) {
    const double pn = cameras[k].norm(), xn = x[k].norm();
    const Matrix34d p = pn > 0 ? Matrix34d(cameras[k] / pn) : cameras[k];
    const Eigen::Vector3d y = xn > 0 ? Eigen::Vector3d(x[k] / xn) : x[k];
    // x cross (P X) = 0: three rows of rank 2; all three keep points at infinity usable.
    a.row(3 * k) = y.y() * p.row(2) - y.z() * p.row(1);
    a.row(3 * k + 1) = y.z() * p.row(0) - y.x() * p.row(2);
    a.row(3 * k + 2) = y.x() * p.row(1) - y.y() * p.row(0);
  }
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeFullV);
  return Canonical(svd.matrixV().col(3));
}

Eigen::Vector2d ProjectHomogeneous(const Matrix34d& P, const Eigen::Vector4d& X) {
  const Eigen::Vector3d y = P * X;
  if (!(std::abs(y.z()) > 0)) return Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
  return y.head<2>() / y.z();
}

namespace {

// The reprojection error of one homogeneous point as a problem of the Levenberg-Marquardt
// driver: steps in the 3 directions orthogonal to the point, which is renormalised after each.
struct TriangulatedPointProblem {
  const std::vector<Matrix34d>& cameras;
  const std::vector<Eigen::Vector2d>& uv;
  Eigen::Vector4d x;
  Eigen::Matrix<double, 4, 3> basis;  // of the complement of x
  Eigen::VectorXd r;                  // at x
  Eigen::MatrixXd j;                  // at x, on the basis
  Eigen::Vector4d candidate = Eigen::Vector4d::Zero();
  bool moved = false;  // x changed since r and j were computed
  Eigen::Matrix3d jtj = Eigen::Matrix3d::Zero();
  Eigen::Vector3d jtr = Eigen::Vector3d::Zero();

  bool Linearize() {
    if (moved) {
      basis = ComplementBasis(x);
      PointResiduals(cameras, uv, x, &basis, &r, &j);
      moved = false;
    }
    jtj = j.transpose() * j;
    jtr = j.transpose() * r;
    return false;
  }
  LmStepStatus Step(double lambda, LmTrial* trial) {
    Eigen::Matrix3d h = jtj;
    h.diagonal() *= 1 + lambda;
    h.diagonal().array() += 1e-300;
    const Eigen::Vector3d delta = -h.ldlt().solve(jtr);
    if (!delta.allFinite()) return LmStepStatus::kSolveFailed;
    candidate = Canonical(x + basis * delta);
    Eigen::VectorXd r_c;
    Eigen::MatrixXd unused;
    if (PointResiduals(cameras, uv, candidate, nullptr, &r_c, &unused)) trial->cost = r_c.squaredNorm();
    trial->step_squared_norm = delta.squaredNorm();
    return LmStepStatus::kSolved;
  }
  void Accept() {
    x = candidate;
    moved = true;
  }
};

}  // namespace

Eigen::Vector4d RefineTriangulatedPoint(const std::vector<Matrix34d>& cameras, const std::vector<Eigen::Vector2d>& uv,
                                        const Eigen::Vector4d& start, int max_iterations) {
  TriangulatedPointProblem problem{cameras, uv, Canonical(start), {}, {}, {}};
  if (cameras.size() != uv.size() || cameras.size() < 2 || !(problem.x.norm() > 0)) return start;
  problem.basis = ComplementBasis(problem.x);
  if (!PointResiduals(cameras, uv, problem.x, &problem.basis, &problem.r, &problem.j)) return start;
  // A different rule from the driver's defaults, kept from this refinement's tuning (it runs
  // for every track, many times in self-calibration): the damping multiplies the diagonal by
  // 1 + lambda with no relative floor (the 1e-300 only keeps a zero column solvable), lambda
  // starts at 1e-6, / 10 down to 1e-12 and x 10 up to 1e12; stop when a step gains at most
  // 1e-15 of the cost after it (= 1e-15 / (1 + 1e-15) of the cost before) or moves the point
  // by at most 1e-15.
  LmOptions lm;
  lm.max_iterations = max_iterations;
  lm.initial_lambda = 1e-6;
  lm.lambda_decrease = 0.1;
  lm.lambda_increase = 10.0;
  lm.lambda_increase_on_failed_solve = 10.0;
  lm.min_lambda = 1e-12;
  lm.max_lambda = lm.max_lambda_on_failed_solve = 1e12;
  lm.relative_decrease_tolerance = 1e-15 / (1.0 + 1e-15);
  lm.min_step_squared_norm = 1e-30;
  MinimizeLevenbergMarquardt(problem.r.squaredNorm(), lm, problem);
  return problem.x;
}

bool ProjectiveReconstructionOptions::Check(std::string* error) const {
  if (max_point_iterations < 0) {
    *error = "max_point_iterations must not be negative";
    return false;
  }
  return true;
}

ProjectiveReconstructionSummary ReconstructProjective(const Eigen::Matrix3d& F, const std::vector<Eigen::Vector2d>& uv1,
                                                      const std::vector<Eigen::Vector2d>& uv2,
                                                      const ProjectiveReconstructionOptions& options) {
  const auto start = Clock::now();
  ProjectiveReconstructionSummary summary;
  auto fail = [&](std::string message) { return FailedSummary(summary, std::move(message), start); };
  std::string error;
  if (!options.Check(&error))
    return FailedSummary(summary, "bad options: " + error, start, SolverTermination::kInvalidInput);
  if (uv1.size() != uv2.size()) return fail("the two images have different numbers of points");
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(F);
  if (!F.allFinite() || !(svd.singularValues()(1) > 1e-12 * svd.singularValues()(0)))
    return fail("F must be finite and of rank 2 (at least)");
  if (!CanonicalCamerasFromFundamental(F, &summary.P1, &summary.P2)) return fail("F gives no canonical cameras");
  const std::vector<Matrix34d> cameras = {summary.P1, summary.P2};
  double sum = 0.0;
  for (size_t i = 0; i < uv1.size(); ++i) {
    if (!uv1[i].allFinite() || !uv2[i].allFinite()) return fail("match " + std::to_string(i) + " is not finite");
    Eigen::Vector4d x = TriangulateLinear(cameras, {uv1[i].homogeneous(), uv2[i].homogeneous()});
    summary.initial_cost += (ProjectHomogeneous(summary.P1, x) - uv1[i]).squaredNorm() +
                            (ProjectHomogeneous(summary.P2, x) - uv2[i]).squaredNorm();
    if (options.refine_points) x = RefineTriangulatedPoint(cameras, {uv1[i], uv2[i]}, x, options.max_point_iterations);
    const double e1 = (ProjectHomogeneous(summary.P1, x) - uv1[i]).squaredNorm();
    const double e2 = (ProjectHomogeneous(summary.P2, x) - uv2[i]).squaredNorm();
    const double e = std::sqrt(0.5 * (e1 + e2));
    summary.points.push_back(x);
    summary.reprojection_errors_px.push_back(std::isfinite(e) ? e : std::numeric_limits<double>::infinity());
    sum += e1 + e2;
  }
  summary.reprojection_rms_px = uv1.empty() ? 0.0 : std::sqrt(sum / (2.0 * uv1.size()));
  summary.final_cost = sum;
  summary.termination = SolverTermination::kConverged;
  summary.message = "canonical cameras and " + std::to_string(uv1.size()) + " points, reprojection RMS " +
                    internal::FormatNumber(summary.reprojection_rms_px) + " px";
  summary.time_ms = MsSince(start);
  return summary;
}

bool AffineUpgradeOptions::Check(std::string* error) const {
  if (!(plane_residual_warning > 0)) {
    *error = "plane_residual_warning must be positive";
    return false;
  }
  return true;
}

AffineUpgradeSummary UpgradeToAffine(const std::vector<Matrix34d>& cameras,
                                     const std::vector<std::vector<Eigen::Vector3d>>& vanishing,
                                     const AffineUpgradeOptions& options) {
  const auto start = Clock::now();
  AffineUpgradeSummary summary;
  auto fail = [&](std::string message) { return FailedSummary(summary, std::move(message), start); };
  std::string error;
  if (!options.Check(&error))
    return FailedSummary(summary, "bad options: " + error, start, SolverTermination::kInvalidInput);
  if (cameras.size() < 2) return fail("the affine upgrade needs at least 2 views");
  for (const auto& p : cameras)
    if (!p.allFinite()) return fail("a camera is not finite");
  const int m = static_cast<int>(vanishing.size());
  if (m < 3) return fail("the plane at infinity needs at least 3 vanishing points, got " + std::to_string(m));
  Eigen::MatrixXd a(m, 4);
  for (int k = 0; k < m; ++k) {
    if (vanishing[k].size() != cameras.size())
      return fail("vanishing point " + std::to_string(k) + " is not given in every view");
    for (const auto& v : vanishing[k])
      if (!v.allFinite() || !(v.norm() > 0))
        return fail("vanishing point " + std::to_string(k) + " is zero or not finite");
    const Eigen::Vector4d x = TriangulateLinear(cameras, vanishing[k]);
    summary.vanishing_points_3d.push_back(x);
    a.row(k) = x.transpose();
  }
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeFullV);
  Eigen::Vector4d sv = Eigen::Vector4d::Zero();
  sv.head(std::min(m, 4)) = svd.singularValues().head(std::min(m, 4));
  if (!(sv(2) > kIndependentDirectionsRatio * sv(0)))
    return fail(
        "the vanishing points give fewer than 3 independent directions (two are the same direction, or all "
        "lie on one line of the image)");
  const Eigen::Vector4d pi = svd.matrixV().col(3).normalized();
  summary.plane_at_infinity = pi;
  summary.plane_residual = sv(3) / sv(0);
  Eigen::JacobiSVD<Matrix34d> svd_p(cameras[0], Eigen::ComputeFullV);
  const Eigen::Vector4d centre = svd_p.matrixV().col(3);
  if (std::abs(pi.dot(centre)) < kPlaneThroughCentre)
    return fail("the plane at infinity passes through the first camera's centre: inconsistent vanishing points");
  // Rows: the unit rows other than pi's largest entry, then pi scaled so that entry is 1; the
  // determinant is +-1, and pi maps to (0, 0, 0, 1).
  Eigen::Index largest = 0;
  pi.cwiseAbs().maxCoeff(&largest);
  Eigen::Matrix4d h = Eigen::Matrix4d::Zero();
  for (int k = 0, row = 0; k < 4; ++k)
    if (k != largest) h(row++, k) = 1.0;
  h.row(3) = pi.transpose() / pi(largest);
  summary.affine_from_projective = h;
  const Eigen::Matrix4d h_inv = h.inverse();
  for (const auto& p : cameras) summary.cameras.push_back(p * h_inv);
  if (summary.plane_residual > options.plane_residual_warning)
    summary.warnings.push_back("the " + std::to_string(m) + " vanishing points fit one plane at infinity only to " +
                               internal::FormatNumber(summary.plane_residual) +
                               " (relative): a vanishing point or its match across the images is off");
  summary.termination = SolverTermination::kConverged;
  summary.message = "plane at infinity from " + std::to_string(m) + " vanishing points, residual " +
                    internal::FormatNumber(summary.plane_residual);
  summary.time_ms = MsSince(start);
  return summary;
}

bool MetricUpgradeOptions::Check(std::string* error) const {
  if (!(rotation_residual_warning > 0)) {
    *error = "rotation_residual_warning must be positive";
    return false;
  }
  return true;
}

bool DecomposeProjectionMatrix(const Matrix34d& P, Eigen::Matrix3d* K, Eigen::Matrix3d* R, Eigen::Vector3d* t) {
  if (!P.allFinite()) return false;
  Eigen::Matrix3d m = P.leftCols<3>();
  const double det = m.determinant();
  if (!(std::abs(det) > 1e-300) || !(std::abs(det) > 1e-14 * std::pow(m.norm(), 3))) return false;
  const double sign = det > 0 ? 1.0 : -1.0;
  m *= sign;
  // RQ through the QR of the row-reversed transpose: with J the reversal, (J m)^T = Q U gives
  // m = (J U^T J) (J Q^T), an upper triangular times an orthogonal matrix.
  Eigen::Matrix3d j = Eigen::Matrix3d::Zero();
  j(0, 2) = j(1, 1) = j(2, 0) = 1.0;
  Eigen::HouseholderQR<Eigen::Matrix3d> qr((j * m).transpose());
  const Eigen::Matrix3d q = qr.householderQ();
  const Eigen::Matrix3d u = qr.matrixQR().triangularView<Eigen::Upper>();
  Eigen::Matrix3d k = j * u.transpose() * j;
  Eigen::Matrix3d r = j * q.transpose();
  const Eigen::Vector3d d = k.diagonal().cwiseSign();
  k = k * d.asDiagonal();
  r = d.asDiagonal() * r;
  const double scale = k(2, 2);
  *K = k / scale;
  *R = r;
  *t = (sign / scale) * K->inverse() * P.col(3);
  return K->allFinite() && R->allFinite() && t->allFinite();
}

MetricUpgradeSummary UpgradeToMetric(const std::vector<Matrix34d>& affine_cameras,
                                     const std::vector<Eigen::Matrix3d>& K,
                                     const std::vector<Eigen::Vector4d>& affine_points,
                                     const MetricUpgradeOptions& options) {
  const auto start = Clock::now();
  MetricUpgradeSummary summary;
  auto fail = [&](std::string message) { return FailedSummary(summary, std::move(message), start); };
  std::string error;
  if (!options.Check(&error))
    return FailedSummary(summary, "bad options: " + error, start, SolverTermination::kInvalidInput);
  const int n = static_cast<int>(affine_cameras.size());
  if (n < 1 || K.size() != affine_cameras.size()) return fail("one intrinsic matrix per camera is needed");
  // Each view: B_i C B_i^T = s_i I with B_i = K_i^-1 M_i normalised; unknowns the 6 entries of
  // C and the n scales, a homogeneous linear system.
  std::vector<Eigen::Matrix3d> b(n);
  for (int i = 0; i < n; ++i) {
    if (!affine_cameras[i].allFinite() || !K[i].allFinite()) return fail("a camera or K is not finite");
    if (!(std::abs(K[i].determinant()) > 0)) return fail("K of view " + std::to_string(i) + " is singular");
    b[i] = K[i].inverse() * affine_cameras[i].leftCols<3>();
    if (!(std::abs(b[i].determinant()) > 1e-14 * std::pow(b[i].norm(), 3)))
      return fail("camera " + std::to_string(i) + " has a singular left 3x3 (its centre is at infinity)");
    b[i] /= b[i].norm();
  }
  const int pairs[6][2] = {{0, 0}, {0, 1}, {0, 2}, {1, 1}, {1, 2}, {2, 2}};
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(6 * n, 6 + n);
  for (int i = 0; i < n; ++i) {
    for (int e = 0; e < 6; ++e) {
      const int r = pairs[e][0], c = pairs[e][1];
      for (int u = 0; u < 6; ++u) {
        const int p = pairs[u][0], q = pairs[u][1];
        double coefficient = b[i](r, p) * b[i](c, q);
        if (p != q) coefficient += b[i](r, q) * b[i](c, p);
        a(6 * i + e, u) = coefficient;
      }
      if (r == c) a(6 * i + e, 6 + i) = -1.0;
    }
  }
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeFullV);
  Eigen::VectorXd z = svd.matrixV().col(5 + n);
  if (z.tail(n).sum() < 0) z = -z;
  Eigen::Matrix3d c;
  for (int u = 0; u < 6; ++u) c(pairs[u][0], pairs[u][1]) = c(pairs[u][1], pairs[u][0]) = z(u);
  Eigen::LLT<Eigen::Matrix3d> llt(c);
  if (llt.info() != Eigen::Success || !(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(c).eigenvalues()(0) > 0))
    return fail(
        "the intrinsics do not fit the affine reconstruction (the transported absolute conic is not positive "
        "definite): wrong K, or the plane at infinity is wrong");
  Eigen::Matrix4d g = Eigen::Matrix4d::Identity();
  g.topLeftCorner<3, 3>() = llt.matrixL();
  g /= std::cbrt(g.topLeftCorner<3, 3>().determinant());
  g(3, 3) = 1.0;
  Eigen::Matrix4d h = g.inverse();
  // Cheirality: the upgrade leaves a reflection free; the points must lie in front.
  auto depth_votes = [&](const Eigen::Matrix4d& metric_from_affine) {
    int votes = 0;
    const Eigen::Matrix4d g_inv = metric_from_affine.inverse();
    for (const auto& pa : affine_cameras) {
      const Matrix34d p = pa * g_inv;
      const double det_sign = p.leftCols<3>().determinant() > 0 ? 1.0 : -1.0;
      for (const auto& xa : affine_points) {
        const Eigen::Vector4d x = metric_from_affine * xa;
        const double depth = det_sign * p.row(2).dot(x) * x(3);
        votes += depth > 0 ? 1 : (depth < 0 ? -1 : 0);
      }
    }
    return votes;
  };
  if (depth_votes(h) < 0) h = Eigen::Vector4d(1, 1, 1, -1).asDiagonal() * h;
  summary.metric_from_affine = h;
  const Eigen::Matrix4d h_inv = h.inverse();
  for (int i = 0; i < n; ++i) {
    const Matrix34d p = affine_cameras[i] * h_inv;
    const Eigen::Matrix3d bi = K[i].inverse() * p.leftCols<3>();
    const double s = std::cbrt(bi.determinant());
    Eigen::JacobiSVD<Eigen::Matrix3d> svd_b(bi / s, Eigen::ComputeFullU | Eigen::ComputeFullV);
    MetricCamera cam;
    cam.K = K[i] / K[i](2, 2);
    cam.cam_from_world_rotation = svd_b.matrixU() * svd_b.matrixV().transpose();
    cam.cam_from_world_translation = K[i].inverse() * p.col(3) / s;
    summary.max_rotation_residual =
        std::max(summary.max_rotation_residual, (bi / s - cam.cam_from_world_rotation).norm() / std::sqrt(3.0));
    summary.cameras.push_back(cam);
  }
  if (summary.max_rotation_residual > options.rotation_residual_warning)
    summary.warnings.push_back("the intrinsics fit the affine cameras only to " +
                               internal::FormatNumber(summary.max_rotation_residual) +
                               " (relative deviation from a rotation): check K and the vanishing points");
  summary.termination = SolverTermination::kConverged;
  summary.message = "metric upgrade of " + std::to_string(n) + " cameras, rotation residual " +
                    internal::FormatNumber(summary.max_rotation_residual);
  summary.time_ms = MsSince(start);
  return summary;
}

std::vector<Eigen::Vector4d> TransformPoints(const Eigen::Matrix4d& b_from_a,
                                             const std::vector<Eigen::Vector4d>& points) {
  std::vector<Eigen::Vector4d> out;
  out.reserve(points.size());
  for (const auto& x : points) out.push_back(Canonical(b_from_a * x));
  return out;
}

bool AlignSimilarity(const std::vector<Eigen::Vector3d>& points_a, const std::vector<Eigen::Vector3d>& points_b,
                     Similarity3d* b_from_a) {
  const size_t n = points_a.size();
  if (n < 3 || points_b.size() != n) return false;
  Eigen::Vector3d mean_a = Eigen::Vector3d::Zero(), mean_b = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < n; ++i) {
    if (!points_a[i].allFinite() || !points_b[i].allFinite()) return false;
    mean_a += points_a[i];
    mean_b += points_b[i];
  }
  mean_a /= static_cast<double>(n);
  mean_b /= static_cast<double>(n);
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  double var_a = 0.0;
  for (size_t i = 0; i < n; ++i) {
    cov += (points_b[i] - mean_b) * (points_a[i] - mean_a).transpose();
    var_a += (points_a[i] - mean_a).squaredNorm();
  }
  cov /= static_cast<double>(n);
  var_a /= static_cast<double>(n);
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(cov, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Vector3d sv = svd.singularValues();
  // Points of a on a line leave the rotation about it free.
  if (!(var_a > 0) || !(sv(1) > 1e-12 * sv(0))) return false;
  Eigen::Vector3d d = Eigen::Vector3d::Ones();
  if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0) d(2) = -1.0;
  b_from_a->rotation = svd.matrixU() * d.asDiagonal() * svd.matrixV().transpose();
  b_from_a->scale = sv.dot(d) / var_a;
  b_from_a->translation = mean_b - b_from_a->scale * b_from_a->rotation * mean_a;
  return true;
}

}  // namespace facet
