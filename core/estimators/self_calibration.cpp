#include "core/estimators/self_calibration.h"

#include <algorithm>
#include <cassert>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <random>

#include <Eigen/Dense>

#include "core/estimators/projective_bundle_adjustment.h"
#include "core/estimators/two_view.h"
#include "core/geometry/cross_product_matrix.h"
#include "core/optim/levenberg_marquardt.h"
#include "core/optim/schur_step.h"
#include "core/optim/solver_summary.h"
#include "core/util/eigen_decompositions.h"
#include "core/util/format.h"
#include "core/util/timer.h"

namespace facet {
namespace {

using Clock = std::chrono::steady_clock;

// A view is resected from at least this many triangulated tracks (DLT needs 6; a margin for
// the outliers the iterations drop).
constexpr int kMinResectionTracks = 8;
constexpr int kResectionRounds = 5;  // refits on the inliers until the set is stable
constexpr int kMinTracks = 8;
constexpr int kMinResectionSamples = 50;
constexpr int kMaxResectionSamples = 2000;
// Pairs (of those sharing the most tracks) whose F is estimated to choose the initial pair.
constexpr int kMaxInitialPairCandidates = 20;
// Starts tried when one leaves views out (each from views no earlier attempt registered).
constexpr int kMaxInitialPairAttempts = 4;

using internal::FailedSummary;
using internal::MsSince;
using internal::Skew;
Eigen::Vector2d ImageCentre(const SelfCalibrationView& v) { return {(v.width_px - 1) / 2.0, (v.height_px - 1) / 2.0}; }

// Normalising intrinsics of a view: the prior K, else f = w + h at the image centre.
Eigen::Matrix3d NormalisingK(const SelfCalibrationView& v) {
  Eigen::Matrix3d k = Eigen::Matrix3d::Identity();
  k(0, 0) = k(1, 1) = v.focal_prior_px > 0 ? v.focal_prior_px : static_cast<double>(v.width_px + v.height_px);
  k.block<2, 1>(0, 2) = ImageCentre(v);
  return k;
}

// The reconstruction in normalised image coordinates (x = N^-1 uv).
struct Projective {
  std::vector<Eigen::Matrix3d> n;               // per view
  std::vector<Matrix34d> P;                     // per view
  std::vector<bool> registered;                 // per view
  std::vector<std::vector<Eigen::Vector2d>> x;  // per track, per observation
  std::vector<std::vector<bool>> ok;            // per track, per observation
  std::vector<Eigen::Vector4d> X;               // per track
  std::vector<bool> has_point;                  // per track
};

double PixelError(const Projective& p, const Track& track, int k, const Eigen::Vector4d& X) {
  const int v = track[k].view;
  const Eigen::Vector3d y = p.n[v] * p.P[v] * X;
  if (!(std::abs(y.z()) > 0)) return std::numeric_limits<double>::infinity();
  return (y.head<2>() / y.z() - track[k].uv_px).norm();
}

// Triangulates track t from its registered, accepted observations; flags observations beyond
// the threshold and drops the point when fewer than 2 remain.
void TriangulateTrack(const std::vector<Track>& tracks, int t, double threshold_px, Projective* p) {
  const Track& track = tracks[t];
  for (int round = 0; round < 2; ++round) {
    std::vector<Matrix34d> cams;
    std::vector<Eigen::Vector3d> xh;
    std::vector<Eigen::Vector2d> xs;
    for (size_t k = 0; k < track.size(); ++k) {
      if (!p->ok[t][k] || !p->registered[track[k].view]) continue;
      cams.push_back(p->P[track[k].view]);
      xh.push_back(p->x[t][k].homogeneous());
      xs.push_back(p->x[t][k]);
    }
    p->has_point[t] = cams.size() >= 2;
    if (!p->has_point[t]) return;
    p->X[t] = RefineTriangulatedPoint(cams, xs, TriangulateLinear(cams, xh), 10);
    bool dropped = false;
    for (size_t k = 0; k < track.size(); ++k) {
      if (!p->ok[t][k] || !p->registered[track[k].view]) continue;
      if (!(PixelError(*p, track, static_cast<int>(k), p->X[t]) < threshold_px)) {
        p->ok[t][k] = false;
        dropped = true;
      }
    }
    if (!dropped) return;
  }
  int remaining = 0;
  for (size_t k = 0; k < track.size(); ++k) remaining += p->ok[t][k] && p->registered[track[k].view];
  p->has_point[t] = remaining >= 2;
}

// DLT camera from homogeneous points Y (already conditioned) and normalised image points x,
// over the listed indices: the right singular vector of the smallest singular value.
Matrix34d DltCamera(const std::vector<Eigen::Vector4d>& Y, const std::vector<Eigen::Vector2d>& x,
                    const std::vector<int>& use) {
  Eigen::MatrixXd a(2 * use.size(), 12);
  int row = 0;
  for (int i : use) {
    a.row(row++) << Eigen::RowVector4d::Zero(), -Y[i].transpose(), x[i].y() * Y[i].transpose();
    a.row(row++) << Y[i].transpose(), Eigen::RowVector4d::Zero(), -x[i].x() * Y[i].transpose();
  }
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeFullV);
  const Eigen::VectorXd sol = svd.matrixV().col(11);
  Matrix34d cam;
  for (int r = 0; r < 3; ++r) cam.row(r) = sol.segment<4>(4 * r).transpose();
  return cam;
}

// Resection of view v from the triangulated tracks it sees: MSAC over minimal 6-point DLT
// samples, then DLT on the inliers, re-classified until stable. Both halves matter: the
// points are whitened (their 4x4 second moment becomes the identity) because in the raw
// projective frame a point's weight in the algebraic error is arbitrary, so a few wrong tracks
// with large weights pulled the whole DLT tens of px off (Middlebury templeSR0006: 6 wrong of
// 64, median error 78 px unconditioned, 3.7 px whitened); and the sampling keeps the wrong
// tracks out of the fit altogether. False with fewer than kMinResectionTracks inliers.
bool Resect(const std::vector<Track>& tracks, int v, double threshold_px, unsigned seed, Projective* p) {
  std::vector<std::pair<int, int>> obs;  // (track, observation)
  for (size_t t = 0; t < tracks.size(); ++t)
    for (size_t k = 0; k < tracks[t].size(); ++k)
      if (tracks[t][k].view == v && p->ok[t][k] && p->has_point[t])
        obs.emplace_back(static_cast<int>(t), static_cast<int>(k));
  const int count = static_cast<int>(obs.size());
  if (count < kMinResectionTracks) return false;
  Eigen::Matrix4d moment = Eigen::Matrix4d::Zero();
  for (const auto& [t, k] : obs) moment += p->X[t] * p->X[t].transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> eig(moment / count);
  if (!(eig.eigenvalues()(0) > 1e-14 * eig.eigenvalues()(3))) return false;
  const Eigen::Matrix4d whiten =
      eig.eigenvalues().cwiseSqrt().cwiseInverse().asDiagonal() * eig.eigenvectors().transpose();
  std::vector<Eigen::Vector4d> Y(count);
  std::vector<Eigen::Vector2d> x(count);
  for (int i = 0; i < count; ++i) {
    Y[i] = (whiten * p->X[obs[i].first]).normalized();
    x[i] = p->x[obs[i].first][obs[i].second];
  }
  const double th_sq = threshold_px * threshold_px;
  // Pixel errors of a conditioned camera; MSAC cost.
  auto errors_of = [&](const Matrix34d& cam, std::vector<double>* e_sq) {
    e_sq->resize(count);
    double cost = 0.0;
    for (int i = 0; i < count; ++i) {
      const Eigen::Vector3d y = p->n[v] * cam * Y[i];
      double e = std::numeric_limits<double>::infinity();
      if (std::abs(y.z()) > 0) e = (y.head<2>() / y.z() - tracks[obs[i].first][obs[i].second].uv_px).squaredNorm();
      (*e_sq)[i] = std::isfinite(e) ? e : std::numeric_limits<double>::max();
      cost += std::min((*e_sq)[i], th_sq);
    }
    return cost;
  };
  std::mt19937 rng(seed + 7919u * static_cast<unsigned>(v));
  Matrix34d best = Matrix34d::Zero();
  double best_cost = std::numeric_limits<double>::infinity();
  std::vector<double> e_sq;
  std::vector<int> sample;
  int max_iterations = kMaxResectionSamples;
  for (int it = 0; it < max_iterations; ++it) {
    sample.clear();
    while (sample.size() < 6) {
      const int i = static_cast<int>(rng() % count);
      if (std::find(sample.begin(), sample.end(), i) == sample.end()) sample.push_back(i);
    }
    const Matrix34d cam = DltCamera(Y, x, sample);
    const double cost = errors_of(cam, &e_sq);
    if (cost < best_cost) {
      best_cost = cost;
      best = cam;
      // Adaptive stop: 99.9 % confidence of having drawn one all-inlier sample.
      const double inlier_ratio =
          static_cast<double>(std::count_if(e_sq.begin(), e_sq.end(), [&](double e) { return e < th_sq; })) / count;
      const double all_inlier = std::min(std::pow(inlier_ratio, 6), 1.0 - 1e-12);
      if (all_inlier > 1e-9) {
        const double needed = std::ceil(std::log(1e-3) / std::log1p(-all_inlier));
        max_iterations = std::min(max_iterations, std::max(kMinResectionSamples, static_cast<int>(needed)));
      }
    }
  }
  errors_of(best, &e_sq);
  std::vector<int> use;
  for (int round = 0; round < kResectionRounds; ++round) {
    std::vector<int> next;
    for (int i = 0; i < count; ++i)
      if (e_sq[i] < th_sq) next.push_back(i);
    if (round > 0 && next == use) break;
    use = next;
    if (static_cast<int>(use.size()) < kMinResectionTracks) return false;
    best = DltCamera(Y, x, use);
    errors_of(best, &e_sq);
  }
  p->P[v] = best * whiten;
  for (int i = 0; i < count; ++i)
    if (!(e_sq[i] < th_sq)) p->ok[obs[i].first][obs[i].second] = false;
  return static_cast<int>(use.size()) >= kMinResectionTracks;
}

struct InitialPair {
  int a = -1, b = -1;
  FundamentalSummary f;
  std::vector<std::pair<int, std::pair<int, int>>> obs;  // track, (observation in a, in b)
};

// Projective bundle adjustment of the registered views over the accepted observations.
ProjectiveBundleSummary AdjustProjective(const std::vector<Track>& tracks, int max_iterations, Projective* p) {
  std::vector<ProjectiveBundleObservation> observations;
  for (size_t t = 0; t < tracks.size(); ++t) {
    if (!p->has_point[t]) continue;
    for (size_t k = 0; k < tracks[t].size(); ++k)
      if (p->ok[t][k] && p->registered[tracks[t][k].view])
        observations.push_back({tracks[t][k].view, static_cast<int>(t), tracks[t][k].uv_px});
  }
  ProjectiveBundleOptions pba;
  pba.max_iterations = max_iterations;
  return ProjectiveBundleAdjust(observations, p->n, pba, &p->P, &p->X);
}

// Step 1 from one initial pair: canonical cameras from its F, triangulation, then every
// further view by resection, the one seeing the most reconstructed points first, with a
// projective bundle adjustment each time options.projective_bundle_every_views more views
// have joined (resection errors compound along a chain of views otherwise). False when F
// gives no canonical cameras.
bool RegisterIncrementally(const std::vector<Track>& tracks, const InitialPair& pair,
                           const SelfCalibrationOptions& options, Projective* p, std::vector<std::string>* warnings) {
  const int n = static_cast<int>(p->P.size());
  const int num_tracks = static_cast<int>(tracks.size());
  for (size_t i = 0; i < pair.obs.size(); ++i)
    if (!pair.f.inliers[i]) {
      p->ok[pair.obs[i].first][pair.obs[i].second.first] = false;
      p->ok[pair.obs[i].first][pair.obs[i].second.second] = false;
    }
  const Eigen::Matrix3d f_normalised = p->n[pair.b].transpose() * pair.f.F * p->n[pair.a];
  if (!CanonicalCamerasFromFundamental(f_normalised, &p->P[pair.a], &p->P[pair.b])) return false;
  p->registered[pair.a] = p->registered[pair.b] = true;
  for (int t = 0; t < num_tracks; ++t) TriangulateTrack(tracks, t, options.inlier_threshold_px, p);
  int since_adjustment = 0;
  while (true) {
    int best = -1, best_count = 0;
    for (int v = 0; v < n; ++v) {
      if (p->registered[v]) continue;
      int count = 0;
      for (int t = 0; t < num_tracks; ++t) {
        if (!p->has_point[t]) continue;
        for (size_t k = 0; k < tracks[t].size(); ++k) count += tracks[t][k].view == v && p->ok[t][k];
      }
      if (count > best_count) {
        best_count = count;
        best = v;
      }
    }
    if (best < 0 || best_count < kMinResectionTracks) break;
    if (!Resect(tracks, best, options.inlier_threshold_px, options.seed, p)) {
      warnings->push_back("view " + std::to_string(best) + " could not be resected (" + std::to_string(best_count) +
                          " triangulated tracks, too few consistent ones)");
      // Marked so that it is not tried again; it stays unregistered.
      for (int t = 0; t < num_tracks; ++t)
        for (size_t k = 0; k < tracks[t].size(); ++k)
          if (tracks[t][k].view == best) p->ok[t][k] = false;
      continue;
    }
    p->registered[best] = true;
    for (int t = 0; t < num_tracks; ++t) TriangulateTrack(tracks, t, options.inlier_threshold_px, p);
    if (options.projective_bundle_adjust && options.projective_bundle_every_views > 0 &&
        ++since_adjustment >= options.projective_bundle_every_views) {
      since_adjustment = 0;
      const ProjectiveBundleSummary result = AdjustProjective(tracks, options.max_projective_bundle_iterations, p);
      if (!result.IsUsable()) warnings->push_back(result.message);
      for (int t = 0; t < num_tracks; ++t) TriangulateTrack(tracks, t, options.inlier_threshold_px, p);
    }
  }
  return true;
}

// Coefficients of w*_ab = (P Q P^T)_ab over the 10 upper-triangular entries of Q.
Eigen::Matrix<double, 1, 10> QuadricRow(const Matrix34d& P, int a, int b) {
  Eigen::Matrix<double, 1, 10> row;
  int u = 0;
  for (int c = 0; c < 4; ++c)
    for (int d = c; d < 4; ++d) row(u++) = c == d ? P(a, c) * P(b, c) : P(a, c) * P(b, d) + P(a, d) * P(b, c);
  return row;
}

Eigen::Matrix4d QuadricFromVector(const Eigen::Matrix<double, 10, 1>& q) {
  Eigen::Matrix4d m;
  int u = 0;
  for (int c = 0; c < 4; ++c)
    for (int d = c; d < 4; ++d) m(c, d) = m(d, c) = q(u++);
  return m;
}

int DepthVotes(const std::vector<Matrix34d>& cams, const std::vector<bool>& registered,
               const std::vector<Eigen::Vector4d>& X, const std::vector<bool>& has_point) {
  int votes = 0;
  for (size_t v = 0; v < cams.size(); ++v) {
    if (!registered[v]) continue;
    const double det_sign = cams[v].leftCols<3>().determinant() > 0 ? 1.0 : -1.0;
    for (size_t t = 0; t < X.size(); ++t) {
      if (!has_point[t]) continue;
      const double depth = det_sign * cams[v].row(2).dot(X[t]) * X[t](3);
      votes += depth > 0 ? 1 : (depth < 0 ? -1 : 0);
    }
  }
  return votes;
}

// Moves the frame so that camera `ref` is at the origin with R = I and the points' RMS
// distance from their centroid is 1.
void NormaliseGauge(int ref, std::vector<Camera>* cameras, std::vector<Eigen::Vector3d>* points,
                    const std::vector<bool>& use_point) {
  const Eigen::Matrix3d r0 = (*cameras)[ref].cam_from_world_rotation;
  const Eigen::Vector3d t0 = (*cameras)[ref].cam_from_world_translation;
  // New world = camera ref's frame, then scaled by s.
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  int count = 0;
  for (size_t j = 0; j < points->size(); ++j)
    if (use_point[j]) {
      centroid += r0 * (*points)[j] + t0;
      ++count;
    }
  if (count == 0) return;
  centroid /= count;
  double sum = 0.0;
  for (size_t j = 0; j < points->size(); ++j)
    if (use_point[j]) sum += (r0 * (*points)[j] + t0 - centroid).squaredNorm();
  const double s = sum > 0 ? 1.0 / std::sqrt(sum / count) : 1.0;
  for (auto& x : *points) x = s * (r0 * x + t0);
  for (auto& c : *cameras) {
    // p_cam = R x + t with x = R0^T (y / s - t0): R' = R R0^T, t' = s (t - R R0^T t0).
    const Eigen::Matrix3d r = c.cam_from_world_rotation * r0.transpose();
    c.cam_from_world_translation = s * (c.cam_from_world_translation - r * t0);
    c.cam_from_world_rotation = r;
  }
}

}  // namespace

bool SelfCalibrationOptions::Check(std::string* error) const {
  if (!(skew_weight >= 0 && aspect_weight >= 0 && principal_point_weight >= 0 && focal_weight >= 0 &&
        prior_focal_weight >= 0)) {
    *error = "the quadric weights must not be negative";
    return false;
  }
  if (!(inlier_threshold_px > 0)) {
    *error = "inlier_threshold_px must be positive";
    return false;
  }
  if (!(principal_point_prior_std >= 0)) {
    *error = "principal_point_prior_std must not be negative";
    return false;
  }
  if (projective_bundle_every_views < 0 || max_projective_bundle_iterations < 0) {
    *error = "projective_bundle_every_views and max_projective_bundle_iterations must not be negative";
    return false;
  }
  if (quadric_reweighting_rounds < 1 || max_bundle_iterations < 0 || bundle_rounds < 1) {
    *error = "quadric_reweighting_rounds and bundle_rounds must be positive, max_bundle_iterations not negative";
    return false;
  }
  return true;
}

bool BundleAdjustmentOptions::Check(std::string* error) const {
  if (max_iterations < 0) {
    *error = "max_iterations must not be negative";
    return false;
  }
  if (!(principal_point_prior_std_px >= 0) || !(observation_std_px > 0)) {
    *error = "principal_point_prior_std_px must not be negative and observation_std_px must be positive";
    return false;
  }
  return true;
}

namespace {

// Where the parameters of the metric bundle adjustment sit in the camera vector: 6 per view
// (rotation increment, translation), then the focal lengths (one shared or one per view), then
// the principal points if refined (likewise).
struct BundleLayout {
  int num_views = 0;
  bool shared = true;
  bool refine_principal_point = false;
  int num_focal = 0;
  int num_principal_point = 0;
  int num_camera_parameters = 0;

  BundleLayout(int n, const BundleAdjustmentOptions& options)
      : num_views(n), shared(options.shared_focal_length), refine_principal_point(options.refine_principal_point) {
    num_focal = shared ? 1 : n;
    num_principal_point = refine_principal_point ? (shared ? 2 : 2 * n) : 0;
    num_camera_parameters = 6 * n + num_focal + num_principal_point;
  }
  int FocalIndex(int v) const { return 6 * num_views + (shared ? 0 : v); }
  int PrincipalPointIndex(int v) const { return 6 * num_views + num_focal + (shared ? 0 : 2 * v); }
};

// The principal-point prior, in the units of the pixel residuals: weight
// (observation_std / prior_std)^2 on the squared distance from the image centre.
struct PrincipalPointPrior {
  bool active = false;
  double weight = 0.0;
  std::vector<Eigen::Vector2d> centre_px;  // per camera
  int num_residuals = 0;
};

PrincipalPointPrior MakePrincipalPointPrior(const BundleAdjustmentOptions& options, const BundleLayout& layout,
                                            const std::vector<Camera>& cams) {
  PrincipalPointPrior prior;
  prior.active = options.refine_principal_point && options.principal_point_prior_std_px > 0;
  prior.weight = prior.active ? std::pow(options.observation_std_px / options.principal_point_prior_std_px, 2) : 0.0;
  for (const auto& c : cams) prior.centre_px.emplace_back((c.width_px - 1) / 2.0, (c.height_px - 1) / 2.0);
  prior.num_residuals = prior.active ? layout.num_principal_point : 0;
  return prior;
}

double ReprojectionCost(const std::vector<BundleObservation>& observations, const std::vector<Camera>& cs,
                        const std::vector<Eigen::Vector3d>& ps) {
  double cost = 0.0;
  for (const auto& o : observations) {
    const double e = (cs[o.view].Project(ps[o.point]) - o.uv_px).squaredNorm();
    cost += std::isfinite(e) ? e : 1e300;
  }
  return cost;
}

double BundleCost(const std::vector<BundleObservation>& observations, const BundleLayout& layout,
                  const PrincipalPointPrior& prior, const std::vector<Camera>& cs,
                  const std::vector<Eigen::Vector3d>& ps) {
  double cost = ReprojectionCost(observations, cs, ps);
  if (prior.active)
    for (int v = 0; v < (layout.shared ? 1 : layout.num_views); ++v)
      cost += prior.weight * (cs[v].principal_point_px - prior.centre_px[v]).squaredNorm();
  return cost;
}

// Per point, the camera rows of the views that see it, then the intrinsics (every view's).
std::vector<std::vector<int>> BundlePointRows(const std::vector<BundleObservation>& observations,
                                              const BundleLayout& layout, int num_points) {
  std::vector<std::vector<int>> point_rows(num_points);
  for (const auto& o : observations) {
    std::vector<int>& rows = point_rows[o.point];
    if (std::find(rows.begin(), rows.end(), 6 * o.view) != rows.end()) continue;
    for (int k = 0; k < 6; ++k) rows.push_back(6 * o.view + k);
  }
  for (auto& rows : point_rows)
    for (int k = 6 * layout.num_views; k < layout.num_camera_parameters; ++k) rows.push_back(k);
  return point_rows;
}

// The Gauss-Newton normal equations of the reprojection residuals and the prior.
void LinearizeBundle(const std::vector<BundleObservation>& observations, const BundleLayout& layout,
                     const PrincipalPointPrior& prior, const std::vector<Camera>& cams,
                     const std::vector<Eigen::Vector3d>& pts, SchurNormalEquations* normal) {
  normal->SetZero();
  Eigen::MatrixXd& u = normal->u;
  Eigen::VectorXd& g_c = normal->g_c;
  int idx[10];
  Eigen::Matrix<double, 2, 10> jc;
  for (const auto& o : observations) {
    const Camera& c = cams[o.view];
    const Eigen::Vector3d rx = c.cam_from_world_rotation * pts[o.point];
    const Eigen::Vector3d p = rx + c.cam_from_world_translation;
    const double z = p.z();
    const Eigen::Vector2d xy = p.head<2>() / z;
    const Eigen::Vector2d r = c.focal_px * xy + c.principal_point_px - o.uv_px;
    Eigen::Matrix<double, 2, 3> dp;
    dp << 1, 0, -xy.x(), 0, 1, -xy.y();
    dp *= c.focal_px / z;
    int count = 0;
    jc.setZero();
    const Eigen::Matrix<double, 2, 3> d_rot = -dp * Skew(rx);
    for (int k = 0; k < 3; ++k) {
      idx[count] = 6 * o.view + k;
      jc.col(count++) = d_rot.col(k);
    }
    for (int k = 0; k < 3; ++k) {
      idx[count] = 6 * o.view + 3 + k;
      jc.col(count++) = dp.col(k);
    }
    idx[count] = layout.FocalIndex(o.view);
    jc.col(count++) = xy;
    if (layout.refine_principal_point) {
      idx[count] = layout.PrincipalPointIndex(o.view);
      jc.col(count++) = Eigen::Vector2d(1, 0);
      idx[count] = layout.PrincipalPointIndex(o.view) + 1;
      jc.col(count++) = Eigen::Vector2d(0, 1);
    }
    const Eigen::Matrix<double, 2, 3> jp = dp * c.cam_from_world_rotation;
    Eigen::MatrixXd& w = normal->w[o.point];
    for (int a = 0; a < count; ++a) {
      g_c(idx[a]) += jc.col(a).dot(r);
      for (int b = 0; b < count; ++b) u(idx[a], idx[b]) += jc.col(a).dot(jc.col(b));
      w.row(idx[a]) += jc.col(a).transpose() * jp;
    }
    normal->v[o.point] += jp.transpose() * jp;
    normal->g_p[o.point] += jp.transpose() * r;
  }
  if (prior.active)
    for (int v = 0; v < (layout.shared ? 1 : layout.num_views); ++v)
      for (int k = 0; k < 2; ++k) {
        const int i = layout.PrincipalPointIndex(v) + k;
        u(i, i) += prior.weight;
        g_c(i) += prior.weight * (cams[v].principal_point_px(k) - prior.centre_px[v](k));
      }
}

// The cameras and points moved by a step: left rotation increments, additive translations,
// focal lengths and principal points.
void ApplyBundleStep(const BundleLayout& layout, const SchurStep& step, const std::vector<bool>& point_used,
                     std::vector<Camera>* cams, std::vector<Eigen::Vector3d>* pts) {
  const Eigen::VectorXd& dc = step.camera;
  for (int v = 0; v < layout.num_views; ++v) {
    Camera& c = (*cams)[v];
    c.cam_from_world_rotation = RotationFromAngleAxis(dc.segment<3>(6 * v)) * c.cam_from_world_rotation;
    c.cam_from_world_translation += dc.segment<3>(6 * v + 3);
    c.focal_px += dc(layout.FocalIndex(v));
    if (layout.refine_principal_point) c.principal_point_px += dc.segment<2>(layout.PrincipalPointIndex(v));
  }
  for (size_t j = 0; j < pts->size(); ++j)
    if (point_used[j]) (*pts)[j] += step.points[j];
}

// Focal uncertainty: sigma^2 (residual over degrees of freedom) times the focal entry of
// the inverse of the undamped reduced camera system S. S is singular along the 7 directions
// of the similarity gauge, known in closed form for this parameterisation (left rotation
// increments, additive translations): a world rotation w moves each camera by
// (dr, dt) = (-R w, 0), a world translation u by (0, -R u), a scale e by (0, e t). They
// have no focal or principal-point part, so with G an orthonormal basis of them,
// (S + G G^T)^-1 - G G^T is the pseudo-inverse and its focal entry is that of
// (S + G G^T)^-1. Everything is Jacobi-scaled first (rotations in rad, translations in scene
// units and focal lengths in px differ by orders of magnitude): a plain eigenvalue cut on
// the unscaled S took the weakly determined focal direction for gauge. `normal` is the
// linearisation at the final state, `cost` its cost.
std::vector<double> FocalStandardDeviations(const SchurNormalEquations& normal, const BundleLayout& layout,
                                            const std::vector<Camera>& cams, int num_observations,
                                            int num_prior_residuals, double cost) {
  const int n = layout.num_views;
  const int nc = layout.num_camera_parameters;
  Eigen::MatrixXd s = normal.u;
  for (int j = 0; j < normal.NumPoints(); ++j) {
    if (!normal.point_used[j]) continue;
    // Pseudo-inverse of the point block: a point seen from (nearly) one centre has no depth
    // information, and skipping its block instead kept its observations in S as if the point
    // were known (on the Middlebury ring, where two photos share a centre, that shrank the
    // focal sigma twentyfold).
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig_v(normal.v[j]);
    const double largest = eig_v.eigenvalues()(2);
    if (!(largest > 0)) continue;
    Eigen::Vector3d inverse_values = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k)
      if (eig_v.eigenvalues()(k) > 1e-12 * largest) inverse_values(k) = 1.0 / eig_v.eigenvalues()(k);
    const Eigen::Matrix3d v_pinv =
        eig_v.eigenvectors() * inverse_values.asDiagonal() * eig_v.eigenvectors().transpose();
    s.noalias() -= normal.w[j] * v_pinv * normal.w[j].transpose();
  }
  const int num_points_used = static_cast<int>(std::count(normal.point_used.begin(), normal.point_used.end(), true));
  const int dof = 2 * num_observations + num_prior_residuals - (nc + 3 * num_points_used - 7);
  const double sigma_sq = dof > 0 ? cost / dof : 0.0;
  Eigen::VectorXd scale(nc);
  for (int k = 0; k < nc; ++k) scale(k) = s(k, k) > 0 ? 1.0 / std::sqrt(s(k, k)) : 1.0;
  Eigen::MatrixXd gauge = Eigen::MatrixXd::Zero(nc, 7);
  for (int v = 0; v < n; ++v) {
    const Eigen::Matrix3d& r = cams[v].cam_from_world_rotation;
    gauge.block<3, 3>(6 * v, 0) = -r;
    gauge.block<3, 3>(6 * v + 3, 3) = -r;
    gauge.block<3, 1>(6 * v + 3, 6) = cams[v].cam_from_world_translation;
  }
  // In scaled coordinates y = x / scale the gauge directions are scale^-1 * g.
  gauge = scale.cwiseInverse().asDiagonal() * gauge;
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(gauge);
  const Eigen::MatrixXd basis = qr.householderQ() * Eigen::MatrixXd::Identity(nc, 7);
  const Eigen::MatrixXd s_scaled = scale.asDiagonal() * s * scale.asDiagonal() + basis * basis.transpose();
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(s_scaled);
  std::vector<double> focal_std_px(n, 0.0);
  for (int v = 0; v < n; ++v) {
    const int f = layout.FocalIndex(v);
    Eigen::VectorXd e = Eigen::VectorXd::Zero(nc);
    e(f) = 1.0;
    const double variance = sigma_sq * scale(f) * scale(f) * ldlt.solve(e)(f);
    focal_std_px[v] = std::isfinite(variance) ? std::sqrt(std::max(0.0, variance)) : 0.0;
  }
  return focal_std_px;
}

}  // namespace

BundleAdjustmentSummary BundleAdjust(const std::vector<BundleObservation>& observations,
                                     const BundleAdjustmentOptions& options, std::vector<Camera>* cameras,
                                     std::vector<Eigen::Vector3d>* points) {
  const auto start = Clock::now();
  BundleAdjustmentSummary summary;
  std::string error;
  if (!options.Check(&error))
    return FailedSummary(summary, "bad options: " + error, start, SolverTermination::kInvalidInput);
  const int n = static_cast<int>(cameras->size());
  const int m = static_cast<int>(points->size());
  if (n == 0 || observations.empty())
    return FailedSummary(summary, "nothing to adjust", start, SolverTermination::kNothingToSolve);
  for (const auto& o : observations) {
    assert(o.view >= 0 && o.view < n && o.point >= 0 && o.point < m);
    if (!o.uv_px.allFinite())
      return FailedSummary(summary, "an observation is not finite", start, SolverTermination::kInvalidInput);
  }
  const BundleLayout layout(n, options);
  std::vector<Camera> cams = *cameras;
  std::vector<Eigen::Vector3d> pts = *points;
  if (layout.shared)
    for (auto& c : cams) {
      c.focal_px = cams[0].focal_px;
      if (options.refine_principal_point) c.principal_point_px = cams[0].principal_point_px;
    }
  const PrincipalPointPrior prior = MakePrincipalPointPrior(options, layout, cams);

  std::vector<bool> point_used(m, false);
  for (const auto& o : observations) point_used[o.point] = true;
  SchurNormalEquations normal;
  normal.Reset(layout.num_camera_parameters, BundlePointRows(observations, layout, m), point_used);
  auto build = [&]() { LinearizeBundle(observations, layout, prior, cams, pts, &normal); };

  double cost = BundleCost(observations, layout, prior, cams, pts);
  const double initial_cost = cost;
  summary.initial_rms_px = std::sqrt(ReprojectionCost(observations, cams, pts) / (2.0 * observations.size()));
  SchurStep schur;
  std::vector<Camera> cams_new;
  std::vector<Eigen::Vector3d> pts_new;
  auto step = [&](double lambda, double* cost_new, double* step_sq) {
    if (!SolveDampedSchurStep(normal, lambda, &schur)) return false;
    cams_new = cams;
    pts_new = pts;
    ApplyBundleStep(layout, schur, point_used, &cams_new, &pts_new);
    *step_sq = schur.SquaredNorm();
    *cost_new = BundleCost(observations, layout, prior, cams_new, pts_new);
    return true;
  };
  auto accept = [&]() {
    cams = std::move(cams_new);
    pts = std::move(pts_new);
  };
  LmOptions lm;
  lm.max_iterations = options.max_iterations;
  lm.relative_decrease_tolerance = 1e-14;
  const LmResult lm_result = MinimizeLevenbergMarquardt(cost, lm, build, step, accept);
  cost = lm_result.final_cost;
  summary.iterations = lm_result.iterations;

  build();
  summary.focal_std_px =
      FocalStandardDeviations(normal, layout, cams, static_cast<int>(observations.size()), prior.num_residuals, cost);
  *cameras = cams;
  *points = pts;
  summary.final_rms_px = std::sqrt(ReprojectionCost(observations, cams, pts) / (2.0 * observations.size()));
  summary.initial_cost = initial_cost;
  summary.final_cost = cost;
  summary.termination = !(std::isfinite(cost) && cost <= initial_cost)           ? SolverTermination::kFailed
                        : lm_result.termination == LmTermination::kMaxIterations ? SolverTermination::kMaxIterations
                                                                                 : SolverTermination::kConverged;
  summary.message = "bundle adjustment: RMS " + internal::FormatNumber(summary.initial_rms_px) + " -> " +
                    internal::FormatNumber(summary.final_rms_px) + " px in " + std::to_string(summary.iterations) +
                    " iterations";
  summary.time_ms = MsSince(start);
  return summary;
}

namespace {

// The tracks in the normalised coordinates of step 1, before any view is registered.
struct TrackInput {
  Projective p;
  std::vector<std::vector<bool>> duplicate;  // per track, per observation: a second pixel of its view
  Eigen::MatrixXi shared_count;              // (a, b) with a < b: the tracks seen in both views
  int duplicates = 0;
};

// "" when every observation names a view in range with a finite pixel, else why not.
std::string PrepareTracks(const std::vector<SelfCalibrationView>& views, const std::vector<Track>& tracks,
                          TrackInput* in) {
  const int n = static_cast<int>(views.size());
  const int num_tracks = static_cast<int>(tracks.size());
  Projective& p = in->p;
  p.n.resize(n);
  for (int v = 0; v < n; ++v) p.n[v] = NormalisingK(views[v]);
  p.P.assign(n, Matrix34d::Zero());
  p.registered.assign(n, false);
  p.x.resize(num_tracks);
  p.ok.resize(num_tracks);
  p.X.assign(num_tracks, Eigen::Vector4d::Zero());
  p.has_point.assign(num_tracks, false);
  in->duplicate.resize(num_tracks);
  in->shared_count = Eigen::MatrixXi::Zero(n, n);
  for (int t = 0; t < num_tracks; ++t) {
    std::vector<bool> seen(n, false);
    for (const auto& o : tracks[t]) {
      if (o.view < 0 || o.view >= n) return "track " + std::to_string(t) + " names a view out of range";
      if (!o.uv_px.allFinite()) return "track " + std::to_string(t) + " has a non-finite pixel";
      const Eigen::Vector3d x = p.n[o.view].inverse() * o.uv_px.homogeneous();
      p.x[t].push_back(x.head<2>() / x.z());
      // A second pixel of the same view is a matching error: the first one is kept.
      p.ok[t].push_back(!seen[o.view]);
      in->duplicate[t].push_back(seen[o.view]);
      in->duplicates += seen[o.view];
      seen[o.view] = true;
    }
    for (int a = 0; a < n; ++a)
      for (int b = a + 1; b < n; ++b) in->shared_count(a, b) += seen[a] && seen[b];
  }
  return "";
}

// Step 1's candidate starts: of the pairs sharing the most tracks, those whose F (in pixels;
// RANSAC flags wrong matches) a homography does not explain (a pair seen from nearly one
// centre, e.g. the two photos of the Middlebury ring taken from one place, matches best of all
// and fixes nothing), best first. False with *error when there is none.
bool FindInitialPairs(const std::vector<Track>& tracks, const TrackInput& in, const SelfCalibrationOptions& options,
                      std::vector<InitialPair>* pairs, int* degenerate_pairs, std::string* error) {
  const int n = static_cast<int>(in.p.P.size());
  const int num_tracks = static_cast<int>(tracks.size());
  std::vector<std::pair<int, std::pair<int, int>>> candidates;  // shared tracks, (a, b)
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b)
      if (in.shared_count(a, b) >= kMinTracks) candidates.push_back({in.shared_count(a, b), {a, b}});
  if (candidates.empty()) {
    *error = "no pair of views shares " + std::to_string(kMinTracks) +
             " tracks (best: " + std::to_string(in.shared_count.maxCoeff()) + ")";
    return false;
  }
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const auto& x, const auto& y) { return x.first > y.first; });
  if (static_cast<int>(candidates.size()) > kMaxInitialPairCandidates) candidates.resize(kMaxInitialPairCandidates);
  FundamentalOptions f_options;
  f_options.inlier_threshold_px = options.inlier_threshold_px;
  f_options.seed = options.seed;
  *degenerate_pairs = 0;
  for (const auto& candidate : candidates) {
    InitialPair pair;
    pair.a = candidate.second.first;
    pair.b = candidate.second.second;
    std::vector<Eigen::Vector2d> uv_a, uv_b;
    for (int t = 0; t < num_tracks; ++t) {
      int ka = -1, kb = -1;
      for (size_t k = 0; k < tracks[t].size(); ++k) {
        if (!in.p.ok[t][k]) continue;
        if (tracks[t][k].view == pair.a) ka = static_cast<int>(k);
        if (tracks[t][k].view == pair.b) kb = static_cast<int>(k);
      }
      if (ka < 0 || kb < 0) continue;
      uv_a.push_back(tracks[t][ka].uv_px);
      uv_b.push_back(tracks[t][kb].uv_px);
      pair.obs.push_back({t, {ka, kb}});
    }
    pair.f = EstimateFundamentalMatrix(uv_a, uv_b, f_options);
    if (!pair.f.IsUsable()) continue;
    if (pair.f.homography_rms_px > 0 &&
        pair.f.homography_rms_px <= f_options.homography_warning_ratio * pair.f.symmetric_epipolar_rms_px +
                                        f_options.homography_warning_slack_px) {
      ++*degenerate_pairs;
      continue;
    }
    pairs->push_back(std::move(pair));
  }
  if (pairs->empty()) {
    *error = "no pair of views gives a fundamental matrix with parallax (" + std::to_string(*degenerate_pairs) +
             " pairs are explained by a homography: one centre or a plane)";
    return false;
  }
  return true;
}

struct Registration {
  Projective p;
  std::vector<std::string> warnings;
  int view_a = -1, view_b = -1;  // the initial pair; -1 when no start gave canonical cameras
};

// Views that share tracks only two at a time with the rest (a ring photographed in two
// halves, a junction of few three-view tracks) cannot be resected into one projective frame:
// a start on one side registers that side only. So further starts are tried from pairs of
// views the attempts so far left out, and the attempt registering the most views is kept.
Registration RegisterFromBestStart(const std::vector<Track>& tracks, const std::vector<InitialPair>& pairs,
                                   const SelfCalibrationOptions& options, const Projective& unregistered) {
  const int n = static_cast<int>(unregistered.P.size());
  std::vector<bool> has_tracks(n, false);
  for (const Track& track : tracks)
    for (const auto& o : track) has_tracks[o.view] = true;
  const int reachable = static_cast<int>(std::count(has_tracks.begin(), has_tracks.end(), true));
  std::vector<bool> tried(n, false);
  Registration best;
  int best_registered = -1, attempts = 0;
  for (const InitialPair& pair : pairs) {
    if (attempts >= kMaxInitialPairAttempts || best_registered == reachable) break;
    if (tried[pair.a] || tried[pair.b]) continue;
    ++attempts;
    Projective attempt = unregistered;
    std::vector<std::string> warnings;
    if (!RegisterIncrementally(tracks, pair, options, &attempt, &warnings)) continue;
    const int registered = static_cast<int>(std::count(attempt.registered.begin(), attempt.registered.end(), true));
    for (int v = 0; v < n; ++v) tried[v] = tried[v] || attempt.registered[v];
    if (registered > best_registered) {
      best_registered = registered;
      best.p = std::move(attempt);
      best.warnings = std::move(warnings);
      best.view_a = pair.a;
      best.view_b = pair.b;
    }
  }
  return best;
}

void WarnUnregisteredViews(const std::vector<Track>& tracks, const Projective& p, std::vector<std::string>* warnings) {
  const int n = static_cast<int>(p.P.size());
  const int num_tracks = static_cast<int>(tracks.size());
  for (int v = 0; v < n; ++v)
    if (!p.registered[v]) {
      int seen = 0, shared = 0;
      for (int t = 0; t < num_tracks; ++t) {
        bool in_v = false, in_registered = false;
        for (const auto& o : tracks[t]) {
          in_v = in_v || o.view == v;
          in_registered = in_registered || p.registered[o.view];
        }
        seen += in_v && p.has_point[t];
        shared += in_v && in_registered;
      }
      warnings->push_back("view " + std::to_string(v) + " is not registered: it sees " + std::to_string(seen) +
                          " reconstructed points (resection needs " + std::to_string(kMinResectionTracks) +
                          " consistent ones) and shares " + std::to_string(shared) + " tracks with registered views");
    }
}

// Reprojection RMS (px) of the projective reconstruction over its accepted observations.
double ProjectiveRms(const std::vector<Track>& tracks, const Projective& p) {
  double sum = 0.0;
  int count = 0;
  for (size_t t = 0; t < tracks.size(); ++t) {
    if (!p.has_point[t]) continue;
    for (size_t k = 0; k < tracks[t].size(); ++k) {
      if (!p.ok[t][k] || !p.registered[tracks[t][k].view]) continue;
      const double e = PixelError(p, tracks[t], static_cast<int>(k), p.X[t]);
      sum += e * e;
      ++count;
    }
  }
  return count > 0 ? std::sqrt(sum / (2.0 * count)) : 0.0;
}

// The projective frame conditioned for the quadric: points whitened (their 4x4 second moment
// becomes the identity; invariant to the sign of each homogeneous point), cameras scaled to
// unit norm.
struct ConditionedFrame {
  Eigen::Matrix4d whiten = Eigen::Matrix4d::Identity();  // X_conditioned ~ whiten X
  std::vector<Matrix34d> cams;                           // per view, zero where unregistered
  std::vector<Eigen::Vector4d> X;                        // per track, zero without a point
};

bool ConditionFrame(const Projective& p, ConditionedFrame* frame, std::string* error) {
  const int n = static_cast<int>(p.P.size());
  const int num_tracks = static_cast<int>(p.X.size());
  Eigen::Matrix4d moment = Eigen::Matrix4d::Zero();
  int num_points = 0;
  for (int t = 0; t < num_tracks; ++t)
    if (p.has_point[t]) {
      moment += p.X[t] * p.X[t].transpose();
      ++num_points;
    }
  if (num_points < kMinTracks) {
    *error = "only " + std::to_string(num_points) + " tracks could be triangulated";
    return false;
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> moment_eig(moment / num_points);
  if (!(moment_eig.eigenvalues()(0) > 1e-14 * moment_eig.eigenvalues()(3))) {
    *error = "the triangulated points are coplanar: the projective reconstruction is degenerate";
    return false;
  }
  frame->whiten =
      moment_eig.eigenvalues().cwiseSqrt().cwiseInverse().asDiagonal() * moment_eig.eigenvectors().transpose();
  const Eigen::Matrix4d whiten_inv = frame->whiten.inverse();
  frame->cams.assign(n, Matrix34d::Zero());
  frame->X.assign(num_tracks, Eigen::Vector4d::Zero());
  for (int v = 0; v < n; ++v)
    if (p.registered[v]) frame->cams[v] = (p.P[v] * whiten_inv).normalized();
  for (int t = 0; t < num_tracks; ++t)
    if (p.has_point[t]) frame->X[t] = (frame->whiten * p.X[t]).normalized();
  return true;
}

// Step 2: the absolute dual quadric, iteratively reweighted by 1 / w*_33.
Eigen::Matrix4d AbsoluteDualQuadric(const std::vector<SelfCalibrationView>& views, const ConditionedFrame& frame,
                                    const std::vector<bool>& registered, const SelfCalibrationOptions& options) {
  const int n = static_cast<int>(views.size());
  const int num_registered = static_cast<int>(std::count(registered.begin(), registered.end(), true));
  const bool all_priors =
      std::all_of(views.begin(), views.end(), [](const SelfCalibrationView& v) { return v.focal_prior_px > 0; });
  Eigen::Matrix4d q = Eigen::Matrix4d::Zero();
  std::vector<double> nu(n, 1.0);
  for (int round = 0; round < options.quadric_reweighting_rounds; ++round) {
    Eigen::MatrixXd a(6 * num_registered, 10);
    int row = 0;
    for (int v = 0; v < n; ++v) {
      if (!registered[v]) continue;
      const Matrix34d& c = frame.cams[v];
      const double w = 1.0 / nu[v];
      const double wf = (views[v].focal_prior_px > 0 || all_priors) ? options.prior_focal_weight : options.focal_weight;
      a.row(row++) = w * options.skew_weight * QuadricRow(c, 0, 1);
      a.row(row++) = w * options.aspect_weight * (QuadricRow(c, 0, 0) - QuadricRow(c, 1, 1));
      a.row(row++) = w * options.principal_point_weight * QuadricRow(c, 0, 2);
      a.row(row++) = w * options.principal_point_weight * QuadricRow(c, 1, 2);
      a.row(row++) = w * wf * (QuadricRow(c, 0, 0) - QuadricRow(c, 2, 2));
      a.row(row++) = w * wf * (QuadricRow(c, 1, 1) - QuadricRow(c, 2, 2));
    }
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeFullV);
    q = QuadricFromVector(svd.matrixV().col(9));
    double sum33 = 0.0;
    for (int v = 0; v < n; ++v)
      if (registered[v]) sum33 += frame.cams[v].row(2) * q * frame.cams[v].row(2).transpose();
    if (sum33 < 0) q = -q;
    for (int v = 0; v < n; ++v)
      if (registered[v])
        nu[v] = std::max(std::abs(double(frame.cams[v].row(2) * q * frame.cams[v].row(2).transpose())), 1e-12);
  }
  return q;
}

// The cameras and points upgraded by the rectifying homography of Q, and the metric frame.
struct MetricFrame {
  std::vector<Matrix34d> cams;                                           // per view
  Eigen::Matrix4d metric_from_projective = Eigen::Matrix4d::Identity();  // of the unconditioned frame
  int negative_eigenvalues = 0;  // of Q, besides the one dropped: > 0 means the upgrade is unreliable
};

MetricFrame UpgradeByQuadric(const Eigen::Matrix4d& q, const ConditionedFrame& frame, const Projective& p) {
  const int n = static_cast<int>(frame.cams.size());
  const int num_tracks = static_cast<int>(frame.X.size());
  MetricFrame metric;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> q_eig(q);
  // Rank 3: drop the eigenvalue of smallest magnitude; the other three must be positive.
  Eigen::Index smallest = 0;
  q_eig.eigenvalues().cwiseAbs().minCoeff(&smallest);
  Eigen::Matrix4d h = Eigen::Matrix4d::Zero();
  for (int k = 0, col = 0; k < 4; ++k) {
    if (k == smallest) continue;
    const double lambda = q_eig.eigenvalues()(k);
    metric.negative_eigenvalues += lambda <= 0;
    h.col(col++) = std::sqrt(std::abs(lambda)) * q_eig.eigenvectors().col(k);
  }
  h.col(3) = q_eig.eigenvectors().col(smallest);
  const Eigen::Matrix4d h_inv = h.inverse();
  metric.cams.assign(n, Matrix34d::Zero());
  std::vector<Eigen::Vector4d> metric_x(num_tracks, Eigen::Vector4d::Zero());
  for (int v = 0; v < n; ++v)
    if (p.registered[v]) metric.cams[v] = frame.cams[v] * h;
  for (int t = 0; t < num_tracks; ++t)
    if (p.has_point[t]) metric_x[t] = h_inv * frame.X[t];
  Eigen::Matrix4d reflect = Eigen::Matrix4d::Identity();
  if (DepthVotes(metric.cams, p.registered, metric_x, p.has_point) < 0) {
    reflect(3, 3) = -1.0;
    for (auto& c : metric.cams) c = c * reflect;
  }
  metric.metric_from_projective = reflect * h_inv * frame.whiten;
  return metric;
}

// Square-pixel cameras from the upgraded ones by RQ (the focal length the mean of K's two,
// the principal point by the option's mode), into summary->cameras and linear_focal_px.
bool LinearMetricCameras(const std::vector<SelfCalibrationView>& views, const SelfCalibrationOptions& options,
                         const Projective& p, const MetricFrame& metric, SelfCalibrationSummary* summary,
                         std::string* error) {
  const int n = static_cast<int>(views.size());
  summary->cameras.resize(n);
  summary->linear_focal_px.assign(n, 0.0);
  std::vector<double> focal_list;
  for (int v = 0; v < n; ++v) {
    Camera& cam = summary->cameras[v];
    cam.width_px = views[v].width_px;
    cam.height_px = views[v].height_px;
    cam.principal_point_px = options.principal_point_mode == PrincipalPointMode::kFixed
                                 ? options.fixed_principal_point_px
                                 : ImageCentre(views[v]);
    if (!p.registered[v]) continue;
    Eigen::Matrix3d k, r;
    Eigen::Vector3d t;
    if (!DecomposeProjectionMatrix(p.n[v] * metric.cams[v], &k, &r, &t)) {
      *error = "the upgraded camera of view " + std::to_string(v) + " cannot be decomposed";
      return false;
    }
    summary->linear_focal_px[v] = 0.5 * (k(0, 0) + k(1, 1));
    focal_list.push_back(summary->linear_focal_px[v]);
    cam.focal_px = summary->linear_focal_px[v];
    cam.cam_from_world_rotation = r;
    cam.cam_from_world_translation = t;
  }
  if (options.shared_focal_length) {
    std::nth_element(focal_list.begin(), focal_list.begin() + focal_list.size() / 2, focal_list.end());
    for (auto& c : summary->cameras) c.focal_px = focal_list[focal_list.size() / 2];
  }
  if (!(focal_list[focal_list.size() / 2] > 0)) {
    *error = "the linear self-calibration gives no positive focal length";
    return false;
  }
  return true;
}

// The metric points of step 3 and the observations that enter the bundle adjustment, on the
// cameras in `cameras` (the summary's); observation flags live in p.ok.
struct MetricTracks {
  const std::vector<Track>& tracks;
  const std::vector<std::vector<bool>>& duplicate;
  Projective& p;
  std::vector<Camera>& cameras;
  std::vector<Eigen::Vector3d> points;  // per track
  std::vector<bool> keep;               // per track: a point with 2 or more observations
  std::vector<BundleObservation> observations;

  int NumTracks() const { return static_cast<int>(tracks.size()); }

  // Points triangulated with the square-pixel cameras from their accepted observations.
  void Triangulate() {
    points.assign(NumTracks(), Eigen::Vector3d::Zero());
    keep.assign(NumTracks(), false);
    for (int t = 0; t < NumTracks(); ++t) {
      if (!p.has_point[t]) continue;
      std::vector<Matrix34d> pc;
      std::vector<Eigen::Vector3d> xh;
      std::vector<Eigen::Vector2d> xs;
      for (size_t k = 0; k < tracks[t].size(); ++k) {
        if (!p.ok[t][k] || !p.registered[tracks[t][k].view]) continue;
        pc.push_back(cameras[tracks[t][k].view].ProjectionMatrix());
        xh.push_back(tracks[t][k].uv_px.homogeneous());
        xs.push_back(tracks[t][k].uv_px);
      }
      if (pc.size() < 2) continue;
      const Eigen::Vector4d xm = RefineTriangulatedPoint(pc, xs, TriangulateLinear(pc, xh), 10);
      if (!(std::abs(xm(3)) > 1e-12)) continue;
      points[t] = xm.head<3>() / xm(3);
      keep[t] = true;
    }
  }

  // Collects the observations of kept tracks, dropping those beyond threshold_px (none when 0)
  // or behind their camera, then the tracks left with one; *rms over those collected.
  void Collect(double threshold_px, double* rms) {
    observations.clear();
    double sum = 0.0;
    std::vector<int> per_track(NumTracks(), 0);
    for (int t = 0; t < NumTracks(); ++t) {
      if (!keep[t]) continue;
      for (size_t k = 0; k < tracks[t].size(); ++k) {
        const int v = tracks[t][k].view;
        if (!p.ok[t][k] || !p.registered[v]) continue;
        const Camera& c = cameras[v];
        const double e = (c.Project(points[t]) - tracks[t][k].uv_px).norm();
        if (threshold_px > 0 && !(e < threshold_px && c.CamFromWorld(points[t]).z() > 0)) {
          p.ok[t][k] = false;
          continue;
        }
        observations.push_back({v, t, tracks[t][k].uv_px});
        sum += e * e;
        ++per_track[t];
      }
    }
    // Tracks left with one observation constrain nothing.
    std::vector<BundleObservation> kept;
    for (const auto& o : observations)
      if (per_track[o.point] >= 2) kept.push_back(o);
    for (int t = 0; t < NumTracks(); ++t) keep[t] = keep[t] && per_track[t] >= 2;
    observations = kept;
    *rms = observations.empty() ? 0.0 : std::sqrt(sum / (2.0 * observations.size()));
  }

  // The linear upgrade is approximate (tens of px are normal), but a few points may land far
  // off or behind a camera and pull the adjustment away: drop those beyond 5 median errors.
  void DropFarFromLinear(double threshold_px) {
    std::vector<double> errors;
    for (const auto& o : observations) errors.push_back((cameras[o.view].Project(points[o.point]) - o.uv_px).norm());
    if (errors.empty()) return;
    std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
    double unused = 0.0;
    Collect(std::max(threshold_px, 5.0 * errors[errors.size() / 2]), &unused);
  }

  // The inliers decided again on the adjusted metric cameras: observations flagged on the
  // rough projective or linear cameras are admitted back when they fit within the threshold,
  // and tracks lost there are triangulated again. The final set must not depend on early,
  // less accurate stages (on the temple, ten observations flagged early moved the focal length
  // by 1.5 %).
  void Readmit(double threshold_px) {
    for (int t = 0; t < NumTracks(); ++t) {
      std::vector<int> candidates;
      for (size_t k = 0; k < tracks[t].size(); ++k)
        if (!duplicate[t][k] && p.registered[tracks[t][k].view]) candidates.push_back(static_cast<int>(k));
      if (candidates.size() < 2) continue;
      if (!keep[t] && !RefinePoint(t, candidates)) continue;
      std::vector<int> inliers = Classify(t, candidates, threshold_px);
      if (inliers.size() >= 2 && RefinePoint(t, inliers)) inliers = Classify(t, candidates, threshold_px);
      for (int k : candidates) p.ok[t][k] = false;
      for (int k : inliers) p.ok[t][k] = true;
      keep[t] = inliers.size() >= 2;
    }
  }

  // Track t's point from the listed observations, started from the kept point if any.
  bool RefinePoint(int t, const std::vector<int>& use) {
    std::vector<Matrix34d> pc;
    std::vector<Eigen::Vector3d> xh;
    std::vector<Eigen::Vector2d> xs;
    for (int k : use) {
      pc.push_back(cameras[tracks[t][k].view].ProjectionMatrix());
      xh.push_back(tracks[t][k].uv_px.homogeneous());
      xs.push_back(tracks[t][k].uv_px);
    }
    const Eigen::Vector4d start = keep[t] ? points[t].homogeneous().normalized() : TriangulateLinear(pc, xh);
    const Eigen::Vector4d xm = RefineTriangulatedPoint(pc, xs, start, 10);
    if (!(std::abs(xm(3)) > 1e-12)) return false;
    points[t] = xm.head<3>() / xm(3);
    return true;
  }

  std::vector<int> Classify(int t, const std::vector<int>& candidates, double threshold_px) const {
    std::vector<int> inliers;
    for (int k : candidates) {
      const Camera& c = cameras[tracks[t][k].view];
      const double e = (c.Project(points[t]) - tracks[t][k].uv_px).norm();
      if (e < threshold_px && c.CamFromWorld(points[t]).z() > 0) inliers.push_back(k);
    }
    return inliers;
  }
};

// Step 3: the bundle adjustment rounds of the registered views, the inliers decided again
// between rounds. Fills the summary's cameras, focal_std_px, iterations and termination.
bool AdjustMetric(const std::vector<SelfCalibrationView>& views, const SelfCalibrationOptions& options, int view_a,
                  MetricTracks* metric, SelfCalibrationSummary* summary, std::string* error) {
  const int n = static_cast<int>(views.size());
  const Projective& p = metric->p;
  BundleAdjustmentOptions ba;
  ba.shared_focal_length = options.shared_focal_length;
  ba.refine_principal_point = options.principal_point_mode == PrincipalPointMode::kSolve;
  ba.principal_point_prior_std_px =
      options.principal_point_prior_std * std::max(views[view_a].width_px, views[view_a].height_px);
  ba.max_iterations = options.max_bundle_iterations;
  // The prior's weight needs the pixel noise: the residual RMS of the round before (of the
  // linear upgrade in the first round, which only makes the prior weaker there).
  double rms_px = summary->linear_rms_px;
  for (int round = 0; round < options.bundle_rounds; ++round) {
    if (round > 0) {
      metric->Readmit(options.inlier_threshold_px);
      metric->Collect(options.inlier_threshold_px, &rms_px);
    }
    ba.observation_std_px = std::max(rms_px, 1e-3);
    // Only registered views take part: a compact camera list for the adjustment.
    std::vector<int> index(n, -1);
    std::vector<Camera> ba_cams;
    for (int v = 0; v < n; ++v)
      if (p.registered[v]) {
        index[v] = static_cast<int>(ba_cams.size());
        ba_cams.push_back(summary->cameras[v]);
      }
    std::vector<BundleObservation> ba_obs = metric->observations;
    for (auto& o : ba_obs) o.view = index[o.view];
    const BundleAdjustmentSummary result = BundleAdjust(ba_obs, ba, &ba_cams, &metric->points);
    if (!result.IsUsable()) {
      *error = "the bundle adjustment failed: " + result.message;
      return false;
    }
    rms_px = result.final_rms_px;
    summary->iterations += result.iterations;
    summary->termination = result.termination;  // the last round's: converged or out of iterations
    summary->focal_std_px.assign(n, 0.0);
    for (int v = 0; v < n; ++v)
      if (index[v] >= 0) {
        summary->cameras[v] = ba_cams[index[v]];
        summary->focal_std_px[v] = result.focal_std_px[index[v]];
      }
  }
  return true;
}

}  // namespace

SelfCalibrationSummary SelfCalibrate(const std::vector<SelfCalibrationView>& views, const std::vector<Track>& tracks,
                                     const SelfCalibrationOptions& options) {
  const auto start = Clock::now();
  SelfCalibrationSummary summary;
  auto fail = [&](std::string message) { return FailedSummary(summary, std::move(message), start); };
  std::string error;
  if (!options.Check(&error))
    return FailedSummary(summary, "bad options: " + error, start, SolverTermination::kInvalidInput);
  const int n = static_cast<int>(views.size());
  if (n < 3) return fail("self-calibration needs at least 3 views, got " + std::to_string(n));
  for (const auto& v : views)
    if (v.width_px <= 0 || v.height_px <= 0 || !(v.focal_prior_px >= 0))
      return fail("every view needs a positive image size and a non-negative focal prior");

  TrackInput input;
  error = PrepareTracks(views, tracks, &input);
  if (!error.empty()) return fail(error);
  if (input.duplicates > 0)
    summary.warnings.push_back(std::to_string(input.duplicates) +
                               " observations repeat a view within their track (ignored)");

  // Step 1: the projective reconstruction from the best initial pair.
  std::vector<InitialPair> pairs;
  int degenerate_pairs = 0;
  if (!FindInitialPairs(tracks, input, options, &pairs, &degenerate_pairs, &error)) return fail(error);
  if (degenerate_pairs > 0)
    summary.warnings.push_back(std::to_string(degenerate_pairs) +
                               " pair(s) sharing many tracks are explained by a homography (nearly one centre or a "
                               "plane) and were not used to start");
  Registration registration = RegisterFromBestStart(tracks, pairs, options, input.p);
  if (registration.view_a < 0) return fail("no initial pair gives canonical cameras");
  Projective& p = registration.p;
  const int va = registration.view_a;
  summary.warnings.insert(summary.warnings.end(), registration.warnings.begin(), registration.warnings.end());
  summary.initial_view_a = va;
  summary.initial_view_b = registration.view_b;
  summary.registered = p.registered;
  if (options.projective_bundle_adjust) {
    const ProjectiveBundleSummary result = AdjustProjective(tracks, options.max_projective_bundle_iterations, &p);
    if (!result.IsUsable()) summary.warnings.push_back(result.message);
  }
  const int num_registered = static_cast<int>(std::count(p.registered.begin(), p.registered.end(), true));
  WarnUnregisteredViews(tracks, p, &summary.warnings);
  if (num_registered < 3)
    return fail("only " + std::to_string(num_registered) + " views could be registered; self-calibration needs 3");
  summary.projective_rms_px = ProjectiveRms(tracks, p);

  // Step 2: the absolute dual quadric and the linear metric cameras.
  ConditionedFrame frame;
  if (!ConditionFrame(p, &frame, &error)) return fail(error);
  const MetricFrame metric_frame = UpgradeByQuadric(AbsoluteDualQuadric(views, frame, p.registered, options), frame, p);
  if (metric_frame.negative_eigenvalues > 0)
    summary.warnings.push_back("the absolute dual quadric is not positive semi-definite (" +
                               std::to_string(metric_frame.negative_eigenvalues) +
                               " negative eigenvalue(s)): the linear self-calibration is unreliable (noise, outliers, "
                               "or a critical motion); the bundle adjustment starts from a rough guess");
  summary.metric_from_projective = metric_frame.metric_from_projective;
  if (!LinearMetricCameras(views, options, p, metric_frame, &summary, &error)) return fail(error);

  // Step 3: points re-triangulated with the square-pixel cameras, the outliers' observations
  // dropped, then the bundle adjustment.
  MetricTracks metric{tracks, input.duplicate, p, summary.cameras, {}, {}, {}};
  metric.Triangulate();
  metric.Collect(0.0, &summary.linear_rms_px);
  const int num_linear_observations = static_cast<int>(metric.observations.size());
  metric.DropFarFromLinear(options.inlier_threshold_px);
  NormaliseGauge(va, &summary.cameras, &metric.points, metric.keep);
  if (options.bundle_adjust) {
    if (!AdjustMetric(views, options, va, &metric, &summary, &error)) return fail(error);
    NormaliseGauge(va, &summary.cameras, &metric.points, metric.keep);
  }
  double final_rms = 0.0;
  metric.Collect(0.0, &final_rms);
  summary.reprojection_rms_px = final_rms;
  summary.num_observations = static_cast<int>(metric.observations.size());
  summary.points = metric.points;
  summary.triangulated = metric.keep;
  for (int v = 0; v < n; ++v)
    if (p.registered[v] && !(summary.cameras[v].focal_px > 0))
      return fail("view " + std::to_string(v) + " ends with a non-positive focal length");
  summary.initial_cost = summary.linear_rms_px * summary.linear_rms_px * 2.0 * num_linear_observations;
  summary.final_cost = final_rms * final_rms * 2.0 * summary.num_observations;
  if (!options.bundle_adjust) summary.termination = SolverTermination::kConverged;
  summary.message = "self-calibrated " + std::to_string(num_registered) + " views, focal " +
                    internal::FormatNumber(summary.cameras[va].focal_px) + " px (linear " +
                    internal::FormatNumber(summary.linear_focal_px[va]) + "), reprojection RMS " +
                    internal::FormatNumber(summary.reprojection_rms_px) + " px";
  summary.time_ms = MsSince(start);
  return summary;
}

}  // namespace facet
