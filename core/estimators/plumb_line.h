// Radial lens distortion (one or two coefficients) estimated from image polylines that should
// be straight (the plumb-line method of Brown, 1971), so a wide-angle photo can be calibrated
// from the same lines as a pinhole one.
//
// Model (polynomial undistortion, evaluated on the distorted pixel so that undistorting is a
// closed form and the plumb-line cost needs no inversion):
//   r    = |uv_d - c| / s
//   uv_u = c + (uv_d - c) * (1 + k1 r^2 + k2 r^4)
// uv_d: distorted (observed) pixel; uv_u: the pixel of an ideal pinhole camera with the same
// focal length and principal point; c: centre of distortion, the principal point or, by
// default, the image centre ((w - 1) / 2, (h - 1) / 2); s: half the image diagonal,
// 0.5 * sqrt(w^2 + h^2), so r <= ~1 inside the image and k1, k2 do not depend on resolution.
// Barrel distortion (straight lines bowing outwards, OpenCV k1 < 0) has k1 > 0 here.
// The centre is never estimated: plumb lines determine it poorly; pass the principal point
// when it is known.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/optim/solver_summary.h"

namespace facet {

// The model above with its centre and scale. The default (k1 = k2 = 0) is the identity.
struct RadialDistortion {
  Eigen::Vector2d center_px = Eigen::Vector2d::Zero();
  double scale_px = 1.0;  // s, > 0
  double k1 = 0.0;
  double k2 = 0.0;

  // Undistorted pixel of a distorted (observed) pixel; closed form.
  Eigen::Vector2d Undistort(const Eigen::Vector2d& uv_distorted_px) const;
  // Distorted pixel of an undistorted pixel: Newton on the radius, converged to 1e-12 px.
  // Returns false (and leaves *uv_distorted_px at the closest radius found) when no distorted
  // radius on the monotonic branch of the model (the part containing the centre, where
  // d r_u / d r_d > 0) maps to this point, e.g. far outside the image with k1 << 0.
  bool Distort(const Eigen::Vector2d& uv_undistorted_px, Eigen::Vector2d* uv_distorted_px) const;
  // Undistorted radius in px of a distorted radius in px (the 1-D model).
  double UndistortRadiusPx(double radius_distorted_px) const;
};

// s = half the image diagonal, in px.
double RadialDistortionScalePx(int width_px, int height_px);
// The identity model of a w x h image: centre (w - 1) / 2, (h - 1) / 2 unless center_px is
// given, scale RadialDistortionScalePx.
RadialDistortion MakeRadialDistortion(int width_px, int height_px,
                                      const std::optional<Eigen::Vector2d>& center_px = std::nullopt);

// OpenCV's radial model (p1 = p2 = 0, principal point = our centre, fx = fy = focal_px):
// x_u = (uv_u - c) / f, rho = |x_u|, uv_d = c + f x_u (1 + k1 rho^2 + k2 rho^4 + k3 rho^6).
struct OpenCvRadialCoefficients {
  double k1 = 0.0;
  double k2 = 0.0;
  double k3 = 0.0;
};

// The two models differ beyond first order (ours is a polynomial in the distorted radius,
// OpenCV's in the undistorted one), so each conversion is a linear least-squares fit of the
// radial mapping, sampled uniformly in distorted radius over [0, max_radius_px] (use the
// distance from the centre to the farthest image corner), minimising the squared px error of
// the fitted model's output radius. To first order k1 = -k1_cv * (s / f)^2.
// *max_error_px (optional) receives the largest radial disagreement in px over that range.
// fit_k2 = false fits k1 alone (k2 = 0 / k2_cv = 0); k3 of the result is always 0.
RadialDistortion RadialDistortionFromOpenCv(const OpenCvRadialCoefficients& opencv, double focal_px,
                                            const Eigen::Vector2d& center_px, double scale_px, double max_radius_px,
                                            bool fit_k2 = true, double* max_error_px = nullptr);
OpenCvRadialCoefficients OpenCvFromRadialDistortion(const RadialDistortion& distortion, double focal_px,
                                                    double max_radius_px, bool fit_k2 = true,
                                                    double* max_error_px = nullptr);

// One polyline of observed (distorted) pixels that lies on one straight 3-D line.
struct PlumbLine {
  std::vector<Eigen::Vector2d> points_px;  // 2 or more, in order or not
  // Lines with the same family >= 0 are parallel in 3-D, so after undistortion they pass
  // through one common vanishing point (homogeneous, may be at infinity); this lets 2-point
  // segments contribute. -1: no family (each polyline gets its own best-fit line, so it needs
  // 3 or more points to say anything).
  int family = -1;
};

struct PlumbLineOptions {
  int width_px = 0;  // image size: fixes the scale s and the default centre; both > 0
  int height_px = 0;
  std::optional<Eigen::Vector2d> center_px;  // centre of distortion; unset: the image centre
  bool estimate_k2 = false;                  // k2 only when asked; still dropped (with a warning) when the data
                                             // cannot separate it from k1
  int max_iterations = 100;                  // Levenberg-Marquardt iterations
  // A warning says k1 is poorly determined when std(k1) > poorly_determined_ratio * |k1|.
  double poorly_determined_ratio = 0.5;

  bool Check(std::string* error) const;
};

// SolverSummary: message says why it failed, or gives the result in one line; warnings: a
// usable result the user should know about; iterations: accepted steps of both fits (the
// vanishing points at k = 0, then k with them); initial_cost / final_cost: the cost below
// (squared distances in observed px, summed) at k = 0 with the vanishing points fitted, and
// at the result.
struct PlumbLineSummary : SolverSummary {
  // The estimate; k1 = k2 = 0 (identity) when the summary is not IsUsable().
  RadialDistortion distortion;
  bool k2_estimated = false;
  // One-sigma standard deviations from the Gauss-Newton covariance scaled by the residual
  // variance (k2_std = 0 when k2 was not estimated).
  double k1_std = 0.0;
  double k2_std = 0.0;
  // Residual standard deviation per constraint, in px of the observed image (see the cost).
  double noise_sigma_px = 0.0;
  // Straightness: RMS over the points of all polylines that constrain anything (not free
  // 2-point polylines, which are always straight) of the distance to their line (each polyline's
  // own best-fit line, or for a family the line through its vanishing point and the
  // polyline's centroid, H&Z 8.6.1), before (k = 0) and after undistortion, in px of the
  // undistorted image.
  double initial_rms_px = 0.0;
  double final_rms_px = 0.0;
  std::vector<double> line_rms_px;  // per input polyline, after
  // Per family index 0..max family: unit homogeneous vanishing point in undistorted px,
  // third coordinate >= 0 (zero at infinity); zero vector for an unused index.
  std::vector<Eigen::Vector3d> vanishing_points_px;
  int num_constraints = 0;  // independent residuals: points minus line and vanishing-point dofs
};

// Estimates k1 (and k2 when asked) from the polylines, starting from k = 0, by
// Levenberg-Marquardt over k and, per family, the vanishing point on the unit sphere; the
// free line of each polyline without a family is eliminated in closed form (smallest
// eigenvector of its 2x2 scatter matrix). Cost: the sum over points of the squared distance
// of the undistorted point to its line, divided by the local stretch of the undistortion
// across that line, i.e. to first order the distance in the observed image where the
// clicking noise is (maximum likelihood for isotropic pixel noise). Jacobian by central
// differences over k and the vanishing points (each of which moves only its own family's
// residuals). Fails with k = 0 and a message on: bad options, non-finite points, a
// polyline with fewer than 2 points, fewer than (number of coefficients + 1) independent
// constraints, or lines that carry no distortion information (all through the centre, where
// radial distortion keeps them straight) or a diverged fit (the input's faults are
// kInvalidInput, the others kFailed).
PlumbLineSummary EstimateRadialDistortion(const std::vector<PlumbLine>& lines, const PlumbLineOptions& options);

}  // namespace facet
