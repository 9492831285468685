// The single copy of the decompositions core/util/eigen_decompositions.h declares.
#include "core/util/eigen_decompositions.h"

template class Eigen::JacobiSVD<Eigen::MatrixXd>;
template class Eigen::JacobiSVD<Eigen::Matrix3d>;
template class Eigen::ColPivHouseholderQR<Eigen::MatrixXd>;
template class Eigen::LDLT<Eigen::MatrixXd>;
template Eigen::LDLT<Eigen::MatrixXd>& Eigen::LDLT<Eigen::MatrixXd>::compute<Eigen::MatrixXd>(
    const Eigen::EigenBase<Eigen::MatrixXd>&);
