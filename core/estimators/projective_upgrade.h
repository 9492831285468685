// Stratified reconstruction from two uncalibrated views: projective cameras from F, the affine
// upgrade through the plane at infinity found from matched vanishing points, and the metric
// upgrade with known intrinsics.
//
// Shapes and conventions (core/geometry/conventions.h): pixels uv follow the OpenCV convention; F is
// that of core/estimators/two_view.h (uv2^T F uv1 = 0). A projection matrix P is 3x4 and maps a
// homogeneous world point X (4-vector) to the homogeneous pixel P X. Projective and affine
// frames are arbitrary up to a 4x4 homography (affine: one whose last row is (0, 0, 0, s));
// "world_b_from_world_a" is the 4x4 H with X_b = H X_a, so cameras change as P_b = P_a H^-1.
// Vanishing points are homogeneous 3-vectors (a point at infinity of the image has z = 0).
// The metric result is a Euclidean frame up to a global similarity (rotation, translation,
// scale): P_i = K_i [R_i | t_i], cam_from_world as everywhere in Facet.
//
// References: Hartley & Zisserman, Multiple View Geometry, 2nd ed.: 9.5 (canonical cameras
// P1 = [I | 0], P2 = [[e']x F | e']), 12.2 and 12.4 (linear triangulation, reprojection
// refinement), 10.4.1 (affine upgrade from three vanishing points), 10.4.2 and 19.1 (metric
// upgrade from the image of the absolute conic).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/optim/solver_summary.h"

namespace facet {

using Matrix34d = Eigen::Matrix<double, 3, 4>;

// P1 = [I | 0], P2 = [[e']x F | e'] with e' the left epipole (F^T e' = 0, unit norm). F must
// have rank 2; a zero or non-finite F returns false.
bool CanonicalCamerasFromFundamental(const Eigen::Matrix3d& F, Matrix34d* P1, Matrix34d* P2);

// Linear (DLT) triangulation of one point seen in 2 or more views: cameras[k] and x[k] are
// the projection matrix and the homogeneous image point of view k (a pixel uv as (u, v, 1),
// a vanishing point as it is). Each row pair is normalised, so views weigh alike. Returns
// the unit-norm homogeneous point (sign: last coordinate >= 0); zero for fewer than 2 views.
Eigen::Vector4d TriangulateLinear(const std::vector<Matrix34d>& cameras, const std::vector<Eigen::Vector3d>& x);

// Gauss-Newton/LM on the reprojection error (px) of one homogeneous point, over the 3
// directions orthogonal to it (so points at or near infinity stay representable). Returns the
// refined unit-norm point; the start point if it cannot be improved.
Eigen::Vector4d RefineTriangulatedPoint(const std::vector<Matrix34d>& cameras, const std::vector<Eigen::Vector2d>& uv,
                                        const Eigen::Vector4d& start, int max_iterations = 20);

// Pixel of a homogeneous point; NaN when it projects to infinity.
Eigen::Vector2d ProjectHomogeneous(const Matrix34d& P, const Eigen::Vector4d& X);

struct ProjectiveReconstructionOptions {
  bool refine_points = true;  // reprojection refinement after the linear triangulation
  int max_point_iterations = 20;

  bool Check(std::string* error) const;
};

// No iterations; initial_cost / final_cost: the sum of squared reprojection errors (px^2) of
// the matches, both images, after the linear triangulation and after the refinement.
struct ProjectiveReconstructionSummary : SolverSummary {
  Matrix34d P1 = Matrix34d::Zero(), P2 = Matrix34d::Zero();  // canonical pair
  std::vector<Eigen::Vector4d> points;                       // per match, unit norm
  // Per match: the RMS of its two reprojection errors (px).
  std::vector<double> reprojection_errors_px;
  double reprojection_rms_px = 0.0;  // over all matches, both images
};

// Canonical cameras from F and the triangulated matches (uv1.size() == uv2.size(), any
// number including zero). Bad F or non-finite input gives an unusable summary.
ProjectiveReconstructionSummary ReconstructProjective(const Eigen::Matrix3d& F, const std::vector<Eigen::Vector2d>& uv1,
                                                      const std::vector<Eigen::Vector2d>& uv2,
                                                      const ProjectiveReconstructionOptions& options);

struct AffineUpgradeOptions {
  // Warning when the triangulated vanishing points fit a plane worse than this (the smallest
  // singular value over the largest of the stacked normalised points): inconsistent vanishing
  // points, or their matches across the images are wrong.
  double plane_residual_warning = 1e-3;

  bool Check(std::string* error) const;
};

// A linear solve: no iterations, and initial_cost / final_cost stay 0 (plane_residual is the
// fit's measure).
struct AffineUpgradeSummary : SolverSummary {
  Eigen::Vector4d plane_at_infinity = Eigen::Vector4d::Zero();           // in the projective frame, unit norm
  Eigen::Matrix4d affine_from_projective = Eigen::Matrix4d::Identity();  // X_a = H X_p
  std::vector<Matrix34d> cameras;                                        // P_a = P_p H^-1
  std::vector<Eigen::Vector4d> vanishing_points_3d;                      // triangulated, projective frame, unit norm
  double plane_residual = 0.0;                                           // see the option
};

// Plane at infinity from 3 or more vanishing points matched across the views (vanishing[k][v]
// is the k-th direction's vanishing point in view v; every direction must be seen in every
// view, and views.size() == cameras.size() >= 2). Fewer than 3 directions, directions that
// triangulate onto a line (fewer than 3 independent ones), or a plane through the first
// camera's centre give an unusable summary.
AffineUpgradeSummary UpgradeToAffine(const std::vector<Matrix34d>& cameras,
                                     const std::vector<std::vector<Eigen::Vector3d>>& vanishing,
                                     const AffineUpgradeOptions& options);

struct MetricCamera {
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d cam_from_world_rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d cam_from_world_translation = Eigen::Vector3d::Zero();
};

struct MetricUpgradeOptions {
  // Warning when a camera's left 3x3, after the upgrade, deviates from K_i times a rotation by
  // more than this (relative): the given intrinsics do not fit the affine reconstruction.
  double rotation_residual_warning = 1e-2;

  bool Check(std::string* error) const;
};

// A linear solve: no iterations, and initial_cost / final_cost stay 0 (max_rotation_residual
// is the fit's measure).
struct MetricUpgradeSummary : SolverSummary {
  Eigen::Matrix4d metric_from_affine = Eigen::Matrix4d::Identity();  // X_m = H X_a
  std::vector<MetricCamera> cameras;  // K as given, R orthonormalised, t in the metric frame
  // The largest relative deviation of K_i^-1 M_i A (the metric camera's left 3x3 over its
  // scale) from a rotation: 0 for intrinsics consistent with the affine reconstruction.
  double max_rotation_residual = 0.0;
};

// Metric upgrade of an affine reconstruction (cameras.size() == K.size() >= 1, each camera's
// left 3x3 M_i invertible) with known intrinsics K_i: the symmetric C = A A^T and the scales
// s_i solving M_i C M_i^T = s_i K_i K_i^T in least squares (the dual image of the absolute
// conic transported by each camera), A its Cholesky factor, H = [[A, 0], [0, 1]]^-1 (scaled
// so det A = 1). Cameras change as P_m = P_a H^-1, points as X_m = H X_a. The upgrade leaves
// a reflection free: affine_points (homogeneous, any number) choose the one that puts most of
// them in front of the cameras; with none, the result may be the mirror image. A C that is
// not positive definite (intrinsics inconsistent with the reconstruction, or not an affine
// one) gives an unusable summary.
MetricUpgradeSummary UpgradeToMetric(const std::vector<Matrix34d>& affine_cameras,
                                     const std::vector<Eigen::Matrix3d>& K,
                                     const std::vector<Eigen::Vector4d>& affine_points,
                                     const MetricUpgradeOptions& options);

// P = s K [R | t] with K upper triangular, positive diagonal, K(2, 2) = 1, det R = +1 (the
// sign of P is free, so s may be negative). False for a singular left 3x3 or non-finite P.
bool DecomposeProjectionMatrix(const Matrix34d& P, Eigen::Matrix3d* K, Eigen::Matrix3d* R, Eigen::Vector3d* t);

// A similarity p_b = scale * rotation * p_a + translation.
struct Similarity3d {
  double scale = 1.0;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  Eigen::Vector3d operator*(const Eigen::Vector3d& p_a) const { return scale * rotation * p_a + translation; }
};

// The least-squares similarity b_from_a taking points_a[i] to points_b[i] (Umeyama, PAMI 1991:
// the rotation from the SVD of the cross-covariance, det +1). Fewer than 3 points, different
// sizes, non-finite input, or points of a on one line return false.
bool AlignSimilarity(const std::vector<Eigen::Vector3d>& points_a, const std::vector<Eigen::Vector3d>& points_b,
                     Similarity3d* b_from_a);

// Applies X_b = H X_a to homogeneous points (unit norm out, last coordinate >= 0).
std::vector<Eigen::Vector4d> TransformPoints(const Eigen::Matrix4d& b_from_a,
                                             const std::vector<Eigen::Vector4d>& points);

}  // namespace facet
