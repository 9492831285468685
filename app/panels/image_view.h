// The image view's transform (zoom and pan per image, app-side UI state) and the loupe: a
// magnified square of the photo and its overlays around a point, with a crosshair on it.
// Pixel convention (core/geometry/conventions.h): screen = origin + zoom * uv_px, where origin is the
// screen position of pixel (0, 0)'s centre; the image covers [-0.5, size - 0.5] in uv.
#pragma once

#include <optional>

#include <imgui.h>
#include <Eigen/Core>

#include "app/panels/image_overlay.h"
#include "app/platform/image_tiles.h"
#include "core/geometry/image_snap.h"

namespace facet::app {

constexpr float kMinImageZoom = 1.0f / 1024.0f;
constexpr float kMaxImageZoom = 64.0f;
constexpr float kMinLoupeMagnification = 2.0f;
constexpr float kMaxLoupeMagnification = 32.0f;
constexpr ImU32 kImageViewBackground = IM_COL32(38, 38, 42, 255);

// One image's view. Never part of the document: zooming is not an edit.
struct ImageViewState {
  bool initialized = false;
  bool fitted = false;  // refit when the panel is resized while this holds
  float zoom = 1.0f;    // screen px per image px
  ImVec2 origin{0, 0};  // screen position of pixel (0, 0)'s centre
  ImVec2 last_size{0, 0};
};

inline ViewTransform TransformOf(const ImageViewState& view) { return ViewTransform{view.origin, view.zoom}; }

// Centres a width_px x height_px image in the screen rectangle at the largest zoom that
// leaves an 8 px margin; marks the view fitted.
void FitImageView(ImageViewState* view, int width_px, int height_px, ImVec2 rect_min, ImVec2 rect_size);
// Centres the image-px box [box_min_px, box_max_px] in the screen rectangle less
// `reserve_bottom_px` at its bottom (kept free for a text box), at the largest zoom that
// leaves an 8 px margin. The view is not marked fitted: a resize keeps it.
void FitImageViewToBox(ImageViewState* view, const Eigen::Vector2d& box_min_px, const Eigen::Vector2d& box_max_px,
                       ImVec2 rect_min, ImVec2 rect_size, float reserve_bottom_px);
// Sets the zoom (clamped to [kMinImageZoom, kMaxImageZoom]) keeping the image point under
// the screen point `anchor` where it is.
void ZoomImageViewAbout(ImageViewState* view, float new_zoom, ImVec2 anchor);

// A segment being drawn, shown in the loupe too.
struct LoupePreview {
  Eigen::Vector2d a_px = Eigen::Vector2d::Zero();
  Axis axis = Axis::kX;
};

// Draws the loupe near the screen position of `uv_px` (inside the view rectangle), showing
// the photo (or a placeholder of width_px x height_px when `texture` is null) and the
// overlays at `magnification` times the view's zoom, centred on uv_px, with the snap target
// (when `snap` is given and snapped) marked.
void DrawLoupe(ImDrawList* draw_list, const TiledTexture* texture, const OverlayInput& overlay,
               const OverlayOptions& overlay_options, const ImageViewState& view, float magnification,
               const Eigen::Vector2d& uv_px, const std::optional<LoupePreview>& preview, ImVec2 rect_min,
               ImVec2 rect_max, int width_px, int height_px, const SnapResult* snap = nullptr);

}  // namespace facet::app
