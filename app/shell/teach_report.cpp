#include "app/shell/teach_report.h"

#include <imgui.h>

namespace facet::app {
namespace {

// Non-finite numbers become null (JSON has no NaN).
nlohmann::json Number(double x) { return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(nullptr); }

nlohmann::json Matrix(const Eigen::Ref<const Eigen::MatrixXd>& m) {
  nlohmann::json rows = nlohmann::json::array();
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    nlohmann::json row = nlohmann::json::array();
    for (Eigen::Index c = 0; c < m.cols(); ++c) row.push_back(Number(m(r, c)));
    rows.push_back(row);
  }
  return rows;
}

nlohmann::json Vector(const Eigen::Ref<const Eigen::VectorXd>& v) {
  nlohmann::json out = nlohmann::json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) out.push_back(Number(v(i)));
  return out;
}

nlohmann::json VanishingJson(const TeachVanishing& t) {
  const VanishingConstruction& c = t.construction;
  nlohmann::json constructions = nlohmann::json::array();
  for (const FocalConstruction& f : c.focal_constructions)
    constructions.push_back({{"axes", {f.axes[0], f.axes[1]}},
                             {"valid", f.valid},
                             {"circle_center_px", Vector(f.circle_center_px)},
                             {"circle_radius_px", Number(f.circle_radius_px)},
                             {"altitude_foot_px", Vector(f.altitude_foot_px)},
                             {"turned_center_px", Vector(f.turned_center_px)},
                             {"focal_end_px", Vector(f.focal_end_px)},
                             {"focal_px", Number(f.focal_px)}});
  nlohmann::json points = nlohmann::json::array(), homogeneous = nlohmann::json::array(),
                 covariances = nlohmann::json::array(), feet = nlohmann::json::array(),
                 directions = nlohmann::json::array();
  for (int a = 0; a < 3; ++a) {
    points.push_back(c.finite[a] ? Vector(c.points_px[a]) : nlohmann::json(nullptr));
    homogeneous.push_back(Vector(t.vanishing_points_px[a]));
    covariances.push_back(Matrix(t.covariance_px2[a]));
    feet.push_back(Vector(c.altitude_feet_px[a]));
    directions.push_back(Vector(t.directions_in_world[a]));
  }
  return {{"image_id", t.image_id},
          {"kind", VanishingConstructionKindName(c.kind)},
          {"present", {c.present[0], c.present[1], c.present[2]}},
          {"finite", {c.finite[0], c.finite[1], c.finite[2]}},
          {"points_px", points},
          {"vanishing_points_px", homogeneous},
          {"covariance_px2", covariances},
          {"principal_point_px", Vector(c.principal_point_px)},
          {"principal_point_assumed", c.principal_point_assumed},
          {"altitude_feet_px", feet},
          {"focal_constructions", constructions},
          {"focal_px", Number(c.focal_px)},
          {"focal_assumed", c.focal_assumed},
          {"horizon", Vector(c.horizon)},
          {"assumptions", t.assumptions},
          {"fitted_focal_px", Number(t.fitted_focal_px)},
          {"camera_center_in_world", Vector(t.camera_center_in_world)},
          {"directions_in_world", directions}};
}

nlohmann::json TraceJson(const std::vector<LmIteration>& trace, double cost_unit) {
  nlohmann::json out = nlohmann::json::array();
  for (const LmIteration& it : trace)
    out.push_back({{"iteration", it.iteration},
                   {"cost", Number(it.cost * cost_unit)},
                   {"trial_cost", Number(it.trial_cost * cost_unit)},
                   {"lambda", Number(it.lambda)},
                   {"step_norm", Number(std::sqrt(it.step_squared_norm))},
                   {"accepted", it.accepted}});
  return out;
}

// The stepped vanishing-point fit: per step (the start first) f, principal point, the
// vanishing points and the cost; the trace (cost in px^2); per segment the residual drawn.
nlohmann::json VpStepsJson(const AppState& state) {
  const TeachVpSteps& vp = state.teach.solver.vp;
  const VpFitSteps& steps = *vp.steps;
  nlohmann::json path = nlohmann::json::array();
  for (const VpFitState& p : steps.path) {
    nlohmann::json points = nlohmann::json::array();
    for (int a = 0; a < 3; ++a) points.push_back(Vector(p.vanishing_points[a]));
    path.push_back({{"focal_px", Number(p.focal_px)},
                    {"principal_point_px", Vector(p.principal_point_px)},
                    {"vanishing_points", points},
                    {"cost", Number(p.cost_px2)}});
  }
  nlohmann::json segments = nlohmann::json::array();
  for (const TeachVpSegmentResidual& r : TeachVpResiduals(state))
    segments.push_back({{"segment_id", r.segment_id},
                        {"axis", r.axis},
                        {"a_px", Vector(r.a_px)},
                        {"b_px", Vector(r.b_px)},
                        {"offset_a_px", Vector(r.offset_a_px)},
                        {"offset_b_px", Vector(r.offset_b_px)},
                        {"residual_px", Number(r.residual_px)}});
  const double px2 = steps.summary.conditioning_scale_px * steps.summary.conditioning_scale_px;
  return {{"image_id", vp.image_id},
          {"steps", steps.steps},
          {"finished", steps.finished},
          {"termination", SolverTerminationName(steps.summary.termination)},
          {"residual_scale", vp.residual_scale},
          {"focal_px", Number(steps.summary.focal_px)},
          {"cam_from_world_rotation", Matrix(steps.summary.cam_from_world_rotation)},
          {"path", path},
          {"trace", TraceJson(steps.trace, px2)},
          {"segments", segments}};
}

// The stepped two-view refinement: F per step (the start first), the trace, per match the
// current and the start's epipolar lines and the symmetric distances.
nlohmann::json TwoViewStepsJson(const AppState& state) {
  const TeachTwoViewSteps& two = state.teach.solver.two_view;
  const FundamentalFitSteps& steps = *two.steps;
  nlohmann::json path = nlohmann::json::array();
  for (const Eigen::Matrix3d& f : steps.path) path.push_back(Matrix(f));
  nlohmann::json matches = nlohmann::json::array();
  for (const TeachEpipolarMatch& m : TeachEpipolarMatches(state))
    matches.push_back({{"pin_a", m.pin_a},
                       {"pin_b", m.pin_b},
                       {"uv_a", Vector(m.uv_a)},
                       {"uv_b", Vector(m.uv_b)},
                       {"line_in_a", Vector(m.line_in_a)},
                       {"line_in_b", Vector(m.line_in_b)},
                       {"start_line_in_a", Vector(m.start_line_in_a)},
                       {"start_line_in_b", Vector(m.start_line_in_b)},
                       {"distances_px", Vector(m.distances_px)},
                       {"drawn", m.drawn}});
  return {{"image_a", two.image_a},
          {"image_b", two.image_b},
          {"steps", steps.steps},
          {"finished", steps.finished},
          {"termination", SolverTerminationName(steps.summary.termination)},
          {"F", Matrix(steps.summary.F)},
          {"cost", Number(steps.summary.final_cost)},
          {"symmetric_epipolar_rms_px", Number(steps.summary.symmetric_epipolar_rms_px)},
          {"path", path},
          {"trace", TraceJson(steps.trace, 1.0)},
          {"matches", matches}};
}

// The Solver steps window's state: what is stepped, the trace, the constraint violations and
// the residual vectors drawn, and the stepped cameras and primitives (full precision, so a
// test compares them with its own solve).
nlohmann::json StepsJson(const AppState& state) {
  const TeachSolverSteps& solver = state.teach.solver;
  const Project* stepped = TeachSteppedProject(state);
  nlohmann::json out = {{"on", state.teach.solver_steps},
                        {"start", TeachStepStartName(solver.start)},
                        {"perturbation", solver.perturbation},
                        {"active", stepped != nullptr},
                        {"message", solver.message},
                        {"residual_scale", solver.residual_scale},
                        {"subject", TeachStepSubjectName(solver.subject)}};
  if (TeachStepping(state) && solver.subject == TeachStepSubject::kVanishingPoints) out["vanishing"] = VpStepsJson(state);
  if (TeachStepping(state) && solver.subject == TeachStepSubject::kTwoView) out["two_view"] = TwoViewStepsJson(state);
  if (stepped == nullptr) return out;
  const JointSolveSteps& steps = *solver.steps;
  out["steps"] = steps.steps;
  out["finished"] = steps.finished;
  out["termination"] = steps.steps > 0 ? SolverTerminationName(steps.summary.termination) : "";
  out["initial_cost"] = steps.steps > 0 ? Number(steps.summary.initial_cost) : nlohmann::json(nullptr);
  out["final_cost"] = steps.steps > 0 ? Number(steps.summary.final_cost) : nlohmann::json(nullptr);
  nlohmann::json trace = nlohmann::json::array();
  for (const LmIteration& it : steps.trace)
    trace.push_back({{"iteration", it.iteration},
                     {"cost", Number(it.cost)},
                     {"trial_cost", Number(it.trial_cost)},
                     {"lambda", Number(it.lambda)},
                     {"step_norm", Number(std::sqrt(it.step_squared_norm))},
                     {"accepted", it.accepted}});
  out["trace"] = trace;
  nlohmann::json constraints = nlohmann::json::array();
  if (steps.steps > 0)
    for (const ConstraintDiagnostic& c : steps.summary.constraints)
      constraints.push_back({{"constraint_id", c.constraint_id},
                             {"residual", Number(c.residual)},
                             {"unit", c.unit},
                             {"satisfied", c.satisfied}});
  out["constraints"] = constraints;
  nlohmann::json pins = nlohmann::json::array();
  for (const TeachPinResidual& r : TeachPinResiduals(*stepped))
    pins.push_back({{"pin_id", r.pin_id},
                    {"image_id", r.image_id},
                    {"uv_px", Vector(r.uv_px)},
                    {"projection_px", Vector(r.projection_px)},
                    {"residual_px", Vector(r.residual_px)}});
  out["pins"] = pins;
  nlohmann::json images = nlohmann::json::array();
  for (const Image& image : stepped->images)
    images.push_back({{"id", image.id},
                      {"focal_px", image.camera.focal_px},
                      {"principal_point_px", Vector(image.camera.principal_point_px)},
                      {"cam_from_world_rotation", Matrix(image.camera.cam_from_world_rotation)},
                      {"cam_from_world_translation", Vector(image.camera.cam_from_world_translation)}});
  out["images"] = images;
  nlohmann::json primitives = nlohmann::json::array();
  for (const Primitive& primitive : stepped->primitives)
    primitives.push_back({{"id", primitive.id},
                          {"params", Vector(primitive.shape.params)},
                          {"rotation", Vector(primitive.shape.rotation)},
                          {"translation", Vector(primitive.shape.translation)}});
  out["primitives"] = primitives;
  return out;
}

nlohmann::json RaysJson(const AppState& state) {
  nlohmann::json out = nlohmann::json::array();
  for (const TeachRayPair& r : TeachRayPairs(state))
    out.push_back({{"vertex", {{"primitive_id", r.vertex.primitive_id}, {"vertex", r.vertex.vertex}}},
                   {"pin_a", r.pin_a},
                   {"pin_b", r.pin_b},
                   {"image_a", r.image_a},
                   {"image_b", r.image_b},
                   {"center_a", Vector(r.center_a)},
                   {"center_b", Vector(r.center_b)},
                   {"direction_a", Vector(r.direction_a)},
                   {"direction_b", Vector(r.direction_b)},
                   {"s", Number(r.closest.s)},
                   {"t", Number(r.closest.t)},
                   {"on_a", Vector(r.closest.on_a)},
                   {"on_b", Vector(r.closest.on_b)},
                   {"midpoint", Vector(r.closest.midpoint)},
                   {"gap", Number(r.closest.gap)},
                   {"gap_px_in_a", Number(r.gap_px_in_a)},
                   {"gap_px_in_b", Number(r.gap_px_in_b)}});
  return out;
}

}  // namespace

nlohmann::json TeachReportJson(const AppState& state) {
  const TeachView& view = state.teach;
  nlohmann::json out;
  out["view"] = {{"vanishing", view.vanishing_points},
                 {"epipolar", view.epipolar},
                 {"numbers", view.numbers},
                 {"state", view.modelling_state},
                 {"steps", view.solver_steps},
                 {"second_image_id", view.second_image_id}};
  nlohmann::json vanishing = nlohmann::json::array();
  for (const Image& image : state.document.project().images)
    if (const std::optional<TeachVanishing> t = TeachVanishingFor(state, image.id)) {
      vanishing.push_back(VanishingJson(*t));
      vanishing.back()["extended_segment_ids"] = TeachExtendedSegments(state, image.id, t->construction);
    }
  out["vanishing"] = vanishing;
  nlohmann::json lines = nlohmann::json::array();
  for (const TeachEpipolarLine& l : TeachEpipolarLines(state))
    lines.push_back({{"from_image_id", l.from_image_id},
                     {"in_image_id", l.in_image_id},
                     {"from_uv_px", Vector(l.from_uv_px)},
                     {"from_pointer", l.from_pointer},
                     {"pin_id", l.pin_id},
                     {"line", Vector(l.line)},
                     {"epipole", Vector(l.epipole)},
                     {"pin_distance_px", Number(l.pin_distance_px)}});
  out["epipolar"] = lines;
  out["rays"] = RaysJson(state);
  out["steps"] = StepsJson(state);
  if (const std::optional<TeachNumbers> n = TeachNumbersFor(state)) {
    out["numbers"] = {{"image_id", n->image_id},
                      {"K", Matrix(n->K)},
                      {"R", Matrix(n->R)},
                      {"t", Vector(n->t)},
                      {"center", Vector(n->center)},
                      {"second_image_id", n->second_image_id},
                      {"F", Matrix(n->F)},
                      {"epipole_in_a", Vector(n->epipole_in_a)},
                      {"epipole_in_b", Vector(n->epipole_in_b)}};
  }
  nlohmann::json counts = nlohmann::json::array();
  for (const ModellingStateCounts& c : HistoryStateCounts(state.document))
    counts.push_back({{"primitives", c.primitives},
                      {"vertices", c.vertices},
                      {"edges", c.edges},
                      {"faces", c.faces},
                      {"pins", c.pins},
                      {"spatial_constraints", c.spatial_constraints},
                      {"images", c.images},
                      {"segments", c.segments}});
  out["history_counts"] = counts;
  out["degrees_of_freedom_left"] = state.last_update.joint.degrees_of_freedom_left;
  const char* clipboard = ImGui::GetCurrentContext() != nullptr ? ImGui::GetClipboardText() : nullptr;
  out["clipboard"] = clipboard != nullptr ? clipboard : "";
  return out;
}

}  // namespace facet::app
