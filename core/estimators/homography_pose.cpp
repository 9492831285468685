#include "core/estimators/homography_pose.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>

#include <Eigen/Dense>

#include "core/geometry/cross_product_matrix.h"
#include "core/geometry/hartley_normalization.h"
#include "core/optim/damped_normal_step.h"
#include "core/optim/levenberg_marquardt.h"
#include "core/optim/solver_summary.h"
#include "core/util/eigen_decompositions.h"
#include "core/util/format.h"
#include "core/util/timer.h"

namespace facet {
namespace {

using internal::FailedSummary;
using internal::FormatNumber;
using internal::MsSince;
using internal::Skew;

// Relative size of the second singular value of centred pixels below which they are one line.
constexpr double kCollinearRatio = 1e-6;
// Second-smallest over largest singular value of the DLT system below which H is not unique.
constexpr double kNullSpaceRatio = 1e-10;
// Twice the area of a triangle of normalised points (mean distance sqrt 2) below which a
// minimal sample has three points on a line.
constexpr double kSampleCollinearArea = 1e-6;
// sigma1 - sigma3 of the scaled calibrated homography below which it is a rotation.
constexpr double kPureRotationGap = 1e-9;
// |t / d| below which the baseline is too short for a useful pose (a warning).
constexpr double kShortBaseline = 1e-2;

bool Collinear(const std::vector<Eigen::Vector2d>& x) {
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  for (const auto& p : x) centroid += p;
  centroid /= static_cast<double>(x.size());
  Eigen::MatrixXd centred(x.size(), 2);
  for (size_t i = 0; i < x.size(); ++i) centred.row(i) = (x[i] - centroid).transpose();
  const Eigen::Vector2d s = Eigen::JacobiSVD<Eigen::MatrixXd>(centred).singularValues();
  return !(s(0) > 0.0) || s(1) < kCollinearRatio * s(0);
}

std::vector<Eigen::Vector2d> Select(const std::vector<Eigen::Vector2d>& x, const std::vector<int>& index) {
  std::vector<Eigen::Vector2d> out;
  out.reserve(index.size());
  for (int i : index) out.push_back(x[i]);
  return out;
}

Eigen::Matrix3d NormalizeH(Eigen::Matrix3d h) {
  h /= h.norm();
  if (h(2, 2) < 0.0) h = -h;
  return h;
}

// Normalised DLT on all given matches; false when the null space is not one-dimensional.
bool HomographyDlt(const std::vector<Eigen::Vector2d>& uv1, const std::vector<Eigen::Vector2d>& uv2,
                   Eigen::Matrix3d* h) {
  const Eigen::Matrix3d t1 = internal::HartleyNormalization(uv1), t2 = internal::HartleyNormalization(uv2);
  const int n = static_cast<int>(uv1.size());
  // Nine columns even for four matches: pad with zero rows so the SVD has a full V.
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(std::max(2 * n, 9), 9);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d x = t1 * uv1[i].homogeneous();
    const Eigen::Vector3d u = t2 * uv2[i].homogeneous();
    a.block<1, 3>(2 * i, 0) = x.transpose();
    a.block<1, 3>(2 * i, 6) = -u.x() * x.transpose();
    a.block<1, 3>(2 * i + 1, 3) = x.transpose();
    a.block<1, 3>(2 * i + 1, 6) = -u.y() * x.transpose();
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeFullV);
  const Eigen::VectorXd& s = svd.singularValues();
  if (!(s(0) > 0.0) || s(7) < kNullSpaceRatio * s(0)) return false;
  const Eigen::VectorXd v = svd.matrixV().col(8);
  Eigen::Matrix3d hn;
  hn << v.segment<3>(0).transpose(), v.segment<3>(3).transpose(), v.segment<3>(6).transpose();
  const Eigen::Matrix3d out = t2.inverse() * hn * t1;
  if (!out.allFinite() || std::abs(out.determinant()) <= 1e-14 * std::pow(out.norm(), 3)) return false;
  *h = NormalizeH(out);
  return true;
}

// Three of four normalised points on a line, in either image.
bool DegenerateSample(const std::vector<Eigen::Vector2d>& uv1, const std::vector<Eigen::Vector2d>& uv2) {
  for (const auto* uv : {&uv1, &uv2}) {
    const Eigen::Matrix3d t = internal::HartleyNormalization(*uv);
    std::vector<Eigen::Vector2d> x;
    for (const auto& p : *uv) x.push_back((t * p.homogeneous()).head<2>());
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j)
        for (int k = j + 1; k < 4; ++k) {
          const Eigen::Vector2d a = x[j] - x[i], b = x[k] - x[i];
          if (std::abs(a.x() * b.y() - a.y() * b.x()) < kSampleCollinearArea) return true;
        }
  }
  return false;
}

// Four residuals per match: H uv1 - uv2 and H^-1 uv2 - uv1 (px).
Eigen::VectorXd TransferResiduals(const Eigen::Matrix3d& h, const std::vector<Eigen::Vector2d>& uv1,
                                  const std::vector<Eigen::Vector2d>& uv2) {
  const Eigen::Matrix3d h_inverse = h.inverse();
  Eigen::VectorXd r(4 * uv1.size());
  for (size_t i = 0; i < uv1.size(); ++i) {
    r.segment<2>(4 * i) = (h * uv1[i].homogeneous()).hnormalized() - uv2[i];
    r.segment<2>(4 * i + 2) = (h_inverse * uv2[i].homogeneous()).hnormalized() - uv1[i];
  }
  return r;
}

double TransferRms(const Eigen::Matrix3d& h, const std::vector<Eigen::Vector2d>& uv1,
                   const std::vector<Eigen::Vector2d>& uv2) {
  if (uv1.empty()) return 0.0;
  const Eigen::VectorXd r = TransferResiduals(h, uv1, uv2);
  return std::isfinite(r.squaredNorm()) ? std::sqrt(r.squaredNorm() / (2.0 * uv1.size()))
                                        : std::numeric_limits<double>::infinity();
}

// The refinement for the Levenberg-Marquardt driver: H in normalised coordinates
// (Hn = T2 H T1^-1, entries of order one), its largest entry held so the scale is fixed, the
// other eight moved additively; Jacobian by central differences.
class HomographyRefinement {
 public:
  HomographyRefinement(const std::vector<Eigen::Vector2d>& uv1, const std::vector<Eigen::Vector2d>& uv2,
                       const Eigen::Matrix3d& h_start)
      : uv1_(uv1), uv2_(uv2) {
    const Eigen::Matrix3d t1 = internal::HartleyNormalization(uv1), t2 = internal::HartleyNormalization(uv2);
    t1_ = t1;
    t2_inverse_ = t2.inverse();
    hn_ = t2 * h_start * t1.inverse();
    hn_ /= hn_.norm();
    Eigen::Index held = 0;
    hn_.cwiseAbs().reshaped().maxCoeff(&held);
    for (int k = 0; k < 9; ++k)
      if (k != held) free_.push_back(k);
    residuals_ = Residuals(hn_);
  }

  double Cost() const { return residuals_.squaredNorm(); }
  Eigen::Matrix3d HomographyInPixels() const { return NormalizeH(ToPixels(hn_)); }

  bool Linearize() {
    Eigen::MatrixXd j(residuals_.size(), 8);
    constexpr double kStep = 1e-7;
    for (int c = 0; c < 8; ++c) {
      Eigen::Matrix3d plus = hn_, minus = hn_;
      plus.reshaped()(free_[c]) += kStep;
      minus.reshaped()(free_[c]) -= kStep;
      j.col(c) = (Residuals(plus) - Residuals(minus)) / (2.0 * kStep);
    }
    normal_ = j.transpose() * j;
    gradient_ = j.transpose() * residuals_;
    damping_ = normal_.diagonal().cwiseMax(1e-300);  // a floor, only against a zero column
    return !gradient_.allFinite() || gradient_.lpNorm<Eigen::Infinity>() == 0.0;
  }

  // A step without a finite solution gives a non-finite candidate cost, which the driver
  // rejects like any other.
  LmStepStatus Step(double lambda, LmTrial* trial) {
    const Eigen::VectorXd step = DampedNormalStep(normal_, gradient_, lambda, damping_);
    candidate_ = hn_;
    for (int c = 0; c < 8; ++c) candidate_.reshaped()(free_[c]) += step(c);
    candidate_residuals_ = Residuals(candidate_);
    trial->cost = candidate_residuals_.squaredNorm();
    trial->step_squared_norm = step.squaredNorm();
    return LmStepStatus::kSolved;
  }

  void Accept() {
    hn_ = candidate_;
    residuals_ = candidate_residuals_;
  }

 private:
  Eigen::Matrix3d ToPixels(const Eigen::Matrix3d& hn) const { return t2_inverse_ * hn * t1_; }
  Eigen::VectorXd Residuals(const Eigen::Matrix3d& hn) const { return TransferResiduals(ToPixels(hn), uv1_, uv2_); }

  const std::vector<Eigen::Vector2d>& uv1_;
  const std::vector<Eigen::Vector2d>& uv2_;
  Eigen::Matrix3d t1_, t2_inverse_, hn_, candidate_;
  std::vector<int> free_;
  Eigen::VectorXd residuals_, candidate_residuals_, gradient_, damping_;
  Eigen::MatrixXd normal_;
};

// Levenberg-Marquardt on the transfer residuals (cost in px^2) from h_start; h_start itself
// when its cost is not finite.
Eigen::Matrix3d RefineHomography(const Eigen::Matrix3d& h_start, const std::vector<Eigen::Vector2d>& uv1,
                                 const std::vector<Eigen::Vector2d>& uv2, int max_iterations, LmResult* result) {
  HomographyRefinement refinement(uv1, uv2, h_start);
  LmOptions options = TenfoldLmOptions(max_iterations);
  // No cap on lambda: 12 trials at most per linearisation.
  options.max_lambda = std::numeric_limits<double>::infinity();
  options.max_trials_per_linearization = 12;
  options.relative_decrease_tolerance = 1e-14;
  options.min_step_squared_norm = 1e-28;  // |step| <= 1e-14 in normalised entries of H
  *result = MinimizeLevenbergMarquardt(refinement.Cost(), options, refinement);
  if (result->termination == LmTermination::kNonFiniteCost) return h_start;
  return refinement.HomographyInPixels();
}

}  // namespace

bool HomographyOptions::Check(std::string* error) const {
  auto fail = [&](const char* message) {
    if (error) *error = message;
    return false;
  };
  if (!(inlier_threshold_px > 0.0) || !std::isfinite(inlier_threshold_px))
    return fail("inlier_threshold_px must be positive");
  if (max_ransac_iterations < 1) return fail("max_ransac_iterations must be at least 1");
  if (!(ransac_confidence > 0.0 && ransac_confidence < 1.0)) return fail("ransac_confidence must be in (0, 1)");
  if (max_refine_iterations < 0) return fail("max_refine_iterations must not be negative");
  return true;
}

bool HomographyPoseOptions::Check(std::string* error) const { return homography.Check(error); }

std::vector<double> SymmetricTransferErrors(const Eigen::Matrix3d& H, const std::vector<Eigen::Vector2d>& uv1,
                                            const std::vector<Eigen::Vector2d>& uv2) {
  std::vector<double> errors(uv1.size(), std::numeric_limits<double>::infinity());
  if (!H.allFinite() || std::abs(H.determinant()) <= 0.0) return errors;
  const Eigen::VectorXd r = TransferResiduals(H, uv1, uv2);
  for (size_t i = 0; i < uv1.size(); ++i) {
    const double e = std::sqrt(r.segment<4>(4 * i).squaredNorm() / 2.0);
    if (std::isfinite(e)) errors[i] = e;
  }
  return errors;
}

// MSAC over 4-point samples: the inliers of the sample with the most (the smaller score
// among equals), with the adaptive number of samples for options.ransac_confidence.
std::vector<int> RansacInliers(const std::vector<Eigen::Vector2d>& uv1, const std::vector<Eigen::Vector2d>& uv2,
                               const HomographyOptions& options, int* iterations) {
  const int n = static_cast<int>(uv1.size());
  std::mt19937 rng(options.seed);
  int best_count = 0;
  double best_score = std::numeric_limits<double>::infinity();
  std::vector<int> best;
  int needed = options.max_ransac_iterations;
  const double threshold = options.inlier_threshold_px;
  for (int iteration = 0; iteration < std::min(needed, options.max_ransac_iterations); ++iteration) {
    *iterations = iteration + 1;
    std::vector<int> sample;
    while (sample.size() < 4) {
      const int k = std::uniform_int_distribution<int>(0, n - 1)(rng);
      if (std::find(sample.begin(), sample.end(), k) == sample.end()) sample.push_back(k);
    }
    const auto s1 = Select(uv1, sample), s2 = Select(uv2, sample);
    Eigen::Matrix3d h;
    if (DegenerateSample(s1, s2) || !HomographyDlt(s1, s2, &h)) continue;
    const std::vector<double> errors = SymmetricTransferErrors(h, uv1, uv2);
    std::vector<int> in;
    double score = 0.0;  // MSAC: inliers' squared errors, outliers at the threshold
    for (int i = 0; i < n; ++i) {
      if (errors[i] < threshold) in.push_back(i);
      score += std::min(errors[i] * errors[i], threshold * threshold);
    }
    if (static_cast<int>(in.size()) > best_count || (static_cast<int>(in.size()) == best_count && score < best_score)) {
      best_count = static_cast<int>(in.size());
      best_score = score;
      best = in;
      const double ratio = static_cast<double>(best_count) / n;
      const double p_all = std::pow(ratio, 4);
      if (p_all >= 1.0) {
        needed = 0;
      } else if (p_all > 0.0) {
        needed = static_cast<int>(std::ceil(std::log(1.0 - options.ransac_confidence) / std::log(1.0 - p_all)));
      }
    }
  }
  return best;
}

HomographySummary EstimateHomography(const std::vector<Eigen::Vector2d>& uv1, const std::vector<Eigen::Vector2d>& uv2,
                                     const HomographyOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  HomographySummary summary;
  std::string error;
  constexpr SolverTermination kInvalidInput = SolverTermination::kInvalidInput;
  if (!options.Check(&error)) return FailedSummary(summary, "invalid options: " + error, start, kInvalidInput);
  if (uv1.size() != uv2.size())
    return FailedSummary(summary, "the two images have different numbers of points", start, kInvalidInput);
  const int n = static_cast<int>(uv1.size());
  if (n < 4)
    return FailedSummary(summary, "a homography needs 4 or more matches on one plane, got " + std::to_string(n), start,
                         kInvalidInput);
  for (int i = 0; i < n; ++i)
    if (!uv1[i].allFinite() || !uv2[i].allFinite())
      return FailedSummary(summary, "match " + std::to_string(i) + " has a non-finite coordinate", start,
                           kInvalidInput);
  for (int image = 0; image < 2; ++image)
    if (Collinear(image == 0 ? uv1 : uv2))
      return FailedSummary(summary,
                           "the points of image " + std::to_string(image + 1) +
                               " are all on one line: they do not determine a homography (4 points, no 3 on a line)",
                           start, kInvalidInput);

  std::vector<int> inlier_index(n);
  std::iota(inlier_index.begin(), inlier_index.end(), 0);
  const bool ransac = options.use_ransac && n >= 6;
  if (ransac) {
    inlier_index = RansacInliers(uv1, uv2, options, &summary.ransac_iterations);
    if (inlier_index.size() < 4)
      return FailedSummary(summary, "no 4 matches agree on a homography (no three of them on a line)", start);
  }

  Eigen::Matrix3d h;
  if (!HomographyDlt(Select(uv1, inlier_index), Select(uv2, inlier_index), &h))
    return FailedSummary(summary,
                         "the matches do not determine a homography (three of four on a line, or a plane seen "
                         "edge-on)",
                         start);
  if (ransac) {
    // The refit on all inliers may take in a match the sample's H just missed, once.
    const std::vector<double> errors = SymmetricTransferErrors(h, uv1, uv2);
    std::vector<int> in;
    for (int i = 0; i < n; ++i)
      if (errors[i] < options.inlier_threshold_px) in.push_back(i);
    Eigen::Matrix3d refit;
    if (in.size() >= inlier_index.size() && HomographyDlt(Select(uv1, in), Select(uv2, in), &refit)) {
      inlier_index = in;
      h = refit;
    }
  }
  const auto in1 = Select(uv1, inlier_index), in2 = Select(uv2, inlier_index);
  summary.initial_symmetric_transfer_rms_px = TransferRms(h, in1, in2);
  summary.initial_cost = TransferResiduals(h, in1, in2).squaredNorm();
  summary.termination = SolverTermination::kConverged;
  if (options.refine && inlier_index.size() > 4) {
    LmResult refinement;
    h = RefineHomography(h, in1, in2, options.max_refine_iterations, &refinement);
    summary.iterations = refinement.iterations;
    if (refinement.termination == LmTermination::kMaxIterations)
      summary.termination = SolverTermination::kMaxIterations;
  }
  summary.H = h;
  summary.symmetric_transfer_rms_px = TransferRms(h, in1, in2);
  summary.final_cost = TransferResiduals(h, in1, in2).squaredNorm();
  summary.inliers.assign(n, false);
  for (int i : inlier_index) summary.inliers[i] = true;
  summary.num_inliers = static_cast<int>(inlier_index.size());
  if (!ransac && n == 5) {
    const std::vector<double> errors = SymmetricTransferErrors(h, uv1, uv2);
    if (*std::max_element(errors.begin(), errors.end()) > options.inlier_threshold_px)
      summary.warnings.push_back(
          "a match is off the homography by more than the threshold, but 5 matches cannot "
          "tell which one (6 or more flag wrong clicks)");
  }
  summary.message = "homography from " + std::to_string(summary.num_inliers) + " of " + std::to_string(n) +
                    " matches, symmetric transfer RMS " + FormatNumber(summary.symmetric_transfer_rms_px) + " px";
  summary.time_ms = MsSince(start);
  return summary;
}

std::vector<PlanePose> DecomposeCalibratedHomography(const Eigen::Matrix3d& G, const std::vector<Eigen::Vector3d>& x1,
                                                     const std::vector<Eigen::Vector3d>& x2) {
  std::vector<PlanePose> out;
  if (!G.allFinite()) return out;
  const Eigen::JacobiSVD<Eigen::Matrix3d> g_svd(G);
  const Eigen::Vector3d g_s = g_svd.singularValues();
  if (!(g_s(2) > 1e-12 * g_s(0))) return out;
  Eigen::Matrix3d h = G / g_s(1);
  // The depth ratio of every matched ray is positive for the true sign: x2 ~ h x1 with x2^T h x1 > 0.
  int positive = 0;
  for (size_t i = 0; i < x1.size(); ++i) positive += x2[i].dot(h * x1[i]) > 0.0 ? 1 : -1;
  if (positive < 0) h = -h;

  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(h.transpose() * h, Eigen::ComputeFullV);
  Eigen::Matrix3d v = svd.matrixV();
  if (v.determinant() < 0.0) v = -v;
  const double s1 = svd.singularValues()(0), s3 = svd.singularValues()(2);  // squared singular values of h
  if (std::sqrt(s1) - std::sqrt(s3) < kPureRotationGap) {
    // A rotation (or no baseline): one solution, plane undefined.
    PlanePose pose;
    const Eigen::JacobiSVD<Eigen::Matrix3d> r_svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
    pose.cam2_from_cam1_rotation = r_svd.matrixU() * r_svd.matrixV().transpose();
    out.push_back(pose);
    return out;
  }
  const Eigen::Vector3d v1 = v.col(0), v2 = v.col(1), v3 = v.col(2);
  const double a = std::sqrt(std::max(1.0 - s3, 0.0)), b = std::sqrt(std::max(s1 - 1.0, 0.0));
  const double c = std::sqrt(s1 - s3);
  const Eigen::Vector3d u1 = (a * v1 + b * v3) / c, u2 = (a * v1 - b * v3) / c;
  for (const Eigen::Vector3d& u : {u1, u2}) {
    Eigen::Matrix3d uu, ww;
    uu << v2, u, v2.cross(u);
    ww << h * v2, h * u, (h * v2).cross(h * u);
    const Eigen::Matrix3d rotation = ww * uu.transpose();
    const Eigen::Vector3d normal = v2.cross(u);
    const Eigen::Vector3d t_over_d = (h - rotation) * normal;
    for (const double sign : {1.0, -1.0}) {
      PlanePose pose;
      pose.cam2_from_cam1_rotation = rotation;
      pose.plane_normal_in_cam1 = sign * normal;
      pose.translation_over_distance = sign * t_over_d;
      out.push_back(pose);
    }
  }
  for (PlanePose& pose : out) {
    const double t_norm = pose.translation_over_distance.norm();
    if (t_norm > 0.0) pose.cam2_from_cam1_translation = pose.translation_over_distance / t_norm;
    // d = 1: points on n^T X = 1 in camera 1.
    const Eigen::Vector3d& n = pose.plane_normal_in_cam1;
    for (size_t i = 0; i < x1.size(); ++i) {
      const double along = n.dot(x1[i]);
      if (!(along > 0.0)) continue;
      const Eigen::Vector3d p2 = pose.cam2_from_cam1_rotation * (x1[i] / along) + pose.translation_over_distance;
      if (p2.z() > 0.0) ++pose.points_in_front;
    }
    const Eigen::Vector3d centre2 = -pose.cam2_from_cam1_rotation.transpose() * pose.translation_over_distance;
    pose.centres_on_one_side = n.dot(centre2) < 1.0;
  }
  return out;
}

HomographyPoseSummary EstimatePlanePose(const std::vector<Eigen::Vector2d>& uv1,
                                        const std::vector<Eigen::Vector2d>& uv2, const Eigen::Matrix3d& K1,
                                        const Eigen::Matrix3d& K2, const HomographyPoseOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  HomographyPoseSummary summary;
  std::string error;
  if (!options.Check(&error))
    return FailedSummary(summary, "invalid options: " + error, start, SolverTermination::kInvalidInput);
  if (!K1.allFinite() || !K2.allFinite() || !(std::abs(K1.determinant()) > 0.0) || !(std::abs(K2.determinant()) > 0.0))
    return FailedSummary(summary, "the intrinsics must be finite and invertible", start,
                         SolverTermination::kInvalidInput);
  summary.homography = EstimateHomography(uv1, uv2, options.homography);
  if (!summary.homography.IsUsable())
    return FailedSummary(summary, summary.homography.message, start, summary.homography.termination);
  summary.iterations = summary.homography.iterations;
  summary.initial_cost = summary.homography.initial_cost;
  summary.final_cost = summary.homography.final_cost;
  for (const auto& w : summary.homography.warnings) summary.warnings.push_back(w);

  const Eigen::Matrix3d k1_inverse = K1.inverse(), k2_inverse = K2.inverse();
  std::vector<Eigen::Vector3d> x1, x2;
  std::vector<Eigen::Vector2d> in1, in2;
  for (size_t i = 0; i < uv1.size(); ++i) {
    if (!summary.homography.inliers[i]) continue;
    x1.push_back(k1_inverse * uv1[i].homogeneous());
    x2.push_back(k2_inverse * uv2[i].homogeneous());
    in1.push_back(uv1[i]);
    in2.push_back(uv2[i]);
  }
  summary.num_points = static_cast<int>(x1.size());
  const Eigen::Matrix3d G = k2_inverse * summary.homography.H * K1;
  std::vector<PlanePose> all = DecomposeCalibratedHomography(G, x1, x2);
  if (all.empty()) return FailedSummary(summary, "the homography is singular: no pose", start);
  if (all.size() == 1) {
    summary.pure_rotation = true;
    summary.candidates = all;
    summary.candidates[0].points_in_front = summary.num_points;
    summary.warnings.push_back(
        "the homography is a pure rotation: the cameras share their centre, so the baseline "
        "and the plane are undetermined");
  } else {
    for (PlanePose& pose : all) {
      if (pose.points_in_front < summary.num_points || !pose.centres_on_one_side) continue;
      const Eigen::Matrix3d h =
          K2 * (pose.cam2_from_cam1_rotation + pose.translation_over_distance * pose.plane_normal_in_cam1.transpose()) *
          k1_inverse;
      pose.reprojection_rms_px = TransferRms(h, in1, in2);
      summary.candidates.push_back(pose);
    }
    if (summary.candidates.empty()) {
      int best = 0;
      for (const PlanePose& pose : all) best = std::max(best, pose.points_in_front);
      return FailedSummary(summary,
                           "no decomposition of the homography puts the points in front of both cameras (at most " +
                               std::to_string(best) + " of " + std::to_string(summary.num_points) +
                               "): wrong clicks, or wrong intrinsics",
                           start);
    }
    std::stable_sort(summary.candidates.begin(), summary.candidates.end(), [](const PlanePose& a, const PlanePose& b) {
      return a.reprojection_rms_px < b.reprojection_rms_px;
    });
    summary.ambiguous = summary.candidates.size() > 1;
  }
  const PlanePose& best = summary.candidates[0];
  summary.cam2_from_cam1_rotation = best.cam2_from_cam1_rotation;
  summary.cam2_from_cam1_translation = best.cam2_from_cam1_translation;
  summary.translation_over_distance = best.translation_over_distance;
  summary.plane_normal_in_cam1 = best.plane_normal_in_cam1;
  if (!summary.pure_rotation && best.translation_over_distance.norm() < kShortBaseline)
    summary.warnings.push_back("the baseline is very short against the plane's distance (|t| / d = " +
                               FormatNumber(best.translation_over_distance.norm()) +
                               "): the pose is weakly determined");
  if (summary.ambiguous)
    summary.warnings.push_back(std::to_string(summary.candidates.size()) +
                               " plane poses explain the matches equally well (a view pair of one plane is "
                               "ambiguous); the first is given, the other is in the candidates");
  summary.termination = summary.homography.termination;
  summary.message = summary.homography.message + "; " +
                    (summary.pure_rotation ? std::string("pure rotation")
                                           : std::to_string(summary.candidates.size()) + " pose(s) pass cheirality");
  summary.time_ms = MsSince(start);
  return summary;
}

}  // namespace facet
