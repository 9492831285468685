#include "core/texture/view_blend.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>

namespace facet {
namespace {

constexpr double kSigmaN = 1.0;  // grey levels
constexpr double kSigmaG = 0.5;
constexpr double kMinGain = 0.25;
constexpr double kMaxGain = 4.0;

}  // namespace

std::vector<Eigen::Vector3d> FitExposureGains(int view_count, const std::vector<ExposureOverlap>& overlaps) {
  std::vector<Eigen::Vector3d> gains(static_cast<size_t>(std::max(0, view_count)), Eigen::Vector3d::Ones());
  if (view_count <= 1) return gains;
  for (int c = 0; c < 3; ++c) {
    Eigen::MatrixXd a = Eigen::MatrixXd::Zero(view_count, view_count);
    Eigen::VectorXd b = Eigen::VectorXd::Zero(view_count);
    Eigen::VectorXd prior = Eigen::VectorXd::Zero(view_count);
    for (const ExposureOverlap& o : overlaps) {
      if (!(o.count > 0.0) || o.view_a == o.view_b) continue;
      const double mean_a = o.sum_a[c] / o.count, mean_b = o.sum_b[c] / o.count;
      const double w = o.count / (kSigmaN * kSigmaN);
      a(o.view_a, o.view_a) += w * mean_a * mean_a;
      a(o.view_b, o.view_b) += w * mean_b * mean_b;
      a(o.view_a, o.view_b) -= w * mean_a * mean_b;
      a(o.view_b, o.view_a) -= w * mean_a * mean_b;
      prior[o.view_a] += o.count;
      prior[o.view_b] += o.count;
    }
    for (int v = 0; v < view_count; ++v) {
      const double w = prior[v] > 0.0 ? prior[v] / (kSigmaG * kSigmaG) : 1.0;
      a(v, v) += w;
      b[v] += w;
    }
    const Eigen::VectorXd g = a.ldlt().solve(b);
    for (int v = 0; v < view_count; ++v) {
      gains[v][c] = std::isfinite(g[v]) ? std::clamp(g[v], kMinGain, kMaxGain) : 1.0;
    }
  }
  return gains;
}

}  // namespace facet
