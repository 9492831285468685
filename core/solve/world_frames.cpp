#include "core/solve/world_frames.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <set>

#include <Eigen/Dense>

#include "core/solve/scene_solve.h"
#include "core/util/eigen_decompositions.h"

namespace facet {

Eigen::Matrix3d AxisTurn(int quarter_turns) {
  static const int kCos[4] = {1, 0, -1, 0};
  static const int kSin[4] = {0, 1, 0, -1};
  const int k = ((quarter_turns % 4) + 4) % 4;
  Eigen::Matrix3d turn;
  turn << kCos[k], -kSin[k], 0, kSin[k], kCos[k], 0, 0, 0, 1;
  return turn;
}

int WorldAxisOfFamily(int family_axis, int quarter_turns) {
  if (family_axis < 2 && quarter_turns >= 0 && quarter_turns % 2 == 1) return 1 - family_axis;
  return family_axis;
}

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// When a turn chosen from pins is kept (world_frames.h): enough points for the fit to have
// redundancy, and a next best turn clearly worse both relatively and in pixels (a click is
// good to a pixel or two; wrong turns with 3+ well-spread pins fit tens of pixels worse).
constexpr int kMinPinsToKeepResectionTurn = 3;
constexpr int kMinVerticesToKeepRelativeTurn = 4;
constexpr double kKeepTurnRatio = 3.0;
constexpr double kKeepTurnGapPx = 3.0;

bool MarginClear(double error, double runner_up) {
  return !std::isfinite(runner_up) || (runner_up >= kKeepTurnRatio * error && runner_up - error >= kKeepTurnGapPx);
}

std::string ProvisionalText() {
  return ": too close to keep, used for now and chosen again at each change (pin more vertices, spread over the "
         "photo)";
}

// A candidate turn's score: fewer points behind first, then the lower RMS.
struct Score {
  int behind = std::numeric_limits<int>::max();
  double rms = kInfinity;
  bool BetterThan(const Score& other) const {
    return behind != other.behind ? behind < other.behind : rms < other.rms;
  }
};

// Normalised camera ray (z = 1) of a photo pixel, distortion removed.
Eigen::Vector3d CameraRay(const Camera& camera, const Eigen::Vector2d& uv_px) {
  const Eigen::Vector2d uv = camera.UndistortPixel(uv_px);
  return {(uv.x() - camera.principal_point_px.x()) / camera.focal_px,
          (uv.y() - camera.principal_point_px.y()) / camera.focal_px, 1.0};
}

struct ResectionPoint {
  Eigen::Vector3d ray;  // camera frame, z = 1
  Eigen::Vector3d world;
  Eigen::Vector2d uv_px;  // undistorted
};

// The camera centre that best fits the points with rotation R (least squares over the
// rays' perpendicular distances, linear), and its score. False when the rays do not fix it.
bool ResectCentre(const Camera& camera, const Eigen::Matrix3d& cam_from_world, const std::vector<ResectionPoint>& points,
                  Eigen::Vector3d* centre, Score* score) {
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (const ResectionPoint& p : points) {
    const Eigen::Vector3d d = (cam_from_world.transpose() * p.ray).normalized();
    const Eigen::Matrix3d perp = Eigen::Matrix3d::Identity() - d * d.transpose();
    a += perp;
    b += perp * p.world;
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(a);
  if (!(eig.eigenvalues()(0) > 1e-9 * eig.eigenvalues()(2))) return false;
  *centre = a.ldlt().solve(b);
  score->behind = 0;
  double sum_sq = 0.0;
  for (const ResectionPoint& p : points) {
    const Eigen::Vector3d q = cam_from_world * (p.world - *centre);
    if (!(q.z() > 0.0)) {
      ++score->behind;
      continue;
    }
    const Eigen::Vector2d uv = camera.focal_px * q.head<2>() / q.z() + camera.principal_point_px;
    sum_sq += (uv - p.uv_px).squaredNorm();
  }
  const int in_front = static_cast<int>(points.size()) - score->behind;
  score->rms = in_front > 0 ? std::sqrt(sum_sq / in_front) : kInfinity;
  return true;
}

std::string ImageName(const Image& image) {
  return image.path.empty() ? "#" + std::to_string(image.id) : "'" + image.path + "'";
}

std::string TurnText(int k) {
  static const char* kText[4] = {"as its lines give them", "turned 90 deg about the vertical",
                                 "turned 180 deg about the vertical", "turned 270 deg about the vertical"};
  return kText[k];
}

void SetTurn(Image* image, int k, const Eigen::Vector3d& centre, bool provisional) {
  // The rotation in the project is vanishing-point x AxisTurn(0) for an image being chosen.
  image->camera.SetPose(image->camera.cam_from_world_rotation * AxisTurn(k), centre);
  image->axis_quarter_turns = k;
  image->axis_turn_provisional = provisional;
}

std::string Figures(const WorldFrameChoice& c, const char* unit) {
  char text[160];
  if (std::isfinite(c.runner_up)) {
    std::snprintf(text, sizeof(text), "%.3g %s RMS, the next best turn %.3g %s", c.error, unit, c.runner_up, unit);
  } else {
    std::snprintf(text, sizeof(text), "%.3g %s RMS, every other turn puts points behind a camera", c.error, unit);
  }
  return text;
}

// Chooses by resection against the model's positions; false when too few pins see it.
bool ChooseByResection(const std::set<Id>& solved_primitives, Image* image, const Project& project,
                       WorldFrameChoice* choice) {
  std::vector<ResectionPoint> points;
  for (const Pin& pin : project.pins) {
    if (pin.image_id != image->id || solved_primitives.count(pin.vertex.primitive_id) == 0) continue;
    if (project.FindVertex(pin.vertex) == nullptr) continue;
    points.push_back({CameraRay(image->camera, pin.uv_px), VertexInWorld(project, pin.vertex),
                      image->camera.UndistortPixel(pin.uv_px)});
  }
  if (points.size() < 2) return false;
  Score best, second;
  int best_k = -1;
  Eigen::Vector3d best_centre = Eigen::Vector3d::Zero();
  for (int k = 0; k < 4; ++k) {
    Eigen::Vector3d centre;
    Score score;
    if (!ResectCentre(image->camera, image->camera.cam_from_world_rotation * AxisTurn(k), points, &centre, &score))
      continue;
    if (score.BetterThan(best)) {
      second = best;
      best = score;
      best_k = k;
      best_centre = centre;
    } else if (score.BetterThan(second)) {
      second = score;
    }
  }
  if (best_k < 0 || best.behind > 0) return false;
  choice->image_id = image->id;
  choice->quarter_turns = best_k;
  choice->source = WorldFrameChoice::Source::kSharedPins;
  choice->num_points = static_cast<int>(points.size());
  choice->error = best.rms;
  choice->runner_up = second.behind == 0 ? second.rms : kInfinity;
  choice->provisional = choice->num_points < kMinPinsToKeepResectionTurn || !MarginClear(choice->error, choice->runner_up);
  choice->note = "Image " + ImageName(*image) + ": world axes " + TurnText(best_k) + ", to agree with the model (" +
                 std::to_string(points.size()) + " pins on solved vertices: " + Figures(*choice, "px") + ")" +
                 (choice->provisional ? ProvisionalText() : "");
  SetTurn(image, best_k, best_centre, choice->provisional);
  return true;
}

// Chooses from the relative pose to a reference image (vertices pinned in both, 3 or more);
// false when no reference shares enough.
bool ChooseByRelativePose(const std::vector<const Image*>& references, Image* image, const Project& project,
                          WorldFrameChoice* choice) {
  for (const Image* reference : references) {
    std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> rays;  // (reference, this), camera frames
    for (const Pin& pin : project.pins) {
      if (pin.image_id != image->id) continue;
      for (const Pin& other : project.pins) {
        if (other.image_id == reference->id && other.vertex == pin.vertex) {
          rays.emplace_back(CameraRay(reference->camera, other.uv_px), CameraRay(image->camera, pin.uv_px));
          break;
        }
      }
    }
    if (rays.size() < 3) continue;
    const Eigen::Matrix3d& r_ref = reference->camera.cam_from_world_rotation;
    Score best, second;
    int best_k = -1;
    Eigen::Vector3d best_baseline = Eigen::Vector3d::Zero();
    for (int k = 0; k < 4; ++k) {
      const Eigen::Matrix3d r_this = image->camera.cam_from_world_rotation * AxisTurn(k);
      // Coplanarity of the baseline b with both world rays: b . (d_ref x d_this) = 0.
      Eigen::MatrixXd normals(rays.size(), 3);
      std::vector<Eigen::Vector3d> d_ref(rays.size()), d_this(rays.size());
      for (size_t i = 0; i < rays.size(); ++i) {
        d_ref[i] = (r_ref.transpose() * rays[i].first).normalized();
        d_this[i] = (r_this.transpose() * rays[i].second).normalized();
        normals.row(static_cast<int>(i)) = d_ref[i].cross(d_this[i]).transpose();
      }
      Eigen::JacobiSVD<Eigen::MatrixXd> svd(normals, Eigen::ComputeFullV);
      const Eigen::Vector3d b = svd.matrixV().col(2);
      for (const double sign : {1.0, -1.0}) {
        Score score;
        score.behind = 0;
        double sum_sq = 0.0;
        for (size_t i = 0; i < rays.size(); ++i) {
          // s d_ref - t d_this = sign b: depths along each ray.
          Eigen::Matrix<double, 3, 2> m;
          m << d_ref[i], -d_this[i];
          const Eigen::Vector2d st = m.colPivHouseholderQr().solve(sign * b);
          if (!(st.x() > 0.0 && st.y() > 0.0)) ++score.behind;
          // Angle of the ray pair off the epipolar plane, in px of this image.
          const double off = std::abs(normals.row(static_cast<int>(i)).dot(b)) /
                             std::max(d_ref[i].cross(b).norm(), 1e-12);
          sum_sq += std::pow(image->camera.focal_px * off, 2);
        }
        score.rms = std::sqrt(sum_sq / rays.size());
        if (score.BetterThan(best)) {
          second = best;
          best = score;
          best_k = k;
          best_baseline = sign * b;
        } else if (score.BetterThan(second) && k != best_k) {
          second = score;
        }
      }
    }
    if (best_k < 0 || best.behind > 0) continue;
    choice->image_id = image->id;
    choice->quarter_turns = best_k;
    choice->source = WorldFrameChoice::Source::kRelativePose;
    choice->num_points = static_cast<int>(rays.size());
    choice->error = best.rms;
    choice->runner_up = second.behind == 0 ? second.rms : kInfinity;
    choice->provisional =
        choice->num_points < kMinVerticesToKeepRelativeTurn || !MarginClear(choice->error, choice->runner_up);
    choice->note = "Image " + ImageName(*image) + ": world axes " + TurnText(best_k) + ", to agree with image " +
                   ImageName(*reference) + " (relative pose from " + std::to_string(rays.size()) +
                   " shared vertices: " + Figures(*choice, "px epipolar") + ")" +
                   (choice->provisional ? ProvisionalText() : "");
    // The baseline's length is unknown here: the reference's distance to the model is the
    // start; the geometry solve sets it.
    const double distance = std::max(reference->camera.CenterInWorld().norm(), 1.0);
    SetTurn(image, best_k, reference->camera.CenterInWorld() + distance * best_baseline, choice->provisional);
    return true;
  }
  return false;
}

// The first image sets the world axes, but the model already has a frame of its own: a
// primitive's dimensions are positive along its axes, and its rotation is usually locked to
// the world's. Of the 4 turns, the one whose geometry solve (cold: the linear start, then
// LM) fits the pins with every pinned vertex in front, at the lowest RMS, is taken; turn 0
// unless another fits better. False when no turn gives a usable solve (e.g. too few pins).
bool ChooseByModelFit(const std::set<Id>& open, Image* image, const Project& project, WorldFrameChoice* choice) {
  Project alone = project;
  for (Image& other : alone.images)
    if (other.id != image->id && open.count(other.id) > 0) other.camera_calibrated = false;
  Image* trial_image = alone.FindImage(image->id);
  const Eigen::Matrix3d rotation = image->camera.cam_from_world_rotation;
  SceneSolveOptions options;
  options.warm_start = false;
  Score best, second;
  int best_k = -1;
  for (int k = 0; k < 4; ++k) {
    trial_image->camera.SetPose(rotation * AxisTurn(k), image->camera.CenterInWorld());
    Project solved;
    const SceneSolveSummary summary = SolveScene(alone, options, &solved);
    if (!summary.IsUsable() || !summary.linear_initialization_used) continue;
    Score score;
    score.behind = 0;
    for (const std::string& w : summary.warnings) score.behind += w.find("lies behind the camera") != std::string::npos;
    score.rms = summary.reprojection_rms_px;
    // Turn 0 (the lines' own axes) unless another fits clearly better.
    if (best_k == 0 && score.behind == best.behind && score.rms >= best.rms * (1.0 - 1e-6) - 1e-9) score.rms = kInfinity;
    if (score.BetterThan(best)) {
      second = best;
      best = score;
      best_k = k;
    } else if (score.BetterThan(second)) {
      second = score;
    }
  }
  if (best_k < 0 || best.behind > 0) return false;
  choice->image_id = image->id;
  choice->quarter_turns = best_k;
  choice->source = WorldFrameChoice::Source::kFirstImage;
  choice->num_points = 0;
  for (const Pin& pin : project.pins) choice->num_points += pin.image_id == image->id;
  choice->error = best.rms;
  choice->runner_up = second.behind == 0 ? second.rms : kInfinity;
  if (best_k != 0) {
    choice->note = "Image " + ImageName(*image) + ": world axes " + TurnText(best_k) +
                   ", so that the model's primitives fit its pins with positive sizes (" +
                   Figures(*choice, "px") + ")";
  }
  SetTurn(image, best_k, image->camera.CenterInWorld(), false);
  return true;
}

}  // namespace

std::vector<WorldFrameChoice> ReconcileWorldFrames(const std::vector<Id>& unchosen, Project* project) {
  std::vector<WorldFrameChoice> choices;
  std::set<Id> open(unchosen.begin(), unchosen.end());
  // Only images in the model before this update place its vertices (the cached positions are
  // their solve's); an image chosen here joins the references for the relative pose only.
  std::set<Id> solved_primitives;
  std::vector<Id> reference_ids;
  for (const Image& image : project->images) {
    if (!image.camera_calibrated || open.count(image.id) > 0) continue;
    reference_ids.push_back(image.id);
    for (const Pin& pin : project->pins)
      if (pin.image_id == image.id) solved_primitives.insert(pin.vertex.primitive_id);
  }
  auto references = [&] {
    std::vector<const Image*> out;
    for (Id id : reference_ids) out.push_back(project->FindImage(id));
    return out;
  };
  bool progress = true;
  while (progress && !open.empty()) {
    progress = false;
    for (Image& image : project->images) {
      if (open.count(image.id) == 0) continue;
      WorldFrameChoice choice;
      if (!ChooseByResection(solved_primitives, &image, *project, &choice)) continue;
      choices.push_back(choice);
      open.erase(image.id);
      reference_ids.push_back(image.id);
      progress = true;
    }
    if (progress || open.empty()) continue;
    for (Image& image : project->images) {
      if (open.count(image.id) == 0) continue;
      WorldFrameChoice choice;
      if (reference_ids.empty()) {
        if (!ChooseByModelFit(open, &image, *project, &choice)) {
          // Too few pins to tell yet: the lines' own axes until the pins can.
          if (std::any_of(project->pins.begin(), project->pins.end(),
                          [&](const Pin& pin) { return pin.image_id == image.id; }))
            continue;
          choice.image_id = image.id;
          choice.source = WorldFrameChoice::Source::kFirstImage;
          image.axis_quarter_turns = 0;
          image.axis_turn_provisional = false;
        }
      } else if (!ChooseByRelativePose(references(), &image, *project, &choice)) {
        continue;
      }
      choices.push_back(choice);
      open.erase(image.id);
      reference_ids.push_back(image.id);
      progress = true;
      break;  // resection first again: the model may now place more of the others' pins
    }
  }
  // An image with one pin on the model so far cannot be resected, and its camera still sits
  // where it was made (at the origin): the solve would find the pinned vertex behind it and
  // refuse the whole update ("at the start a pinned vertex lies on or behind its camera").
  // It is put on that pin's ray at the reference cameras' distance from the vertex, so the
  // pin joins the solve; its turn waits for a second pin.
  for (Image& image : project->images) {
    if (open.count(image.id) == 0 || reference_ids.empty()) continue;
    const Pin* first = nullptr;
    for (const Pin& pin : project->pins) {
      if (pin.image_id == image.id && solved_primitives.count(pin.vertex.primitive_id) > 0 &&
          project->FindVertex(pin.vertex) != nullptr) {
        first = &pin;
        break;
      }
    }
    if (first == nullptr) continue;
    const Eigen::Vector3d vertex = VertexInWorld(*project, first->vertex);
    if (image.camera.CamFromWorld(vertex).z() > 0.0) continue;  // already in front
    double distance = 0.0;
    for (Id id : reference_ids) distance += (project->FindImage(id)->camera.CenterInWorld() - vertex).norm();
    distance /= static_cast<double>(reference_ids.size());
    if (!(distance > 0.0) || !std::isfinite(distance)) continue;
    const Eigen::Vector3d ray =
        (image.camera.cam_from_world_rotation.transpose() * CameraRay(image.camera, first->uv_px)).normalized();
    image.camera.SetPose(image.camera.cam_from_world_rotation, vertex - distance * ray);
  }
  // A provisional turn the pins no longer choose (e.g. pins removed) is unchosen again: its
  // camera holds the lines' own axes now, and the solve must read its families that way.
  for (Image& image : project->images) {
    if (open.count(image.id) == 0 || !image.axis_turn_provisional) continue;
    image.axis_quarter_turns = Image::kAxisTurnsUnchosen;
    image.axis_turn_provisional = false;
  }
  return choices;
}

}  // namespace facet
