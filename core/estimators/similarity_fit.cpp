#include "core/estimators/similarity_fit.h"

#include <cmath>

#include <Eigen/LU>

#include "core/util/eigen_decompositions.h"

namespace facet {

SimilarityFit FitSimilarity(const std::vector<Eigen::Vector3d>& source, const std::vector<Eigen::Vector3d>& target) {
  SimilarityFit fit;
  const size_t n = source.size();
  if (n != target.size() || n < 3) {
    fit.message = "a similarity needs at least three point pairs";
    return fit;
  }
  Eigen::Vector3d mean_source = Eigen::Vector3d::Zero(), mean_target = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < n; ++i) {
    if (!source[i].allFinite() || !target[i].allFinite()) {
      fit.message = "a point is not a number";
      return fit;
    }
    mean_source += source[i];
    mean_target += target[i];
  }
  mean_source /= n;
  mean_target /= n;
  double source_variance = 0.0;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();  // target x source^T
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d a = source[i] - mean_source;
    source_variance += a.squaredNorm();
    covariance += (target[i] - mean_target) * a.transpose();
  }
  source_variance /= n;
  covariance /= n;
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(covariance, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Vector3d d = svd.singularValues();
  // The second singular value vanishes when either set lies on a line: the rotation is then free.
  if (!(source_variance > 0.0) || !(d(1) > 1e-12 * d(0))) {
    fit.message = "the points lie on one line: the rotation about it is free";
    return fit;
  }
  Eigen::Vector3d signs(1.0, 1.0, 1.0);
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0.0) signs(2) = -1.0;
  fit.transform.rotation = svd.matrixU() * signs.asDiagonal() * svd.matrixV().transpose();
  fit.transform.scale = d.dot(signs) / source_variance;
  fit.transform.translation = mean_target - fit.transform.scale * fit.transform.rotation * mean_source;
  double sum = 0.0;
  for (size_t i = 0; i < n; ++i) sum += (target[i] - fit.transform.Apply(source[i])).squaredNorm();
  fit.rms_residual = std::sqrt(sum / n);
  fit.ok = true;
  return fit;
}

}  // namespace facet
