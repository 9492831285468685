#include "core/estimators/calibrate_vp.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include <Eigen/Dense>

#include "core/estimators/vanishing_point.h"
#include "core/geometry/camera.h"
#include "core/geometry/camera_checks.h"
#include "core/optim/damped_normal_step.h"
#include "core/optim/levenberg_marquardt.h"
#include "core/util/eigen_decompositions.h"
#include "core/util/format.h"
#include "core/util/stats.h"
#include "core/util/timer.h"

namespace facet {
namespace {

using internal::FailedSummary;

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
// Two families whose vanishing points are closer than this, in degrees between their rays
// seen from the image centre with a focal length of half the image's larger side, are one
// direction in space: orthogonal directions stay tens of degrees apart for any real lens.
constexpr double kSameVanishingPointDeg = 1.0;

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

std::string FamilyName(int axis) { return std::string("family ") + AxisName(static_cast<Axis>(axis)); }

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
        const Eigen::RowVector3d dr_dv =
            s.g.transpose() / n - (s.g.dot(v) / (n * n * n)) * (mv.transpose() * s.m_cross);
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

// The joint fit for the Levenberg-Marquardt driver: the camera moves by JointProblem::Apply.
class JointFit {
 public:
  JointFit(const JointProblem& problem, JointCamera* camera) : problem_(problem), camera_(camera) {
    problem_.Residuals(*camera_, &residuals_);
  }

  double Cost() const { return residuals_.squaredNorm(); }

  bool Linearize() {
    problem_.Jacobian(*camera_, &jacobian_);
    normal_ = jacobian_.transpose() * jacobian_;
    gradient_ = jacobian_.transpose() * residuals_;
    damping_ = (normal_.diagonal().array() + 1e-12).matrix();  // the floor is added, not a max
    return false;
  }

  LmStepStatus Step(double lambda, LmTrial* trial) {
    const Eigen::VectorXd step = DampedNormalStep(normal_, gradient_, lambda, damping_);
    if (!step.allFinite()) return LmStepStatus::kSolveFailed;
    candidate_ = problem_.Apply(*camera_, step);
    problem_.Residuals(candidate_, &candidate_residuals_);
    trial->cost = candidate_residuals_.squaredNorm();
    trial->step_squared_norm = step.squaredNorm();
    return LmStepStatus::kSolved;
  }

  void Accept() {
    *camera_ = candidate_;
    residuals_ = candidate_residuals_;
  }

 private:
  const JointProblem& problem_;
  JointCamera* camera_;
  Eigen::VectorXd residuals_, candidate_residuals_, gradient_, damping_;
  Eigen::MatrixXd jacobian_, normal_;
  JointCamera candidate_;
};

// Levenberg-Marquardt on the joint problem from *camera; the cost is in conditioned units.
LmResult RefineJointly(const JointProblem& problem, const VpCalibrationOptions& vp_options, JointCamera* camera,
                       std::vector<LmIteration>* trace) {
  LmOptions options = TenfoldLmOptions(vp_options.max_joint_iterations);
  // Rejections up to 1e12; a damped system without a finite solution ends the fit (as in
  // core/estimators/vanishing_point.cpp).
  options.max_lambda = 1e12;
  options.stop_on_failed_solve = true;
  options.relative_decrease_tolerance = 1e-15;
  options.min_step_squared_norm = 1e-28;  // |step| <= 1e-14 (log f, conditioned px, rad)
  if (vp_options.record_joint_trace)
    options.callback = [trace](const LmIteration& it) {
      trace->push_back(it);
      return true;
    };
  JointFit fit(problem, camera);
  return MinimizeLevenbergMarquardt(fit.Cost(), options, fit);
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

// The segments of each family (axis x, y, z), with their input indices for the residuals
// and messages.
struct Families {
  std::array<std::vector<Eigen::Vector4d>, 3> segments_px;
  std::array<std::vector<int>, 3> input_indices;
  std::array<bool, 3> present{};  // 2 or more segments
  int count = 0;                  // present families
  // One horizontal family with the horizon and a known focal length.
  bool one_family_mode = false;
};

// Pixels about the image centre in units of half the larger image side, so that the
// intrinsics solve sees numbers of order 1: uv_px = center_px + scale_px * uv.
struct Conditioning {
  Eigen::Vector2d center_px;
  double scale_px = 1.0;

  Eigen::Vector2d FromPixels(const Eigen::Vector2d& uv_px) const { return (uv_px - center_px) / scale_px; }
};

// Groups the segments into families and checks that they make a calibration mode; fills
// summary->segments_per_axis. False (with *error) on invalid input.
bool GroupFamilies(const std::vector<Segment>& segments, const VpCalibrationOptions& options, Families* families,
                   VpCalibrationSummary* summary, std::string* error) {
  auto fail = [&](std::string message) {
    *error = std::move(message);
    return false;
  };
  for (int i = 0; i < static_cast<int>(segments.size()); ++i) {
    const Segment& s = segments[i];
    const int axis = static_cast<int>(s.axis);
    if (axis < 0 || axis > 2) return fail("segment " + std::to_string(i) + " has an invalid axis");
    const Eigen::Vector4d seg(s.a_px.x(), s.a_px.y(), s.b_px.x(), s.b_px.y());
    if (!seg.allFinite())
      return fail(FamilyName(axis) + ": segment " + std::to_string(i) + " has a non-finite coordinate");
    if ((s.b_px - s.a_px).norm() < 1e-9 * std::max(options.width_px, options.height_px))
      return fail(FamilyName(axis) + ": segment " + std::to_string(i) + " has zero length (both ends at (" +
                  internal::FormatNumber(s.a_px.x(), 6) + ", " + internal::FormatNumber(s.a_px.y(), 6) + "))");
    families->segments_px[axis].push_back(seg);
    families->input_indices[axis].push_back(i);
  }
  for (int a = 0; a < 3; ++a) summary->segments_per_axis[a] = static_cast<int>(families->segments_px[a].size());
  // The count checks below fail only because the drawing is not finished yet.
  summary->incomplete = true;
  std::string present_names;
  for (int a = 0; a < 3; ++a) {
    const size_t size = families->segments_px[a].size();
    if (size == 1) return fail(FamilyName(a) + " has only 1 segment; a family needs at least 2");
    families->present[a] = size >= 2;
    if (families->present[a]) {
      ++families->count;
      present_names +=
          present_names.empty() ? AxisName(static_cast<Axis>(a)) : std::string(", ") + AxisName(static_cast<Axis>(a));
    }
  }
  families->one_family_mode = families->count == 1 && options.use_horizon;
  if (families->count < 2 && !families->one_family_mode)
    return fail("calibration needs at least two line families (x, y, z), got " +
                (families->count == 0 ? std::string("none") : "only " + present_names) +
                " (one horizontal family also works with the horizon and a known focal length)");
  if (families->one_family_mode && families->present[2])
    return fail(
        "with a single family it must be horizontal (x or y): the vertical family and the horizon leave the heading "
        "free");
  if (families->one_family_mode && !(options.fixed_focal_px > 0.0) && !(options.focal_prior_px > 0.0))
    return fail(
        "one family with the horizon needs a known focal length (fixed or a prior): a vanishing point on the "
        "horizon is consistent with any focal length");
  summary->incomplete = false;
  return true;
}

// Each family's vanishing point fitted on its own (core/estimators/vanishing_point.h).
struct FreeVanishingPoints {
  std::array<Eigen::Vector3d, 3> v;  // conditioned, unit norm
  std::array<bool, 3> at_infinity{};
  double sum_squared_residuals_px = 0.0;  // over all segments, px^2
};

// Fits the free vanishing points; fills the summary's per-family figures, the segment
// residuals against them and the vanishing-point triangle. False (with *error) when a
// family's segments do not fix a point.
bool FitFreeVanishingPoints(const Families& families, const Conditioning& conditioning, FreeVanishingPoints* free,
                            VpCalibrationSummary* summary, std::string* error) {
  VanishingPointOptions vp_options;
  vp_options.conditioning_center_px = conditioning.center_px;
  vp_options.conditioning_scale_px = conditioning.scale_px;
  for (int a = 0; a < 3; ++a) {
    if (!families.present[a]) continue;
    summary->family_angle_spread_deg[a] = AngleSpreadDeg(families.segments_px[a]);
    const VanishingPointSummary fit = FitVanishingPoint(families.segments_px[a], vp_options);
    if (!fit.IsUsable()) {
      *error = FamilyName(a) + ": " + fit.message;
      return false;
    }
    free->v[a] = fit.vp_conditioned;
    summary->vanishing_points[a] = fit.vp_px;
    summary->family_vanishing_points[a] = fit.vp_px;
    summary->family_vanishing_point_covariance_px2[a] = fit.point_covariance_px2;
    free->at_infinity[a] = fit.distance_in_scales > kAtInfinityDistance;
    summary->vanishing_point_at_infinity[a] = free->at_infinity[a];
    summary->vanishing_point_rms_px[a] = fit.final_rms_px;
    for (size_t k = 0; k < fit.residuals_px.size(); ++k) {
      summary->segment_residuals_px[families.input_indices[a][k]] = fit.residuals_px[k];
      free->sum_squared_residuals_px += fit.residuals_px[k] * fit.residuals_px[k];
    }
    if (fit.line_spread < kNearlyCollinearSpread)
      summary->warnings.push_back(FamilyName(a) +
                                  ": its segments lie nearly on one line, so its vanishing point is poorly fixed");
  }
  if (families.count == 3 && !free->at_infinity[0] && !free->at_infinity[1] && !free->at_infinity[2]) {
    std::array<Eigen::Vector2d, 3> points;
    for (int a = 0; a < 3; ++a) points[a] = summary->vanishing_points[a].head<2>() / summary->vanishing_points[a].z();
    summary->vanishing_point_triangle_max_angle_deg = TriangleMaxAngleDeg(points);
  }
  return true;
}

// False (with *error) when two families meet at one vanishing point: the same lines given
// twice, or one direction split into two families; nothing then fixes the focal length.
bool FamiliesAreDistinct(const Families& families, const FreeVanishingPoints& free, std::string* error) {
  for (int a = 0; a < 3; ++a) {
    for (int b = a + 1; b < 3; ++b) {
      if (!families.present[a] || !families.present[b]) continue;
      const double angle_deg = std::acos(std::min(1.0, std::abs(free.v[a].dot(free.v[b])))) * kRadToDeg;
      if (angle_deg >= kSameVanishingPointDeg) continue;
      *error = FamilyName(a) + " and " + FamilyName(b) + " meet at one vanishing point (" +
               internal::FormatNumber(angle_deg, 3) +
               " deg apart seen from the image centre): they are one direction in space, not two orthogonal "
               "ones; check the family assignment of the segments";
      return false;
    }
  }
  return true;
}

using FamilyPairs = std::vector<std::array<int, 2>>;

FamilyPairs PresentPairs(const std::array<bool, 3>& present) {
  FamilyPairs pairs;
  for (int i = 0; i < 3; ++i)
    for (int j = i + 1; j < 3; ++j)
      if (present[i] && present[j]) pairs.push_back({i, j});
  return pairs;
}

// Intrinsics from the image of the absolute conic, omega ~ [[1, 0, -cx], [0, 1, -cy],
// [-cx, -cy, cx^2 + cy^2 + f^2]] in conditioned coordinates: orthogonal directions give
// v_i^T omega v_j = (p_i - c w_i).(p_j - c w_j) + f^2 w_i w_j = 0 with v = (p, w).

// f^2 by least squares over the pairs for the principal point c; NaN when no pair has two
// finite points (then f does not enter any constraint).
double FocalSquaredFor(const Eigen::Vector2d& c, const FamilyPairs& pairs, const std::array<Eigen::Vector3d, 3>& v) {
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
}

// Three finite vanishing points: the unknowns (cx, cy, k = cx^2 + cy^2 + f^2), one equation
// per pair. False (with *error) when the points are collinear or coincide.
bool ThreePointIntrinsics(const std::array<Eigen::Vector3d, 3>& v, const FamilyPairs& pairs, Eigen::Vector2d* pp,
                          double* f_squared, std::string* error) {
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
  if (!(sv(2) > 1e-12 * sv(0))) {
    *error =
        "the three vanishing points are collinear or coincide, so they do not fix the principal point; check the "
        "family assignment or use the image centre";
    return false;
  }
  const Eigen::Vector3d u = svd.solve(rhs);
  *pp = u.head<2>();
  *f_squared = u(2) - pp->squaredNorm();
  return true;
}

// The closed-form intrinsics that start the joint fit.
struct ClosedForm {
  PrincipalPointMode mode = PrincipalPointMode::kSolve;  // kSolve only with three families
  Eigen::Vector2d pp = Eigen::Vector2d::Zero();          // conditioned
  double f = 0.0;                                        // conditioned
  // The three points gave no real focal length and the fit starts from the image centre: its
  // result is accepted only if it explains the segments (else no_real_focal says why).
  bool started_from_center = false;
  // No two finite vanishing points: the segments say nothing about f, the prior holds it.
  bool focal_prior_only = false;
  std::string no_real_focal;
};

// The principal point by the mode and the focal length from the pairs of families (or the
// known focal length, the prior or the warm start); fills the summary's closed-form figures.
// False (with *error) when the vanishing points give no camera.
bool SolveClosedForm(const VpCalibrationOptions& options, const Families& families, const FreeVanishingPoints& free,
                     const Conditioning& conditioning, ClosedForm* out, VpCalibrationSummary* summary,
                     std::string* error) {
  auto fail = [&](std::string message) {
    *error = std::move(message);
    return false;
  };
  const bool focal_fixed = options.fixed_focal_px > 0.0;
  const bool focal_prior = options.focal_prior_px > 0.0;
  const double scale_px = conditioning.scale_px;
  out->mode = options.principal_point_mode;
  if (out->mode == PrincipalPointMode::kSolve && families.count < 3) {
    out->mode = PrincipalPointMode::kImageCenter;
    summary->warnings.push_back(std::string(families.count == 2 ? "two line families" : "one line family") +
                                " cannot fix the principal point; it was set to the image centre");
  }
  const FamilyPairs pairs = PresentPairs(families.present);
  const double known_f =
      focal_fixed ? options.fixed_focal_px / scale_px : (focal_prior ? options.focal_prior_px / scale_px : 0.0);
  double f_squared = 0.0;
  if (out->mode == PrincipalPointMode::kSolve) {
    for (int a = 0; a < 3; ++a)
      if (free.at_infinity[a])
        return fail(FamilyName(a) +
                    ": its segments are parallel in the image (vanishing point at infinity), so three vanishing "
                    "points cannot fix the principal point; use the image centre or a fixed principal point");
    if (!ThreePointIntrinsics(free.v, pairs, &out->pp, &f_squared, error)) return false;
    summary->closed_form_focal_px = f_squared > 0.0 ? std::sqrt(f_squared) * scale_px : 0.0;
    summary->closed_form_principal_point_px = conditioning.center_px + scale_px * out->pp;
    // A vanishing point far from the image makes the closed form unstable: noise can push
    // f^2 below zero. The joint fit, started at the image centre, still finds the camera if
    // one explains the segments (checked after the fit).
    const double f_squared_at_center = FocalSquaredFor(Eigen::Vector2d::Zero(), pairs, free.v);
    if (!(f_squared > 0.0) && (f_squared_at_center > 0.0 || known_f > 0.0)) {
      out->started_from_center = true;
      out->pp.setZero();
      f_squared = f_squared_at_center > 0.0 ? f_squared_at_center : known_f * known_f;
    }
  } else {
    const Eigen::Vector2d pp_px =
        out->mode == PrincipalPointMode::kFixed ? options.fixed_principal_point_px : conditioning.center_px;
    out->pp = conditioning.FromPixels(pp_px);
    f_squared = pairs.empty() ? std::nan("") : FocalSquaredFor(out->pp, pairs, free.v);
    if (std::isnan(f_squared) && known_f == 0.0)
      return fail(
          "the focal length is undetermined: no two families have finite vanishing points (segments parallel in the "
          "image)");
  }
  out->focal_prior_only = focal_prior && std::isnan(f_squared);
  if (out->focal_prior_only)
    summary->warnings.push_back("the segments do not fix the focal length; it is the prior's (" +
                                internal::FormatNumber(options.focal_prior_px, 6) + " +- " +
                                internal::FormatNumber(options.focal_prior_std_px, 6) + " px)");
  out->no_real_focal =
      "the vanishing points give no real focal length (f^2 = " +
      internal::FormatNumber(f_squared * scale_px * scale_px, 6) +
      " px^2 <= 0): the vanishing-point triangle is obtuse or the families are not mutually orthogonal; check the "
      "family assignment of the segments";
  if (focal_fixed) {
    f_squared = known_f * known_f;
  } else if (!(f_squared > 0.0) && focal_prior) {
    // The prior is the better start when the vanishing points alone give no focal length.
    f_squared = known_f * known_f;
    out->started_from_center = out->started_from_center || out->mode == PrincipalPointMode::kSolve;
  }
  if (options.warm_start && !(f_squared > 0.0)) {
    f_squared = std::pow(options.warm_start_focal_px / scale_px, 2);
    out->started_from_center = false;
  }
  if (!std::isfinite(f_squared)) return fail("the focal length is not finite (numerical failure)");
  if (f_squared <= 0.0) return fail(out->no_real_focal);
  out->f = std::sqrt(f_squared);
  return true;
}

// The vanishing directions d ~ K^-1 v of the closed-form camera (columns: world x, y, z in
// the camera frame; the same in conditioned and pixel coordinates), an absent family's as
// the cross product of the other two, the vertical of one family from the horizon. Fills
// summary->max_orthogonality_error_deg. False (with *error) when the horizon makes the
// family vertical.
bool VanishingDirections(const Families& families, const FreeVanishingPoints& free, const ClosedForm& closed_form,
                         const std::array<Eigen::Vector2d, 2>& horizon, Eigen::Matrix3d* directions,
                         VpCalibrationSummary* summary, std::string* error) {
  const double f = closed_form.f;
  const Eigen::Vector2d& pp = closed_form.pp;
  Eigen::Matrix3d k_inverse = Eigen::Matrix3d::Identity();
  k_inverse(0, 0) = k_inverse(1, 1) = 1.0 / f;
  k_inverse(0, 2) = -pp.x() / f;
  k_inverse(1, 2) = -pp.y() / f;
  Eigen::Matrix3d& d = *directions;
  d.setZero();
  for (int a = 0; a < 3; ++a)
    if (families.present[a]) d.col(a) = (k_inverse * free.v[a]).normalized();
  double max_orthogonality_error_deg = 0.0;
  for (const auto& pair : PresentPairs(families.present)) {
    const double cosine = std::clamp(d.col(pair[0]).dot(d.col(pair[1])), -1.0, 1.0);
    max_orthogonality_error_deg = std::max(max_orthogonality_error_deg, std::abs(std::asin(cosine)) * kRadToDeg);
  }
  summary->max_orthogonality_error_deg = max_orthogonality_error_deg;
  if (families.one_family_mode) {
    // The vertical is the normal of the horizon's plane: K^T l for the horizon line l.
    const Eigen::Vector3d line = Eigen::Vector3d(horizon[0].x(), horizon[0].y(), 1.0)
                                     .cross(Eigen::Vector3d(horizon[1].x(), horizon[1].y(), 1.0));
    const Eigen::Vector3d vertical(f * line.x(), f * line.y(), pp.dot(line.head<2>()) + line.z());
    d.col(2) = vertical.normalized();
    const int a = families.present[0] ? 0 : 1;
    Eigen::Vector3d horizontal = d.col(a) - d.col(a).dot(d.col(2)) * d.col(2);
    if (!(horizontal.norm() > 1e-9)) {
      *error = "the family's vanishing direction is vertical by the horizon given; check the horizon";
      return false;
    }
    d.col(a) = horizontal.normalized();
  }
  for (int a = 0; a < 3; ++a) {
    if (families.present[a] || (families.one_family_mode && a == 2)) continue;
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    d.col(a) = d.col(b).cross(d.col(c)).normalized();
  }
  return true;
}

// The joint fit of the camera to all segments (and the horizon). With a fixed principal
// point it enforces the orthogonality the closed form only approximates. With the principal
// point solved, three free vanishing points and (f, c, R) have the same 6 degrees of
// freedom, so the data alone would return the closed form; the prior at the image centre,
// weighted against the noise the segments show, decides where the data leave the principal
// point loose (a vanishing point far away). noise: the segments' noise, conditioned.
JointProblem MakeJointProblem(const VpCalibrationOptions& options, const Families& families,
                              const Conditioning& conditioning, const ClosedForm& closed_form, double noise,
                              const std::array<Eigen::Vector2d, 2>& horizon) {
  const double scale_px = conditioning.scale_px;
  JointProblem problem;
  problem.solve_focal = !(options.fixed_focal_px > 0.0) && !closed_form.focal_prior_only;
  problem.solve_pp = closed_form.mode == PrincipalPointMode::kSolve;
  for (int a = 0; a < 3; ++a)
    for (size_t k = 0; k < families.segments_px[a].size(); ++k) {
      const Eigen::Vector4d& s = families.segments_px[a][k];
      problem.segments.push_back(MakeJointSegment(
          conditioning.FromPixels(s.head<2>()), conditioning.FromPixels(s.tail<2>()), a, families.input_indices[a][k]));
    }
  if (problem.solve_pp && options.principal_point_prior_std_px >= 0.0) {
    const double prior_std_px = options.principal_point_prior_std_px > 0.0 ? options.principal_point_prior_std_px
                                                                           : kPrincipalPointPriorSigma * scale_px;
    problem.pp_prior_weight = noise / (prior_std_px / scale_px);
  }
  if (problem.solve_focal && options.focal_prior_px > 0.0) {
    problem.focal_prior = options.focal_prior_px / scale_px;
    problem.focal_prior_weight = noise / (options.focal_prior_std_px / scale_px);
  }
  problem.use_horizon = options.use_horizon;
  problem.horizon = horizon;
  return problem;
}

// The joint fit's start: the closed form, or the warm start where it applies.
JointCamera StartCamera(const VpCalibrationOptions& options, const JointProblem& problem,
                        const Conditioning& conditioning, const ClosedForm& closed_form,
                        const Eigen::Matrix3d& rotation) {
  JointCamera camera;
  camera.f = closed_form.f;
  camera.pp = closed_form.pp;
  camera.r = rotation;
  if (options.warm_start) {
    if (problem.solve_focal) camera.f = options.warm_start_focal_px / conditioning.scale_px;
    if (problem.solve_pp) camera.pp = conditioning.FromPixels(options.warm_start_principal_point_px);
    camera.r = NearestRotation(options.warm_start_rotation);
  }
  return camera;
}

// Flags every segment of full_problem against the camera, with the threshold from the
// residuals of the segments it was fitted to (a robust sigma from their median absolute
// residual); sets summary->outlier_threshold_px.
std::vector<bool> FlagOutliers(const JointProblem& fitted, const JointProblem& full_problem, const JointCamera& camera,
                               const VpCalibrationOptions& options, double scale_px, VpCalibrationSummary* summary) {
  Eigen::VectorXd r;
  fitted.Residuals(camera, &r);
  std::vector<double> abs_px(fitted.segments.size());
  for (size_t i = 0; i < fitted.segments.size(); ++i) abs_px[i] = std::abs(r(i)) * scale_px;
  const double threshold_px =
      std::max(options.outlier_threshold_sigmas * 1.4826 * internal::Median(abs_px), options.outlier_floor_px);
  summary->outlier_threshold_px = threshold_px;
  full_problem.Residuals(camera, &r);
  const int num_segments = static_cast<int>(full_problem.segments.size());
  std::vector<bool> flagged(num_segments);
  for (int i = 0; i < num_segments; ++i) flagged[i] = std::abs(r(i)) * scale_px > threshold_px;
  return flagged;
}

// The segments of full_problem to leave out: the flagged ones, except each family's two best.
std::vector<bool> SegmentsToRemove(const JointProblem& full_problem, const JointCamera& camera,
                                   const std::vector<bool>& flagged) {
  const int num_segments = static_cast<int>(full_problem.segments.size());
  Eigen::VectorXd r;
  full_problem.Residuals(camera, &r);
  std::array<std::vector<std::pair<double, int>>, 3> by_family;
  for (int i = 0; i < num_segments; ++i) by_family[full_problem.segments[i].axis].push_back({std::abs(r(i)), i});
  std::vector<bool> removed(num_segments, false);
  for (int a = 0; a < 3; ++a) {
    std::sort(by_family[a].begin(), by_family[a].end());
    for (size_t k = 0; k < by_family[a].size(); ++k) {
      const int i = by_family[a][k].second;
      removed[i] = k >= 2 && flagged[i];
    }
  }
  return removed;
}

// Fits the camera to full_problem, flags the outliers and (when the options ask) refits
// without them until the set is stable. On return *problem is the problem the camera was
// last fitted to. Fills the summary's iterations, costs (px^2), termination and outliers.
void FitJointly(const VpCalibrationOptions& options, const JointProblem& full_problem, double scale_px,
                size_t num_input_segments, JointProblem* problem, JointCamera* camera, VpCalibrationSummary* summary) {
  const double px_squared = scale_px * scale_px;
  auto record = [&](const LmResult& fit) {
    summary->iterations += fit.accepted_steps;
    summary->final_cost = fit.final_cost * px_squared;
    summary->termination = fit.termination == LmTermination::kMaxIterations ? SolverTermination::kMaxIterations
                                                                            : SolverTermination::kConverged;
  };
  *problem = full_problem;
  const LmResult first = RefineJointly(*problem, options, camera, &summary->joint_trace);
  summary->initial_cost = first.initial_cost * px_squared;
  record(first);
  std::vector<bool> flagged = FlagOutliers(*problem, full_problem, *camera, options, scale_px, summary);
  if (options.refit_without_outliers) {
    // Refit without the flagged segments and flag again against the new camera, until the
    // set is stable: a wrong segment drags its neighbours over the threshold in the first
    // fit, and they come back once it is gone. Each family keeps its two best segments.
    const int num_segments = static_cast<int>(full_problem.segments.size());
    std::vector<bool> removed(num_segments, false);
    for (int round = 0; round < kMaxOutlierRounds && flagged != removed; ++round) {
      removed = SegmentsToRemove(full_problem, *camera, flagged);
      problem->segments.clear();
      for (int i = 0; i < num_segments; ++i)
        if (!removed[i]) problem->segments.push_back(full_problem.segments[i]);
      record(RefineJointly(*problem, options, camera, &summary->joint_trace));
      summary->refitted_without_outliers = std::count(removed.begin(), removed.end(), true) > 0;
      flagged = FlagOutliers(*problem, full_problem, *camera, options, scale_px, summary);
    }
  }
  summary->segment_is_outlier.assign(num_input_segments, false);
  for (size_t i = 0; i < full_problem.segments.size(); ++i)
    if (flagged[i]) summary->segment_is_outlier[full_problem.segments[i].input_index] = true;
  for (size_t i = 0; i < num_input_segments; ++i)
    if (summary->segment_is_outlier[i]) summary->outlier_segments.push_back(static_cast<int>(i));
}

// First-order covariance of the parameters of the final fit (the problem the camera was
// fitted to): the summary's standard deviations, residual sigma and degrees of freedom.
// noise: what the prior rows were weighted with.
void EstimateUncertainty(const VpCalibrationOptions& options, const Families& families, const ClosedForm& closed_form,
                         const JointProblem& problem, const JointCamera& camera, double noise, double scale_px,
                         VpCalibrationSummary* summary) {
  Eigen::VectorXd r;
  Eigen::MatrixXd jacobian;
  problem.Residuals(camera, &r);
  problem.Jacobian(camera, &jacobian);
  const int num_params = problem.NumParams();
  summary->degrees_of_freedom = problem.NumResiduals() - num_params;
  const double nan = std::nan("");
  summary->focal_std_px = options.fixed_focal_px > 0.0   ? 0.0
                          : closed_form.focal_prior_only ? options.focal_prior_std_px
                                                         : nan;
  summary->principal_point_std_px = problem.solve_pp ? Eigen::Vector2d(nan, nan) : Eigen::Vector2d::Zero();
  summary->residual_sigma_px = nan;
  for (int a = 0; a < 3; ++a)
    summary->vanishing_direction_std_deg[a] = families.present[a] || families.one_family_mode ? nan : 0.0;
  // Information: the segment rows scaled by the sigma their residuals show, the prior rows
  // (weighted noise / prior std) by the noise they were weighted with, so that a prior
  // contributes exactly 1 / std^2 whatever the residuals.
  const int num_data = static_cast<int>(problem.segments.size()) + (problem.use_horizon ? 2 : 0);
  const double sigma_squared =
      std::max(r.head(num_data).squaredNorm() / std::max(1, summary->degrees_of_freedom), 1e-300);
  const Eigen::MatrixXd data_jacobian = jacobian.topRows(num_data);
  const Eigen::MatrixXd prior_jacobian = jacobian.bottomRows(jacobian.rows() - num_data);
  const Eigen::MatrixXd information = data_jacobian.transpose() * data_jacobian / sigma_squared +
                                      prior_jacobian.transpose() * prior_jacobian / (noise * noise);
  const Eigen::FullPivLU<Eigen::MatrixXd> lu(information);
  if (!(summary->degrees_of_freedom > 0 && lu.isInvertible())) {
    summary->warnings.push_back("too few segments to estimate the uncertainty (" +
                                std::to_string(summary->degrees_of_freedom) + " degrees of freedom)");
    return;
  }
  summary->residual_sigma_px = std::sqrt(sigma_squared) * scale_px;
  const Eigen::MatrixXd covariance = lu.inverse();
  int k = 0;
  if (problem.solve_focal) summary->focal_std_px = camera.f * scale_px * std::sqrt(covariance(k, k)), ++k;
  if (problem.solve_pp) {
    summary->principal_point_std_px =
        scale_px * Eigen::Vector2d(std::sqrt(covariance(k, k)), std::sqrt(covariance(k + 1, k + 1)));
    k += 2;
  }
  const Eigen::Matrix3d rotation_covariance = covariance.block<3, 3>(k, k);
  for (int a = 0; a < 3; ++a) {
    if (summary->vanishing_direction_std_deg[a] == 0.0) continue;
    // d' = exp(w) d ~ d + w x d = d - [d]x w.
    const Eigen::Matrix3d cross = Cross(camera.r.col(a));
    summary->vanishing_direction_std_deg[a] =
        std::sqrt(std::max(0.0, (cross * rotation_covariance * cross.transpose()).trace())) * kRadToDeg;
  }
}

// The fitted camera in pixels, its vanishing points and the residuals of every segment
// against them (so that camera, points and residuals agree), the per-family figures and the
// horizon's residual.
void ReportFinalCamera(const std::vector<Segment>& segments, const Families& families, const JointProblem& full_problem,
                       const JointProblem& problem, const JointCamera& camera, const Conditioning& conditioning,
                       VpCalibrationSummary* summary) {
  const double scale_px = conditioning.scale_px;
  summary->focal_px = camera.f * scale_px;
  summary->principal_point_px = conditioning.center_px + scale_px * camera.pp;
  summary->cam_from_world_rotation = NearestRotation(ChooseAxisSigns(camera.r));

  Eigen::Matrix3d k_final = Eigen::Matrix3d::Identity();
  k_final(0, 0) = k_final(1, 1) = summary->focal_px;
  k_final(0, 2) = summary->principal_point_px.x();
  k_final(1, 2) = summary->principal_point_px.y();
  const Eigen::Matrix3d final_vps = k_final * summary->cam_from_world_rotation;
  double joint_sum_sq = 0.0;
  std::array<double, 3> family_sum_sq = {0, 0, 0};
  for (const JointSegment& js : full_problem.segments) {
    const Segment& s = segments[js.input_index];
    const Eigen::Vector4d seg(s.a_px.x(), s.a_px.y(), s.b_px.x(), s.b_px.y());
    const double r = SegmentVanishingPointResidualPx(seg, final_vps.col(js.axis));
    summary->segment_residuals_px[js.input_index] = r;
    joint_sum_sq += r * r;
    family_sum_sq[js.axis] += r * r;
  }
  summary->rms_residual_px = std::sqrt(joint_sum_sq / full_problem.segments.size());
  summary->min_vanishing_point_to_principal_point_px = std::numeric_limits<double>::infinity();
  summary->min_family_angle_spread_deg = 90.0;
  for (int a = 0; a < 3; ++a) {
    if (!families.present[a]) continue;
    Eigen::Vector3d vp = final_vps.col(a).normalized();
    if (vp.z() < 0.0) vp = -vp;
    summary->vanishing_points[a] = vp;
    summary->vanishing_point_rms_px[a] = std::sqrt(family_sum_sq[a] / summary->segments_per_axis[a]);
    const Eigen::Vector3d d = summary->cam_from_world_rotation.col(a);
    const double distance_px = d.z() != 0.0 ? summary->focal_px * d.head<2>().norm() / std::abs(d.z())
                                            : std::numeric_limits<double>::infinity();
    summary->vanishing_point_to_principal_point_px[a] = distance_px;
    summary->min_vanishing_point_to_principal_point_px =
        std::min(summary->min_vanishing_point_to_principal_point_px, distance_px);
    summary->min_family_angle_spread_deg =
        std::min(summary->min_family_angle_spread_deg, summary->family_angle_spread_deg[a]);
  }
  if (problem.use_horizon) {
    Eigen::VectorXd r;
    problem.Residuals(camera, &r);
    summary->horizon_residual_px = std::sqrt(0.5 * r.segment<2>(problem.segments.size()).squaredNorm()) * scale_px;
  }
}

// The warnings about a usable calibration: an ambiguous vertical, nearly parallel families,
// vanishing points far away or near the principal point, a nearly degenerate triangle,
// outliers, a principal point outside the image. directions: the closed form's.
void AddQualityWarnings(const VpCalibrationOptions& options, const Families& families, const FreeVanishingPoints& free,
                        const Eigen::Matrix3d& directions, PrincipalPointMode mode, VpCalibrationSummary* summary) {
  std::vector<std::string>& warnings = summary->warnings;
  if (std::abs(summary->cam_from_world_rotation(1, 2)) < 1e-3)
    warnings.push_back("the vertical (family z) is nearly parallel to the image rows: up and down are ambiguous");
  for (int a = 0; a < 3; ++a) {
    if (!families.present[a]) continue;
    if (summary->family_angle_spread_deg[a] < kMinAngleSpreadDeg && !free.at_infinity[a])
      warnings.push_back(FamilyName(a) + ": its segments are nearly parallel in the image (largest angle " +
                         internal::FormatNumber(summary->family_angle_spread_deg[a], 6) +
                         " deg between two), so its vanishing point is poorly fixed");
    if (free.at_infinity[a]) continue;
    const double to_plane_deg = std::asin(std::min(1.0, std::abs(directions(2, a)))) * kRadToDeg;
    if (to_plane_deg < kFarVanishingPointDeg)
      warnings.push_back(FamilyName(a) + ": vanishing point very far from the image (direction " +
                         internal::FormatNumber(to_plane_deg, 6) +
                         " deg from the image plane); the focal length is poorly constrained");
    if (90.0 - to_plane_deg < kCentralVanishingPointDeg)
      warnings.push_back(FamilyName(a) + ": vanishing point near the principal point (" +
                         internal::FormatNumber(summary->vanishing_point_to_principal_point_px[a], 6) +
                         " px, direction " + internal::FormatNumber(90.0 - to_plane_deg, 6) +
                         " deg from the optical axis); the focal length is poorly constrained");
  }
  if (mode == PrincipalPointMode::kSolve && summary->vanishing_point_triangle_max_angle_deg > kMaxTriangleAngleDeg)
    warnings.push_back("the vanishing-point triangle is nearly degenerate (largest angle " +
                       internal::FormatNumber(summary->vanishing_point_triangle_max_angle_deg, 6) +
                       " deg): the principal point and focal length are poorly fixed");
  if (!summary->outlier_segments.empty()) {
    std::string list;
    for (size_t k = 0; k < summary->outlier_segments.size() && k < 10; ++k)
      list += (k ? ", " : "") + std::to_string(summary->outlier_segments[k]);
    if (summary->outlier_segments.size() > 10) list += ", ...";
    warnings.push_back(std::to_string(summary->outlier_segments.size()) +
                       " segment(s) flagged as outliers (residual above " +
                       internal::FormatNumber(summary->outlier_threshold_px, 6) + " px): " + list +
                       (summary->refitted_without_outliers ? "; the camera was refitted without them" : ""));
  }
  if (mode == PrincipalPointMode::kSolve) {
    const Eigen::Vector2d& c = summary->principal_point_px;
    if (c.x() < 0 || c.y() < 0 || c.x() > options.width_px - 1 || c.y() > options.height_px - 1)
      warnings.push_back("the solved principal point (" + internal::FormatNumber(c.x(), 6) + ", " +
                         internal::FormatNumber(c.y(), 6) +
                         ") lies outside the image: a cropped photo, or inaccurate vanishing points");
  }
}

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
    *error = "the fixed focal length must be finite and positive (0 to solve it), got " +
             internal::FormatNumber(fixed_focal_px, 6);
    return false;
  }
  const bool has_prior = focal_prior_px != 0.0 || focal_prior_std_px != 0.0;
  if (has_prior && (!(focal_prior_px > 0.0) || !(focal_prior_std_px > 0.0) || !std::isfinite(focal_prior_px) ||
                    !std::isfinite(focal_prior_std_px))) {
    *error = "the focal length prior needs a positive value and a positive standard deviation, got " +
             internal::FormatNumber(focal_prior_px, 6) + " +- " + internal::FormatNumber(focal_prior_std_px, 6) + " px";
    return false;
  }
  if (has_prior && fixed_focal_px > 0.0) {
    *error = "give either a fixed focal length or a focal length prior, not both";
    return false;
  }
  if (use_horizon && (!horizon_px.allFinite() ||
                      (horizon_px.head<2>() - horizon_px.tail<2>()).norm() < 1e-6 * std::max(width_px, height_px))) {
    *error = "the horizon needs two distinct finite points";
    return false;
  }
  if (warm_start && (!(warm_start_focal_px > 0.0) || !std::isfinite(warm_start_focal_px) ||
                     !warm_start_principal_point_px.allFinite() || !warm_start_rotation.allFinite())) {
    *error = "the warm start needs a finite positive focal length, principal point and rotation";
    return false;
  }
  if (max_joint_iterations < 0) {
    *error = "the joint fit's iteration budget must not be negative";
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
  if (!options.Check(&error)) return FailedSummary(summary, error, start, SolverTermination::kInvalidInput);
  Families families;
  if (!GroupFamilies(segments, options, &families, &summary, &error))
    return FailedSummary(summary, error, start, SolverTermination::kInvalidInput);

  const Conditioning conditioning{Eigen::Vector2d((options.width_px - 1) / 2.0, (options.height_px - 1) / 2.0),
                                  std::max(options.width_px, options.height_px) / 2.0};
  const double scale_px = conditioning.scale_px;
  summary.conditioning_scale_px = scale_px;
  summary.segment_residuals_px.assign(segments.size(), 0.0);
  FreeVanishingPoints free;
  if (!FitFreeVanishingPoints(families, conditioning, &free, &summary, &error) ||
      !FamiliesAreDistinct(families, free, &error))
    return FailedSummary(summary, error, start);
  ClosedForm closed_form;
  if (!SolveClosedForm(options, families, free, conditioning, &closed_form, &summary, &error))
    return FailedSummary(summary, error, start);
  std::array<Eigen::Vector2d, 2> horizon;  // conditioned
  if (options.use_horizon) {
    horizon[0] = conditioning.FromPixels(options.horizon_px.head<2>());
    horizon[1] = conditioning.FromPixels(options.horizon_px.tail<2>());
  }
  Eigen::Matrix3d directions;
  if (!VanishingDirections(families, free, closed_form, horizon, &directions, &summary, &error))
    return FailedSummary(summary, error, start);

  // Noise of the segments (conditioned) from the free vanishing points, each of which took 2
  // degrees of freedom. The floor (3e-8 of the conditioning scale, ~1e-5 px) keeps the prior
  // rows from vanishing against exact data, which would leave a direction only a prior fixes
  // numerically singular.
  const int num_segments = static_cast<int>(segments.size());
  const double independent_rms_px = std::sqrt(free.sum_squared_residuals_px / num_segments);
  const double noise =
      std::max(std::sqrt(free.sum_squared_residuals_px / std::max(1, num_segments - 2 * families.count)) / scale_px,
               kNoiseFloor);
  const JointProblem full_problem = MakeJointProblem(options, families, conditioning, closed_form, noise, horizon);
  JointCamera camera =
      StartCamera(options, full_problem, conditioning, closed_form, NearestRotation(ChooseAxisSigns(directions)));
  JointProblem problem;
  FitJointly(options, full_problem, scale_px, segments.size(), &problem, &camera, &summary);
  EstimateUncertainty(options, families, closed_form, problem, camera, noise, scale_px, &summary);
  ReportFinalCamera(segments, families, full_problem, problem, camera, conditioning, &summary);

  if (closed_form.started_from_center) {
    // Orthogonal directions that explain the segments about as well as free vanishing points
    // do mean the closed form failed on noise, not on inconsistent families.
    if (!(summary.rms_residual_px <= kMaxJointRmsRatio * independent_rms_px + kJointRmsSlackPx))
      return FailedSummary(summary,
                           closed_form.no_real_focal + " (a fit with orthogonal directions leaves " +
                               internal::FormatNumber(summary.rms_residual_px, 6) + " px RMS against " +
                               internal::FormatNumber(independent_rms_px, 6) + " px for free vanishing points)",
                           start);
    summary.warnings.push_back(
        "the three vanishing points alone give no real focal length (a vanishing point far from the image makes "
        "them unstable); the camera was fitted to all segments starting from the image centre");
  }
  if (!summary.cam_from_world_rotation.allFinite() || !std::isfinite(summary.focal_px) ||
      !summary.principal_point_px.allFinite())
    return FailedSummary(summary, "the calibration is not finite (numerical failure)", start);
  std::string not_a_camera =
      WhyNotACamera(summary.focal_px, summary.principal_point_px, options.width_px, options.height_px);
  if (not_a_camera.empty()) not_a_camera = WhyFocalIsUndetermined(summary.focal_px, summary.focal_std_px);
  if (!not_a_camera.empty()) return FailedSummary(summary, "no camera: " + not_a_camera, start);
  AddQualityWarnings(options, families, free, directions, closed_form.mode, &summary);

  summary.message = "f = " + internal::FormatNumber(summary.focal_px, 6) + " px";
  if (std::isfinite(summary.focal_std_px) && summary.focal_std_px > 0.0)
    summary.message += " +- " + internal::FormatNumber(summary.focal_std_px, 6);
  summary.message += ", principal point (" + internal::FormatNumber(summary.principal_point_px.x(), 6) + ", " +
                     internal::FormatNumber(summary.principal_point_px.y(), 6) + ") px from " +
                     std::to_string(families.count) +
                     (families.count == 1 ? " vanishing point and the horizon" : " vanishing points");
  summary.time_ms = internal::MsSince(start);
  return summary;
}

}  // namespace facet
