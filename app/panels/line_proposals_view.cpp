#include "app/panels/line_proposals_view.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

#include "app/panels/image_overlay.h"
#include "app/panels/widgets.h"
#include "app/state/line_proposals.h"

namespace facet::app {
namespace {

constexpr double kPickRadiusPx = 6.0;  // screen px, as the panel's other picks
constexpr float kDashPx = 7.0f;

const LineProposals* ProposalsOf(const AppState& state, Id image_id) {
  return state.line_proposals && state.line_proposals->image_id == image_id ? &*state.line_proposals : nullptr;
}

double ScreenDistanceToSegment(const ViewTransform& view, const Segment& s, ImVec2 p) {
  const ImVec2 a = view.ToScreen(s.a_px.x(), s.a_px.y()), b = view.ToScreen(s.b_px.x(), s.b_px.y());
  const Eigen::Vector2d ea(a.x, a.y), eb(b.x, b.y), ep(p.x, p.y);
  const Eigen::Vector2d d = eb - ea;
  const double t = d.squaredNorm() > 0.0 ? std::clamp((ep - ea).dot(d) / d.squaredNorm(), 0.0, 1.0) : 0.0;
  return (ea + t * d - ep).norm();
}

// A dashed line between two image points, clipped to the rectangle.
void DrawDashed(ImDrawList* draw_list, const ViewTransform& view, const Eigen::Vector2d& a_px,
                const Eigen::Vector2d& b_px, ImVec2 clip_min, ImVec2 clip_max, ImU32 color, float thickness) {
  const ImVec2 a = view.ToScreen(a_px.x(), a_px.y()), b = view.ToScreen(b_px.x(), b_px.y());
  Eigen::Vector2d ea(a.x, a.y), eb(b.x, b.y);
  if (!ClipSegmentToRect(&ea, &eb, Eigen::Vector2d(clip_min.x, clip_min.y), Eigen::Vector2d(clip_max.x, clip_max.y)))
    return;
  const double length = (eb - ea).norm();
  const int dashes = std::max(1, static_cast<int>(length / (2.0 * kDashPx)));
  for (int i = 0; i < dashes; ++i) {
    const Eigen::Vector2d p = ea + (eb - ea) * (2.0 * i) / (2.0 * dashes - 1.0);
    const Eigen::Vector2d q = ea + (eb - ea) * (2.0 * i + 1.0) / (2.0 * dashes - 1.0);
    draw_list->AddLine(ImVec2(static_cast<float>(p.x()), static_cast<float>(p.y())),
                       ImVec2(static_cast<float>(q.x()), static_cast<float>(q.y())), color, thickness);
  }
}

}  // namespace

void DrawLineProposalsBar(AppState* state, Id image_id) {
  const std::optional<LineDetectionJob>& running = state->line_detection.job;
  ImGui::BeginDisabled(running.has_value());
  if (ImGui::SmallButton("Detect lines")) StartLineDetection(state, image_id);
  ImGui::EndDisabled();
  RecordItem(state, "image.detect_lines");
  if (ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled))
    ImGui::SetTooltip("Find the photo's straight lines and group them into three directions, as proposals");
  if (running) {
    // The worker gives no progress of its own: a turning bar and the seconds so far say it
    // is alive. Frame time, not the wall clock, so that an offscreen picture is repeatable.
    const double elapsed_s = std::max(0.0, state->time_s - running->started_s);
    const char spinner = "|/-\\"[static_cast<int>(elapsed_s * 8.0) % 4];
    ImGui::SameLine();
    if (running->image_id == image_id) {
      ImGui::TextColored(kDimText, "Detecting lines... %c %.1f s", spinner, elapsed_s);
    } else {
      ImGui::TextColored(kDimText, "Detecting lines on %s... %c %.1f s", running->photo_name.c_str(), spinner,
                         elapsed_s);
    }
    RecordItem(state, "image.detecting_lines");
    return;
  }
  const LineProposals* proposals = ProposalsOf(*state, image_id);
  if (proposals == nullptr) return;
  int counts[3] = {0, 0, 0};
  for (const Segment& s : proposals->segments) ++counts[static_cast<int>(s.axis)];
  ImGui::SameLine();
  ImGui::Text("%d proposed:", static_cast<int>(proposals->segments.size()));
  for (int a = 0; a < 3; ++a) {
    ImGui::SameLine();
    ImGui::TextColored(ImGui::ColorConvertU32ToFloat4(AxisColor(static_cast<Axis>(a), 255)), "%s %d",
                       AxisName(static_cast<Axis>(a)), counts[a]);
  }
  ImGui::SameLine();
  if (ImGui::SmallButton("Accept all")) {
    AcceptLineProposals(state);
    return;
  }
  RecordItem(state, "image.accept_lines");
  ImGui::SameLine();
  if (ImGui::SmallButton("Discard")) {
    DiscardLineProposals(state);
    return;
  }
  // The selected proposal's own row: the panel is too narrow for both on one.
  const int selected = proposals->selected;
  if (selected < 0) {
    ImGui::TextDisabled("Dashed: proposed lines. Click one to re-assign or remove it (Delete).");
    return;
  }
  ImGui::TextDisabled("Line %d:", selected);
  for (int a = 0; a < 3; ++a) {
    const Axis axis = static_cast<Axis>(a);
    ImGui::SameLine();
    const bool current = proposals->segments[selected].axis == axis;
    ImGui::PushStyleColor(ImGuiCol_Text, AxisColor(axis, 255));
    const std::string label = std::string(current ? "[" : " ") + AxisName(axis) + (current ? "]" : " ");
    if (ImGui::SmallButton(label.c_str())) AssignLineProposal(state, selected, axis);
    ImGui::PopStyleColor();
  }
  ImGui::SameLine();
  if (ImGui::SmallButton("Remove")) RemoveLineProposal(state, selected);
}

bool ClickLineProposal(AppState* state, Id image_id, const ViewTransform& view, bool view_hovered) {
  if (!view_hovered || !ImGui::IsMouseClicked(ImGuiMouseButton_Left)) return false;
  if (!state->line_proposals || state->line_proposals->image_id != image_id) return false;
  LineProposals& proposals = *state->line_proposals;
  const ImVec2 mouse = ImGui::GetIO().MousePos;
  int best = -1;
  double best_distance = kPickRadiusPx;
  for (size_t i = 0; i < proposals.segments.size(); ++i) {
    const double d = ScreenDistanceToSegment(view, proposals.segments[i], mouse);
    if (d < best_distance) {
      best_distance = d;
      best = static_cast<int>(i);
    }
  }
  if (best < 0) return false;
  proposals.selected = best;
  return true;
}

void DrawLineProposals(ImDrawList* draw_list, const AppState& state, Id image_id, const ViewTransform& view,
                       ImVec2 clip_min, ImVec2 clip_max) {
  const LineProposals* proposals = ProposalsOf(state, image_id);
  if (proposals == nullptr) return;
  draw_list->PushClipRect(clip_min, clip_max, true);
  for (const Eigen::Vector4d& s : proposals->outliers)
    DrawImageLine(draw_list, view, s.head<2>(), s.tail<2>(), clip_min, clip_max, IM_COL32(200, 200, 200, 110), 1.0f);
  for (size_t i = 0; i < proposals->segments.size(); ++i) {
    const Segment& s = proposals->segments[i];
    const bool selected = static_cast<int>(i) == proposals->selected;
    DrawDashed(draw_list, view, s.a_px, s.b_px, clip_min, clip_max, IM_COL32(0, 0, 0, 170), selected ? 6.0f : 4.0f);
    DrawDashed(draw_list, view, s.a_px, s.b_px, clip_min, clip_max,
               selected ? IM_COL32(255, 255, 255, 255) : AxisColor(s.axis, 255), selected ? 3.5f : 2.0f);
    if (selected) DrawDashed(draw_list, view, s.a_px, s.b_px, clip_min, clip_max, AxisColor(s.axis, 255), 2.0f);
  }
  draw_list->PopClipRect();
}

}  // namespace facet::app
