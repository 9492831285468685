#include "core/calibrate_vp.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>

#include <Eigen/Dense>

#include "core/camera.h"
#include "core/vanishing_point.h"

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

constexpr double kRadToDeg = 180.0 / M_PI;

std::string Fmt(double x) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.6g", x);
  return buffer;
}

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

// Maximum-likelihood-style fit of the whole camera to all segments at once: focal length,
// principal point (when solved) and rotation, with the three vanishing directions kept
// orthogonal by construction (v_a = K R e_a). Residuals are the segments' endpoint distances
// (core/vanishing_point.h) in conditioned coordinates. Levenberg-Marquardt on log f, the
// principal point and a left rotation increment; the Jacobian by central differences
// (6 columns, cheap next to the fit's other costs). Returns the number of accepted steps.
struct JointSegment {
  Eigen::Vector4d segment;  // conditioned
  int axis;
};

Eigen::VectorXd JointResiduals(const std::vector<JointSegment>& segments, double f, const Eigen::Vector2d& pp,
                               const Eigen::Matrix3d& r, double prior_weight) {
  Eigen::Matrix3d k = Eigen::Matrix3d::Identity();
  k(0, 0) = k(1, 1) = f;
  k(0, 2) = pp.x();
  k(1, 2) = pp.y();
  const Eigen::Matrix3d vps = k * r;
  Eigen::VectorXd residuals(segments.size() + (prior_weight > 0 ? 2 : 0));
  for (size_t i = 0; i < segments.size(); ++i)
    residuals(i) = SegmentVanishingPointSignedDistance(segments[i].segment, vps.col(segments[i].axis));
  if (prior_weight > 0) residuals.tail<2>() = prior_weight * pp;
  return residuals;
}

int RefineJointly(const std::vector<JointSegment>& segments, bool solve_pp, double prior_weight, double* f,
                  Eigen::Vector2d* pp, Eigen::Matrix3d* r) {
  const int num_params = solve_pp ? 6 : 4;
  auto apply = [&](const Eigen::VectorXd& delta, double* f_out, Eigen::Vector2d* pp_out, Eigen::Matrix3d* r_out) {
    *f_out = *f * std::exp(delta(0));
    *pp_out = solve_pp ? Eigen::Vector2d(*pp + delta.segment<2>(1)) : *pp;
    *r_out = RotationFromAngleAxis(delta.tail<3>()) * *r;
  };
  auto residuals_at = [&](const Eigen::VectorXd& delta) {
    double f2;
    Eigen::Vector2d pp2;
    Eigen::Matrix3d r2;
    apply(delta, &f2, &pp2, &r2);
    return JointResiduals(segments, f2, pp2, r2, prior_weight);
  };
  Eigen::VectorXd residuals = JointResiduals(segments, *f, *pp, *r, prior_weight);
  double cost = residuals.squaredNorm();
  double lambda = 1e-4;
  int accepted = 0;
  constexpr double kStep = 1e-7;
  Eigen::MatrixXd jacobian(residuals.size(), num_params);
  for (int iteration = 0; iteration < 100 && std::isfinite(cost) && cost > 0.0; ++iteration) {
    for (int p = 0; p < num_params; ++p) {
      Eigen::VectorXd delta = Eigen::VectorXd::Zero(num_params);
      delta(p) = kStep;
      const Eigen::VectorXd plus = residuals_at(delta);
      delta(p) = -kStep;
      jacobian.col(p) = (plus - residuals_at(delta)) / (2 * kStep);
    }
    const Eigen::MatrixXd jtj = jacobian.transpose() * jacobian;
    const Eigen::VectorXd jtr = jacobian.transpose() * residuals;
    bool improved = false;
    while (lambda < 1e12) {
      Eigen::MatrixXd damped = jtj;
      damped.diagonal() += lambda * (jtj.diagonal().array() + 1e-12).matrix();
      const Eigen::VectorXd step = -damped.ldlt().solve(jtr);
      if (!step.allFinite()) break;
      double f2;
      Eigen::Vector2d pp2;
      Eigen::Matrix3d r2;
      apply(step, &f2, &pp2, &r2);
      const Eigen::VectorXd candidate = JointResiduals(segments, f2, pp2, r2, prior_weight);
      const double candidate_cost = candidate.squaredNorm();
      if (candidate_cost < cost) {
        const double decrease = cost - candidate_cost;
        *f = f2;
        *pp = pp2;
        *r = r2;
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
  return true;
}

VpCalibrationSummary CalibrateFromVanishingLines(const std::vector<Segment>& segments,
                                                 const VpCalibrationOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  VpCalibrationSummary summary;
  std::string error;
  if (!options.Check(&error)) return Fail(summary, error, start);

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
  if (num_families < 2)
    return Fail(summary,
                "calibration needs at least two line families (x, y, z), got " +
                    (num_families == 0 ? std::string("none") : "only " + present_names),
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
  for (int a = 0; a < 3; ++a) {
    if (!present[a]) continue;
    const VanishingPointSummary fit = FitVanishingPoint(family_segments[a], vp_options);
    if (!fit.success) return Fail(summary, FamilyName(a) + ": " + fit.message, start);
    v[a] = fit.vp_conditioned;
    summary.vanishing_points[a] = fit.vp_px;
    at_infinity[a] = fit.distance_in_scales > kAtInfinityDistance;
    summary.vanishing_point_at_infinity[a] = at_infinity[a];
    summary.vanishing_point_rms_px[a] = fit.final_rms_px;
    for (size_t k = 0; k < fit.residuals_px.size(); ++k)
      summary.segment_residuals_px[family_indices[a][k]] = fit.residuals_px[k];
    if (fit.line_spread < kNearlyCollinearSpread)
      summary.warnings.push_back(FamilyName(a) + ": its segments lie nearly on one line, so its vanishing point is poorly fixed");
  }

  // Intrinsics from the image of the absolute conic, omega ~ [[1, 0, -cx], [0, 1, -cy],
  // [-cx, -cy, cx^2 + cy^2 + f^2]] in conditioned coordinates: orthogonal directions give
  // v_i^T omega v_j = (p_i - c w_i).(p_j - c w_j) + f^2 w_i w_j = 0 with v = (p, w).
  PrincipalPointMode mode = options.principal_point_mode;
  if (mode == PrincipalPointMode::kSolve && num_families == 2) {
    mode = PrincipalPointMode::kImageCenter;
    summary.warnings.push_back("two line families cannot fix the principal point; it was set to the image centre");
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
    if (!(f_squared > 0.0) && f_squared_at_center > 0.0) {
      started_from_center = true;
      pp.setZero();
      f_squared = f_squared_at_center;
    }
  } else {
    const Eigen::Vector2d pp_px =
        mode == PrincipalPointMode::kFixed ? options.fixed_principal_point_px : center_px;
    pp = (pp_px - center_px) / scale_px;
    f_squared = focal_squared_for(pp);
    if (std::isnan(f_squared))
      return Fail(summary,
                  "the focal length is undetermined: no two families have finite vanishing points (segments parallel "
                  "in the image)",
                  start);
  }
  const std::string no_real_focal =
      "the vanishing points give no real focal length (f^2 = " + Fmt(f_squared * scale_px * scale_px) +
      " px^2 <= 0): the vanishing-point triangle is obtuse or the families are not mutually orthogonal; check the "
      "family assignment of the segments";
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
  for (int a = 0; a < 3; ++a) {
    if (present[a]) continue;
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    directions.col(a) = directions.col(b).cross(directions.col(c)).normalized();
  }
  Eigen::Matrix3d rotation = NearestRotation(ChooseAxisSigns(directions));

  // Joint fit of the camera to all segments. With a fixed principal point it enforces the
  // orthogonality the closed form only approximates. With the principal point solved, three
  // free vanishing points and (f, c, R) have the same 6 degrees of freedom, so the data alone
  // would return the closed form; the weak prior at the image centre, weighted by the noise
  // the segments show, decides only where the data leave the principal point loose (a
  // vanishing point far away) and vanishes for exact data.
  std::vector<JointSegment> joint;
  std::vector<int> joint_input_index;
  double independent_sum_sq = 0.0;
  for (int a = 0; a < 3; ++a)
    for (size_t k = 0; k < family_segments[a].size(); ++k) {
      const Eigen::Vector4d& s = family_segments[a][k];
      Eigen::Vector4d c;
      c.head<2>() = (s.head<2>() - center_px) / scale_px;
      c.tail<2>() = (s.tail<2>() - center_px) / scale_px;
      joint.push_back({c, a});
      joint_input_index.push_back(family_indices[a][k]);
      independent_sum_sq += std::pow(summary.segment_residuals_px[family_indices[a][k]], 2);
    }
  const double independent_rms_px = std::sqrt(independent_sum_sq / joint.size());
  const double prior_weight =
      mode == PrincipalPointMode::kSolve ? independent_rms_px / (kPrincipalPointPriorSigma * scale_px) : 0.0;
  summary.joint_fit_iterations =
      RefineJointly(joint, mode == PrincipalPointMode::kSolve, prior_weight, &f, &pp, &rotation);
  summary.focal_px = f * scale_px;
  summary.principal_point_px = center_px + scale_px * pp;
  summary.cam_from_world_rotation = NearestRotation(ChooseAxisSigns(rotation));

  // Report the vanishing points of the final camera and the residuals against them, so
  // that camera, points and residuals agree.
  Eigen::Matrix3d k_final = Eigen::Matrix3d::Identity();
  k_final(0, 0) = k_final(1, 1) = summary.focal_px;
  k_final(0, 2) = summary.principal_point_px.x();
  k_final(1, 2) = summary.principal_point_px.y();
  const Eigen::Matrix3d final_vps = k_final * summary.cam_from_world_rotation;
  double joint_sum_sq = 0.0;
  std::array<double, 3> family_sum_sq = {0, 0, 0};
  for (size_t i = 0; i < joint.size(); ++i) {
    const Segment& s = segments[joint_input_index[i]];
    const Eigen::Vector4d seg(s.a_px.x(), s.a_px.y(), s.b_px.x(), s.b_px.y());
    const double r = SegmentVanishingPointResidualPx(seg, final_vps.col(joint[i].axis));
    summary.segment_residuals_px[joint_input_index[i]] = r;
    joint_sum_sq += r * r;
    family_sum_sq[joint[i].axis] += r * r;
  }
  summary.rms_residual_px = std::sqrt(joint_sum_sq / joint.size());
  for (int a = 0; a < 3; ++a) {
    if (!present[a]) continue;
    Eigen::Vector3d vp = final_vps.col(a).normalized();
    if (vp.z() < 0.0) vp = -vp;
    summary.vanishing_points[a] = vp;
    summary.vanishing_point_rms_px[a] = std::sqrt(family_sum_sq[a] / summary.segments_per_axis[a]);
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
    if (!present[a] || at_infinity[a]) continue;
    const double to_plane_deg = std::asin(std::min(1.0, std::abs(directions(2, a)))) * kRadToDeg;
    if (to_plane_deg < kFarVanishingPointDeg)
      summary.warnings.push_back(FamilyName(a) + ": vanishing point very far from the image (direction " +
                                 Fmt(to_plane_deg) + " deg from the image plane); the focal length is poorly constrained");
    if (90.0 - to_plane_deg < kCentralVanishingPointDeg)
      summary.warnings.push_back(FamilyName(a) + ": vanishing point near the principal point (direction " +
                                 Fmt(90.0 - to_plane_deg) +
                                 " deg from the optical axis); the focal length is poorly constrained");
  }
  if (mode == PrincipalPointMode::kSolve) {
    const Eigen::Vector2d& c = summary.principal_point_px;
    if (c.x() < 0 || c.y() < 0 || c.x() > options.width_px - 1 || c.y() > options.height_px - 1)
      summary.warnings.push_back("the solved principal point (" + Fmt(c.x()) + ", " + Fmt(c.y()) +
                                 ") lies outside the image; the vanishing points are probably inaccurate");
  }

  summary.success = true;
  summary.message = "f = " + Fmt(summary.focal_px) + " px, principal point (" + Fmt(summary.principal_point_px.x()) +
                    ", " + Fmt(summary.principal_point_px.y()) + ") px from " + std::to_string(num_families) +
                    " vanishing points";
  summary.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

}  // namespace facet
