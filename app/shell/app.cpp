#include "app/shell/app.h"

#include <epoxy/gl.h>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>  // key codes only: the offscreen key map matches the GLFW backend's

#include <algorithm>
#include <cfloat>
#include <cstdio>
#include <filesystem>

#include <imgui.h>
#include <imgui_impl_opengl3.h>
#include <imgui_internal.h>  // ImTextCharFromUtf8: a script's typed text, one character at a time
#include <nlohmann/json.hpp>

#include "app/panels/image_panel.h"
#include "app/panels/side_panels.h"
#include "app/panels/viewport_panel.h"
#include "app/platform/egl_context.h"
#include "app/shell/cameras_command.h"
#include "app/shell/export_view.h"
#include "app/shell/file_actions.h"
#include "app/shell/frame.h"
#include "app/shell/glfw_window.h"
#include "app/shell/input_feed.h"
#include "app/shell/layout.h"
#include "app/shell/teach_report.h"
#include "app/state/app_state.h"
#include "app/state/colmap_cameras.h"
#include "app/state/input_script.h"
#include "app/state/line_proposals.h"
#include "core/io/project_io.h"

namespace facet::app {
namespace {

constexpr int kWarmUpFrames = 4;  // layout, fonts and panel textures settle before any input
constexpr int kSettleFrames = 3;  // after the script, before the final read-back
constexpr double kFrameTimeS = 1.0 / 60.0;

// The same mapping as ImGui's GLFW backend, so panels test keys identically in both modes.
void SetGlfwKeyMap(ImGuiIO& io) {
  io.KeyMap[ImGuiKey_Tab] = GLFW_KEY_TAB;
  io.KeyMap[ImGuiKey_LeftArrow] = GLFW_KEY_LEFT;
  io.KeyMap[ImGuiKey_RightArrow] = GLFW_KEY_RIGHT;
  io.KeyMap[ImGuiKey_UpArrow] = GLFW_KEY_UP;
  io.KeyMap[ImGuiKey_DownArrow] = GLFW_KEY_DOWN;
  io.KeyMap[ImGuiKey_PageUp] = GLFW_KEY_PAGE_UP;
  io.KeyMap[ImGuiKey_PageDown] = GLFW_KEY_PAGE_DOWN;
  io.KeyMap[ImGuiKey_Home] = GLFW_KEY_HOME;
  io.KeyMap[ImGuiKey_End] = GLFW_KEY_END;
  io.KeyMap[ImGuiKey_Insert] = GLFW_KEY_INSERT;
  io.KeyMap[ImGuiKey_Delete] = GLFW_KEY_DELETE;
  io.KeyMap[ImGuiKey_Backspace] = GLFW_KEY_BACKSPACE;
  io.KeyMap[ImGuiKey_Space] = GLFW_KEY_SPACE;
  io.KeyMap[ImGuiKey_Enter] = GLFW_KEY_ENTER;
  io.KeyMap[ImGuiKey_Escape] = GLFW_KEY_ESCAPE;
  io.KeyMap[ImGuiKey_KeyPadEnter] = GLFW_KEY_KP_ENTER;
  io.KeyMap[ImGuiKey_A] = GLFW_KEY_A;
  io.KeyMap[ImGuiKey_C] = GLFW_KEY_C;
  io.KeyMap[ImGuiKey_V] = GLFW_KEY_V;
  io.KeyMap[ImGuiKey_X] = GLFW_KEY_X;
  io.KeyMap[ImGuiKey_Y] = GLFW_KEY_Y;
  io.KeyMap[ImGuiKey_Z] = GLFW_KEY_Z;
}

// The synthetic input device of the offscreen mode: each step's events go through the same
// queue as the window's (app/state/input_queue.h), stamped with the step's frame time.
struct ScriptedInput {
  InputQueue* queue = nullptr;
  bool hold_shift = false, hold_ctrl = false, hold_alt = false;
  bool shift_down = false, ctrl_down = false, alt_down = false;  // as queued
  int key_down = -1;  // the previous step's key, released at the start of the next step

  void SetModifier(double t, int key, bool want, bool* down) {
    if (want != *down) queue->Key(t, key, want);
    *down = want;
  }
  void SetModifiers(double t, bool shift, bool ctrl, bool alt) {
    SetModifier(t, GLFW_KEY_LEFT_SHIFT, shift, &shift_down);
    SetModifier(t, GLFW_KEY_LEFT_CONTROL, ctrl, &ctrl_down);
    SetModifier(t, GLFW_KEY_LEFT_ALT, alt, &alt_down);
  }

  // Queues what the platform would deliver during the step's frame at time `t`.
  void Push(const ScriptStep* step, double t) {
    if (key_down >= 0) queue->Key(t, key_down, false);
    key_down = -1;
    ScriptKey key;
    if (step) {
      const bool release_first = step->burst == Burst::kReleaseThenMove;
      if (release_first) queue->MouseButton(t, step->burst_button, false);
      if (step->mouse_pos) queue->MouseMove(t, (*step->mouse_pos)[0], (*step->mouse_pos)[1]);
      for (int b = 0; b < 3; ++b) {
        if (step->mouse_down[b]) queue->MouseButton(t, b, *step->mouse_down[b]);
      }
      if (step->burst == Burst::kDoubleClick) {
        for (bool down : {true, false, true, false}) queue->MouseButton(t, step->burst_button, down);
      }
      if (step->hold_shift) hold_shift = *step->hold_shift;
      if (step->hold_ctrl) hold_ctrl = *step->hold_ctrl;
      if (step->hold_alt) hold_alt = *step->hold_alt;
      if (step->wheel != 0.0f) queue->Wheel(t, 0.0f, step->wheel);
      if (step->key_press) key = *step->key_press;
    }
    SetModifiers(t, hold_shift || key.shift, hold_ctrl || key.ctrl, hold_alt || key.alt);
    if (step && step->key_press) {
      queue->Key(t, key.key_code, true);
      if (key.character) queue->Char(t, key.character);
      if (step->burst == Burst::kTap) {
        queue->Key(t, key.key_code, false);
        SetModifiers(t, hold_shift, hold_ctrl, hold_alt);
      } else {
        key_down = key.key_code;
      }
    }
    if (step) {
      const char* text = step->text.c_str();
      const char* end = text + step->text.size();
      while (text < end) {
        unsigned c = 0;
        const int length = ImTextCharFromUtf8(&c, text, end);
        if (length <= 0) break;
        text += length;
        if (c) queue->Char(t, c);
      }
    }
  }
};

// Where a script point is on the screen: image and vertex points through the image panel's
// view of the frame before, item points at the centre of the widget drawn then (what the user
// saw when they moved there).
bool ResolveScriptPoint(const AppState& state, const ShellState& shell, const ScriptStep& step,
                        std::array<float, 2>* screen, std::string* error) {
  const std::array<float, 2> xy = *step.mouse_pos;
  if (step.mouse_space == PointSpace::kScreen) {
    *screen = xy;
    return true;
  }
  if (step.mouse_space == PointSpace::kItem) {
    const auto it = state.item_rects.find(step.mouse_item);
    if (it == state.item_rects.end()) {
      *error = "no widget named '" + step.mouse_item + "' was drawn in the frame before";
      return false;
    }
    if (state.clipped_items.count(step.mouse_item) > 0) {
      *error = "widget '" + step.mouse_item + "' was drawn out of view (its panel is scrolled or too small)";
      return false;
    }
    *screen = {it->second.x + 0.5f * it->second.w, it->second.y + 0.5f * it->second.h};
    return true;
  }
  const ImageViewReport view = LastImageViewReport(shell.image_panel);
  const Image* image = state.document.project().FindImage(view.image_id);
  if (image == nullptr || view.zoom <= 0.0f) {
    *error = "an image or vertex point, but the image panel shows no photo";
    return false;
  }
  Eigen::Vector2d uv(xy[0], xy[1]);
  if (step.mouse_space == PointSpace::kVertex) {
    const Project& project = state.document.project();
    const auto [index, vertex] = step.mouse_vertex;
    if (index >= static_cast<int>(project.primitives.size()) ||
        !project.primitives[index].mesh.IsVertex(static_cast<VertexId>(vertex))) {
      *error = "no vertex " + std::to_string(vertex) + " on primitive " + std::to_string(index) + " (of " +
               std::to_string(project.primitives.size()) + ")";
      return false;
    }
    if (!image->camera_calibrated) {
      *error = "a vertex point, but the photo shown has no camera yet";
      return false;
    }
    uv = image->camera.Project(VertexInWorld(project, {project.primitives[index].id, static_cast<VertexId>(vertex)}));
  }
  *screen = {view.origin_x + view.zoom * static_cast<float>(uv.x()), view.origin_y + view.zoom * static_cast<float>(uv.y())};
  return true;
}

// The report's name of the open modal dialog.
const char* DialogName(Dialog dialog) {
  switch (dialog) {
    case Dialog::kNone: return "";
    case Dialog::kOpen: return "open";
    case Dialog::kSaveAs: return "save-as";
    case Dialog::kExport: return "export";
    case Dialog::kExportView: return "export-view";
    case Dialog::kExportColmap: return "export-colmap";
    case Dialog::kExportTransforms: return "export-transforms";
    case Dialog::kAddPhoto: return "add-photo";
    case Dialog::kRelinkPhoto: return "relink-photo";
    case Dialog::kAddReference: return "add-reference";
    case Dialog::kAbout: return "about";
    case Dialog::kConfirmQuit: return "confirm-quit";
    case Dialog::kConfirmNew: return "confirm-new";
    case Dialog::kConfirmOpen: return "confirm-open";
    case Dialog::kRecover: return "recover";
    case Dialog::kProjectLocked: return "project-locked";
    case Dialog::kSaveChanged: return "save-changed";
  }
  return "";
}

// The report's `texture` section: the view settings, the last bake's per-face sources (what
// View > Texture sources tints) and the legend it draws.
nlohmann::json TextureReportJson(const AppState& state) {
  const Project& project = state.document.project();
  nlohmann::json faces = nlohmann::json::array();
  for (const FaceTextureReport& r : state.last_bake.faces) {
    nlohmann::json sources = nlohmann::json::array();
    for (const TextureSourceShare& s : r.sources) sources.push_back({{"image_id", s.image_id}, {"share", s.share}});
    faces.push_back({{"primitive_id", r.primitive_id},
                     {"face", r.face},
                     {"sources", std::move(sources)},
                     {"width_texels", r.width_texels},
                     {"height_texels", r.height_texels},
                     {"forced_image", r.forced_image},
                     {"forced_fallback_texels", r.forced_fallback_texels},
                     {"forced_unavailable", r.forced_unavailable}});
  }
  nlohmann::json legend = nlohmann::json::array();
  for (const TextureLegendRow& row : TextureLegend(state)) {
    legend.push_back({{"image_index", row.image_index},
                      {"image_id", project.images[row.image_index].id},
                      {"label", row.label},
                      {"colour", {row.colour[0], row.colour[1], row.colour[2]}},
                      {"faces", row.faces},
                      {"used", row.used}});
  }
  return {{"show_sources", state.texture.show_sources},
          {"export_texels_per_unit", state.texture.export_texels_per_unit},
          {"bake_message", state.last_bake.message},
          {"faces", std::move(faces)},
          {"legend", std::move(legend)}};
}

nlohmann::json RectJson(const Rect& r) { return {{"x", r.x}, {"y", r.y}, {"w", r.w}, {"h", r.h}}; }

std::string BuildReport(const AppState& state, const ShellState& shell, const RenderOptions& options,
                        const std::string& renderer, int frames, const Script& script) {
  nlohmann::json report;
  report["script_ui_events"] = script.ui_events;
  report["size"] = {options.width, options.height};
  report["renderer"] = renderer;
  report["frames"] = frames;
  report["menu_bar"] = RectJson(shell.menu_bar_rect);
  nlohmann::json panels = nlohmann::json::object();
  for (int i = 0; i < kNumPanels; ++i) {
    if (!shell.panel_drawn[i]) continue;
    nlohmann::json p = RectJson(shell.panel_rects[i]);
    p["floating"] = shell.layout.panels[i].floating;
    panels[PanelTitle(static_cast<PanelId>(i))] = p;
  }
  report["panels"] = panels;
  nlohmann::json items = nlohmann::json::object();
  for (const auto& [name, rect] : state.item_rects) items[name] = RectJson(rect);
  report["items"] = items;
  const ImageViewReport view = LastImageViewReport(shell.image_panel);
  report["image_view"] = {{"image_id", view.image_id},
                          {"origin_x", view.origin_x},
                          {"origin_y", view.origin_y},
                          {"zoom", view.zoom},
                          {"rect", RectJson({view.rect_x, view.rect_y, view.rect_w, view.rect_h})}};
  const ViewportReport viewport = LastViewportReport(shell.viewport_panel);
  if (viewport.drawn) {
    report["viewport"] = {{"origin_x", viewport.origin_x},
                          {"origin_y", viewport.origin_y},
                          {"width_px", viewport.width_px},
                          {"height_px", viewport.height_px},
                          {"clip_from_world", viewport.clip_from_world}};
  }
  nlohmann::json undo = nlohmann::json::array(), redo = nlohmann::json::array();
  for (const Edit& e : state.document.undo_stack()) undo.push_back(e.label);
  for (const Edit& e : state.document.redo_stack()) redo.push_back(e.label);
  report["undo_stack"] = undo;
  report["redo_stack"] = redo;
  report["dirty"] = state.document.dirty();
  report["project_path"] = state.project_path;  // empty for an unsaved project
  // Reference meshes as the panels draw them: read (with their triangle count) or why not.
  nlohmann::json references = nlohmann::json::array();
  for (const Reference& reference : state.document.project().references) {
    const auto loaded = state.references.find(reference.id);
    const bool read = loaded != state.references.end() && loaded->second.error.empty();
    references.push_back(
        {{"id", reference.id},
         {"path", reference.path},
         {"loaded", read},
         {"triangles", read ? loaded->second.mesh.triangles.size() : 0},
         {"error", loaded != state.references.end() ? loaded->second.error : std::string("not read yet")}});
  }
  report["references"] = references;
  report["tool"] = ToolName(state.tool);
  report["active_image_id"] = state.active_image_id;
  const LineDetectionStats& lines = state.line_detection.stats;
  report["line_detection"] = {{"in_flight", LineDetectionInFlight(state)},
                              {"started", lines.started},
                              {"collected", lines.collected},
                              {"dropped", lines.dropped},
                              {"last_image_id", lines.last_image_id},
                              {"last_frames_in_flight", lines.last_frames_in_flight},
                              {"last_start_ms", lines.last_start_ms}};
  report["detect_lines_on_add"] = state.detect_lines_on_add;
  const ColmapWork& colmap = state.colmap;
  const ColmapJob* colmap_job = colmap.job.get();
  report["colmap"] = {
      {"executable", colmap.executable},
      {"available", colmap.available.value_or(false)},
      {"install_hint", ColmapInstallHint()},
      {"window_open", colmap.window_open},
      {"in_flight", colmap_job != nullptr},
      {"stage", colmap_job ? ColmapStageName(static_cast<ColmapStage>(colmap_job->stage.load())) : ""},
      {"working_dir", colmap_job ? colmap_job->working_dir : colmap.last_working_dir},
      {"started", colmap.started},
      {"applied", colmap.applied},
      {"cancelled", colmap.cancelled},
      {"failed", colmap.failed},
      {"dropped", colmap.dropped},
      {"last_message", colmap.last_message},
      {"last_log", colmap.last_log_path},
      {"alignment", colmap.last_alignment ? ColmapAlignmentJson(*colmap.last_alignment) : nlohmann::json()}};
  report["line_proposals"] = {{"image_id", state.line_proposals ? state.line_proposals->image_id : kNoId},
                              {"count", state.line_proposals ? state.line_proposals->segments.size() : 0}};
  {
    // Ghost pins as last computed (app/state/ghost_pins.h): refused ones with their reason.
    const GhostPinsState& ghosts = state.ghost_pins;
    nlohmann::json proposals = nlohmann::json::array();
    if (ghosts.computed) {
      for (const PinProposal& p : ghosts.summary.proposals) {
        proposals.push_back({{"primitive_id", p.vertex.primitive_id},
                             {"vertex", p.vertex.vertex},
                             {"source_image_id", p.source_image_id},
                             {"u", p.match.uv_px.x()},
                             {"v", p.match.uv_px.y()},
                             {"score", p.match.score},
                             {"uniqueness", p.match.uniqueness},
                             {"proposed", p.Proposed()},
                             {"reason", p.match.reason}});
      }
    }
    report["pin_proposals"] = {{"image_id", ghosts.computed ? ghosts.image_id : kNoId},
                               {"computations", ghosts.computations},
                               {"error", ghosts.summary.error},
                               {"proposals", std::move(proposals)}};
  }
  report["selection"] = {{"segment_id", state.selection.segment_id},
                         {"segment_endpoint", state.selection.segment_endpoint},
                         {"pin_id", state.selection.pin_id},
                         {"primitive_id", state.selection.primitive_id},
                         {"element",
                          {{"kind", ElementKindName(state.selection.element.kind)},
                           {"primitive_id", state.selection.element.primitive_id},
                           {"id", state.selection.element.element}}}};
  nlohmann::json extra = nlohmann::json::array();
  for (const ElementRef& e : state.selection.extra)
    extra.push_back({{"kind", ElementKindName(e.kind)}, {"primitive_id", e.primitive_id}, {"id", e.element}});
  report["selection"]["extra"] = std::move(extra);
  report["hover"] = {{"kind", ElementKindName(state.hover.kind)},
                     {"primitive_id", state.hover.primitive_id},
                     {"id", state.hover.element}};
  report["solve"] = {{"termination", SolverTerminationName(state.last_update.solve.termination)},
                     {"rms_px", state.last_update.solve.reprojection_rms_px},
                     {"max_px", state.last_update.solve.reprojection_max_px}};
  const JointSolveSummary& joint = state.last_update.joint;
  report["joint_solve"] = {{"termination", SolverTerminationName(joint.termination)},
                           {"message", joint.message},
                           {"rms_px", joint.reprojection_rms_px},
                           {"undetermined", joint.undetermined},
                           {"conflicts", joint.conflicts}};
  nlohmann::json log = nlohmann::json::array();
  for (const LogEntry& e : state.log) {
    const char* level = e.level == LogLevel::kInfo ? "info" : e.level == LogLevel::kWarning ? "warning" : "error";
    log.push_back({{"level", level}, {"text", e.text}});
  }
  report["log"] = log;
  report["dialog"] = DialogName(shell.dialog);
  const AutosaveState& autosave = state.autosave;
  report["autosave"] = {{"enabled", autosave.enabled},
                        {"recovery_file", autosave.owned_path},
                        {"writes", autosave.stats.writes},
                        {"failures", autosave.stats.failures},
                        {"compactions", autosave.stats.compactions},
                        {"bytes_written", autosave.stats.bytes_written},
                        {"last_bytes_written", autosave.stats.last_bytes_written},
                        {"last_snapshot_ms", autosave.stats.last_snapshot_ms},
                        {"last_write_ms", autosave.stats.last_write_ms},
                        {"last_bytes", autosave.stats.last_bytes},
                        {"offer", autosave.offer ? autosave.offer->recovery_path : std::string()}};
  const ProjectGuard& guard = state.project_guard;
  report["project_lock"] = {{"held", guard.lock.held()},
                            {"lock_file", guard.lock.path()},
                            {"read_only", guard.read_only},
                            {"question_path", guard.question_path}};
  const FileDialogState& browser = shell.file_dialog;
  report["file_dialog"] = {{"folder", browser.folder},
                           {"name", browser.name_field},
                           {"selected", browser.selected},
                           {"error", browser.error},
                           {"confirm_overwrite", browser.confirm_overwrite},
                           {"all_files", browser.all_files}};
  report["recent_files"] = {{"files", shell.recent_files.files}, {"folders", shell.recent_files.folders}};
  report["project"] = nlohmann::json::parse(ProjectToJson(state.document.project()), nullptr, false);
  report["teach"] = TeachReportJson(state);
  report["texture"] = TextureReportJson(state);
  // Paths are bytes: one that is not UTF-8 (a folder named in another encoding) is reported
  // with U+FFFD rather than making dump() throw (nlohmann's error 316 aborted the render).
  return report.dump(2, ' ', false, nlohmann::json::error_handler_t::replace);
}

bool StepNeedsLineDetection(const ScriptStep& step) {
  const bool presses = std::any_of(step.mouse_down.begin(), step.mouse_down.end(),
                                   [](const std::optional<bool>& down) { return down.value_or(false); });
  return presses || step.key_press || !step.text.empty() || !step.dropped_paths.empty() ||
         !step.screenshot_path.empty() || step.burst != Burst::kNone ||
         (step.mouse_pos && step.mouse_space == PointSpace::kItem);
}

int Fail(const std::string& message) {
  std::fprintf(stderr, "facet render: %s\n", message.c_str());
  return 1;
}

int RenderWithContext(const RenderOptions& options, AppState* state, ShellState* shell, const Script& script,
                      const std::string& renderer) {
  std::string error;
  OffscreenTarget target;
  if (!target.Create(options.width, options.height, &error)) return Fail(error);

  ImGuiIO& io = ImGui::GetIO();
  io.DisplaySize = ImVec2(static_cast<float>(options.width), static_cast<float>(options.height));
  io.DisplayFramebufferScale = ImVec2(1, 1);
  io.DeltaTime = static_cast<float>(kFrameTimeS);
  SetGlfwKeyMap(io);

  ScriptedInput input;
  input.queue = &shell->input_queue;
  std::array<float, 2> drag_anchor{0.0f, 0.0f};  // screen position where the current drag began
  int frame = 0;
  // One frame: input, app command, UI, render into the target, optional screenshot.
  auto draw_frame = [&](const ScriptStep* step) -> bool {
    ScriptStep resolved;
    if (step && step->mouse_pos) {
      resolved = *step;
      std::array<float, 2> screen;
      std::string point_error;
      if (!ResolveScriptPoint(*state, *shell, *step, &screen, &point_error)) {
        error = "script line " + std::to_string(step->line) + ": " + point_error;
        return false;
      }
      if (step->drag_anchor) drag_anchor = screen;
      if (step->drag_fraction) {
        const float f = *step->drag_fraction;
        screen = {drag_anchor[0] + f * (screen[0] - drag_anchor[0]), drag_anchor[1] + f * (screen[1] - drag_anchor[1])};
      }
      resolved.mouse_pos = screen;
      resolved.mouse_space = PointSpace::kScreen;
      step = &resolved;
    }
    // The frame's time on the queue's clock: each frame one step of the fixed clock later.
    const double input_time_s = (frame + 1) * kFrameTimeS;
    input.Push(step, input_time_s);
    ApplyInputFrame(shell->input_queue.NextFrame(input_time_s), &io);
    if (step && !step->dropped_paths.empty()) shell->dropped_paths = step->dropped_paths;
    if (step && !step->command.empty()) {
      std::string command_error;
      if (!RunAppCommand(state, shell, step->command, step->command_args, &command_error)) {
        error = "script line " + std::to_string(step->line) + ": command " + step->command + ": " + command_error;
        return false;
      }
    }
    ImGui_ImplOpenGL3_NewFrame();
    ImGui::NewFrame();
    DrawFrame(state, shell, frame * kFrameTimeS + shell->clock_offset_s);
    ImGui::Render();
    target.Bind();
    glClearColor(0.075f, 0.08f, 0.09f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    ++frame;
    if (step && !step->screenshot_path.empty()) {
      const std::string write_error = WritePng(step->screenshot_path, target.Read());
      if (!write_error.empty()) {
        error = "script line " + std::to_string(step->line) + ": screenshot: " + write_error;
        return false;
      }
    }
    // `export-view` (the command or File > Export view's dialog): after the frame that asked.
    const std::string export_error = RunPendingExportView(state, shell, frame * kFrameTimeS + shell->clock_offset_s);
    if (!export_error.empty()) {
      error = "script line " + std::to_string(step ? step->line : 0) + ": " + export_error;
      return false;
    }
    return true;
  };

  // A line detection on its worker is waited for before a step whose outcome may depend on
  // the proposals (a click or key on them, a picture of them, a point on one of their
  // widgets), so a script acts the same however fast the worker is; between such steps the
  // frames go on while it runs, as in the GUI. When the wait brought the proposals, one frame
  // draws them first, so that `item image.accept_lines` finds its button. `lines` commands
  // wait by themselves (app/state/line_proposals.h).
  auto run_frame = [&](const ScriptStep* step) -> bool {
    if (step && StepNeedsLineDetection(*step) && LineDetectionInFlight(*state)) {
      CollectLineDetection(state, /*wait=*/true);
      if (!draw_frame(nullptr)) return false;
    }
    return draw_frame(step);
  };

  bool ok = true;
  for (int i = 0; ok && i < kWarmUpFrames; ++i) ok = run_frame(nullptr);
  for (size_t i = 0; ok && i < script.steps.size(); ++i) ok = run_frame(&script.steps[i]);
  if (ok) CollectLineDetection(state, /*wait=*/true);  // the final picture and report show its proposals
  for (int i = 0; ok && i < kSettleFrames; ++i) ok = run_frame(nullptr);
  if (!ok) return Fail(error);

  if (options.panel.empty()) {
    const std::string write_error = WritePng(options.output_png, target.Read());
    if (!write_error.empty()) return Fail("cannot write " + options.output_png + ": " + write_error);
  } else {  // --panel: the panel alone, its canvas the asked size (app/shell/export_view.h)
    ExportViewRequest request;
    request.panel = options.panel == "image" ? PanelId::kImage : PanelId::kViewport;
    request.width_px = options.panel_width;
    request.height_px = options.panel_height;
    request.path = options.output_png;
    const std::string export_error = ExportView(state, shell, request, frame * kFrameTimeS);
    if (!export_error.empty()) return Fail(export_error);
  }
  if (!options.report_path.empty()) {
    const std::string report = BuildReport(*state, *shell, options, renderer, frame, script);
    const std::string report_error = WriteFileAtomically(options.report_path, report);
    if (!report_error.empty()) return Fail("cannot write " + options.report_path + ": " + report_error);
  }
  return 0;
}

}  // namespace

int RunGui(const GuiOptions& options) {
  if (!HasDisplay()) {
    std::fputs("facet: no display found; use 'facet render PROJECT -o SHOT.png' for offscreen rendering\n", stderr);
    return 2;
  }
  AppState state;
  ShellState shell;
  const std::string layout_path = LayoutFilePath();
  std::string imgui_ini;
  if (!layout_path.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(ConfigDirectory(), ec);
    imgui_ini = ConfigDirectory() + "/imgui.ini";
    if (std::filesystem::exists(layout_path, ec)) {
      std::string error;
      if (!LoadLayoutFile(layout_path, &shell.layout, &error)) {
        state.Log(LogLevel::kWarning, "Layout not restored (" + error + "); using the default layout");
      }
    }
  }
  UseRecentFilesIn(&state, &shell, ConfigDirectory());
  state.autosave.enabled = true;
  // A project another Facet holds is not opened yet: DrawFrame asks (read-only, a copy, cancel).
  if (!options.project_path.empty() && OpenProject(&state, options.project_path)) {
    NoteRecentFile(&state, &shell, options.project_path);
  }
  // A crashed session's work: the project's own recovery file, else an unsaved project's
  // (whichever project opened, the default sample included). DrawFrame shows the offer.
  FindRecovery(&state, /*also_unsaved=*/true);

  const int code = RunGlfwWindow(&state, &shell, imgui_ini);
  FinishAutosave(&state);
  if (code == 0 && !layout_path.empty()) {
    std::string error;
    if (!SaveLayoutFile(layout_path, shell.layout, &error)) std::fprintf(stderr, "facet: %s\n", error.c_str());
  }
  return code;
}

int RunOffscreen(const RenderOptions& options) {
  if (options.output_png.empty()) return Fail("no output file (-o SHOT.png)");
  if (!options.panel.empty() && options.panel != "image" && options.panel != "3d")
    return Fail("--panel must be image or 3d, not " + options.panel);
  if (options.width < 64 || options.height < 64 || options.width > 8192 || options.height > 8192) {
    return Fail("size " + std::to_string(options.width) + "x" + std::to_string(options.height) +
                " is outside 64..8192 px");
  }
  Script script;
  std::string error;
  if (!options.script_path.empty() && !LoadScript(options.script_path, &script, &error)) return Fail(error);

  AppState state;
  ShellState shell;
  shell.offscreen = true;  // the default layout, never the user's
  state.snapping = options.snapping;
  if (!options.config_dir.empty()) UseRecentFilesIn(&state, &shell, options.config_dir);
  // With --autosave, a project another Facet holds opens read-only here (a script's `command
  // open` asks as the GUI does); without it, the lock is taken when a script saves
  // (app/state/project_guard.h).
  state.project_guard.lock_on_open = options.autosave;
  if (!options.project_path.empty() && !OpenProject(&state, options.project_path, OpenAccess::kEditOrReadOnly)) {
    return Fail("cannot open project " + options.project_path);
  }
  state.autosave.enabled = options.autosave;
  // As the GUI's start: the project's recovery file, else an unsaved project's.
  FindRecovery(&state, /*also_unsaved=*/true);

  EglContext egl;
  if (!egl.Create(&error)) return Fail("no offscreen OpenGL context: " + error);
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ConfigureImGui(/*offscreen=*/true);
  if (!ImGui_ImplOpenGL3_Init("#version 330")) {
    ImGui::DestroyContext();
    return Fail("the ImGui OpenGL3 renderer failed to start on " + egl.Renderer());
  }
  // --panel: the app runs in its default window size; --size is the panel's picture.
  RenderOptions run = options;
  if (!options.panel.empty()) {
    run.panel_width = options.width;
    run.panel_height = options.height;
    run.width = RenderOptions().width;
    run.height = RenderOptions().height;
  }
  const int code = RenderWithContext(run, &state, &shell, script, egl.Renderer());
  FinishAutosave(&state);  // the end of a script is a clean exit, failed or not
  ShutdownImagePanel(&shell.image_panel);
  ShutdownViewportPanel(&shell.viewport_panel);
  ImGui_ImplOpenGL3_Shutdown();
  ImGui::DestroyContext();
  return code;
}

}  // namespace facet::app
