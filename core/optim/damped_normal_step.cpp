#include "core/optim/damped_normal_step.h"

#include <Eigen/Cholesky>

#include "core/util/eigen_decompositions.h"

namespace facet {
namespace {

template <typename NormalMatrix, typename Gradient, typename Damping>
typename Gradient::PlainObject Step(const NormalMatrix& normal, const Gradient& gradient, double lambda,
                                    const Damping& damping) {
  typename NormalMatrix::PlainObject damped = normal;
  damped.diagonal() += lambda * damping;
  return damped.ldlt().solve(-gradient);
}

}  // namespace

Eigen::VectorXd DampedNormalStep(const Eigen::MatrixXd& normal, const Eigen::VectorXd& gradient, double lambda,
                                 const Eigen::VectorXd& damping) {
  return Step(normal, gradient, lambda, damping);
}

Eigen::Vector2d DampedNormalStep(const Eigen::Matrix2d& normal, const Eigen::Vector2d& gradient, double lambda,
                                 const Eigen::Vector2d& damping) {
  return Step(normal, gradient, lambda, damping);
}

}  // namespace facet
