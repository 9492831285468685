#include "core/calibrate_vp.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>

#include <Eigen/Dense>

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

  Eigen::Vector2d pp;  // conditioned
  double f_squared = 0.0;
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
  } else {
    const Eigen::Vector2d pp_px =
        mode == PrincipalPointMode::kFixed ? options.fixed_principal_point_px : center_px;
    pp = (pp_px - center_px) / scale_px;
    double num = 0.0, den = 0.0, max_coefficient = 0.0;
    for (const auto& pair : pairs) {
      const Eigen::Vector3d& vi = v[pair[0]];
      const Eigen::Vector3d& vj = v[pair[1]];
      const double coefficient = vi.z() * vj.z();
      const double constant = (vi.head<2>() - pp * vi.z()).dot(vj.head<2>() - pp * vj.z());
      num += coefficient * constant;
      den += coefficient * coefficient;
      max_coefficient = std::max(max_coefficient, std::abs(coefficient));
    }
    if (!(max_coefficient > 1.0 / (kAtInfinityDistance * kAtInfinityDistance)))
      return Fail(summary,
                  "the focal length is undetermined: no two families have finite vanishing points (segments parallel "
                  "in the image)",
                  start);
    f_squared = -num / den;
  }
  if (!std::isfinite(f_squared))
    return Fail(summary, "the focal length is not finite (numerical failure)", start);
  if (f_squared <= 0.0)
    return Fail(summary,
                "the vanishing points give no real focal length (f^2 = " + Fmt(f_squared * scale_px * scale_px) +
                    " px^2 <= 0): the vanishing-point triangle is obtuse or the families are not mutually orthogonal; "
                    "check the family assignment of the segments",
                start);
  const double f = std::sqrt(f_squared);
  summary.focal_px = f * scale_px;
  summary.principal_point_px = center_px + scale_px * pp;

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
  summary.cam_from_world_rotation = NearestRotation(ChooseAxisSigns(directions));
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
