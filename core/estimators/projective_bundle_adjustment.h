// Projective bundle adjustment: refines 3x4 projection matrices and homogeneous points of a
// projective reconstruction to minimise the reprojection error in pixels, before any metric
// upgrade (the absolute dual quadric of core/estimators/self_calibration.h is sensitive to the drift an
// incremental, resection-by-resection reconstruction accumulates).
//
// Shapes and frames: cameras[v] is a 3x4 P acting on homogeneous world points X (4-vectors)
// in normalised image coordinates; pixel_from_normalised[v] (3x3, e.g. the normalising K of
// self-calibration) maps P X to homogeneous pixels, so an observation's residual is
// dehomogenise(N_v P_v X_j) - uv_px. Both are up to scale: each camera and point is moved
// only orthogonally to itself (11 and 3 degrees of freedom) and renormalised to unit norm, so
// points at or near the plane at infinity stay representable. The 15-dimensional projective
// gauge is left to the damping: the result is one of the equivalent minima.
//
// Degenerate input (no observations, an index out of range, non-finite pixels) returns
// an unusable summary with a message and leaves cameras and points unchanged.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/estimators/projective_upgrade.h"
#include "core/optim/solver_summary.h"

namespace facet {

struct ProjectiveBundleObservation {
  int view = 0;
  int point = 0;
  Eigen::Vector2d uv_px = Eigen::Vector2d::Zero();
};

struct ProjectiveBundleOptions {
  int max_iterations = 50;

  bool Check(std::string* error) const;
};

// initial_cost / final_cost: the sum of squared reprojection errors (px^2).
struct ProjectiveBundleSummary : SolverSummary {
  double initial_rms_px = 0.0;
  double final_rms_px = 0.0;
};

ProjectiveBundleSummary ProjectiveBundleAdjust(const std::vector<ProjectiveBundleObservation>& observations,
                                               const std::vector<Eigen::Matrix3d>& pixel_from_normalised,
                                               const ProjectiveBundleOptions& options, std::vector<Matrix34d>* cameras,
                                               std::vector<Eigen::Vector4d>* points);

}  // namespace facet
