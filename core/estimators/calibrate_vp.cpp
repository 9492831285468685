#include "core/estimators/calibrate_vp.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include <Eigen/Dense>

#include "core/geometry/camera.h"
#include "core/estimators/vanishing_point.h"
#include "core/util/format.h"

namespace facet {
namespace {

// A vanishing point farther from the image centre than this many half image sizes is
// treated as at infinity: its direction is within ~1e-5 rad of the image plane, closer than
// any segment can resolve, and the three-point principal-point solve is singular there.
constexpr double kAtInfinityDistance = 1e5;
// Warning thresholds, in degrees between a vanishing direction and the image plane or the
// optical axis: there the focal length depends on tiny angles and is poorly constrained.
constexpr double kFarVanishingPointDeg = 2.0;
constexpr double kCentralVanishingPointDeg = 5.0;
// Second / largest singular value of a family's stacked lines below which its segments are
// nearly on one line.
constexpr double kNearlyCollinearSpread = 1e-3;

// Standard deviation, in half image sizes, of the weak prior that keeps a solved principal
// point near the image centre where the segments leave it loose (5 %: 16 px at 640 x 480).
constexpr double kPrincipalPointPriorSigma = 0.05;
// When the closed form fails and the joint fit starts from the image centre, the result is
// accepted only if its residuals stay near those of free vanishing points.
constexpr double kMaxJointRmsRatio = 2.0;
constexpr double kJointRmsSlackPx = 0.1;
// Smallest segment noise (conditioned units) assumed when weighting the priors.
constexpr double kNoiseFloor = 3e-8;
// Rounds of refitting without the flagged segments and flagging again.
constexpr int kMaxOutlierRounds = 5;

constexpr double kRadToDeg = 180.0 / M_PI;

std::string Fmt(double x) { return internal::FormatNumber(x, 6); }

std::string FamilyName(int axis) { return std::string("family ") + AxisName(static_cast<Axis>(axis)); }

VpCalibrationSummary Fail(VpCalibrationSummary summary, std::string message,
                          std::chrono::steady_clock::time_point start) {
  summary.success = false;
  summary.message = std::move(message);
  summary.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

// Chooses the signs of the vanishing directions (columns of d, world x, y, z in the camera
// frame): det = +1, world z up in the image (negative camera-y component), and x and y both
// towards their vanishing points in front of the camera where possible; when they cannot
// both be (one points forward, the other backward), the bisector x + y points forward.
Eigen::Matrix3d ChooseAxisSigns(const Eigen::Matrix3d& d) {
  Eigen::Matrix3d best = d;
  double best_score = -1e300;
  for (int signs = 0; signs < 8; ++signs) {
    Eigen::Matrix3d r = d;
    for (int k = 0; k < 3; ++k)
      if (signs & (1 << k)) r.col(k) *= -1.0;
    if (r.determinant() <= 0.0) continue;
    // z up dominates, then the forward rule; ties keep the first candidate.
    const double score = (r(1, 2) < 0.0 ? 10.0 : 0.0) + r(2, 0) + r(2, 1);
    if (score > best_score + 1e-15) {
      best_score = score;
      best = r;
    }
  }
  return best;
}

Eigen::Matrix3d NearestRotation(const Eigen::Matrix3d& m) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d u = svd.matrixU();
  if ((u * svd.matrixV().transpose()).determinant() < 0.0) u.col(2) *= -1.0;
  return u * svd.matrixV().transpose();
}

// [d]x: the matrix of the cross product d x (.).
Eigen::Matrix3d Cross(const Eigen::Vector3d& d) {
  Eigen::Matrix3d m;
  m << 0.0, -d.z(), d.y(), d.z(), 0.0, -d.x(), -d.y(), d.x(), 0.0;
  return m;
}

// One segment of the joint fit in conditioned coordinates, with the constants of its signed
// endpoint distance r(v) = g.v / |M v| (core/estimators/vanishing_point.h): g = a x m (a an endpoint,
// m the midpoint), M v = the first two entries of m x v.
struct JointSegment {
  Eigen::Vector3d g;
  Eigen::Matrix<double, 2, 3> m_cross;
  int axis;
  int input_index;
};

JointSegment MakeJointSegment(const Eigen::Vector2d& a, const Eigen::Vector2d& b, int axis, int input_index) {
  const Eigen::Vector2d mid = 0.5 * (a + b);
  JointSegment s;
  s.g = Eigen::Vector3d(a.x(), a.y(), 1.0).cross(Eigen::Vector3d(mid.x(), mid.y(), 1.0));
  s.m_cross << 0.0, -1.0, mid.y(), 1.0, 0.0, -mid.x();
  s.axis = axis;
  s.input_index = input_index;
  return s;
}

// The camera of the joint fit, conditioned: focal length and principal point in units of
// the conditioning scale about the image centre.
struct JointCamera {
  double f = 1.0;
  Eigen::Vector2d pp = Eigen::Vector2d::Zero();
  Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
};

// What the joint fit solves and which extra residuals it carries. Parameters, in order:
// log f (when solved), the principal point (when solved), a left rotation increment.
struct JointProblem {
  std::vector<JointSegment> segments;
  bool solve_focal = true;
  bool solve_pp = false;
  double pp_prior_weight = 0.0;     // residuals pp_prior_weight * pp (prior at the centre)
  double focal_prior_weight = 0.0;  // residual focal_prior_weight * (f - focal_prior)
  double focal_prior = 0.0;
  bool use_horizon = false;
  std::array<Eigen::Vector2d, 2> horizon;  // conditioned points on the horizon

  int NumParams() const { return (solve_focal ? 1 : 0) + (solve_pp ? 2 : 0) + 3; }
  int NumResiduals() const {
    return static_cast<int>(segments.size()) + (use_horizon ? 2 : 0) + (pp_prior_weight > 0 ? 2 : 0) +
           (focal_prior_weight > 0 ? 1 : 0);
  }

  JointCamera Apply(const JointCamera& c, const Eigen::VectorXd& delta) const {
    JointCamera out = c;
    int k = 0;
    if (solve_focal) out.f = c.f * std::exp(delta(k++));
    if (solve_pp) {
      out.pp = c.pp + delta.segment<2>(k);
      k += 2;
    }
    out.r = RotationFromAngleAxis(delta.segment<3>(k)) * c.r;
    return out;
  }

  void Residuals(const JointCamera& c, Eigen::VectorXd* out) const {
    out->resize(NumResiduals());
    Eigen::Matrix3d k = Eigen::Matrix3d::Identity();
    k(0, 0) = k(1, 1) = c.f;
    k(0, 2) = c.pp.x();
    k(1, 2) = c.pp.y();
    const Eigen::Matrix3d vps = k * c.r;
    int i = 0;
    for (const JointSegment& s : segments) {
      const Eigen::Vector3d v = vps.col(s.axis);
      const double n = (s.m_cross * v).norm();
      (*out)(i++) = n > 0.0 ? s.g.dot(v) / n : 1e10;
    }
    if (use_horizon) {
      // The horizon is the image of the plane orthogonal to the vertical d = R e_z: points p
      // with (p - c).d_xy + f d_z = 0, at distance ((p - c).d_xy + f d_z) / |d_xy|.
      const Eigen::Vector3d d = c.r.col(2);
      const double n = d.head<2>().norm();
      for (const Eigen::Vector2d& p : horizon)
        (*out)(i++) = n > 0.0 ? ((p - c.pp).dot(d.head<2>()) + c.f * d.z()) / n : 1e10;
    }
    if (pp_prior_weight > 0) {
      out->segment<2>(i) = pp_prior_weight * c.pp;
      i += 2;
    }
    if (focal_prior_weight > 0) (*out)(i++) = focal_prior_weight * (c.f - focal_prior);
  }

  // Analytic Jacobian (exact to rounding, which matters where only a weak prior fixes a
  // direction). With v = K d, d = R e_axis and the left increment d' = d + w x d:
  // dv/dlog f = f (d_x, d_y, 0), dv/dc = d_z I_2 (top rows), dv/dw = -K [d]x.
  void Jacobian(const JointCamera& c, Eigen::MatrixXd* jacobian) const {
    const int p = NumParams();
    jacobian->setZero(NumResiduals(), p);
    const int rotation_column = p - 3;
    Eigen::Matrix3d k = Eigen::Matrix3d::Identity();
    k(0, 0) = k(1, 1) = c.f;
    k(0, 2) = c.pp.x();
    k(1, 2) = c.pp.y();
    std::array<Eigen::Matrix<double, 3, Eigen::Dynamic>, 3> dv_dparams;
    for (int a = 0; a < 3; ++a) {
      const Eigen::Vector3d d = c.r.col(a);
      Eigen::Matrix<double, 3, Eigen::Dynamic>& m = dv_dparams[a];
      m.setZero(3, p);
      int col = 0;
      if (solve_focal) m.col(col++) << c.f * d.x(), c.f * d.y(), 0.0;
      if (solve_pp) {
        m(0, col++) = d.z();
        m(1, col++) = d.z();
      }
      m.rightCols<3>() = -k * Cross(d);
    }
    const Eigen::Matrix3d vps = k * c.r;
    int i = 0;
    for (const JointSegment& s : segments) {
      const Eigen::Vector3d v = vps.col(s.axis);
      const Eigen::Vector2d mv = s.m_cross * v;
      const double n = mv.norm();
      if (n > 0.0) {
        const Eigen::RowVector3d dr_dv = s.g.transpose() / n - (s.g.dot(v) / (n * n * n)) * (mv.transpose() * s.m_cross);
        jacobian->row(i) = dr_dv * dv_dparams[s.axis];
      }
      ++i;
    }
    if (use_horizon) {
      const Eigen::Vector3d d = c.r.col(2);
      const Eigen::Vector2d e = d.head<2>();
      const double n = e.norm();
      for (const Eigen::Vector2d& point : horizon) {
        if (n > 0.0) {
          const Eigen::Vector2d q = point - c.pp;
          const double r = (q.dot(e) + c.f * d.z()) / n;
          Eigen::RowVector3d dr_dd;
          dr_dd.head<2>() = (q / n - r * e / (n * n)).transpose();
          dr_dd(2) = c.f / n;
          int col = 0;
          if (solve_focal) (*jacobian)(i, col++) = c.f * d.z() / n;
          if (solve_pp) {
            (*jacobian)(i, col++) = -e.x() / n;
            (*jacobian)(i, col++) = -e.y() / n;
          }
          jacobian->block<1, 3>(i, rotation_column) = -dr_dd * Cross(d);
        }
        ++i;
      }
    }
    if (pp_prior_weight > 0) {
      const int col = solve_focal ? 1 : 0;
      (*jacobian)(i, col) = pp_prior_weight;
      (*jacobian)(i + 1, col + 1) = pp_prior_weight;
      i += 2;
    }
    if (focal_prior_weight > 0) (*jacobian)(i++, 0) = focal_prior_weight * c.f;
  }
};

// Levenberg-Marquardt on the joint problem; returns the number of accepted steps.
int RefineJointly(const JointProblem& problem, JointCamera* camera) {
  Eigen::VectorXd residuals, candidate;
  problem.Residuals(*camera, &residuals);
  double cost = residuals.squaredNorm();
  double lambda = 1e-4;
  int accepted = 0;
  Eigen::MatrixXd jacobian;
  for (int iteration = 0; iteration < 100 && std::isfinite(cost) && cost > 0.0; ++iteration) {
    problem.Jacobian(*camera, &jacobian);
    const Eigen::MatrixXd jtj = jacobian.transpose() * jacobian;
    const Eigen::VectorXd jtr = jacobian.transpose() * residuals;
    bool improved = false;
    while (lambda < 1e12) {
      Eigen::MatrixXd damped = jtj;
      damped.diagonal() += lambda * (jtj.diagonal().array() + 1e-12).matrix();
      const Eigen::VectorXd step = -damped.ldlt().solve(jtr);
      if (!step.allFinite()) break;
      const JointCamera next = problem.Apply(*camera, step);
      problem.Residuals(next, &candidate);
      const double candidate_cost = candidate.squaredNorm();
      if (candidate_cost < cost) {
        const double decrease = cost - candidate_cost;
        *camera = next;
        residuals = candidate;
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

double Median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  const size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + mid, values.end());
  const double upper = values[mid];
  if (values.size() % 2) return upper;
  return 0.5 * (upper + *std::max_element(values.begin(), values.begin() + mid));
}

// Largest angle in degrees between two of the segments in the image (orientations, so at
// most 90): the spread of their doubled-angle directions about their mean.
double AngleSpreadDeg(const std::vector<Eigen::Vector4d>& family) {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  std::vector<double> angles;
  angles.reserve(family.size());
  for (const Eigen::Vector4d& s : family) {
    const double angle = std::atan2(s.w() - s.y(), s.z() - s.x());
    angles.push_back(angle);
    mean += Eigen::Vector2d(std::cos(2 * angle), std::sin(2 * angle));
  }
  const double mean_angle = 0.5 * std::atan2(mean.y(), mean.x());
  double lo = 0.0, hi = 0.0;
  for (double angle : angles) {
    // Deviation from the mean orientation, wrapped into [-90, 90) degrees.
    double d = std::remainder(angle - mean_angle, M_PI);
    lo = std::min(lo, d);
    hi = std::max(hi, d);
  }
  return std::min(90.0, (hi - lo) * kRadToDeg);
}

// Largest angle in degrees of the triangle of three finite points.
double TriangleMaxAngleDeg(const std::array<Eigen::Vector2d, 3>& p) {
  double largest = 0.0;
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector2d u = p[(i + 1) % 3] - p[i], w = p[(i + 2) % 3] - p[i];
    const double angle = std::atan2(std::abs(u.x() * w.y() - u.y() * w.x()), u.dot(w));
    largest = std::max(largest, angle * kRadToDeg);
  }
  return largest;
}

// Thresholds of the degeneracy warnings.
constexpr double kMinAngleSpreadDeg = 2.0;
constexpr double kMaxTriangleAngleDeg = 85.0;

}  // namespace

bool VpCalibrationOptions::Check(std::string* error) const {
  if (width_px <= 0 || height_px <= 0) {
    *error = "image size must be positive, got " + std::to_string(width_px) + " x " + std::to_string(height_px);
    return false;
  }
  if (principal_point_mode == PrincipalPointMode::kFixed && !fixed_principal_point_px.allFinite()) {
    *error = "the fixed principal point is not finite";
    return false;
  }
  if (!std::isfinite(principal_point_prior_std_px)) {
    *error = "the principal point prior's standard deviation is not finite";
    return false;
  }
  if (!(fixed_focal_px >= 0.0) || !std::isfinite(fixed_focal_px)) {
    *error = "the fixed focal length must be finite and positive (0 to solve it), got " + Fmt(fixed_focal_px);
    return false;
  }
  const bool has_prior = focal_prior_px != 0.0 || focal_prior_std_px != 0.0;
  if (has_prior && (!(focal_prior_px > 0.0) || !(focal_prior_std_px > 0.0) || !std::isfinite(focal_prior_px) ||
                    !std::isfinite(focal_prior_std_px))) {
    *error = "the focal length prior needs a positive value and a positive standard deviation, got " +
             Fmt(focal_prior_px) + " +- " + Fmt(focal_prior_std_px) + " px";
    return false;
  }
  if (has_prior && fixed_focal_px > 0.0) {
    *error = "give either a fixed focal length or a focal length prior, not both";
    return false;
  }
  if (use_horizon && (!horizon_px.allFinite() || (horizon_px.head<2>() - horizon_px.tail<2>()).norm() <
                                                     1e-6 * std::max(width_px, height_px))) {
    *error = "the horizon needs two distinct finite points";
    return false;
  }
  if (warm_start && (!(warm_start_focal_px > 0.0) || !std::isfinite(warm_start_focal_px) ||
                     !warm_start_principal_point_px.allFinite() || !warm_start_rotation.allFinite())) {
    *error = "the warm start needs a finite positive focal length, principal point and rotation";
    return false;
  }
  if (!(outlier_threshold_sigmas > 0.0) || !(outlier_floor_px >= 0.0)) {
    *error = "the outlier threshold must be positive and its floor non-negative";
    return false;
  }
  return true;
}

VpCalibrationSummary CalibrateFromVanishingLines(const std::vector<Segment>& segments,
                                                 const VpCalibrationOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  VpCalibrationSummary summary;
  std::string error;
  if (!options.Check(&error)) return Fail(summary, error, start);
  const bool focal_fixed = options.fixed_focal_px > 0.0;
  const bool focal_prior = options.focal_prior_px > 0.0;

  // Families, keeping each segment's input index for the residuals and messages.
  std::array<std::vector<Eigen::Vector4d>, 3> family_segments;
  std::array<std::vector<int>, 3> family_indices;
  for (int i = 0; i < static_cast<int>(segments.size()); ++i) {
    const Segment& s = segments[i];
    const int axis = static_cast<int>(s.axis);
    if (axis < 0 || axis > 2) return Fail(summary, "segment " + std::to_string(i) + " has an invalid axis", start);
    const Eigen::Vector4d seg(s.a_px.x(), s.a_px.y(), s.b_px.x(), s.b_px.y());
    if (!seg.allFinite())
      return Fail(summary, FamilyName(axis) + ": segment " + std::to_string(i) + " has a non-finite coordinate", start);
    if ((s.b_px - s.a_px).norm() < 1e-9 * std::max(options.width_px, options.height_px))
      return Fail(summary,
                  FamilyName(axis) + ": segment " + std::to_string(i) + " has zero length (both ends at (" +
                      Fmt(s.a_px.x()) + ", " + Fmt(s.a_px.y()) + "))",
                  start);
    family_segments[axis].push_back(seg);
    family_indices[axis].push_back(i);
  }
  std::array<bool, 3> present{};
  int num_families = 0;
  std::string present_names;
  for (int a = 0; a < 3; ++a) {
    summary.segments_per_axis[a] = static_cast<int>(family_segments[a].size());
    if (family_segments[a].size() == 1)
      return Fail(summary, FamilyName(a) + " has only 1 segment; a family needs at least 2", start);
    present[a] = family_segments[a].size() >= 2;
    if (present[a]) {
      ++num_families;
      present_names += present_names.empty() ? AxisName(static_cast<Axis>(a)) : std::string(", ") + AxisName(static_cast<Axis>(a));
    }
  }
  const bool one_family_mode = num_families == 1 && options.use_horizon;
  if (num_families < 2 && !one_family_mode)
    return Fail(summary,
                "calibration needs at least two line families (x, y, z), got " +
                    (num_families == 0 ? std::string("none") : "only " + present_names) +
                    " (one horizontal family also works with the horizon and a known focal length)",
                start);
  if (one_family_mode && present[2])
    return Fail(summary,
                "with a single family it must be horizontal (x or y): the vertical family and the horizon leave the "
                "heading free",
                start);
  if (one_family_mode && !focal_fixed && !focal_prior)
    return Fail(summary,
                "one family with the horizon needs a known focal length (fixed or a prior): a vanishing point on the "
                "horizon is consistent with any focal length",
                start);

  // Conditioning shared by all families, so that the intrinsics solve sees numbers of order 1.
  const Eigen::Vector2d center_px((options.width_px - 1) / 2.0, (options.height_px - 1) / 2.0);
  const double scale_px = std::max(options.width_px, options.height_px) / 2.0;
  VanishingPointOptions vp_options;
  vp_options.conditioning_center_px = center_px;
  vp_options.conditioning_scale_px = scale_px;

  std::array<Eigen::Vector3d, 3> v;  // conditioned, unit norm
  std::array<bool, 3> at_infinity{};
  summary.segment_residuals_px.assign(segments.size(), 0.0);
  double independent_sum_sq = 0.0;
  for (int a = 0; a < 3; ++a) {
    if (!present[a]) continue;
    summary.family_angle_spread_deg[a] = AngleSpreadDeg(family_segments[a]);
    const VanishingPointSummary fit = FitVanishingPoint(family_segments[a], vp_options);
    if (!fit.success) return Fail(summary, FamilyName(a) + ": " + fit.message, start);
    v[a] = fit.vp_conditioned;
    summary.vanishing_points[a] = fit.vp_px;
    at_infinity[a] = fit.distance_in_scales > kAtInfinityDistance;
    summary.vanishing_point_at_infinity[a] = at_infinity[a];
    summary.vanishing_point_rms_px[a] = fit.final_rms_px;
    for (size_t k = 0; k < fit.residuals_px.size(); ++k) {
      summary.segment_residuals_px[family_indices[a][k]] = fit.residuals_px[k];
      independent_sum_sq += fit.residuals_px[k] * fit.residuals_px[k];
    }
    if (fit.line_spread < kNearlyCollinearSpread)
      summary.warnings.push_back(FamilyName(a) + ": its segments lie nearly on one line, so its vanishing point is poorly fixed");
  }
  if (num_families == 3 && !at_infinity[0] && !at_infinity[1] && !at_infinity[2]) {
    std::array<Eigen::Vector2d, 3> points;
    for (int a = 0; a < 3; ++a) points[a] = summary.vanishing_points[a].head<2>() / summary.vanishing_points[a].z();
    summary.vanishing_point_triangle_max_angle_deg = TriangleMaxAngleDeg(points);
  }

  // Intrinsics from the image of the absolute conic, omega ~ [[1, 0, -cx], [0, 1, -cy],
  // [-cx, -cy, cx^2 + cy^2 + f^2]] in conditioned coordinates: orthogonal directions give
  // v_i^T omega v_j = (p_i - c w_i).(p_j - c w_j) + f^2 w_i w_j = 0 with v = (p, w).
  PrincipalPointMode mode = options.principal_point_mode;
  if (mode == PrincipalPointMode::kSolve && num_families < 3) {
    mode = PrincipalPointMode::kImageCenter;
    summary.warnings.push_back(std::string(num_families == 2 ? "two line families" : "one line family") +
                               " cannot fix the principal point; it was set to the image centre");
  }
  std::vector<std::array<int, 2>> pairs;
  for (int i = 0; i < 3; ++i)
    for (int j = i + 1; j < 3; ++j)
      if (present[i] && present[j]) pairs.push_back({i, j});
  // f^2 by least squares over the pairs for a given principal point; NaN when no pair has
  // two finite points (then f does not enter any constraint).
  auto focal_squared_for = [&](const Eigen::Vector2d& c) {
    double num = 0.0, den = 0.0, max_coefficient = 0.0;
    for (const auto& pair : pairs) {
      const Eigen::Vector3d& vi = v[pair[0]];
      const Eigen::Vector3d& vj = v[pair[1]];
      const double coefficient = vi.z() * vj.z();
      num += coefficient * (vi.head<2>() - c * vi.z()).dot(vj.head<2>() - c * vj.z());
      den += coefficient * coefficient;
      max_coefficient = std::max(max_coefficient, std::abs(coefficient));
    }
    return max_coefficient > 1.0 / (kAtInfinityDistance * kAtInfinityDistance) ? -num / den : std::nan("");
  };
  const double known_f = focal_fixed ? options.fixed_focal_px / scale_px
                                     : (focal_prior ? options.focal_prior_px / scale_px : 0.0);

  Eigen::Vector2d pp;  // conditioned
  double f_squared = 0.0;
  bool started_from_center = false;
  if (mode == PrincipalPointMode::kSolve) {
    for (int a = 0; a < 3; ++a)
      if (at_infinity[a])
        return Fail(summary,
                    FamilyName(a) +
                        ": its segments are parallel in the image (vanishing point at infinity), so three vanishing "
                        "points cannot fix the principal point; use the image centre or a fixed principal point",
                    start);
    // Unknowns (cx, cy, k = cx^2 + cy^2 + f^2); one equation per pair.
    Eigen::Matrix3d a_matrix;
    Eigen::Vector3d rhs;
    for (int e = 0; e < 3; ++e) {
      const Eigen::Vector3d& vi = v[pairs[e][0]];
      const Eigen::Vector3d& vj = v[pairs[e][1]];
      a_matrix(e, 0) = -(vi.x() * vj.z() + vi.z() * vj.x());
      a_matrix(e, 1) = -(vi.y() * vj.z() + vi.z() * vj.y());
      a_matrix(e, 2) = vi.z() * vj.z();
      rhs(e) = -(vi.x() * vj.x() + vi.y() * vj.y());
    }
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(a_matrix, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Eigen::Vector3d sv = svd.singularValues();
    if (!(sv(2) > 1e-12 * sv(0)))
      return Fail(summary,
                  "the three vanishing points are collinear or coincide, so they do not fix the principal point; check "
                  "the family assignment or use the image centre",
                  start);
    const Eigen::Vector3d u = svd.solve(rhs);
    pp = u.head<2>();
    f_squared = u(2) - pp.squaredNorm();
    summary.closed_form_focal_px = f_squared > 0.0 ? std::sqrt(f_squared) * scale_px : 0.0;
    summary.closed_form_principal_point_px = center_px + scale_px * pp;
    // A vanishing point far from the image makes the closed form unstable: noise can push
    // f^2 below zero. The joint fit below, started at the image centre, still finds the
    // camera if one explains the segments (checked after the fit).
    const double f_squared_at_center = focal_squared_for(Eigen::Vector2d::Zero());
    if (!(f_squared > 0.0) && (f_squared_at_center > 0.0 || known_f > 0.0)) {
      started_from_center = true;
      pp.setZero();
      f_squared = f_squared_at_center > 0.0 ? f_squared_at_center : known_f * known_f;
    }
  } else {
    const Eigen::Vector2d pp_px =
        mode == PrincipalPointMode::kFixed ? options.fixed_principal_point_px : center_px;
    pp = (pp_px - center_px) / scale_px;
    f_squared = pairs.empty() ? std::nan("") : focal_squared_for(pp);
    if (std::isnan(f_squared) && known_f == 0.0)
      return Fail(summary,
                  "the focal length is undetermined: no two families have finite vanishing points (segments parallel "
                  "in the image)",
                  start);
  }
  // No two finite vanishing points (one family, or one at infinity with the principal point
  // given): the segments say nothing about f, so a prior is all there is and f is held there.
  const bool focal_prior_only = focal_prior && std::isnan(f_squared);
  if (focal_prior_only)
    summary.warnings.push_back("the segments do not fix the focal length; it is the prior's (" +
                               Fmt(options.focal_prior_px) + " +- " + Fmt(options.focal_prior_std_px) + " px)");
  const std::string no_real_focal =
      "the vanishing points give no real focal length (f^2 = " + Fmt(f_squared * scale_px * scale_px) +
      " px^2 <= 0): the vanishing-point triangle is obtuse or the families are not mutually orthogonal; check the "
      "family assignment of the segments";
  if (focal_fixed) {
    f_squared = known_f * known_f;
  } else if (!(f_squared > 0.0) && focal_prior) {
    // The prior is the better start when the vanishing points alone give no focal length.
    f_squared = known_f * known_f;
    started_from_center = started_from_center || mode == PrincipalPointMode::kSolve;
  }
  if (options.warm_start && !(f_squared > 0.0)) {
    f_squared = std::pow(options.warm_start_focal_px / scale_px, 2);
    started_from_center = false;
  }
  if (!std::isfinite(f_squared)) return Fail(summary, "the focal length is not finite (numerical failure)", start);
  if (f_squared <= 0.0) return Fail(summary, no_real_focal, start);
  double f = std::sqrt(f_squared);

  // Vanishing directions d ~ K^-1 v (the same in conditioned and pixel coordinates).
  Eigen::Matrix3d k_inverse = Eigen::Matrix3d::Identity();
  k_inverse(0, 0) = k_inverse(1, 1) = 1.0 / f;
  k_inverse(0, 2) = -pp.x() / f;
  k_inverse(1, 2) = -pp.y() / f;
  Eigen::Matrix3d directions = Eigen::Matrix3d::Zero();
  for (int a = 0; a < 3; ++a)
    if (present[a]) directions.col(a) = (k_inverse * v[a]).normalized();
  double max_orthogonality_error_deg = 0.0;
  for (const auto& pair : pairs) {
    const double cosine = std::clamp(directions.col(pair[0]).dot(directions.col(pair[1])), -1.0, 1.0);
    max_orthogonality_error_deg = std::max(max_orthogonality_error_deg, std::abs(std::asin(cosine)) * kRadToDeg);
  }
  summary.max_orthogonality_error_deg = max_orthogonality_error_deg;
  std::array<Eigen::Vector2d, 2> horizon_conditioned;
  if (options.use_horizon) {
    horizon_conditioned[0] = (options.horizon_px.head<2>() - center_px) / scale_px;
    horizon_conditioned[1] = (options.horizon_px.tail<2>() - center_px) / scale_px;
  }
  if (one_family_mode) {
    // The vertical is the normal of the horizon's plane: K^T l for the horizon line l.
    const Eigen::Vector3d line = Eigen::Vector3d(horizon_conditioned[0].x(), horizon_conditioned[0].y(), 1.0)
                                     .cross(Eigen::Vector3d(horizon_conditioned[1].x(), horizon_conditioned[1].y(), 1.0));
    const Eigen::Vector3d vertical(f * line.x(), f * line.y(), pp.dot(line.head<2>()) + line.z());
    directions.col(2) = vertical.normalized();
    const int a = present[0] ? 0 : 1;
    Eigen::Vector3d d = directions.col(a) - directions.col(a).dot(directions.col(2)) * directions.col(2);
    if (!(d.norm() > 1e-9))
      return Fail(summary, "the family's vanishing direction is vertical by the horizon given; check the horizon", start);
    directions.col(a) = d.normalized();
  }
  for (int a = 0; a < 3; ++a) {
    if (present[a] || (one_family_mode && a == 2)) continue;
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    directions.col(a) = directions.col(b).cross(directions.col(c)).normalized();
  }
  Eigen::Matrix3d rotation = NearestRotation(ChooseAxisSigns(directions));

  // Joint fit of the camera to all segments (and the horizon). With a fixed principal point
  // it enforces the orthogonality the closed form only approximates. With the principal
  // point solved, three free vanishing points and (f, c, R) have the same 6 degrees of
  // freedom, so the data alone would return the closed form; the prior at the image centre,
  // weighted against the noise the segments show, decides where the data leave the
  // principal point loose (a vanishing point far away).
  JointProblem problem;
  problem.solve_focal = !focal_fixed && !focal_prior_only;
  problem.solve_pp = mode == PrincipalPointMode::kSolve;
  for (int a = 0; a < 3; ++a)
    for (size_t k = 0; k < family_segments[a].size(); ++k) {
      const Eigen::Vector4d& s = family_segments[a][k];
      problem.segments.push_back(MakeJointSegment((s.head<2>() - center_px) / scale_px,
                                                  (s.tail<2>() - center_px) / scale_px, a, family_indices[a][k]));
    }
  const int num_segments = static_cast<int>(problem.segments.size());
  // Noise of the segments (conditioned) from the free vanishing points, each of which took
  // 2 degrees of freedom; the floor only avoids a zero weight for exact data.
  const double independent_rms_px = std::sqrt(independent_sum_sq / num_segments);
  // The floor (3e-8 of the conditioning scale, ~1e-5 px) keeps the prior rows from vanishing
  // against exact data, which would leave a direction only a prior fixes numerically singular.
  const double noise =
      std::max(std::sqrt(independent_sum_sq / std::max(1, num_segments - 2 * num_families)) / scale_px, kNoiseFloor);
  if (problem.solve_pp && options.principal_point_prior_std_px >= 0.0) {
    const double prior_std_px = options.principal_point_prior_std_px > 0.0
                                    ? options.principal_point_prior_std_px
                                    : kPrincipalPointPriorSigma * scale_px;
    problem.pp_prior_weight = noise / (prior_std_px / scale_px);
  }
  if (problem.solve_focal && focal_prior) {
    problem.focal_prior = options.focal_prior_px / scale_px;
    problem.focal_prior_weight = noise / (options.focal_prior_std_px / scale_px);
  }
  problem.use_horizon = options.use_horizon;
  problem.horizon = horizon_conditioned;
  JointCamera camera;
  camera.f = f;
  camera.pp = pp;
  camera.r = rotation;
  if (options.warm_start) {
    if (problem.solve_focal) camera.f = options.warm_start_focal_px / scale_px;
    if (problem.solve_pp) camera.pp = (options.warm_start_principal_point_px - center_px) / scale_px;
    camera.r = NearestRotation(options.warm_start_rotation);
  }
  summary.joint_fit_iterations = RefineJointly(problem, &camera);

  // Flags every segment against the camera with the threshold from the residuals of the
  // segments it was fitted to: a robust sigma from their median absolute residual.
  const JointProblem full_problem = problem;
  auto flag_outliers = [&](const JointProblem& fitted) {
    Eigen::VectorXd r;
    fitted.Residuals(camera, &r);
    std::vector<double> abs_px(fitted.segments.size());
    for (size_t i = 0; i < fitted.segments.size(); ++i) abs_px[i] = std::abs(r(i)) * scale_px;
    const double threshold_px =
        std::max(options.outlier_threshold_sigmas * 1.4826 * Median(abs_px), options.outlier_floor_px);
    summary.outlier_threshold_px = threshold_px;
    full_problem.Residuals(camera, &r);
    std::vector<bool> flagged(num_segments);
    for (int i = 0; i < num_segments; ++i) flagged[i] = std::abs(r(i)) * scale_px > threshold_px;
    return flagged;
  };
  std::vector<bool> flagged = flag_outliers(problem);
  if (options.refit_without_outliers) {
    // Refit without the flagged segments and flag again against the new camera, until the
    // set is stable: a wrong segment drags its neighbours over the threshold in the first
    // fit, and they come back once it is gone. Each family keeps its two best segments.
    std::vector<bool> removed(num_segments, false);
    for (int round = 0; round < kMaxOutlierRounds && flagged != removed; ++round) {
      Eigen::VectorXd r;
      full_problem.Residuals(camera, &r);
      std::array<std::vector<std::pair<double, int>>, 3> by_family;
      for (int i = 0; i < num_segments; ++i) by_family[full_problem.segments[i].axis].push_back({std::abs(r(i)), i});
      for (int a = 0; a < 3; ++a) {
        std::sort(by_family[a].begin(), by_family[a].end());
        for (size_t k = 0; k < by_family[a].size(); ++k) {
          const int i = by_family[a][k].second;
          removed[i] = k >= 2 && flagged[i];
        }
      }
      problem.segments.clear();
      for (int i = 0; i < num_segments; ++i)
        if (!removed[i]) problem.segments.push_back(full_problem.segments[i]);
      summary.joint_fit_iterations += RefineJointly(problem, &camera);
      summary.refitted_without_outliers = std::count(removed.begin(), removed.end(), true) > 0;
      flagged = flag_outliers(problem);
    }
  }
  summary.segment_is_outlier.assign(segments.size(), false);
  for (int i = 0; i < num_segments; ++i)
    if (flagged[i]) summary.segment_is_outlier[full_problem.segments[i].input_index] = true;
  for (int i = 0; i < static_cast<int>(segments.size()); ++i)
    if (summary.segment_is_outlier[i]) summary.outlier_segments.push_back(i);

  // Covariance of the parameters of the final fit (the problem the camera was fitted to).
  {
    Eigen::VectorXd r;
    Eigen::MatrixXd jacobian;
    problem.Residuals(camera, &r);
    problem.Jacobian(camera, &jacobian);
    const int num_params = problem.NumParams();
    summary.degrees_of_freedom = problem.NumResiduals() - num_params;
    const double nan = std::nan("");
    summary.focal_std_px = focal_fixed ? 0.0 : focal_prior_only ? options.focal_prior_std_px : nan;
    summary.principal_point_std_px = problem.solve_pp ? Eigen::Vector2d(nan, nan) : Eigen::Vector2d::Zero();
    summary.residual_sigma_px = nan;
    for (int a = 0; a < 3; ++a) summary.vanishing_direction_std_deg[a] = present[a] || one_family_mode ? nan : 0.0;
    // Information: the segment rows scaled by the sigma their residuals show, the prior rows
    // (weighted noise / prior std) by the noise they were weighted with, so that a prior
    // contributes exactly 1 / std^2 whatever the residuals.
    const int num_data = static_cast<int>(problem.segments.size()) + (problem.use_horizon ? 2 : 0);
    const double sigma_squared =
        std::max(r.head(num_data).squaredNorm() / std::max(1, summary.degrees_of_freedom), 1e-300);
    const Eigen::MatrixXd data_jacobian = jacobian.topRows(num_data);
    const Eigen::MatrixXd prior_jacobian = jacobian.bottomRows(jacobian.rows() - num_data);
    const Eigen::MatrixXd information = data_jacobian.transpose() * data_jacobian / sigma_squared +
                                        prior_jacobian.transpose() * prior_jacobian / (noise * noise);
    const Eigen::FullPivLU<Eigen::MatrixXd> lu(information);
    if (summary.degrees_of_freedom > 0 && lu.isInvertible()) {
      summary.residual_sigma_px = std::sqrt(sigma_squared) * scale_px;
      const Eigen::MatrixXd covariance = lu.inverse();
      int k = 0;
      if (problem.solve_focal) summary.focal_std_px = camera.f * scale_px * std::sqrt(covariance(k, k)), ++k;
      if (problem.solve_pp) {
        summary.principal_point_std_px =
            scale_px * Eigen::Vector2d(std::sqrt(covariance(k, k)), std::sqrt(covariance(k + 1, k + 1)));
        k += 2;
      }
      const Eigen::Matrix3d rotation_covariance = covariance.block<3, 3>(k, k);
      for (int a = 0; a < 3; ++a) {
        if (summary.vanishing_direction_std_deg[a] == 0.0) continue;
        // d' = exp(w) d ~ d + w x d = d - [d]x w.
        const Eigen::Matrix3d cross = Cross(camera.r.col(a));
        summary.vanishing_direction_std_deg[a] =
            std::sqrt(std::max(0.0, (cross * rotation_covariance * cross.transpose()).trace())) * kRadToDeg;
      }
    } else {
      summary.warnings.push_back("too few segments to estimate the uncertainty (" +
                                 std::to_string(summary.degrees_of_freedom) + " degrees of freedom)");
    }
  }

  summary.focal_px = camera.f * scale_px;
  summary.principal_point_px = center_px + scale_px * camera.pp;
  summary.cam_from_world_rotation = NearestRotation(ChooseAxisSigns(camera.r));

  // Report the vanishing points of the final camera and the residuals against them, so
  // that camera, points and residuals agree.
  Eigen::Matrix3d k_final = Eigen::Matrix3d::Identity();
  k_final(0, 0) = k_final(1, 1) = summary.focal_px;
  k_final(0, 2) = summary.principal_point_px.x();
  k_final(1, 2) = summary.principal_point_px.y();
  const Eigen::Matrix3d final_vps = k_final * summary.cam_from_world_rotation;
  double joint_sum_sq = 0.0;
  std::array<double, 3> family_sum_sq = {0, 0, 0};
  for (const JointSegment& js : full_problem.segments) {
    const Segment& s = segments[js.input_index];
    const Eigen::Vector4d seg(s.a_px.x(), s.a_px.y(), s.b_px.x(), s.b_px.y());
    const double r = SegmentVanishingPointResidualPx(seg, final_vps.col(js.axis));
    summary.segment_residuals_px[js.input_index] = r;
    joint_sum_sq += r * r;
    family_sum_sq[js.axis] += r * r;
  }
  summary.rms_residual_px = std::sqrt(joint_sum_sq / num_segments);
  summary.min_vanishing_point_to_principal_point_px = std::numeric_limits<double>::infinity();
  summary.min_family_angle_spread_deg = 90.0;
  for (int a = 0; a < 3; ++a) {
    if (!present[a]) continue;
    Eigen::Vector3d vp = final_vps.col(a).normalized();
    if (vp.z() < 0.0) vp = -vp;
    summary.vanishing_points[a] = vp;
    summary.vanishing_point_rms_px[a] = std::sqrt(family_sum_sq[a] / summary.segments_per_axis[a]);
    const Eigen::Vector3d d = summary.cam_from_world_rotation.col(a);
    const double distance_px = d.z() != 0.0 ? summary.focal_px * d.head<2>().norm() / std::abs(d.z())
                                            : std::numeric_limits<double>::infinity();
    summary.vanishing_point_to_principal_point_px[a] = distance_px;
    summary.min_vanishing_point_to_principal_point_px =
        std::min(summary.min_vanishing_point_to_principal_point_px, distance_px);
    summary.min_family_angle_spread_deg = std::min(summary.min_family_angle_spread_deg, summary.family_angle_spread_deg[a]);
  }
  if (options.use_horizon) {
    Eigen::VectorXd r;
    problem.Residuals(camera, &r);
    summary.horizon_residual_px = std::sqrt(0.5 * r.segment<2>(problem.segments.size()).squaredNorm()) * scale_px;
  }
  if (started_from_center) {
    // Orthogonal directions that explain the segments about as well as free vanishing points
    // do mean the closed form failed on noise, not on inconsistent families.
    if (!(summary.rms_residual_px <= kMaxJointRmsRatio * independent_rms_px + kJointRmsSlackPx))
      return Fail(summary,
                  no_real_focal + " (a fit with orthogonal directions leaves " + Fmt(summary.rms_residual_px) +
                      " px RMS against " + Fmt(independent_rms_px) + " px for free vanishing points)",
                  start);
    summary.warnings.push_back(
        "the three vanishing points alone give no real focal length (a vanishing point far from the image makes "
        "them unstable); the camera was fitted to all segments starting from the image centre");
  }
  if (!summary.cam_from_world_rotation.allFinite() || !std::isfinite(summary.focal_px) ||
      !summary.principal_point_px.allFinite())
    return Fail(summary, "the calibration is not finite (numerical failure)", start);
  if (std::abs(summary.cam_from_world_rotation(1, 2)) < 1e-3)
    summary.warnings.push_back("the vertical (family z) is nearly parallel to the image rows: up and down are ambiguous");

  for (int a = 0; a < 3; ++a) {
    if (!present[a]) continue;
    if (summary.family_angle_spread_deg[a] < kMinAngleSpreadDeg && !at_infinity[a])
      summary.warnings.push_back(FamilyName(a) + ": its segments are nearly parallel in the image (largest angle " +
                                 Fmt(summary.family_angle_spread_deg[a]) +
                                 " deg between two), so its vanishing point is poorly fixed");
    if (at_infinity[a]) continue;
    const double to_plane_deg = std::asin(std::min(1.0, std::abs(directions(2, a)))) * kRadToDeg;
    if (to_plane_deg < kFarVanishingPointDeg)
      summary.warnings.push_back(FamilyName(a) + ": vanishing point very far from the image (direction " +
                                 Fmt(to_plane_deg) + " deg from the image plane); the focal length is poorly constrained");
    if (90.0 - to_plane_deg < kCentralVanishingPointDeg)
      summary.warnings.push_back(FamilyName(a) + ": vanishing point near the principal point (" +
                                 Fmt(summary.vanishing_point_to_principal_point_px[a]) + " px, direction " +
                                 Fmt(90.0 - to_plane_deg) +
                                 " deg from the optical axis); the focal length is poorly constrained");
  }
  if (mode == PrincipalPointMode::kSolve && summary.vanishing_point_triangle_max_angle_deg > kMaxTriangleAngleDeg)
    summary.warnings.push_back("the vanishing-point triangle is nearly degenerate (largest angle " +
                               Fmt(summary.vanishing_point_triangle_max_angle_deg) +
                               " deg): the principal point and focal length are poorly fixed");
  if (!summary.outlier_segments.empty()) {
    std::string list;
    for (size_t k = 0; k < summary.outlier_segments.size() && k < 10; ++k)
      list += (k ? ", " : "") + std::to_string(summary.outlier_segments[k]);
    if (summary.outlier_segments.size() > 10) list += ", ...";
    summary.warnings.push_back(std::to_string(summary.outlier_segments.size()) +
                               " segment(s) flagged as outliers (residual above " +
                               Fmt(summary.outlier_threshold_px) + " px): " + list +
                               (summary.refitted_without_outliers ? "; the camera was refitted without them" : ""));
  }
  if (mode == PrincipalPointMode::kSolve) {
    const Eigen::Vector2d& c = summary.principal_point_px;
    if (c.x() < 0 || c.y() < 0 || c.x() > options.width_px - 1 || c.y() > options.height_px - 1)
      summary.warnings.push_back("the solved principal point (" + Fmt(c.x()) + ", " + Fmt(c.y()) +
                                 ") lies outside the image: a cropped photo, or inaccurate vanishing points");
  }

  summary.success = true;
  summary.message = "f = " + Fmt(summary.focal_px) + " px";
  if (std::isfinite(summary.focal_std_px) && summary.focal_std_px > 0.0)
    summary.message += " +- " + Fmt(summary.focal_std_px);
  summary.message += ", principal point (" + Fmt(summary.principal_point_px.x()) + ", " +
                     Fmt(summary.principal_point_px.y()) + ") px from " + std::to_string(num_families) +
                     (num_families == 1 ? " vanishing point and the horizon" : " vanishing points");
  summary.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

}  // namespace facet
