#include "core/estimators/two_view.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <limits>
#include <numeric>
#include <random>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>

#include "core/geometry/camera.h"
#include "core/geometry/cross_product_matrix.h"
#include "core/geometry/hartley_normalization.h"
#include "core/optim/levenberg_marquardt.h"
#include "core/optim/solver_summary.h"
#include "core/util/eigen_decompositions.h"
#include "core/util/format.h"
#include "core/util/timer.h"

namespace facet {
namespace {

using Clock = std::chrono::steady_clock;
using Points = std::vector<Eigen::Vector2d>;

// Second-smallest / largest singular value of the normalised 8-point design matrix below
// which its null space has two or more dimensions: F is not determined by the matches.
constexpr double kNullSpaceRatio = 1e-10;
// Smallest / largest spread of an image's points below which they lie on one line.
constexpr double kCollinearSpreadRatio = 1e-7;
// Two matches closer than this (px, in both images) are the same click.
constexpr double kSamePointPx = 1e-6;
// RANSAC draws at least this many samples. The adaptive count log(1 - p) / log(1 - w^7)
// falls to 1 once one sample's F explains every match, but that w is measured on a single
// 7-point model; a few more samples let MSAC choose among several all-inlier models, so an
// ill-conditioned sample (points bunched in one part of the image, whose F extrapolates
// badly) does not end the search alone. Missing a borderline match is not a reason for
// more samples: the final inlier set is decided on the refined F.
constexpr int kMinRansacIterations = 5;
// Rounds of fit -> re-classify on the refined F; more than two changes of the inlier set
// means it oscillates between borderline matches, and the last fitted set is kept.
constexpr int kMaxInlierRounds = 3;
// Flagged matches within this many thresholds of the refined F are tried back in (see
// EstimateFundamentalMatrix); wrong clicks lie farther and cost no refit.
constexpr double kReadmitFactor = 2.0;
// Pairs are tried only among this many readmission candidates (at most 66 refits).
constexpr size_t kMaxPairReadmitCandidates = 12;
// Single readmissions are tried for at most this many flagged matches, the nearest to F
// (each is a refit on all inliers). Leverage points are few; many matches just outside the
// threshold are noise or random outliers near their epipolar lines (1e5 matches with 90 %
// outliers put ~1,000 there, one refit each: most of a 32 s run).
constexpr size_t kMaxSingleReadmitCandidates = 32;

using internal::FailedSummary;
using internal::MsSince;
using internal::Skew;
Eigen::Matrix<double, 9, 1> VecRowMajor(const Eigen::Matrix3d& m) {
  Eigen::Matrix<double, 9, 1> v;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) v(3 * r + c) = m(r, c);
  return v;
}

Eigen::Matrix3d FromVecRowMajor(const Eigen::Matrix<double, 9, 1>& v) {
  Eigen::Matrix3d m;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m(r, c) = v(3 * r + c);
  return m;
}

Eigen::Vector3d Apply(const Eigen::Matrix3d& t, const Eigen::Vector2d& p) { return t * p.homogeneous(); }

// Rows kron(x2, x1) of the linear system A vec(Fn) = 0 in normalised coordinates.
Eigen::MatrixXd DesignMatrix(const Points& uv1, const Points& uv2, const Eigen::Matrix3d& t1,
                             const Eigen::Matrix3d& t2) {
  Eigen::MatrixXd a(uv1.size(), 9);
  for (size_t i = 0; i < uv1.size(); ++i) {
    const Eigen::Vector3d x1 = Apply(t1, uv1[i]);
    const Eigen::Vector3d x2 = Apply(t2, uv2[i]);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) a(i, 3 * r + c) = x2(r) * x1(c);
  }
  return a;
}

Points Select(const Points& uv, const std::vector<bool>& flags) {
  Points out;
  for (size_t i = 0; i < uv.size(); ++i)
    if (flags[i]) out.push_back(uv[i]);
  return out;
}

// Squared RMS of a match's two point-to-line distances.
double MatchSquaredError(const Eigen::Matrix3d& F, const Eigen::Vector2d& uv1, const Eigen::Vector2d& uv2) {
  return 0.5 * SymmetricEpipolarDistances(F, uv1, uv2).squaredNorm();
}

// Gauss-Newton blocks over F's nine entries (row-major), summed per match so that the
// 2n x 9 Jacobian is never formed: the LM's time is in this loop.
struct EpipolarNormalEquations {
  Eigen::Matrix<double, 9, 9> jtj = Eigen::Matrix<double, 9, 9>::Zero();
  Eigen::Matrix<double, 9, 1> jtr = Eigen::Matrix<double, 9, 1>::Zero();
};

// Sum of squared symmetric epipolar residuals (those of internal::SymmetricEpipolarResiduals)
// and, when `normal` is given, their normal equations over F.
double SymmetricEpipolarCost(const Eigen::Matrix3d& F, const Points& uv1, const Points& uv2,
                             EpipolarNormalEquations* normal) {
  double cost = 0.0;
  Eigen::Matrix<double, 9, 1> g1, g2;
  for (size_t i = 0; i < uv1.size(); ++i) {
    const Eigen::Vector3d x1 = uv1[i].homogeneous(), x2 = uv2[i].homogeneous();
    const Eigen::Vector3d l2 = F * x1, l1 = F.transpose() * x2;
    const double e = x2.dot(l2);
    const double n2_sq = l2.x() * l2.x() + l2.y() * l2.y(), n1_sq = l1.x() * l1.x() + l1.y() * l1.y();
    if (!(n2_sq > 0) || !(n1_sq > 0)) continue;
    const double inv_n2 = 1.0 / std::sqrt(n2_sq), inv_n1 = 1.0 / std::sqrt(n1_sq);
    const double r2 = e * inv_n2, r1 = e * inv_n1;
    cost += r2 * r2 + r1 * r1;
    if (!normal) continue;
    // d e / d F_rc = x2_r x1_c; d n2 / d F_rc = l2_r x1_c / n2 (r < 2); d n1 / d F_rc =
    // l1_c x2_r / n1 (c < 2).
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) {
        const double de = x2(r) * x1(c);
        const double dn2 = r < 2 ? l2(r) * x1(c) * inv_n2 : 0.0;
        const double dn1 = c < 2 ? l1(c) * x2(r) * inv_n1 : 0.0;
        g2(3 * r + c) = (de - r2 * dn2) * inv_n2;
        g1(3 * r + c) = (de - r1 * dn1) * inv_n1;
      }
    normal->jtj.noalias() += g2 * g2.transpose() + g1 * g1.transpose();
    normal->jtr += r2 * g2 + r1 * g1;
  }
  return cost;
}

// The symmetric epipolar residuals over a parameterisation of F (State: F(), Plus(delta),
// Tangent()) as a problem of the Levenberg-Marquardt driver.
template <int D, class State>
struct SymmetricEpipolarProblem {
  using VecD = Eigen::Matrix<double, D, 1>;
  using MatD = Eigen::Matrix<double, D, D>;
  const Points& uv1;
  const Points& uv2;
  State state;
  EpipolarNormalEquations normal;  // at state, over F's nine entries
  State candidate;
  EpipolarNormalEquations candidate_normal;
  MatD jtj;
  VecD jtr;

  bool Linearize() {
    const Eigen::Matrix<double, 9, D> tangent = state.Tangent();
    jtj = tangent.transpose() * normal.jtj * tangent;
    jtr = tangent.transpose() * normal.jtr;
    return false;
  }
  LmStepStatus Step(double lambda, LmTrial* trial) {
    MatD h = jtj;
    h.diagonal() += lambda * (jtj.diagonal().array() + 1e-12 * jtj.diagonal().maxCoeff()).matrix();
    const VecD delta = -h.ldlt().solve(jtr);
    if (!delta.allFinite()) return LmStepStatus::kSolveFailed;
    candidate = state.Plus(delta);
    candidate_normal = EpipolarNormalEquations();
    trial->cost = SymmetricEpipolarCost(candidate.F(), uv1, uv2, &candidate_normal);
    trial->step_squared_norm = delta.squaredNorm();
    return LmStepStatus::kSolved;
  }
  void Accept() {
    state = candidate;
    normal = candidate_normal;
  }
};

// Levenberg-Marquardt on the symmetric epipolar residuals. Only steps that lower the cost are
// taken, so the result is never worse than the start.
template <int D, class State>
State MinimizeSymmetricEpipolar(State state, const Points& uv1, const Points& uv2, int max_iterations, LmResult* result,
                                std::vector<LmIteration>* trace = nullptr) {
  SymmetricEpipolarProblem<D, State> problem{uv1, uv2, state, {}, state, {}, {}, {}};
  const double cost = SymmetricEpipolarCost(state.F(), uv1, uv2, &problem.normal);
  // A different rule from the driver's defaults, kept from the refinement's tuning: the
  // damping lambda (diag + 1e-12 max diag) scales J^T J's own diagonal (Marquardt), so lambda
  // is relative and starts at 1e-4 (Levenberg's absolute 1e-4 max diag damped the first steps
  // ~100-fold and cost 5 to 10 iterations); lambda / 10 and x 10 within [1e-15, 1e20); stop
  // when a step gains at most 1e-10 of the cost after it (= 1e-10 / (1 + 1e-10) of the cost
  // before, the driver's measure) or moves the parameters by less than 1e-12.
  LmOptions lm;
  lm.max_iterations = max_iterations;
  lm.initial_lambda = 1e-4;
  lm.lambda_decrease = 0.1;
  lm.lambda_increase = 10.0;
  lm.lambda_increase_on_failed_solve = 10.0;
  lm.min_lambda = 1e-15;
  lm.max_lambda = lm.max_lambda_on_failed_solve = 1e20;
  lm.relative_decrease_tolerance = 1e-10 / (1.0 + 1e-10);
  lm.min_step_squared_norm = 1e-24;
  if (trace != nullptr)
    lm.callback = [trace](const LmIteration& it) {
      trace->push_back(it);
      return true;
    };
  *result = MinimizeLevenbergMarquardt(cost, lm, problem);
  return problem.state;
}

// The sum of the squared distances (px^2) behind a symmetric epipolar RMS over `count` matches.
double SquaredRmsToSum(double rms_px, int count) { return rms_px * rms_px * 2.0 * count; }

// A refinement that ran out of iterations leaves a usable F, better than the linear one.
SolverTermination RefineTermination(const LmResult& result) {
  return result.termination == LmTermination::kMaxIterations ? SolverTermination::kMaxIterations
                                                             : SolverTermination::kConverged;
}

// The SVD of an n x 9 design matrix through its 9 x 9 triangular factor: the same singular
// values and right singular vectors as A's own SVD, at a fixed size (RANSAC calls this for
// every 7-point sample; a dynamic-size SVD of A was a sixth of the estimate's time).
Eigen::JacobiSVD<Eigen::Matrix<double, 9, 9>> DesignMatrixSvd(const Eigen::MatrixXd& a) {
  Eigen::Matrix<double, 9, 9> r = Eigen::Matrix<double, 9, 9>::Zero();
  if (a.rows() > 9) {
    const Eigen::HouseholderQR<Eigen::MatrixXd> qr(a);
    r = qr.matrixQR().topRows<9>().triangularView<Eigen::Upper>();
  } else {
    r.topRows(a.rows()) = a;
  }
  return Eigen::JacobiSVD<Eigen::Matrix<double, 9, 9>>(r, Eigen::ComputeFullV);
}

// Normalised DLT homography uv2 ~ H uv1 (4 or more matches); false when degenerate.
bool HomographyDlt(const Points& uv1, const Points& uv2, Eigen::Matrix3d* h) {
  const Eigen::Matrix3d t1 = internal::HartleyNormalization(uv1), t2 = internal::HartleyNormalization(uv2);
  Eigen::MatrixXd a(2 * uv1.size(), 9);
  for (size_t i = 0; i < uv1.size(); ++i) {
    const Eigen::Vector3d x = Apply(t1, uv1[i]);
    const Eigen::Vector3d y = Apply(t2, uv2[i]);
    a.row(2 * i) << 0, 0, 0, -y.z() * x.transpose(), y.y() * x.transpose();
    a.row(2 * i + 1) << y.z() * x.transpose(), 0, 0, 0, -y.x() * x.transpose();
  }
  const auto svd = DesignMatrixSvd(a);
  const Eigen::Matrix3d hn = FromVecRowMajor(svd.matrixV().col(8));
  *h = t2.inverse() * hn * t1;
  return h->allFinite() && std::abs(h->determinant()) > 0;
}

double HomographyTransferRms(const Eigen::Matrix3d& h, const Points& uv1, const Points& uv2) {
  const Eigen::Matrix3d h_inv = h.inverse();
  double sum = 0.0;
  for (size_t i = 0; i < uv1.size(); ++i) {
    const Eigen::Vector3d a = h * uv1[i].homogeneous();
    const Eigen::Vector3d b = h_inv * uv2[i].homogeneous();
    sum += (a.hnormalized() - uv2[i]).squaredNorm() + (b.hnormalized() - uv1[i]).squaredNorm();
  }
  return std::sqrt(sum / (2.0 * uv1.size()));
}

// "" when the points of one image are spread in two dimensions, else what is wrong.
std::string SpreadProblem(const Points& uv, const char* image_name) {
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  for (const auto& p : uv) centroid += p;
  centroid /= static_cast<double>(uv.size());
  Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
  for (const auto& p : uv) scatter += (p - centroid) * (p - centroid).transpose();
  const Eigen::Vector2d eig = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(scatter).eigenvalues();
  const double largest = std::sqrt(std::max(eig(1), 0.0)), smallest = std::sqrt(std::max(eig(0), 0.0));
  if (largest <= kSamePointPx) return std::string("all points of ") + image_name + " coincide";
  if (smallest < kCollinearSpreadRatio * largest)
    return std::string("all points of ") + image_name + " lie on one line: F is not determined";
  return "";
}

int CountDistinctMatches(const Points& uv1, const Points& uv2) {
  std::vector<int> order(uv1.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return uv1[a].x() < uv1[b].x(); });
  int distinct = 0;
  for (size_t i = 0; i < order.size(); ++i) {
    bool repeated = false;
    for (size_t j = i; j-- > 0;) {
      if (uv1[order[i]].x() - uv1[order[j]].x() > kSamePointPx) break;
      if ((uv1[order[i]] - uv1[order[j]]).norm() <= kSamePointPx &&
          (uv2[order[i]] - uv2[order[j]]).norm() <= kSamePointPx) {
        repeated = true;
        break;
      }
    }
    if (!repeated) ++distinct;
  }
  return distinct;
}

// The linear estimate on a set of 7 or more matches: 8-point, or the best 7-point root.
bool LinearFundamental(const Points& uv1, const Points& uv2, Eigen::Matrix3d* F, std::string* error) {
  if (uv1.size() >= 8) {
    if (FundamentalEightPoint(uv1, uv2, F)) return true;
    *error =
        "F is not unique: the matches fit a family of fundamental matrices (a planar scene or a pure rotation "
        "seen without noise, or points in a degenerate configuration)";
    return false;
  }
  const std::vector<Eigen::Matrix3d> candidates = FundamentalSevenPoint(uv1, uv2);
  if (candidates.empty()) {
    *error = "the 7 matches are in a degenerate configuration: the 7-point algorithm has no solution";
    return false;
  }
  double best = std::numeric_limits<double>::infinity();
  for (const auto& candidate : candidates) {
    const double rms = SymmetricEpipolarRms(candidate, uv1, uv2);
    if (rms < best) {
      best = rms;
      *F = candidate;
    }
  }
  return true;
}

std::vector<bool> Classify(const Eigen::Matrix3d& F, const Points& uv1, const Points& uv2, double threshold_px) {
  std::vector<bool> inliers(uv1.size());
  for (size_t i = 0; i < uv1.size(); ++i)
    inliers[i] = MatchSquaredError(F, uv1[i], uv2[i]) < threshold_px * threshold_px;
  return inliers;
}

int Count(const std::vector<bool>& flags) { return static_cast<int>(std::count(flags.begin(), flags.end(), true)); }

// MSAC over 7-point samples; returns the inlier flags of the best model.
std::vector<bool> Ransac(const Points& uv1, const Points& uv2, const FundamentalOptions& options, int* iterations) {
  const int n = static_cast<int>(uv1.size());
  const double threshold_sq = options.inlier_threshold_px * options.inlier_threshold_px;
  std::mt19937 rng(options.seed);
  double best_cost = std::numeric_limits<double>::infinity();
  std::vector<bool> best_inliers(n, true);
  int needed = options.max_ransac_iterations;
  Points s1(7), s2(7);
  std::vector<int> sample;
  *iterations = 0;
  for (int it = 0; it < std::min(needed, options.max_ransac_iterations); ++it) {
    ++*iterations;
    sample.clear();
    while (static_cast<int>(sample.size()) < 7) {
      const int k = static_cast<int>(rng() % static_cast<unsigned>(n));
      if (std::find(sample.begin(), sample.end(), k) == sample.end()) sample.push_back(k);
    }
    for (int k = 0; k < 7; ++k) {
      s1[k] = uv1[sample[k]];
      s2[k] = uv2[sample[k]];
    }
    for (const auto& F : FundamentalSevenPoint(s1, s2)) {
      double cost = 0.0;
      int count = 0;
      for (int i = 0; i < n; ++i) {
        const double e = MatchSquaredError(F, uv1[i], uv2[i]);
        cost += std::min(e, threshold_sq);
        count += e < threshold_sq;
      }
      if (cost < best_cost) {
        best_cost = cost;
        best_inliers = Classify(F, uv1, uv2, options.inlier_threshold_px);
        const double w = static_cast<double>(count) / n;
        const double p_good = std::pow(w, 7);
        if (p_good >= 1.0 - 1e-12) {
          needed = kMinRansacIterations;
        } else if (p_good > 0) {
          // A tiny p_good asks for more iterations than an int holds: capped before the
          // conversion (converting an out-of-range double is undefined behaviour).
          const double wanted = std::ceil(std::log(1 - options.ransac_confidence) / std::log(1 - p_good));
          needed = std::max(kMinRansacIterations,
                            static_cast<int>(std::min(wanted, static_cast<double>(options.max_ransac_iterations))));
        }
      }
    }
  }
  return best_inliers;
}

}  // namespace

bool FundamentalOptions::Check(std::string* error) const {
  if (!(inlier_threshold_px > 0) || !std::isfinite(inlier_threshold_px)) {
    *error = "inlier_threshold_px must be positive";
    return false;
  }
  if (max_ransac_iterations < 1 || !(ransac_confidence > 0 && ransac_confidence < 1)) {
    *error = "max_ransac_iterations must be positive and ransac_confidence in (0, 1)";
    return false;
  }
  if (max_refine_iterations < 0) {
    *error = "max_refine_iterations must not be negative";
    return false;
  }
  if (warm_start && (!warm_start_F.allFinite() || !(warm_start_F.norm() > 0.0))) {
    *error = "the warm start needs a finite non-zero F";
    return false;
  }
  return true;
}

bool RelativePoseOptions::Check(std::string* error) const {
  if (max_refine_iterations < 0) {
    *error = "max_refine_iterations must not be negative";
    return false;
  }
  return true;
}

Eigen::Matrix3d NormalizeFundamental(const Eigen::Matrix3d& F) {
  const double norm = F.norm();
  if (!(norm > 0)) return F;
  Eigen::Matrix3d out = F / norm;
  Eigen::Index r = 0, c = 0;
  out.cwiseAbs().maxCoeff(&r, &c);
  if (out(r, c) < 0) out = -out;
  return out;
}

Eigen::Vector2d SymmetricEpipolarDistances(const Eigen::Matrix3d& F, const Eigen::Vector2d& uv1,
                                           const Eigen::Vector2d& uv2) {
  const Eigen::Vector3d x1 = uv1.homogeneous(), x2 = uv2.homogeneous();
  const Eigen::Vector3d l2 = F * x1, l1 = F.transpose() * x2;
  const double e = x2.dot(l2);
  // sqrt, not hypot: line coefficients of pixel data cannot overflow, and hypot was a tenth
  // of the fundamental matrix's time.
  const double n2 = std::sqrt(l2.x() * l2.x() + l2.y() * l2.y()), n1 = std::sqrt(l1.x() * l1.x() + l1.y() * l1.y());
  return {n2 > 0 ? e / n2 : 0.0, n1 > 0 ? e / n1 : 0.0};
}

double SymmetricEpipolarRms(const Eigen::Matrix3d& F, const Points& uv1, const Points& uv2,
                            const std::vector<bool>& inliers) {
  double sum = 0.0;
  int count = 0;
  for (size_t i = 0; i < uv1.size(); ++i) {
    if (!inliers.empty() && !inliers[i]) continue;
    sum += SymmetricEpipolarDistances(F, uv1[i], uv2[i]).squaredNorm();
    ++count;
  }
  return count > 0 ? std::sqrt(sum / (2.0 * count)) : 0.0;
}

bool FundamentalEightPoint(const Points& uv1, const Points& uv2, Eigen::Matrix3d* F) {
  if (uv1.size() < 8 || uv1.size() != uv2.size()) return false;
  const Eigen::Matrix3d t1 = internal::HartleyNormalization(uv1), t2 = internal::HartleyNormalization(uv2);
  const Eigen::MatrixXd a = DesignMatrix(uv1, uv2, t1, t2);
  const auto svd = DesignMatrixSvd(a);
  const Eigen::Matrix<double, 9, 1>& sv = svd.singularValues();
  if (!(sv(0) > 0) || sv(7) < kNullSpaceRatio * sv(0)) return false;
  const Eigen::Matrix3d fn = FromVecRowMajor(svd.matrixV().col(8));
  Eigen::JacobiSVD<Eigen::Matrix3d> svd_f(fn, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Vector3d s = svd_f.singularValues();
  s(2) = 0.0;
  const Eigen::Matrix3d fn2 = svd_f.matrixU() * s.asDiagonal() * svd_f.matrixV().transpose();
  *F = NormalizeFundamental(t2.transpose() * fn2 * t1);
  return F->allFinite();
}

std::vector<Eigen::Matrix3d> FundamentalSevenPoint(const Points& uv1, const Points& uv2) {
  std::vector<Eigen::Matrix3d> out;
  if (uv1.size() != 7 || uv2.size() != 7) return out;
  const Eigen::Matrix3d t1 = internal::HartleyNormalization(uv1), t2 = internal::HartleyNormalization(uv2);
  const Eigen::MatrixXd a = DesignMatrix(uv1, uv2, t1, t2);
  const auto svd = DesignMatrixSvd(a);
  const Eigen::Matrix<double, 9, 1>& sv = svd.singularValues();
  if (!(sv(0) > 0) || sv(6) < kNullSpaceRatio * sv(0)) return out;
  const Eigen::Matrix3d f1 = FromVecRowMajor(svd.matrixV().col(7));
  const Eigen::Matrix3d f2 = FromVecRowMajor(svd.matrixV().col(8));
  // det(x f1 + (1 - x) f2) = c3 x^3 + c2 x^2 + c1 x + c0, from its values at 0, +-1, 2.
  auto det_at = [&](double x) { return (x * f1 + (1 - x) * f2).determinant(); };
  const double p0 = det_at(0), p1 = det_at(1), pm1 = det_at(-1), p2 = det_at(2);
  const double c0 = p0;
  const double c2 = 0.5 * (p1 + pm1) - c0;
  const double odd = 0.5 * (p1 - pm1);  // c3 + c1
  const double c3 = (p2 - 4 * c2 - c0 - 2 * odd) / 6.0;
  const double c1 = odd - c3;
  std::vector<Eigen::Matrix3d> roots_f;
  const double scale = std::max({std::abs(c0), std::abs(c1), std::abs(c2), std::abs(c3)});
  if (!(scale > 0)) return out;
  std::vector<double> roots;
  if (std::abs(c3) > 1e-12 * scale) {
    Eigen::Matrix3d companion = Eigen::Matrix3d::Zero();
    companion(0, 0) = -c2 / c3;
    companion(0, 1) = -c1 / c3;
    companion(0, 2) = -c0 / c3;
    companion(1, 0) = companion(2, 1) = 1.0;
    const Eigen::Vector3cd ev = Eigen::EigenSolver<Eigen::Matrix3d>(companion, false).eigenvalues();
    for (int k = 0; k < 3; ++k)
      if (std::abs(ev(k).imag()) <= 1e-8 * (1 + std::abs(ev(k).real()))) roots.push_back(ev(k).real());
  } else {
    // A root at infinity: f1 - f2 itself is singular.
    roots_f.push_back(f1 - f2);
    if (std::abs(c2) > 1e-12 * scale) {
      const double disc = c1 * c1 - 4 * c2 * c0;
      if (disc >= 0) {
        roots.push_back((-c1 + std::sqrt(disc)) / (2 * c2));
        roots.push_back((-c1 - std::sqrt(disc)) / (2 * c2));
      }
    } else if (std::abs(c1) > 0) {
      roots.push_back(-c0 / c1);
    }
  }
  for (double x : roots) roots_f.push_back(x * f1 + (1 - x) * f2);
  for (const auto& fn : roots_f) {
    const Eigen::Matrix3d F = NormalizeFundamental(t2.transpose() * fn * t1);
    if (F.allFinite() && F.norm() > 0) out.push_back(F);
  }
  return out;
}

std::array<std::pair<Eigen::Matrix3d, Eigen::Vector3d>, 4> DecomposeEssential(const Eigen::Matrix3d& E) {
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(E, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d u = svd.matrixU(), v = svd.matrixV();
  // E is defined up to sign, so flipping all of U or V keeps it and makes both rotations.
  if (u.determinant() < 0) u = -u;
  if (v.determinant() < 0) v = -v;
  Eigen::Matrix3d w;
  w << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  const Eigen::Matrix3d ra = u * w * v.transpose(), rb = u * w.transpose() * v.transpose();
  const Eigen::Vector3d t = u.col(2).normalized();
  return {{{ra, t}, {ra, -t}, {rb, t}, {rb, -t}}};
}

namespace internal {

void SymmetricEpipolarResiduals(const Eigen::Matrix3d& F, const Points& uv1, const Points& uv2,
                                Eigen::VectorXd* residuals, Eigen::Matrix<double, Eigen::Dynamic, 9>* jacobian) {
  const Eigen::Index n = static_cast<Eigen::Index>(uv1.size());
  residuals->resize(2 * n);
  jacobian->setZero(2 * n, 9);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector3d x1 = uv1[i].homogeneous(), x2 = uv2[i].homogeneous();
    const Eigen::Vector3d l2 = F * x1, l1 = F.transpose() * x2;
    const double e = x2.dot(l2);
    const double n2 = std::hypot(l2.x(), l2.y()), n1 = std::hypot(l1.x(), l1.y());
    if (!(n2 > 0) || !(n1 > 0)) {
      (*residuals)(2 * i) = (*residuals)(2 * i + 1) = 0.0;
      continue;
    }
    (*residuals)(2 * i) = e / n2;
    (*residuals)(2 * i + 1) = e / n1;
    // d e / d F_rc = x2_r x1_c; d l2_r / d F_rc = x1_c; d l1_c / d F_rc = x2_r.
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) {
        const double de = x2(r) * x1(c);
        const double dn2 = r < 2 ? l2(r) * x1(c) / n2 : 0.0;
        const double dn1 = c < 2 ? l1(c) * x2(r) / n1 : 0.0;
        (*jacobian)(2 * i, 3 * r + c) = de / n2 - e * dn2 / (n2 * n2);
        (*jacobian)(2 * i + 1, 3 * r + c) = de / n1 - e * dn1 / (n1 * n1);
      }
    }
  }
}

OrthonormalFundamental OrthonormalFundamental::FromF(const Eigen::Matrix3d& F, const Eigen::Matrix3d& T1,
                                                     const Eigen::Matrix3d& T2) {
  OrthonormalFundamental o;
  o.T1 = T1;
  o.T2 = T2;
  const Eigen::Matrix3d fn = T2.transpose().inverse() * F * T1.inverse();
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(fn, Eigen::ComputeFullU | Eigen::ComputeFullV);
  o.U = svd.matrixU();
  o.V = svd.matrixV();
  // The third singular vectors multiply a zero singular value: their sign is free.
  if (o.U.determinant() < 0) o.U.col(2) *= -1;
  if (o.V.determinant() < 0) o.V.col(2) *= -1;
  const Eigen::Vector3d s = svd.singularValues();
  o.s = s(0) > 0 ? s(1) / s(0) : 0.0;
  return o;
}

Eigen::Matrix3d OrthonormalFundamental::F() const {
  const Eigen::Vector3d d(1.0, s, 0.0);
  return T2.transpose() * (U * d.asDiagonal() * V.transpose()) * T1;
}

OrthonormalFundamental OrthonormalFundamental::Plus(const Eigen::Matrix<double, 7, 1>& delta) const {
  OrthonormalFundamental o = *this;
  o.U = U * RotationFromAngleAxis(delta.segment<3>(0));
  o.V = V * RotationFromAngleAxis(delta.segment<3>(3));
  o.s = s + delta(6);
  return o;
}

Eigen::Matrix<double, 9, 7> OrthonormalFundamental::Tangent() const {
  Eigen::Matrix<double, 9, 7> t;
  const Eigen::Matrix3d d = Eigen::Vector3d(1.0, s, 0.0).asDiagonal();
  for (int k = 0; k < 3; ++k) {
    const Eigen::Matrix3d g = Skew(Eigen::Vector3d::Unit(k));
    t.col(k) = VecRowMajor(T2.transpose() * (U * g * d * V.transpose()) * T1);
    t.col(3 + k) = VecRowMajor(T2.transpose() * (U * d * g.transpose() * V.transpose()) * T1);
  }
  t.col(6) = VecRowMajor(T2.transpose() * (U.col(1) * V.col(1).transpose()) * T1);
  return t;
}

namespace {
void TangentBasis(const Eigen::Vector3d& t, Eigen::Vector3d* b1, Eigen::Vector3d* b2) {
  Eigen::Index k = 0;
  t.cwiseAbs().minCoeff(&k);
  *b1 = t.cross(Eigen::Vector3d::Unit(k)).normalized();
  *b2 = t.normalized().cross(*b1);
}
}  // namespace

Eigen::Matrix3d PoseFundamental::F() const { return K2_inv.transpose() * Skew(t) * R * K1_inv; }

PoseFundamental PoseFundamental::Plus(const Eigen::Matrix<double, 5, 1>& delta) const {
  PoseFundamental p = *this;
  Eigen::Vector3d b1, b2;
  TangentBasis(t, &b1, &b2);
  p.R = R * RotationFromAngleAxis(delta.segment<3>(0));
  p.t = (t + delta(3) * b1 + delta(4) * b2).normalized();
  return p;
}

Eigen::Matrix<double, 9, 5> PoseFundamental::Tangent() const {
  Eigen::Matrix<double, 9, 5> out;
  Eigen::Vector3d b1, b2;
  TangentBasis(t, &b1, &b2);
  for (int k = 0; k < 3; ++k)
    out.col(k) = VecRowMajor(K2_inv.transpose() * Skew(t) * R * Skew(Eigen::Vector3d::Unit(k)) * K1_inv);
  out.col(3) = VecRowMajor(K2_inv.transpose() * Skew(b1) * R * K1_inv);
  out.col(4) = VecRowMajor(K2_inv.transpose() * Skew(b2) * R * K1_inv);
  return out;
}

}  // namespace internal

FundamentalSummary EstimateFundamentalMatrix(const Points& uv1, const Points& uv2, const FundamentalOptions& options) {
  const auto start = Clock::now();
  FundamentalSummary summary;
  auto fail = [&](std::string message) { return FailedSummary(summary, std::move(message), start); };
  std::string error;
  if (!options.Check(&error))
    return FailedSummary(summary, "bad options: " + error, start, SolverTermination::kInvalidInput);
  if (uv1.size() != uv2.size())
    return fail("the two images have different numbers of points (" + std::to_string(uv1.size()) + " and " +
                std::to_string(uv2.size()) + ")");
  const int n = static_cast<int>(uv1.size());
  if (n < 7) return fail("the fundamental matrix needs at least 7 matches, got " + std::to_string(n));
  for (int i = 0; i < n; ++i)
    if (!uv1[i].allFinite() || !uv2[i].allFinite())
      return fail("match " + std::to_string(i) + " has a non-finite coordinate");
  const int distinct = CountDistinctMatches(uv1, uv2);
  if (distinct < 7)
    return fail("only " + std::to_string(distinct) + " of the " + std::to_string(n) +
                " matches are distinct; the fundamental matrix needs at least 7");
  for (const std::string& problem : {SpreadProblem(uv1, "image 1"), SpreadProblem(uv2, "image 2")})
    if (!problem.empty()) return fail(problem);

  std::vector<bool> inliers(n, true);
  if (options.use_ransac && n > 8) inliers = Ransac(uv1, uv2, options, &summary.ransac_iterations);
  if (Count(inliers) < 7)
    return fail("fewer than 7 matches agree on one fundamental matrix (" + std::to_string(Count(inliers)) + " within " +
                internal::FormatNumber(options.inlier_threshold_px) + " px)");

  // Linear estimate and refinement on the inliers. The RANSAC flags come from one sample's
  // F, which noise in its 7 matches tilts; the refined F decides the final set, and a
  // changed set is fitted again.
  Eigen::Matrix3d f_linear, f_final;
  LmResult refine_result;
  std::vector<LmIteration> refine_trace;
  auto fit = [&](const std::vector<bool>& flags, Eigen::Matrix3d* linear, Eigen::Matrix3d* refined, LmResult* result,
                 std::vector<LmIteration>* trace) {
    const Points in1 = Select(uv1, flags), in2 = Select(uv2, flags);
    if (!LinearFundamental(in1, in2, linear, &error)) return false;
    if (options.warm_start) *linear = options.warm_start_F;
    *refined = *linear;
    *result = LmResult();
    result->termination = LmTermination::kConverged;
    trace->clear();
    if (options.refine) {
      const internal::OrthonormalFundamental start_state = internal::OrthonormalFundamental::FromF(
          *linear, internal::HartleyNormalization(in1), internal::HartleyNormalization(in2));
      *refined = MinimizeSymmetricEpipolar<7>(start_state, in1, in2, options.max_refine_iterations, result,
                                              options.record_refine_trace ? trace : nullptr)
                     .F();
    }
    return true;
  };
  const bool robust = options.use_ransac && n > 8;
  for (int round = 0; round < kMaxInlierRounds; ++round) {
    if (!fit(inliers, &f_linear, &f_final, &refine_result, &refine_trace)) return fail(error);
    if (!robust) break;
    const std::vector<bool> updated = Classify(f_final, uv1, uv2, options.inlier_threshold_px);
    if (updated == inliers || Count(updated) < 7 || round + 1 == kMaxInlierRounds) break;
    inliers = updated;
  }
  // A true match far from the others has leverage: F fitted without it may extrapolate past
  // the threshold there. A flagged match within kReadmitFactor thresholds is fitted back in,
  // and kept when the refit F holds it and every inlier within the threshold.
  if (robust) {
    // Adds the flagged matches `added` and keeps them when the refit classifies exactly the
    // enlarged set as inliers.
    auto try_readmit = [&](std::initializer_list<int> added) {
      std::vector<bool> trial = inliers;
      for (int i : added) trial[i] = true;
      ++summary.readmission_refits;
      Eigen::Matrix3d trial_linear, trial_final;
      LmResult trial_result;
      std::vector<LmIteration> trial_trace;
      if (!fit(trial, &trial_linear, &trial_final, &trial_result, &trial_trace)) return;
      if (Classify(trial_final, uv1, uv2, options.inlier_threshold_px) != trial) return;
      inliers = trial;
      f_linear = trial_linear;
      f_final = trial_final;
      refine_result = trial_result;
      refine_trace = std::move(trial_trace);
    };
    // Nearest first, and at most kMaxSingleReadmitCandidates of them: each try is a refit.
    std::vector<std::pair<double, int>> near;
    for (int i = 0; i < n; ++i) {
      const double error_sq = MatchSquaredError(f_final, uv1[i], uv2[i]);
      if (!inliers[i] && error_sq < std::pow(kReadmitFactor * options.inlier_threshold_px, 2))
        near.emplace_back(error_sq, i);
    }
    if (near.size() > kMaxSingleReadmitCandidates) {
      std::partial_sort(near.begin(), near.begin() + kMaxSingleReadmitCandidates, near.end());
      near.resize(kMaxSingleReadmitCandidates);
    }
    std::sort(near.begin(), near.end(), [](const auto& a, const auto& b) { return a.second < b.second; });
    for (const auto& candidate : near) {
      const int i = candidate.second;  // tested again: an earlier readmission moved F
      if (!inliers[i] &&
          MatchSquaredError(f_final, uv1[i], uv2[i]) < std::pow(kReadmitFactor * options.inlier_threshold_px, 2))
        try_readmit({i});
    }
    // Two true matches in the same far region can each hold the other's fit: fitted without
    // both, F misses both, and neither comes back alone. Pairs of the flagged matches within
    // kReadmitFactor thresholds are tried the same way (the refit must hold both and change
    // nothing else), which is as strict per match as the single test; a joint fixed point
    // over all of them was tried and let wrong matches in on real tracks.
    std::vector<int> candidates;
    for (int i = 0; i < n; ++i) {
      if (!inliers[i] &&
          MatchSquaredError(f_final, uv1[i], uv2[i]) < std::pow(kReadmitFactor * options.inlier_threshold_px, 2))
        candidates.push_back(i);
    }
    if (candidates.size() <= kMaxPairReadmitCandidates) {
      for (size_t a = 0; a < candidates.size(); ++a) {
        for (size_t b = a + 1; b < candidates.size(); ++b) {
          if (inliers[candidates[a]] || inliers[candidates[b]]) continue;
          try_readmit({candidates[a], candidates[b]});
        }
      }
    }
  }
  summary.iterations = refine_result.iterations;
  summary.refine_trace = std::move(refine_trace);

  summary.F = NormalizeFundamental(f_final);
  summary.inliers = inliers;
  summary.num_inliers = Count(inliers);
  summary.initial_symmetric_epipolar_rms_px = SymmetricEpipolarRms(f_linear, uv1, uv2, inliers);
  summary.symmetric_epipolar_rms_px = SymmetricEpipolarRms(summary.F, uv1, uv2, inliers);
  summary.initial_cost = SquaredRmsToSum(summary.initial_symmetric_epipolar_rms_px, summary.num_inliers);
  summary.final_cost = SquaredRmsToSum(summary.symmetric_epipolar_rms_px, summary.num_inliers);

  if (n == 7)
    summary.warnings.push_back(
        "only 7 matches: up to three fundamental matrices fit them exactly; the one with the smallest residual was "
        "chosen and no wrong click can be detected");
  else if (n == 8 || !options.use_ransac)
    summary.warnings.push_back("no redundancy check for wrong clicks (RANSAC needs more than 8 matches)");
  if (summary.num_inliers < n)
    summary.warnings.push_back(std::to_string(n - summary.num_inliers) + " of " + std::to_string(n) +
                               " matches disagree with the others by more than " +
                               internal::FormatNumber(options.inlier_threshold_px) + " px (flagged as outliers)");
  if (summary.num_inliers >= 4) {
    Eigen::Matrix3d h;
    const Points in1 = Select(uv1, inliers), in2 = Select(uv2, inliers);
    if (HomographyDlt(in1, in2, &h)) {
      summary.homography_rms_px = HomographyTransferRms(h, in1, in2);
      if (summary.homography_rms_px <=
          options.homography_warning_ratio * summary.symmetric_epipolar_rms_px + options.homography_warning_slack_px)
        summary.warnings.push_back("a homography explains the matches about as well (transfer RMS " +
                                   internal::FormatNumber(summary.homography_rms_px) +
                                   " px): a planar scene or a camera that only rotated; F is poorly determined");
    }
  }
  summary.termination = RefineTermination(refine_result);
  summary.message = "F from " + std::to_string(summary.num_inliers) + " of " + std::to_string(n) +
                    " matches, symmetric epipolar RMS " + internal::FormatNumber(summary.symmetric_epipolar_rms_px) +
                    " px";
  summary.time_ms = MsSince(start);
  return summary;
}

namespace {

// Depths of a match along both rays for cam2_from_cam1 (r, t), normalised coordinates x1, x2
// (third coordinate 1), by least squares on z2 x2 = z1 R x1 + t.
Eigen::Vector2d TriangulateDepths(const Eigen::Matrix3d& r, const Eigen::Vector3d& t, const Eigen::Vector3d& x1,
                                  const Eigen::Vector3d& x2) {
  Eigen::Matrix<double, 3, 2> a;
  a.col(0) = r * x1;
  a.col(1) = -x2;
  return a.colPivHouseholderQr().solve(-t);
}

int CountInFront(const Eigen::Matrix3d& r, const Eigen::Vector3d& t, const Points& x1, const Points& x2,
                 const Eigen::Matrix3d& k1_inv, const Eigen::Matrix3d& k2_inv) {
  int count = 0;
  for (size_t i = 0; i < x1.size(); ++i) {
    const Eigen::Vector3d a = k1_inv * x1[i].homogeneous(), b = k2_inv * x2[i].homogeneous();
    const Eigen::Vector2d z = TriangulateDepths(r, t, a / a.z(), b / b.z());
    count += z(0) > 0 && z(1) > 0;
  }
  return count;
}

}  // namespace

RelativePoseSummary EstimateRelativePose(const Eigen::Matrix3d& F, const Eigen::Matrix3d& K1, const Eigen::Matrix3d& K2,
                                         const Points& uv1, const Points& uv2, const std::vector<bool>& inliers,
                                         const RelativePoseOptions& options) {
  const auto start = Clock::now();
  RelativePoseSummary summary;
  auto fail = [&](std::string message) { return FailedSummary(summary, std::move(message), start); };
  std::string error;
  if (!options.Check(&error))
    return FailedSummary(summary, "bad options: " + error, start, SolverTermination::kInvalidInput);
  if (uv1.size() != uv2.size()) return fail("the two images have different numbers of points");
  if (!inliers.empty() && inliers.size() != uv1.size()) return fail("inliers must have one flag per match");
  if (!F.allFinite() || !(F.norm() > 0)) return fail("F is zero or not finite");
  for (const Eigen::Matrix3d* k : {&K1, &K2}) {
    if (!k->allFinite() || !(std::abs(k->determinant()) > 1e-12 * std::pow(k->norm(), 3)))
      return fail("an intrinsic matrix K is singular or not finite");
  }
  const Points in1 = inliers.empty() ? uv1 : Select(uv1, inliers);
  const Points in2 = inliers.empty() ? uv2 : Select(uv2, inliers);
  for (size_t i = 0; i < in1.size(); ++i)
    if (!in1[i].allFinite() || !in2[i].allFinite()) return fail("a match has a non-finite coordinate");
  summary.num_points = static_cast<int>(in1.size());
  if (summary.num_points < 5)
    return fail("the relative pose needs at least 5 matches, got " + std::to_string(summary.num_points));

  const Eigen::Matrix3d k1_inv = K1.inverse(), k2_inv = K2.inverse();
  const auto poses = DecomposeEssential(K2.transpose() * F * K1);
  int best = -1, best_count = -1, second_count = -1;
  for (int k = 0; k < 4; ++k) {
    const int count = CountInFront(poses[k].first, poses[k].second, in1, in2, k1_inv, k2_inv);
    if (count > best_count) {
      second_count = best_count;
      best_count = count;
      best = k;
    } else if (count > second_count) {
      second_count = count;
    }
  }
  if (2 * best_count <= summary.num_points)
    return fail("no decomposition of E puts most points in front of both cameras (best: " + std::to_string(best_count) +
                " of " + std::to_string(summary.num_points) + "): wrong intrinsics or matches");

  internal::PoseFundamental state;
  state.K1_inv = k1_inv;
  state.K2_inv = k2_inv;
  state.R = poses[best].first;
  state.t = poses[best].second;
  summary.initial_symmetric_epipolar_rms_px = SymmetricEpipolarRms(state.F(), in1, in2);
  LmResult refine_result;
  refine_result.termination = LmTermination::kConverged;
  if (options.refine)
    state = MinimizeSymmetricEpipolar<5>(state, in1, in2, options.max_refine_iterations, &refine_result);
  summary.iterations = refine_result.iterations;
  summary.symmetric_epipolar_rms_px = SymmetricEpipolarRms(state.F(), in1, in2);
  summary.initial_cost = SquaredRmsToSum(summary.initial_symmetric_epipolar_rms_px, summary.num_points);
  summary.final_cost = SquaredRmsToSum(summary.symmetric_epipolar_rms_px, summary.num_points);
  summary.cam2_from_cam1_rotation = state.R;
  summary.cam2_from_cam1_translation = state.t.normalized();
  summary.E = Skew(summary.cam2_from_cam1_translation) * state.R;
  summary.points_in_front = CountInFront(state.R, state.t, in1, in2, k1_inv, k2_inv);
  if (summary.points_in_front < summary.num_points)
    summary.warnings.push_back(std::to_string(summary.num_points - summary.points_in_front) + " of " +
                               std::to_string(summary.num_points) +
                               " points triangulate behind a camera (wrong clicks or points near the baseline)");
  if (second_count >= best_count - 1 && summary.num_points > 2)
    summary.warnings.push_back("two decompositions of E put nearly as many points in front: the pose is ambiguous");
  summary.termination = RefineTermination(refine_result);
  summary.message = "relative pose with " + std::to_string(summary.points_in_front) + " of " +
                    std::to_string(summary.num_points) + " points in front, symmetric epipolar RMS " +
                    internal::FormatNumber(summary.symmetric_epipolar_rms_px) + " px";
  summary.time_ms = MsSince(start);
  return summary;
}

}  // namespace facet
