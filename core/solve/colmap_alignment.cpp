#include "core/solve/colmap_alignment.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <set>

#include <Eigen/Geometry>
#include <Eigen/SVD>

#include "core/estimators/projective_upgrade.h"
#include "core/estimators/vanishing_point.h"
#include "core/solve/world_frames.h"
#include "core/util/format.h"

namespace facet {
namespace {

using internal::FormatNumber;

constexpr double kRadToDeg = 180.0 / M_PI;
constexpr double kTwoPi = 2.0 * M_PI;
// Two known lengths that give scales further apart than this (relative) are worth a warning.
constexpr double kKnownLengthDisagreement = 0.05;
// A box's kept size is a known length only while its corners 0 and 2^k still span it.
constexpr double kBoxCornerTolerance = 1e-6;
// A photo's line family further than this from every world axis the aligned camera could give
// it leaves its turn unchosen.
constexpr double kMaxTurnErrorDeg = 20.0;
// A direction whose horizontal part is shorter than this is no horizontal family's.
constexpr double kMinHorizontalPart = 0.5;

double RotationAngleDeg(const Eigen::Matrix3d& r) { return Eigen::AngleAxisd(r).angle() * kRadToDeg; }

std::string Plural(int n, const std::string& one, const std::string& many) {
  return std::to_string(n) + " " + (n == 1 ? one : many);
}

// The rotation nearest (Frobenius) to a sum of rotations: their chordal L2 mean.
Eigen::Matrix3d NearestRotation(const Eigen::Matrix3d& sum) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(sum, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Vector3d signs(1.0, 1.0, 1.0);
  if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0) signs(2) = -1.0;
  return svd.matrixU() * signs.asDiagonal() * svd.matrixV().transpose();
}

// RMS distance of points from their mean, and the mean.
double Spread(const std::vector<Eigen::Vector3d>& points, Eigen::Vector3d* mean) {
  *mean = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : points) *mean += p;
  *mean /= static_cast<double>(points.size());
  double sum = 0.0;
  for (const Eigen::Vector3d& p : points) sum += (p - *mean).squaredNorm();
  return std::sqrt(sum / static_cast<double>(points.size()));
}

bool Distinct(const std::vector<Eigen::Vector3d>& points, double tolerance) {
  if (points.size() < 2) return false;
  Eigen::Vector3d mean;
  const double spread = Spread(points, &mean);
  return spread > tolerance * (1.0 + mean.norm());
}

// The vertex's position in the frame of the cameras of `images` (in `project`), triangulated
// from its pins in them: two or more, from distinct centres, the point in front of each.
bool TriangulateVertex(const Project& project, const std::set<Id>& images, const VertexRef& vertex,
                       Eigen::Vector3d* point) {
  std::vector<Matrix34d> cameras;
  std::vector<Eigen::Vector3d> rays;
  std::vector<Eigen::Vector2d> uvs;
  std::vector<const Camera*> used;
  for (const Pin& pin : project.pins) {
    if (!(pin.vertex == vertex) || !images.count(pin.image_id)) continue;
    const Image* image = project.FindImage(pin.image_id);
    if (image == nullptr) continue;
    const Eigen::Vector2d uv = image->camera.UndistortPixel(pin.uv_px);
    cameras.push_back(image->camera.ProjectionMatrix());
    rays.push_back(uv.homogeneous());
    uvs.push_back(uv);
    used.push_back(&image->camera);
  }
  if (cameras.size() < 2) return false;
  std::vector<Eigen::Vector3d> centers;
  for (const Camera* c : used) centers.push_back(c->CenterInWorld());
  if (!Distinct(centers, 1e-12)) return false;
  Eigen::Vector4d x = TriangulateLinear(cameras, rays);
  x = RefineTriangulatedPoint(cameras, uvs, x);
  if (!(std::abs(x(3)) > 1e-12 * x.head<3>().norm())) return false;
  *point = x.head<3>() / x(3);
  if (!point->allFinite()) return false;
  for (const Camera* c : used)
    if (!(c->CamFromWorld(*point).z() > 0.0)) return false;
  return true;
}

struct KnownLength {
  VertexRef a, b;
  double value = 0.0;
};

// The project's known lengths: distance constraints, and the kept sizes of boxes whose
// corners 0 and 2^k still span them.
std::vector<KnownLength> KnownLengths(const Project& project) {
  std::vector<KnownLength> lengths;
  for (const Constraint& c : project.constraints) {
    if (c.kind != ConstraintKind::kDistance || c.vertices.size() != 2 || !(c.value > 0.0)) continue;
    lengths.push_back({c.vertices[0], c.vertices[1], c.value});
  }
  for (const Primitive& p : project.primitives) {
    if (p.shape.kind != PrimitiveKind::kBox) continue;
    for (int k = 0; k < 3; ++k) {
      if (!p.param_locked[k]) continue;
      const VertexRef a{p.id, 0}, b{p.id, static_cast<VertexId>(1u << k)};
      const double size = std::abs(p.shape.params(k));
      if (!(size > 0.0) || !project.FindVertex(a) || !project.FindVertex(b)) continue;
      const double spans = (VertexInWorld(project, a) - VertexInWorld(project, b)).norm();
      if (std::abs(spans - size) > kBoxCornerTolerance * size) continue;
      lengths.push_back({a, b, size});
    }
  }
  return lengths;
}

// The scale from the known lengths seen by the reconstruction (the median of their ratios),
// or false when none is.
bool ScaleFromKnownLengths(const Project& project, const std::set<Id>& images, ColmapAlignmentSummary* summary,
                           double* scale) {
  std::vector<double> ratios;
  double only_value = 0.0;
  for (const KnownLength& length : KnownLengths(project)) {
    Eigen::Vector3d a, b;
    if (!TriangulateVertex(project, images, length.a, &a) || !TriangulateVertex(project, images, length.b, &b))
      continue;
    const double d = (a - b).norm();
    if (!(d > 0.0) || !std::isfinite(d)) continue;
    ratios.push_back(length.value / d);
    only_value = length.value;
  }
  if (ratios.empty()) return false;
  std::sort(ratios.begin(), ratios.end());
  const size_t n = ratios.size();
  *scale = n % 2 == 1 ? ratios[n / 2] : 0.5 * (ratios[n / 2 - 1] + ratios[n / 2]);
  summary->num_known_lengths = static_cast<int>(n);
  summary->scale_note = n == 1 ? "known length " + FormatNumber(only_value) + " " + project.units
                               : Plural(static_cast<int>(n), "known length", "known lengths");
  if (ratios.back() > (1.0 + kKnownLengthDisagreement) * ratios.front())
    summary->warnings.push_back("The known lengths disagree by " +
                                FormatNumber(100.0 * (ratios.back() / ratios.front() - 1.0), 3) +
                                " % in the reconstruction; the scale is their median");
  return true;
}

// A family's vanishing direction in the camera (unit), from its segments undistorted by the
// camera's lens; false with fewer than two segments or no fit.
bool FamilyDirection(const Project& project, const Image& image, Axis axis, Eigen::Vector3d* direction_in_cam) {
  std::vector<Eigen::Vector4d> segments;
  for (const Segment& s : project.segments) {
    if (s.image_id != image.id || s.axis != axis) continue;
    const Eigen::Vector2d a = image.camera.UndistortPixel(s.a_px), b = image.camera.UndistortPixel(s.b_px);
    segments.emplace_back(a.x(), a.y(), b.x(), b.y());
  }
  if (segments.size() < 2) return false;
  VanishingPointOptions options;
  options.conditioning_center_px =
      Eigen::Vector2d(0.5 * (image.camera.width_px - 1), 0.5 * (image.camera.height_px - 1));
  options.conditioning_scale_px = 0.5 * std::max(1, std::max(image.camera.width_px, image.camera.height_px));
  const VanishingPointSummary vp = FitVanishingPoint(segments, options);
  if (!vp.IsUsable()) return false;
  const Eigen::Vector3d d = image.camera.K().inverse() * vp.vp_px;
  if (!(d.norm() > 0.0) || !d.allFinite()) return false;
  *direction_in_cam = d.normalized();
  return true;
}

// One horizontal family's heading: the turn about z (rad) that takes its direction to its
// world axis, known modulo `period` (2 pi: axis and sign known; pi: the sign is not; pi / 2:
// the image's turn is not chosen, so neither is which horizontal axis it is).
struct HeadingObservation {
  double turn_rad = 0.0;
  double period = kTwoPi;
};

double Wrap(double angle, double period) { return angle - period * std::floor(angle / period + 0.5); }

// The rotation from the line families of the registered photos (else the cameras' up), as
// rotation_source and rotation_note of *summary say.
Eigen::Matrix3d RotationFromLines(const Project& project, const std::vector<const Image*>& images,
                                  const ColmapAlignmentOptions& options, ColmapAlignmentSummary* summary) {
  Eigen::Vector3d camera_up = Eigen::Vector3d::Zero(), line_up = Eigen::Vector3d::Zero();
  int vertical_photos = 0;
  for (const Image* image : images) {
    const Eigen::Matrix3d& r = image->camera.cam_from_world_rotation;
    camera_up -= r.row(1).transpose();  // the camera's -y (up in the photo) in the world
    Eigen::Vector3d d;
    if (!FamilyDirection(project, *image, Axis::kZ, &d)) continue;
    if (d.y() > 0.0) d = -d;  // world z points up in the photo
    line_up += r.transpose() * d;
    ++vertical_photos;
  }
  Eigen::Vector3d up;
  if (vertical_photos > 0) {
    up = line_up.normalized();
    const double disagreement = std::acos(std::clamp(up.dot(camera_up.normalized()), -1.0, 1.0)) * kRadToDeg;
    if (disagreement > options.max_up_disagreement_deg)
      summary->warnings.push_back("The vertical lines' up is " + FormatNumber(disagreement, 3) +
                                  " deg from the cameras' mean up; it is taken from the lines");
  } else {
    up = camera_up.normalized();
  }
  const Eigen::Matrix3d level = Eigen::Quaterniond::FromTwoVectors(up, Eigen::Vector3d::UnitZ()).toRotationMatrix();

  // Headings. Without any recorded turn, the first photo with a horizontal family sets the
  // axes as its own calibration would (turn 0), as core/solve/world_frames.h does.
  const bool any_turn = std::any_of(images.begin(), images.end(), [](const Image* image) {
    return image->axis_quarter_turns != Image::kAxisTurnsUnchosen;
  });
  std::vector<HeadingObservation> headings;
  int horizontal_photos = 0;
  bool reference_taken = false;
  for (const Image* image : images) {
    bool counted = false;
    for (Axis axis : {Axis::kX, Axis::kY}) {
      Eigen::Vector3d d;
      if (!FamilyDirection(project, *image, axis, &d)) continue;
      const bool signed_direction = std::abs(d.z()) >= options.min_forward_component;
      if (d.z() < 0.0) d = -d;  // towards the vanishing point's side in front of the camera
      const Eigen::Vector3d levelled = level * image->camera.cam_from_world_rotation.transpose() * d;
      const Eigen::Vector2d h = levelled.head<2>();
      if (h.norm() < kMinHorizontalPart) continue;
      const int a = static_cast<int>(axis);
      int turns = image->axis_quarter_turns;
      const bool reference = !any_turn && !reference_taken;
      if (reference) turns = 0;
      HeadingObservation o;
      if (turns == Image::kAxisTurnsUnchosen) {
        o.period = M_PI / 2.0;
        o.turn_rad = (a == 0 ? 0.0 : M_PI / 2.0) - std::atan2(h.y(), h.x());
      } else {
        const Eigen::Vector3d target = AxisTurn(-turns) * Eigen::Vector3d::Unit(a);
        o.period = signed_direction ? kTwoPi : M_PI;
        o.turn_rad = std::atan2(target.y(), target.x()) - std::atan2(h.y(), h.x());
      }
      headings.push_back(o);
      counted = true;
    }
    if (counted) {
      ++horizontal_photos;
      if (!any_turn) reference_taken = true;
    }
  }
  // The best-determined first; each further one joins at its representative nearest the mean.
  std::stable_sort(headings.begin(), headings.end(),
                   [](const HeadingObservation& a, const HeadingObservation& b) { return a.period > b.period; });
  double heading = 0.0, sum_cos = 0.0, sum_sin = 0.0;
  for (const HeadingObservation& o : headings) {
    const double turn = sum_cos == 0.0 && sum_sin == 0.0 ? o.turn_rad : heading + Wrap(o.turn_rad - heading, o.period);
    sum_cos += std::cos(turn);
    sum_sin += std::sin(turn);
    heading = std::atan2(sum_sin, sum_cos);
  }
  summary->num_line_families = vertical_photos + static_cast<int>(headings.size());

  if (vertical_photos == 0 && headings.empty()) {
    summary->rotation_source = AlignmentSource::kCameraUp;
    summary->rotation_note = "up from the mean of " + Plural(static_cast<int>(images.size()), "camera", "cameras") +
                             " (no line family on the photos), heading kept";
  } else {
    summary->rotation_source = AlignmentSource::kLineFamilies;
    std::string note = vertical_photos > 0 ? "up from vertical lines in " + Plural(vertical_photos, "photo", "photos")
                                           : "up from the mean of the cameras (no vertical lines)";
    note += headings.empty() ? ", heading kept (no horizontal lines)"
                             : ", heading from horizontal lines in " + Plural(horizontal_photos, "photo", "photos");
    summary->rotation_note = note;
  }
  return Eigen::AngleAxisd(heading, Eigen::Vector3d::UnitZ()).toRotationMatrix() * level;
}

}  // namespace

const char* AlignmentSourceName(AlignmentSource source) {
  switch (source) {
    case AlignmentSource::kCommonCameras: return "cameras in common";
    case AlignmentSource::kLineFamilies: return "line families";
    case AlignmentSource::kCameraUp: return "cameras' up";
    case AlignmentSource::kKnownLength: return "known length";
    case AlignmentSource::kKept: return "kept";
  }
  return "unknown";
}

bool ColmapAlignmentOptions::Check(std::string* error) const {
  auto fail = [&](const char* why) {
    if (error != nullptr) *error = why;
    return false;
  };
  if (!(max_rotation_disagreement_deg > 0.0)) return fail("max_rotation_disagreement_deg must be positive");
  if (!(min_center_spread > 0.0)) return fail("min_center_spread must be positive");
  if (!(min_forward_component >= 0.0 && min_forward_component < 1.0))
    return fail("min_forward_component must be in [0, 1)");
  if (!(max_up_disagreement_deg > 0.0)) return fail("max_up_disagreement_deg must be positive");
  return true;
}

void TransformCamera(const SimilarityTransform& transform, Camera* camera) {
  const Eigen::Vector3d center = transform.Apply(camera->CenterInWorld());
  camera->SetPose(camera->cam_from_world_rotation * transform.rotation.transpose(), center);
}

ColmapAlignmentSummary AlignReconstructionToProject(const Project& before, const std::vector<Id>& reconstructed_images,
                                                    const ColmapAlignmentOptions& options, Project* project) {
  const auto start = std::chrono::steady_clock::now();
  ColmapAlignmentSummary summary;
  std::string error;
  if (!options.Check(&error))
    return internal::FailedSummary(summary, "alignment options: " + error, start, SolverTermination::kInvalidInput);
  std::vector<const Image*> registered;
  std::set<Id> registered_ids;
  for (Id id : reconstructed_images) {
    const Image* image = project->FindImage(id);
    if (image != nullptr && registered_ids.insert(id).second) registered.push_back(image);
  }
  if (registered.empty())
    return internal::FailedSummary(summary, "no image of the project is in the reconstruction", start,
                                   SolverTermination::kInvalidInput);

  // Cameras in common: their rotations, and centres in both frames.
  std::vector<Eigen::Vector3d> centers, project_centers;
  Eigen::Matrix3d rotation_sum = Eigen::Matrix3d::Zero();
  for (const Image* image : registered) {
    const Image* old = before.FindImage(image->id);
    if (old == nullptr || !old->camera_calibrated) continue;
    summary.common_images.push_back(image->id);
    rotation_sum += old->camera.cam_from_world_rotation.transpose() * image->camera.cam_from_world_rotation;
    centers.push_back(image->camera.CenterInWorld());
    project_centers.push_back(old->camera.CenterInWorld());
  }
  const int num_common = static_cast<int>(summary.common_images.size());

  SimilarityTransform& transform = summary.project_from_reconstruction;
  bool scale_fixed = false;
  if (num_common > 0) {
    transform.rotation = NearestRotation(rotation_sum);
    summary.rotation_source = AlignmentSource::kCommonCameras;
    summary.rotation_note = Plural(num_common, "camera", "cameras") + " in common";
    Eigen::Vector3d mean, project_mean;
    Spread(centers, &mean);
    Spread(project_centers, &project_mean);
    if (Distinct(centers, options.min_center_spread) && Distinct(project_centers, options.min_center_spread)) {
      // Scale and position: least squares on the centres, given the rotation.
      double numerator = 0.0, denominator = 0.0;
      for (int i = 0; i < num_common; ++i) {
        numerator += (project_centers[i] - project_mean).dot(transform.rotation * (centers[i] - mean));
        denominator += (centers[i] - mean).squaredNorm();
      }
      transform.scale = numerator / denominator;
      if (!(transform.scale > 0.0) || !std::isfinite(transform.scale))
        return internal::FailedSummary(summary,
                                       "the cameras in common give no positive scale (their centres are mirrored "
                                       "or turned against their rotations): not aligned",
                                       start);
      transform.translation = project_mean - transform.scale * transform.rotation * mean;
      summary.num_distinct_centers = num_common;
      summary.scale_source = summary.position_source = AlignmentSource::kCommonCameras;
      summary.scale_note = summary.position_note = Plural(num_common, "camera centre", "camera centres");
      scale_fixed = true;
      if (num_common >= 3) {
        const SimilarityFit fit = FitSimilarity(centers, project_centers);
        if (fit.ok) {
          summary.center_fit_rotation_deg = RotationAngleDeg(fit.transform.rotation * transform.rotation.transpose());
          if (summary.center_fit_rotation_deg > options.max_rotation_disagreement_deg)
            summary.warnings.push_back("The camera centres alone turn the reconstruction " +
                                       FormatNumber(summary.center_fit_rotation_deg, 3) +
                                       " deg from the cameras' rotations; the rotations are used");
        }
      }
    } else {
      summary.position_source = AlignmentSource::kCommonCameras;
      summary.position_note =
          num_common == 1 ? "1 camera in common" : Plural(num_common, "camera", "cameras") + " in common (one centre)";
    }
  } else {
    transform.rotation = RotationFromLines(*project, registered, options, &summary);
    summary.position_note = "kept (no camera in common)";
  }
  if (!scale_fixed) {
    double scale = 1.0;
    if (ScaleFromKnownLengths(*project, registered_ids, &summary, &scale)) {
      transform.scale = scale;
      summary.scale_source = AlignmentSource::kKnownLength;
    } else {
      transform.scale = 1.0;
      summary.scale_note = num_common > 0 ? "kept (one camera centre in common and no known length the photos see)"
                                          : "kept (no camera in common and no known length the photos see)";
    }
    if (num_common > 0) {
      Eigen::Vector3d mean, project_mean;
      Spread(centers, &mean);
      Spread(project_centers, &project_mean);
      transform.translation = project_mean - transform.scale * transform.rotation * mean;
    }
  }

  for (const Image* image : registered) TransformCamera(transform, &project->FindImage(image->id)->camera);

  // A photo with horizontal line families and no recorded turn is re-calibrated from its lines
  // after the edit (core/solve/model_update.h) as vanishing-point rotation x AxisTurn(turn):
  // the turn that puts its families where the aligned camera sees them is recorded, so that
  // the re-calibration keeps this heading instead of a guess (core/solve/world_frames.h).
  for (const Image* registered_image : registered) {
    Image* image = project->FindImage(registered_image->id);
    if (image->axis_quarter_turns != Image::kAxisTurnsUnchosen) continue;
    for (Axis axis : {Axis::kX, Axis::kY}) {
      Eigen::Vector3d d;
      if (!FamilyDirection(*project, *image, axis, &d) || std::abs(d.z()) < options.min_forward_component) continue;
      if (d.z() < 0.0) d = -d;
      const Eigen::Vector3d in_world = image->camera.cam_from_world_rotation.transpose() * d;
      int best = 0;
      double best_cos = -2.0;
      for (int turns = 0; turns < 4; ++turns) {
        const double c = (AxisTurn(-turns) * Eigen::Vector3d::Unit(static_cast<int>(axis))).dot(in_world);
        if (c > best_cos) best_cos = c, best = turns;
      }
      if (best_cos < std::cos(kMaxTurnErrorDeg / kRadToDeg)) continue;
      image->axis_quarter_turns = best;
      summary.chosen_turns.emplace_back(image->id, best);
      break;
    }
  }

  // How well the cameras in common agree once aligned.
  double center_sum = 0.0, rotation_sum_deg2 = 0.0;
  for (Id id : summary.common_images) {
    const Camera& aligned = project->FindImage(id)->camera;
    const Camera& old = before.FindImage(id)->camera;
    center_sum += (aligned.CenterInWorld() - old.CenterInWorld()).squaredNorm();
    const double angle = RotationAngleDeg(aligned.cam_from_world_rotation * old.cam_from_world_rotation.transpose());
    rotation_sum_deg2 += angle * angle;
    if (angle > options.max_rotation_disagreement_deg)
      summary.warnings.push_back("Photo " + before.FindImage(id)->path + ": the reconstruction's camera is turned " +
                                 FormatNumber(angle, 3) + " deg from the project's");
  }
  if (num_common > 0) {
    summary.center_rms = std::sqrt(center_sum / num_common);
    summary.rotation_rms_deg = std::sqrt(rotation_sum_deg2 / num_common);
  }
  summary.termination = SolverTermination::kConverged;
  summary.message =
      "rotation: " + summary.rotation_note + "; scale: " + summary.scale_note + "; position: " + summary.position_note;
  summary.time_ms = internal::MsSince(start);
  return summary;
}

}  // namespace facet
