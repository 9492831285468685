#include "app/panels/widgets.h"

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstring>

namespace facet::app {

void RecordItem(AppState* state, const std::string& name) {
  const ImVec2 min = ImGui::GetItemRectMin(), size = ImGui::GetItemRectSize();
  state->item_rects[name] = {min.x, min.y, size.x, size.y};
  // Drawn but scrolled out of its panel (or clipped by it): a scripted click at its centre
  // would land on whatever is there instead.
  const ImVec2 clip_min = ImGui::GetWindowDrawList()->GetClipRectMin();
  const ImVec2 clip_max = ImGui::GetWindowDrawList()->GetClipRectMax();
  const ImVec2 centre(min.x + 0.5f * size.x, min.y + 0.5f * size.y);
  const bool in_view = centre.x >= clip_min.x && centre.y >= clip_min.y && centre.x < clip_max.x &&
                       centre.y < clip_max.y;
  if (in_view) {
    state->clipped_items.erase(name);
  } else {
    state->clipped_items.insert(name);
  }
}

ImVec4 AxisColor(Axis axis) {
  switch (axis) {
    case Axis::kX: return ImVec4(0.95f, 0.35f, 0.32f, 1.0f);
    case Axis::kY: return ImVec4(0.40f, 0.85f, 0.40f, 1.0f);
    case Axis::kZ: return ImVec4(0.40f, 0.60f, 1.00f, 1.0f);
  }
  return ImVec4(1, 1, 1, 1);
}

void LabelValue(const char* label, const char* fmt, ...) {
  ImGui::TextColored(kDimText, "%s", label);
  ImGui::SameLine(ImGui::GetFontSize() * 7.5f);
  va_list args;
  va_start(args, fmt);
  ImGui::TextV(fmt, args);
  va_end(args);
}

void WrappedColored(const ImVec4& color, const std::string& text) {
  ImGui::PushStyleColor(ImGuiCol_Text, color);
  ImGui::TextWrapped("%s", text.c_str());
  ImGui::PopStyleColor();
}

void TrackEdit(AppState* state, const std::string& label, bool changed, const std::function<void(Project*)>& apply) {
  if (ImGui::IsItemActivated()) BeginDrag(state, label);
  if (changed) {
    Project edited = state->document.project();
    apply(&edited);
    if (state->drag_start) {
      UpdateDrag(state, std::move(edited));
    } else {
      CommitEdit(state, label, std::move(edited));
    }
  }
  if (ImGui::IsItemDeactivatedAfterEdit()) {
    EndDrag(state);
  } else if (ImGui::IsItemDeactivated()) {
    CancelDrag(state);
  }
}

bool DragDoubles(const char* label, double* values, int count, float speed, const char* format) {
  return ImGui::DragScalarN(label, ImGuiDataType_Double, values, count, speed, nullptr, nullptr, format);
}

bool DragDoublesRecorded(AppState* state, const char* label, double* values, int count, float speed, const char* format,
                         const std::string& item_name) {
  const float spacing = ImGui::GetStyle().ItemInnerSpacing.x;
  const float full_width = ImGui::CalcItemWidth();
  bool changed = false;
  ImGui::BeginGroup();
  ImGui::PushID(label);
  for (int i = 0; i < count; ++i) {
    ImGui::PushID(i);
    if (i > 0) ImGui::SameLine(0.0f, spacing);
    // As DragScalarN: equal widths, the last one taking what rounding leaves.
    const float each = std::max(1.0f, (full_width - spacing * (count - 1)) / count);
    const float width =
        i + 1 < count ? std::floor(each) : std::max(1.0f, full_width - (std::floor(each) + spacing) * (count - 1));
    ImGui::SetNextItemWidth(width);
    changed |= ImGui::DragScalar("", ImGuiDataType_Double, &values[i], speed, nullptr, nullptr, format);
    RecordItem(state, item_name + "." + std::to_string(i));
    ImGui::PopID();
  }
  ImGui::PopID();
  const char* hidden = std::strstr(label, "##");  // ImGui's convention: what follows is not shown
  const char* label_end = hidden != nullptr ? hidden : label + std::strlen(label);
  if (label != label_end) {
    ImGui::SameLine(0.0f, spacing);
    ImGui::TextUnformatted(label, label_end);
  }
  ImGui::EndGroup();
  return changed;
}

}  // namespace facet::app
