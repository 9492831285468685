// The damped Levenberg-Marquardt step of a bundle adjustment, by the Schur complement over its
// 3x3 point blocks. Shared by the metric bundle adjustment (core/estimators/self_calibration.h)
// and the projective one (core/estimators/projective_bundle_adjustment.h).
//
// The normal equations over nc camera parameters and m points of 3 parameters each:
//   [ U    W ] [dc]     [g_c]      U: nc x nc; V = diag(V_1 .. V_m), V_j 3 x 3;
//   [ W^T  V ] [dp] = - [g_p]      W = [W_1 .. W_m], W_j nc x 3; g = J^T r.
// Damping (Marquardt, scaled by the diagonal): every diagonal entry d of U gets
// lambda * (d + 1e-12 * max diag U), of V_j lambda * (d + 1e-12 * max diag V_j); the floor
// keeps a parameter without curvature (a gauge direction) solvable.
// The reduced camera system S dc = b, S = U - sum_j W_j V_j^-1 W_j^T, b = -g_c + sum_j W_j
// V_j^-1 g_p_j (damped U and V_j), is solved densely by LDLT (fine for the tens of views a
// user clicks in, any number of points); then dp_j = V_j^-1 (-g_p_j - W_j^T dc).
// Sparsity: W_j is non-zero only in the rows of the cameras that see point j (and of
// parameters every camera shares, such as a shared focal length); camera_rows[j] lists them
// and only that sub-block of S is updated (the Middlebury ring's self-calibration: 20 s -> 4 s).
#pragma once

#include <vector>

#include <Eigen/Core>

namespace facet {

struct SchurNormalEquations {
  Eigen::MatrixXd u;                          // nc x nc
  Eigen::VectorXd g_c;                        // nc
  std::vector<Eigen::Matrix3d> v;             // per point
  std::vector<Eigen::Vector3d> g_p;           // per point
  std::vector<Eigen::MatrixXd> w;             // per used point, nc x 3 (empty for unused points)
  std::vector<std::vector<int>> camera_rows;  // per point, the rows where W_j may be non-zero
  std::vector<bool> point_used;               // per point; an unused point gets a zero step

  // Sizes for nc camera parameters and camera_rows.size() points; all blocks zero.
  void Reset(int num_camera_parameters, std::vector<std::vector<int>> camera_rows, std::vector<bool> point_used);
  // All blocks back to zero at the same sizes (before accumulating a new linearisation).
  void SetZero();
  int NumCameraParameters() const { return static_cast<int>(g_c.size()); }
  int NumPoints() const { return static_cast<int>(v.size()); }
};

struct SchurStep {
  Eigen::VectorXd camera;               // dc, nc
  std::vector<Eigen::Vector3d> points;  // dp_j per point (zero for unused points)

  double SquaredNorm() const;  // |dc|^2 + sum_j |dp_j|^2

  // Workspace kept between calls (the reduced system and the damped point inverses).
  Eigen::MatrixXd reduced;
  Eigen::VectorXd rhs;
  std::vector<Eigen::Matrix3d> v_inverse;
};

// Solves the damped normal equations at `lambda` (>= 0) into *step. False when the reduced
// camera system has no finite solution.
bool SolveDampedSchurStep(const SchurNormalEquations& equations, double lambda, SchurStep* step);

}  // namespace facet
