#include "core/solve/pin_resection.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include <Eigen/Dense>

#include "core/estimators/calibrate_dlt.h"
#include "core/estimators/projective_upgrade.h"
#include "core/geometry/camera_checks.h"
#include "core/optim/levenberg_marquardt.h"

namespace facet {
namespace {

// Pixels or points spread along one line only (second singular value over the first): no
// camera follows from them.
constexpr double kMinSpreadRatio = 1e-3;
// The depth start's Gauss-Newton on the pairwise distances.
constexpr int kDepthIterations = 50;

std::string Format(const char* format, double a) {
  char buffer[256];
  std::snprintf(buffer, sizeof(buffer), format, a);
  return buffer;
}

Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

Eigen::Matrix3d SmallRotation(const Eigen::Vector3d& w) {
  const double angle = w.norm();
  if (angle == 0.0) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
}

template <int Dim>
Eigen::VectorXd SingularValuesOfCentred(const std::vector<Eigen::Matrix<double, Dim, 1>>& v) {
  if (v.size() < 2) return Eigen::VectorXd::Zero(Dim);
  Eigen::Matrix<double, Dim, 1> mean = Eigen::Matrix<double, Dim, 1>::Zero();
  for (const auto& p : v) mean += p;
  mean /= static_cast<double>(v.size());
  Eigen::MatrixXd a(v.size(), Dim);
  for (size_t i = 0; i < v.size(); ++i) a.row(i) = (v[i] - mean).transpose();
  return Eigen::JacobiSVD<Eigen::MatrixXd>(a).singularValues();
}

std::vector<double> Residuals(const Camera& camera, const PinResectionInput& input, double* rms) {
  std::vector<double> out;
  double sum = 0.0;
  for (size_t i = 0; i < input.points.size(); ++i) {
    const double e = (camera.Project(input.points[i]) - input.pixels[i]).norm();
    out.push_back(e);
    sum += e * e;
  }
  *rms = out.empty() ? 0.0 : std::sqrt(sum / out.size());
  return out;
}

// Levenberg-Marquardt on the pixels over (f when free), the rotation (left-multiplied) and t;
// the principal point held. Returns false when a point is behind the camera at the start.
bool Refine(const PinResectionInput& input, bool focal_free, Camera* camera) {
  const int n = static_cast<int>(input.points.size());
  const int num_params = (focal_free ? 1 : 0) + 6;
  Eigen::MatrixXd jacobian(2 * n, num_params);
  Eigen::VectorXd residual(2 * n);
  auto evaluate = [&](const Camera& c, Eigen::VectorXd* r, Eigen::MatrixXd* j) {
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d rotated = c.cam_from_world_rotation * input.points[i];
      const Eigen::Vector3d p = rotated + c.cam_from_world_translation;
      if (!(p.z() > 0.0)) return false;
      const double x = p.x() / p.z(), y = p.y() / p.z();
      r->segment<2>(2 * i) = c.focal_px * Eigen::Vector2d(x, y) + c.principal_point_px - input.pixels[i];
      if (j == nullptr) continue;
      Eigen::Matrix<double, 2, 3> d_p;
      d_p << 1.0 / p.z(), 0.0, -x / p.z(), 0.0, 1.0 / p.z(), -y / p.z();
      d_p *= c.focal_px;
      int col = 0;
      if (focal_free) j->block<2, 1>(2 * i, col++) = Eigen::Vector2d(x, y);
      j->block<2, 3>(2 * i, col) = -d_p * Skew(rotated);
      j->block<2, 3>(2 * i, col + 3) = d_p;
    }
    return true;
  };
  if (!evaluate(*camera, &residual, nullptr)) return false;
  Camera trial = *camera;
  Eigen::VectorXd trial_residual(2 * n);
  auto apply = [&](const Eigen::VectorXd& delta, Camera* out) {
    *out = *camera;
    int col = 0;
    if (focal_free) out->focal_px += delta(col++);
    out->cam_from_world_rotation = SmallRotation(delta.segment<3>(col)) * camera->cam_from_world_rotation;
    out->cam_from_world_translation += delta.segment<3>(col + 3);
  };
  Eigen::MatrixXd normal;
  Eigen::VectorXd gradient;
  auto linearize = [&]() {
    evaluate(*camera, &residual, &jacobian);
    normal = jacobian.transpose() * jacobian;
    gradient = jacobian.transpose() * residual;
  };
  auto step = [&](double lambda, double* cost, double* step_squared_norm) {
    Eigen::MatrixXd damped = normal;
    damped.diagonal() += lambda * normal.diagonal().cwiseMax(1e-12 * normal.diagonal().maxCoeff());
    const Eigen::VectorXd delta = damped.ldlt().solve(-gradient);
    if (!delta.allFinite()) return false;
    apply(delta, &trial);
    *step_squared_norm = delta.squaredNorm();
    *cost = evaluate(trial, &trial_residual, nullptr) && trial.focal_px > 0.0 ? 0.5 * trial_residual.squaredNorm()
                                                                              : std::numeric_limits<double>::infinity();
    return true;
  };
  auto accept = [&]() { *camera = trial; };
  LmOptions options = TenfoldLmOptions(input.max_iterations);
  options.relative_decrease_tolerance = 1e-16;
  MinimizeLevenbergMarquardt(0.5 * residual.squaredNorm(), options, linearize, step, accept);
  return true;
}

// Depths d_i > 0 along the unit rays u_i with |d_i u_i - d_j u_j| = |X_i - X_j| for every pair,
// least squares by Gauss-Newton from equal depths; false when it does not converge to
// positive depths.
bool DepthsKeepingDistances(const std::vector<Eigen::Vector3d>& rays, const std::vector<Eigen::Vector3d>& points,
                            std::vector<double>* depths) {
  const int n = static_cast<int>(rays.size());
  // Equal depths: the points' spread over the rays' angular spread.
  double point_spread = 0.0, ray_spread = 0.0;
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j) {
      point_spread += (points[i] - points[j]).norm();
      ray_spread += (rays[i] - rays[j]).norm();
    }
  if (!(ray_spread > 0.0) || !(point_spread > 0.0)) return false;
  Eigen::VectorXd d = Eigen::VectorXd::Constant(n, point_spread / ray_spread);
  const int pairs = n * (n - 1) / 2;
  Eigen::MatrixXd j(pairs, n);
  Eigen::VectorXd r(pairs);
  for (int iteration = 0; iteration < kDepthIterations; ++iteration) {
    j.setZero();
    int row = 0;
    for (int a = 0; a < n; ++a)
      for (int b = a + 1; b < n; ++b, ++row) {
        // Squared distances: d_a^2 + d_b^2 - 2 d_a d_b cos - |X_a - X_b|^2, scaled by the mean depth.
        const double c = rays[a].dot(rays[b]);
        r(row) = d(a) * d(a) + d(b) * d(b) - 2.0 * d(a) * d(b) * c - (points[a] - points[b]).squaredNorm();
        j(row, a) = 2.0 * d(a) - 2.0 * d(b) * c;
        j(row, b) = 2.0 * d(b) - 2.0 * d(a) * c;
      }
    const Eigen::VectorXd delta = j.colPivHouseholderQr().solve(-r);
    if (!delta.allFinite()) return false;
    d += delta;
    if (delta.norm() <= 1e-14 * d.norm()) break;
  }
  if (!(d.minCoeff() > 0.0)) return false;
  depths->assign(d.data(), d.data() + n);
  return true;
}

PinResectionResult Finish(const PinResectionInput& input, const Camera& camera, const std::string& what) {
  PinResectionResult result;
  result.camera = camera;
  result.camera.width_px = input.width_px;
  result.camera.height_px = input.height_px;
  const std::string refused = WhyResectedCameraRefused(result.camera, input.points, input.width_px, input.height_px);
  if (!refused.empty()) {
    result.message = what + " refused: " + refused;
    return result;
  }
  result.residuals_px = Residuals(result.camera, input, &result.rms_px);
  result.ok = true;
  result.message = what + " from " + std::to_string(input.points.size()) +
                   " pins, f = " + Format("%.1f px", result.camera.focal_px) + ", RMS " +
                   Format("%.3f px", result.rms_px);
  return result;
}

}  // namespace

double PointsThicknessRatio(const std::vector<Eigen::Vector3d>& points) {
  if (points.size() < 3) return 0.0;
  const Eigen::VectorXd s = SingularValuesOfCentred<3>(points);
  return s(0) > 0.0 ? s(2) / s(0) : 0.0;
}

std::string WhyPinsNotSpread(const PinResectionInput& input) {
  const size_t n = input.points.size();
  if (n < 4 || input.pixels.size() != n) return std::to_string(n) + " pins on placed vertices; resection needs 4";
  const Eigen::VectorXd px = SingularValuesOfCentred<2>(input.pixels);
  if (!(px(1) > kMinSpreadRatio * px(0))) return "the pins lie on one line in the photo";
  const Eigen::VectorXd xyz = SingularValuesOfCentred<3>(input.points);
  if (!(xyz(1) > kMinSpreadRatio * xyz(0))) return "the pinned vertices lie on one line in the model";
  return "";
}

std::string WhyResectedCameraRefused(const Camera& camera, const std::vector<Eigen::Vector3d>& points, int width_px,
                                     int height_px) {
  const std::string not_a_camera = WhyNotACamera(camera.focal_px, camera.principal_point_px, width_px, height_px);
  if (!not_a_camera.empty()) return not_a_camera;
  if (!camera.cam_from_world_rotation.allFinite() || !camera.cam_from_world_translation.allFinite())
    return "the pose is not finite";
  for (const Eigen::Vector3d& p : points) {
    if (!(camera.CamFromWorld(p).z() > 0.0)) return "a pinned vertex lies behind the camera";
  }
  return "";
}

PinResectionResult ResectNearlyPlanar(const PinResectionInput& input) {
  PinResectionResult result;
  if (const std::string why = WhyPinsNotSpread(input); !why.empty()) {
    result.message = why;
    return result;
  }
  // The points on their best plane: the exact-plane path of the DLT calibration applies.
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : input.points) mean += p;
  mean /= static_cast<double>(input.points.size());
  Eigen::MatrixXd a(input.points.size(), 3);
  for (size_t i = 0; i < input.points.size(); ++i) a.row(i) = (input.points[i] - mean).transpose();
  const Eigen::Vector3d normal = Eigen::JacobiSVD<Eigen::MatrixXd>(a, Eigen::ComputeFullV).matrixV().col(2);
  std::vector<PointCorrespondence> flat;
  for (size_t i = 0; i < input.points.size(); ++i) {
    const Eigen::Vector3d& p = input.points[i];
    flat.push_back({p - normal * normal.dot(p - mean), input.pixels[i]});
  }
  DltCalibrationOptions options;
  options.width_px = input.width_px;
  options.height_px = input.height_px;
  options.principal_point_mode = PrincipalPointMode::kFixed;
  options.fixed_principal_point_px = input.principal_point_px;
  options.max_iterations = input.max_iterations;
  const DltCalibrationSummary linear = CalibrateFromPoints(flat, options);
  if (!linear.IsUsable()) {
    result.message = "the pins' common plane gave no camera (" + linear.message + ")";
    return result;
  }
  Camera camera = linear.camera;
  camera.k1 = camera.k2 = 0.0;
  bool refined = Refine(input, true, &camera);
  double best_rms = 0.0;
  if (refined) Residuals(camera, input, &best_rms);
  // The projected plane's focal length can start the refinement in the wrong basin (4 points,
  // 7 unknowns): starts from the pose at a sweep of focal lengths, f free, keep the best fit.
  const double diagonal = std::hypot(static_cast<double>(input.width_px), static_cast<double>(input.height_px));
  for (const double factor : {0.5, 0.7, 1.0, 1.4, 2.0, 3.0, 5.0}) {
    PinResectionResult pose = ResectWithKnownFocal(input, factor * diagonal);
    if (!pose.ok) continue;
    Camera start = pose.camera;
    if (!Refine(input, true, &start)) continue;
    double rms = 0.0;
    Residuals(start, input, &rms);
    if (!refined || rms < best_rms) {
      camera = start;
      best_rms = rms;
      refined = true;
    }
  }
  if (!refined) {
    result.message = "a pinned vertex lies behind the plane's camera";
    return result;
  }
  return Finish(input, camera, "resection (nearly planar)");
}

PinResectionResult ResectWithKnownFocal(const PinResectionInput& input, double focal_px) {
  PinResectionResult result;
  if (const std::string why = WhyPinsNotSpread(input); !why.empty()) {
    result.message = why;
    return result;
  }
  if (!(focal_px > 0.0) || !std::isfinite(focal_px)) {
    result.message = "no known focal length";
    return result;
  }
  std::vector<Eigen::Vector3d> rays;
  for (const Eigen::Vector2d& uv : input.pixels)
    rays.push_back(Eigen::Vector3d((uv.x() - input.principal_point_px.x()) / focal_px,
                                   (uv.y() - input.principal_point_px.y()) / focal_px, 1.0)
                       .normalized());
  std::vector<double> depths;
  if (!DepthsKeepingDistances(rays, input.points, &depths)) {
    result.message = "no depths along the pins' rays fit the model's distances";
    return result;
  }
  std::vector<Eigen::Vector3d> in_camera;
  for (size_t i = 0; i < rays.size(); ++i) in_camera.push_back(depths[i] * rays[i]);
  Similarity3d camera_from_world;
  if (!AlignSimilarity(input.points, in_camera, &camera_from_world)) {
    result.message = "the pins' rays could not be aligned with the model";
    return result;
  }
  Camera camera;
  camera.focal_px = focal_px;
  camera.principal_point_px = input.principal_point_px;
  camera.cam_from_world_rotation = camera_from_world.rotation;
  // The similarity's scale is ~1 (the depths keep the model's distances); the rigid pose
  // keeps its rotation and puts the points' centroid where the rays' points are.
  Eigen::Vector3d world_mean = Eigen::Vector3d::Zero(), camera_mean = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < rays.size(); ++i) {
    world_mean += input.points[i];
    camera_mean += in_camera[i];
  }
  camera.cam_from_world_translation = (camera_mean - camera_from_world.rotation * world_mean) / rays.size();
  if (!Refine(input, false, &camera)) {
    result.message = "a pinned vertex lies behind the camera of the known focal length";
    return result;
  }
  return Finish(input, camera, "pose with the known focal length");
}

}  // namespace facet
