#include "core/solve/multiview_init.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <set>
#include <utility>

#include <Eigen/Dense>

#include "core/estimators/calibrate_dlt.h"
#include "core/estimators/homography_pose.h"
#include "core/estimators/projective_upgrade.h"
#include "core/solve/pin_resection.h"
#include "core/util/eigen_decompositions.h"

namespace facet {
namespace {

using VertexKey = std::pair<Id, VertexId>;

VertexKey KeyOf(const VertexRef& ref) { return {ref.primitive_id, ref.vertex}; }

std::string Format(const char* format, double a) {
  char buffer[256];
  std::snprintf(buffer, sizeof(buffer), format, a);
  return buffer;
}

std::string Quoted(const Image& image) { return "image '" + image.path + "'"; }

// The usable pins of one image: vertex exists, pixel finite, first pin per vertex.
std::vector<const Pin*> UsablePins(const Project& project, Id image_id) {
  std::vector<const Pin*> pins;
  std::set<VertexKey> seen;
  for (const Pin& pin : project.pins) {
    if (pin.image_id != image_id || !pin.uv_px.allFinite() || project.FindVertex(pin.vertex) == nullptr) continue;
    if (!VertexInWorld(project, pin.vertex).allFinite()) continue;
    if (seen.insert(KeyOf(pin.vertex)).second) pins.push_back(&pin);
  }
  return pins;
}

Eigen::Vector2d ImageCenter(int width_px, int height_px) {
  return Eigen::Vector2d((width_px - 1) / 2.0, (height_px - 1) / 2.0);
}

// RMS distance of points from their centroid; 0 for fewer than 2.
double RmsSpread(const std::vector<Eigen::Vector3d>& points) {
  if (points.size() < 2) return 0.0;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : points) mean += p;
  mean /= static_cast<double>(points.size());
  double sum = 0.0;
  for (const auto& p : points) sum += (p - mean).squaredNorm();
  return std::sqrt(sum / points.size());
}

// Camera (R, t) of a reconstruction frame moved to the world by X_w = s Rs X_r + ts; the
// camera's scale follows so that its pixels stay the same.
Camera MoveCamera(const Camera& camera_in_recon, const Similarity3d& world_from_recon) {
  Camera out = camera_in_recon;
  const Eigen::Matrix3d rotation = camera_in_recon.cam_from_world_rotation * world_from_recon.rotation.transpose();
  out.cam_from_world_rotation = rotation;
  out.cam_from_world_translation =
      world_from_recon.scale * camera_in_recon.cam_from_world_translation - rotation * world_from_recon.translation;
  return out;
}

// The similarity that puts the reconstruction's camera `in_recon` at the pose of `in_world`,
// with scale s: camera(X_w) = s camera_recon(X_r).
Similarity3d KeepCameraSimilarity(const Camera& in_recon, const Camera& in_world, double scale) {
  Similarity3d sim;
  sim.scale = scale;
  const Eigen::Matrix3d& rw = in_world.cam_from_world_rotation;
  sim.rotation = rw.transpose() * in_recon.cam_from_world_rotation;
  sim.translation =
      rw.transpose() * (scale * in_recon.cam_from_world_translation - in_world.cam_from_world_translation);
  return sim;
}

// The spread ratio of the header's gauge; 1 when either side has no spread.
double SpreadScale(const std::vector<Eigen::Vector3d>& recon, const std::vector<Eigen::Vector3d>& model) {
  const double spread_recon = RmsSpread(recon), spread_model = RmsSpread(model);
  if (!(spread_recon > 0.0) || !(spread_model > 0.0) || !std::isfinite(spread_model / spread_recon)) return 1.0;
  return spread_model / spread_recon;
}

// Gauge for a reconstruction with no calibrated camera: align to the model or keep the first
// camera's pose (see the header).
Similarity3d ChooseGauge(const std::vector<Eigen::Vector3d>& recon, const std::vector<Eigen::Vector3d>& model,
                         const Camera& first_in_recon, const Camera& first_in_world, MultiViewGauge gauge,
                         std::string* gauge_name) {
  if (gauge == MultiViewGauge::kAlignToModel && recon.size() >= 3) {
    Similarity3d sim;
    if (AlignSimilarity(recon, model, &sim) && sim.scale > 0.0 && std::isfinite(sim.scale) &&
        sim.translation.allFinite() && RmsSpread(model) > 0.0) {
      *gauge_name = "aligned to the model";
      return sim;
    }
  }
  *gauge_name = "first camera kept where it was";
  return KeepCameraSimilarity(first_in_recon, first_in_world, SpreadScale(recon, model));
}

// The focal length known for an uncalibrated image (options, then the image's fixed focal
// length or prior), or 0.
double KnownFocalPx(const Image& image, const MultiViewInitOptions& options) {
  const auto given = options.focal_px_by_image.find(image.id);
  if (given != options.focal_px_by_image.end()) return given->second;
  if (image.focal_mode == FocalMode::kFixed && image.fixed_focal_px > 0.0) return image.fixed_focal_px;
  if (image.focal_mode == FocalMode::kPrior && image.focal_prior_px > 0.0) return image.focal_prior_px;
  return 0.0;
}

// Intrinsics for an image: its own when calibrated, else the known or guessed focal length and
// the principal point its mode asks for (the centre when solved: two views cannot).
Camera IntrinsicsFor(const Image& image, const MultiViewInitOptions& options, bool* guessed) {
  *guessed = false;
  if (image.camera_calibrated) return image.camera;
  Camera camera;
  camera.width_px = image.width_px;
  camera.height_px = image.height_px;
  camera.focal_px = KnownFocalPx(image, options);
  if (!(camera.focal_px > 0.0)) {
    camera.focal_px = options.default_focal_factor * std::max(image.width_px, image.height_px);
    *guessed = true;
  }
  camera.principal_point_px = image.principal_point_mode == PrincipalPointMode::kFixed
                                  ? image.fixed_principal_point_px
                                  : ImageCenter(image.width_px, image.height_px);
  return camera;
}

bool IsFinite(const Camera& camera) {
  return std::isfinite(camera.focal_px) && camera.focal_px > 0.0 && camera.principal_point_px.allFinite() &&
         camera.cam_from_world_rotation.allFinite() && camera.cam_from_world_translation.allFinite();
}

void SetCamera(Image* image, Camera camera) {
  camera.width_px = image->width_px;
  camera.height_px = image->height_px;
  image->camera = camera;
  image->camera_calibrated = true;
}

// ---- (a) Resection ----

struct ResectionResult {
  bool ok = false;
  std::string message;
  std::vector<std::string> warnings;
  Camera camera;
  double rms_px = 0.0;
  double focal_std_px = 0.0;
  std::vector<Id> flagged;
};

// The focal length of a calibrated image that shares `image`'s lens (Image::lens_group), or 0;
// *source names it.
double SharedLensFocalPx(const Project& project, const Image& image, std::string* source) {
  if (image.lens_group <= 0) return 0.0;
  for (const Image& other : project.images) {
    if (other.id == image.id || other.lens_group != image.lens_group || !other.camera_calibrated) continue;
    if (!(other.camera.focal_px > 0.0) || !std::isfinite(other.camera.focal_px)) continue;
    *source = "the lens it shares with " + Quoted(other);
    return other.camera.focal_px;
  }
  return 0.0;
}

// When the DLT or the exact plane gave no camera, or one that is no camera (`reason`): the
// nearly planar path, then the pose with a known focal length (the shared lens's, EXIF, the
// image's fixed focal length or its prior), each checked as a camera (core/solve/pin_resection.h).
ResectionResult ResectOtherwise(const Project& project, const Image& image,
                                const std::vector<PointCorrespondence>& points, const MultiViewInitOptions& options,
                                const std::string& reason) {
  ResectionResult result;
  PinResectionInput input;
  for (const PointCorrespondence& p : points) {
    input.points.push_back(p.xyz);
    input.pixels.push_back(p.uv_px);
  }
  input.width_px = image.width_px;
  input.height_px = image.height_px;
  input.principal_point_px = image.principal_point_mode == PrincipalPointMode::kFixed
                                 ? image.fixed_principal_point_px
                                 : ImageCenter(image.width_px, image.height_px);
  input.max_iterations = options.max_resection_iterations;
  std::string why = reason;
  if (const std::string spread = WhyPinsNotSpread(input); !spread.empty()) {
    result.message = why + "; " + spread;
    return result;
  }
  const bool focal_fixed = image.focal_mode == FocalMode::kFixed && image.fixed_focal_px > 0.0;
  auto take = [&](const PinResectionResult& r, const std::string& note) {
    result.ok = true;
    result.camera = r.camera;
    result.rms_px = r.rms_px;
    result.message = r.message + note;
    result.warnings.push_back(Quoted(image) + ": " + reason + "; " + r.message + note);
  };
  if (!focal_fixed && PointsThicknessRatio(input.points) <= options.coplanar_thickness_ratio) {
    const PinResectionResult planar = ResectNearlyPlanar(input);
    if (planar.ok) {
      take(planar, "");
      return result;
    }
    why += "; " + planar.message;
  }
  std::string source;
  double focal_px = SharedLensFocalPx(project, image, &source);
  if (!(focal_px > 0.0)) {
    focal_px = KnownFocalPx(image, options);
    source = options.focal_px_by_image.count(image.id) ? "the photo's EXIF" : "the image's focal setting";
  }
  if (focal_px > 0.0) {
    const PinResectionResult pose = ResectWithKnownFocal(input, focal_px);
    if (pose.ok) {
      take(pose, " (f from " + source + ", held)");
      return result;
    }
    why += "; with f = " + Format("%.1f px", focal_px) + " from " + source + ": " + pose.message;
  } else {
    why += "; no focal length is known for it (share a lens with a calibrated photo, or give its focal length)";
  }
  result.message = why;
  return result;
}

ResectionResult Resect(const Project& project, const Image& image, const std::vector<const Pin*>& pins,
                       const MultiViewInitOptions& options) {
  ResectionResult result;
  std::vector<PointCorrespondence> points;
  std::vector<Id> ids;
  for (const Pin* pin : pins) {
    points.push_back({VertexInWorld(project, pin->vertex), pin->uv_px});
    ids.push_back(pin->id);
  }
  DltCalibrationOptions dlt_options;
  dlt_options.width_px = image.width_px;
  dlt_options.height_px = image.height_px;
  dlt_options.principal_point_mode = image.principal_point_mode;
  dlt_options.fixed_principal_point_px = image.fixed_principal_point_px;
  dlt_options.max_iterations = options.max_resection_iterations;
  if (image.focal_mode == FocalMode::kFixed && image.fixed_focal_px > 0.0) {
    dlt_options.fixed_focal_px = image.fixed_focal_px;
  } else if (image.focal_mode == FocalMode::kPrior && image.focal_prior_px > 0.0 && image.focal_prior_std_px > 0.0) {
    dlt_options.focal_prior_px = image.focal_prior_px;
    dlt_options.focal_prior_std_px = image.focal_prior_std_px;
    dlt_options.pixel_noise_px = options.resection_pixel_noise_px;
  }
  while (true) {
    DltCalibrationSummary dlt = CalibrateFromPoints(points, dlt_options);
    if (!dlt.IsUsable()) {
      ResectionResult other = ResectOtherwise(project, image, points, options, dlt.message);
      other.flagged.insert(other.flagged.begin(), result.flagged.begin(), result.flagged.end());
      return other;
    }
    // A focal length beyond any lens (f = 63,038 px was kept) is refused by name, never kept.
    if (const std::string refused = WhyResectedCameraRefused(
            dlt.camera,
            [&] {
              std::vector<Eigen::Vector3d> xyz;
              for (const PointCorrespondence& p : points) xyz.push_back(p.xyz);
              return xyz;
            }(),
            image.width_px, image.height_px);
        !refused.empty()) {
      ResectionResult other =
          ResectOtherwise(project, image, points, options,
                          std::string(dlt.planar ? "resection (planar)" : "resection") + " refused: " + refused);
      other.flagged.insert(other.flagged.begin(), result.flagged.begin(), result.flagged.end());
      return other;
    }
    const auto worst = std::max_element(dlt.residuals_px.begin(), dlt.residuals_px.end());
    const int min_points = dlt.planar ? 4 : 6;
    // A wrong click is dropped only while one redundant point remains to confirm the refit.
    if (!IsFinite(dlt.camera)) {
      result.message = "the resection gave a non-finite camera";
      return result;
    }
    if (worst == dlt.residuals_px.end() || *worst <= options.wrong_click_threshold_px ||
        static_cast<int>(points.size()) - 1 < min_points + 1) {
      if (worst != dlt.residuals_px.end() && *worst > options.wrong_click_threshold_px)
        result.warnings.push_back(Format("a pin reprojects %.1f px away, but too few pins remain to drop it", *worst));
      result.ok = true;
      result.camera = dlt.camera;
      result.rms_px = dlt.reprojection_rms_px;
      result.focal_std_px = dlt.focal_std_px;
      result.message = std::string(dlt.planar ? "resection (planar)" : "resection") + " from " +
                       std::to_string(points.size()) + " pins, f = " + Format("%.1f px", dlt.camera.focal_px) +
                       (dlt.focal_fixed        ? " (known, held)"
                        : dlt.focal_prior_used ? " (with the prior)"
                                               : "") +
                       ", RMS " + Format("%.3f px", dlt.reprojection_rms_px);
      for (const auto& w : dlt.warnings) result.warnings.push_back(w);
      return result;
    }
    const size_t drop = worst - dlt.residuals_px.begin();
    result.flagged.push_back(ids[drop]);
    points.erase(points.begin() + drop);
    ids.erase(ids.begin() + drop);
  }
}

// ---- (b) Two views ----

struct TwoViewResult {
  bool ok = false;
  std::string message;
  std::vector<std::string> warnings;
  Camera camera_b;  // in world; camera a is unchanged when calibrated
  Camera camera_a;  // in world (only applied when a was not calibrated)
  double rms_px = 0.0;
  std::vector<Id> flagged_a, flagged_b;
  MultiViewPairGeometry pair;
  bool guessed_a = false, guessed_b = false;
  bool plane = false;  // by the plane's homography
};

// The pixel a pinhole camera would see: a calibrated image's distortion removed (its K is
// known); an uncalibrated image is taken as pinhole.
Eigen::Vector2d PinholePixel(const Image& image, const Eigen::Vector2d& uv_px) {
  return image.camera_calibrated ? image.camera.UndistortPixel(uv_px) : uv_px;
}

Eigen::Vector3d TriangulateEuclidean(const Camera& a, const Camera& b, const Eigen::Vector2d& uv_a,
                                     const Eigen::Vector2d& uv_b, bool* ok) {
  const std::vector<Matrix34d> cameras = {a.ProjectionMatrix(), b.ProjectionMatrix()};
  Eigen::Vector4d x = TriangulateLinear(cameras, {uv_a.homogeneous(), uv_b.homogeneous()});
  x = RefineTriangulatedPoint(cameras, {uv_a, uv_b}, x);
  *ok = std::abs(x(3)) > 1e-12 * x.head<3>().norm();
  return *ok ? Eigen::Vector3d(x.head<3>() / x(3)) : Eigen::Vector3d::Zero();
}

// The model's positions of the shared vertices lie on one plane: their thickness (smallest
// singular value of the centred points) is below ratio times their extent (the largest).
bool OnOnePlane(const std::vector<Eigen::Vector3d>& points, double ratio) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : points) mean += p;
  mean /= static_cast<double>(points.size());
  Eigen::MatrixXd centred(points.size(), 3);
  for (size_t i = 0; i < points.size(); ++i) centred.row(i) = (points[i] - mean).transpose();
  const Eigen::Vector3d s = Eigen::JacobiSVD<Eigen::MatrixXd>(centred).singularValues();
  return s(0) > 0.0 && s(2) <= ratio * s(0);
}

// How far the inliers triangulated by two reconstruction cameras are from the model's
// positions after the best similarity, as an RMS relative to the model's spread; infinity
// when they cannot be aligned.
double ModelMisfit(const Camera& recon_a, const Camera& recon_b, const std::vector<Eigen::Vector2d>& uv_a,
                   const std::vector<Eigen::Vector2d>& uv_b, const std::vector<Eigen::Vector3d>& model,
                   const std::vector<bool>& inliers) {
  std::vector<Eigen::Vector3d> recon, target;
  for (size_t i = 0; i < uv_a.size(); ++i) {
    if (!inliers[i]) continue;
    bool ok = false;
    const Eigen::Vector3d x = TriangulateEuclidean(recon_a, recon_b, uv_a[i], uv_b[i], &ok);
    if (!ok) continue;
    recon.push_back(x);
    target.push_back(model[i]);
  }
  Similarity3d sim;
  const double spread = RmsSpread(target);
  if (recon.size() < 3 || !(spread > 0.0) || !AlignSimilarity(recon, target, &sim))
    return std::numeric_limits<double>::infinity();
  double sum = 0.0;
  for (size_t i = 0; i < recon.size(); ++i)
    sum += (sim.scale * sim.rotation * recon[i] + sim.translation - target[i]).squaredNorm();
  return std::sqrt(sum / recon.size()) / spread;
}

// The vertices pinned in both images, in the same order on both sides.
struct PinMatches {
  std::vector<const Pin*> pins_a, pins_b;
  std::vector<Eigen::Vector2d> uv_a, uv_b;  // pinhole pixels
  std::vector<Eigen::Vector3d> model;       // the matched vertices in the world
};

PinMatches MatchPins(const Project& project, const Image& image_a, const std::vector<const Pin*>& pins_a,
                     const Image& image_b, const std::vector<const Pin*>& pins_b) {
  PinMatches matches;
  std::map<VertexKey, const Pin*> in_b;
  for (const Pin* pin : pins_b) in_b[KeyOf(pin->vertex)] = pin;
  for (const Pin* pin : pins_a) {
    const auto it = in_b.find(KeyOf(pin->vertex));
    if (it == in_b.end()) continue;
    matches.pins_a.push_back(pin);
    matches.pins_b.push_back(it->second);
    matches.uv_a.push_back(PinholePixel(image_a, pin->uv_px));
    matches.uv_b.push_back(PinholePixel(image_b, it->second->uv_px));
  }
  for (const Pin* pin : matches.pins_a) matches.model.push_back(VertexInWorld(project, pin->vertex));
  return matches;
}

// The two images with their intrinsics, as the relative-pose estimators see them.
struct ViewPair {
  const Image& image_a;
  const Image& image_b;
  const Camera& intrinsics_a;
  const Camera& intrinsics_b;
};

// The relative pose (b from a, unit baseline) and the clicks it keeps.
struct RelativePoseEstimate {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  std::vector<bool> inliers;
  std::string method;
  Eigen::Matrix3d estimated_f = Eigen::Matrix3d::Zero();  // F's path: the estimated F, for display
};

// By the fundamental matrix; false (result->message says why) when it fails.
bool PoseFromFundamental(const ViewPair& views, const PinMatches& matches, const MultiViewInitOptions& options,
                         TwoViewResult* result, RelativePoseEstimate* estimate) {
  const Image& image_a = views.image_a;
  const Image& image_b = views.image_b;
  FundamentalOptions f_options = options.fundamental;
  f_options.inlier_threshold_px = options.wrong_click_threshold_px;
  const FundamentalSummary f = EstimateFundamentalMatrix(matches.uv_a, matches.uv_b, f_options);
  if (!f.IsUsable()) {
    result->message = "fundamental matrix of " + Quoted(image_a) + " and " + Quoted(image_b) + ": " + f.message;
    return false;
  }
  for (const auto& w : f.warnings) result->warnings.push_back("F: " + w);
  const RelativePoseSummary pose = EstimateRelativePose(f.F, views.intrinsics_a.K(), views.intrinsics_b.K(),
                                                        matches.uv_a, matches.uv_b, f.inliers, options.relative_pose);
  if (!pose.IsUsable()) {
    result->message = "relative pose of " + Quoted(image_b) + " to " + Quoted(image_a) + ": " + pose.message;
    return false;
  }
  for (const auto& w : pose.warnings) result->warnings.push_back("pose: " + w);
  estimate->rotation = pose.cam2_from_cam1_rotation;
  estimate->translation = pose.cam2_from_cam1_translation;
  estimate->inliers = f.inliers;
  estimate->estimated_f = f.F;
  estimate->method = std::to_string(f.num_inliers) + " of " + std::to_string(matches.uv_a.size()) + " correspondences";
  return true;
}

// By the homography of one plane; false (result->message says why) when it fails.
bool PoseFromPlane(const ViewPair& views, const PinMatches& matches, const MultiViewInitOptions& options,
                   TwoViewResult* result, RelativePoseEstimate* estimate) {
  const Image& image_a = views.image_a;
  const Image& image_b = views.image_b;
  HomographyPoseOptions h_options;
  h_options.homography = options.homography;
  h_options.homography.inlier_threshold_px = options.wrong_click_threshold_px;
  const HomographyPoseSummary pose =
      EstimatePlanePose(matches.uv_a, matches.uv_b, views.intrinsics_a.K(), views.intrinsics_b.K(), h_options);
  if (!pose.IsUsable()) {
    result->message = "two views of one plane (" + Quoted(image_a) + " and " + Quoted(image_b) + "): " + pose.message;
    return false;
  }
  if (pose.pure_rotation) {
    result->message = "two views of one plane (" + Quoted(image_a) + " and " + Quoted(image_b) +
                      "): the cameras share their centre (a pure rotation): no baseline to place them";
    return false;
  }
  for (const auto& w : pose.warnings)
    if (!pose.ambiguous || w.find("ambiguous") == std::string::npos) result->warnings.push_back("plane: " + w);
  estimate->inliers = pose.homography.inliers;
  // Several decompositions reproduce H: the model, which knows the plane, picks the one whose
  // triangulated vertices it fits best (a similarity, relative to the vertices' spread).
  const PlanePose* chosen = &pose.candidates[0];
  if (pose.ambiguous) {
    std::vector<double> misfit;
    for (const PlanePose& candidate : pose.candidates) {
      Camera recon_a = views.intrinsics_a, recon_b = views.intrinsics_b;
      recon_a.cam_from_world_rotation.setIdentity();
      recon_a.cam_from_world_translation.setZero();
      recon_b.cam_from_world_rotation = candidate.cam2_from_cam1_rotation;
      recon_b.cam_from_world_translation = candidate.cam2_from_cam1_translation;
      misfit.push_back(ModelMisfit(recon_a, recon_b, matches.uv_a, matches.uv_b, matches.model, estimate->inliers));
    }
    const size_t best = std::min_element(misfit.begin(), misfit.end()) - misfit.begin();
    chosen = &pose.candidates[best];
    std::vector<double> others = misfit;
    others.erase(others.begin() + best);
    const double second = *std::min_element(others.begin(), others.end());
    result->warnings.push_back("plane: " + std::to_string(pose.candidates.size()) +
                               " poses explain the clicks; the model's vertices chose one (misfit " +
                               Format("%.3g", misfit[best]) + " against " + Format("%.3g", second) +
                               " of their spread)");
    if (!(second > 2.0 * misfit[best] + 1e-3))
      result->warnings.push_back(
          "plane: the model hardly tells the poses apart: the camera may be the mirror "
          "pose; pin a vertex off the face");
  }
  estimate->rotation = chosen->cam2_from_cam1_rotation;
  estimate->translation = chosen->cam2_from_cam1_translation;
  result->plane = true;
  estimate->method = "one plane (homography), " + std::to_string(pose.homography.num_inliers) + " of " +
                     std::to_string(matches.uv_a.size()) + " correspondences";
  return true;
}

// a is the calibrated image when one of them is.
TwoViewResult TwoViews(const Project& project, const Image& image_a, const std::vector<const Pin*>& pins_a,
                       const Image& image_b, const std::vector<const Pin*>& pins_b,
                       const MultiViewInitOptions& options) {
  TwoViewResult result;
  result.pair.image_a = image_a.id;
  result.pair.image_b = image_b.id;
  const PinMatches matches = MatchPins(project, image_a, pins_a, image_b, pins_b);
  const std::vector<Eigen::Vector2d>& uv_a = matches.uv_a;
  const std::vector<Eigen::Vector2d>& uv_b = matches.uv_b;
  result.pair.num_correspondences = static_cast<int>(uv_a.size());
  const bool on_one_plane = uv_a.size() >= 4 && OnOnePlane(matches.model, options.coplanar_thickness_ratio);
  if (uv_a.size() < 4 || (uv_a.size() < 7 && !on_one_plane)) {
    result.message = std::to_string(uv_a.size()) + " vertices pinned in both " + Quoted(image_a) + " and " +
                     Quoted(image_b) + "; two views need 7 (8 to flag wrong clicks), or 4 on one face";
    return result;
  }
  for (const Image* image : {&image_a, &image_b})
    if (!image->camera_calibrated && (image->width_px <= 0 || image->height_px <= 0)) {
      result.message = Quoted(*image) + " has no size: its principal point is unknown";
      return result;
    }
  const Camera intrinsics_a = IntrinsicsFor(image_a, options, &result.guessed_a);
  const Camera intrinsics_b = IntrinsicsFor(image_b, options, &result.guessed_b);

  // The relative pose (b from a, unit baseline) and its inliers, by F or by the plane.
  const ViewPair views{image_a, image_b, intrinsics_a, intrinsics_b};
  RelativePoseEstimate estimate;
  const bool estimated = on_one_plane ? PoseFromPlane(views, matches, options, &result, &estimate)
                                      : PoseFromFundamental(views, matches, options, &result, &estimate);
  if (!estimated) return result;
  const std::vector<bool>& inliers = estimate.inliers;
  int num_inliers = 0;
  for (size_t i = 0; i < uv_a.size(); ++i) {
    if (inliers[i]) {
      ++num_inliers;
      continue;
    }
    result.flagged_a.push_back(matches.pins_a[i]->id);
    result.flagged_b.push_back(matches.pins_b[i]->id);
  }
  result.pair.num_inliers = num_inliers;

  // The reconstruction frame: camera a at the origin, unit baseline.
  Camera recon_a = intrinsics_a, recon_b = intrinsics_b;
  recon_a.cam_from_world_rotation.setIdentity();
  recon_a.cam_from_world_translation.setZero();
  recon_b.cam_from_world_rotation = estimate.rotation;
  recon_b.cam_from_world_translation = estimate.translation;
  const Eigen::Matrix3d pose_f = NormalizeFundamental(FundamentalFromCameras(recon_a, recon_b));
  result.pair.F = result.plane ? pose_f : estimate.estimated_f;
  const double epipolar_rms_px = SymmetricEpipolarRms(pose_f, uv_a, uv_b, inliers);
  std::vector<Eigen::Vector3d> recon_points, model_points;
  for (size_t i = 0; i < uv_a.size(); ++i) {
    if (!inliers[i]) continue;
    bool ok = false;
    const Eigen::Vector3d x = TriangulateEuclidean(recon_a, recon_b, uv_a[i], uv_b[i], &ok);
    if (!ok) continue;
    recon_points.push_back(x);
    model_points.push_back(matches.model[i]);
  }

  std::string gauge;
  Similarity3d world_from_recon;
  if (image_a.camera_calibrated) {
    world_from_recon = KeepCameraSimilarity(recon_a, image_a.camera, SpreadScale(recon_points, model_points));
    gauge = Quoted(image_a) + " kept where it was, baseline scaled to the model";
  } else {
    world_from_recon = ChooseGauge(recon_points, model_points, recon_a, image_a.camera, options.gauge, &gauge);
  }
  result.camera_a = MoveCamera(recon_a, world_from_recon);
  result.camera_b = MoveCamera(recon_b, world_from_recon);
  if (!IsFinite(result.camera_a) || !IsFinite(result.camera_b)) {
    result.message = "two views of " + Quoted(image_a) + " and " + Quoted(image_b) + " gave a non-finite camera";
    return result;
  }
  result.rms_px = epipolar_rms_px;
  result.ok = true;
  result.message = "two views with " + Quoted(image_a) + " and " + Quoted(image_b) + ": " + estimate.method +
                   ", epipolar RMS " + Format("%.3f px", epipolar_rms_px) + "; " + gauge;
  return result;
}

// ---- (c) Self-calibration ----

struct SelfCalibrationResult {
  bool ok = false;
  std::string message;
  std::vector<std::string> warnings;
  std::vector<bool> registered;
  std::vector<Camera> cameras;  // world
  std::vector<double> rms_px;
  std::vector<double> focal_std_px;
  std::vector<std::vector<Id>> flagged;
  std::vector<bool> guessed;
};

SelfCalibrationResult SelfCalibrateImages(const Project& project, const std::vector<const Image*>& images,
                                          const std::vector<std::vector<const Pin*>>& pins,
                                          const MultiViewInitOptions& options) {
  SelfCalibrationResult result;
  const int n = static_cast<int>(images.size());
  result.rms_px.assign(n, 0.0);
  result.flagged.assign(n, {});
  result.guessed.assign(n, true);
  std::vector<SelfCalibrationView> views(n);
  for (int v = 0; v < n; ++v) {
    views[v].width_px = images[v]->width_px;
    views[v].height_px = images[v]->height_px;
    views[v].focal_prior_px = KnownFocalPx(*images[v], options);
    result.guessed[v] = !(views[v].focal_prior_px > 0.0);
  }
  // Tracks of the vertices pinned in two or more of the images.
  std::map<VertexKey, std::vector<std::pair<int, const Pin*>>> by_vertex;
  for (int v = 0; v < n; ++v)
    for (const Pin* pin : pins[v]) by_vertex[KeyOf(pin->vertex)].push_back({v, pin});
  std::vector<Track> tracks;
  std::vector<std::vector<std::pair<int, const Pin*>>> track_pins;
  std::vector<VertexRef> track_vertices;
  for (const auto& [key, observations] : by_vertex) {
    if (observations.size() < 2) continue;
    Track track;
    for (const auto& [v, pin] : observations) track.push_back({v, pin->uv_px});
    tracks.push_back(std::move(track));
    track_pins.push_back(observations);
    track_vertices.push_back(observations.front().second->vertex);
  }
  SelfCalibrationOptions sc_options = options.self_calibration;
  sc_options.inlier_threshold_px = options.wrong_click_threshold_px;
  const SelfCalibrationSummary sc = SelfCalibrate(views, tracks, sc_options);
  if (!sc.IsUsable()) {
    result.message = "self-calibration of " + std::to_string(n) + " images from " + std::to_string(tracks.size()) +
                     " shared vertices: " + sc.message;
    return result;
  }
  result.warnings = sc.warnings;

  std::vector<Eigen::Vector3d> recon_points, model_points;
  for (size_t t = 0; t < tracks.size(); ++t) {
    if (!sc.triangulated[t]) continue;
    recon_points.push_back(sc.points[t]);
    model_points.push_back(VertexInWorld(project, track_vertices[t]));
  }
  int first = -1;
  for (int v = 0; v < n && first < 0; ++v)
    if (sc.registered[v]) first = v;
  std::string gauge;
  const Similarity3d world_from_recon =
      ChooseGauge(recon_points, model_points, sc.cameras[first], images[first]->camera, options.gauge, &gauge);

  result.registered = sc.registered;
  result.focal_std_px = sc.focal_std_px;
  result.focal_std_px.resize(n, 0.0);
  result.cameras.resize(n);
  std::vector<double> sum_sq(n, 0.0);
  std::vector<int> count(n, 0);
  for (size_t t = 0; t < tracks.size(); ++t) {
    if (!sc.triangulated[t]) continue;  // a track left out says nothing of one click alone
    for (const auto& [v, pin] : track_pins[t]) {
      if (!sc.registered[v]) continue;
      const Camera& camera = sc.cameras[v];
      const bool in_front = camera.CamFromWorld(sc.points[t]).z() > 0;
      const double error =
          in_front ? (camera.Project(sc.points[t]) - pin->uv_px).norm() : std::numeric_limits<double>::infinity();
      if (error > options.wrong_click_threshold_px) {
        result.flagged[v].push_back(pin->id);
      } else {
        sum_sq[v] += error * error;
        ++count[v];
      }
    }
  }
  for (int v = 0; v < n; ++v) {
    if (!sc.registered[v]) continue;
    result.cameras[v] = MoveCamera(sc.cameras[v], world_from_recon);
    if (!IsFinite(result.cameras[v])) result.registered[v] = false;
    result.rms_px[v] = count[v] > 0 ? std::sqrt(sum_sq[v] / count[v]) : 0.0;
  }
  result.ok = true;
  result.message = "self-calibration of " + std::to_string(n) + " images from " + std::to_string(tracks.size()) +
                   " shared vertices, RMS " + Format("%.3f px", sc.reprojection_rms_px) + "; " + gauge;
  return result;
}

// What the initialisation paths share: the input, its usable pins, and what they write.
struct PinInitContext {
  const Project& project;
  const MultiViewInitOptions& options;
  const std::vector<std::vector<const Pin*>>& pins;  // usable pins, per project image
  Project* out;
  MultiViewInitSummary* summary;
  // Why resection did not apply, per image, to prefix a later failure; each later path that
  // does not apply appends its reason.
  std::vector<std::string>* notes;
};

void AppendFailure(const PinInitContext& ctx, int i, const std::string& reason) { (*ctx.notes)[i] += "; " + reason; }

// Resects each uncalibrated image with enough pins on `known` vertices and reports every
// image; returns the uncalibrated images with pins that resection did not initialise.
std::vector<int> InitializeByResection(const PinInitContext& ctx, const std::set<VertexKey>& known) {
  const Project& project = ctx.project;
  std::vector<int> left;
  for (size_t i = 0; i < project.images.size(); ++i) {
    const Image& image = project.images[i];
    const std::vector<const Pin*>& pins = ctx.pins[i];
    std::string& note = (*ctx.notes)[i];
    MultiViewImageReport report;
    report.image_id = image.id;
    report.image_path = image.path;
    report.num_pins = static_cast<int>(pins.size());
    std::vector<const Pin*> known_pins;
    for (const Pin* pin : pins)
      if (known.count(KeyOf(pin->vertex))) known_pins.push_back(pin);
    report.num_known_pins = static_cast<int>(known_pins.size());
    if (image.camera_calibrated) {
      report.path = MultiViewInitPath::kAlreadyCalibrated;
      report.message = "already calibrated";
    } else if (pins.empty()) {
      report.message = "no pins";
    } else if (known_pins.size() >= 4) {
      ResectionResult r = Resect(project, image, known_pins, ctx.options);
      if (r.ok) {
        SetCamera(&ctx.out->images[i], r.camera);
        report.path = MultiViewInitPath::kResection;
        report.initialized = true;
        report.residual_px = r.rms_px;
        report.focal_px = r.camera.focal_px;
        report.focal_std_px = r.focal_std_px;
        report.flagged_pins = r.flagged;
        report.warnings = r.warnings;
        report.message = r.message;
      } else if (known_pins.size() < 6) {
        // The DLT found them off one plane: the count is what the user must change.
        note = std::to_string(known_pins.size()) +
               " pins on known vertices; resection needs 6, or 4 on one face, or 4 with a known focal length (" +
               r.message + ")";
        left.push_back(static_cast<int>(i));
      } else {
        note = std::to_string(known_pins.size()) + " pins on known vertices, resection failed (" + r.message + ")";
        left.push_back(static_cast<int>(i));
      }
    } else if (known_pins.empty()) {
      note = "none of its " + std::to_string(pins.size()) +
             " pins is on a vertex pinned in a calibrated image (resection needs 6, or 4 on one face)";
      left.push_back(static_cast<int>(i));
    } else {
      note = std::to_string(known_pins.size()) + " pins on known vertices; resection needs 6, or 4 on one face";
      left.push_back(static_cast<int>(i));
    }
    ctx.summary->images.push_back(std::move(report));
  }
  return left;
}

// Initialises whichever of images ia and ib is uncalibrated from the two views.
void ApplyTwoViews(const PinInitContext& ctx, int ia, int ib) {
  Project* out = ctx.out;
  // Image a is the calibrated one when there is one (it keeps its pose).
  if (out->images[ib].camera_calibrated) std::swap(ia, ib);
  const Image& image_a = out->images[ia];
  const Image& image_b = out->images[ib];
  TwoViewResult r = TwoViews(ctx.project, image_a, ctx.pins[ia], image_b, ctx.pins[ib], ctx.options);
  std::vector<int> targets;
  for (int i : {ia, ib})
    if (!out->images[i].camera_calibrated) targets.push_back(i);
  if (!r.ok) {
    for (int i : targets) AppendFailure(ctx, i, r.message);
    return;
  }
  ctx.summary->pairs.push_back(r.pair);
  for (int i : targets) {
    const bool is_a = i == ia;
    const Camera& camera = is_a ? r.camera_a : r.camera_b;
    SetCamera(&out->images[i], camera);
    MultiViewImageReport& report = ctx.summary->images[i];
    report.path = MultiViewInitPath::kTwoView;
    report.initialized = true;
    report.partner_image_id = out->images[is_a ? ib : ia].id;
    report.residual_px = r.rms_px;
    report.focal_px = camera.focal_px;
    report.focal_guessed = is_a ? r.guessed_a : r.guessed_b;
    report.flagged_pins = is_a ? r.flagged_a : r.flagged_b;
    report.two_view_plane = r.plane;
    report.warnings = r.warnings;
    report.message = r.message;
  }
}

int SharedVertices(const std::vector<const Pin*>& pins_a, const std::vector<const Pin*>& pins_b) {
  std::set<VertexKey> in_a;
  for (const Pin* pin : pins_a) in_a.insert(KeyOf(pin->vertex));
  int shared = 0;
  for (const Pin* pin : pins_b) shared += static_cast<int>(in_a.count(KeyOf(pin->vertex)));
  return shared;
}

// Self-calibrates the images resection left (three or more) together.
void ApplySelfCalibration(const PinInitContext& ctx, const std::vector<int>& left) {
  std::vector<const Image*> images;
  std::vector<std::vector<const Pin*>> image_pins;
  for (int i : left) {
    images.push_back(&ctx.project.images[i]);
    image_pins.push_back(ctx.pins[i]);
  }
  SelfCalibrationResult r = SelfCalibrateImages(ctx.project, images, image_pins, ctx.options);
  for (size_t v = 0; v < left.size(); ++v) {
    const int i = left[v];
    if (!r.ok || !r.registered[v]) {
      AppendFailure(
          ctx, i, r.ok ? "not registered by the self-calibration of the others (too few shared vertices)" : r.message);
      continue;
    }
    SetCamera(&ctx.out->images[i], r.cameras[v]);
    MultiViewImageReport& report = ctx.summary->images[i];
    report.path = MultiViewInitPath::kSelfCalibration;
    report.initialized = true;
    report.residual_px = r.rms_px[v];
    report.focal_px = r.cameras[v].focal_px;
    report.focal_std_px = r.focal_std_px[v];
    report.focal_guessed = r.guessed[v];
    report.flagged_pins = r.flagged[v];
    report.warnings = r.warnings;
    report.message = r.message;
  }
}

// Two views for what self-calibration did not initialise.
void ApplyTwoViewsToTheRest(const PinInitContext& ctx, const std::vector<int>& left) {
  const Project* out = ctx.out;
  // Self-calibration failed for all: the pair sharing the most vertices may still do.
  const bool none_initialised =
      std::none_of(left.begin(), left.end(), [&](int i) { return out->images[i].camera_calibrated; });
  if (left.size() >= 3 && none_initialised) {
    int best_a = -1, best_b = -1, best_shared = 0;
    for (size_t a = 0; a < left.size(); ++a)
      for (size_t b = a + 1; b < left.size(); ++b) {
        const int shared = SharedVertices(ctx.pins[left[a]], ctx.pins[left[b]]);
        if (shared > best_shared) {
          best_a = left[a];
          best_b = left[b];
          best_shared = shared;
        }
      }
    if (best_a >= 0) ApplyTwoViews(ctx, best_a, best_b);
  }
  // Whatever is still uncalibrated pairs with the calibrated image (at input, or initialised
  // above) it shares the most pinned vertices with.
  for (const int i : left) {
    if (out->images[i].camera_calibrated) continue;
    int best = -1, best_shared = 0;
    for (int j = 0; j < static_cast<int>(ctx.project.images.size()); ++j) {
      if (j == i || !out->images[j].camera_calibrated) continue;
      const int shared = SharedVertices(ctx.pins[i], ctx.pins[j]);
      if (shared > best_shared) {
        best = j;
        best_shared = shared;
      }
    }
    if (best >= 0)
      ApplyTwoViews(ctx, i, best);
    else if (left.size() == 1)
      AppendFailure(ctx, i, "no calibrated image shares a pinned vertex with it");
  }
}

}  // namespace

bool MultiViewInitOptions::Check(std::string* error) const {
  auto fail = [&](const std::string& message) {
    if (error) *error = message;
    return false;
  };
  if (!(wrong_click_threshold_px > 0.0) || !std::isfinite(wrong_click_threshold_px))
    return fail("wrong_click_threshold_px must be positive");
  if (!(default_focal_factor > 0.0) || !std::isfinite(default_focal_factor))
    return fail("default_focal_factor must be positive");
  if (max_resection_iterations < 1) return fail("max_resection_iterations must be at least 1");
  for (const auto& [id, focal] : focal_px_by_image)
    if (!(focal > 0.0) || !std::isfinite(focal)) return fail("focal_px_by_image: focal lengths must be positive");
  std::string sub;
  FundamentalOptions f = fundamental;
  f.inlier_threshold_px = wrong_click_threshold_px;
  if (!f.Check(&sub)) return fail("fundamental: " + sub);
  if (!relative_pose.Check(&sub)) return fail("relative_pose: " + sub);
  HomographyOptions h = homography;
  h.inlier_threshold_px = wrong_click_threshold_px;
  if (!h.Check(&sub)) return fail("homography: " + sub);
  if (!(coplanar_thickness_ratio >= 0.0) || !(coplanar_thickness_ratio < 1.0))
    return fail("coplanar_thickness_ratio must be in [0, 1)");
  if (!(resection_pixel_noise_px > 0.0) || !std::isfinite(resection_pixel_noise_px))
    return fail("resection_pixel_noise_px must be positive");
  SelfCalibrationOptions sc = self_calibration;
  sc.inlier_threshold_px = wrong_click_threshold_px;
  if (!sc.Check(&sub)) return fail("self_calibration: " + sub);
  return true;
}

const char* MultiViewInitPathName(MultiViewInitPath path) {
  switch (path) {
    case MultiViewInitPath::kNone: return "none";
    case MultiViewInitPath::kAlreadyCalibrated: return "calibrated";
    case MultiViewInitPath::kResection: return "resection";
    case MultiViewInitPath::kTwoView: return "two views";
    case MultiViewInitPath::kSelfCalibration: return "self-calibration";
  }
  return "?";
}

const MultiViewImageReport* MultiViewInitSummary::Find(Id image_id) const {
  for (const auto& report : images)
    if (report.image_id == image_id) return &report;
  return nullptr;
}

MultiViewInitSummary CalibrateImagesFromPins(const Project& project, const MultiViewInitOptions& options,
                                             Project* out) {
  const auto start = std::chrono::steady_clock::now();
  MultiViewInitSummary summary;
  *out = project;
  std::string error;
  if (!options.Check(&error)) {
    return internal::FailedSummary(summary, "invalid options: " + error, start, SolverTermination::kInvalidInput);
  }
  summary.termination = SolverTermination::kConverged;

  // Vertices the current model places: pinned in an image calibrated at input.
  std::set<VertexKey> known;
  std::vector<std::vector<const Pin*>> pins(project.images.size());
  for (size_t i = 0; i < project.images.size(); ++i) {
    pins[i] = UsablePins(project, project.images[i].id);
    if (project.images[i].camera_calibrated)
      for (const Pin* pin : pins[i]) known.insert(KeyOf(pin->vertex));
  }

  std::vector<std::string> resection_notes(project.images.size());
  const PinInitContext ctx{project, options, pins, out, &summary, &resection_notes};
  // Uncalibrated images with pins that resection did not initialise.
  const std::vector<int> left = InitializeByResection(ctx, known);
  if (left.size() >= 3)
    ApplySelfCalibration(ctx, left);
  else if (left.size() == 2)
    ApplyTwoViews(ctx, left[0], left[1]);
  ApplyTwoViewsToTheRest(ctx, left);
  for (const int i : left) {
    if (out->images[i].camera_calibrated) continue;
    summary.images[i].message = resection_notes[i];
    summary.messages.push_back(Quoted(project.images[i]) + ": " + resection_notes[i]);
  }

  for (const auto& report : summary.images) summary.num_initialized += report.initialized ? 1 : 0;
  summary.message = std::to_string(summary.num_initialized) + " image(s) initialised from pins" +
                    (summary.messages.empty() ? "" : ", " + std::to_string(summary.messages.size()) + " could not be");
  summary.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

Eigen::Matrix3d FundamentalFromCameras(const Camera& camera_a, const Camera& camera_b) {
  const Eigen::Matrix3d rotation = camera_b.cam_from_world_rotation * camera_a.cam_from_world_rotation.transpose();
  const Eigen::Vector3d t = camera_b.cam_from_world_translation - rotation * camera_a.cam_from_world_translation;
  if (!(t.norm() > 0.0)) return Eigen::Matrix3d::Zero();
  Eigen::Matrix3d tx;
  tx << 0, -t.z(), t.y(), t.z(), 0, -t.x(), -t.y(), t.x(), 0;
  return camera_b.K().inverse().transpose() * tx * rotation * camera_a.K().inverse();
}

EpipolePair EpipolesOfCameras(const Camera& camera_a, const Camera& camera_b) {
  EpipolePair out;
  const Eigen::Vector3d center_a = camera_a.CenterInWorld(), center_b = camera_b.CenterInWorld();
  if (!((center_a - center_b).norm() > 0.0)) return out;
  out.in_a = (camera_a.K() * camera_a.CamFromWorld(center_b)).normalized();
  out.in_b = (camera_b.K() * camera_b.CamFromWorld(center_a)).normalized();
  return out;
}

EpipolarLine EpipolarLineInImage(const Eigen::Matrix3d& F, const Eigen::Vector2d& uv_a_px, int width_b_px,
                                 int height_b_px) {
  EpipolarLine result;
  const Eigen::Vector3d line = F * uv_a_px.homogeneous();
  const double norm = line.head<2>().norm();
  if (!(norm > 1e-12 * line.norm()) || !line.allFinite()) return result;
  result.line = line / norm;
  const Eigen::Vector3d& l = result.line;
  const double x0 = -0.5, y0 = -0.5, x1 = width_b_px - 0.5, y1 = height_b_px - 0.5;
  if (!(x1 > x0) || !(y1 > y0)) return result;
  // Intersections with the four edges that fall on the rectangle (a relative slack keeps a
  // corner hit).
  const double slack = 1e-9 * std::max(x1 - x0, y1 - y0);
  std::vector<Eigen::Vector2d> hits;
  for (const double x : {x0, x1})
    if (std::abs(l.y()) > 1e-15) {
      const double y = -(l.x() * x + l.z()) / l.y();
      if (y >= y0 - slack && y <= y1 + slack) hits.emplace_back(x, std::clamp(y, y0, y1));
    }
  for (const double y : {y0, y1})
    if (std::abs(l.x()) > 1e-15) {
      const double x = -(l.y() * y + l.z()) / l.x();
      if (x >= x0 - slack && x <= x1 + slack) hits.emplace_back(std::clamp(x, x0, x1), y);
    }
  double best = 0.0;
  for (size_t i = 0; i < hits.size(); ++i)
    for (size_t j = i + 1; j < hits.size(); ++j) {
      const double d = (hits[i] - hits[j]).norm();
      if (d > best) {
        best = d;
        result.segment_px = std::make_pair(hits[i], hits[j]);
      }
    }
  // A line touching a corner only is a point, not a segment to draw.
  if (best <= slack) result.segment_px.reset();
  return result;
}

}  // namespace facet
