// Least-squares vanishing point of one family of image line segments, homogeneous throughout
// so that vanishing points at or near infinity (segments parallel in the image) are handled.
// The fit starts from the algebraic solution (smallest singular vector of the stacked segment
// lines, each weighted by its length) and refines it by Levenberg-Marquardt over the unit
// sphere, minimising the squared distances of each segment's endpoints to the line through
// the segment's midpoint and the vanishing point (the maximum-likelihood-style cost of
// Hartley & Zisserman, 2nd ed., section 8.6.1).
#pragma once

#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/optim/solver_summary.h"

namespace facet {

struct VanishingPointOptions {
  // Conditioning: pixels are mapped to (uv_px - center_px) / scale_px before fitting, so the
  // numbers are of order 1 (use the image centre and half the larger image side).
  Eigen::Vector2d conditioning_center_px = Eigen::Vector2d::Zero();
  double conditioning_scale_px = 1.0;
  bool refine = true;       // false keeps the algebraic fit
  int max_iterations = 50;  // Levenberg-Marquardt iterations of the refinement

  bool Check(std::string* error) const;
};

// SolverSummary: message says why it failed; iterations are the refinement's accepted steps;
// initial_cost / final_cost are the sums over segments of residuals_px^2 (px^2) at the
// algebraic fit and at the result.
struct VanishingPointSummary : SolverSummary {
  // Unit-norm homogeneous vanishing point in pixels, and in conditioned coordinates; the
  // third coordinate is >= 0 (zero for a vanishing point at infinity).
  Eigen::Vector3d vp_px = Eigen::Vector3d::Zero();
  Eigen::Vector3d vp_conditioned = Eigen::Vector3d::Zero();
  // Distance from the image centre of the conditioned vanishing point in units of
  // conditioning_scale_px; +infinity for a vanishing point at infinity.
  double distance_in_scales = 0.0;
  // Ratio of the second smallest to the largest singular value of the stacked lines: near
  // zero when all segments lie on one line (the vanishing point is then undetermined).
  double line_spread = 0.0;
  // Per segment (input order): distance in px of its endpoints to the line through its
  // midpoint and the vanishing point (both endpoints are equally far by symmetry).
  std::vector<double> residuals_px;
  double initial_rms_px = 0.0;  // of the algebraic fit
  double final_rms_px = 0.0;
  bool refined = false;  // the refinement ran and was kept
  // First-order uncertainty of the result: sigma^2 (J^T J)^-1 in the plane tangent to the
  // unit sphere at vp_conditioned (J: the residuals' derivatives there), with sigma^2 = sum of
  // squared residuals / (n - 2), the noise the segments show. As a 3 x 3 covariance of
  // vp_conditioned (rank 2), and propagated to the image point (u, v) = vp_px's (x / w, y / w)
  // in px^2. NaN with 2 segments (no redundancy to measure the noise); the point's is NaN at
  // infinity too.
  Eigen::Matrix3d vp_conditioned_covariance = Eigen::Matrix3d::Constant(std::numeric_limits<double>::quiet_NaN());
  Eigen::Matrix2d point_covariance_px2 = Eigen::Matrix2d::Constant(std::numeric_limits<double>::quiet_NaN());
};

// segments_px: one (x1, y1, x2, y2) per segment, 2 or more, none of zero length.
// Fewer than 2 segments, a zero-length or non-finite segment (kInvalidInput), or all
// segments on one line (kFailed) give a summary that is not IsUsable().
VanishingPointSummary FitVanishingPoint(const std::vector<Eigen::Vector4d>& segments_px,
                                        const VanishingPointOptions& options);

// Distance in px of a segment's endpoints to the line through its midpoint and the
// homogeneous vanishing point vp_px; +infinity when the vanishing point is the midpoint.
double SegmentVanishingPointResidualPx(const Eigen::Vector4d& segment_px, const Eigen::Vector3d& vp_px);
// The same distance with a sign (which side of that line endpoint a lies on), smooth in
// vp_px for least squares; it works in any coordinates the segment and point share.
double SegmentVanishingPointSignedDistance(const Eigen::Vector4d& segment, const Eigen::Vector3d& vp);

}  // namespace facet
