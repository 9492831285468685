// The similarity transform (scale, rotation, translation) that best maps one point set onto
// another in the least-squares sense (Umeyama 1991, "Least-squares estimation of
// transformation parameters between two point patterns"): for bringing a reconstruction in its
// own frame (COLMAP's) into the project's or the ground truth's, from the camera centres both
// have.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

namespace facet {

// target ~ scale * rotation * source + translation.
struct SimilarityTransform {
  double scale = 1.0;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Eigen::Vector3d Apply(const Eigen::Vector3d& p) const { return scale * rotation * p + translation; }
};

struct SimilarityFit {
  bool ok = false;
  std::string message;  // why not, when !ok
  SimilarityTransform transform;
  double rms_residual = 0.0;  // of |target - transform(source)|, in the target's units
};

// Minimises sum_i |target_i - (s R source_i + t)|^2 over s > 0, R in SO(3) (a proper rotation,
// never a reflection), t. Needs at least three pairs, the source points not all on one line
// (the rotation about that line would be free); refused otherwise.
SimilarityFit FitSimilarity(const std::vector<Eigen::Vector3d>& source, const std::vector<Eigen::Vector3d>& target);

}  // namespace facet
