// Two-view geometry from user correspondences: the fundamental matrix (the paper's epipolar
// constraint, refined on the symmetric point-to-epipolar-line distance) and, with known
// intrinsics, the essential matrix and the relative pose of the second camera.
//
// Shapes and conventions (core/geometry/conventions.h): uv1[i] in image 1 and uv2[i] in image 2 are
// the pixels (OpenCV convention) of one scene point; F maps a point of image 1 to its
// epipolar line in image 2: uv2^T F uv1 = 0 in homogeneous pixels. K1, K2 are 3x3 upper
// triangular intrinsics. The relative pose is cam2_from_cam1: p_in_cam2 = R p_in_cam1 + t,
// with |t| = 1 (two views fix the baseline only up to scale), so E = [t]x R and
// x2^T E x1 = 0 for x = K^-1 uv.
//
// The symmetric epipolar RMS, used throughout (px):
//   sqrt( sum_{i in inliers} (d(uv2_i, F uv1_i)^2 + d(uv1_i, F^T uv2_i)^2) / (2 * #inliers) ),
// where d(x, l) is the distance of a pixel to a line: the RMS of both directions' distances.
//
// References: Hartley & Zisserman, Multiple View Geometry, 2nd ed.: 11.1-11.3 (normalised
// 8-point, 7-point), 11.4.3 and 11.6 (symmetric epipolar distance, RANSAC), 9.6 (E and its
// four decompositions); Bartoli & Sturm, "Non-linear estimation of the fundamental matrix
// with minimal parameters", PAMI 2004 (orthonormal representation F = U diag(1, s, 0) V^T).
#pragma once

#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/optim/levenberg_marquardt.h"
#include "core/optim/solver_summary.h"

namespace facet {

struct FundamentalOptions {
  // RANSAC over 7-point samples flags wrong clicks when there are more than 8 matches. A
  // match is an inlier when the RMS of its two point-to-epipolar-line distances is below
  // the threshold.
  bool use_ransac = true;
  double inlier_threshold_px = 3.0;
  int max_ransac_iterations = 5000;
  double ransac_confidence = 0.9999;
  unsigned seed = 1;  // RANSAC is deterministic for a given seed
  // Levenberg-Marquardt on the symmetric epipolar distance over the 7 parameters of the
  // orthonormal representation, started from the normalised 8-point estimate on the inliers.
  bool refine = true;
  int max_refine_iterations = 100;
  // Fill FundamentalSummary::refine_trace (Teach mode's stepping, core/estimators/fit_steps.h).
  bool record_refine_trace = false;
  // Warm start: begin the refinement at this F (rank 2 is taken from its SVD) instead of the
  // linear estimate, e.g. Teach mode's start moved off the answer. The inliers are decided as
  // without it; the "initial" figures of the summary are then this F's.
  bool warm_start = false;
  Eigen::Matrix3d warm_start_F = Eigen::Matrix3d::Zero();
  // A warning when a homography explains the matches (symmetric transfer RMS) within this
  // factor of F's RMS plus the slack: a planar scene or a pure rotation leaves F loose.
  double homography_warning_ratio = 2.0;
  double homography_warning_slack_px = 1.0;

  bool Check(std::string* error) const;
};

// iterations: of the final refinement; initial_cost / final_cost: the sum of the squared
// symmetric epipolar distances (px^2) over the inliers, of the linear and the final estimate.
// warnings: a usable result the user should know about (7 or 8 matches, outliers, a
// homography that fits as well).
struct FundamentalSummary : SolverSummary {
  // x2^T F x1 = 0; unit Frobenius norm, sign such that the entry of largest magnitude is
  // positive; rank 2.
  Eigen::Matrix3d F = Eigen::Matrix3d::Zero();
  std::vector<bool> inliers;  // per input match
  int num_inliers = 0;
  // Symmetric epipolar RMS over the inliers (see the top of this file) of the linear
  // (8-point or 7-point) estimate and of the final one.
  double initial_symmetric_epipolar_rms_px = 0.0;
  double symmetric_epipolar_rms_px = 0.0;
  // Symmetric transfer RMS of the best homography (DLT) on the inliers; 0 if not computed.
  double homography_rms_px = 0.0;
  int ransac_iterations = 0;
  // Refits that tried flagged matches near the threshold back in (bounded: at most 32 single
  // and 66 pair trials, whatever the number of matches).
  int readmission_refits = 0;
  // With FundamentalOptions::record_refine_trace: every trial of the final refinement (cost in
  // px^2, step in the orthonormal representation's 7 parameters).
  std::vector<LmIteration> refine_trace;
};

// Estimates F from 7 or more matches (uv1.size() == uv2.size()). Fewer than 7 matches (or
// fewer than 7 distinct ones), non-finite coordinates, all points of an image on one line,
// and configurations where F is not unique (e.g. a noise-free planar scene) give a summary
// that is not usable, with a message. With exactly 7 matches the 7-point algorithm gives up to
// three F; the one with the smallest RMS is returned with a warning.
FundamentalSummary EstimateFundamentalMatrix(const std::vector<Eigen::Vector2d>& uv1,
                                             const std::vector<Eigen::Vector2d>& uv2,
                                             const FundamentalOptions& options);

struct RelativePoseOptions {
  // Levenberg-Marquardt on the symmetric epipolar distance (px) of F = K2^-T [t]x R K1^-1
  // over R and the direction of t (5 parameters).
  bool refine = true;
  int max_refine_iterations = 100;

  bool Check(std::string* error) const;
};

// iterations: of the refinement; initial_cost / final_cost: the sum of the squared symmetric
// epipolar distances (px^2) over the points used, before and after it.
struct RelativePoseSummary : SolverSummary {
  // E = [t]x R (singular values 1, 1, 0).
  Eigen::Matrix3d E = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d cam2_from_cam1_rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d cam2_from_cam1_translation = Eigen::Vector3d::Zero();  // unit norm
  // Inlier matches whose triangulated point lies in front of both cameras, out of
  // num_points (the inliers used).
  int points_in_front = 0;
  int num_points = 0;
  // Symmetric epipolar RMS (px) of the projected E before and after the refinement.
  double initial_symmetric_epipolar_rms_px = 0.0;
  double symmetric_epipolar_rms_px = 0.0;
};

// Relative pose from F (any scale, rank 2) and the intrinsics: E = K2^T F K1 projected to
// the essential manifold, the decomposition whose triangulated inliers lie in front of both
// cameras most often, then the optional refinement. inliers may be empty (all matches are
// used) or have one flag per match. Fewer than 5 points, a non-invertible K, non-finite
// input, or no decomposition with a majority in front give an unusable summary.
RelativePoseSummary EstimateRelativePose(const Eigen::Matrix3d& F, const Eigen::Matrix3d& K1, const Eigen::Matrix3d& K2,
                                         const std::vector<Eigen::Vector2d>& uv1,
                                         const std::vector<Eigen::Vector2d>& uv2, const std::vector<bool>& inliers,
                                         const RelativePoseOptions& options);

// Building blocks, exposed for tests and benchmarks.

// Normalised 8-point with rank-2 enforcement on all given matches (8 or more). Returns
// false when the design matrix has a null space of more than one dimension (F not unique).
bool FundamentalEightPoint(const std::vector<Eigen::Vector2d>& uv1, const std::vector<Eigen::Vector2d>& uv2,
                           Eigen::Matrix3d* F);
// 7-point algorithm on exactly 7 matches: the real roots of det(a F1 + (1 - a) F2) = 0,
// 1 to 3 rank-2 matrices (none for a degenerate sample).
std::vector<Eigen::Matrix3d> FundamentalSevenPoint(const std::vector<Eigen::Vector2d>& uv1,
                                                   const std::vector<Eigen::Vector2d>& uv2);
// Signed distances (px) of uv2 to the line F uv1 and of uv1 to the line F^T uv2; both zero
// when a line is undefined (F uv1 = 0).
Eigen::Vector2d SymmetricEpipolarDistances(const Eigen::Matrix3d& F, const Eigen::Vector2d& uv1,
                                           const Eigen::Vector2d& uv2);
// The symmetric epipolar RMS (top of this file) over the flagged matches (all when inliers
// is empty); 0 with no match.
double SymmetricEpipolarRms(const Eigen::Matrix3d& F, const std::vector<Eigen::Vector2d>& uv1,
                            const std::vector<Eigen::Vector2d>& uv2, const std::vector<bool>& inliers = {});
// E projected to the essential manifold (singular values 1, 1, 0) and its four
// (R, t) decompositions, t unit norm: (R_a, t), (R_a, -t), (R_b, t), (R_b, -t).
std::array<std::pair<Eigen::Matrix3d, Eigen::Vector3d>, 4> DecomposeEssential(const Eigen::Matrix3d& E);
// F scaled to unit Frobenius norm with its largest-magnitude entry positive.
Eigen::Matrix3d NormalizeFundamental(const Eigen::Matrix3d& F);

namespace internal {

// Residuals (2 per match: the two signed distances of SymmetricEpipolarDistances) and their
// Jacobian with respect to the 9 entries of F in row-major order (rows 2i, 2i + 1).
void SymmetricEpipolarResiduals(const Eigen::Matrix3d& F, const std::vector<Eigen::Vector2d>& uv1,
                                const std::vector<Eigen::Vector2d>& uv2, Eigen::VectorXd* residuals,
                                Eigen::Matrix<double, Eigen::Dynamic, 9>* jacobian);

// The orthonormal representation F = T2^T (U diag(1, s, 0) V^T) T1 with fixed T1, T2
// (Hartley normalisations), updated by U <- U exp([w_u]x), V <- V exp([w_v]x), s <- s + ds:
// 7 parameters (w_u, w_v, ds).
struct OrthonormalFundamental {
  Eigen::Matrix3d T1 = Eigen::Matrix3d::Identity(), T2 = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d U = Eigen::Matrix3d::Identity(), V = Eigen::Matrix3d::Identity();
  double s = 1.0;

  static OrthonormalFundamental FromF(const Eigen::Matrix3d& F, const Eigen::Matrix3d& T1, const Eigen::Matrix3d& T2);
  Eigen::Matrix3d F() const;
  OrthonormalFundamental Plus(const Eigen::Matrix<double, 7, 1>& delta) const;
  // d vec(F) / d delta at delta = 0, vec row-major.
  Eigen::Matrix<double, 9, 7> Tangent() const;
};

// F = K2^-T [t]x R K1^-1 with R <- R exp([w]x), t <- normalize(t + a b1 + b b2) (b1, b2 an
// orthonormal basis of the plane orthogonal to t): 5 parameters (w, a, b).
struct PoseFundamental {
  Eigen::Matrix3d K1_inv = Eigen::Matrix3d::Identity(), K2_inv = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::UnitX();

  Eigen::Matrix3d F() const;
  PoseFundamental Plus(const Eigen::Matrix<double, 5, 1>& delta) const;
  Eigen::Matrix<double, 9, 5> Tangent() const;
};

}  // namespace internal
}  // namespace facet
