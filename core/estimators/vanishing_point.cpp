#include "core/estimators/vanishing_point.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include <Eigen/Dense>

namespace facet {
namespace {

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

// Two unit vectors spanning the plane orthogonal to the unit vector v.
Eigen::Matrix<double, 3, 2> TangentBasis(const Eigen::Vector3d& v) {
  Eigen::Index smallest;
  v.cwiseAbs().minCoeff(&smallest);
  const Eigen::Vector3d e1 = v.cross(Eigen::Vector3d::Unit(smallest)).normalized();
  Eigen::Matrix<double, 3, 2> basis;
  basis.col(0) = e1;
  basis.col(1) = v.cross(e1);
  return basis;
}

// Levenberg-Marquardt over the unit sphere; returns the number of accepted steps.
int Refine(const std::vector<ConditionedSegment>& segments, int max_iterations, Eigen::Vector3d* v) {
  double cost = Cost(segments, *v);
  double lambda = 1e-3;
  int accepted = 0;
  const int n = static_cast<int>(segments.size());
  Eigen::MatrixXd jacobian(n, 2);
  Eigen::VectorXd residuals(n);
  for (int iteration = 0; iteration < max_iterations; ++iteration) {
    if (!std::isfinite(cost) || cost == 0.0) break;
    const Eigen::Matrix<double, 3, 2> basis = TangentBasis(*v);
    for (int i = 0; i < n; ++i) {
      Eigen::RowVector3d gradient;
      residuals(i) = Residual(segments[i], *v, &gradient);
      jacobian.row(i) = gradient * basis;
    }
    const Eigen::Matrix2d jtj = jacobian.transpose() * jacobian;
    const Eigen::Vector2d jtr = jacobian.transpose() * residuals;
    bool improved = false;
    while (lambda < 1e12) {
      Eigen::Matrix2d damped = jtj;
      damped.diagonal() += lambda * (jtj.diagonal().array() + 1e-12).matrix();
      const Eigen::Vector2d step = -damped.ldlt().solve(jtr);
      if (!step.allFinite()) break;
      const Eigen::Vector3d candidate = (*v + basis * step).normalized();
      const double candidate_cost = Cost(segments, candidate);
      if (candidate_cost < cost) {
        const double decrease = cost - candidate_cost;
        *v = candidate;
        cost = candidate_cost;
        lambda = std::max(lambda * 0.1, 1e-12);
        ++accepted;
        improved = decrease > 1e-15 * cost && step.norm() > 1e-14;
        break;
      }
      lambda *= 10.0;
    }
    if (!improved) break;
  }
  return accepted;
}

double Rms(const std::vector<double>& values) {
  double sum = 0.0;
  for (double x : values) sum += x * x;
  return values.empty() ? 0.0 : std::sqrt(sum / values.size());
}

}  // namespace

bool VanishingPointOptions::Check(std::string* error) const {
  if (!(conditioning_scale_px > 0.0) || !std::isfinite(conditioning_scale_px) ||
      !conditioning_center_px.allFinite()) {
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
  VanishingPointSummary summary;
  if (!options.Check(&summary.message)) return summary;
  const int n = static_cast<int>(segments_px.size());
  if (n < 2) {
    summary.message = "needs at least 2 segments, got " + std::to_string(n);
    return summary;
  }

  // Conditioned coordinates: a similarity, so distances scale by 1 / scale and back.
  const double scale = options.conditioning_scale_px;
  std::vector<ConditionedSegment> segments;
  segments.reserve(n);
  Eigen::MatrixXd lines(n, 3);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector4d& s = segments_px[i];
    if (!s.allFinite()) {
      summary.message = "segment " + std::to_string(i) + " has a non-finite coordinate";
      return summary;
    }
    const Eigen::Vector2d a = (s.head<2>() - options.conditioning_center_px) / scale;
    const Eigen::Vector2d b = (s.tail<2>() - options.conditioning_center_px) / scale;
    if ((b - a).norm() * scale < 1e-9 * std::max(1.0, scale)) {
      std::ostringstream out;
      out << "segment " << i << " has zero length (" << s.x() << ", " << s.y() << ") - (" << s.z() << ", "
          << s.w() << ")";
      summary.message = out.str();
      return summary;
    }
    // a x b is the segment's line scaled by its length: the length weighting for free.
    lines.row(i) = Eigen::Vector3d(a.x(), a.y(), 1.0).cross(Eigen::Vector3d(b.x(), b.y(), 1.0)).transpose();
    segments.push_back(MakeConditionedSegment(a, b));
  }

  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(lines, Eigen::ComputeFullV);
  const Eigen::Vector3d singular = svd.singularValues();
  summary.line_spread = singular(0) > 0.0 ? singular(1) / singular(0) : 0.0;
  if (summary.line_spread < kMinLineSpread) {
    summary.message = "all segments lie on one line, so they do not fix a vanishing point";
    return summary;
  }
  Eigen::Vector3d v = svd.matrixV().col(2);

  auto residuals_px = [&](const Eigen::Vector3d& vp) {
    std::vector<double> out(n);
    for (int i = 0; i < n; ++i) out[i] = std::abs(Residual(segments[i], vp, nullptr)) * scale;
    return out;
  };
  summary.initial_rms_px = Rms(residuals_px(v));
  if (options.refine) {
    summary.iterations = Refine(segments, options.max_iterations, &v);
    summary.refined = summary.iterations > 0;
  }
  if (v.z() < 0.0) v = -v;
  if (!v.allFinite()) {
    summary.message = "the vanishing point is not finite (numerical failure)";
    return summary;
  }
  summary.vp_conditioned = v;
  summary.residuals_px = residuals_px(v);
  summary.final_rms_px = Rms(summary.residuals_px);
  summary.distance_in_scales = v.z() > 0.0 ? v.head<2>().norm() / v.z() : kInfinity;

  // Undo the conditioning: v_px ~ T^-1 v with T = [I / scale, -center / scale; 0, 1].
  Eigen::Vector3d vp_px(scale * v.x() + options.conditioning_center_px.x() * v.z(),
                        scale * v.y() + options.conditioning_center_px.y() * v.z(), v.z());
  summary.vp_px = vp_px.normalized();
  summary.success = true;
  return summary;
}

}  // namespace facet
