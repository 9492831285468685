#include "core/estimators/vanishing_point.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

#include <Eigen/Dense>

#include "core/geometry/tangent_basis.h"
#include "core/optim/damped_normal_step.h"
#include "core/optim/levenberg_marquardt.h"
#include "core/util/eigen_decompositions.h"
#include "core/util/stats.h"
#include "core/util/timer.h"

namespace facet {
namespace {

using internal::FailedSummary;

constexpr double kInfinity = std::numeric_limits<double>::infinity();
// All segments on one line: the second smallest singular value vanishes up to rounding.
constexpr double kMinLineSpread = 1e-10;

// One segment in conditioned coordinates, with the constants of its residual
// r(v) = g.v / |M v|: g = a x m (a endpoint, m midpoint), M v = first two entries of m x v.
struct ConditionedSegment {
  Eigen::Vector3d g;
  Eigen::Matrix<double, 2, 3> m_cross;
};

ConditionedSegment MakeConditionedSegment(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d mid = 0.5 * (a + b);
  ConditionedSegment s;
  s.g = Eigen::Vector3d(a.x(), a.y(), 1.0).cross(Eigen::Vector3d(mid.x(), mid.y(), 1.0));
  s.m_cross << 0.0, -1.0, mid.y(), 1.0, 0.0, -mid.x();
  return s;
}

// Signed endpoint distance and its gradient with respect to v (homogeneous, degree 0).
double Residual(const ConditionedSegment& s, const Eigen::Vector3d& v, Eigen::RowVector3d* gradient) {
  const Eigen::Vector2d mv = s.m_cross * v;
  const double n = mv.norm();
  if (n == 0.0) {
    if (gradient) gradient->setZero();
    return kInfinity;
  }
  const double num = s.g.dot(v);
  if (gradient) *gradient = s.g.transpose() / n - (num / (n * n * n)) * (mv.transpose() * s.m_cross);
  return num / n;
}

double Cost(const std::vector<ConditionedSegment>& segments, const Eigen::Vector3d& v) {
  double cost = 0.0;
  for (const auto& s : segments) {
    const double r = Residual(s, v, nullptr);
    cost += r * r;
  }
  return cost;
}

// The refinement's least-squares problem for the driver: v on the unit sphere, each step
// taken in the plane tangent to it at v and normalised back onto the sphere.
class SphereProblem {
 public:
  SphereProblem(const std::vector<ConditionedSegment>& segments, Eigen::Vector3d* v)
      : segments_(segments), v_(v), jacobian_(segments.size(), 2), residuals_(segments.size()) {}

  bool Linearize() {
    basis_ = internal::TangentBasis(*v_);
    for (size_t i = 0; i < segments_.size(); ++i) {
      Eigen::RowVector3d gradient;
      residuals_(i) = Residual(segments_[i], *v_, &gradient);
      jacobian_.row(i) = gradient * basis_;
    }
    normal_ = jacobian_.transpose() * jacobian_;
    gradient_ = jacobian_.transpose() * residuals_;
    damping_ = (normal_.diagonal().array() + 1e-12).matrix();  // the floor is added, not a max
    return false;
  }

  LmStepStatus Step(double lambda, LmTrial* trial) {
    const Eigen::Vector2d step = DampedNormalStep(normal_, gradient_, lambda, damping_);
    if (!step.allFinite()) return LmStepStatus::kSolveFailed;
    candidate_ = (*v_ + basis_ * step).normalized();
    trial->cost = Cost(segments_, candidate_);
    trial->step_squared_norm = step.squaredNorm();
    return LmStepStatus::kSolved;
  }

  void Accept() { *v_ = candidate_; }

 private:
  const std::vector<ConditionedSegment>& segments_;
  Eigen::Vector3d* v_;
  Eigen::MatrixXd jacobian_;
  Eigen::VectorXd residuals_;
  Eigen::Matrix<double, 3, 2> basis_;
  Eigen::Matrix2d normal_;
  Eigen::Vector2d gradient_, damping_;
  Eigen::Vector3d candidate_;
};

// Levenberg-Marquardt over the unit sphere from *v (the algebraic fit).
LmResult Refine(const std::vector<ConditionedSegment>& segments, int max_iterations, Eigen::Vector3d* v) {
  LmOptions options = TenfoldLmOptions(max_iterations);
  // Marquardt's factors of 10 from lambda = 1e-3, rejections up to 1e12; a damped system
  // without a finite solution ends the fit (two unknowns: it only fails on degenerate data).
  options.initial_lambda = 1e-3;
  options.max_lambda = 1e12;
  options.stop_on_failed_solve = true;
  options.relative_decrease_tolerance = 1e-15;
  options.min_step_squared_norm = 1e-28;  // |step| <= 1e-14 on the unit sphere
  SphereProblem problem(segments, v);
  return MinimizeLevenbergMarquardt(Cost(segments, *v), options, problem);
}

double SumOfSquares(const std::vector<double>& values) {
  double sum = 0.0;
  for (double x : values) sum += x * x;
  return sum;
}

// The summary's covariances at the result v (conditioned, unit norm); cost_conditioned is the
// sum of squared residuals in conditioned units.
void EstimateCovariance(const std::vector<ConditionedSegment>& segments, const Eigen::Vector3d& v,
                        const VanishingPointOptions& options, double cost_conditioned, VanishingPointSummary* summary) {
  const int n = static_cast<int>(segments.size());
  const Eigen::Matrix<double, 3, 2> basis = internal::TangentBasis(v);
  Eigen::Matrix2d normal = Eigen::Matrix2d::Zero();
  for (const ConditionedSegment& s : segments) {
    Eigen::RowVector3d gradient;
    Residual(s, v, &gradient);
    const Eigen::RowVector2d row = gradient * basis;
    normal += row.transpose() * row;
  }
  const Eigen::FullPivLU<Eigen::Matrix2d> lu(normal);
  if (!lu.isInvertible()) return;
  const double sigma_squared = cost_conditioned / (n - 2);
  const Eigen::Matrix2d tangent = sigma_squared * lu.inverse();
  summary->vp_conditioned_covariance = basis * tangent * basis.transpose();
  if (summary->distance_in_scales == kInfinity) return;
  // (u, v) = scale (x / w, y / w) + centre for v = (x, y, w).
  const double scale = options.conditioning_scale_px;
  Eigen::Matrix<double, 2, 3> jacobian;
  jacobian << 1.0 / v.z(), 0.0, -v.x() / (v.z() * v.z()), 0.0, 1.0 / v.z(), -v.y() / (v.z() * v.z());
  jacobian *= scale;
  summary->point_covariance_px2 = jacobian * summary->vp_conditioned_covariance * jacobian.transpose();
}

}  // namespace

bool VanishingPointOptions::Check(std::string* error) const {
  if (!(conditioning_scale_px > 0.0) || !std::isfinite(conditioning_scale_px) || !conditioning_center_px.allFinite()) {
    *error = "vanishing point: the conditioning centre and scale must be finite, the scale positive";
    return false;
  }
  if (max_iterations < 0) {
    *error = "vanishing point: max_iterations must be >= 0";
    return false;
  }
  return true;
}

double SegmentVanishingPointResidualPx(const Eigen::Vector4d& segment_px, const Eigen::Vector3d& vp_px) {
  const ConditionedSegment s = MakeConditionedSegment(segment_px.head<2>(), segment_px.tail<2>());
  return std::abs(Residual(s, vp_px, nullptr));
}

double SegmentVanishingPointSignedDistance(const Eigen::Vector4d& segment, const Eigen::Vector3d& vp) {
  return Residual(MakeConditionedSegment(segment.head<2>(), segment.tail<2>()), vp, nullptr);
}

VanishingPointSummary FitVanishingPoint(const std::vector<Eigen::Vector4d>& segments_px,
                                        const VanishingPointOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  VanishingPointSummary summary;
  std::string error;
  if (!options.Check(&error)) return FailedSummary(summary, error, start, SolverTermination::kInvalidInput);
  const int n = static_cast<int>(segments_px.size());
  if (n < 2)
    return FailedSummary(summary, "needs at least 2 segments, got " + std::to_string(n), start,
                         SolverTermination::kInvalidInput);

  // Conditioned coordinates: a similarity, so distances scale by 1 / scale and back.
  const double scale = options.conditioning_scale_px;
  std::vector<ConditionedSegment> segments;
  segments.reserve(n);
  Eigen::MatrixXd lines(n, 3);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector4d& s = segments_px[i];
    if (!s.allFinite())
      return FailedSummary(summary, "segment " + std::to_string(i) + " has a non-finite coordinate", start,
                           SolverTermination::kInvalidInput);
    const Eigen::Vector2d a = (s.head<2>() - options.conditioning_center_px) / scale;
    const Eigen::Vector2d b = (s.tail<2>() - options.conditioning_center_px) / scale;
    if ((b - a).norm() * scale < 1e-9 * std::max(1.0, scale)) {
      std::ostringstream out;
      out << "segment " << i << " has zero length (" << s.x() << ", " << s.y() << ") - (" << s.z() << ", " << s.w()
          << ")";
      return FailedSummary(summary, out.str(), start, SolverTermination::kInvalidInput);
    }
    // a x b is the segment's line scaled by its length: the length weighting for free.
    lines.row(i) = Eigen::Vector3d(a.x(), a.y(), 1.0).cross(Eigen::Vector3d(b.x(), b.y(), 1.0)).transpose();
    segments.push_back(MakeConditionedSegment(a, b));
  }

  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(lines, Eigen::ComputeFullV);
  // min(n, 3) values: two segments give two (a fixed Vector3d here read past them).
  const Eigen::VectorXd singular = svd.singularValues();
  summary.line_spread = singular(0) > 0.0 ? singular(1) / singular(0) : 0.0;
  if (summary.line_spread < kMinLineSpread)
    return FailedSummary(summary, "all segments lie on one line, so they do not fix a vanishing point", start);
  Eigen::Vector3d v = svd.matrixV().col(2);

  auto residuals_px = [&](const Eigen::Vector3d& vp) {
    std::vector<double> out(n);
    for (int i = 0; i < n; ++i) out[i] = std::abs(Residual(segments[i], vp, nullptr)) * scale;
    return out;
  };
  const std::vector<double> initial_residuals_px = residuals_px(v);
  summary.initial_rms_px = internal::RootMeanSquare(initial_residuals_px);
  summary.initial_cost = SumOfSquares(initial_residuals_px);
  summary.termination = SolverTermination::kConverged;
  if (options.refine) {
    const LmResult refinement = Refine(segments, options.max_iterations, &v);
    summary.iterations = refinement.accepted_steps;
    summary.refined = summary.iterations > 0;
    if (refinement.termination == LmTermination::kMaxIterations)
      summary.termination = SolverTermination::kMaxIterations;
  }
  if (v.z() < 0.0) v = -v;
  if (!v.allFinite()) return FailedSummary(summary, "the vanishing point is not finite (numerical failure)", start);
  summary.vp_conditioned = v;
  summary.residuals_px = residuals_px(v);
  summary.final_rms_px = internal::RootMeanSquare(summary.residuals_px);
  summary.final_cost = SumOfSquares(summary.residuals_px);
  summary.distance_in_scales = v.z() > 0.0 ? v.head<2>().norm() / v.z() : kInfinity;

  // Undo the conditioning: v_px ~ T^-1 v with T = [I / scale, -center / scale; 0, 1].
  Eigen::Vector3d vp_px(scale * v.x() + options.conditioning_center_px.x() * v.z(),
                        scale * v.y() + options.conditioning_center_px.y() * v.z(), v.z());
  summary.vp_px = vp_px.normalized();
  if (n > 2) EstimateCovariance(segments, v, options, summary.final_cost / (scale * scale), &summary);
  summary.time_ms = internal::MsSince(start);
  return summary;
}

}  // namespace facet
