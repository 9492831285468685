#include "app/panels/colmap_window.h"

#include <cstdio>
#include <string>

#include <imgui.h>

#include "app/panels/widgets.h"
#include "app/state/colmap_cameras.h"
#include "core/io/colmap_run.h"

namespace facet::app {
namespace {

constexpr float kWindowWidth = 560.0f;

// How far the bar is: COLMAP's three stages a third each (they report no finer progress);
// reading the model fills it.
float StageFraction(ColmapStage stage, int step) {
  if (stage == ColmapStage::kReadingModel || stage == ColmapStage::kDone) return 1.0f;
  return step > 0 ? (step - 1) / 3.0f : 0.0f;
}

void DrawRunning(AppState* state, const ColmapJob& job) {
  const ColmapStage stage = static_cast<ColmapStage>(job.stage.load());
  const int step = job.step.load();
  ImGui::Text("COLMAP on %d photos", job.num_photos);
  char overlay[96];
  if (step > 0) {
    std::snprintf(overlay, sizeof(overlay), "%s (%d of 3)", ColmapStageName(stage), step);
  } else {
    std::snprintf(overlay, sizeof(overlay), "%s", ColmapStageName(stage));
  }
  ImGui::ProgressBar(StageFraction(stage, step), ImVec2(-1.0f, 0.0f), overlay);
  RecordItem(state, "colmap.progress");
  ImGui::TextColored(kDimText, "%.0f s; working folder %s", state->time_s - job.started_s, job.working_dir.c_str());
  ImGui::Spacing();
  if (job.cancel) {
    ImGui::TextColored(kDimText, "Cancelling: ending COLMAP's processes...");
  } else {
    if (ImGui::Button("Cancel", ImVec2(110, 0))) CancelColmapCameras(state);
    RecordItem(state, "colmap.cancel");
    ImGui::SameLine();
    ImGui::TextColored(kDimText, "the project stays as it was");
  }
}

void DrawIdle(AppState* state) {
  ColmapWork& work = state->colmap;
  const size_t photos = state->document.project().images.size();
  ImGui::PushTextWrapPos(kWindowWidth - 16.0f);
  ImGui::TextUnformatted(
      "A camera for every photo from COLMAP (structure from motion on the CPU: minutes for a few dozen "
      "photos), brought into the project's frame and applied as one undoable edit.");
  ImGui::TextColored(kDimText, "%zu photos; working folder %s", photos, ColmapWorkingDir(*state).c_str());
  ImGui::Checkbox("One camera and lens for all photos", &work.single_camera);
  RecordItem(state, "colmap.single_camera");
  const bool available = ColmapAvailable(state);
  if (!available) ImGui::TextColored(kErrorText, "%s (FACET_COLMAP)", ColmapInstallHint().c_str());
  if (!work.last_message.empty()) {
    ImGui::Separator();
    ImGui::TextColored(work.last_applied ? ImVec4(0.55f, 0.85f, 0.55f, 1.0f) : kDimText, "Last run: %s",
                       work.last_message.c_str());
    if (work.last_alignment)
      for (const std::string& w : work.last_alignment->warnings) ImGui::TextColored(kErrorText, "%s", w.c_str());
    if (!work.last_log_path.empty()) ImGui::TextColored(kDimText, "COLMAP's log: %s", work.last_log_path.c_str());
  }
  ImGui::PopTextWrapPos();
  ImGui::Spacing();
  ImGui::BeginDisabled(!available || photos < 2);
  if (ImGui::Button("Start", ImVec2(110, 0))) StartColmapCameras(state);
  ImGui::EndDisabled();
  RecordItem(state, "colmap.start");
  ImGui::SameLine();
  if (ImGui::Button("Close", ImVec2(110, 0))) work.window_open = false;
  RecordItem(state, "colmap.close");
}

}  // namespace

void DrawColmapWindow(AppState* state) {
  ColmapWork& work = state->colmap;
  if (!work.window_open && !work.job) return;
  const ImGuiViewport* viewport = ImGui::GetMainViewport();
  ImGui::SetNextWindowPos(ImVec2(viewport->Pos.x + viewport->Size.x * 0.5f, viewport->Pos.y + viewport->Size.y * 0.35f),
                          ImGuiCond_Appearing, ImVec2(0.5f, 0.5f));
  ImGui::SetNextWindowSize(ImVec2(kWindowWidth, 0.0f), ImGuiCond_Always);
  bool open = true;
  // No close box while COLMAP runs: Cancel is the way out.
  const bool shown = ImGui::Begin("Cameras from all photos", work.job ? nullptr : &open,
                                  ImGuiWindowFlags_NoSavedSettings | ImGuiWindowFlags_NoCollapse);
  if (shown) {
    if (work.job) {
      DrawRunning(state, *work.job);
    } else {
      DrawIdle(state);
    }
  }
  ImGui::End();
  if (!open) work.window_open = false;
}

}  // namespace facet::app
