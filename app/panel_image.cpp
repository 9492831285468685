#include "app/panel_image.h"

#include <imgui.h>

#include "app/panel_util.h"
#include "core/scene_solve.h"

namespace facet::app {

void DrawImageSection(AppState* state) {
  if (!state->ActiveImage()) {
    ImGui::TextColored(kDimText, "No image in the project.");
    return;
  }
  // A copy: the edits below replace the project that a pointer would point into.
  const Image active_image = *state->ActiveImage();
  const Image* image = &active_image;
  const Id image_id = image->id;
  if (!ImGui::CollapsingHeader("Image", ImGuiTreeNodeFlags_DefaultOpen)) return;
  LabelValue("Path", "%s", image->path.c_str());
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", image->path.c_str());
  LabelValue("Size", "%d x %d px", image->width_px, image->height_px);
  if (auto err = state->photo_errors.find(image_id); err != state->photo_errors.end()) {
    WrappedColored(kErrorText, err->second);
  }
  const Camera& cam = image->camera;
  LabelValue("Calibrated", "%s", image->camera_calibrated ? "yes" : "no");
  LabelValue("Focal", "%.1f px", cam.focal_px);
  LabelValue("Principal pt", "%.1f, %.1f px", cam.principal_point_px.x(), cam.principal_point_px.y());
  if (image->camera_calibrated) {
    const Eigen::Vector3d c = cam.CenterInWorld();
    LabelValue("Centre", "%.3f, %.3f, %.3f", c.x(), c.y(), c.z());
  }

  int mode = static_cast<int>(image->principal_point_mode);
  const char* modes[] = {"Solve (3 VPs)", "Image centre", "Fixed"};
  ImGui::SetNextItemWidth(-FLT_MIN);
  if (ImGui::Combo("##pp_mode", &mode, modes, 3)) {
    Project edited = state->document.project();
    edited.FindImage(image_id)->principal_point_mode = static_cast<PrincipalPointMode>(mode);
    CommitEdit(state, "Principal point mode", std::move(edited));
  }
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("How calibration treats the principal point");
  bool pose_locked = image->pose_locked;
  if (ImGui::Checkbox("Lock camera position", &pose_locked)) {
    Project edited = state->document.project();
    edited.FindImage(image_id)->pose_locked = pose_locked;
    CommitEdit(state, pose_locked ? "Lock camera" : "Unlock camera", std::move(edited));
  }

  ImGui::Spacing();
  ImGui::TextColored(kDimText, "Vanishing-point calibration");
  ImGui::Separator();
  const auto cal = state->last_update.calibration.find(image_id);
  if (cal == state->last_update.calibration.end()) {
    ImGui::TextColored(kDimText, "No line families drawn in this image.");
  } else {
    const VpCalibrationSummary& c = cal->second;
    ImGui::TextColored(c.success ? kGoodText : kErrorText, "%s", c.success ? "Calibrated" : "Failed");
    LabelValue("Segments", " ");
    for (int a = 0; a < 3; ++a) {
      ImGui::SameLine();
      ImGui::TextColored(AxisColor(static_cast<Axis>(a)), "%s %d", AxisName(static_cast<Axis>(a)), c.segments_per_axis[a]);
    }
    if (c.success) {
      LabelValue("Focal", "%.1f px", c.focal_px);
      LabelValue("Principal pt", "%.1f, %.1f px", c.principal_point_px.x(), c.principal_point_px.y());
    }
    if (!c.message.empty()) WrappedColored(c.success ? ImGui::GetStyleColorVec4(ImGuiCol_Text) : kErrorText, c.message);
    for (const std::string& w : c.warnings) WrappedColored(kWarningText, w);
  }
}

void DrawSolveSection(AppState* state) {
  if (!ImGui::CollapsingHeader("Geometry solve", ImGuiTreeNodeFlags_DefaultOpen)) return;
  const SceneSolveSummary& s = state->last_update.solve;
  const bool usable = s.IsUsable();
  const bool nothing = s.termination == SolveTermination::kNothingToSolve;
  ImGui::TextColored(usable ? kGoodText : (nothing ? kDimText : kErrorText), "%s",
                     SolveTerminationName(s.termination));
  if (usable) {
    LabelValue("Iterations", "%d", s.iterations);
    LabelValue("RMS", "%.3f px", s.reprojection_rms_px);
    LabelValue("Max", "%.3f px", s.reprojection_max_px);
    LabelValue("Residuals", "%d (%d parameters)", s.num_residuals, s.num_parameters);
  }
  LabelValue("Time", "%.2f ms", s.time_ms);
  LabelValue("Update", "%.2f ms", state->last_update.time_ms);
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Calibration and solve after the last change");
  if (!s.message.empty()) WrappedColored(usable ? ImGui::GetStyleColorVec4(ImGuiCol_Text) : kDimText, s.message);
  for (const std::string& w : s.warnings) WrappedColored(kWarningText, w);
  for (const std::string& m : state->last_update.messages) WrappedColored(kWarningText, m);

  // The joint solve refines everything at once (free vertices, constraints, intrinsics).
  const JointSolveSummary& j = state->last_update.joint;
  if (j.termination == JointSolveSummary::Termination::kInvalidInput && j.message.empty()) return;
  ImGui::Spacing();
  ImGui::TextColored(kDimText, "Joint solve");
  ImGui::Separator();
  ImGui::TextColored(j.IsUsable() ? kGoodText : kDimText, "%s", JointSolveTerminationName(j.termination));
  if (j.IsUsable()) {
    LabelValue("Iterations", "%d", j.iterations);
    LabelValue("RMS", "%.3f px", j.reprojection_rms_px);
    LabelValue("Max", "%.3f px", j.reprojection_max_px);
    LabelValue("Residuals", "%d (%d parameters)", j.num_residuals, j.num_parameters);
  }
  if (!j.message.empty()) WrappedColored(kDimText, j.message);
  for (const std::string& w : j.undetermined) WrappedColored(kWarningText, w);
  for (const std::string& w : j.conflicts) WrappedColored(kErrorText, w);
  for (const std::string& w : j.warnings) WrappedColored(kWarningText, w);
}

bool RunCalibrationCommand(AppState* /*state*/, const std::string& arg, std::string* error) {
  *error = "calibration: not available yet ('" + arg + "')";
  return false;
}

}  // namespace facet::app
