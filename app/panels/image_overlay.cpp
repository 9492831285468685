#include "app/panels/image_overlay.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "core/mesh/triangulate.h"

namespace facet::app {
namespace {

// Screen margin (px) added around the clip rectangle before clipping lines, so that thick
// lines and handles at the border are not cut visibly short.
constexpr double kClipMarginPx = 8.0;

constexpr ImU32 kPinColor = IM_COL32(255, 70, 200, 255);
constexpr ImU32 kHighlightColor = IM_COL32(255, 255, 255, 255);
constexpr ImU32 kShadowColor = IM_COL32(0, 0, 0, 200);
constexpr ImU32 kHorizonColor = IM_COL32(255, 255, 255, 170);
constexpr ImU32 kSelectedElementColor = IM_COL32(255, 140, 30, 255);
constexpr ImU32 kSelectedFaceColor = IM_COL32(255, 140, 30, 70);
constexpr ImU32 kHoveredFaceColor = IM_COL32(255, 255, 255, 45);
constexpr ImU32 kFreeVertexColor = IM_COL32(80, 230, 255, 255);
constexpr ImU32 kLinePinColor = IM_COL32(0, 255, 200, 255);      // a line pin's photo line
constexpr ImU32 kLinePinLineColor = IM_COL32(0, 255, 200, 110);  // ... extended across the view
constexpr ImU32 kLinePinResidualColor = IM_COL32(255, 70, 200, 255);
constexpr ImU32 kFlaggedPinColor = IM_COL32(255, 50, 50, 255);  // a pin the solve flagged as a likely wrong click
constexpr ImU32 kGhostPinColor = IM_COL32(140, 255, 120, 255);  // a pin proposed from another photo

struct ScreenRect {
  Eigen::Vector2d min, max;
  bool Contains(const Eigen::Vector2d& p, double margin = 0.0) const {
    return p.x() >= min.x() - margin && p.y() >= min.y() - margin && p.x() <= max.x() + margin &&
           p.y() <= max.y() + margin;
  }
};

void DrawScreenLine(ImDrawList* draw_list, const Eigen::Vector2d& a, const Eigen::Vector2d& b, const ScreenRect& rect,
                    ImU32 color, float thickness_px) {
  DrawClippedScreenLine(draw_list, a, b, rect.min, rect.max, color, thickness_px);
}

void DrawDashedScreenLine(ImDrawList* draw_list, const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                          const ScreenRect& rect, ImU32 color, float thickness_px, double dash_px) {
  DrawClippedScreenLine(draw_list, a, b, rect.min, rect.max, color, thickness_px, dash_px);
}

// An infinite image line a*u + b*v + c = 0 drawn across the view.
void DrawInfiniteImageLine(ImDrawList* draw_list, const Eigen::Vector3d& line, const ViewTransform& view,
                           const ScreenRect& rect, ImU32 color, float thickness_px, bool dashed) {
  Eigen::Vector2d a, b;
  if (!ImageLineAcrossView(view, line, rect.min, rect.max, &a, &b)) return;
  DrawClippedScreenLine(draw_list, a, b, rect.min, rect.max, color, thickness_px, dashed ? 10.0 : 0.0);
}

// Marks a vanishing point: a target when it is in or near the view, else an arrow at the
// view's border pointing towards it (also for points at infinity, by their direction).
void DrawVanishingPoint(ImDrawList* draw_list, Axis axis, const Eigen::Vector3d& vp, const ViewTransform& view,
                        const ScreenRect& rect, bool show_labels) {
  const ImU32 color = AxisColor(axis);
  const std::string label = std::string("VP") + AxisName(axis);
  const Eigen::Vector2d center = 0.5 * (rect.min + rect.max);
  Eigen::Vector2d direction;
  const bool finite = std::abs(vp.z()) > 1e-12 * vp.head<2>().norm();
  if (finite) {
    const Eigen::Vector2d vp_screen = ImageToScreen(view, vp.head<2>() / vp.z());
    if (rect.Contains(vp_screen, 40.0)) {
      const ImVec2 p = ToImVec2(vp_screen);
      draw_list->AddCircle(p, 9.0f, kShadowColor, 0, 4.0f);
      draw_list->AddCircle(p, 9.0f, color, 0, 2.0f);
      draw_list->AddLine(ImVec2(p.x - 14, p.y), ImVec2(p.x + 14, p.y), color, 1.5f);
      draw_list->AddLine(ImVec2(p.x, p.y - 14), ImVec2(p.x, p.y + 14), color, 1.5f);
      if (show_labels) DrawShadowedText(draw_list, ImVec2(p.x + 11, p.y - 22), color, label.c_str());
      return;
    }
    direction = vp_screen - center;
  } else {
    direction = vp.head<2>();  // image and screen axes are parallel (positive zoom)
  }
  if (direction.norm() < 1e-12) return;
  direction.normalize();
  // Where the ray from the centre leaves the rectangle shrunk by the arrow's size.
  const Eigen::Vector2d half = 0.5 * (rect.max - rect.min) - Eigen::Vector2d(18.0, 18.0);
  if (half.x() <= 0.0 || half.y() <= 0.0) return;
  const double s = std::min(std::abs(direction.x()) > 1e-12 ? half.x() / std::abs(direction.x()) : 1e300,
                            std::abs(direction.y()) > 1e-12 ? half.y() / std::abs(direction.y()) : 1e300);
  const Eigen::Vector2d tip = center + s * direction;
  const Eigen::Vector2d normal(-direction.y(), direction.x());
  const Eigen::Vector2d base = tip - 12.0 * direction;
  draw_list->AddTriangleFilled(ToImVec2(tip), ToImVec2(base + 6.0 * normal), ToImVec2(base - 6.0 * normal), color);
  if (show_labels) {
    const Eigen::Vector2d text_pos = base - 14.0 * direction - Eigen::Vector2d(10.0, 7.0);
    DrawShadowedText(draw_list, ToImVec2(text_pos), color, label.c_str());
  }
}

// An edge of camera-frame points p-q, cut at the near depth, in screen px; false when it is
// wholly behind the camera.
bool ProjectEdge(const Camera& camera, const ViewTransform& view, Eigen::Vector3d p, Eigen::Vector3d q,
                 Eigen::Vector2d* a, Eigen::Vector2d* b) {
  if (p.z() < kNearDepth && q.z() < kNearDepth) return false;
  if (p.z() < kNearDepth) std::swap(p, q);
  if (q.z() < kNearDepth) q = p + (q - p) * ((p.z() - kNearDepth) / (p.z() - q.z()));
  auto project_px = [&](const Eigen::Vector3d& x) {
    return Eigen::Vector2d(camera.focal_px * x.x() / x.z() + camera.principal_point_px.x(),
                           camera.focal_px * x.y() / x.z() + camera.principal_point_px.y());
  };
  *a = ImageToScreen(view, project_px(p));
  *b = ImageToScreen(view, project_px(q));
  return true;
}

const ProjectedPrimitive* FindProjected(const OverlayInput& input, Id primitive_id) {
  if (input.model == nullptr) return nullptr;
  for (const ProjectedPrimitive& pp : *input.model) {
    if (pp.primitive_id == primitive_id) return &pp;
  }
  return nullptr;
}

// A face filled with a translucent colour: as one polygon when its projection is convex (no
// seams between triangles), else through its triangulation (faces may be concave).
void FillFace(ImDrawList* draw_list, const Primitive& primitive, const ProjectedPrimitive& pp, FaceId f,
              const ViewTransform& view, ImU32 color) {
  const PolyMesh& mesh = primitive.mesh;
  std::vector<ImVec2> polygon;
  for (VertexId v : FaceVertices(mesh, f)) {
    if (v >= pp.in_front.size() || !pp.in_front[v]) return;
    polygon.push_back(ToImVec2(ImageToScreen(view, pp.uv_px[v])));
  }
  int positive = 0, negative = 0;
  const size_t n = polygon.size();
  for (size_t i = 0; i < n; ++i) {
    const ImVec2 a = polygon[i], b = polygon[(i + 1) % n], c = polygon[(i + 2) % n];
    const float cross = (b.x - a.x) * (c.y - b.y) - (b.y - a.y) * (c.x - b.x);
    positive += cross > 0.0f;
    negative += cross < 0.0f;
  }
  if (positive == 0 || negative == 0) {
    draw_list->AddConvexPolyFilled(polygon.data(), static_cast<int>(n), color);
    return;
  }
  for (const CornerTriangle& tri : TriangulateFace(mesh, f)) {
    ImVec2 p[3];
    for (int i = 0; i < 3; ++i) {
      const VertexId v = mesh.Origin(tri[i]);
      p[i] = ToImVec2(ImageToScreen(view, pp.uv_px[v]));
    }
    draw_list->AddTriangleFilled(p[0], p[1], p[2], color);
  }
}

// The visible reference meshes' outlines, under the model.
void DrawReferences(ImDrawList* draw_list, const OverlayInput& input, const ViewTransform& view,
                    const ScreenRect& rect) {
  const Camera& camera = input.image->camera;
  for (const Reference& reference : input.project->references) {
    const auto loaded = input.references->find(reference.id);
    if (!reference.visible || loaded == input.references->end()) continue;
    const ReferenceMesh& mesh = loaded->second.mesh;
    for (const auto& e : mesh.edges) {
      Eigen::Vector2d a, b;
      if (!ProjectEdge(camera, view, camera.CamFromWorld(mesh.positions[e[0]]),
                       camera.CamFromWorld(mesh.positions[e[1]]), &a, &b))
        continue;
      DrawScreenLine(draw_list, a, b, rect, kReferenceEdgeColor, kReferenceEdgeThicknessPx);
    }
  }
}

// Every edge of every primitive in the model colour; the selected primitive with a light
// underlay; the selected and hovered faces filled, edges thickened.
void DrawModel(ImDrawList* draw_list, const OverlayInput& input, const ViewTransform& view, const ScreenRect& rect) {
  const Camera& camera = input.image->camera;
  const ElementRef& hover = input.hover.element;
  const std::vector<ElementRef> selected = SelectedElements(input.selection);
  for (const Primitive& primitive : input.project->primitives) {
    const PolyMesh& mesh = primitive.mesh;
    const ProjectedPrimitive* pp = FindProjected(input, primitive.id);
    if (pp != nullptr) {
      auto fill = [&](const ElementRef& ref, ImU32 color) {
        if (ref.kind != ElementKind::kFace || ref.primitive_id != primitive.id || !mesh.IsFace(ref.element)) return;
        FillFace(draw_list, primitive, *pp, ref.element, view, color);
      };
      for (const ElementRef& ref : selected) fill(ref, kSelectedFaceColor);
      fill(hover, kHoveredFaceColor);
      fill(input.other_hover, kHoveredFaceColor);
    }
    const bool primitive_selected = input.selection.primitive_id == primitive.id;
    for (EdgeId e = 0; e < mesh.EdgeIdEnd(); ++e) {
      if (!mesh.IsEdge(e)) continue;
      Eigen::Vector2d a, b;
      const Eigen::Vector3d p = camera.CamFromWorld(mesh.vertex(mesh.Origin(2 * e)).position);
      const Eigen::Vector3d q = camera.CamFromWorld(mesh.vertex(mesh.Dest(2 * e)).position);
      if (!ProjectEdge(camera, view, p, q, &a, &b)) continue;
      const ElementRef ref{ElementKind::kEdge, primitive.id, e};
      const bool is_selected = IsSelected(input.selection, ref);
      const bool is_hovered = hover == ref || input.other_hover == ref;
      if (is_selected) {
        DrawScreenLine(draw_list, a, b, rect, kSelectedElementColor, kModelEdgeThicknessPx + 4.0f);
      } else if (is_hovered) {
        DrawScreenLine(draw_list, a, b, rect, kHighlightColor, kModelEdgeThicknessPx + 4.0f);
      } else if (primitive_selected) {
        DrawScreenLine(draw_list, a, b, rect, IM_COL32(255, 255, 255, 160), kModelEdgeThicknessPx + 3.0f);
      }
      DrawScreenLine(draw_list, a, b, rect, kModelEdgeColor, kModelEdgeThicknessPx);
      // Where the split tool would cut the hovered edge.
      if (is_hovered && hover == ref && input.tool == Tool::kSplitEdge) {
        const Eigen::Vector3d at = (1.0 - input.hover.edge_t) * mesh.vertex(mesh.Origin(2 * e)).position +
                                   input.hover.edge_t * mesh.vertex(mesh.Dest(2 * e)).position;
        const Eigen::Vector3d at_in_cam = camera.CamFromWorld(at);
        if (at_in_cam.z() > kNearDepth) {
          const ImVec2 c = ToImVec2(ImageToScreen(view, camera.Project(at)));
          draw_list->AddCircleFilled(c, 5.0f, kShadowColor);
          draw_list->AddCircleFilled(c, 4.0f, kSelectedElementColor);
        }
      }
    }
  }
}

// Vertex dots; free vertices as rings; the selected, hovered and V_connect start marked.
void DrawModelVertices(ImDrawList* draw_list, const OverlayInput& input, const ViewTransform& view,
                       const ScreenRect& rect) {
  for (const ProjectedPrimitive& pp : *input.model) {
    const Primitive* primitive = input.project->FindPrimitive(pp.primitive_id);
    if (primitive == nullptr) continue;
    for (VertexId v = 0; v < pp.in_front.size(); ++v) {
      if (!pp.in_front[v] || !primitive->mesh.IsVertex(v)) continue;
      const Eigen::Vector2d p = ImageToScreen(view, pp.uv_px[v]);
      if (!rect.Contains(p, kClipMarginPx)) continue;
      const ElementRef ref{ElementKind::kVertex, pp.primitive_id, v};
      const bool hot = input.hover.element == ref || input.other_hover == ref;
      const bool chosen = IsSelected(input.selection, ref) || input.selection.connect_from == ref;
      const ImVec2 c = ToImVec2(p);
      draw_list->AddCircleFilled(c, 4.0f, kShadowColor);
      if (primitive->mesh.vertex(v).local.free) {
        draw_list->AddCircle(c, 4.5f, kFreeVertexColor, 0, 2.0f);
      } else {
        draw_list->AddCircleFilled(c, 3.0f, kModelEdgeColor);
      }
      if (chosen) draw_list->AddCircleFilled(c, 3.0f, kSelectedElementColor);
      if (hot || chosen)
        draw_list->AddCircle(c, chosen ? 9.0f : 7.0f, hot ? kHighlightColor : kSelectedElementColor, 0, 2.0f);
    }
  }
}

// How a line pin's line is drawn: highlighted when selected or hovered, with end handles
// (hot_end: the end under the cursor or being dragged, -1 none).
struct PinnedLineLook {
  bool handles = false;
  bool selected = false;
  bool hovered = false;
  int hot_end = -1;
};

// A diamond handle centred on p.
void DrawLinePinHandle(ImDrawList* draw_list, const Eigen::Vector2d& p, bool hot) {
  const float r = hot ? kLinePinHandleHotRadiusPx : kLinePinHandleRadiusPx;
  const ImVec2 c = ToImVec2(p);
  const ImVec2 q[4] = {{c.x, c.y - r}, {c.x + r, c.y}, {c.x, c.y + r}, {c.x - r, c.y}};
  const ImVec2 o[4] = {{c.x, c.y - r - 1.5f}, {c.x + r + 1.5f, c.y}, {c.x, c.y + r + 1.5f}, {c.x - r - 1.5f, c.y}};
  draw_list->AddConvexPolyFilled(o, 4, kShadowColor);
  draw_list->AddConvexPolyFilled(q, 4, hot ? kHighlightColor : kLinePinColor);
}

// A line pin's image line: the two points the user dragged, solid, the line through them
// dashed across the view.
void DrawPinnedLine(ImDrawList* draw_list, const ViewTransform& view, const Eigen::Vector2d& a_px,
                    const Eigen::Vector2d& b_px, const ScreenRect& rect, const PinnedLineLook& look = {}) {
  const Eigen::Vector3d line = Eigen::Vector3d(a_px.x(), a_px.y(), 1.0).cross(Eigen::Vector3d(b_px.x(), b_px.y(), 1.0));
  DrawInfiniteImageLine(draw_list, line, view, rect, kLinePinLineColor, 1.0f, true);
  const Eigen::Vector2d a = ImageToScreen(view, a_px), b = ImageToScreen(view, b_px);
  if (look.selected) {
    DrawScreenLine(draw_list, a, b, rect, kSelectedElementColor, 6.0f);
  } else if (look.hovered) {
    DrawScreenLine(draw_list, a, b, rect, IM_COL32(255, 255, 255, 160), 5.0f);
  } else {
    DrawScreenLine(draw_list, a, b, rect, kShadowColor, 4.0f);
  }
  DrawScreenLine(draw_list, a, b, rect, kLinePinColor, 2.0f);
  if (!look.handles) return;
  for (int end = 0; end < 2; ++end) {
    const Eigen::Vector2d& p = end == 0 ? a : b;
    if (rect.Contains(p, kClipMarginPx)) DrawLinePinHandle(draw_list, p, look.hot_end == end);
  }
}

// Every line pin (kEdgeOnImageLine) of this image: its line, and from each projected end of
// its edge the perpendicular to the line (the residual), with the larger distance in pixels.
void DrawLinePins(ImDrawList* draw_list, const OverlayInput& input, const ViewTransform& view, const ScreenRect& rect,
                  bool show_labels) {
  const Image& image = *input.image;
  for (const Constraint& c : input.project->constraints) {
    if (c.kind != ConstraintKind::kEdgeOnImageLine || c.image_id != image.id || c.vertices.size() != 2) continue;
    const Eigen::Vector2d d = c.line_b_px - c.line_a_px;
    if (d.norm() <= 0.0) continue;
    PinnedLineLook look;
    look.handles = true;
    look.selected = input.selected_line_pin == c.id;
    look.hovered = input.hover.line_pin_id == c.id;
    look.hot_end = look.hovered ? input.hover.line_pin_endpoint : -1;
    // The residuals (edge ends to their feet on the line) go under the line and its handles.
    std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> residuals;
    if (!image.camera_calibrated) {
      DrawPinnedLine(draw_list, view, c.line_a_px, c.line_b_px, rect, look);
      continue;
    }
    const Eigen::Vector2d n = Eigen::Vector2d(-d.y(), d.x()).normalized();
    double worst_px = 0.0;
    Eigen::Vector2d label_at = ImageToScreen(view, 0.5 * (c.line_a_px + c.line_b_px));
    for (const VertexRef& v : c.vertices) {
      if (input.project->FindVertex(v) == nullptr) continue;
      const Eigen::Vector3d p = VertexInWorld(*input.project, v);
      if (image.camera.CamFromWorld(p).z() <= kNearDepth) continue;
      const Eigen::Vector2d uv = image.camera.Project(p);
      const double dist = (uv - c.line_a_px).dot(n);
      const Eigen::Vector2d foot = uv - dist * n;
      residuals.emplace_back(ImageToScreen(view, uv), ImageToScreen(view, foot));
      if (std::abs(dist) >= worst_px) {
        worst_px = std::abs(dist);
        label_at = ImageToScreen(view, foot);
      }
    }
    for (const auto& [from, to] : residuals) DrawScreenLine(draw_list, from, to, rect, kLinePinResidualColor, 1.5f);
    DrawPinnedLine(draw_list, view, c.line_a_px, c.line_b_px, rect, look);
    if (show_labels && rect.Contains(label_at)) {
      char text[32];
      std::snprintf(text, sizeof(text), "%.2f px", worst_px);
      DrawShadowedText(draw_list, ImVec2(static_cast<float>(label_at.x()) + 6, static_cast<float>(label_at.y()) + 4),
                       kLinePinColor, text);
    }
  }
}

}  // namespace

void DrawLinePinPreview(ImDrawList* draw_list, const OverlayInput& input, const ViewTransform& view,
                        const Eigen::Vector2d& a_px, const Eigen::Vector2d& b_px, ImVec2 clip_min, ImVec2 clip_max) {
  const ScreenRect rect{{clip_min.x, clip_min.y}, {clip_max.x, clip_max.y}};
  draw_list->PushClipRect(clip_min, clip_max, true);
  DrawPinnedLine(draw_list, view, a_px, b_px, rect);
  // The selected edge's projected ends and how far they are from the line being drawn.
  const ElementRef& edge = input.selection.element;
  const Primitive* primitive = input.project ? input.project->FindPrimitive(edge.primitive_id) : nullptr;
  const Eigen::Vector2d d = b_px - a_px;
  if (edge.kind == ElementKind::kEdge && primitive != nullptr && primitive->mesh.IsEdge(edge.element) &&
      input.image != nullptr && input.image->camera_calibrated && d.norm() > 0.0) {
    const Eigen::Vector2d n = Eigen::Vector2d(-d.y(), d.x()).normalized();
    const PolyMesh& mesh = primitive->mesh;
    for (VertexId v : {mesh.Origin(2 * edge.element), mesh.Dest(2 * edge.element)}) {
      const Eigen::Vector3d p = mesh.vertex(v).position;
      if (input.image->camera.CamFromWorld(p).z() <= kNearDepth) continue;
      const Eigen::Vector2d uv = input.image->camera.Project(p);
      const Eigen::Vector2d foot = uv - (uv - a_px).dot(n) * n;
      DrawDashedScreenLine(draw_list, ImageToScreen(view, uv), ImageToScreen(view, foot), rect, kLinePinResidualColor,
                           1.5f, 4.0);
    }
  }
  draw_list->PopClipRect();
}

ImU32 AxisColor(Axis axis, int alpha) {
  switch (axis) {
    case Axis::kX: return IM_COL32(255, 60, 60, alpha);
    case Axis::kY: return IM_COL32(60, 230, 60, alpha);
    case Axis::kZ: return IM_COL32(70, 140, 255, alpha);
  }
  return IM_COL32(255, 255, 255, alpha);
}

Eigen::Vector2d ImageToScreen(const ViewTransform& view, const Eigen::Vector2d& uv_px) {
  return {view.origin.x + static_cast<double>(view.zoom) * uv_px.x(),
          view.origin.y + static_cast<double>(view.zoom) * uv_px.y()};
}

ImVec2 ToImVec2(const Eigen::Vector2d& p) { return ImVec2(static_cast<float>(p.x()), static_cast<float>(p.y())); }

bool ImageLineAcrossView(const ViewTransform& view, const Eigen::Vector3d& line, const Eigen::Vector2d& rect_min,
                         const Eigen::Vector2d& rect_max, Eigen::Vector2d* a, Eigen::Vector2d* b) {
  const double n2 = line.x() * line.x() + line.y() * line.y();
  if (!(n2 >= 1e-300)) return false;  // the line at infinity
  double cu, cv;
  view.ToImage(ToImVec2(0.5 * (rect_min + rect_max)), &cu, &cv);
  const Eigen::Vector2d center(cu, cv);
  const double offset = (line.x() * cu + line.y() * cv + line.z()) / n2;
  const Eigen::Vector2d foot = center - offset * Eigen::Vector2d(line.x(), line.y());
  const Eigen::Vector2d dir = Eigen::Vector2d(-line.y(), line.x()) / std::sqrt(n2);
  // Twice the view's diagonal from its centre's foot: past the view on both sides.
  const double reach_px = 2.0 * (rect_max - rect_min).norm() / view.zoom + 1.0;
  *a = ImageToScreen(view, foot - reach_px * dir);
  *b = ImageToScreen(view, foot + reach_px * dir);
  return true;
}

void DrawClippedScreenLine(ImDrawList* draw_list, Eigen::Vector2d a, Eigen::Vector2d b, const Eigen::Vector2d& rect_min,
                           const Eigen::Vector2d& rect_max, ImU32 color, float thickness_px, double dash_px,
                           ImU32 shadow) {
  const Eigen::Vector2d margin(kClipMarginPx, kClipMarginPx);
  if (!ClipSegmentToRect(&a, &b, rect_min - margin, rect_max + margin)) return;
  const double length = (b - a).norm();
  if (!(length > 0.0)) return;
  const Eigen::Vector2d dir = (b - a) / length;
  const double dash = dash_px > 0.0 ? dash_px : length;
  for (double s = 0.0; s < length; s += 2.0 * dash) {
    const ImVec2 p = ToImVec2(a + s * dir), q = ToImVec2(a + std::min(length, s + dash) * dir);
    if (shadow != 0) draw_list->AddLine(p, q, shadow, thickness_px + 2.0f);
    draw_list->AddLine(p, q, color, thickness_px);
  }
}

bool ClipSegmentToRect(Eigen::Vector2d* a, Eigen::Vector2d* b, const Eigen::Vector2d& rect_min,
                       const Eigen::Vector2d& rect_max) {
  // Liang-Barsky: the part of a + t (b - a), t in [0, 1], inside all four half-planes.
  const Eigen::Vector2d d = *b - *a;
  double t0 = 0.0, t1 = 1.0;
  const double p[4] = {-d.x(), d.x(), -d.y(), d.y()};
  const double q[4] = {a->x() - rect_min.x(), rect_max.x() - a->x(), a->y() - rect_min.y(), rect_max.y() - a->y()};
  for (int i = 0; i < 4; ++i) {
    if (p[i] == 0.0) {
      if (q[i] < 0.0) return false;
      continue;
    }
    const double t = q[i] / p[i];
    if (p[i] < 0.0) {
      if (t > t1) return false;
      t0 = std::max(t0, t);
    } else {
      if (t < t0) return false;
      t1 = std::min(t1, t);
    }
  }
  const Eigen::Vector2d start = *a;
  *a = start + t0 * d;
  *b = start + t1 * d;
  return true;
}

void DrawShadowedText(ImDrawList* draw_list, ImVec2 pos, ImU32 color, const char* text) {
  draw_list->AddText(ImVec2(pos.x + 1, pos.y + 1), kShadowColor, text);
  draw_list->AddText(pos, color, text);
}

void DrawImageLine(ImDrawList* draw_list, const ViewTransform& view, const Eigen::Vector2d& a_px,
                   const Eigen::Vector2d& b_px, ImVec2 clip_min, ImVec2 clip_max, ImU32 color, float thickness_px) {
  const ScreenRect rect{{clip_min.x, clip_min.y}, {clip_max.x, clip_max.y}};
  DrawScreenLine(draw_list, ImageToScreen(view, a_px), ImageToScreen(view, b_px), rect, color, thickness_px);
}

void DrawImageOverlays(ImDrawList* draw_list, const OverlayInput& input, const ViewTransform& view, ImVec2 clip_min,
                       ImVec2 clip_max, const OverlayOptions& options) {
  if (input.project == nullptr || input.image == nullptr) return;
  const Project& project = *input.project;
  const Image& image = *input.image;
  const ScreenRect rect{{clip_min.x, clip_min.y}, {clip_max.x, clip_max.y}};
  draw_list->PushClipRect(clip_min, clip_max, true);

  const VpCalibrationSummary* calibration = input.calibration;
  auto vanishing_point = [&](Axis axis) -> const Eigen::Vector3d* {
    if (calibration == nullptr) return nullptr;
    const Eigen::Vector3d& vp = calibration->vanishing_points[static_cast<int>(axis)];
    return vp.squaredNorm() > 0.0 ? &vp : nullptr;
  };

  // Horizon and the faint segment-to-VP lines sit under everything else.
  if (options.show_vanishing_points) {
    const Eigen::Vector3d* vx = vanishing_point(Axis::kX);
    const Eigen::Vector3d* vy = vanishing_point(Axis::kY);
    if (vx != nullptr && vy != nullptr) {
      DrawInfiniteImageLine(draw_list, vx->cross(*vy), view, rect, kHorizonColor, 1.5f, true);
    }
  }
  if (options.show_segments && options.show_vp_lines) {
    for (const Segment& segment : project.segments) {
      if (segment.image_id != image.id) continue;
      const Eigen::Vector3d* vp = vanishing_point(segment.axis);
      if (vp == nullptr) continue;
      const Eigen::Vector2d mid = 0.5 * (segment.a_px + segment.b_px);
      const ImU32 color = AxisColor(segment.axis, 90);
      if (std::abs(vp->z()) > 1e-12 * vp->head<2>().norm()) {
        DrawImageLine(draw_list, view, mid, vp->head<2>() / vp->z(), clip_min, clip_max, color, 1.0f);
      } else {
        // A point at infinity: the line through the midpoint along its direction.
        const Eigen::Vector3d line = Eigen::Vector3d(mid.x(), mid.y(), 1.0).cross(*vp);
        DrawInfiniteImageLine(draw_list, line, view, rect, color, 1.0f, false);
      }
    }
  }

  // The projected model: edges cut at the near depth so that nothing behind the camera
  // projects through the centre.
  if (options.show_model && image.camera_calibrated && input.references != nullptr)
    DrawReferences(draw_list, input, view, rect);
  if (options.show_model && image.camera_calibrated) DrawModel(draw_list, input, view, rect);

  if (options.show_segments) {
    for (const Segment& segment : project.segments) {
      if (segment.image_id != image.id) continue;
      const bool selected = input.selection.segment_id == segment.id;
      const bool hovered = input.hover.segment_id == segment.id;
      const Eigen::Vector2d a = ImageToScreen(view, segment.a_px);
      const Eigen::Vector2d b = ImageToScreen(view, segment.b_px);
      const ImU32 color = AxisColor(segment.axis);
      if (selected || hovered) {
        DrawScreenLine(draw_list, a, b, rect, selected ? kHighlightColor : IM_COL32(255, 255, 255, 140),
                       selected ? 5.0f : 4.0f);
      } else {
        DrawScreenLine(draw_list, a, b, rect, kShadowColor, 3.5f);
      }
      DrawScreenLine(draw_list, a, b, rect, color, 2.0f);
      for (int end = 0; end < 2; ++end) {
        const Eigen::Vector2d& p = end == 0 ? a : b;
        if (!rect.Contains(p, kClipMarginPx)) continue;
        const bool hot =
            (hovered && input.hover.segment_endpoint == end) || (selected && input.selection.segment_endpoint == end);
        const float r = hot ? 5.0f : 3.0f;
        const ImVec2 c = ToImVec2(p);
        draw_list->AddRectFilled(ImVec2(c.x - r - 1, c.y - r - 1), ImVec2(c.x + r + 1, c.y + r + 1), kShadowColor);
        draw_list->AddRectFilled(ImVec2(c.x - r, c.y - r), ImVec2(c.x + r, c.y + r), hot ? kHighlightColor : color);
      }
    }
  }

  if (options.show_model && input.model != nullptr) DrawModelVertices(draw_list, input, view, rect);
  if (options.show_model) DrawLinePins(draw_list, input, view, rect, options.show_labels);

  if (options.show_pins) {
    int number = 0;
    for (const Pin& pin : project.pins) {
      if (pin.image_id != image.id) continue;
      ++number;
      const Eigen::Vector2d p = ImageToScreen(view, pin.uv_px);
      // The residual: from where the user pinned the corner to where the model puts it.
      if (input.model != nullptr) {
        for (const ProjectedPrimitive& pp : *input.model) {
          const VertexId v = pin.vertex.vertex;
          if (pp.primitive_id != pin.vertex.primitive_id || v >= pp.in_front.size() || !pp.in_front[v]) continue;
          DrawScreenLine(draw_list, p, ImageToScreen(view, pp.uv_px[v]), rect, kPinColor, 1.5f);
        }
      }
      if (!rect.Contains(p, 20.0)) continue;
      const bool hot = input.hover.pin_id == pin.id || input.selection.pin_id == pin.id;
      const ImVec2 c = ToImVec2(p);
      draw_list->AddCircle(c, 6.0f, kShadowColor, 0, 4.0f);
      draw_list->AddCircle(c, 6.0f, hot ? kHighlightColor : kPinColor, 0, 2.0f);
      draw_list->AddCircleFilled(c, 1.5f, kPinColor);
      if (options.show_labels) {
        char text[16];
        std::snprintf(text, sizeof(text), "%d", number);
        DrawShadowedText(draw_list, ImVec2(c.x + 7, c.y - 18), hot ? kHighlightColor : kPinColor, text);
      }
      // A likely wrong click: a red ring around the pin and how far the model puts its vertex,
      // so that it stands out among the others before the user reads the log.
      if (input.flagged_pins != nullptr) {
        for (const FlaggedPin& flagged : *input.flagged_pins) {
          if (flagged.pin_id != pin.id) continue;
          draw_list->AddCircle(c, 11.0f, kShadowColor, 0, 4.5f);
          draw_list->AddCircle(c, 11.0f, kFlaggedPinColor, 0, 2.5f);
          char text[32];
          std::snprintf(text, sizeof(text), "%.0f px off?", flagged.error_px);
          DrawShadowedText(draw_list, ImVec2(c.x + 13, c.y + 2), kFlaggedPinColor, text);
        }
      }
    }
  }

  if (options.show_pins && input.ghost_pins != nullptr) {
    // Ghost pins: a dashed ring, hollow, with the match's score.
    for (const PinProposal& proposal : input.ghost_pins->proposals) {
      if (!proposal.Proposed()) continue;
      const Eigen::Vector2d p = ImageToScreen(view, proposal.match.uv_px);
      if (!rect.Contains(p, 20.0)) continue;
      const ImVec2 c = ToImVec2(p);
      draw_list->AddCircle(c, kGhostPinRadiusPx, kShadowColor, 0, 3.5f);
      constexpr int kDashes = 8;
      for (int k = 0; k < kDashes; ++k) {
        const float a0 = 2.0f * 3.14159265f * k / kDashes, a1 = a0 + 3.14159265f / kDashes;
        draw_list->PathArcTo(c, kGhostPinRadiusPx, a0, a1, 4);
        draw_list->PathStroke(kGhostPinColor, 0, 2.0f);
      }
      draw_list->AddLine(ImVec2(c.x - 2, c.y), ImVec2(c.x + 2, c.y), kGhostPinColor, 1.0f);
      draw_list->AddLine(ImVec2(c.x, c.y - 2), ImVec2(c.x, c.y + 2), kGhostPinColor, 1.0f);
      if (options.show_labels) {
        char text[16];
        std::snprintf(text, sizeof(text), "%.2f", proposal.match.score);
        DrawShadowedText(draw_list, ImVec2(c.x + 9, c.y + 2), kGhostPinColor, text);
      }
    }
  }

  if (options.show_vanishing_points) {
    for (Axis axis : {Axis::kX, Axis::kY, Axis::kZ}) {
      if (const Eigen::Vector3d* vp = vanishing_point(axis)) {
        DrawVanishingPoint(draw_list, axis, *vp, view, rect, options.show_labels);
      }
    }
  }
  draw_list->PopClipRect();
}

}  // namespace facet::app
