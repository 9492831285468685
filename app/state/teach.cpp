#include "app/state/teach.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "app/state/app_state.h"
#include "core/solve/model_update.h"
#include "core/solve/multiview_init.h"
#include "core/util/format.h"

namespace facet::app {
namespace {

using internal::FormatNumber;

std::string Point(const Eigen::Vector2d& p) {
  return "(" + FormatNumber(p.x(), 5) + ", " + FormatNumber(p.y(), 5) + ") px";
}

const Image* CalibratedImage(const Project& project, Id id) {
  const Image* image = project.FindImage(id);
  return image != nullptr && image->camera_calibrated ? image : nullptr;
}

// The vertices whose pins the epipolar overlay follows: the selected ones and the selected pin's.
std::vector<VertexRef> SelectedVertices(const AppState& state) {
  std::vector<VertexRef> vertices;
  for (const ElementRef& e : SelectedElements(state.selection))
    if (e.kind == ElementKind::kVertex) vertices.push_back({e.primitive_id, e.element});
  if (const Pin* pin = state.document.project().FindPin(state.selection.pin_id)) vertices.push_back(pin->vertex);
  return vertices;
}

}  // namespace

bool* TeachFlag(TeachView* view, const std::string& name) {
  if (name == "vanishing") return &view->vanishing_points;
  if (name == "epipolar") return &view->epipolar;
  if (name == "numbers") return &view->numbers;
  if (name == "state") return &view->modelling_state;
  if (name == "steps") return &view->solver_steps;
  return nullptr;
}

const FocalConstruction* ShownFocalConstruction(const VanishingConstruction& construction) {
  const FocalConstruction* shown = nullptr;
  for (const FocalConstruction& f : construction.focal_constructions)
    if (f.valid && (shown == nullptr || f.circle_radius_px < shown->circle_radius_px)) shown = &f;
  return shown;
}

std::vector<Id> TeachExtendedSegments(const AppState& state, Id image_id, const VanishingConstruction& construction) {
  std::array<std::vector<const Segment*>, 3> families;
  for (const Segment& segment : state.document.project().segments) {
    if (segment.image_id == image_id && construction.present[static_cast<int>(segment.axis)])
      families[static_cast<int>(segment.axis)].push_back(&segment);
  }
  std::vector<Id> ids;
  for (std::vector<const Segment*>& family : families) {
    const size_t keep = std::min(family.size(), kTeachExtensionsPerFamily);
    std::partial_sort(family.begin(), family.begin() + keep, family.end(), [](const Segment* p, const Segment* q) {
      return (p->b_px - p->a_px).squaredNorm() > (q->b_px - q->a_px).squaredNorm();
    });
    for (size_t k = 0; k < keep; ++k) ids.push_back(family[k]->id);
  }
  return ids;
}

void TeachVanishingExtent(const TeachVanishing& teach, int width_px, int height_px, Eigen::Vector2d* min_px,
                          Eigen::Vector2d* max_px) {
  const Eigen::Vector2d size(width_px, height_px);
  const Eigen::Vector2d centre = 0.5 * size;
  const double limit = kMaxVanishingViewDiagonals * size.norm();
  Eigen::Vector2d lo = Eigen::Vector2d::Zero(), hi = size;
  auto include = [&](const Eigen::Vector2d& p) {
    if (!p.allFinite() || (p - centre).norm() > limit) return;
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  };
  const VanishingConstruction& c = teach.construction;
  for (int a = 0; a < 3; ++a) {
    if (c.finite[a]) include(c.points_px[a]);
  }
  include(c.principal_point_px);
  if (const FocalConstruction* f = ShownFocalConstruction(c)) {
    // The whole circle only when it is about the photo's size: a circle through far points
    // would shrink the photo to a corner, and the construction's steps (h, C', f) lie near
    // the photo whatever the circle's size.
    const Eigen::Vector2d r = Eigen::Vector2d::Constant(f->circle_radius_px);
    if (f->circle_radius_px < kMaxVanishingCircleViewDiagonals * size.norm()) {
      include(f->circle_center_px - r);
      include(f->circle_center_px + r);
    }
    include(f->altitude_foot_px);
    include(f->turned_center_px);
    include(f->focal_end_px);
  }
  *min_px = lo;
  *max_px = hi;
}

std::optional<TeachVanishing> TeachVanishingFor(const AppState& state, Id image_id) {
  const Project& project = state.document.project();
  const Image* image = project.FindImage(image_id);
  const auto found = state.last_update.calibration.find(image_id);
  if (image == nullptr || found == state.last_update.calibration.end() || !found->second.IsUsable())
    return std::nullopt;
  const VpCalibrationSummary& calibration = found->second;
  TeachVanishing out;
  out.image_id = image_id;
  VanishingConstructionInput input;
  input.vanishing_points_px = calibration.family_vanishing_points;
  input.assumed_principal_point_px = calibration.principal_point_px;
  input.assumed_focal_px = calibration.focal_px;
  input.at_infinity = calibration.vanishing_point_at_infinity;
  out.construction = ConstructFromVanishingPoints(input);
  out.vanishing_points_px = input.vanishing_points_px;
  out.covariance_px2 = calibration.family_vanishing_point_covariance_px2;
  out.fitted_focal_px = calibration.focal_px;
  out.fitted_focal_std_px = calibration.focal_std_px;
  out.fitted_principal_point_px = calibration.principal_point_px;

  const VanishingConstruction& c = out.construction;
  int families = 0;
  for (int a = 0; a < 3; ++a) families += c.present[a] ? 1 : 0;
  out.assumptions.push_back("assumed: the line families are orthogonal in the world; square pixels, no skew");
  if (c.triangle_failed)
    out.assumptions.push_back("the vanishing triangle gives no camera (a point nearly at infinity): two points used");
  for (int a = 0; a < 3; ++a)
    if (c.present[a] && !c.finite[a])
      out.assumptions.push_back(std::string("v") + AxisName(static_cast<Axis>(a)) +
                                " is at infinity: its lines are parallel in the photo");
  if (c.principal_point_assumed) {
    if (image->principal_point_mode == PrincipalPointMode::kFixed) {
      out.assumptions.push_back("assumed: principal point given at " + Point(c.principal_point_px));
    } else if (image->principal_point_mode == PrincipalPointMode::kImageCenter || families < 3 ||
               calibration.principal_point_std_px.isZero()) {
      out.assumptions.push_back("assumed: principal point at the image centre " + Point(c.principal_point_px));
    } else {
      out.assumptions.push_back("principal point from the joint fit " + Point(c.principal_point_px) +
                                " (a vanishing point at infinity leaves the triangle open)");
    }
  }
  if (c.focal_assumed) {
    if (image->focal_mode == FocalMode::kFixed) {
      out.assumptions.push_back("assumed: focal length known, f = " + FormatNumber(c.focal_px, 5) + " px (given)");
    } else if (image->focal_mode == FocalMode::kPrior) {
      out.assumptions.push_back("assumed: focal length from the prior (EXIF), f = " + FormatNumber(c.focal_px, 5) +
                                " px");
    } else {
      out.assumptions.push_back("focal length from the joint fit, f = " + FormatNumber(c.focal_px, 5) + " px");
    }
  }
  if (image->use_horizon) out.assumptions.push_back("assumed: the horizon given (dashed orange)");

  if (image->camera_calibrated) {
    const Camera& camera = image->camera;
    out.camera_center_in_world = camera.CenterInWorld();
    for (int a = 0; a < 3; ++a)
      out.directions_in_world[a] = camera.cam_from_world_rotation.transpose() * c.directions_in_cam[a];
  }
  return out;
}

std::vector<TeachEpipolarLine> TeachEpipolarLines(const AppState& state) {
  std::vector<TeachEpipolarLine> out;
  const Project& project = state.document.project();
  auto add_lines_from = [&](const Image& from, const Eigen::Vector2d& uv_px, bool pointer, const Pin* pin) {
    // F acts on pinhole pixels: the point is undistorted first, the line is in b's pinhole pixels.
    const Eigen::Vector2d uv_pinhole = from.camera.UndistortPixel(uv_px);
    for (const Image& other : project.images) {
      if (other.id == from.id || !other.camera_calibrated) continue;
      const Eigen::Matrix3d F = FundamentalFromCameras(from.camera, other.camera);
      const EpipolarLine line = EpipolarLineInImage(F, uv_pinhole, other.width_px, other.height_px);
      if (line.line.isZero()) continue;
      TeachEpipolarLine l;
      l.from_image_id = from.id;
      l.in_image_id = other.id;
      l.from_uv_px = uv_px;
      l.from_pointer = pointer;
      l.pin_id = pin != nullptr ? pin->id : kNoId;
      l.line = line.line;
      l.epipole = EpipolesOfCameras(from.camera, other.camera).in_b;
      if (pin != nullptr) {
        for (const Pin& there : project.pins) {
          if (there.image_id != other.id || !(there.vertex == pin->vertex)) continue;
          l.pin_distance_px = std::abs(l.line.dot(other.camera.UndistortPixel(there.uv_px).homogeneous()));
        }
      }
      out.push_back(l);
    }
  };
  const std::vector<VertexRef> vertices = SelectedVertices(state);
  for (const Pin& pin : project.pins) {
    if (std::find(vertices.begin(), vertices.end(), pin.vertex) == vertices.end()) continue;
    if (const Image* from = CalibratedImage(project, pin.image_id)) add_lines_from(*from, pin.uv_px, false, &pin);
  }
  if (state.pointer_in_image_px) {
    if (const Image* from = CalibratedImage(project, state.pointer_image_id))
      add_lines_from(*from, *state.pointer_in_image_px, true, nullptr);
  }
  return out;
}

std::optional<TeachNumbers> TeachNumbersFor(const AppState& state) {
  const Project& project = state.document.project();
  const Image* image = CalibratedImage(project, state.active_image_id);
  if (image == nullptr) return std::nullopt;
  TeachNumbers out;
  out.image_id = image->id;
  out.K = image->camera.K();
  out.R = image->camera.cam_from_world_rotation;
  out.t = image->camera.cam_from_world_translation;
  out.center = image->camera.CenterInWorld();
  const Image* second = CalibratedImage(project, state.teach.second_image_id);
  if (second == nullptr || second->id == image->id) return out;
  Eigen::Matrix3d F = FundamentalFromCameras(image->camera, second->camera);
  if (!(F.norm() > 0.0)) return out;
  F /= F.norm();
  Eigen::Index row, col;
  F.cwiseAbs().maxCoeff(&row, &col);
  if (F(row, col) < 0.0) F = -F;
  out.second_image_id = second->id;
  out.F = F;
  const EpipolePair epipoles = EpipolesOfCameras(image->camera, second->camera);
  out.epipole_in_a = epipoles.in_a;
  out.epipole_in_b = epipoles.in_b;
  return out;
}

void UpdateTeachHistoryCounts(AppState* state) {
  if (state->teach.history_counts_revision == state->document.revision()) return;
  state->teach.history_counts = HistoryStateCounts(state->document);
  state->teach.history_counts_revision = state->document.revision();
}

std::vector<TeachRayPair> TeachRayPairs(const AppState& state) {
  std::vector<TeachRayPair> out;
  const Project& project = state.document.project();
  std::vector<VertexRef> vertices = SelectedVertices(state);
  for (size_t i = 0; i < vertices.size(); ++i) {
    if (std::find(vertices.begin(), vertices.begin() + i, vertices[i]) != vertices.begin() + i) continue;
    std::vector<const Pin*> pins;
    for (const Pin& pin : project.pins)
      if (pin.vertex == vertices[i] && CalibratedImage(project, pin.image_id) != nullptr) pins.push_back(&pin);
    for (size_t a = 0; a < pins.size(); ++a) {
      for (size_t b = a + 1; b < pins.size(); ++b) {
        if (pins[a]->image_id == pins[b]->image_id) continue;
        const Camera& ca = project.FindImage(pins[a]->image_id)->camera;
        const Camera& cb = project.FindImage(pins[b]->image_id)->camera;
        TeachRayPair pair;
        pair.vertex = vertices[i];
        pair.pin_a = pins[a]->id;
        pair.pin_b = pins[b]->id;
        pair.image_a = pins[a]->image_id;
        pair.image_b = pins[b]->image_id;
        pair.center_a = ca.CenterInWorld();
        pair.center_b = cb.CenterInWorld();
        pair.direction_a = ca.RayDirectionInWorld(pins[a]->uv_px);
        pair.direction_b = cb.RayDirectionInWorld(pins[b]->uv_px);
        pair.closest = ClosestPointsOfRays(pair.center_a, pair.direction_a, pair.center_b, pair.direction_b);
        if (!pair.closest.valid) continue;
        pair.gap_px_in_a = (ca.Project(pair.closest.on_b) - pins[a]->uv_px).norm();
        pair.gap_px_in_b = (cb.Project(pair.closest.on_a) - pins[b]->uv_px).norm();
        out.push_back(pair);
      }
    }
  }
  return out;
}

const char* TeachStepStartName(TeachStepStart start) {
  return start == TeachStepStart::kPerturbed ? "perturbed" : "as-is";
}

std::optional<TeachStepStart> TeachStepStartFromName(const std::string& name) {
  if (name == "perturbed") return TeachStepStart::kPerturbed;
  if (name == "as-is") return TeachStepStart::kAsIs;
  return std::nullopt;
}

std::vector<TeachPinResidual> TeachPinResiduals(const Project& project) {
  std::vector<TeachPinResidual> out;
  for (const Pin& pin : project.pins) {
    const Image* image = CalibratedImage(project, pin.image_id);
    if (image == nullptr || project.FindVertex(pin.vertex) == nullptr) continue;
    const Eigen::Vector3d x = VertexInWorld(project, pin.vertex);
    if (!(image->camera.CamFromWorld(x).z() > 0.0)) continue;
    TeachPinResidual r;
    r.pin_id = pin.id;
    r.image_id = pin.image_id;
    r.uv_px = pin.uv_px;
    r.projection_px = image->camera.Project(x);
    r.residual_px = r.projection_px - pin.uv_px;
    out.push_back(r);
  }
  return out;
}

namespace {

// 1, 2 or 5 x 10^k, the largest not above `x` (x > 0).
double RoundScaleDown(double x) {
  const double decade = std::pow(10.0, std::floor(std::log10(x)));
  for (const double m : {5.0, 2.0, 1.0})
    if (m * decade <= x) return m * decade;
  return decade;
}

void RefreshSteppedMesh(TeachSolverSteps* solver) {
  solver->mesh = BuildUntexturedMesh(solver->steps->current);
  ++solver->mesh_revision;
}

void BeginSteps(AppState* state) {
  TeachSolverSteps& solver = state->teach.solver;
  const Project& document = state->document.project();
  const Project start =
      solver.start == TeachStepStart::kPerturbed ? PerturbForSteps(document, solver.perturbation) : document;
  solver.steps = BeginJointSolveSteps(start, SolveStepsOptions());
  solver.document_revision = state->document.revision();
  constexpr double kLongestVectorOfDiagonal = 0.08;
  constexpr double kMinScale = 1e-3, kMaxScale = 1e6;
  double scale = std::numeric_limits<double>::infinity();
  for (const TeachPinResidual& r : TeachPinResiduals(start)) {
    const Image* image = start.FindImage(r.image_id);
    const double length = r.residual_px.norm();
    if (!(length > 0.0)) continue;
    scale = std::min(scale, kLongestVectorOfDiagonal * std::hypot(image->width_px, image->height_px) / length);
  }
  solver.residual_scale = std::isfinite(scale) ? std::clamp(RoundScaleDown(scale), kMinScale, kMaxScale) : 1.0;
  solver.message = std::string("start: ") +
                   (solver.start == TeachStepStart::kPerturbed
                        ? "the project moved off its answer by " + FormatNumber(100.0 * solver.perturbation, 3) + " %"
                        : "the project as it is");
  RefreshSteppedMesh(&solver);
}

}  // namespace

const Project* TeachSteppedProject(const AppState& state) {
  const TeachSolverSteps& solver = state.teach.solver;
  if (!state.teach.solver_steps || !solver.steps || solver.document_revision != state.document.revision())
    return nullptr;
  return &solver.steps->current;
}

namespace {

std::string PhotoName(const Image& image) {
  const size_t slash = image.path.find_last_of("/\\");
  return slash == std::string::npos ? image.path : image.path.substr(slash + 1);
}

// A pixel as the fits read it: straightened by the camera's distortion, if it has any.
Eigen::Vector2d FittedPixel(const Image& image, const Eigen::Vector2d& uv_px) {
  return image.camera_calibrated && image.camera.HasDistortion() ? image.camera.UndistortPixel(uv_px) : uv_px;
}

std::string StepMessage(int steps, double cost_px2, bool finished, SolverTermination termination,
                        const std::string& more) {
  return "step " + std::to_string(steps) + ": cost " + FormatNumber(cost_px2, 6) + " px^2" + more +
         (finished ? std::string(", finished (") + SolverTerminationName(termination) + ")" : std::string());
}

bool BeginVpSteps(AppState* state) {
  TeachSolverSteps& solver = state->teach.solver;
  TeachVpSteps& vp = solver.vp;
  const Project& project = state->document.project();
  const Image* image = project.FindImage(state->active_image_id);
  if (image == nullptr) {
    solver.message = "vanishing points: no active photo";
    return false;
  }
  std::vector<Segment> segments;
  std::vector<Id> ids;
  for (const Segment& s : project.segments) {
    if (s.image_id != image->id) continue;
    Segment fitted = s;
    fitted.a_px = FittedPixel(*image, s.a_px);
    fitted.b_px = FittedPixel(*image, s.b_px);
    segments.push_back(fitted);
    ids.push_back(s.id);
  }
  VpFitSteps steps;
  VpCalibrationSummary failure;
  const double amount = solver.start == TeachStepStart::kPerturbed ? solver.perturbation : 0.0;
  if (!BeginVpFitSteps(segments, CalibrationOptionsFor(*image), amount, &steps, &failure)) {
    solver.message = "vanishing points of " + PhotoName(*image) + ": " + failure.message;
    return false;
  }
  vp.image_id = image->id;
  vp.segment_ids = std::move(ids);
  double largest = 0.0;
  for (const double r : steps.summary.segment_residuals_px) largest = std::max(largest, std::abs(r));
  constexpr double kLongestOfDiagonal = 0.06;
  const double scale = kLongestOfDiagonal * std::hypot(image->width_px, image->height_px) / largest;
  vp.residual_scale = std::isfinite(scale) && scale > 0.0 ? std::clamp(RoundScaleDown(scale), 1e-3, 1e6) : 1.0;
  vp.steps = std::move(steps);
  solver.document_revision = state->document.revision();
  solver.message = std::string("start: ") +
                   (amount != 0.0 ? "the fit's answer moved off by " + FormatNumber(100.0 * amount, 3) + " %"
                                  : std::string("the fit's closed form")) +
                   " on " + std::to_string(segments.size()) + " segments of " + PhotoName(*image) + ", cost " +
                   FormatNumber(vp.steps->summary.final_cost, 6) + " px^2";
  return true;
}

// The second photo of the pair: the chosen one, else the first other photo sharing 7 or more
// pinned vertices with the active one.
const Image* SecondPhoto(const AppState& state, const Image& a) {
  const Project& project = state.document.project();
  if (const Image* b = project.FindImage(state.teach.second_image_id); b != nullptr && b->id != a.id) return b;
  for (const Image& b : project.images) {
    if (b.id == a.id) continue;
    int shared = 0;
    for (const Pin& pa : project.pins)
      if (pa.image_id == a.id)
        for (const Pin& pb : project.pins)
          if (pb.image_id == b.id && pb.vertex == pa.vertex) {
            ++shared;
            break;
          }
    if (shared >= 7) return &b;
  }
  return nullptr;
}

bool BeginTwoViewSteps(AppState* state) {
  TeachSolverSteps& solver = state->teach.solver;
  TeachTwoViewSteps& two = solver.two_view;
  const Project& project = state->document.project();
  const Image* a = project.FindImage(state->active_image_id);
  const Image* b = a != nullptr ? SecondPhoto(*state, *a) : nullptr;
  if (b == nullptr) {
    solver.message = "two views: choose a second photo sharing 7 or more pinned vertices with the active one";
    return false;
  }
  std::vector<Eigen::Vector2d> uv_a, uv_b;
  std::vector<Id> pins_a, pins_b;
  for (const Pin& pa : project.pins) {
    if (pa.image_id != a->id) continue;
    for (const Pin& pb : project.pins) {
      if (pb.image_id != b->id || !(pb.vertex == pa.vertex)) continue;
      uv_a.push_back(FittedPixel(*a, pa.uv_px));
      uv_b.push_back(FittedPixel(*b, pb.uv_px));
      pins_a.push_back(pa.id);
      pins_b.push_back(pb.id);
      break;
    }
  }
  const std::string pair = PhotoName(*a) + " and " + PhotoName(*b);
  const FundamentalSummary full = EstimateFundamentalMatrix(uv_a, uv_b, FundamentalOptions());
  if (!full.IsUsable()) {
    solver.message = "two views " + pair + ": " + full.message;
    return false;
  }
  std::vector<Eigen::Vector2d> in_a, in_b;
  two.pins_a.clear();
  two.pins_b.clear();
  for (size_t i = 0; i < uv_a.size(); ++i) {
    if (!full.inliers[i]) continue;
    in_a.push_back(uv_a[i]);
    in_b.push_back(uv_b[i]);
    two.pins_a.push_back(pins_a[i]);
    two.pins_b.push_back(pins_b[i]);
  }
  FundamentalFitSteps steps;
  FundamentalSummary failure;
  const double amount = solver.start == TeachStepStart::kPerturbed ? solver.perturbation : 0.0;
  if (!BeginFundamentalFitSteps(in_a, in_b, FundamentalOptions(), amount, &steps, &failure)) {
    solver.message = "two views " + pair + ": " + failure.message;
    return false;
  }
  two.image_a = a->id;
  two.image_b = b->id;
  two.steps = std::move(steps);
  solver.document_revision = state->document.revision();
  solver.message = std::string("start: ") +
                   (amount != 0.0 ? "the refined F moved off by " + FormatNumber(100.0 * amount, 3) + " %"
                                  : std::string("the 8-point F")) +
                   " of " + pair + " on " + std::to_string(in_a.size()) + " of " + std::to_string(uv_a.size()) +
                   " matches, cost " + FormatNumber(two.steps->summary.final_cost, 6) + " px^2";
  return true;
}

bool StepVp(AppState* state) {
  TeachSolverSteps& solver = state->teach.solver;
  if (!solver.vp.steps && !BeginVpSteps(state)) return false;
  VpFitSteps& steps = *solver.vp.steps;
  if (steps.finished) {
    solver.message = "the fit has finished: Reset to step again";
    return false;
  }
  VpCalibrationSummary failure;
  if (!StepVpFit(&steps, &failure)) {
    solver.message = "the step failed: " + failure.message;
    return false;
  }
  solver.message = StepMessage(steps.steps, steps.summary.final_cost, steps.finished, steps.summary.termination,
                               ", f = " + FormatNumber(steps.summary.focal_px, 6) + " px");
  return true;
}

bool StepTwoView(AppState* state) {
  TeachSolverSteps& solver = state->teach.solver;
  if (!solver.two_view.steps && !BeginTwoViewSteps(state)) return false;
  FundamentalFitSteps& steps = *solver.two_view.steps;
  if (steps.finished) {
    solver.message = "the refinement has finished: Reset to step again";
    return false;
  }
  FundamentalSummary failure;
  if (!StepFundamentalFit(&steps, &failure)) {
    solver.message = "the step failed: " + failure.message;
    return false;
  }
  solver.message =
      StepMessage(steps.steps, steps.summary.final_cost, steps.finished, steps.summary.termination,
                  ", symmetric epipolar RMS " + FormatNumber(steps.summary.symmetric_epipolar_rms_px, 5) + " px");
  return true;
}

}  // namespace

const char* TeachStepSubjectName(TeachStepSubject subject) {
  switch (subject) {
    case TeachStepSubject::kJointSolve: return "joint";
    case TeachStepSubject::kVanishingPoints: return "vanishing";
    case TeachStepSubject::kTwoView: return "two-view";
  }
  return "joint";
}

std::optional<TeachStepSubject> TeachStepSubjectFromName(const std::string& name) {
  if (name == "joint") return TeachStepSubject::kJointSolve;
  if (name == "vanishing") return TeachStepSubject::kVanishingPoints;
  if (name == "two-view") return TeachStepSubject::kTwoView;
  return std::nullopt;
}

bool TeachStepping(const AppState& state) {
  const TeachSolverSteps& solver = state.teach.solver;
  if (!state.teach.solver_steps || solver.document_revision != state.document.revision()) return false;
  switch (solver.subject) {
    case TeachStepSubject::kJointSolve: return TeachSteppedProject(state) != nullptr;
    case TeachStepSubject::kVanishingPoints: return solver.vp.steps.has_value();
    case TeachStepSubject::kTwoView: return solver.two_view.steps.has_value();
  }
  return false;
}

bool TeachStep(AppState* state) {
  state->teach.solver_steps = true;
  UpdateTeachSteps(state);
  TeachSolverSteps& solver = state->teach.solver;
  if (solver.subject == TeachStepSubject::kVanishingPoints) return StepVp(state);
  if (solver.subject == TeachStepSubject::kTwoView) return StepTwoView(state);
  if (!solver.steps) BeginSteps(state);
  if (solver.steps->finished) {
    solver.message = "the solve has finished (" +
                     std::string(SolverTerminationName(solver.steps->summary.termination)) + "): Reset to step again";
    return false;
  }
  JointSolveSummary failure;
  if (!StepJointSolve(&*solver.steps, &failure)) {
    // Nothing stepped yet: the panels go back to the project rather than show a start that
    // cannot be solved.
    if (solver.steps->steps == 0) TeachEndSteps(state);
    solver.message = "the step failed: " + failure.message;
    return false;
  }
  const JointSolveSteps& steps = *solver.steps;
  solver.message =
      "step " + std::to_string(steps.steps) + ": observation cost " + FormatNumber(steps.summary.final_cost, 6) +
      " px^2" +
      (steps.finished ? std::string(", finished (") + SolverTerminationName(steps.summary.termination) + ")"
                      : std::string());
  RefreshSteppedMesh(&solver);
  return true;
}

void TeachResetSteps(AppState* state) {
  UpdateTeachSteps(state);
  TeachSolverSteps& solver = state->teach.solver;
  if (solver.subject == TeachStepSubject::kVanishingPoints) {
    if (!solver.vp.steps) return;
    ResetVpFitSteps(&*solver.vp.steps);
    solver.message = "reset to the start";
    return;
  }
  if (solver.subject == TeachStepSubject::kTwoView) {
    if (!solver.two_view.steps) return;
    ResetFundamentalFitSteps(&*solver.two_view.steps);
    solver.message = "reset to the start";
    return;
  }
  if (!solver.steps) return;
  ResetJointSolveSteps(&*solver.steps);
  solver.message = "reset to the start";
  RefreshSteppedMesh(&solver);
}

void TeachEndSteps(AppState* state) {
  state->teach.solver.steps.reset();
  state->teach.solver.vp.steps.reset();
  state->teach.solver.two_view.steps.reset();
  state->teach.solver.mesh = TexturedMesh();
  ++state->teach.solver.mesh_revision;
}

void UpdateTeachSteps(AppState* state) {
  const TeachSolverSteps& solver = state->teach.solver;
  const bool any = solver.steps || solver.vp.steps || solver.two_view.steps;
  if (any && (!state->teach.solver_steps || solver.document_revision != state->document.revision()))
    TeachEndSteps(state);
}

std::vector<TeachVpSegmentResidual> TeachVpResiduals(const AppState& state) {
  std::vector<TeachVpSegmentResidual> out;
  const TeachVpSteps& vp = state.teach.solver.vp;
  if (!TeachStepping(state) || state.teach.solver.subject != TeachStepSubject::kVanishingPoints) return out;
  const VpFitSteps& steps = *vp.steps;
  for (size_t i = 0; i < steps.segments.size(); ++i) {
    const Segment& s = steps.segments[i];
    const int axis = static_cast<int>(s.axis);
    const Eigen::Vector3d& v = steps.summary.vanishing_points[axis];
    TeachVpSegmentResidual r;
    r.segment_id = vp.segment_ids[i];
    r.axis = axis;
    r.a_px = s.a_px;
    r.b_px = s.b_px;
    r.residual_px = steps.summary.segment_residuals_px[i];
    // The line through the midpoint m and v: direction v_xy - v_z m (at infinity: v_xy).
    const Eigen::Vector2d m = 0.5 * (s.a_px + s.b_px);
    const Eigen::Vector2d d = v.head<2>() - v.z() * m;
    if (d.norm() > 0.0) {
      const Eigen::Vector2d u = d.normalized();
      r.offset_a_px = m + u * u.dot(s.a_px - m) - s.a_px;
      r.offset_b_px = m + u * u.dot(s.b_px - m) - s.b_px;
    }
    out.push_back(r);
  }
  return out;
}

std::vector<TeachEpipolarMatch> TeachEpipolarMatches(const AppState& state) {
  std::vector<TeachEpipolarMatch> out;
  const TeachTwoViewSteps& two = state.teach.solver.two_view;
  if (!TeachStepping(state) || state.teach.solver.subject != TeachStepSubject::kTwoView) return out;
  const FundamentalFitSteps& steps = *two.steps;
  const Eigen::Matrix3d& f = steps.summary.F;
  const Eigen::Matrix3d& f0 = steps.path.front();
  const auto unit = [](const Eigen::Vector3d& l) {
    const double n = l.head<2>().norm();
    return n > 0.0 ? Eigen::Vector3d(l / n) : Eigen::Vector3d::Zero().eval();
  };
  // A few matches spread over the list, so that the lines stay readable.
  constexpr size_t kDrawn = 6;
  const size_t n = steps.uv1.size();
  for (size_t i = 0; i < n; ++i) {
    TeachEpipolarMatch m;
    m.pin_a = two.pins_a[i];
    m.pin_b = two.pins_b[i];
    m.uv_a = steps.uv1[i];
    m.uv_b = steps.uv2[i];
    const Eigen::Vector3d xa(m.uv_a.x(), m.uv_a.y(), 1.0), xb(m.uv_b.x(), m.uv_b.y(), 1.0);
    m.line_in_b = unit(f * xa);
    m.line_in_a = unit(f.transpose() * xb);
    m.start_line_in_b = unit(f0 * xa);
    m.start_line_in_a = unit(f0.transpose() * xb);
    m.distances_px = SymmetricEpipolarDistances(f, m.uv_a, m.uv_b);
    m.drawn = n <= kDrawn || i * kDrawn / n != (i + 1) * kDrawn / n;
    out.push_back(m);
  }
  return out;
}

}  // namespace facet::app
