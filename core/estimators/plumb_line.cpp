#include "core/estimators/plumb_line.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>

#include <Eigen/Dense>

#include "core/geometry/tangent_basis.h"
#include "core/optim/damped_normal_step.h"
#include "core/optim/levenberg_marquardt.h"
#include "core/util/eigen_decompositions.h"
#include "core/util/timer.h"

namespace facet {
namespace {

using internal::FailedSummary;

// Inverting an odd polynomial radius map: Newton steps that stop below this (in the
// normalised radius, ~1e-13 px at s = 1000 px).
constexpr double kRadiusTolerance = 1e-16;
// Sampling of the radial mapping when converting to and from OpenCV's model.
constexpr int kConversionSamples = 400;
// Lines whose residuals change by less than this (in units of s per unit k1, RMS over the
// residuals) carry no distortion information: lines through the centre stay straight.
constexpr double kMinRelativeSensitivity = 1e-7;
// k2 is dropped when the data cannot tell it from k1 (reduced information nearly singular).
constexpr double kMaxK1K2Correlation = 0.9999;
// Central-difference steps: k in units of r^2 (order 1), vanishing point on the unit sphere.
constexpr double kDerivativeStep = 1e-6;

// g(x) = x (1 + a[0] x^2 + a[1] x^4 + a[2] x^6) and its derivative.
double OddPolynomial(const std::array<double, 3>& a, double x) {
  const double x2 = x * x;
  return x * (1.0 + x2 * (a[0] + x2 * (a[1] + x2 * a[2])));
}
double OddPolynomialDerivative(const std::array<double, 3>& a, double x) {
  const double x2 = x * x;
  return 1.0 + x2 * (3.0 * a[0] + x2 * (5.0 * a[1] + x2 * 7.0 * a[2]));
}

// Solves g(x) = target >= 0 for x on the increasing branch of g that starts at x = 0.
// Returns false when that branch ends (g' <= 0) before reaching target; *x is then the
// largest x reached.
bool InvertOddPolynomial(const std::array<double, 3>& a, double target, double* x) {
  *x = 0.0;
  if (target <= 0.0) return true;
  // Bracket by marching, so that a turning point of g is found rather than jumped over.
  const double step = target / 16.0;
  double lo = 0.0;
  double hi = 0.0;
  bool bracketed = false;
  for (int i = 1; i <= 4096; ++i) {
    const double xi = i * step;
    if (OddPolynomialDerivative(a, xi) <= 0.0) break;
    if (OddPolynomial(a, xi) >= target) {
      hi = xi;
      bracketed = true;
      break;
    }
    lo = xi;
  }
  if (!bracketed) {
    *x = lo;
    return false;
  }
  double xi = 0.5 * (lo + hi);
  for (int iteration = 0; iteration < 200; ++iteration) {
    const double g = OddPolynomial(a, xi) - target;
    if (g == 0.0) break;
    if (g > 0.0) {
      hi = xi;
    } else {
      lo = xi;
    }
    const double derivative = OddPolynomialDerivative(a, xi);
    double next = xi - g / derivative;
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const double change = std::abs(next - xi);
    xi = next;
    if (change <= kRadiusTolerance * std::max(1.0, xi) || hi - lo <= kRadiusTolerance * std::max(1.0, xi)) break;
  }
  *x = xi;
  return true;
}

Eigen::Vector2d Perpendicular(const Eigen::Vector2d& d) { return Eigen::Vector2d(-d.y(), d.x()); }

// A polyline in conditioned coordinates (uv - c) / s, with its role in the cost.
struct Polyline {
  std::vector<Eigen::Vector2d> points;
  int family_slot = -1;  // index into the vanishing points, -1: own free line
  int first_residual = 0;
  int num_residuals = 0;  // 0 for a free 2-point polyline (always straight)
};

struct Problem {
  std::vector<Polyline> polylines;
  int num_families = 0;
  int num_residuals = 0;
};

// Parameters: k (1 or 2 entries) then two tangent coordinates per family, applied to the
// base vanishing points.
struct State {
  double k1 = 0.0;
  double k2 = 0.0;
  std::vector<Eigen::Vector3d> vanishing_points;  // unit, conditioned undistorted coordinates
};

Eigen::Vector2d UndistortConditioned(const Eigen::Vector2d& p, double k1, double k2) {
  const double r2 = p.squaredNorm();
  return p * (1.0 + r2 * (k1 + r2 * k2));
}

// Unit line direction of a polyline (dominant eigenvector of its scatter), oriented from its
// first to its last point so that small parameter changes never flip its sign.
Eigen::Vector2d LineDirection(const std::vector<Eigen::Vector2d>& points, const Eigen::Vector2d& centroid) {
  Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
  for (const auto& p : points) scatter += (p - centroid) * (p - centroid).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen;
  eigen.computeDirect(scatter);
  Eigen::Vector2d direction = eigen.eigenvectors().col(1);
  Eigen::Vector2d span = points.back() - points.front();
  if (span.squaredNorm() == 0.0) span = points[1] - points.front();
  if (direction.dot(span) < 0.0) direction = -direction;
  return direction;
}

Eigen::Vector2d Centroid(const std::vector<Eigen::Vector2d>& points) {
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  for (const auto& p : points) sum += p;
  return sum / static_cast<double>(points.size());
}

// How far the undistortion stretches the image at p across a line of unit normal n: the
// norm of D^T n with D the (symmetric) Jacobian of UndistortConditioned at p.
double StretchAcross(const Eigen::Vector2d& p, const Eigen::Vector2d& normal, double k1, double k2) {
  const double r2 = p.squaredNorm();
  const double f = 1.0 + r2 * (k1 + r2 * k2);
  const double f_prime = k1 + 2.0 * r2 * k2;
  return (f * normal + 2.0 * f_prime * p.dot(normal) * p).norm();
}

// Signed distances (conditioned units) of every point to its line, in residual order. With
// in_observed_units each distance is divided by the local stretch of the undistortion across
// the line, which turns it into (to first order) a distance in the observed image, where the
// clicking noise lives: the least-squares fit is then maximum-likelihood for isotropic pixel
// noise, and the edges, which the model stretches or shrinks, get their fair weight.
// only_family_slot >= 0 evaluates that family's polylines alone (the others' entries are
// zero), for the vanishing-point columns of the Jacobian.
Eigen::VectorXd Residuals(const Problem& problem, const State& state, bool in_observed_units = true,
                          int only_family_slot = -1) {
  Eigen::VectorXd residuals = Eigen::VectorXd::Zero(problem.num_residuals);
  std::vector<Eigen::Vector2d> undistorted;
  for (const auto& polyline : problem.polylines) {
    if (polyline.num_residuals == 0) continue;
    if (only_family_slot >= 0 && polyline.family_slot != only_family_slot) continue;
    undistorted.clear();
    for (const auto& p : polyline.points) undistorted.push_back(UndistortConditioned(p, state.k1, state.k2));
    const Eigen::Vector2d centroid = Centroid(undistorted);
    Eigen::Vector2d normal;
    double offset = 0.0;  // the line is normal . x = offset
    if (polyline.family_slot < 0) {
      normal = Perpendicular(LineDirection(undistorted, centroid));
      offset = normal.dot(centroid);
    } else {
      // Line through the vanishing point and the centroid (H&Z 8.6.1 with the midpoint).
      const Eigen::Vector3d line =
          state.vanishing_points[polyline.family_slot].cross(Eigen::Vector3d(centroid.x(), centroid.y(), 1.0));
      const double norm = line.head<2>().norm();
      if (norm == 0.0) {
        residuals.segment(polyline.first_residual, polyline.num_residuals)
            .setConstant(std::numeric_limits<double>::infinity());
        continue;
      }
      normal = line.head<2>() / norm;
      offset = -line.z() / norm;
    }
    for (size_t i = 0; i < undistorted.size(); ++i) {
      double distance = normal.dot(undistorted[i]) - offset;
      if (in_observed_units) distance /= StretchAcross(polyline.points[i], normal, state.k1, state.k2);
      residuals(polyline.first_residual + i) = distance;
    }
  }
  return residuals;
}

// Which parameters the optimiser moves.
struct ActiveSet {
  bool k1 = true;
  bool k2 = false;
  int num_families = 0;
  int Size() const { return (k1 ? 1 : 0) + (k2 ? 1 : 0) + 2 * num_families; }
};

State Apply(const State& base, const ActiveSet& active, const Eigen::VectorXd& delta) {
  State state = base;
  int index = 0;
  if (active.k1) state.k1 += delta(index++);
  if (active.k2) state.k2 += delta(index++);
  for (int f = 0; f < active.num_families; ++f) {
    const Eigen::Vector3d v = base.vanishing_points[f];
    state.vanishing_points[f] = (v + internal::TangentBasis(v) * delta.segment<2>(index)).normalized();
    index += 2;
  }
  return state;
}

Eigen::MatrixXd NumericJacobian(const Problem& problem, const State& state, const ActiveSet& active) {
  const int n = active.Size();
  Eigen::MatrixXd jacobian(problem.num_residuals, n);
  Eigen::VectorXd delta = Eigen::VectorXd::Zero(n);
  const int num_k = (active.k1 ? 1 : 0) + (active.k2 ? 1 : 0);
  for (int j = 0; j < n; ++j) {
    // A vanishing point moves its own family's residuals only.
    const int slot = j < num_k ? -1 : (j - num_k) / 2;
    delta(j) = kDerivativeStep;
    const Eigen::VectorXd plus = Residuals(problem, Apply(state, active, delta), true, slot);
    delta(j) = -kDerivativeStep;
    const Eigen::VectorXd minus = Residuals(problem, Apply(state, active, delta), true, slot);
    delta(j) = 0.0;
    jacobian.col(j) = (plus - minus) / (2.0 * kDerivativeStep);
  }
  return jacobian;
}

// The plumb-line fit for the Levenberg-Marquardt driver: k moves additively, each vanishing
// point on the unit sphere (Apply); Jacobian by central differences.
class PlumbLineFit {
 public:
  PlumbLineFit(const Problem& problem, const ActiveSet& active, State* state)
      : problem_(problem), active_(active), state_(state), residuals_(Residuals(problem, *state)) {}

  double Cost() const { return residuals_.squaredNorm(); }

  bool Linearize() {
    const Eigen::MatrixXd jacobian = NumericJacobian(problem_, *state_, active_);
    normal_ = jacobian.transpose() * jacobian;
    gradient_ = jacobian.transpose() * residuals_;
    damping_ = normal_.diagonal().cwiseMax(1e-12);  // a floor, not an addition
    // Stationary to rounding: the largest gradient entry is below 1e-15 of the cost.
    return gradient_.cwiseAbs().maxCoeff() <= 1e-15 * std::max(Cost(), 1e-300);
  }

  LmStepStatus Step(double lambda, LmTrial* trial) {
    const Eigen::VectorXd step = DampedNormalStep(normal_, gradient_, lambda, damping_);
    if (!step.allFinite()) return LmStepStatus::kSolveFailed;
    candidate_ = Apply(*state_, active_, step);
    candidate_residuals_ = Residuals(problem_, candidate_);
    trial->cost = candidate_residuals_.squaredNorm();
    trial->step_squared_norm = step.squaredNorm();
    return LmStepStatus::kSolved;
  }

  void Accept() {
    *state_ = candidate_;
    residuals_ = candidate_residuals_;
  }

 private:
  const Problem& problem_;
  const ActiveSet& active_;
  State* state_;
  Eigen::VectorXd residuals_, candidate_residuals_, gradient_, damping_;
  Eigen::MatrixXd normal_;
  State candidate_;
};

// Levenberg-Marquardt over the active parameters from *state.
LmResult Minimise(const Problem& problem, const ActiveSet& active, int max_iterations, State* state) {
  if (active.Size() == 0 || problem.num_residuals == 0) {
    LmResult nothing_to_fit;
    nothing_to_fit.termination = LmTermination::kConverged;
    return nothing_to_fit;
  }
  LmOptions options = TenfoldLmOptions(max_iterations);
  // No cap on lambda: 30 trials at most per linearisation, a damped system without a finite
  // solution counting as one.
  options.max_lambda = std::numeric_limits<double>::infinity();
  options.max_lambda_on_failed_solve = std::numeric_limits<double>::infinity();
  options.max_trials_per_linearization = 30;
  options.relative_decrease_tolerance = 1e-15;
  options.min_step_squared_norm = 1e-28;  // |step| <= 1e-14 (k, tangent coordinates)
  PlumbLineFit fit(problem, active, state);
  return MinimizeLevenbergMarquardt(fit.Cost(), options, fit);
}

// Pseudo-inverse of a symmetric positive semi-definite matrix: eigenvalues below a relative
// threshold (directions the data do not determine) are dropped rather than inverted.
Eigen::MatrixXd PseudoInverseSymmetric(const Eigen::MatrixXd& matrix) {
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(matrix);
  const Eigen::VectorXd& values = eigen.eigenvalues();
  const double threshold = 1e-14 * std::max(values.cwiseAbs().maxCoeff(), 1e-300);
  Eigen::VectorXd inverse_values = Eigen::VectorXd::Zero(values.size());
  for (Eigen::Index i = 0; i < values.size(); ++i) {
    if (values(i) > threshold) inverse_values(i) = 1.0 / values(i);
  }
  return eigen.eigenvectors() * inverse_values.asDiagonal() * eigen.eigenvectors().transpose();
}

// Reduced (Schur complement) information of the k parameters: the vanishing points are
// nuisance parameters whose freedom must not be mistaken for information about k.
Eigen::MatrixXd ReducedInformation(const Eigen::MatrixXd& jacobian, int num_k) {
  const Eigen::MatrixXd normal = jacobian.transpose() * jacobian;
  const int num_v = static_cast<int>(normal.rows()) - num_k;
  Eigen::MatrixXd reduced = normal.topLeftCorner(num_k, num_k);
  if (num_v > 0) {
    const Eigen::MatrixXd vv_inverse = PseudoInverseSymmetric(normal.bottomRightCorner(num_v, num_v));
    reduced -= normal.topRightCorner(num_k, num_v) * vv_inverse * normal.bottomLeftCorner(num_v, num_k);
  }
  return reduced;
}

// Initial vanishing point of a family: smallest singular vector of its stacked best-fit
// lines (each normalised so its value at a point is a distance).
Eigen::Vector3d AlgebraicVanishingPoint(const Problem& problem, int slot, double k1, double k2) {
  std::vector<Eigen::RowVector3d> rows;
  for (const auto& polyline : problem.polylines) {
    if (polyline.family_slot != slot) continue;
    std::vector<Eigen::Vector2d> undistorted;
    for (const auto& p : polyline.points) undistorted.push_back(UndistortConditioned(p, k1, k2));
    const Eigen::Vector2d centroid = Centroid(undistorted);
    const Eigen::Vector2d normal = Perpendicular(LineDirection(undistorted, centroid));
    rows.emplace_back(normal.x(), normal.y(), -normal.dot(centroid));
  }
  Eigen::MatrixXd stacked(rows.size(), 3);
  for (size_t i = 0; i < rows.size(); ++i) stacked.row(i) = rows[i];
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(stacked, Eigen::ComputeFullV);
  return svd.matrixV().col(2).normalized();
}

std::string Format(const char* format, double a, double b = 0.0, double c = 0.0) {
  char buffer[256];
  std::snprintf(buffer, sizeof(buffer), format, a, b, c);
  return buffer;
}

double Rms(const Eigen::VectorXd& residuals, int count) {
  return count > 0 ? std::sqrt(residuals.squaredNorm() / count) : 0.0;
}

// What the polylines contribute: the input family of each vanishing point (slot), the points
// that constrain anything and the independent constraints they give.
struct ProblemLayout {
  std::vector<int> family_of_slot;
  int num_points = 0;
  int num_constraints = 0;  // points minus line and vanishing-point dofs, >= 0
};

// The polylines in conditioned coordinates of `model`, with their residual ranges. Families
// with two or more polylines get a vanishing point; a lone member is a free line. False
// (with *error) on a polyline with fewer than 2 distinct or non-finite points.
bool BuildProblem(const std::vector<PlumbLine>& lines, const RadialDistortion& model, Problem* problem,
                  ProblemLayout* layout, std::string* error) {
  std::map<int, int> family_sizes;
  for (const auto& line : lines) {
    if (line.family >= 0) ++family_sizes[line.family];
  }
  std::map<int, int> slot_of_family;
  for (const auto& [family, size] : family_sizes) {
    if (size >= 2) {
      slot_of_family[family] = static_cast<int>(layout->family_of_slot.size());
      layout->family_of_slot.push_back(family);
    }
  }
  problem->num_families = static_cast<int>(layout->family_of_slot.size());
  int num_constraints = -2 * problem->num_families;
  for (size_t i = 0; i < lines.size(); ++i) {
    const auto& points = lines[i].points_px;
    if (points.size() < 2) {
      *error = "polyline " + std::to_string(i) + " has fewer than 2 points";
      return false;
    }
    Polyline polyline;
    double extent = 0.0;
    for (const auto& p : points) {
      if (!p.allFinite()) {
        *error = "polyline " + std::to_string(i) + " has a non-finite point";
        return false;
      }
      polyline.points.push_back((p - model.center_px) / model.scale_px);
      extent = std::max(extent, (p - points.front()).norm());
    }
    if (extent == 0.0) {
      *error = "polyline " + std::to_string(i) + " has all its points at one pixel";
      return false;
    }
    const auto slot = slot_of_family.find(lines[i].family);
    polyline.family_slot = slot == slot_of_family.end() ? -1 : slot->second;
    const int n = static_cast<int>(points.size());
    if (polyline.family_slot >= 0 || n >= 3) {
      polyline.first_residual = problem->num_residuals;
      polyline.num_residuals = n;
      problem->num_residuals += n;
      layout->num_points += n;
      num_constraints += polyline.family_slot >= 0 ? n - 1 : n - 2;
    }
    problem->polylines.push_back(std::move(polyline));
  }
  layout->num_constraints = std::max(num_constraints, 0);
  return true;
}

// The coefficients to estimate, from the information about k at `state` net of the vanishing
// points' freedom: k1 always, k2 when asked and the data can separate it from k1 (else a
// warning). False (with *error) when the lines carry no distortion information.
bool ChooseCoefficients(const Problem& problem, const State& state, const PlumbLineOptions& options,
                        int num_constraints, ActiveSet* active, std::vector<std::string>* warnings,
                        std::string* error) {
  active->num_families = problem.num_families;
  active->k2 = true;
  const Eigen::MatrixXd information = ReducedInformation(NumericJacobian(problem, state, *active), 2);
  const double k1_sensitivity = std::sqrt(std::max(information(0, 0), 0.0) / problem.num_residuals);
  if (!(k1_sensitivity > kMinRelativeSensitivity)) {
    *error =
        "the lines carry no distortion information (they all pass through the centre of distortion, where radial "
        "distortion keeps them straight); k = 0";
    return false;
  }
  active->k2 = false;
  if (!options.estimate_k2) return true;
  const double product = information(0, 0) * information(1, 1);
  const double correlation = product > 0.0 ? std::abs(information(0, 1)) / std::sqrt(product) : 1.0;
  if (num_constraints < 3) {
    warnings->push_back("k2 not estimated: it needs at least 3 independent constraints, there are " +
                        std::to_string(num_constraints));
  } else if (!(correlation < kMaxK1K2Correlation)) {
    warnings->push_back(
        Format("k2 not estimated: the points do not span enough radii to separate k2 from k1 (correlation %.6f)",
               correlation));
  } else {
    active->k2 = true;
  }
  return true;
}

// One-sigma standard deviations of k from the Gauss-Newton covariance of the reduced
// information, scaled by the residual variance; the noise sigma in px.
void EstimateCoefficientStd(const Problem& problem, const State& state, const ActiveSet& active, int num_constraints,
                            const Eigen::VectorXd& residuals, double scale, PlumbLineSummary* summary) {
  const int num_k = active.k2 ? 2 : 1;
  const int dof = num_constraints - num_k;
  const Eigen::MatrixXd reduced = ReducedInformation(NumericJacobian(problem, state, active), num_k);
  const double variance = dof > 0 ? residuals.squaredNorm() / dof : 0.0;
  const Eigen::MatrixXd covariance = variance * PseudoInverseSymmetric(reduced);
  summary->noise_sigma_px = scale * std::sqrt(variance);
  summary->k1_std = std::sqrt(std::max(covariance(0, 0), 0.0));
  summary->k2_std = active.k2 ? std::sqrt(std::max(covariance(1, 1), 0.0)) : 0.0;
}

// Straightness per polyline and the vanishing points in undistorted px.
void ReportLines(const Problem& problem, const ProblemLayout& layout, const State& state,
                 const Eigen::VectorXd& distances, const RadialDistortion& model, PlumbLineSummary* summary) {
  const double scale = model.scale_px;
  const Eigen::Vector2d& center = model.center_px;
  summary->final_rms_px = scale * Rms(distances, layout.num_points);
  for (size_t i = 0; i < problem.polylines.size(); ++i) {
    const auto& polyline = problem.polylines[i];
    if (polyline.num_residuals == 0) continue;
    summary->line_rms_px[i] =
        scale * Rms(distances.segment(polyline.first_residual, polyline.num_residuals), polyline.num_residuals);
  }
  int max_family = -1;
  for (int family : layout.family_of_slot) max_family = std::max(max_family, family);
  summary->vanishing_points_px.assign(max_family + 1, Eigen::Vector3d::Zero());
  for (int slot = 0; slot < problem.num_families; ++slot) {
    const Eigen::Vector3d& v = state.vanishing_points[slot];
    Eigen::Vector3d v_px(scale * v.x() + center.x() * v.z(), scale * v.y() + center.y() * v.z(), v.z());
    v_px.normalize();
    if (v_px.z() < 0.0) v_px = -v_px;
    summary->vanishing_points_px[layout.family_of_slot[slot]] = v_px;
  }
}

SolverTermination TerminationOf(const LmResult& fit) {
  return fit.termination == LmTermination::kMaxIterations ? SolverTermination::kMaxIterations
                                                          : SolverTermination::kConverged;
}

}  // namespace

Eigen::Vector2d RadialDistortion::Undistort(const Eigen::Vector2d& uv_distorted_px) const {
  const Eigen::Vector2d d = uv_distorted_px - center_px;
  const double r2 = d.squaredNorm() / (scale_px * scale_px);
  return center_px + d * (1.0 + r2 * (k1 + r2 * k2));
}

double RadialDistortion::UndistortRadiusPx(double radius_distorted_px) const {
  return scale_px * OddPolynomial({k1, k2, 0.0}, radius_distorted_px / scale_px);
}

bool RadialDistortion::Distort(const Eigen::Vector2d& uv_undistorted_px, Eigen::Vector2d* uv_distorted_px) const {
  const Eigen::Vector2d d = uv_undistorted_px - center_px;
  const double radius = d.norm();
  if (radius == 0.0) {
    *uv_distorted_px = center_px;
    return true;
  }
  double rho = 0.0;
  const bool ok = InvertOddPolynomial({k1, k2, 0.0}, radius / scale_px, &rho);
  *uv_distorted_px = center_px + d * (rho * scale_px / radius);
  return ok;
}

double RadialDistortionScalePx(int width_px, int height_px) {
  return 0.5 * std::hypot(static_cast<double>(width_px), static_cast<double>(height_px));
}

RadialDistortion MakeRadialDistortion(int width_px, int height_px, const std::optional<Eigen::Vector2d>& center_px) {
  RadialDistortion distortion;
  distortion.center_px = center_px ? *center_px : Eigen::Vector2d(0.5 * (width_px - 1), 0.5 * (height_px - 1));
  distortion.scale_px = RadialDistortionScalePx(width_px, height_px);
  return distortion;
}

RadialDistortion RadialDistortionFromOpenCv(const OpenCvRadialCoefficients& opencv, double focal_px,
                                            const Eigen::Vector2d& center_px, double scale_px, double max_radius_px,
                                            bool fit_k2, double* max_error_px) {
  RadialDistortion distortion;
  distortion.center_px = center_px;
  distortion.scale_px = scale_px;
  const std::array<double, 3> a = {opencv.k1, opencv.k2, opencv.k3};
  const int columns = fit_k2 ? 2 : 1;
  Eigen::MatrixXd design(kConversionSamples, columns);
  Eigen::VectorXd target(kConversionSamples);
  for (int i = 0; i < kConversionSamples; ++i) {
    const double radius_d = max_radius_px * (i + 1) / kConversionSamples;
    double rho_u = 0.0;
    InvertOddPolynomial(a, radius_d / focal_px, &rho_u);
    const double r2 = (radius_d / scale_px) * (radius_d / scale_px);
    design(i, 0) = radius_d * r2;
    if (fit_k2) design(i, 1) = radius_d * r2 * r2;
    target(i) = rho_u * focal_px - radius_d;
  }
  const Eigen::VectorXd k = design.colPivHouseholderQr().solve(target);
  distortion.k1 = k(0);
  distortion.k2 = fit_k2 ? k(1) : 0.0;
  if (max_error_px) *max_error_px = (design * k - target).cwiseAbs().maxCoeff();
  return distortion;
}

OpenCvRadialCoefficients OpenCvFromRadialDistortion(const RadialDistortion& distortion, double focal_px,
                                                    double max_radius_px, bool fit_k2, double* max_error_px) {
  const int columns = fit_k2 ? 2 : 1;
  Eigen::MatrixXd design(kConversionSamples, columns);
  Eigen::VectorXd target(kConversionSamples);
  for (int i = 0; i < kConversionSamples; ++i) {
    const double radius_d = max_radius_px * (i + 1) / kConversionSamples;
    const double radius_u = distortion.UndistortRadiusPx(radius_d);
    const double rho2 = (radius_u / focal_px) * (radius_u / focal_px);
    design(i, 0) = radius_u * rho2;
    if (fit_k2) design(i, 1) = radius_u * rho2 * rho2;
    target(i) = radius_d - radius_u;
  }
  const Eigen::VectorXd k = design.colPivHouseholderQr().solve(target);
  OpenCvRadialCoefficients opencv;
  opencv.k1 = k(0);
  opencv.k2 = fit_k2 ? k(1) : 0.0;
  if (max_error_px) *max_error_px = (design * k - target).cwiseAbs().maxCoeff();
  return opencv;
}

bool PlumbLineOptions::Check(std::string* error) const {
  if (width_px <= 0 || height_px <= 0) {
    *error = "the image size must be positive";
    return false;
  }
  if (center_px && !center_px->allFinite()) {
    *error = "the centre of distortion must be finite";
    return false;
  }
  if (max_iterations < 0) {
    *error = "max_iterations must not be negative";
    return false;
  }
  if (!(poorly_determined_ratio > 0.0)) {
    *error = "poorly_determined_ratio must be positive";
    return false;
  }
  return true;
}

PlumbLineSummary EstimateRadialDistortion(const std::vector<PlumbLine>& lines, const PlumbLineOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  PlumbLineSummary summary;
  std::string error;
  if (!options.Check(&error))
    return FailedSummary(summary, "bad options: " + error, start, SolverTermination::kInvalidInput);
  summary.distortion = MakeRadialDistortion(options.width_px, options.height_px, options.center_px);
  const double scale = summary.distortion.scale_px;
  summary.line_rms_px.assign(lines.size(), 0.0);

  Problem problem;
  ProblemLayout layout;
  if (!BuildProblem(lines, summary.distortion, &problem, &layout, &error))
    return FailedSummary(summary, error, start, SolverTermination::kInvalidInput);
  summary.num_constraints = layout.num_constraints;
  if (layout.num_constraints < 2)
    return FailedSummary(summary,
                         "too few points: " + std::to_string(layout.num_constraints) +
                             " independent constraint(s), k1 needs at least 2 (each polyline of n points gives n - "
                             "2, or n - 1 in a family of parallel lines, less 2 per family)",
                         start, SolverTermination::kInvalidInput);

  // Start: k = 0 with the vanishing points refined for straight lines; that fit is also the
  // "before" straightness.
  State state;
  for (int slot = 0; slot < problem.num_families; ++slot) {
    state.vanishing_points.push_back(AlgebraicVanishingPoint(problem, slot, 0.0, 0.0));
  }
  ActiveSet vanishing_only;
  vanishing_only.k1 = false;
  vanishing_only.num_families = problem.num_families;
  summary.iterations += Minimise(problem, vanishing_only, options.max_iterations, &state).accepted_steps;
  summary.initial_rms_px = scale * Rms(Residuals(problem, state, false), layout.num_points);

  ActiveSet active;
  if (!ChooseCoefficients(problem, state, options, layout.num_constraints, &active, &summary.warnings, &error))
    return FailedSummary(summary, error, start);
  summary.k2_estimated = active.k2;

  summary.initial_cost = scale * scale * Residuals(problem, state).squaredNorm();
  const LmResult fit = Minimise(problem, active, options.max_iterations, &state);
  summary.iterations += fit.accepted_steps;
  const Eigen::VectorXd residuals = Residuals(problem, state);
  const Eigen::VectorXd distances = Residuals(problem, state, false);
  if (!residuals.allFinite())
    return FailedSummary(summary, "the fit diverged (a vanishing point coincides with a polyline's centroid); k = 0",
                         start);
  summary.final_cost = scale * scale * residuals.squaredNorm();

  EstimateCoefficientStd(problem, state, active, layout.num_constraints, residuals, scale, &summary);
  summary.distortion.k1 = state.k1;
  summary.distortion.k2 = state.k2;
  ReportLines(problem, layout, state, distances, summary.distortion, &summary);

  if (summary.k1_std > options.poorly_determined_ratio * std::abs(state.k1)) {
    summary.warnings.push_back(
        Format("k1 is poorly determined: %.4g +- %.2g; add lines far from the centre", state.k1, summary.k1_std));
  }
  if (active.k2 && summary.k2_std > options.poorly_determined_ratio * std::abs(state.k2)) {
    summary.warnings.push_back(
        Format("k2 is poorly determined: %.4g +- %.2g; consider k1 alone", state.k2, summary.k2_std));
  }
  summary.termination = TerminationOf(fit);
  summary.message =
      active.k2 ? Format("k1 = %.5g, k2 = %.5g, straightness RMS %.3g px", state.k1, state.k2, summary.final_rms_px)
                : Format("k1 = %.5g, straightness RMS %.3g px", state.k1, summary.final_rms_px);
  summary.time_ms = internal::MsSince(start);
  return summary;
}

}  // namespace facet
