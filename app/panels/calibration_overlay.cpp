#include "app/panels/calibration_overlay.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include "app/panels/image_overlay.h"
#include "core/solve/multiview_init.h"

namespace facet::app {

namespace {

constexpr ImU32 kGivenHorizonColor = IM_COL32(255, 160, 60, 255);  // the fitted one is kHorizonColor
// Outliers are the fit working as meant, not a failure: a muted mark (red is kept for failures).
constexpr ImU32 kOutlierColor = IM_COL32(190, 190, 190, 255);
constexpr ImU32 kShadow = IM_COL32(0, 0, 0, 170);
constexpr float kDashPx = 10.0f;
constexpr float kGapPx = 6.0f;

// The screen line through a and b extended across [clip_min, clip_max]; false when it misses.
bool LineAcrossRect(Eigen::Vector2d a, Eigen::Vector2d b, ImVec2 clip_min, ImVec2 clip_max, Eigen::Vector2d* p0,
                    Eigen::Vector2d* p1) {
  const Eigen::Vector2d d = b - a;
  const double len = d.norm();
  if (!(len > 1e-9)) return false;
  const double reach = 4.0 * (std::abs(clip_max.x - clip_min.x) + std::abs(clip_max.y - clip_min.y)) +
                       (a - Eigen::Vector2d(clip_min.x, clip_min.y)).norm();
  *p0 = a - d / len * reach;
  *p1 = a + d / len * reach;
  return ClipSegmentToRect(p0, p1, Eigen::Vector2d(clip_min.x, clip_min.y), Eigen::Vector2d(clip_max.x, clip_max.y));
}

void DrawDashed(ImDrawList* draw_list, const Eigen::Vector2d& p0, const Eigen::Vector2d& p1, ImU32 color, float width) {
  const Eigen::Vector2d d = p1 - p0;
  const double len = d.norm();
  if (!(len > 0.0)) return;
  const Eigen::Vector2d u = d / len;
  for (double s = 0.0; s < len; s += kDashPx + kGapPx) {
    const Eigen::Vector2d a = p0 + u * s, b = p0 + u * std::min(len, s + kDashPx);
    draw_list->AddLine(ImVec2(float(a.x()), float(a.y())), ImVec2(float(b.x()), float(b.y())), kShadow, width + 2.0f);
    draw_list->AddLine(ImVec2(float(a.x()), float(a.y())), ImVec2(float(b.x()), float(b.y())), color, width);
  }
}

Eigen::Vector2d Screen(const ViewTransform& view, double u, double v) {
  return Eigen::Vector2d(view.origin.x + static_cast<double>(view.zoom) * u,
                         view.origin.y + static_cast<double>(view.zoom) * v);
}

// The user's horizon: dashed across the view, its two points as rings, labelled at the first.
void DrawGivenHorizon(ImDrawList* draw_list, const Image& image, const ViewTransform& view, ImVec2 clip_min,
                      ImVec2 clip_max) {
  const Eigen::Vector4d& h = image.horizon_px;
  const Eigen::Vector2d a = Screen(view, h[0], h[1]), b = Screen(view, h[2], h[3]);
  Eigen::Vector2d p0, p1;
  if (!LineAcrossRect(a, b, clip_min, clip_max, &p0, &p1)) return;
  DrawDashed(draw_list, p0, p1, kGivenHorizonColor, 2.0f);
  for (const Eigen::Vector2d& p : {a, b}) {
    const ImVec2 c(float(p.x()), float(p.y()));
    draw_list->AddCircle(c, 5.0f, kShadow, 0, 4.0f);
    draw_list->AddCircle(c, 5.0f, kGivenHorizonColor, 0, 2.0f);
  }
  // The label sits on the visible part of the line, a little in from its left end.
  const Eigen::Vector2d left = p0.x() <= p1.x() ? p0 : p1, right = p0.x() <= p1.x() ? p1 : p0;
  const Eigen::Vector2d at = left + (right - left) * std::min(1.0, 24.0 / std::max(1.0, (right - left).norm()));
  DrawShadowedText(draw_list, ImVec2(float(at.x()), float(at.y()) - 18.0f), kGivenHorizonColor, "horizon (given)");
}

// Segments the calibration flagged as outliers: a small grey cross at their midpoint, named
// only when the segment is selected or the pointer is near the cross, so that a photo with
// many detected lines is not covered in labels.
void DrawOutliers(ImDrawList* draw_list, const AppState& state, const Image& image, const ViewTransform& view) {
  const auto cal = state.last_update.calibration.find(image.id);
  if (cal == state.last_update.calibration.end() || cal->second.outlier_segments.empty()) return;
  std::vector<const Segment*> segments;  // the calibration's input order
  for (const Segment& s : state.document.project().segments)
    if (s.image_id == image.id) segments.push_back(&s);
  const std::vector<bool>& flags = cal->second.segment_is_outlier;
  if (flags.size() != segments.size()) return;  // the summary is of another edit
  std::optional<Eigen::Vector2d> pointer;
  if (state.pointer_image_id == image.id && state.pointer_in_image_px) {
    pointer = Screen(view, state.pointer_in_image_px->x(), state.pointer_in_image_px->y());
  }
  for (size_t i = 0; i < segments.size(); ++i) {
    if (!flags[i]) continue;
    const Eigen::Vector2d m = 0.5 * (segments[i]->a_px + segments[i]->b_px);
    const Eigen::Vector2d s = Screen(view, m.x(), m.y());
    const ImVec2 c(float(s.x()), float(s.y()));
    constexpr float r = 4.0f;
    for (const ImU32 color : {kShadow, kOutlierColor}) {
      const float w = color == kShadow ? 3.0f : 1.5f;
      draw_list->AddLine(ImVec2(c.x - r, c.y - r), ImVec2(c.x + r, c.y + r), color, w);
      draw_list->AddLine(ImVec2(c.x - r, c.y + r), ImVec2(c.x + r, c.y - r), color, w);
    }
    constexpr double kLabelReachPx = 24.0;
    const bool named =
        state.selection.segment_id == segments[i]->id || (pointer && (*pointer - s).norm() <= kLabelReachPx);
    if (named) DrawShadowedText(draw_list, ImVec2(c.x + 8.0f, c.y + 2.0f), kOutlierColor, "outlier");
  }
}

// Epipolar lines for teaching two-view geometry: for the selected vertices (or the selected
// pin's vertex), the line in this image of each pin of that vertex in another calibrated
// image (F from the two cameras, core/solve/multiview_init.h). The vertex's own pin here should lie
// on every such line; the distance is what the two-view solve minimises. On a distorted
// photo the true epipolar curve bends: the line is drawn in pinhole pixels.
void DrawEpipolarLines(ImDrawList* draw_list, const AppState& state, const Image& image, const ViewTransform& view) {
  if (!image.camera_calibrated) return;
  const Project& project = state.document.project();
  std::vector<VertexRef> vertices;
  for (const ElementRef& e : SelectedElements(state.selection))
    if (e.kind == ElementKind::kVertex) vertices.push_back({e.primitive_id, e.element});
  if (const Pin* pin = project.FindPin(state.selection.pin_id)) vertices.push_back(pin->vertex);
  if (vertices.empty()) return;
  constexpr ImU32 kEpipolarColor = IM_COL32(120, 230, 255, 230);
  for (const Image& other : project.images) {
    if (other.id == image.id || !other.camera_calibrated) continue;
    const Eigen::Matrix3d f = FundamentalFromCameras(other.camera, image.camera);
    for (const Pin& pin : project.pins) {
      if (pin.image_id != other.id) continue;
      if (std::find(vertices.begin(), vertices.end(), pin.vertex) == vertices.end()) continue;
      const EpipolarLine line = EpipolarLineInImage(f, pin.uv_px, image.width_px, image.height_px);
      if (!line.segment_px) continue;
      const Eigen::Vector2d a = Screen(view, line.segment_px->first.x(), line.segment_px->first.y());
      const Eigen::Vector2d b = Screen(view, line.segment_px->second.x(), line.segment_px->second.y());
      DrawDashed(draw_list, a, b, kEpipolarColor, 1.5f);
      const std::string label = "epipolar from " + other.path;
      DrawShadowedText(draw_list, ImVec2(float(a.x()) + 6.0f, float(a.y()) + 4.0f), kEpipolarColor, label.c_str());
    }
  }
}

}  // namespace

void DrawCalibrationOverlay(ImDrawList* draw_list, const AppState& state, const Image& image, const ViewTransform& view,
                            ImVec2 clip_min, ImVec2 clip_max, const Eigen::Vector2d* /*mouse_uv*/) {
  draw_list->PushClipRect(clip_min, clip_max, true);
  if (image.use_horizon) DrawGivenHorizon(draw_list, image, view, clip_min, clip_max);
  DrawOutliers(draw_list, state, image, view);
  if (!state.teach.epipolar) DrawEpipolarLines(draw_list, state, image, view);  // teach mode draws its own
  draw_list->PopClipRect();
}

}  // namespace facet::app
