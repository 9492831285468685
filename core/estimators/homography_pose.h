// Two views of one plane: the homography between the images from point correspondences, and
// with known intrinsics its decomposition into the relative pose and the plane, for the case
// where the fundamental matrix is not unique (every match on one face of the model).
//
// Shapes and conventions (core/geometry/conventions.h): uv1[i] in image 1 and uv2[i] in image 2 are
// the pixels of one point of the plane; H maps image 1 to image 2: uv2 ~ H uv1 in homogeneous
// pixels. K1, K2 are 3x3 upper-triangular intrinsics. The pose is cam2_from_cam1:
// p_in_cam2 = R p_in_cam1 + t. The plane, in camera 1's frame, is n^T p = d with n a unit
// normal pointing away from camera 1 (d > 0, the distance of camera 1's centre from the
// plane), so that K2^-1 H K1 ~ R + (t / d) n^T. Two views fix the scale only up to one
// factor: t / d is determined; the summary also gives t scaled to unit norm.
//
// The symmetric transfer RMS, used throughout (px):
//   sqrt( sum_{i in inliers} (|uv2_i - H(uv1_i)|^2 + |uv1_i - H^-1(uv2_i)|^2) / (2 * #inliers) ).
//
// Decomposition (Faugeras & Lustman 1988, in the SVD form of Ma, Soatto, Kosecka & Sastry,
// "An Invitation to 3-D Vision", 5.3): the calibrated homography scaled so that its middle
// singular value is 1 has four (R, t / d, n) solutions in two sign-paired couples. Those that
// put every inlier in front of both cameras (cheirality) and both camera centres on the same
// side of the plane (an opaque face is seen from one side) remain; generally two do, a genuine
// ambiguity of one view pair of a plane that the image evidence cannot break (both reproduce
// H exactly). Then `ambiguous` is set and `candidates` lists both, the first one with the
// smaller reprojection error of the points triangulated on its plane (equal up to rounding for
// an exact H); a caller that knows the plane (e.g. the model's positions of the points) picks
// the candidate that matches it. A pure rotation (t = 0, the homography is K2 R K1^-1) gives
// one solution with t = 0 and n undefined (a warning; the baseline is then zero).
//
// Degenerate input: fewer than 4 matches, non-finite values, all points of an image on one
// line (or three of four in a minimal set), a homography whose null space is not unique: a
// summary that is not IsUsable(), with a message. RANSAC over 4-point samples flags wrong clicks
// when there are 6 or more matches (5 cannot tell a wrong one from a right one: any 4 fit).
// References: Hartley & Zisserman, Multiple View Geometry, 2nd ed., 4.1-4.2 (normalised DLT,
// symmetric transfer error), 4.7 (RANSAC), 13.1 (homography induced by a plane).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/optim/solver_summary.h"

namespace facet {

struct HomographyOptions {
  // RANSAC over 4-point samples when there are 6 or more matches. A match is an inlier when
  // the RMS of its two transfer distances is below the threshold.
  bool use_ransac = true;
  double inlier_threshold_px = 3.0;
  int max_ransac_iterations = 2000;
  double ransac_confidence = 0.9999;
  unsigned seed = 1;  // deterministic for a given seed
  // Levenberg-Marquardt on the symmetric transfer distances over the 8 free entries of H,
  // started from the normalised DLT on the inliers.
  bool refine = true;
  int max_refine_iterations = 100;

  bool Check(std::string* error) const;
};

// SolverSummary: iterations are the refinement's linearisations (0 without it); initial_cost /
// final_cost the sum over the inliers of their four squared transfer residuals (px^2), for
// the DLT on the inliers and for the final H.
struct HomographySummary : SolverSummary {
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();  // unit Frobenius norm, H(2, 2) >= 0
  std::vector<bool> inliers;                    // per input match
  int num_inliers = 0;
  double initial_symmetric_transfer_rms_px = 0.0;  // the DLT on the inliers
  double symmetric_transfer_rms_px = 0.0;          // the final H
  int ransac_iterations = 0;
};

// H from 4 or more matches (uv1.size() == uv2.size()).
HomographySummary EstimateHomography(const std::vector<Eigen::Vector2d>& uv1, const std::vector<Eigen::Vector2d>& uv2,
                                     const HomographyOptions& options);

// One decomposition of a calibrated homography.
struct PlanePose {
  Eigen::Matrix3d cam2_from_cam1_rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation_over_distance = Eigen::Vector3d::Zero();   // t / d
  Eigen::Vector3d cam2_from_cam1_translation = Eigen::Vector3d::Zero();  // unit norm (zero if t = 0)
  Eigen::Vector3d plane_normal_in_cam1 = Eigen::Vector3d::UnitZ();       // unit, away from camera 1
  int points_in_front = 0;           // inliers in front of both cameras, out of the summary's num_points
  bool centres_on_one_side = false;  // both camera centres on the near side of the plane
  // RMS (px) over both images of the inliers triangulated on this plane and reprojected.
  double reprojection_rms_px = 0.0;
};

struct HomographyPoseOptions {
  HomographyOptions homography;

  bool Check(std::string* error) const;
};

// SolverSummary: termination, iterations and costs are the homography's (the decomposition is
// closed form); warnings include the homography's.
struct HomographyPoseSummary : SolverSummary {
  HomographySummary homography;
  // The chosen decomposition (candidates[0]), repeated for convenience.
  Eigen::Matrix3d cam2_from_cam1_rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d cam2_from_cam1_translation = Eigen::Vector3d::Zero();  // unit norm
  Eigen::Vector3d translation_over_distance = Eigen::Vector3d::Zero();
  Eigen::Vector3d plane_normal_in_cam1 = Eigen::Vector3d::UnitZ();
  // The decompositions that pass cheirality and the one-side test, best first; more than one
  // sets ambiguous (see the top of this file).
  std::vector<PlanePose> candidates;
  bool ambiguous = false;
  bool pure_rotation = false;  // no measurable baseline
  int num_points = 0;          // inliers used
};

// Estimates H from the matches (options.homography) and decomposes it with K1, K2.
HomographyPoseSummary EstimatePlanePose(const std::vector<Eigen::Vector2d>& uv1,
                                        const std::vector<Eigen::Vector2d>& uv2, const Eigen::Matrix3d& K1,
                                        const Eigen::Matrix3d& K2, const HomographyPoseOptions& options);

// Building blocks, exposed for tests.

// The four decompositions of a calibrated homography G ~ R + (t / d) n^T (any scale and
// sign: G is scaled to a middle singular value of 1 and its sign chosen by the points x1, x2
// of matched rays, x2^T G x1 > 0 for most). Empty when G is singular or not finite.
std::vector<PlanePose> DecomposeCalibratedHomography(const Eigen::Matrix3d& G, const std::vector<Eigen::Vector3d>& x1,
                                                     const std::vector<Eigen::Vector3d>& x2);
// Per match, the RMS of its two transfer distances (px) under H; infinity where undefined.
std::vector<double> SymmetricTransferErrors(const Eigen::Matrix3d& H, const std::vector<Eigen::Vector2d>& uv1,
                                            const std::vector<Eigen::Vector2d>& uv2);

}  // namespace facet
