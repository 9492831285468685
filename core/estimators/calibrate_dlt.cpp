#include "core/estimators/calibrate_dlt.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

#include <Eigen/Dense>
#include <Eigen/SVD>

#include "core/geometry/camera_checks.h"
#include "core/optim/damped_normal_step.h"
#include "core/optim/levenberg_marquardt.h"
#include "core/util/eigen_decompositions.h"
#include "core/util/timer.h"

namespace facet {
namespace {

using internal::FailedSummary;

// Relative size of the smallest singular value of the centred 3D points below which they are
// one plane (the planar path then projects them onto it; the refinement still uses their
// true coordinates), and below which the non-planar DLT is poorly conditioned (a warning).
constexpr double kPlanarRatio = 1e-4;
constexpr double kNearlyPlanarRatio = 0.05;
// Relative size of the second singular value below which the points are one line.
constexpr double kCollinearRatio = 1e-6;
// A linear system whose second-smallest singular value is this small relative to the largest
// has more than one solution: the configuration does not determine the camera.
constexpr double kNullSpaceRatio = 1e-10;

using Matrix34d = Eigen::Matrix<double, 3, 4>;

std::string Format(const char* format, double a, double b = 0.0, double c = 0.0) {
  char buffer[256];
  std::snprintf(buffer, sizeof(buffer), format, a, b, c);
  return buffer;
}

// Hartley normalisation: the centroid to the origin and the mean distance to sqrt(dim).
template <int kDim>
Eigen::Matrix<double, kDim + 1, kDim + 1> Normalisation(const std::vector<Eigen::Matrix<double, kDim, 1>>& x) {
  Eigen::Matrix<double, kDim, 1> centroid = Eigen::Matrix<double, kDim, 1>::Zero();
  for (const auto& p : x) centroid += p;
  centroid /= static_cast<double>(x.size());
  double mean_distance = 0.0;
  for (const auto& p : x) mean_distance += (p - centroid).norm();
  mean_distance /= static_cast<double>(x.size());
  const double scale = mean_distance > 0.0 ? std::sqrt(static_cast<double>(kDim)) / mean_distance : 1.0;
  Eigen::Matrix<double, kDim + 1, kDim + 1> t = Eigen::Matrix<double, kDim + 1, kDim + 1>::Identity();
  t.template topLeftCorner<kDim, kDim>() *= scale;
  t.template topRightCorner<kDim, 1>() = -scale * centroid;
  return t;
}

// Null vector of a (rows x cols) system; false when the null space has more than one dimension.
bool NullVector(const Eigen::MatrixXd& a, Eigen::VectorXd* v) {
  if (!a.allFinite()) return false;  // Eigen's SVD does not converge on NaN or infinity
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeFullV);
  const Eigen::VectorXd& s = svd.singularValues();
  const int n = static_cast<int>(a.cols());
  // With fewer rows than columns the missing singular values are zero.
  const double second_smallest = (s.size() >= n - 1) ? s(n - 2) : 0.0;
  if (!(s(0) > 0.0) || second_smallest < kNullSpaceRatio * s(0)) return false;
  *v = svd.matrixV().col(n - 1);
  return true;
}

// M = K R with K upper triangular (positive diagonal) and R orthogonal.
void RqDecomposition(const Eigen::Matrix3d& m, Eigen::Matrix3d* k, Eigen::Matrix3d* r) {
  Eigen::Matrix3d flip;
  flip << 0, 0, 1, 0, 1, 0, 1, 0, 0;
  // QR of (flip M)^T = Q U gives M = (flip U^T flip)(flip Q^T): upper triangular times orthogonal.
  const Eigen::HouseholderQR<Eigen::Matrix3d> qr((flip * m).transpose());
  const Eigen::Matrix3d q = qr.householderQ();
  const Eigen::Matrix3d u = qr.matrixQR().triangularView<Eigen::Upper>();
  *k = flip * u.transpose() * flip;
  *r = flip * q.transpose();
  for (int i = 0; i < 3; ++i) {
    if ((*k)(i, i) < 0.0) {
      k->col(i) *= -1.0;
      r->row(i) *= -1.0;
    }
  }
}

Eigen::Matrix3d NearestRotation(const Eigen::Matrix3d& m) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
  return svd.matrixU() * d * svd.matrixV().transpose();
}

// The refined model: square pixels, zero skew, radial distortion (header).
struct Model {
  double focal_px = 0.0;
  Eigen::Vector2d principal_point_px = Eigen::Vector2d::Zero();
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  double k1 = 0.0;
  double k2 = 0.0;
};

// Parameter layout of a model update: f, cx, cy, rotation (angle-axis, applied on the left
// of the current rotation, so the update is local), t, k1, k2.
constexpr int kNumParams = 11;
enum Param { kFocal = 0, kCx = 1, kCy = 2, kRotation = 3, kTranslation = 6, kK1 = 9, kK2 = 10 };

Model Apply(const Model& model, const Eigen::Matrix<double, kNumParams, 1>& delta) {
  Model out = model;
  out.focal_px += delta(kFocal);
  out.principal_point_px += delta.segment<2>(kCx);
  out.rotation = RotationFromAngleAxis(delta.segment<3>(kRotation)) * model.rotation;
  out.translation += delta.segment<3>(kTranslation);
  out.k1 += delta(kK1);
  out.k2 += delta(kK2);
  return out;
}

Eigen::Vector2d ProjectModel(const Model& m, const Eigen::Vector3d& p_in_world) {
  const Eigen::Vector3d p = m.rotation * p_in_world + m.translation;
  const double x = p.x() / p.z(), y = p.y() / p.z();
  const double r2 = x * x + y * y;
  const double d = 1.0 + r2 * (m.k1 + m.k2 * r2);
  return {m.focal_px * x * d + m.principal_point_px.x(), m.focal_px * y * d + m.principal_point_px.y()};
}

// A Gaussian focal prior as one more residual, (f - focal_px) * weight, weight = pixel noise
// over the prior's standard deviation; weight 0: no prior.
struct FocalPrior {
  double focal_px = 0.0;
  double weight = 0.0;
};

Eigen::VectorXd Residuals(const Model& m, const std::vector<PointCorrespondence>& points,
                          const FocalPrior& prior = {}) {
  const bool with_prior = prior.weight > 0.0;
  Eigen::VectorXd r(2 * points.size() + (with_prior ? 1 : 0));
  for (size_t i = 0; i < points.size(); ++i) r.segment<2>(2 * i) = ProjectModel(m, points[i].xyz) - points[i].uv_px;
  if (with_prior) r(r.size() - 1) = (m.focal_px - prior.focal_px) * prior.weight;
  return r;
}

// Central differences; each step is scaled to its parameter, so the truncation error
// (~h^2) and the rounding error (~eps / h) are both near 1e-10 relative: far below any
// pixel noise, and the fixed point of Gauss-Newton does not depend on the Jacobian.
Eigen::MatrixXd Jacobian(const Model& m, const std::vector<PointCorrespondence>& points, const std::vector<int>& free,
                         double length_scale, const FocalPrior& prior) {
  Eigen::MatrixXd j(2 * points.size() + (prior.weight > 0.0 ? 1 : 0), free.size());
  for (size_t c = 0; c < free.size(); ++c) {
    const int p = free[c];
    double h = 1e-6;
    if (p == kFocal || p == kCx || p == kCy) h = 1e-6 * m.focal_px;
    if (p >= kTranslation && p < kTranslation + 3) h = 1e-6 * (m.translation.norm() + length_scale);
    Eigen::Matrix<double, kNumParams, 1> delta = Eigen::Matrix<double, kNumParams, 1>::Zero();
    delta(p) = h;
    const Eigen::VectorXd plus = Residuals(Apply(m, delta), points, prior);
    delta(p) = -h;
    const Eigen::VectorXd minus = Residuals(Apply(m, delta), points, prior);
    j.col(c) = (plus - minus) / (2.0 * h);
  }
  return j;
}

// The refinement for the Levenberg-Marquardt driver: the free parameters of the model move
// by Apply; Jacobian by central differences.
class Refinement {
 public:
  Refinement(const std::vector<PointCorrespondence>& points, const std::vector<int>& free, double length_scale,
             const FocalPrior& prior, Model* model)
      : points_(points),
        free_(free),
        length_scale_(length_scale),
        prior_(prior),
        model_(model),
        residuals_(Residuals(*model, points, prior)) {}

  double Cost() const { return residuals_.squaredNorm(); }

  bool Linearize() {
    const Eigen::MatrixXd j = Jacobian(*model_, points_, free_, length_scale_, prior_);
    normal_ = j.transpose() * j;
    gradient_ = j.transpose() * residuals_;
    damping_ = normal_.diagonal().cwiseMax(1e-300);  // a floor, only against a zero column
    return !gradient_.allFinite() || gradient_.lpNorm<Eigen::Infinity>() == 0.0;
  }

  // A step without a finite solution gives a non-finite candidate cost, which the driver
  // rejects like any other.
  LmStepStatus Step(double lambda, LmTrial* trial) {
    const Eigen::VectorXd step = DampedNormalStep(normal_, gradient_, lambda, damping_);
    Eigen::Matrix<double, kNumParams, 1> delta = Eigen::Matrix<double, kNumParams, 1>::Zero();
    for (size_t i = 0; i < free_.size(); ++i) delta(free_[i]) = step(i);
    candidate_ = Apply(*model_, delta);
    candidate_residuals_ = Residuals(candidate_, points_, prior_);
    trial->cost = candidate_residuals_.squaredNorm();
    // In Marquardt's scaled coordinates and relative to the residual norm, so that the stop
    // test (a step below rounding in every scaled coordinate) does not depend on units.
    const double scaled_step = (normal_.diagonal().cwiseSqrt().cwiseProduct(step)).norm();
    trial->step_squared_norm = scaled_step * scaled_step / (Cost() + 1e-300);
    return LmStepStatus::kSolved;
  }

  void Accept() {
    *model_ = candidate_;
    residuals_ = candidate_residuals_;
  }

 private:
  const std::vector<PointCorrespondence>& points_;
  const std::vector<int>& free_;
  double length_scale_;
  FocalPrior prior_;
  Model* model_;
  Eigen::VectorXd residuals_, candidate_residuals_, gradient_, damping_;
  Eigen::MatrixXd normal_;
  Model candidate_;
};

// Levenberg-Marquardt with Marquardt's diagonal scaling, which makes the step independent of
// the units of f, t and the distortion coefficients; the cost is in px^2 (with the prior's row).
LmResult Refine(const std::vector<PointCorrespondence>& points, const std::vector<int>& free, double length_scale,
                int max_iterations, const FocalPrior& prior, Model* model) {
  LmOptions options = TenfoldLmOptions(max_iterations);
  // No cap on lambda: 12 trials at most per linearisation.
  options.max_lambda = std::numeric_limits<double>::infinity();
  options.max_trials_per_linearization = 12;
  options.relative_decrease_tolerance = 1e-14;
  options.min_step_squared_norm = 1e-24;  // scaled step <= 1e-12 of the residual norm
  Refinement refinement(points, free, length_scale, prior, model);
  return MinimizeLevenbergMarquardt(refinement.Cost(), options, refinement);
}

struct LinearResult {
  Matrix34d p = Matrix34d::Zero();
  Eigen::Matrix3d k = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
};

bool LinearNonPlanar(const std::vector<PointCorrespondence>& points, LinearResult* out, std::string* error) {
  std::vector<Eigen::Vector3d> xyz;
  std::vector<Eigen::Vector2d> uv;
  for (const auto& p : points) {
    xyz.push_back(p.xyz);
    uv.push_back(p.uv_px);
  }
  const Eigen::Matrix4d t3 = Normalisation<3>(xyz);
  const Eigen::Matrix3d t2 = Normalisation<2>(uv);
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(2 * points.size(), 12);
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector4d x = t3 * xyz[i].homogeneous();
    const Eigen::Vector3d u = t2 * uv[i].homogeneous();
    a.block<1, 4>(2 * i, 0) = x.transpose();
    a.block<1, 4>(2 * i, 8) = -u.x() * x.transpose();
    a.block<1, 4>(2 * i + 1, 4) = x.transpose();
    a.block<1, 4>(2 * i + 1, 8) = -u.y() * x.transpose();
  }
  Eigen::VectorXd v;
  if (!NullVector(a, &v)) {
    *error =
        "the points do not determine a projection matrix (a degenerate configuration, e.g. points on a "
        "line and a plane, or coplanar up to noise)";
    return false;
  }
  Matrix34d p_normalised;
  p_normalised << v.segment<4>(0).transpose(), v.segment<4>(4).transpose(), v.segment<4>(8).transpose();
  Matrix34d p = t2.inverse() * p_normalised * t3;
  p /= p.norm();
  // The sign of P is free; with det M > 0 the RQ gives det R = +1 and K with positive
  // diagonal. The depth sign of a point (det M times its w) does not depend on this choice.
  const double det = p.leftCols<3>().determinant();
  if (!(std::abs(det) > 0.0)) {
    *error = "the projection matrix is singular (the camera centre is at infinity)";
    return false;
  }
  if (det < 0.0) p = -p;
  Eigen::Matrix3d k, r;
  RqDecomposition(p.leftCols<3>(), &k, &r);
  out->p = p;
  out->translation = k.inverse() * p.col(3);
  out->k = k / k(2, 2);
  out->rotation = r;
  return true;
}

bool LinearPlanar(const std::vector<PointCorrespondence>& points, const Eigen::Vector3d& centroid,
                  const Eigen::Matrix3d& plane_basis, const Eigen::Vector2d& principal_point_px, int width_px,
                  int height_px, double known_focal_px, double fallback_focal_px, LinearResult* out,
                  std::vector<std::string>* warnings, std::string* error) {
  std::vector<Eigen::Vector2d> ab, uv;
  for (const auto& p : points) {
    ab.push_back((plane_basis.transpose() * (p.xyz - centroid)).head<2>());
    uv.push_back(p.uv_px);
  }
  const Eigen::Matrix3d t_plane = Normalisation<2>(ab);
  const Eigen::Matrix3d t_image = Normalisation<2>(uv);
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(2 * points.size(), 9);
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d x = t_plane * ab[i].homogeneous();
    const Eigen::Vector3d u = t_image * uv[i].homogeneous();
    a.block<1, 3>(2 * i, 0) = x.transpose();
    a.block<1, 3>(2 * i, 6) = -u.x() * x.transpose();
    a.block<1, 3>(2 * i + 1, 3) = x.transpose();
    a.block<1, 3>(2 * i + 1, 6) = -u.y() * x.transpose();
  }
  Eigen::VectorXd v;
  if (!NullVector(a, &v)) {
    *error =
        "the plane's points do not determine a homography (three of four points on a line, or the "
        "plane seen edge-on)";
    return false;
  }
  Eigen::Matrix3d h_normalised;
  h_normalised << v.segment<3>(0).transpose(), v.segment<3>(3).transpose(), v.segment<3>(6).transpose();
  const Eigen::Matrix3d h = t_image.inverse() * h_normalised * t_plane;

  // Zhang's constraints with K = diag(f, f, 1) after moving the principal point to the
  // origin: h1^T w h2 = 0 and h1^T w h1 = h2^T w h2 for w = diag(1/f^2, 1/f^2, 1); each is
  // a1 / f^2 + b1 = 0, solved together by least squares in 1/f^2.
  Eigen::Matrix3d shift = Eigen::Matrix3d::Identity();
  shift.topRightCorner<2, 1>() = -principal_point_px;
  Eigen::Matrix3d hc = shift * h;
  hc /= hc.norm();
  const Eigen::Vector3d h1 = hc.col(0), h2 = hc.col(1);
  const double a1 = h1.x() * h2.x() + h1.y() * h2.y(), b1 = h1.z() * h2.z();
  const double a2 = h1.head<2>().squaredNorm() - h2.head<2>().squaredNorm(), b2 = h1.z() * h1.z() - h2.z() * h2.z();
  const double inverse_f2 = -(a1 * b1 + a2 * b2) / (a1 * a1 + a2 * a2);
  double focal_px = known_focal_px;
  if (!(focal_px > 0.0)) {
    const bool determined = inverse_f2 > 0.0 && std::isfinite(1.0 / std::sqrt(inverse_f2));
    if (!determined && !(fallback_focal_px > 0.0)) {
      *error =
          "the focal length is undetermined from this plane: it is seen (nearly) fronto-parallel, or the "
          "principal point is far from the one assumed";
      return false;
    }
    if (determined) {
      focal_px = 1.0 / std::sqrt(inverse_f2);
      const double diagonal_px = std::hypot(width_px, height_px);
      if (focal_px > 20.0 * diagonal_px)
        warnings->push_back(
            Format("the focal length (%.0f px) is weakly determined: the plane is seen nearly "
                   "fronto-parallel; tilt it or use non-coplanar points",
                   focal_px));
    } else {
      focal_px = fallback_focal_px;
      warnings->push_back(
          Format("the plane does not determine the focal length (seen fronto-parallel): it "
                 "starts from the prior, %.0f px",
                 focal_px));
    }
  }

  Eigen::Matrix3d k = Eigen::Matrix3d::Identity();
  k(0, 0) = k(1, 1) = focal_px;
  k.topRightCorner<2, 1>() = principal_point_px;
  const Eigen::Matrix3d b = k.inverse() * h;
  double lambda = 2.0 / (b.col(0).norm() + b.col(1).norm());
  if (!b.allFinite() || !std::isfinite(lambda) || !(lambda != 0.0)) {
    *error = "the plane's homography gives no pose for this focal length";
    return false;
  }
  // The plane's centroid is the origin of its coordinates: it lies in front of the camera.
  if (b(2, 2) < 0.0) lambda = -lambda;
  Eigen::Matrix3d rotation_from_plane;
  rotation_from_plane.col(0) = lambda * b.col(0);
  rotation_from_plane.col(1) = lambda * b.col(1);
  rotation_from_plane.col(2) = rotation_from_plane.col(0).cross(rotation_from_plane.col(1));
  rotation_from_plane = NearestRotation(rotation_from_plane);
  const Eigen::Vector3d translation_from_plane = lambda * b.col(2);

  out->k = k;
  out->rotation = rotation_from_plane * plane_basis.transpose();
  out->translation = translation_from_plane - out->rotation * centroid;
  out->p.leftCols<3>() = k * out->rotation;
  out->p.col(3) = k * out->translation;
  out->p /= out->p.norm();
  return true;
}

// t minimising the algebraic error [x_i]x (R X_i + t) = 0 of each point's ray x_i = K^-1 uv_i,
// with K and R held: the pose start of a calibrated camera after the DLT's own K is dropped.
bool TranslationGivenRotation(const std::vector<PointCorrespondence>& points, const Eigen::Matrix3d& k,
                              const Eigen::Matrix3d& rotation, Eigen::Vector3d* translation) {
  const Eigen::Matrix3d k_inverse = k.inverse();
  Eigen::MatrixXd a(3 * points.size(), 3);
  Eigen::VectorXd b(3 * points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d ray = (k_inverse * points[i].uv_px.homogeneous()).normalized();
    Eigen::Matrix3d skew;
    skew << 0, -ray.z(), ray.y(), ray.z(), 0, -ray.x(), -ray.y(), ray.x(), 0;
    a.block<3, 3>(3 * i, 0) = skew;
    b.segment<3>(3 * i) = -skew * rotation * points[i].xyz;
  }
  // Eigen's SVD of a matrix with NaN or infinity does not converge (and has crashed): refuse
  // it here whatever the options' checks let through.
  if (!a.allFinite() || !b.allFinite()) return false;
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeThinU | Eigen::ComputeThinV);
  if (!(svd.singularValues()(2) > 1e-12 * svd.singularValues()(0))) return false;
  *translation = svd.solve(b);
  return translation->allFinite();
}

double Rms(const Eigen::VectorXd& r) { return r.size() == 0 ? 0.0 : std::sqrt(r.squaredNorm() / (r.size() / 2)); }

// The shape of the 3D points: their centroid, principal directions (columns of basis, the
// largest spread first) and singular values of the centred points.
struct PointShape {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  Eigen::Matrix3d basis = Eigen::Matrix3d::Identity();
  Eigen::Vector3d singular_values = Eigen::Vector3d::Zero();
};

PointShape ShapeOf(const std::vector<PointCorrespondence>& points) {
  const int n = static_cast<int>(points.size());
  PointShape shape;
  for (const auto& p : points) shape.centroid += p.xyz;
  shape.centroid /= n;
  Eigen::MatrixXd centred(n, 3);
  for (int i = 0; i < n; ++i) centred.row(i) = (points[i].xyz - shape.centroid).transpose();
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(centred, Eigen::ComputeThinV);
  shape.basis = svd.matrixV();
  shape.singular_values = svd.singularValues();
  return shape;
}

// The linear camera: the plane's homography with Zhang's focal length, or the DLT (6 or more
// points). Fills the summary's linear figures and warnings. False (with *error) on a
// configuration that does not determine a camera.
bool LinearCamera(const std::vector<PointCorrespondence>& points, const PointShape& shape,
                  const DltCalibrationOptions& options, const Eigen::Vector2d& given_principal_point, bool use_prior,
                  LinearResult* linear, DltCalibrationSummary* summary, std::string* error) {
  const int n = static_cast<int>(points.size());
  if (summary->planar) {
    Eigen::Matrix3d basis = shape.basis;
    basis.col(2) = basis.col(0).cross(basis.col(1));
    if (!LinearPlanar(points, shape.centroid, basis, given_principal_point, options.width_px, options.height_px,
                      options.fixed_focal_px, use_prior ? options.focal_prior_px : 0.0, linear, &summary->warnings,
                      error))
      return false;
  } else {
    const double planarity = shape.singular_values(2) / shape.singular_values(0);
    if (planarity < kNearlyPlanarRatio)
      summary->warnings.push_back(
          Format("the points are nearly coplanar (thickness %.2g of their extent): the "
                 "linear estimate is poorly conditioned",
                 planarity));
    if (!LinearNonPlanar(points, linear, error)) return false;
  }
  summary->P = linear->p;
  summary->fx = linear->k(0, 0);
  summary->fy = linear->k(1, 1);
  summary->skew = linear->k(0, 1);
  summary->linear_principal_point_px = linear->k.block<2, 1>(0, 2);
  // The linear camera's own error: with its fx, fy and skew (pinhole).
  Eigen::VectorXd r(2 * n);
  for (int i = 0; i < n; ++i)
    r.segment<2>(2 * i) = (linear->p * points[i].xyz.homogeneous()).hnormalized() - points[i].uv_px;
  summary->initial_rms_px = Rms(r);
  return true;
}

// The refined parameters: f unless known, the principal point when solved, R, t, and the
// distortion terms asked for.
std::vector<int> FreeParameters(const DltCalibrationOptions& options, bool focal_fixed, bool solve_principal_point) {
  std::vector<int> free;
  if (!focal_fixed) free.push_back(kFocal);
  if (solve_principal_point) {
    free.push_back(kCx);
    free.push_back(kCy);
  }
  for (int p = kRotation; p < kTranslation + 3; ++p) free.push_back(p);  // R, then t
  if (options.radial_distortion_terms >= 1) free.push_back(kK1);
  if (options.radial_distortion_terms >= 2) free.push_back(kK2);
  return free;
}

// One-sigma standard deviations of the free parameters from the covariance (J^T J)^-1 at the
// refined model, scaled by the residual variance; a warning when J^T J is singular.
void EstimateStd(const std::vector<PointCorrespondence>& points, const std::vector<int>& free, double length_scale,
                 const FocalPrior& prior, const Model& model, DltCalibrationSummary* summary) {
  const Eigen::MatrixXd jacobian = Jacobian(model, points, free, length_scale, prior);
  const int dof = 2 * static_cast<int>(points.size()) + (prior.weight > 0.0 ? 1 : 0) - static_cast<int>(free.size());
  const Eigen::MatrixXd information = jacobian.transpose() * jacobian;
  if (!information.allFinite()) {  // Eigen's SVD does not converge on NaN or infinity
    summary->warnings.push_back("the refinement's uncertainties overflowed: no standard deviations");
    return;
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> info_svd(information, Eigen::ComputeFullU | Eigen::ComputeFullV);
  if (dof > 0 && info_svd.singularValues()(free.size() - 1) > 1e-14 * info_svd.singularValues()(0)) {
    const double variance = Residuals(model, points, prior).squaredNorm() / dof;
    const Eigen::MatrixXd covariance = variance * information.inverse();
    for (size_t c = 0; c < free.size(); ++c) {
      const double sd = std::sqrt(std::max(covariance(c, c), 0.0));
      if (free[c] == kFocal) summary->focal_std_px = sd;
      if (free[c] == kCx) summary->principal_point_std_px.x() = sd;
      if (free[c] == kCy) summary->principal_point_std_px.y() = sd;
      if (free[c] == kK1) summary->k1_std = sd;
    }
  } else if (dof > 0) {
    summary->warnings.push_back("the refinement's parameters are not all determined by these points");
  }
}

// The final camera, its reprojection errors, the points behind it and the one-line message.
void ReportCamera(const std::vector<PointCorrespondence>& points, const Model& model,
                  const DltCalibrationOptions& options, bool solve_principal_point, DltCalibrationSummary* summary) {
  Camera& camera = summary->camera;
  camera.width_px = options.width_px;
  camera.height_px = options.height_px;
  camera.focal_px = model.focal_px;
  camera.principal_point_px = model.principal_point_px;
  camera.cam_from_world_rotation = model.rotation;
  camera.cam_from_world_translation = model.translation;
  summary->k1 = model.k1;
  summary->k2 = model.k2;

  const int n = static_cast<int>(points.size());
  const Eigen::VectorXd r = Residuals(model, points);
  summary->residuals_px.resize(n);
  int behind = 0;
  for (int i = 0; i < n; ++i) {
    summary->residuals_px[i] = r.segment<2>(2 * i).norm();
    if (camera.CamFromWorld(points[i].xyz).z() <= 0.0) ++behind;
  }
  summary->reprojection_rms_px = Rms(r);
  if (behind > 0)
    summary->warnings.push_back(std::to_string(behind) +
                                " point(s) lie behind the camera: a point or its pixel "
                                "is probably wrong");
  summary->message = Format(summary->planar ? "planar (homography), f = %.2f px, RMS %.3f px (linear %.3f px)"
                                            : "DLT, f = %.2f px, RMS %.3f px (linear %.3f px)",
                            camera.focal_px, summary->reprojection_rms_px, summary->initial_rms_px);
  if (summary->focal_fixed) summary->message += "; focal length known (pose only)";
  if (summary->focal_prior_used)
    summary->message += Format("; focal prior %.1f +- %.1f px", options.focal_prior_px, options.focal_prior_std_px);
  if (!solve_principal_point && (options.refine || summary->planar))
    summary->message +=
        Format("; principal point held at (%.1f, %.1f)", camera.principal_point_px.x(), camera.principal_point_px.y());
}

}  // namespace

bool DltCalibrationOptions::Check(std::string* error) const {
  if (width_px <= 0 || height_px <= 0) {
    *error = "the image size must be positive";
    return false;
  }
  if (!square_pixels_zero_skew) {
    *error = "only square pixels with zero skew are supported (the camera model has one focal length)";
    return false;
  }
  if (radial_distortion_terms < 0 || radial_distortion_terms > 2) {
    *error = "radial_distortion_terms must be 0, 1 or 2";
    return false;
  }
  if (radial_distortion_terms > 0 && !refine) {
    *error = "radial distortion is estimated only by the refinement: set refine";
    return false;
  }
  if (max_iterations < 0) {
    *error = "max_iterations must not be negative";
    return false;
  }
  if (principal_point_mode == PrincipalPointMode::kFixed && !fixed_principal_point_px.allFinite()) {
    *error = "the fixed principal point must be finite";
    return false;
  }
  if (!(fixed_focal_px >= 0.0) || !std::isfinite(fixed_focal_px)) {
    *error = "fixed_focal_px must be finite and not negative (0: solve the focal length)";
    return false;
  }
  // A known focal length far outside any lens overflows the pose's linear algebra (1e-300 px
  // made K^-1 infinite and the SVD crash): the range of WhyNotACamera, checked before use.
  if (fixed_focal_px > 0.0) {
    const std::string why = WhyNotAFocalLength(fixed_focal_px, width_px, height_px);
    if (!why.empty()) {
      *error = "fixed_focal_px: " + why;
      return false;
    }
  }
  if (!(focal_prior_px >= 0.0) || !std::isfinite(focal_prior_px) || !(focal_prior_std_px >= 0.0) ||
      !std::isfinite(focal_prior_std_px)) {
    *error = "focal_prior_px and focal_prior_std_px must be finite and not negative (0: no prior)";
    return false;
  }
  if (focal_prior_px > 0.0 && focal_prior_std_px > 0.0) {
    const std::string why = WhyNotAFocalPrior(focal_prior_px, focal_prior_std_px, width_px, height_px);
    if (!why.empty()) {
      *error = "focal prior: " + why;
      return false;
    }
  }
  if (!(pixel_noise_px > 0.0) || !std::isfinite(pixel_noise_px)) {
    *error = "pixel_noise_px must be positive";
    return false;
  }
  return true;
}

DltCalibrationSummary CalibrateFromPoints(const std::vector<PointCorrespondence>& points,
                                          const DltCalibrationOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  DltCalibrationSummary summary;
  std::string error;
  if (!options.Check(&error))
    return FailedSummary(summary, "invalid options: " + error, start, SolverTermination::kInvalidInput);
  for (size_t i = 0; i < points.size(); ++i) {
    if (!points[i].xyz.allFinite() || !points[i].uv_px.allFinite())
      return FailedSummary(summary, "point " + std::to_string(i) + " has a non-finite coordinate", start,
                           SolverTermination::kInvalidInput);
  }
  const int n = static_cast<int>(points.size());
  if (n < 4)
    return FailedSummary(
        summary,
        "calibration needs 6 or more non-coplanar points or 4 or more coplanar points, got " + std::to_string(n), start,
        SolverTermination::kInvalidInput);

  // Shape of the 3D points: a line, a plane, or a volume.
  const PointShape shape = ShapeOf(points);
  const Eigen::Vector3d& s = shape.singular_values;
  if (!(s(0) > 0.0) || s(1) < kCollinearRatio * s(0))
    return FailedSummary(summary, "the 3D points are all on one line (or one point): they do not determine a camera",
                         start, SolverTermination::kInvalidInput);
  summary.planar = s(2) / s(0) < kPlanarRatio;
  const double length_scale = s(0) / std::sqrt(static_cast<double>(n));
  const Eigen::Vector2d image_center((options.width_px - 1) / 2.0, (options.height_px - 1) / 2.0);
  const Eigen::Vector2d given_principal_point =
      options.principal_point_mode == PrincipalPointMode::kFixed ? options.fixed_principal_point_px : image_center;

  const bool focal_fixed = options.fixed_focal_px > 0.0;
  const bool use_prior = !focal_fixed && options.focal_prior_px > 0.0 && options.focal_prior_std_px > 0.0;
  FocalPrior prior;
  if (use_prior) prior = {options.focal_prior_px, options.pixel_noise_px / options.focal_prior_std_px};
  summary.focal_fixed = focal_fixed;

  if (!summary.planar && n < 6)
    return FailedSummary(summary,
                         "the points are not coplanar: that needs 6 or more points, got " + std::to_string(n) +
                             " (or give 4 or more points on one plane)",
                         start, SolverTermination::kInvalidInput);
  LinearResult linear;
  if (!LinearCamera(points, shape, options, given_principal_point, use_prior, &linear, &summary, &error))
    return FailedSummary(summary, error, start);
  Model model;
  model.focal_px = 0.5 * (summary.fx + summary.fy);
  model.principal_point_px = summary.linear_principal_point_px;
  model.rotation = linear.rotation;
  model.translation = linear.translation;

  const bool solve_principal_point = !summary.planar && options.principal_point_mode == PrincipalPointMode::kSolve;
  // Without refinement the camera stays the linear one (a non-planar DLT estimates its own
  // principal point); the refinement starts from the held principal point.
  if (!solve_principal_point && options.refine) model.principal_point_px = given_principal_point;
  if (focal_fixed && !summary.planar) {
    // The DLT's K is dropped for the known one: its R stays, t follows for the known K.
    model.focal_px = options.fixed_focal_px;
    Eigen::Matrix3d k = Eigen::Matrix3d::Identity();
    k(0, 0) = k(1, 1) = model.focal_px;
    k.topRightCorner<2, 1>() = model.principal_point_px;
    if (!TranslationGivenRotation(points, k, model.rotation, &model.translation))
      return FailedSummary(summary, "the points do not determine the camera position for the known focal length",
                           start);
  }
  if (use_prior && options.refine) summary.focal_prior_used = true;
  summary.termination = SolverTermination::kConverged;
  if (options.refine) {
    const std::vector<int> free = FreeParameters(options, focal_fixed, solve_principal_point);
    if (2 * n < static_cast<int>(free.size()))
      return FailedSummary(summary,
                           "too few points for the requested model: " + std::to_string(free.size()) +
                               " parameters need at least " + std::to_string((free.size() + 1) / 2) + " points",
                           start, SolverTermination::kInvalidInput);
    const LmResult refined = Refine(points, free, length_scale, options.max_iterations, prior, &model);
    summary.iterations = refined.iterations;
    summary.initial_cost = refined.initial_cost;
    summary.final_cost = refined.final_cost;
    if (refined.termination == LmTermination::kMaxIterations) summary.termination = SolverTermination::kMaxIterations;
    EstimateStd(points, free, length_scale, prior, model, &summary);
  }

  if (!(model.focal_px > 0.0) || !model.rotation.allFinite() || !model.translation.allFinite())
    return FailedSummary(summary, "the calibration diverged (no positive focal length); check the points", start);
  ReportCamera(points, model, options, solve_principal_point, &summary);
  std::string not_a_camera = WhyNotACamera(summary.camera.focal_px, summary.camera.principal_point_px,
                                           options.width_px, options.height_px);
  if (not_a_camera.empty()) not_a_camera = WhyFocalIsUndetermined(summary.camera.focal_px, summary.focal_std_px);
  if (!not_a_camera.empty()) return FailedSummary(summary, "no camera: " + not_a_camera, start);
  summary.time_ms = internal::MsSince(start);
  return summary;
}

}  // namespace facet
