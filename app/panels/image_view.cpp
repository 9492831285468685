#include "app/panels/image_view.h"

#include "app/panels/image_snapping.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace facet::app {
namespace {

constexpr float kFitMarginPx = 8.0f;
constexpr float kLoupeSizePx = 220.0f;
constexpr float kLoupeOffsetPx = 28.0f;

}  // namespace

void FitImageView(ImageViewState* view, int width_px, int height_px, ImVec2 rect_min, ImVec2 rect_size) {
  const float avail_w = std::max(1.0f, rect_size.x - 2.0f * kFitMarginPx);
  const float avail_h = std::max(1.0f, rect_size.y - 2.0f * kFitMarginPx);
  view->zoom = std::clamp(std::min(avail_w / width_px, avail_h / height_px), kMinImageZoom, kMaxImageZoom);
  // The image spans [-0.5, size - 0.5]: its centre is at ((w - 1) / 2, (h - 1) / 2).
  const ImVec2 center(rect_min.x + 0.5f * rect_size.x, rect_min.y + 0.5f * rect_size.y);
  view->origin = ImVec2(center.x - view->zoom * 0.5f * (width_px - 1), center.y - view->zoom * 0.5f * (height_px - 1));
  view->fitted = true;
  view->initialized = true;
  view->last_size = rect_size;
}

void FitImageViewToBox(ImageViewState* view, const Eigen::Vector2d& box_min_px, const Eigen::Vector2d& box_max_px,
                       ImVec2 rect_min, ImVec2 rect_size, float reserve_bottom_px) {
  const float usable_h = std::max(1.0f, rect_size.y - std::max(0.0f, reserve_bottom_px));
  const float avail_w = std::max(1.0f, rect_size.x - 2.0f * kFitMarginPx);
  const float avail_h = std::max(1.0f, usable_h - 2.0f * kFitMarginPx);
  const Eigen::Vector2d size = (box_max_px - box_min_px).cwiseMax(1.0);
  view->zoom = std::clamp(std::min(avail_w / static_cast<float>(size.x()), avail_h / static_cast<float>(size.y())),
                          kMinImageZoom, kMaxImageZoom);
  const Eigen::Vector2d box_centre = 0.5 * (box_min_px + box_max_px);
  const ImVec2 centre(rect_min.x + 0.5f * rect_size.x, rect_min.y + 0.5f * usable_h);
  view->origin = ImVec2(centre.x - view->zoom * static_cast<float>(box_centre.x()),
                        centre.y - view->zoom * static_cast<float>(box_centre.y()));
  view->fitted = false;
  view->initialized = true;
  view->last_size = rect_size;
}

void ZoomImageViewAbout(ImageViewState* view, float new_zoom, ImVec2 anchor) {
  new_zoom = std::clamp(new_zoom, kMinImageZoom, kMaxImageZoom);
  const float ratio = new_zoom / view->zoom;
  view->origin = ImVec2(anchor.x - (anchor.x - view->origin.x) * ratio, anchor.y - (anchor.y - view->origin.y) * ratio);
  view->zoom = new_zoom;
  view->fitted = false;
}

void DrawLoupe(ImDrawList* draw_list, const TiledTexture* texture, const OverlayInput& overlay,
               const OverlayOptions& overlay_options, const ImageViewState& view, float magnification,
               const Eigen::Vector2d& uv, const std::optional<LoupePreview>& preview, ImVec2 rect_min, ImVec2 rect_max,
               int width_px, int height_px, const SnapResult* snap) {
  const ImVec2 pointer = TransformOf(view).ToScreen(uv.x(), uv.y());
  const float size = std::min({kLoupeSizePx, rect_max.x - rect_min.x - 4.0f, rect_max.y - rect_min.y - 4.0f});
  if (size < 40.0f) return;
  // Above-right of the pointer, flipped to stay inside the view.
  ImVec2 p_min(pointer.x + kLoupeOffsetPx, pointer.y - kLoupeOffsetPx - size);
  if (p_min.x + size > rect_max.x) p_min.x = pointer.x - kLoupeOffsetPx - size;
  if (p_min.y < rect_min.y) p_min.y = pointer.y + kLoupeOffsetPx;
  p_min.x = std::clamp(p_min.x, rect_min.x + 2.0f, rect_max.x - size - 2.0f);
  p_min.y = std::clamp(p_min.y, rect_min.y + 2.0f, rect_max.y - size - 2.0f);
  const ImVec2 p_max(p_min.x + size, p_min.y + size);
  const ImVec2 center(std::floor(p_min.x + 0.5f * size) + 0.5f, std::floor(p_min.y + 0.5f * size) + 0.5f);

  ViewTransform loupe;
  loupe.zoom = std::min(view.zoom * magnification, kMaxImageZoom * 4.0f);
  loupe.origin =
      ImVec2(static_cast<float>(center.x - loupe.zoom * uv.x()), static_cast<float>(center.y - loupe.zoom * uv.y()));

  draw_list->AddRectFilled(ImVec2(p_min.x - 3, p_min.y - 3), ImVec2(p_max.x + 3, p_max.y + 3), IM_COL32(0, 0, 0, 220));
  draw_list->AddRectFilled(p_min, p_max, kImageViewBackground);
  draw_list->PushClipRect(p_min, p_max, true);
  if (texture != nullptr) {
    DrawTiledTexture(draw_list, *texture, loupe, p_min, p_max);
  } else {
    draw_list->AddRectFilled(loupe.ToScreen(-0.5, -0.5), loupe.ToScreen(width_px - 0.5, height_px - 0.5),
                             IM_COL32(70, 70, 76, 255));
  }
  OverlayOptions options = overlay_options;
  options.show_labels = false;
  options.show_vanishing_points = false;  // border arrows would crowd the small square
  DrawImageOverlays(draw_list, overlay, loupe, p_min, p_max, options);
  if (preview) {
    DrawImageLine(draw_list, loupe, preview->a_px, uv, p_min, p_max, IM_COL32(0, 0, 0, 200), 4.0f);
    DrawImageLine(draw_list, loupe, preview->a_px, uv, p_min, p_max, AxisColor(preview->axis), 2.0f);
  }
  if (snap != nullptr && snap->kind != SnapKind::kNone) {
    DrawSnapMarker(draw_list, loupe.ToScreen(snap->position_px.x(), snap->position_px.y()), snap->kind, true);
  }
  // Crosshair with a gap, so the pixel under the cursor stays visible.
  const float gap = 4.0f;
  const ImU32 dark = IM_COL32(0, 0, 0, 200), light = IM_COL32(255, 255, 255, 230);
  for (int pass = 0; pass < 2; ++pass) {
    const ImU32 c = pass == 0 ? dark : light;
    const float t = pass == 0 ? 3.0f : 1.0f;
    draw_list->AddLine(ImVec2(p_min.x, center.y), ImVec2(center.x - gap, center.y), c, t);
    draw_list->AddLine(ImVec2(center.x + gap, center.y), ImVec2(p_max.x, center.y), c, t);
    draw_list->AddLine(ImVec2(center.x, p_min.y), ImVec2(center.x, center.y - gap), c, t);
    draw_list->AddLine(ImVec2(center.x, center.y + gap), ImVec2(center.x, p_max.y), c, t);
  }
  char text[96];
  std::snprintf(text, sizeof(text), "%gx  (%.1f, %.1f)", magnification, uv.x(), uv.y());
  DrawShadowedText(draw_list, ImVec2(p_min.x + 5, p_max.y - ImGui::GetTextLineHeight() - 4), light, text);
  draw_list->PopClipRect();
  draw_list->AddRect(p_min, p_max, light, 0.0f, 0, 1.0f);
}

}  // namespace facet::app
