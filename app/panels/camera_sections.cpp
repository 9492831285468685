#include "app/panels/camera_sections.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <sstream>
#include <vector>

#include <imgui.h>

#include "app/panels/texture_sections.h"
#include "app/panels/widgets.h"
#include "app/state/calgui_exif_prior.h"
#include "app/state/model_edits.h"
#include "core/io/project_io.h"
#include "core/solve/scene_solve.h"

namespace facet::app {

namespace {

const char* const kPrincipalPointModes[] = {"Solve (3 VPs)", "Image centre", "Fixed"};
const char* const kFocalModes[] = {"Solve from lines", "Known focal", "Prior"};

std::string PhotoPath(const AppState& state, const Image& image) {
  return state.project_path.empty() ? image.path : ResolveImagePath(state.project_path, image.path);
}

// The horizon (x1, y1, x2, y2) level at row v across the whole image.
Eigen::Vector4d LevelHorizon(const Image& image, double v_px) {
  return Eigen::Vector4d(0.0, v_px, std::max(1, image.width_px - 1), v_px);
}

// A starting horizon when the user turns it on: the fitted one (the line through the x and y
// vanishing points) where it crosses the image's left and right borders, else level through
// the image centre.
Eigen::Vector4d DefaultHorizon(const AppState& state, const Image& image) {
  const double w = std::max(1, image.width_px - 1);
  const Eigen::Vector4d level = LevelHorizon(image, 0.5 * std::max(0, image.height_px - 1));
  const auto cal = state.last_update.calibration.find(image.id);
  if (cal == state.last_update.calibration.end() || !cal->second.IsUsable()) return level;
  const Eigen::Vector3d& vx = cal->second.vanishing_points[0];
  const Eigen::Vector3d& vy = cal->second.vanishing_points[1];
  if (vx.squaredNorm() == 0.0 || vy.squaredNorm() == 0.0) return level;
  const Eigen::Vector3d line = vx.cross(vy);                            // a u + b v + c = 0
  if (std::abs(line.y()) < 1e-9 * line.head<2>().norm()) return level;  // vertical: not a horizon
  auto v_at = [&](double u) { return -(line.x() * u + line.z()) / line.y(); };
  return Eigen::Vector4d(0.0, v_at(0.0), w, v_at(w));
}

// Fields a newly chosen mode needs, from the current camera when the user never set them.
void SeedFocalMode(FocalMode mode, Image* image) {
  image->focal_mode = mode;
  const double f = image->camera.focal_px > 0.0 ? image->camera.focal_px : std::max(image->width_px, image->height_px);
  if (mode == FocalMode::kFixed && !(image->fixed_focal_px > 0.0)) image->fixed_focal_px = f;
  if (mode == FocalMode::kPrior && !(image->focal_prior_px > 0.0)) image->focal_prior_px = f;
  // 10 %: a guess, wider than an EXIF prior's few percent (app/state/calgui_exif_prior.h).
  if (mode == FocalMode::kPrior && !(image->focal_prior_std_px > 0.0))
    image->focal_prior_std_px = 0.1 * image->focal_prior_px;
}

void SeedPrincipalPointMode(PrincipalPointMode mode, Image* image) {
  image->principal_point_mode = mode;
  if (mode == PrincipalPointMode::kFixed && image->fixed_principal_point_px.isZero()) {
    image->fixed_principal_point_px = image->camera_calibrated
                                          ? image->camera.principal_point_px
                                          : Eigen::Vector2d(0.5 * (image->width_px - 1), 0.5 * (image->height_px - 1));
  }
}

// Edits the active image of a project copy and commits it as one history entry.
void CommitImageEdit(AppState* state, Id image_id, const std::string& label, const std::function<void(Image*)>& apply) {
  Project edited = state->document.project();
  Image* image = edited.FindImage(image_id);
  if (image == nullptr) return;
  apply(image);
  CommitEdit(state, label, std::move(edited));
}

// TrackEdit on one image's fields (continuous widgets: one entry per drag).
void TrackImageEdit(AppState* state, Id image_id, const std::string& label, bool changed,
                    const std::function<void(Image*)>& apply) {
  TrackEdit(state, label, changed, [&](Project* p) {
    if (Image* image = p->FindImage(image_id)) apply(image);
  });
}

void FromExif(AppState* state, const Image& image, ExifFeedback* feedback) {
  const ExifFocalPrior prior = ReadExifFocalPrior(PhotoPath(*state, image), image);
  *feedback = {image.id, prior.found, prior.message};
  if (!prior.found) {
    state->Log(LogLevel::kWarning, prior.message);
    return;
  }
  state->Log(LogLevel::kInfo, prior.message);
  CommitImageEdit(state, image.id, "Focal prior from EXIF", [&](Image* im) { ApplyExifFocalPrior(prior, im); });
}

void DrawCalibrationControls(AppState* state, const Image& image, ExifFeedback* exif_feedback) {
  const Id id = image.id;
  const float full = -FLT_MIN;

  int pp_mode = static_cast<int>(image.principal_point_mode);
  ImGui::TextColored(kDimText, "Principal pt");
  ImGui::SameLine(ImGui::GetFontSize() * 7.5f);
  ImGui::SetNextItemWidth(full);
  if (ImGui::Combo("##pp_mode", &pp_mode, kPrincipalPointModes, 3)) {
    CommitImageEdit(state, id, "Principal point mode",
                    [&](Image* im) { SeedPrincipalPointMode(static_cast<PrincipalPointMode>(pp_mode), im); });
  }
  RecordItem(state, "calibration.pp_mode");
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("How calibration treats the principal point");
  if (image.principal_point_mode == PrincipalPointMode::kFixed) {
    double pp[2] = {image.fixed_principal_point_px.x(), image.fixed_principal_point_px.y()};
    ImGui::SetNextItemWidth(full);
    const bool changed = DragDoubles("##pp_fixed", pp, 2, 0.5f, "%.1f px");
    RecordItem(state, "calibration.pp_fixed");
    TrackImageEdit(state, id, "Fixed principal point", changed,
                   [&](Image* im) { im->fixed_principal_point_px = Eigen::Vector2d(pp[0], pp[1]); });
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Principal point u, v in px (may lie outside a cropped photo)");
  }

  int focal_mode = static_cast<int>(image.focal_mode);
  ImGui::TextColored(kDimText, "Focal");
  ImGui::SameLine(ImGui::GetFontSize() * 7.5f);
  const float exif_width = ImGui::CalcTextSize("EXIF").x + 2.0f * ImGui::GetStyle().FramePadding.x;
  ImGui::SetNextItemWidth(-(exif_width + ImGui::GetStyle().ItemSpacing.x));
  if (ImGui::Combo("##focal_mode", &focal_mode, kFocalModes, 3)) {
    CommitImageEdit(state, id, "Focal mode", [&](Image* im) { SeedFocalMode(static_cast<FocalMode>(focal_mode), im); });
  }
  RecordItem(state, "calibration.focal_mode");
  if (ImGui::IsItemHovered()) {
    ImGui::SetTooltip(
        "Solve: from the vanishing points. Known focal: a calibrated lens.\n"
        "Prior: solved, pulled towards a value +- std (e.g. from EXIF).");
  }
  ImGui::SameLine();
  if (ImGui::Button("EXIF")) FromExif(state, image, exif_feedback);
  RecordItem(state, "calibration.from_exif");
  if (ImGui::IsItemHovered()) {
    ImGui::SetTooltip(
        "From EXIF: focal prior from the photo's 35 mm-equivalent focal length,\n"
        "+- ~3 %% (the spread between the makers' equivalence conventions)");
  }
  if (image.focal_mode == FocalMode::kFixed) {
    double f = image.fixed_focal_px;
    ImGui::SetNextItemWidth(full);
    const bool changed =
        ImGui::DragScalar("##focal_fixed", ImGuiDataType_Double, &f, 1.0f, nullptr, nullptr, "%.1f px");
    RecordItem(state, "calibration.focal_fixed");
    TrackImageEdit(state, id, "Known focal", changed && f > 0.0, [&](Image* im) { im->fixed_focal_px = f; });
  } else if (image.focal_mode == FocalMode::kPrior) {
    double prior[2] = {image.focal_prior_px, image.focal_prior_std_px};
    ImGui::SetNextItemWidth(full);
    const bool changed = DragDoubles("##focal_prior", prior, 2, 1.0f, "%.1f px");
    RecordItem(state, "calibration.focal_prior");
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Prior focal length and its standard deviation, px");
    TrackImageEdit(state, id, "Focal prior", changed && prior[0] > 0.0 && prior[1] > 0.0, [&](Image* im) {
      im->focal_prior_px = prior[0];
      im->focal_prior_std_px = prior[1];
    });
  }
  const ExifFeedback& feedback = *exif_feedback;
  if (feedback.image_id == id && !feedback.message.empty()) {
    WrappedColored(feedback.found ? kDimText : kWarningText, feedback.message);
  }

  bool use_horizon = image.use_horizon;
  if (ImGui::Checkbox("Use horizon", &use_horizon)) {
    const Eigen::Vector4d start = DefaultHorizon(*state, image);
    CommitImageEdit(state, id, use_horizon ? "Use horizon" : "No horizon", [&](Image* im) {
      im->use_horizon = use_horizon;
      if (use_horizon && im->horizon_px.isZero()) im->horizon_px = start;
    });
  }
  RecordItem(state, "calibration.use_horizon");
  if (ImGui::IsItemHovered()) {
    ImGui::SetTooltip(
        "The image of the horizontal plane at infinity: with a known focal\n"
        "length, one horizontal line family is then enough");
  }
  if (image.use_horizon) {
    double h[4] = {image.horizon_px[0], image.horizon_px[1], image.horizon_px[2], image.horizon_px[3]};
    ImGui::SetNextItemWidth(full);
    const bool changed = DragDoubles("##horizon_a", h, 2, 0.5f, "%.1f");
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("First horizon point u, v (px)");
    TrackImageEdit(state, id, "Horizon", changed,
                   [&](Image* im) { im->horizon_px.head<2>() = Eigen::Vector2d(h[0], h[1]); });
    ImGui::SetNextItemWidth(full);
    const bool changed_b = DragDoubles("##horizon_b", h + 2, 2, 0.5f, "%.1f");
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Second horizon point u, v (px)");
    TrackImageEdit(state, id, "Horizon", changed_b,
                   [&](Image* im) { im->horizon_px.tail<2>() = Eigen::Vector2d(h[2], h[3]); });
    double row = 0.5 * (h[1] + h[3]);
    ImGui::TextColored(kDimText, "Level at row");
    ImGui::SameLine(ImGui::GetFontSize() * 7.5f);
    ImGui::SetNextItemWidth(full);
    const bool level =
        ImGui::DragScalar("##horizon_level", ImGuiDataType_Double, &row, 0.5f, nullptr, nullptr, "%.1f px");
    RecordItem(state, "calibration.horizon_level");
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Sets a level horizon across the image at this row");
    TrackImageEdit(state, id, "Level horizon", level, [&](Image* im) { im->horizon_px = LevelHorizon(*im, row); });
  }

  bool estimate = image.estimate_distortion;
  if (ImGui::Checkbox("Estimate distortion (from lines)", &estimate)) {
    CommitImageEdit(state, id, estimate ? "Estimate distortion" : "No distortion estimate",
                    [&](Image* im) { im->estimate_distortion = estimate; });
  }
  RecordItem(state, "calibration.estimate_distortion");
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Radial k1, k2 from the straightness of the drawn segments");
  // What the joint solve may refine with the model (each kept as calibration gave it when locked).
  bool focal_locked = image.focal_locked;
  if (ImGui::Checkbox("Lock focal", &focal_locked)) {
    CommitImageEdit(state, id, focal_locked ? "Lock focal" : "Unlock focal",
                    [&](Image* im) { im->focal_locked = focal_locked; });
  }
  RecordItem(state, "calibration.focal_locked");
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Unlocked: the joint solve refines the focal length with the model");
  ImGui::SameLine();
  bool pp_locked = image.principal_point_locked;
  if (ImGui::Checkbox("Lock principal pt", &pp_locked)) {
    CommitImageEdit(state, id, pp_locked ? "Lock principal point" : "Unlock principal point",
                    [&](Image* im) { im->principal_point_locked = pp_locked; });
  }
  RecordItem(state, "calibration.principal_point_locked");
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Unlocked: the joint solve refines the principal point with the model");
  // Calibration groups (PhotoModeler, Metashape): photos from one camera and lens share one
  // focal length, principal point and k1, k2 in the joint solve. The checkbox joins group 1;
  // `calibration lens-group N` picks any group.
  bool shared_lens = image.lens_group > 0;
  if (ImGui::Checkbox("Same lens as other photos", &shared_lens)) {
    CommitImageEdit(state, id, shared_lens ? "Share the lens" : "Own lens",
                    [&](Image* im) { im->lens_group = shared_lens ? 1 : 0; });
  }
  RecordItem(state, "calibration.lens_group");
  if (ImGui::IsItemHovered()) {
    ImGui::SetTooltip(
        "Photos ticked here were taken with one camera and lens: the joint solve gives them one\n"
        "focal length (and principal point, distortion) where their locks are off%s",
        image.lens_group > 1 ? ("\nThis photo is in lens group " + std::to_string(image.lens_group)).c_str() : "");
  }
  bool locked = image.distortion_locked;
  if (ImGui::Checkbox("Lock distortion", &locked)) {
    CommitImageEdit(state, id, locked ? "Lock distortion" : "Unlock distortion",
                    [&](Image* im) { im->distortion_locked = locked; });
  }
  RecordItem(state, "calibration.distortion_locked");
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Unlocked: the joint solve refines k1, k2 with the model");
  bool pose_locked = image.pose_locked;
  if (ImGui::Checkbox("Lock camera position", &pose_locked)) {
    CommitImageEdit(state, id, pose_locked ? "Lock camera" : "Unlock camera",
                    [&](Image* im) { im->pose_locked = pose_locked; });
  }
}

// "1.2" or "-" for a NaN std (an undetermined parameter).
std::string Std(double v, const char* fmt = "%.1f") {
  if (!std::isfinite(v)) return "?";
  char text[32];
  std::snprintf(text, sizeof(text), fmt, v);
  return text;
}

void DrawCalibrationResult(AppState* state, const Image& image) {
  const auto cal = state->last_update.calibration.find(image.id);
  if (cal == state->last_update.calibration.end()) {
    ImGui::TextColored(kDimText, "No line families drawn in this image.");
    return;
  }
  const VpCalibrationSummary& c = cal->second;
  // An unfinished drawing is progress, not a failure: red is kept for what went wrong.
  const ImVec4 status_color = c.IsUsable() ? kGoodText : c.incomplete ? kDimText : kErrorText;
  ImGui::TextColored(status_color, "%s", c.IsUsable() ? "Calibrated" : c.incomplete ? "More lines needed" : "Failed");
  RecordItem(state, "calibration.status");
  for (int a = 0; a < 3; ++a) {
    ImGui::SameLine();
    ImGui::TextColored(AxisColor(static_cast<Axis>(a)), "%s %d", AxisName(static_cast<Axis>(a)),
                       c.segments_per_axis[a]);
  }
  if (c.IsUsable()) {
    const Camera& cam = image.camera;
    if (image.focal_mode == FocalMode::kFixed) {
      LabelValue("Focal", "%.1f px (known)", c.focal_px);
    } else {
      LabelValue("Focal", "%.1f +- %s px", c.focal_px, Std(c.focal_std_px).c_str());
    }
    RecordItem(state, "calibration.result_focal");
    const Eigen::Vector2d& pp = c.principal_point_px;
    if (image.principal_point_mode == PrincipalPointMode::kSolve && c.principal_point_std_px.squaredNorm() > 0.0) {
      LabelValue("Principal pt", "%.1f, %.1f px", pp.x(), pp.y());
      LabelValue("", "+- %s, %s px", Std(c.principal_point_std_px.x()).c_str(),
                 Std(c.principal_point_std_px.y()).c_str());
    } else {
      LabelValue("Principal pt", "%.1f, %.1f px", pp.x(), pp.y());
    }
    // The joint solve may refine unlocked intrinsics after the calibration.
    if (std::abs(cam.focal_px - c.focal_px) > 1e-6 * c.focal_px) LabelValue("Joint focal", "%.1f px", cam.focal_px);
    if (cam.k1 != 0.0 || cam.k2 != 0.0) LabelValue("k1, k2", "%.4g, %.4g", cam.k1, cam.k2);
    LabelValue("Sigma", "%s px (%d dof)", Std(c.residual_sigma_px, "%.3f").c_str(), c.degrees_of_freedom);
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip("Noise level the segments show: RMS residual over the degrees of freedom");
    const int n = static_cast<int>(c.segment_is_outlier.size());
    LabelValue("Outliers", "%d of %d%s", static_cast<int>(c.outlier_segments.size()), n,
               c.outlier_segments.empty() ? "" : " (marked)");
    if (ImGui::IsItemHovered()) {
      ImGui::SetTooltip("Segments above %.2f px (crossed out in red in the image), fitted without",
                        c.outlier_threshold_px);
    }
    if (image.use_horizon) LabelValue("Horizon", "%.2f px off", c.horizon_residual_px);
  }
  if (!c.message.empty()) {
    WrappedColored(c.IsUsable() || c.incomplete ? kDimText : kErrorText, c.message);
    RecordItem(state, "calibration.message");
  }
  for (const std::string& w : c.warnings) WrappedColored(kWarningText, w);

  if (!c.IsUsable()) return;
  const bool details = ImGui::TreeNodeEx("Details##calibration", ImGuiTreeNodeFlags_SpanAvailWidth);
  RecordItem(state, "calibration.details");
  if (details) {
    for (int a = 0; a < 3; ++a) {
      if (c.segments_per_axis[a] == 0) continue;
      const Axis axis = static_cast<Axis>(a);
      ImGui::TextColored(AxisColor(axis), "VP %s", AxisName(axis));
      ImGui::SameLine(ImGui::GetFontSize() * 7.5f);
      ImGui::Text("rms %.2f px%s", c.vanishing_point_rms_px[a], c.vanishing_point_at_infinity[a] ? ", at inf." : "");
      if (ImGui::IsItemHovered()) {
        ImGui::SetTooltip(
            "RMS residual of the family's segments; %s\nDirection +- %.2f deg; segments spread over %.1f deg",
            c.vanishing_point_at_infinity[a]
                ? "vanishing point at infinity (parallel in the image)"
                : (std::to_string(static_cast<long>(std::lround(c.vanishing_point_to_principal_point_px[a]))) +
                   " px from the principal point")
                      .c_str(),
            c.vanishing_direction_std_deg[a], c.family_angle_spread_deg[a]);
      }
    }
    LabelValue("Min spread", "%.1f deg", c.min_family_angle_spread_deg);
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Smallest angle over which a family's segments spread in the image");
    if (std::isinf(c.min_vanishing_point_to_principal_point_px)) {
      LabelValue("VP to pp", "infinite");
    } else {
      LabelValue("VP to pp", "%.0f px min", c.min_vanishing_point_to_principal_point_px);
    }
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Near 0, a vanishing point says nothing about the focal length");
    if (c.vanishing_point_triangle_max_angle_deg > 0.0) {
      LabelValue("VP triangle", "%.1f deg", c.vanishing_point_triangle_max_angle_deg);
      if (ImGui::IsItemHovered())
        ImGui::SetTooltip("Largest angle of the vanishing-point triangle (near 90: poorly fixed)");
    }
    if (c.closed_form_focal_px > 0.0) LabelValue("Closed form", "f %.1f px", c.closed_form_focal_px);
    if (c.max_orthogonality_error_deg > 0.0) LabelValue("Orth. error", "%.2f deg", c.max_orthogonality_error_deg);
    LabelValue("Residual", "%.3f px", c.rms_residual_px);
    LabelValue("Fit", "%d it, %.1f ms%s", c.iterations, c.time_ms, c.refitted_without_outliers ? ", refit" : "");
    ImGui::TreePop();
  }
}

std::string ImageLabel(const Project& project, Id image_id) {
  const Image* image = project.FindImage(image_id);
  if (image == nullptr) return "image " + std::to_string(image_id);
  const std::string name = std::filesystem::path(image->path).filename().string();
  return name.size() > 14 ? name.substr(0, 13) + "~" : name;
}

void DrawGeometrySolveFigures(const SceneSolveSummary& s, const char* title) {
  const bool usable = s.IsUsable();
  // Nothing to solve yet, or no solve ran (a new project: kInvalidInput without a message).
  const bool nothing = s.termination == SolverTermination::kNothingToSolve ||
                       (s.termination == SolverTermination::kInvalidInput && s.message.empty());
  ImGui::TextColored(usable ? kGoodText : (nothing ? kDimText : kErrorText), "%s%s", title,
                     nothing && s.message.empty() ? "nothing to solve yet" : SolverTerminationName(s.termination));
  if (usable) {
    LabelValue("Iterations", "%d", s.iterations);
    LabelValue("RMS", "%.3f px", s.reprojection_rms_px);
    LabelValue("Max", "%.3f px", s.reprojection_max_px);
    LabelValue("Residuals", "%d (%d parameters)", s.num_residuals, s.num_parameters);
  }
  LabelValue("Time", "%.2f ms", s.time_ms);
  if (!s.message.empty()) WrappedColored(usable ? ImGui::GetStyleColorVec4(ImGuiCol_Text) : kDimText, s.message);
  for (const std::string& w : s.warnings) WrappedColored(kWarningText, w);
}

}  // namespace

void DrawImageSection(AppState* state, ExifFeedback* exif_feedback) {
  if (!state->ActiveImage()) {
    ImGui::TextColored(kDimText, "No image in the project.");
    return;
  }
  // A copy: the edits below replace the project that a pointer would point into.
  const Image image = *state->ActiveImage();
  if (!ImGui::CollapsingHeader("Image", ImGuiTreeNodeFlags_DefaultOpen)) return;
  LabelValue("Path", "%s", image.path.c_str());
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", image.path.c_str());
  LabelValue("Size", "%d x %d px", image.width_px, image.height_px);
  DrawPhotoTextureOption(state, image);
  if (auto err = state->photo_errors.find(image.id); err != state->photo_errors.end()) {
    WrappedColored(kErrorText, err->second);
  }
  if (image.camera_calibrated) {
    const Eigen::Vector3d c = image.camera.CenterInWorld();
    LabelValue("Centre", "%.3f, %.3f, %.3f", c.x(), c.y(), c.z());
  } else {
    LabelValue("Camera", "not calibrated");
  }

  ImGui::Spacing();
  ImGui::TextColored(kDimText, "Calibration");
  ImGui::Separator();
  DrawCalibrationControls(state, image, exif_feedback);

  // The controls above may have committed an edit: show the figures of the current camera.
  if (const Image* now = state->document.project().FindImage(image.id)) {
    if (state->last_update.calibration.count(image.id)) {
      ImGui::Spacing();
      ImGui::TextColored(kDimText, "Vanishing-point result");
      ImGui::Separator();
    }
    DrawCalibrationResult(state, *now);
  }
}

void DrawSolveSection(AppState* state) {
  if (!ImGui::CollapsingHeader("Solve", ImGuiTreeNodeFlags_DefaultOpen)) return;
  const ModelUpdateSummary& update = state->last_update;
  const JointSolveSummary& j = update.joint;
  if (j.IsUsable()) {
    // The geometry solve is the joint solve's start; with free vertices its RMS is not the
    // model's (tens of px where the joint solve reaches half a pixel), so it stays folded.
    ImGui::TextColored(kGoodText, "Joint solve: %s", SolverTerminationName(j.termination));
    LabelValue("RMS", "%.3f px", j.reprojection_rms_px);
    RecordItem(state, "solve.joint_rms");
    LabelValue("Max", "%.3f px", j.reprojection_max_px);
    LabelValue("Iterations", "%d", j.iterations);
    LabelValue("Residuals", "%d (%d parameters)", j.num_residuals, j.num_parameters);
    for (const ImageDiagnostic& d : j.images) {
      LabelValue(ImageLabel(state->document.project(), d.image_id).c_str(), "%.2f / %.2f px, %d pins", d.rms_px,
                 d.max_px, d.num_pins);
      if (ImGui::IsItemHovered()) ImGui::SetTooltip("Pin reprojection RMS / max in this image");
    }
    LabelValue("Time", "%.2f ms", j.time_ms);
  } else {
    // Only the geometry solve's result stands: its figures are the model's.
    DrawGeometrySolveFigures(update.solve, "Geometry solve: ");
    if (j.termination != SolverTermination::kInvalidInput || !j.message.empty()) {
      ImGui::TextColored(kDimText, "Joint solve: %s", SolverTerminationName(j.termination));
    }
  }
  if (!j.message.empty()) WrappedColored(kDimText, j.message);
  for (const std::string& w : j.undetermined) WrappedColored(kWarningText, w);
  for (const std::string& w : j.conflicts) WrappedColored(kErrorText, w);
  for (const std::string& w : j.warnings) WrappedColored(kWarningText, w);
  if (j.IsUsable() && j.num_downweighted_pins > 0) {
    LabelValue("Down-weighted", "%d pins (noise scale %.2f px)", j.num_downweighted_pins, j.pin_scale_px);
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip("Pins far from where the model puts them count less in the solve (robust loss)");
  }
  if (j.IsUsable() && !j.flagged_pins.empty()) {
    // The offer to drop the likely wrong clicks: one undoable edit (Edit > Undo brings them back).
    const std::string label =
        "Drop " + std::to_string(j.flagged_pins.size()) + " flagged pin" + (j.flagged_pins.size() == 1 ? "" : "s");
    if (ImGui::Button(label.c_str())) DropFlaggedPinsEdit(state);
    RecordItem(state, "solve.drop_flagged_pins");
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Remove the pins marked in red (likely wrong clicks); undoable");
  }
  if (j.IsUsable()) {
    const bool open = ImGui::TreeNodeEx("Geometry solve (start)", ImGuiTreeNodeFlags_SpanAvailWidth);
    RecordItem(state, "solve.geometry_node");
    if (open) {
      DrawGeometrySolveFigures(update.solve, "");
      ImGui::TreePop();
    }
  }
  LabelValue("Update", "%.2f ms", update.time_ms);
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Calibration and solves after the last change");
  for (const std::string& m : update.messages) WrappedColored(kWarningText, m);
  for (const std::string& m : update.progress) WrappedColored(kDimText, m);
}

namespace {

bool ParseNumbers(const std::vector<std::string>& words, size_t first, size_t count, double* out) {
  if (words.size() != first + count) return false;
  for (size_t i = 0; i < count; ++i) {
    char* end = nullptr;
    out[i] = std::strtod(words[first + i].c_str(), &end);
    if (end == words[first + i].c_str() || *end != '\0' || !std::isfinite(out[i])) return false;
  }
  return true;
}

bool ParseOnOff(const std::vector<std::string>& words, bool* on) {
  if (words.size() != 2 || (words[1] != "on" && words[1] != "off")) return false;
  *on = words[1] == "on";
  return true;
}

}  // namespace

bool RunCalibrationCommand(AppState* state, ExifFeedback* exif_feedback, const std::string& arg, std::string* error) {
  std::vector<std::string> w;
  std::istringstream in(arg);
  for (std::string word; in >> word;) w.push_back(word);
  const Image* active = state->ActiveImage();
  if (active == nullptr) {
    *error = "calibration: the project has no image";
    return false;
  }
  const Image image = *active;
  const std::string key = w.empty() ? "" : w[0];
  const std::string sub = w.size() > 1 ? w[1] : "";
  auto fail = [&](const std::string& usage) {
    *error = "calibration " + key + ": expected " + usage + " (got '" + arg + "')";
    return false;
  };
  double v[4] = {0, 0, 0, 0};
  bool on = false;
  if (key == "principal-point") {
    const char* usage = "solve, center or fixed X Y";
    if (sub == "solve" && w.size() == 2) {
      CommitImageEdit(state, image.id, "Principal point: solve",
                      [](Image* im) { im->principal_point_mode = PrincipalPointMode::kSolve; });
    } else if ((sub == "center" || sub == "centre") && w.size() == 2) {
      CommitImageEdit(state, image.id, "Principal point: image centre",
                      [](Image* im) { im->principal_point_mode = PrincipalPointMode::kImageCenter; });
    } else if (sub == "fixed" && ParseNumbers(w, 2, 2, v)) {
      CommitImageEdit(state, image.id, "Principal point: fixed", [&](Image* im) {
        im->principal_point_mode = PrincipalPointMode::kFixed;
        im->fixed_principal_point_px = Eigen::Vector2d(v[0], v[1]);
      });
    } else {
      return fail(usage);
    }
    return true;
  }
  if (key == "focal") {
    const char* usage = "solve, fixed F, prior F STD or exif (F, STD > 0 px)";
    if (sub == "solve" && w.size() == 2) {
      CommitImageEdit(state, image.id, "Focal: solve", [](Image* im) { im->focal_mode = FocalMode::kSolve; });
    } else if (sub == "fixed" && ParseNumbers(w, 2, 1, v) && v[0] > 0.0) {
      CommitImageEdit(state, image.id, "Focal: known", [&](Image* im) {
        im->focal_mode = FocalMode::kFixed;
        im->fixed_focal_px = v[0];
      });
    } else if (sub == "prior" && ParseNumbers(w, 2, 2, v) && v[0] > 0.0 && v[1] > 0.0) {
      CommitImageEdit(state, image.id, "Focal: prior", [&](Image* im) {
        im->focal_mode = FocalMode::kPrior;
        im->focal_prior_px = v[0];
        im->focal_prior_std_px = v[1];
      });
    } else if (sub == "exif" && w.size() == 2) {
      const ExifFocalPrior prior = ReadExifFocalPrior(PhotoPath(*state, image), image);
      *exif_feedback = {image.id, prior.found, prior.message};
      if (!prior.found) {
        *error = "calibration focal exif: " + prior.message;
        return false;
      }
      state->Log(LogLevel::kInfo, prior.message);
      CommitImageEdit(state, image.id, "Focal prior from EXIF", [&](Image* im) { ApplyExifFocalPrior(prior, im); });
    } else {
      return fail(usage);
    }
    return true;
  }
  if (key == "horizon") {
    if (sub == "off" && w.size() == 2) {
      CommitImageEdit(state, image.id, "No horizon", [](Image* im) { im->use_horizon = false; });
    } else if (sub == "level" && ParseNumbers(w, 2, 1, v)) {
      CommitImageEdit(state, image.id, "Level horizon", [&](Image* im) {
        im->use_horizon = true;
        im->horizon_px = LevelHorizon(*im, v[0]);
      });
    } else if (ParseNumbers(w, 1, 4, v)) {
      if (v[0] == v[2] && v[1] == v[3]) {
        *error = "calibration horizon: the two points must differ";
        return false;
      }
      CommitImageEdit(state, image.id, "Horizon", [&](Image* im) {
        im->use_horizon = true;
        im->horizon_px = Eigen::Vector4d(v[0], v[1], v[2], v[3]);
      });
    } else {
      return fail("off, level V or X1 Y1 X2 Y2 (px)");
    }
    return true;
  }
  if (key == "distortion") {
    if (!ParseOnOff(w, &on)) return fail("on or off");
    CommitImageEdit(state, image.id, on ? "Estimate distortion" : "No distortion estimate",
                    [&](Image* im) { im->estimate_distortion = on; });
    return true;
  }
  if (key == "distortion-lock") {
    if (!ParseOnOff(w, &on)) return fail("on or off");
    CommitImageEdit(state, image.id, on ? "Lock distortion" : "Unlock distortion",
                    [&](Image* im) { im->distortion_locked = on; });
    return true;
  }
  if (key == "focal-lock" || key == "principal-point-lock") {
    if (!ParseOnOff(w, &on)) return fail("on or off");
    const bool focal = key == "focal-lock";
    const std::string what = focal ? "focal" : "principal point";
    CommitImageEdit(state, image.id, (on ? "Lock " : "Unlock ") + what,
                    [&](Image* im) { (focal ? im->focal_locked : im->principal_point_locked) = on; });
    return true;
  }
  if (key == "lens-group") {
    if (!ParseNumbers(w, 1, 1, v) || v[0] < 0.0 || v[0] != std::floor(v[0]) || v[0] > 1e6) {
      return fail("N: 0 (the photo's own lens) or a group number shared with other photos");
    }
    const int group = static_cast<int>(v[0]);
    CommitImageEdit(state, image.id, group > 0 ? "Share the lens" : "Own lens",
                    [&](Image* im) { im->lens_group = group; });
    return true;
  }
  *error = "calibration: unknown key '" + key +
           "' (principal-point, focal, horizon, distortion, distortion-lock, focal-lock, principal-point-lock, "
           "lens-group)";
  return false;
}

}  // namespace facet::app
