// The dense decompositions several translation units use, compiled once.
// Instantiating Eigen::JacobiSVD<MatrixXd> (with its ColPivHouseholderQR preconditioner),
// LDLT and ColPivHouseholderQR costs seconds of compile time in every file that uses them;
// the `extern template` declarations below make those files link against the single copy
// core/util/eigen_decompositions.cpp instantiates (in facet_util, which every part of Facet
// links). Only the out-of-line members are shared: inline ones, and the solve() member
// templates, are still compiled where they are used. Include this header after, or instead
// of, <Eigen/Dense>, <Eigen/SVD> or <Eigen/Cholesky>; the results are the same as without it.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/QR>
#include <Eigen/SVD>

extern template class Eigen::JacobiSVD<Eigen::MatrixXd>;
extern template class Eigen::JacobiSVD<Eigen::Matrix3d>;
extern template class Eigen::ColPivHouseholderQR<Eigen::MatrixXd>;
extern template class Eigen::LDLT<Eigen::MatrixXd>;
// LDLT::compute is a member template, which the class declaration above does not cover.
extern template Eigen::LDLT<Eigen::MatrixXd>& Eigen::LDLT<Eigen::MatrixXd>::compute<Eigen::MatrixXd>(
    const Eigen::EigenBase<Eigen::MatrixXd>&);
