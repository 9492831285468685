#include "app/panels/image_panel.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <imgui.h>
#include <imgui_internal.h>  // SetItemUsingMouseWheel: the view, not the window, takes the wheel

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include "app/panels/calibration_overlay.h"
#include "app/panels/image_overlay.h"
#include "app/panels/image_snapping.h"
#include "app/panels/image_view.h"
#include "app/panels/line_proposals_view.h"
#include "app/panels/teach_overlay.h"
#include "app/panels/widgets.h"
#include "app/platform/image_tiles.h"
#include "app/state/ghost_pins.h"
#include "app/state/line_proposals.h"
#include "app/state/model_edits.h"
#include "app/state/model_pick.h"
#include "app/state/teach.h"

namespace facet::app {
namespace {

constexpr float kWheelZoomStep = 1.2f;
constexpr double kPickRadiusPx = 6.0;
constexpr double kCornerPickRadiusPx = 8.0;
constexpr double kMinSegmentLengthPx = 3.0;  // shorter new segments are accidental clicks
constexpr double kDragStartPx = 2.0;         // motion before a press becomes a drag
constexpr int kImagePanelHover = 1;          // AppState::hover_panel
// Lines of the vanishing overlay's text box the view leaves room for under the photo.
constexpr int kVanishingTextLines = 9;

// GL textures of one photo, and which pixels they were made from.
struct CachedPhoto {
  const std::uint8_t* pixels = nullptr;
  int width = 0, height = 0;
  TiledTexture texture;
};

enum class DragKind {
  kNone,
  kPan,
  kNewSegment,
  kMoveEndpoint,
  kMoveSegment,
  kMovePin,
  kPlacePin,
  kLinePin,
  kMoveLinePinEnd,  // an existing line pin's end handle (target_id, endpoint)
};

struct Interaction {
  DragKind kind = DragKind::kNone;
  int button = 0;
  Id image_id = kNoId;
  bool began = false;           // BeginDrag was called (edit drags) / motion passed the threshold
  bool place_on_click = false;  // kPlacePin: a release without motion pins the vertex there
  Id target_id = kNoId;         // segment or pin
  int endpoint = -1;
  VertexRef vertex;          // kPlacePin: the vertex being pinned
  ElementRef press_element;  // kLinePin: the element under the press (a click selects it)
  double press_edge_t = 0.5;
  Id press_line_pin = kNoId;  // kLinePin: the line pin under the press (a click selects it too)
  // Shift+press on a pin (select tool): a click toggles the pinned vertex in the
  // multi-selection, a drag moves the pin (fine pointing) and leaves the selection alone.
  ElementRef toggle_on_click;
  Axis axis = Axis::kX;
  ImVec2 press_screen{0, 0};
  Eigen::Vector2d press_uv = Eigen::Vector2d::Zero();
  Eigen::Vector2d grab_offset = Eigen::Vector2d::Zero();  // item position minus press position
  Eigen::Vector2d original_a = Eigen::Vector2d::Zero(), original_b = Eigen::Vector2d::Zero();
  Eigen::Vector2d last_uv = Eigen::Vector2d::Constant(1e300);
  int ghost_index = -1;  // the ghost pin pressed on (GhostUnderPress): a click accepts it
};

}  // namespace

struct ImagePanelState::Impl {
  std::map<Id, ImageViewState> views;
  std::map<Id, CachedPhoto> textures;
  Interaction interaction;
  OverlayOptions overlay;
  float loupe_magnification = 4.0f;
  Id shown_tab = kNoId;
  Id context_segment = kNoId;
  bool fit_requested = false;
  std::uint64_t document_generation = 0;  // AppState's, when the views were last started afresh
  Id vanishing_view_image = kNoId;        // the image ShowVanishingConstruction last framed
  ImageViewReport report;
  // Fine pointing, Shift held during a press: ImGui reports whole screen pixels, so the
  // pointer then moves at 1 / magnification of the mouse's speed, continuing from where it
  // was, and the loupe shows it. That gives sub-screen-pixel placement at any zoom.
  bool fine_active = false;
  ImVec2 fine_anchor_screen{0, 0};
  Eigen::Vector2d fine_anchor_uv = Eigen::Vector2d::Zero();
  ImVec2 last_mouse_screen{0, 0};
  Eigen::Vector2d last_pointer_uv = Eigen::Vector2d::Zero();
  PhotoFeatures photo_features;
  SnapResult snap;  // this frame's, drawn before the click; kNone when nothing snapped
  // File > Export view: the view of another panel to show, scaled to this panel's canvas
  // (RequestImageViewLike); applied every frame while set.
  std::optional<ImageViewReport> like_view;
};

ImagePanelState::ImagePanelState() = default;
ImagePanelState::~ImagePanelState() = default;

namespace {

using PanelState = ImagePanelState::Impl;

PanelState& Panel(ImagePanelState* owner) {
  if (!owner->impl) owner->impl = std::make_unique<PanelState>();
  return *owner->impl;
}

Eigen::Vector2d ToEigen(ImVec2 p) { return {p.x, p.y}; }

std::string FileName(const std::string& path) {
  const size_t slash = path.find_last_of("/\\");
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

Eigen::Vector2d MouseUv(const ImageViewState& view) {
  double u, v;
  TransformOf(view).ToImage(ImGui::GetIO().MousePos, &u, &v);
  return {u, v};
}

const TiledTexture* TextureFor(PanelState* panel, const AppState& state, Id image_id) {
  auto photo = state.photos.find(image_id);
  if (photo == state.photos.end() || photo->second.empty()) return nullptr;
  CachedPhoto& cached = panel->textures[image_id];
  const ImageRgba8& image = photo->second;
  if (cached.pixels != image.pixels.data() || cached.width != image.width || cached.height != image.height) {
    DestroyTiledTexture(&cached.texture);
    cached.texture = CreateTiledTexture(image);
    cached.pixels = image.pixels.data();
    cached.width = image.width;
    cached.height = image.height;
  }
  return &cached.texture;
}

// Drops textures and views of images that left the project or whose photo went away.
void CollectGarbage(PanelState* panel, const AppState& state) {
  const Project& project = state.document.project();
  for (auto it = panel->textures.begin(); it != panel->textures.end();) {
    auto photo = state.photos.find(it->first);
    const bool keep = project.FindImage(it->first) != nullptr && photo != state.photos.end() &&
                      photo->second.pixels.data() == it->second.pixels;
    if (keep) {
      ++it;
    } else {
      DestroyTiledTexture(&it->second.texture);
      it = panel->textures.erase(it);
    }
  }
  for (auto it = panel->views.begin(); it != panel->views.end();) {
    it = project.FindImage(it->first) ? std::next(it) : panel->views.erase(it);
  }
  panel->photo_features.CollectGarbage(state);
}

const VpCalibrationSummary* CalibrationFor(const AppState& state, Id image_id) {
  auto it = state.last_update.calibration.find(image_id);
  return it == state.last_update.calibration.end() ? nullptr : &it->second;
}

// The selected line pin, or kNoId when the selection moved on (another element, a multi-
// selection, a segment or pin) or the constraint is gone (a delete, an undo).
Id SelectedLinePin(AppState* state) {
  Selection& selection = state->selection;
  const Constraint* c = state->document.project().FindConstraint(selection.line_pin_id);
  const bool holds = c != nullptr && c->kind == ConstraintKind::kEdgeOnImageLine &&
                     selection.element == selection.line_pin_edge && selection.extra.empty() &&
                     selection.segment_id == kNoId && selection.pin_id == kNoId;
  if (!holds) {
    selection.line_pin_id = kNoId;
    selection.line_pin_edge = {};
  }
  return selection.line_pin_id;
}

// Selects a line pin and its edge (when the edge still exists).
void SelectLinePin(AppState* state, Id constraint_id) {
  const Project& project = state->document.project();
  const Constraint* c = project.FindConstraint(constraint_id);
  if (c == nullptr) return;
  const ElementRef edge = LinePinEdge(project, *c);
  state->selection = edge.Empty() ? Selection() : Selection::Of(edge);
  state->selection.line_pin_id = constraint_id;
  state->selection.line_pin_edge = edge;
}

// The residual of a segment from the last calibration, when that calibration still matches
// the image's segments (the summary lists them in project order).
bool SegmentResidual(const AppState& state, const Segment& segment, double* residual_px) {
  const VpCalibrationSummary* calibration = CalibrationFor(state, segment.image_id);
  if (calibration == nullptr) return false;
  size_t index = 0, count = 0, found = SIZE_MAX;
  for (const Segment& s : state.document.project().segments) {
    if (s.image_id != segment.image_id) continue;
    if (s.id == segment.id) found = index;
    ++index;
    ++count;
  }
  if (found == SIZE_MAX || calibration->segment_residuals_px.size() != count) return false;
  *residual_px = calibration->segment_residuals_px[found];
  return true;
}

// The nearest pickable item under the cursor within the pick radius: pins, then segment
// endpoints, then the model's vertices, edges and faces (app/state/model_pick.h), then segments.
// `multi_select` (the select tool with Shift held: a click adds to the multi-selection of
// model elements): a model vertex or edge under the cursor wins over segments, whose ends
// snapping puts on the model's corners; with no model element there, segments are picked as
// usual (Shift's loupe for a fine drag of a segment's end).
OverlayHover HitTest(const Project& project, const Image& image, const std::vector<ProjectedPrimitive>& model,
                     const ViewTransform& view, ImVec2 mouse, Tool tool, bool multi_select) {
  OverlayHover hover;
  const Eigen::Vector2d m = ToEigen(mouse);
  auto screen = [&](const Eigen::Vector2d& uv) { return ToEigen(view.ToScreen(uv.x(), uv.y())); };
  const bool pick_pins = tool == Tool::kSelect || tool == Tool::kPin;
  const bool pick_lines = tool == Tool::kSelect;
  const bool pick_line_pins = tool == Tool::kSelect || tool == Tool::kLinePin;
  double best = kPickRadiusPx;
  for (const Pin& pin : project.pins) {
    if (pin.image_id != image.id || !pick_pins) continue;
    // Pins win ties with the vertex they pin: subtract a small bias.
    const double d = (screen(pin.uv_px) - m).norm() - 0.5;
    if (d < best) {
      best = d;
      hover = OverlayHover();
      hover.pin_id = pin.id;
    }
  }
  // Line pins' end handles: the nearest one within the radius, like the pins.
  for (const Constraint& c : project.constraints) {
    if (!pick_line_pins || c.kind != ConstraintKind::kEdgeOnImageLine || c.image_id != image.id) continue;
    for (int end = 0; end < 2; ++end) {
      const double d = (screen(end == 0 ? c.line_a_px : c.line_b_px) - m).norm();
      if (d < best) {
        best = d;
        hover = OverlayHover();
        hover.line_pin_id = c.id;
        hover.line_pin_endpoint = end;
      }
    }
  }
  if (hover.line_pin_id != kNoId) return hover;
  const PickFilter filter = PickFilterOf(tool);
  const ElementPick pick = PickInImage(project, model, image.camera, view.zoom, ToEigen(view.ToScreen(0.0, 0.0)), m,
                                       filter, kCornerPickRadiusPx);
  if (multi_select && hover.pin_id == kNoId && !pick.element.Empty() && pick.element.kind != ElementKind::kFace) {
    hover.element = pick.element;
    hover.edge_t = pick.t;
    return hover;
  }
  if (pick_lines) {
    for (const Segment& segment : project.segments) {
      if (segment.image_id != image.id) continue;
      for (int end = 0; end < 2; ++end) {
        const double d = (screen(end == 0 ? segment.a_px : segment.b_px) - m).norm();
        if (d < best) {
          best = d;
          hover = OverlayHover();
          hover.segment_id = segment.id;
          hover.segment_endpoint = end;
        }
      }
    }
  }
  if (hover.pin_id != kNoId || hover.segment_id != kNoId) return hover;
  // A line pin's drawn line (between its two points) beats the model's edges and faces: the
  // solve puts its edge right under it. A vertex, or another edge nearer the cursor, wins.
  if (pick_line_pins && pick.element.kind != ElementKind::kVertex) {
    double best_line = kPickRadiusPx;
    OverlayHover line_hover;
    for (const Constraint& c : project.constraints) {
      if (c.kind != ConstraintKind::kEdgeOnImageLine || c.image_id != image.id) continue;
      const double d = DistanceToSegment(m, screen(c.line_a_px), screen(c.line_b_px));
      if (d >= best_line) continue;
      const ElementRef edge = LinePinEdge(project, c);
      if (pick.element.kind == ElementKind::kEdge && pick.element != edge && pick.distance_px < d) continue;
      best_line = d;
      line_hover = OverlayHover();
      line_hover.line_pin_id = c.id;
      line_hover.element = edge;
    }
    if (line_hover.line_pin_id != kNoId) return line_hover;
  }
  // Segments win over the model's faces (a line drawn on a face stays pickable).
  if (!pick.element.Empty() && pick.element.kind != ElementKind::kFace) {
    hover.element = pick.element;
    hover.edge_t = pick.t;
    return hover;
  }
  if (pick_lines) {
    double best_line = kPickRadiusPx;
    for (const Segment& segment : project.segments) {
      if (segment.image_id != image.id) continue;
      const double d = DistanceToSegment(m, screen(segment.a_px), screen(segment.b_px));
      if (d < best_line) {
        best_line = d;
        hover = OverlayHover();
        hover.segment_id = segment.id;
      }
    }
  }
  if (hover.segment_id == kNoId) hover.element = pick.element;
  return hover;
}

std::string DescribeHover(const AppState& state, const OverlayHover& hover) {
  const Project& project = state.document.project();
  char text[160];
  if (const Segment* segment = hover.segment_id != kNoId ? project.FindSegment(hover.segment_id) : nullptr) {
    double residual_px = 0.0;
    const bool has_residual = SegmentResidual(state, *segment, &residual_px);
    const char* part = hover.segment_endpoint == 0 ? " end a" : hover.segment_endpoint == 1 ? " end b" : "";
    if (has_residual) {
      std::snprintf(text, sizeof(text), "%s line %llu%s, residual %.2f px", AxisName(segment->axis),
                    static_cast<unsigned long long>(segment->id), part, residual_px);
    } else {
      std::snprintf(text, sizeof(text), "%s line %llu%s", AxisName(segment->axis),
                    static_cast<unsigned long long>(segment->id), part);
    }
    return text;
  }
  if (const Pin* pin = hover.pin_id != kNoId ? project.FindPin(hover.pin_id) : nullptr) {
    const std::string vertex =
        DescribeElement(project, {ElementKind::kVertex, pin->vertex.primitive_id, pin->vertex.vertex});
    std::snprintf(text, sizeof(text), "pin %llu: %s at (%.1f, %.1f)", static_cast<unsigned long long>(pin->id),
                  vertex.c_str(), pin->uv_px.x(), pin->uv_px.y());
    return text;
  }
  if (const Constraint* c = hover.line_pin_id != kNoId ? project.FindConstraint(hover.line_pin_id) : nullptr) {
    const ElementRef edge = LinePinEdge(project, *c);
    const std::string what = edge.Empty() ? std::string("a deleted edge") : DescribeElement(project, edge);
    const char* part = hover.line_pin_endpoint == 0   ? ", end a (drag to move)"
                       : hover.line_pin_endpoint == 1 ? ", end b (drag to move)"
                                                      : "";
    std::snprintf(text, sizeof(text), "line pin %llu of %s%s", static_cast<unsigned long long>(c->id), what.c_str(),
                  part);
    return text;
  }
  if (!hover.element.Empty()) {
    std::string description = DescribeElement(project, hover.element);
    if (hover.element.kind == ElementKind::kVertex) {
      const Primitive* primitive = project.FindPrimitive(hover.element.primitive_id);
      if (primitive && primitive->mesh.IsVertex(hover.element.element) &&
          primitive->mesh.vertex(hover.element.element).local.free) {
        description += " (free)";
      }
    }
    return description;
  }
  return "";
}

void DeleteSelection(AppState* state, PanelState* panel) {
  if (const Id line_pin = SelectedLinePin(state); line_pin != kNoId) {
    // The line pin, not its edge (which the selection holds with it).
    state->selection = Selection();
    RemoveConstraintEdit(state, line_pin);
    return;
  }
  Project edited = state->document.project();
  const Selection& selection = state->selection;
  if (selection.segment_id != kNoId && edited.FindSegment(selection.segment_id)) {
    std::erase_if(edited.segments, [&](const Segment& s) { return s.id == selection.segment_id; });
    state->selection = Selection();
    CommitEdit(state, "Delete line", std::move(edited));
  } else if (selection.pin_id != kNoId && edited.FindPin(selection.pin_id)) {
    std::erase_if(edited.pins, [&](const Pin& p) { return p.id == selection.pin_id; });
    state->selection = Selection();
    CommitEdit(state, "Delete pin", std::move(edited));
  } else if (selection.element.kind == ElementKind::kVertex) {
    DeleteVertexEdit(state, selection.element.primitive_id, selection.element.element);
  } else if (selection.element.kind == ElementKind::kEdge) {
    DeleteEdgeEdit(state, selection.element.primitive_id, selection.element.element);
  } else if (selection.primitive_id != kNoId && selection.element.Empty()) {
    DeletePrimitiveEdit(state, selection.primitive_id);
  }
}

Axis AxisOfTool(Tool tool) { return tool == Tool::kLineY ? Axis::kY : tool == Tool::kLineZ ? Axis::kZ : Axis::kX; }

bool IsLineTool(Tool tool) { return tool == Tool::kLineX || tool == Tool::kLineY || tool == Tool::kLineZ; }

// Applies the current mouse position to the item being dragged, as a preview edit.
void UpdateEditDrag(AppState* state, Interaction* drag, const Eigen::Vector2d& mouse_uv) {
  const Eigen::Vector2d target = mouse_uv + drag->grab_offset;
  if ((target - drag->last_uv).norm() == 0.0) return;
  drag->last_uv = target;
  Project edited = state->document.project();
  switch (drag->kind) {
    case DragKind::kMoveEndpoint:
      if (Segment* s = edited.FindSegment(drag->target_id)) (drag->endpoint == 0 ? s->a_px : s->b_px) = target;
      break;
    case DragKind::kMoveSegment:
      if (Segment* s = edited.FindSegment(drag->target_id)) {
        const Eigen::Vector2d delta = mouse_uv - drag->press_uv;
        s->a_px = drag->original_a + delta;
        s->b_px = drag->original_b + delta;
      }
      break;
    case DragKind::kMovePin:
      if (Pin* p = edited.FindPin(drag->target_id)) p->uv_px = target;
      break;
    case DragKind::kPlacePin: state->selection.pin_id = PinVertex(&edited, drag->image_id, drag->vertex, target); break;
    case DragKind::kMoveLinePinEnd:
      // Too close to the other end: the line keeps its last valid position.
      if (!MoveLinePinEnd(&edited, drag->target_id, drag->endpoint, target)) return;
      break;
    default: return;
  }
  UpdateDrag(state, std::move(edited));
}

const char* DragLabel(DragKind kind) {
  switch (kind) {
    case DragKind::kMoveEndpoint: return "Move line end";
    case DragKind::kMoveSegment: return "Move line";
    case DragKind::kMovePin: return "Move pin";
    case DragKind::kPlacePin: return "Pin vertex";
    case DragKind::kMoveLinePinEnd: return "Move line pin end";
    default: return "Drag";
  }
}

bool IsEditDrag(DragKind kind) {
  return kind == DragKind::kMoveEndpoint || kind == DragKind::kMoveSegment || kind == DragKind::kMovePin ||
         kind == DragKind::kPlacePin || kind == DragKind::kMoveLinePinEnd;
}

// A left press with the current tool: decides what the press will do.
void StartLeftPress(AppState* state, PanelState* panel, const Image& image, const OverlayHover& hover,
                    const Eigen::Vector2d& mouse_uv) {
  Interaction& drag = panel->interaction;
  drag = Interaction();
  drag.button = ImGuiMouseButton_Left;
  drag.image_id = image.id;
  drag.press_screen = ImGui::GetIO().MousePos;
  drag.press_uv = mouse_uv;
  const Project& project = state->document.project();
  const Tool tool = state->tool;
  if (IsLineTool(tool)) {
    drag.kind = DragKind::kNewSegment;
    drag.axis = AxisOfTool(tool);
    return;
  }
  if ((tool == Tool::kLinePin || tool == Tool::kSelect) && hover.line_pin_id != kNoId && hover.line_pin_endpoint >= 0) {
    // An end handle: a drag moves that end (the model re-solves live), a click selects it.
    const Constraint* c = project.FindConstraint(hover.line_pin_id);
    SelectLinePin(state, hover.line_pin_id);
    drag.kind = DragKind::kMoveLinePinEnd;
    drag.target_id = hover.line_pin_id;
    drag.endpoint = hover.line_pin_endpoint;
    drag.grab_offset = (drag.endpoint == 0 ? c->line_a_px : c->line_b_px) - mouse_uv;
    return;
  }
  if (tool == Tool::kLinePin) {
    // A drag draws the photo's line for the selected edge; a click selects an edge (and the
    // line pin clicked on, if any).
    drag.kind = DragKind::kLinePin;
    drag.press_element = hover.element;
    drag.press_edge_t = hover.edge_t;
    drag.press_line_pin = hover.line_pin_id;
    return;
  }
  if (tool == Tool::kSelect && hover.line_pin_id != kNoId && !ImGui::GetIO().KeyShift) {
    SelectLinePin(state, hover.line_pin_id);
    return;
  }
  if (tool != Tool::kSelect && tool != Tool::kPin) {
    ApplyToolClick(state, hover.element, hover.edge_t, false);  // the K-operators act on a press
    return;
  }
  if (hover.pin_id != kNoId) {
    const Pin* pin = project.FindPin(hover.pin_id);
    const ElementRef chosen = state->selection.element;
    // The Pin tool with a vertex chosen: a click (no drag) near another pin still pins the
    // chosen vertex where clicked (two corners a few px apart); a drag moves the pin under
    // the pointer, as with any tool.
    const bool click_pins_chosen = tool == Tool::kPin && chosen.kind == ElementKind::kVertex &&
                                   ElementExists(project, chosen) &&
                                   !(pin->vertex.primitive_id == chosen.primitive_id && pin->vertex.vertex == chosen.element);
    if (tool == Tool::kSelect && ImGui::GetIO().KeyShift) {
      drag.toggle_on_click = {ElementKind::kVertex, pin->vertex.primitive_id, pin->vertex.vertex};
    } else if (!click_pins_chosen) {
      state->selection = Selection();
      state->selection.pin_id = hover.pin_id;
    }
    drag.kind = DragKind::kMovePin;
    drag.target_id = hover.pin_id;
    drag.grab_offset = pin->uv_px - mouse_uv;
    if (click_pins_chosen) {
      drag.place_on_click = true;
      drag.vertex = {chosen.primitive_id, chosen.element};
    }
    return;
  }
  if (hover.segment_id != kNoId) {
    const Segment* segment = project.FindSegment(hover.segment_id);
    state->selection = Selection();
    state->selection.segment_id = hover.segment_id;
    state->selection.segment_endpoint = hover.segment_endpoint;
    drag.target_id = hover.segment_id;
    if (hover.segment_endpoint >= 0) {
      drag.kind = DragKind::kMoveEndpoint;
      drag.endpoint = hover.segment_endpoint;
      drag.grab_offset = (hover.segment_endpoint == 0 ? segment->a_px : segment->b_px) - mouse_uv;
    } else {
      drag.kind = DragKind::kMoveSegment;
      drag.original_a = segment->a_px;
      drag.original_b = segment->b_px;
    }
    return;
  }
  if (tool == Tool::kSelect && ImGui::GetIO().KeyShift) {
    // Shift+click: the multi-selection (a click on nothing keeps it).
    ApplyToolClick(state, hover.element, hover.edge_t, true);
    return;
  }
  const ElementRef chosen = state->selection.element;
  if (tool == Tool::kPin && hover.element.kind == ElementKind::kVertex && hover.element == chosen) {
    // The chosen vertex already projects where its pin goes (the solve predicted it): a
    // click there pins it there.
    drag.kind = DragKind::kPlacePin;
    drag.place_on_click = true;
    drag.vertex = {chosen.primitive_id, chosen.element};
    return;
  }
  if (hover.element.kind == ElementKind::kVertex) {
    // Pressing on a projected vertex chooses it; dragging from it pins it where released.
    state->selection = Selection::Of(hover.element);
    drag.kind = DragKind::kPlacePin;
    drag.vertex = {hover.element.primitive_id, hover.element.element};
    // Start from where the vertex is drawn, so that the first motion does not jump.
    for (const ProjectedPrimitive& pp : ProjectModel(project, image)) {
      if (pp.primitive_id == hover.element.primitive_id && hover.element.element < pp.uv_px.size()) {
        drag.grab_offset = pp.uv_px[hover.element.element] - mouse_uv;
      }
    }
    return;
  }
  if (tool == Tool::kPin && chosen.kind == ElementKind::kVertex && ElementExists(project, chosen)) {
    drag.kind = DragKind::kPlacePin;
    drag.place_on_click = true;
    drag.vertex = {chosen.primitive_id, chosen.element};
    return;
  }
  if (tool == Tool::kSelect && !hover.element.Empty()) {
    state->selection = Selection::Of(hover.element);
    return;
  }
  if (tool == Tool::kSelect) state->selection = Selection();
}

// Whether `uv` (image px) is on the image's photo; logs why not.
bool PinFitsPhoto(AppState* state, Id image_id, const Eigen::Vector2d& uv) {
  const Image* image = state->document.project().FindImage(image_id);
  if (image == nullptr) return false;
  if (uv.x() >= 0.0 && uv.y() >= 0.0 && uv.x() <= image->width_px && uv.y() <= image->height_px) return true;
  char text[200];
  std::snprintf(text, sizeof(text), "Pin not placed: (%.1f, %.1f) is outside the %d x %d photo", uv.x(), uv.y(),
                image->width_px, image->height_px);
  state->Log(LogLevel::kWarning, text);
  return false;
}

// `pointer_px_per_image_px`: screen px per image px of the pointer's motion (the zoom, times
// the magnification in fine mode), so "too short" means what the user saw.
void FinishLeftPress(AppState* state, PanelState* panel, const Eigen::Vector2d& mouse_uv,
                     double pointer_px_per_image_px) {
  Interaction& drag = panel->interaction;
  if (drag.ghost_index >= 0 && !drag.began && drag.kind != DragKind::kPan) {
    // A click on a ghost pin: it is accepted instead of what the click would have done.
    const Id image_id = drag.image_id;
    const size_t ghost = static_cast<size_t>(drag.ghost_index);
    drag = Interaction();
    AcceptGhostPinEdit(state, image_id, ghost);
    return;
  }
  if (drag.kind == DragKind::kNewSegment) {
    const double length_px = (mouse_uv - drag.press_uv).norm() * pointer_px_per_image_px;
    if (length_px >= kMinSegmentLengthPx && state->document.project().FindImage(drag.image_id)) {
      Project edited = state->document.project();
      Segment segment;
      segment.id = edited.NewId();
      segment.image_id = drag.image_id;
      segment.axis = drag.axis;
      segment.a_px = drag.press_uv;
      segment.b_px = mouse_uv;
      edited.segments.push_back(segment);
      state->selection = Selection();
      state->selection.segment_id = segment.id;
      CommitEdit(state, std::string("Add ") + AxisName(drag.axis) + " line", std::move(edited));
    }
  } else if (drag.kind == DragKind::kLinePin) {
    const double length_px = (mouse_uv - drag.press_uv).norm() * pointer_px_per_image_px;
    if (length_px >= kMinSegmentLengthPx) {
      LinePinEdit(state, state->selection.element, drag.image_id, drag.press_uv, mouse_uv);
    } else {
      ApplyToolClick(state, drag.press_element, drag.press_edge_t, false);
      if (drag.press_line_pin != kNoId) SelectLinePin(state, drag.press_line_pin);
    }
  } else if (IsEditDrag(drag.kind)) {
    const bool pins = drag.kind == DragKind::kPlacePin || drag.kind == DragKind::kMovePin;
    const bool places = drag.began || drag.place_on_click;
    // A click places the chosen vertex's pin where clicked; a drag moves or places it where
    // the grabbed point ends.
    const Eigen::Vector2d placed_uv = drag.began ? Eigen::Vector2d(mouse_uv + drag.grab_offset) : mouse_uv;
    if (pins && places && !PinFitsPhoto(state, drag.image_id, placed_uv)) {
      // A pin off the photo pins the vertex to nothing the photo shows: refused, and said so.
      if (drag.began) CancelDrag(state);
      if (drag.kind == DragKind::kPlacePin) state->selection.pin_id = kNoId;
      drag = Interaction();
      return;
    }
    if (!drag.began && !drag.toggle_on_click.Empty()) {
      if (ElementExists(state->document.project(), drag.toggle_on_click)) {
        ToggleSelected(&state->selection, drag.toggle_on_click);
      }
    } else if (drag.began && drag.kind == DragKind::kMoveLinePinEnd) {
      // Released where it was pressed: nothing to record. Otherwise the release is like any
      // other drag's (the commit update from the last preview reaches the cold commit's model:
      // tests/test_drag_release.cpp).
      const Constraint* c = state->document.project().FindConstraint(drag.target_id);
      const Constraint* old = state->drag_start ? state->drag_start->FindConstraint(drag.target_id) : nullptr;
      const bool moved = c && old &&
                         (drag.endpoint == 0 ? c->line_a_px != old->line_a_px : c->line_b_px != old->line_b_px);
      if (moved) {
        EndDrag(state);
      } else {
        CancelDrag(state);
      }
    } else if (drag.began) {
      EndDrag(state);
    } else if ((drag.kind == DragKind::kPlacePin || drag.kind == DragKind::kMovePin) && drag.place_on_click) {
      Project edited = state->document.project();
      const Id pin_id = PinVertex(&edited, drag.image_id, drag.vertex, mouse_uv);
      state->selection = Selection();
      state->selection.pin_id = pin_id;
      state->selection.primitive_id = drag.vertex.primitive_id;
      CommitEdit(state, "Pin vertex", std::move(edited));
    }
    if ((drag.kind == DragKind::kPlacePin && drag.began) || (!drag.began && drag.place_on_click)) {
      // The vertex is pinned: the next pin starts by choosing a vertex again.
      state->selection.element = {};
    }
  }
  drag = Interaction();
}

void DrawSegmentContextMenu(AppState* state, PanelState* panel) {
  if (!ImGui::BeginPopup("##segment_menu")) return;
  const Segment* segment = state->document.project().FindSegment(panel->context_segment);
  if (segment == nullptr) {
    ImGui::CloseCurrentPopup();
    ImGui::EndPopup();
    return;
  }
  ImGui::TextDisabled("%s line %llu", AxisName(segment->axis), static_cast<unsigned long long>(segment->id));
  ImGui::Separator();
  for (Axis axis : {Axis::kX, Axis::kY, Axis::kZ}) {
    const std::string label = std::string(AxisName(axis)) + " family";
    if (ImGui::MenuItem(label.c_str(), nullptr, segment->axis == axis) && segment->axis != axis) {
      Project edited = state->document.project();
      edited.FindSegment(panel->context_segment)->axis = axis;
      CommitEdit(state, std::string("Make ") + AxisName(axis) + " line", std::move(edited));
      break;  // `segment` points into the replaced project
    }
  }
  if (state->document.project().FindSegment(panel->context_segment) && ImGui::MenuItem("Delete")) {
    Project edited = state->document.project();
    std::erase_if(edited.segments, [&](const Segment& s) { return s.id == panel->context_segment; });
    if (state->selection.segment_id == panel->context_segment) state->selection = Selection();
    CommitEdit(state, "Delete line", std::move(edited));
  }
  ImGui::EndPopup();
}

// The tab bar: selects state->active_image_id, and follows it when another panel changes it.
void DrawTabs(AppState* state, PanelState* panel) {
  const Project& project = state->document.project();
  if (!project.FindImage(state->active_image_id)) state->active_image_id = project.images.front().id;
  const Id requested = state->active_image_id != panel->shown_tab ? state->active_image_id : kNoId;
  Id shown = kNoId;
  if (ImGui::BeginTabBar("##image_tabs", ImGuiTabBarFlags_FittingPolicyScroll)) {
    for (const Image& image : project.images) {
      std::string label = FileName(image.path);
      if (label.empty()) label = "image " + std::to_string(image.id);
      if (state->photo_errors.count(image.id)) label += " (!)";
      label += "##" + std::to_string(image.id);
      const ImGuiTabItemFlags flags = image.id == requested ? ImGuiTabItemFlags_SetSelected : 0;
      if (ImGui::BeginTabItem(label.c_str(), nullptr, flags)) {
        shown = image.id;
        ImGui::EndTabItem();
      }
    }
    ImGui::EndTabBar();
  }
  // A tab chosen by the user becomes active; a pending request waits until its tab shows.
  if (shown != kNoId && (requested == kNoId || shown == requested)) state->active_image_id = shown;
  panel->shown_tab = shown;
}

void DrawToolbar(AppState* state, PanelState* panel, ImageViewState* view, bool* fit_now, bool* one_to_one) {
  ImGui::AlignTextToFramePadding();
  ImGui::Text("%6.1f%%", view->zoom * 100.0f);
  ImGui::SameLine();
  if (ImGui::SmallButton("Fit")) *fit_now = true;
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Fit the image to the panel (F)");
  ImGui::SameLine();
  if (ImGui::SmallButton("1:1")) *one_to_one = true;
  ImGui::SameLine();
  ImGui::TextDisabled("|");
  ImGui::SameLine();
  ImGui::Checkbox("Model", &panel->overlay.show_model);
  ImGui::SameLine();
  ImGui::Checkbox("VPs", &panel->overlay.show_vanishing_points);
  ImGui::SameLine();
  ImGui::Checkbox("VP lines", &panel->overlay.show_vp_lines);
  ImGui::SameLine();
  ImGui::Checkbox("Snap", &state->snapping);
  if (ImGui::IsItemHovered()) {
    ImGui::SetTooltip("Points placed in the photo snap to corners, segments and the model nearby (hold Alt to place freely)");
  }
  ImGui::SameLine();
  ImGui::TextDisabled("| loupe %gx (Shift)", panel->loupe_magnification);
}

std::string ToolHint(const AppState& state) {
  switch (state.tool) {
    case Tool::kLineX:
    case Tool::kLineY:
    case Tool::kLineZ: return std::string("drag to draw a ") + AxisName(AxisOfTool(state.tool)) + " line";
    case Tool::kPin:
      if (state.selection.element.kind == ElementKind::kVertex) {
        return "click to pin " + DescribeElement(state.document.project(), state.selection.element);
      }
      return "click a model vertex, then where it is in the photo";
    case Tool::kSplitEdge: return "click on an edge to split it there (snaps to the middle)";
    case Tool::kDeleteVertex: return "click on a vertex made by a split to delete it";
    case Tool::kConnectVertices:
      return state.selection.connect_from.Empty() ? "click the first vertex of a face"
                                                  : "click the second vertex on the same face";
    case Tool::kDeleteEdge: return "click on an edge between two faces to merge them";
    case Tool::kLinePin:
      if (state.selection.element.kind == ElementKind::kEdge) {
        return "drag along the photo's line of " + DescribeElement(state.document.project(), state.selection.element) +
               " to pin it there (Shift: fine); click another edge to choose it";
      }
      return "click a model edge, then drag along its line in the photo; drag a line pin's end handle to move it";
    case Tool::kSelect:
      if (!state.selection.extra.empty()) {
        return std::to_string(SelectedElements(state.selection).size()) +
               " selected: Shift+click adds or removes, Esc clears; constraints in the properties panel";
      }
      return state.selection.element.Empty() ? "" : "Shift+click to select more (coplanar, collinear, two edges)";
    case Tool::kPushPull:
      return state.selection.element.kind == ElementKind::kFace
                 ? "type the distance in the tools panel, then Extrude (Enter)"
                 : "click a face to push or pull it";
    default: return "";
  }
}

// What one frame of the image view works with, filled step by step by DrawImageView.
struct ViewFrame {
  const TiledTexture* texture = nullptr;                   // null while the photo is not loaded
  int width_px = 1, height_px = 1;                         // the image's size
  ImVec2 rect_min{0, 0}, rect_max{0, 0}, rect_size{0, 0};  // the view's screen rectangle
  bool hovered = false;
  bool keys_for_us = false;                            // keyboard shortcuts act on this view
  bool fine = false;                                   // fine pointing (Shift during a press)
  double pointer_scale = 1.0;                          // screen px per image px of the pointer's motion
  Eigen::Vector2d mouse_uv = Eigen::Vector2d::Zero();  // the pointer, image px
  ImVec2 pointer_screen{0, 0};  // the pointer before snapping: what hit tests use
  OverlayHover hover;
};

// Step 1: the toolbar, the view's rectangle (an invisible button taking the mouse and the
// wheel) and whether keys are ours. Sets *fit_now / *one_to_one from the toolbar.
ViewFrame LayOutView(AppState* state, PanelState* panel, ImageViewState* view, bool* fit_now, bool* one_to_one) {
  ImGuiIO& io = ImGui::GetIO();
  ViewFrame frame;
  DrawToolbar(state, panel, view, fit_now, one_to_one);
  const float status_h = ImGui::GetTextLineHeightWithSpacing();
  const ImVec2 avail = ImGui::GetContentRegionAvail();
  frame.rect_size = ImVec2(std::max(avail.x, 32.0f), std::max(avail.y - status_h, 32.0f));
  frame.rect_min = ImGui::GetCursorScreenPos();
  frame.rect_max = ImVec2(frame.rect_min.x + frame.rect_size.x, frame.rect_min.y + frame.rect_size.y);

  ImGui::InvisibleButton(
      "##image_view", frame.rect_size,
      ImGuiButtonFlags_MouseButtonLeft | ImGuiButtonFlags_MouseButtonRight | ImGuiButtonFlags_MouseButtonMiddle);
  ImGui::SetItemUsingMouseWheel();
  frame.hovered = ImGui::IsItemHovered();
  const bool focused = ImGui::IsWindowFocused(ImGuiFocusedFlags_RootAndChildWindows);
  // Keys go to the panel under the mouse, or to this one when it has focus and the mouse
  // is over no other window (the 3D panel also answers F).
  const bool other_window_hovered = ImGui::IsWindowHovered(ImGuiHoveredFlags_AnyWindow) &&
                                    !ImGui::IsWindowHovered(ImGuiHoveredFlags_RootAndChildWindows);
  frame.keys_for_us = (frame.hovered || (focused && !other_window_hovered)) && !io.WantTextInput;
  return frame;
}

// Step 2: fit (requested, F, or a resize of a fitted view), 1:1, and the wheel: zoom about
// the cursor, or with Shift the loupe's magnification.
void FitAndZoomView(PanelState* panel, ImageViewState* view, const ViewFrame& frame, bool fit_now, bool one_to_one) {
  ImGuiIO& io = ImGui::GetIO();
  if (panel->fit_requested) fit_now = true;
  if (frame.keys_for_us && ImGui::IsKeyPressed(GLFW_KEY_F, false) && !io.KeyCtrl && !io.KeyAlt) fit_now = true;
  const bool resized = view->last_size.x != frame.rect_size.x || view->last_size.y != frame.rect_size.y;
  if (!view->initialized || fit_now || (view->fitted && resized)) {
    FitImageView(view, frame.width_px, frame.height_px, frame.rect_min, frame.rect_size);
    panel->fit_requested = false;
  }
  view->last_size = frame.rect_size;
  if (one_to_one) {
    ZoomImageViewAbout(
        view, 1.0f, ImVec2(frame.rect_min.x + 0.5f * frame.rect_size.x, frame.rect_min.y + 0.5f * frame.rect_size.y));
  }
  if (!frame.hovered) return;
  const float wheel = io.KeyShift && io.MouseWheel == 0.0f ? io.MouseWheelH : io.MouseWheel;
  if (wheel == 0.0f) return;
  if (io.KeyShift) {
    const float factor = wheel > 0 ? 2.0f : 0.5f;
    panel->loupe_magnification =
        std::clamp(panel->loupe_magnification * factor, kMinLoupeMagnification, kMaxLoupeMagnification);
    panel->fine_active = false;  // re-anchored below at the current pointer
  } else {
    ZoomImageViewAbout(view, view->zoom * std::pow(kWheelZoomStep, wheel), io.MousePos);
  }
}

// Step 3: the pointer: the mouse, or in fine mode (Shift during a press) the slowed-down
// point that the loupe shows.
void UpdatePointer(PanelState* panel, const ImageViewState& view, const ViewTransform& transform, ViewFrame* frame) {
  ImGuiIO& io = ImGui::GetIO();
  const Interaction& drag = panel->interaction;
  const bool busy = drag.kind != DragKind::kNone;
  frame->fine = io.KeyShift && busy && drag.kind != DragKind::kPan;
  if (frame->fine && !panel->fine_active) {
    panel->fine_anchor_screen = panel->last_mouse_screen;
    panel->fine_anchor_uv = panel->last_pointer_uv;
  }
  panel->fine_active = frame->fine;
  frame->pointer_scale = view.zoom * (frame->fine ? panel->loupe_magnification : 1.0f);
  frame->mouse_uv =
      frame->fine ? Eigen::Vector2d(panel->fine_anchor_uv +
                                    (ToEigen(io.MousePos) - ToEigen(panel->fine_anchor_screen)) / frame->pointer_scale)
                  : MouseUv(view);
  frame->pointer_screen = transform.ToScreen(frame->mouse_uv.x(), frame->mouse_uv.y());
  panel->last_pointer_uv = frame->mouse_uv;
  panel->last_mouse_screen = io.MousePos;
}

// What the current tool or drag places, so that it may snap (SnapRequest).
SnapRequest SnapRequestFor(const AppState& state, const PanelState& panel) {
  const Interaction& drag = panel.interaction;
  const Project& project = state.document.project();
  SnapRequest request;
  switch (drag.kind) {
    case DragKind::kNone:
      request.active = IsLineTool(state.tool) || state.tool == Tool::kPin || state.tool == Tool::kLinePin;
      if (state.tool == Tool::kPin || state.tool == Tool::kLinePin) {
        request.exclude_primitive = state.selection.element.primitive_id;
      }
      break;
    case DragKind::kNewSegment:
      request.active = true;
      request.vanishing_direction = true;
      request.axis = drag.axis;
      request.anchor_px = drag.press_uv;
      break;
    case DragKind::kMoveEndpoint:
      if (const Segment* s = project.FindSegment(drag.target_id)) {
        request.active = true;
        request.exclude_segment = s->id;
        request.vanishing_direction = true;
        request.axis = s->axis;
        request.anchor_px = drag.endpoint == 0 ? s->b_px : s->a_px;
      }
      break;
    case DragKind::kMovePin:
      if (const Pin* pin = project.FindPin(drag.target_id)) {
        request.active = true;
        request.exclude_primitive = pin->vertex.primitive_id;
      }
      break;
    case DragKind::kPlacePin:
      request.active = true;
      request.exclude_primitive = drag.vertex.primitive_id;
      break;
    case DragKind::kLinePin:
      request.active = true;
      request.exclude_primitive = state.selection.element.primitive_id;
      break;
    case DragKind::kMoveLinePinEnd:
      if (const Constraint* c = project.FindConstraint(drag.target_id)) {
        request.active = true;
        if (!c->vertices.empty()) request.exclude_primitive = c->vertices[0].primitive_id;
      }
      break;
    default: break;
  }
  return request;
}

// Step 3b: snapping (Alt turns it off). The point placed is the pointer plus the drag's grab
// offset, so that is what snaps; frame->mouse_uv moves by the same amount.
void ApplySnapping(const AppState& state, PanelState* panel, const Image& image,
                   const std::vector<ProjectedPrimitive>& model, ViewFrame* frame) {
  panel->snap = SnapResult();
  const SnapRequest request = SnapRequestFor(state, *panel);
  if (!state.snapping || !request.active || ImGui::GetIO().KeyAlt ||
      !(frame->hovered || panel->interaction.kind != DragKind::kNone)) {
    return;
  }
  const SnapFeatures features =
      CollectSnapFeatures(state, image, model, panel->photo_features.Get(state, image.id), request);
  const Eigen::Vector2d offset = IsEditDrag(panel->interaction.kind) ? panel->interaction.grab_offset
                                                                     : Eigen::Vector2d::Zero();
  const SnapResult snap = SnapToFeatures(frame->mouse_uv + offset, features, kSnapRadiusScreenPx / frame->pointer_scale);
  if (snap.kind == SnapKind::kNone) return;
  panel->snap = snap;
  frame->mouse_uv = snap.position_px - offset;
}

// Step 4: what is under the pointer, shared with the 3D panel through AppState::hover.
void UpdateHover(AppState* state, const PanelState& panel, const Image& image,
                 const std::vector<ProjectedPrimitive>& model, const ViewTransform& transform, ViewFrame* frame) {
  const bool busy = panel.interaction.kind != DragKind::kNone;
  if (frame->hovered && !busy) {
    const bool multi_select = state->tool == Tool::kSelect && ImGui::GetIO().KeyShift;
    frame->hover =
        HitTest(state->document.project(), image, model, transform, frame->pointer_screen, state->tool, multi_select);
  }
  if (frame->hovered && !busy) {
    state->hover = frame->hover.element;
    state->hover_panel = kImagePanelHover;
  } else if (state->hover_panel == kImagePanelHover) {
    state->hover = {};
    state->hover_panel = 0;
  }
}

// Step 5: presses start an interaction; a drag started elsewhere (another panel) blocks edits.
void StartInteraction(AppState* state, PanelState* panel, const Image& image,
                      const std::vector<ProjectedPrimitive>& model, const ViewTransform& transform,
                      const ViewFrame& frame) {
  Interaction& drag = panel->interaction;
  if (!frame.hovered || drag.kind != DragKind::kNone) return;
  const bool space_down = ImGui::IsKeyDown(ImGui::GetKeyIndex(ImGuiKey_Space));
  if (ImGui::IsMouseClicked(ImGuiMouseButton_Middle) || (ImGui::IsMouseClicked(ImGuiMouseButton_Left) && space_down)) {
    drag = Interaction();
    drag.kind = DragKind::kPan;
    drag.button = ImGui::IsMouseClicked(ImGuiMouseButton_Middle) ? ImGuiMouseButton_Middle : ImGuiMouseButton_Left;
  } else if (ImGui::IsMouseClicked(ImGuiMouseButton_Left) && !state->drag_start) {
    StartLeftPress(state, panel, image, frame.hover, frame.mouse_uv);
  } else if (ImGui::IsMouseClicked(ImGuiMouseButton_Right)) {
    // The context menu works with every tool, so pick segments as the select tool does.
    const OverlayHover under =
        HitTest(state->document.project(), image, model, transform, frame.pointer_screen, Tool::kSelect, false);
    if (under.segment_id != kNoId) {
      panel->context_segment = under.segment_id;
      ImGui::OpenPopup("##segment_menu");
    }
  }
}

// Step 6a: an edit drag in progress: begin it past the threshold, cancel on Escape, update,
// finish on release.
void ContinueEditDrag(AppState* state, PanelState* panel, const ViewFrame& frame) {
  ImGuiIO& io = ImGui::GetIO();
  Interaction& drag = panel->interaction;
  if (IsEditDrag(drag.kind) && drag.began && !state->drag_start) {
    drag.kind = DragKind::kNone;  // cancelled elsewhere (undo during the drag)
  }
  const double moved_px = (ToEigen(io.MousePos) - ToEigen(drag.press_screen)).norm();
  if (IsEditDrag(drag.kind) && !drag.began && moved_px >= kDragStartPx && !state->drag_start) {
    drag.began = true;
    BeginDrag(state, DragLabel(drag.kind));
  }
  if (IsEditDrag(drag.kind) && drag.began && ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Escape), false)) {
    CancelDrag(state);
    if (drag.kind == DragKind::kPlacePin) state->selection.pin_id = kNoId;
    drag.kind = DragKind::kNone;  // the rest of the press does nothing
  } else if ((drag.kind == DragKind::kNewSegment || drag.kind == DragKind::kLinePin) &&
             ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Escape), false)) {
    drag.kind = DragKind::kNone;
  } else if (IsEditDrag(drag.kind) && drag.began) {
    UpdateEditDrag(state, &drag, frame.mouse_uv);
  }
  if (ImGui::IsMouseReleased(drag.button) || !ImGui::IsMouseDown(drag.button)) {
    FinishLeftPress(state, panel, frame.mouse_uv, frame.pointer_scale);
  }
}

// Step 6b: the keys of an idle view: Delete removes the selection, Escape steps back.
void HandleIdleKeys(AppState* state, PanelState* panel) {
  const bool delete_pressed = ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Delete), false) ||
                              ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Backspace), false);
  // A selected line proposal takes Delete and Escape before the model's selection.
  if (state->line_proposals && state->line_proposals->selected >= 0) {
    if (delete_pressed) RemoveLineProposal(state, state->line_proposals->selected);
    if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Escape), false)) state->line_proposals->selected = -1;
    if (delete_pressed || ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Escape), false)) return;
  }
  if (delete_pressed) DeleteSelection(state, panel);
  // Enter accepts the ghost pins (the button above the photo).
  if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Enter), false) &&
      (state->tool == Tool::kSelect || state->tool == Tool::kPin)) {
    const PinProposalSummary* ghosts = GhostPinsFor(state, state->active_image_id);
    if (ghosts != nullptr && ProposedGhostPins(*ghosts) > 0) AcceptGhostPinsEdit(state, state->active_image_id);
  }
  if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Escape), false)) {
    // Escape steps back: first whatever is half done (V_connect's first vertex, the
    // multi-selection beyond its main element, the constraint builder's first edge, the vertex
    // to pin); with nothing half done, the selection itself, as the constraints hint says.
    const bool half_done = !state->selection.connect_from.Empty() || !state->selection.extra.empty() ||
                           state->constraint_first_kind.has_value() ||
                           (state->tool == Tool::kPin && !state->selection.element.Empty());
    state->selection.connect_from = {};
    if (state->tool == Tool::kPin) state->selection.element = {};
    state->selection.extra.clear();
    state->constraint_first_kind.reset();
    state->constraint_first_edge = {};
    if (!half_done) state->selection = Selection{};
  }
}

// Step 6: the ongoing interaction (pan, edit drag) or, when idle, the keys.
void ContinueInteraction(AppState* state, PanelState* panel, ImageViewState* view, const ViewFrame& frame) {
  ImGuiIO& io = ImGui::GetIO();
  Interaction& drag = panel->interaction;
  if (drag.kind == DragKind::kPan) {
    view->origin = ImVec2(view->origin.x + io.MouseDelta.x, view->origin.y + io.MouseDelta.y);
    if (io.MouseDelta.x != 0.0f || io.MouseDelta.y != 0.0f) view->fitted = false;
    if (!ImGui::IsMouseDown(drag.button)) drag = Interaction();
  } else if (drag.kind != DragKind::kNone) {
    ContinueEditDrag(state, panel, frame);
  } else if (frame.keys_for_us) {
    HandleIdleKeys(state, panel);
  }
}

// Step 7: what the overlays show, from the project as it is now (step 6 may have edited it).
// `model` is current_image projected and must outlive the result.
OverlayInput MakeOverlayInput(AppState* state, const PanelState& panel, const Image& current_image,
                              const std::vector<ProjectedPrimitive>& model, const OverlayHover& hover) {
  OverlayInput overlay;
  overlay.project = &state->document.project();
  overlay.image = &current_image;
  overlay.calibration = CalibrationFor(*state, current_image.id);
  overlay.model = &model;
  overlay.references = &state->references;
  overlay.tool = state->tool;
  if (state->hover_panel != kImagePanelHover) overlay.other_hover = state->hover;
  overlay.selection = state->selection;
  overlay.selected_line_pin = SelectedLinePin(state);
  overlay.hover = hover;
  overlay.flagged_pins = &state->last_update.joint.flagged_pins;
  overlay.ghost_pins = GhostPinsFor(state, current_image.id);
  const Interaction& drag = panel.interaction;
  if (drag.kind == DragKind::kMoveLinePinEnd) {  // the dragged handle stays lit
    overlay.hover = OverlayHover();
    overlay.hover.line_pin_id = drag.target_id;
    overlay.hover.line_pin_endpoint = drag.endpoint;
  }
  return overlay;
}

// Step 8: the photo (or its placeholder), the overlays, the drag previews, a load error, the
// loupe and the fine pointer, clipped to the view. Returns the top of the teach overlay's text
// boxes (screen y; the view's bottom when there are none).
float DrawViewContents(const AppState& state, const PanelState& panel, const ImageViewState& view, const Image& image,
                       const OverlayInput& overlay, const ViewFrame& frame,
                       const std::function<const TiledTexture*(Id)>& texture_of) {
  ImGuiIO& io = ImGui::GetIO();
  const ViewTransform transform = TransformOf(view);
  const Interaction& drag = panel.interaction;
  const ImVec2 rect_min = frame.rect_min, rect_max = frame.rect_max;
  const Eigen::Vector2d& mouse_uv = frame.mouse_uv;
  ImDrawList* draw_list = ImGui::GetWindowDrawList();
  draw_list->PushClipRect(rect_min, rect_max, true);
  draw_list->AddRectFilled(rect_min, rect_max, kImageViewBackground);
  const ImVec2 image_min = transform.ToScreen(-0.5, -0.5);
  const ImVec2 image_max = transform.ToScreen(frame.width_px - 0.5, frame.height_px - 0.5);
  if (frame.texture != nullptr) {
    DrawTiledTexture(draw_list, *frame.texture, transform, rect_min, rect_max);
  } else {
    draw_list->AddRectFilled(image_min, image_max, IM_COL32(70, 70, 76, 255));
  }
  draw_list->AddRect(ImVec2(image_min.x - 1, image_min.y - 1), ImVec2(image_max.x + 1, image_max.y + 1),
                     IM_COL32(0, 0, 0, 255));
  DrawImageOverlays(draw_list, overlay, transform, rect_min, rect_max, panel.overlay);
  DrawCalibrationOverlay(draw_list, state, image, transform, rect_min, rect_max, frame.hovered ? &mouse_uv : nullptr);
  const float teach_text_top =
      DrawTeachImageOverlay(draw_list, state, image, transform, rect_min, rect_max, texture_of);
  DrawLineProposals(draw_list, state, image.id, transform, rect_min, rect_max);
  if (drag.kind == DragKind::kNewSegment) {
    DrawImageLine(draw_list, transform, drag.press_uv, mouse_uv, rect_min, rect_max, IM_COL32(0, 0, 0, 200), 4.0f);
    DrawImageLine(draw_list, transform, drag.press_uv, mouse_uv, rect_min, rect_max, AxisColor(drag.axis, 255), 2.0f);
  }
  if (drag.kind == DragKind::kLinePin &&
      (mouse_uv - drag.press_uv).norm() * frame.pointer_scale >= kMinSegmentLengthPx) {
    DrawLinePinPreview(draw_list, overlay, transform, drag.press_uv, mouse_uv, rect_min, rect_max);
  }
  if (panel.snap.kind != SnapKind::kNone) {
    DrawSnapMarker(draw_list, transform.ToScreen(panel.snap.position_px.x(), panel.snap.position_px.y()),
                   panel.snap.kind, true);
  }
  if (auto error = state.photo_errors.find(image.id); error != state.photo_errors.end()) {
    const std::string text =
        "Cannot show this photo: " + error->second + "\nFile > Relink photo... points this image at its file.";
    draw_list->AddText(ImGui::GetFont(), ImGui::GetFontSize(), ImVec2(rect_min.x + 10, rect_min.y + 10),
                       IM_COL32(255, 110, 110, 255), text.c_str(), nullptr, frame.rect_size.x - 20.0f);
  } else if (frame.texture == nullptr) {
    draw_list->AddText(ImVec2(rect_min.x + 10, rect_min.y + 10), IM_COL32(200, 200, 200, 255), "Loading photo...");
  }
  if ((frame.hovered || frame.fine) && io.KeyShift && drag.kind != DragKind::kPan) {
    std::optional<LoupePreview> preview;
    if (drag.kind == DragKind::kNewSegment) preview = LoupePreview{drag.press_uv, drag.axis};
    DrawLoupe(draw_list, frame.texture, overlay, panel.overlay, view, panel.loupe_magnification, mouse_uv, preview,
              rect_min, rect_max, frame.width_px, frame.height_px, &panel.snap);
    if (frame.fine) {  // where the slowed-down pointer is in the main view
      const ImVec2 p = transform.ToScreen(mouse_uv.x(), mouse_uv.y());
      draw_list->AddCircle(p, 5.0f, IM_COL32(0, 0, 0, 200), 0, 3.0f);
      draw_list->AddCircle(p, 5.0f, IM_COL32(255, 255, 255, 230), 0, 1.5f);
    }
  }
  draw_list->PopClipRect();
  return teach_text_top;
}

// Step 9: the hover tooltip and the status line (pointer, zoom, hover, tool hint).
void DrawViewStatus(const AppState& state, const PanelState& panel, const ImageViewState& view,
                    const ViewFrame& frame) {
  ImGuiIO& io = ImGui::GetIO();
  if (frame.hovered && panel.interaction.kind == DragKind::kNone && !io.KeyShift) {
    const std::string hover_text = DescribeHover(state, frame.hover);
    if (!hover_text.empty()) ImGui::SetTooltip("%s", hover_text.c_str());
  }
  std::string hover_text = DescribeHover(state, frame.hover);
  if (panel.snap.kind != SnapKind::kNone) {
    hover_text += std::string(hover_text.empty() ? "" : "   ") + "snap: " + SnapKindName(panel.snap.kind) + " (Alt: off)";
  }
  const std::string hint = ToolHint(state);
  if (frame.hovered) {
    ImGui::Text("(%.1f, %.1f) px   %.1f%%   %s%s%s", frame.mouse_uv.x(), frame.mouse_uv.y(), view.zoom * 100.0f,
                hover_text.c_str(), hover_text.empty() || hint.empty() ? "" : "   ", hint.c_str());
  } else {
    ImGui::Text("%d x %d px   %.1f%%   %s", frame.width_px, frame.height_px, view.zoom * 100.0f, hint.c_str());
  }
}

// View > Teach > Vanishing points just turned on (or another photo shown with it on): the
// view takes in the construction (the vanishing points, the circle, C'), which lies mostly
// off the photo, with room under it for the overlay's text box. Once: the user zooms freely.
void ShowVanishingConstruction(const AppState* state, PanelState* panel, ImageViewState* view, const Image& image,
                               const ViewFrame& frame) {
  if (!state->teach.vanishing_points) {
    panel->vanishing_view_image = kNoId;
    return;
  }
  if (panel->vanishing_view_image == image.id) return;
  panel->vanishing_view_image = image.id;
  const std::optional<TeachVanishing> teach = TeachVanishingFor(*state, image.id);
  if (!teach) return;
  Eigen::Vector2d lo, hi;
  TeachVanishingExtent(*teach, frame.width_px, frame.height_px, &lo, &hi);
  const float text_box_px = kVanishingTextLines * (ImGui::GetTextLineHeight() + 2.0f) + 24.0f;
  FitImageViewToBox(view, lo, hi, frame.rect_min, frame.rect_size, text_box_px);
}

// The last solve's likely wrong clicks in this photo (JointSolveSummary::flagged_pins), in a
// row above the view where the user is looking, with the offer to drop every flagged pin as
// one undoable edit (the Solve section has the same button).
void DrawFlaggedPinsBar(AppState* state, Id image_id) {
  const JointSolveSummary& joint = state->last_update.joint;
  if (!joint.IsUsable() || joint.flagged_pins.empty()) return;
  int here = 0;
  double worst_px = 0.0;
  for (const FlaggedPin& flagged : joint.flagged_pins) {
    if (flagged.image_id != image_id) continue;
    ++here;
    worst_px = std::max(worst_px, flagged.error_px);
  }
  if (here == 0) return;
  ImGui::TextColored(kWarningText, "%d pin%s here %s far from the model (up to %.0f px): wrong click%s?", here,
                     here == 1 ? "" : "s", here == 1 ? "is" : "are", worst_px, here == 1 ? "" : "s");
  RecordItem(state, "image.flagged_pins");
  ImGui::SameLine();
  const size_t all = joint.flagged_pins.size();
  const std::string label = "Drop " + std::to_string(all) + " flagged pin" + (all == 1 ? "" : "s");
  if (ImGui::SmallButton(label.c_str())) DropFlaggedPinsEdit(state);
  RecordItem(state, "image.drop_flagged_pins");
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("Remove the pins ringed in red in every photo (likely wrong clicks); Edit > Undo brings them back");
}

// Pins proposed from the other photos' pins (app/state/ghost_pins.h), above the view like the
// flagged pins, with the offer to accept them all as one undoable edit (or Enter). On the
// Detect lines row unless that row shows a detection or its proposals: the offer comes and
// goes with every edit, and a row of its own would move the photo under the pointer.
void DrawGhostPinsBar(AppState* state, Id image_id) {
  const PinProposalSummary* summary = GhostPinsFor(state, image_id);
  if (summary == nullptr) return;
  const int proposed = ProposedGhostPins(*summary);
  if (proposed == 0) return;
  const bool lines_row_busy =
      state->line_detection.job.has_value() || (state->line_proposals && state->line_proposals->image_id == image_id);
  if (!lines_row_busy) ImGui::SameLine();
  ImGui::TextColored(ImVec4(0.55f, 1.0f, 0.47f, 1.0f), "%d pin%s proposed from the other photos", proposed,
                     proposed == 1 ? "" : "s");
  RecordItem(state, "image.pin_proposals");
  ImGui::SameLine();
  const std::string label = "Accept " + std::to_string(proposed) + " proposal" + (proposed == 1 ? "" : "s");
  if (ImGui::SmallButton(label.c_str())) AcceptGhostPinsEdit(state, image_id);
  RecordItem(state, "image.accept_pin_proposals");
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip(
        "Pin every hollow green marker (Enter); a click on one pins that one; Edit > Undo takes them back");
}

// The ghost pin under a left press (not with Alt, which places by hand, nor with the Pin
// tool's vertex chosen, which pins that vertex where clicked), or -1. A click on it (no drag)
// accepts it; a drag from it does what it did before (e.g. drags the vertex under it).
int GhostUnderPress(AppState* state, Id image_id, const ViewTransform& view, bool view_hovered) {
  if (!view_hovered || !ImGui::IsMouseClicked(ImGuiMouseButton_Left) || ImGui::GetIO().KeyAlt) return -1;
  if (state->tool != Tool::kSelect && state->tool != Tool::kPin) return -1;
  if (state->tool == Tool::kPin && state->selection.element.kind == ElementKind::kVertex) return -1;
  const PinProposalSummary* summary = GhostPinsFor(state, image_id);
  if (summary == nullptr) return -1;
  const Eigen::Vector2d mouse = ToEigen(ImGui::GetIO().MousePos);
  double best = kGhostPinRadiusPx;
  int found = -1;
  for (size_t k = 0; k < summary->proposals.size(); ++k) {
    const PinProposal& p = summary->proposals[k];
    if (!p.Proposed()) continue;
    const double d = (ToEigen(view.ToScreen(p.match.uv_px.x(), p.match.uv_px.y())) - mouse).norm();
    if (d < best) {
      best = d;
      found = static_cast<int>(k);
    }
  }
  return found;
}

// One image's view for one frame, in the steps above.
void DrawImageView(AppState* state, PanelState* panel, const Image& image) {
  ImageViewState& view = panel->views[image.id];
  bool fit_now = false, one_to_one = false;
  DrawLineProposalsBar(state, image.id);
  DrawGhostPinsBar(state, image.id);
  DrawFlaggedPinsBar(state, image.id);
  ViewFrame frame = LayOutView(state, panel, &view, &fit_now, &one_to_one);
  frame.texture = TextureFor(panel, *state, image.id);
  frame.width_px = frame.texture ? frame.texture->width : std::max(1, image.width_px);
  frame.height_px = frame.texture ? frame.texture->height : std::max(1, image.height_px);
  FitAndZoomView(panel, &view, frame, fit_now, one_to_one);
  ShowVanishingConstruction(state, panel, &view, image, frame);
  if (panel->like_view && panel->like_view->image_id == image.id && panel->like_view->rect_w > 0.0f &&
      panel->like_view->rect_h > 0.0f) {
    // The other panel's view scaled about the canvas centres, all of it in view.
    const ImageViewReport& like = *panel->like_view;
    const float s = std::min(frame.rect_size.x / like.rect_w, frame.rect_size.y / like.rect_h);
    const ImVec2 center(frame.rect_min.x + 0.5f * frame.rect_size.x, frame.rect_min.y + 0.5f * frame.rect_size.y);
    view.zoom = like.zoom * s;
    view.origin = ImVec2(center.x + s * (like.origin_x - (like.rect_x + 0.5f * like.rect_w)),
                         center.y + s * (like.origin_y - (like.rect_y + 0.5f * like.rect_h)));
    view.initialized = true;
    view.fitted = false;
  }

  const std::vector<ProjectedPrimitive> model = ProjectModel(state->document.project(), image);
  const ViewTransform transform = TransformOf(view);
  UpdatePointer(panel, view, transform, &frame);
  state->pointer_in_image_px = frame.hovered ? std::optional<Eigen::Vector2d>(frame.mouse_uv) : std::nullopt;
  state->pointer_image_id = image.id;
  ApplySnapping(*state, panel, image, model, &frame);
  UpdateHover(state, *panel, image, model, transform, &frame);
  // A click on a detected line's proposal selects it rather than starting a tool's action.
  if (!ClickLineProposal(state, image.id, transform, frame.hovered)) {
    const int ghost = GhostUnderPress(state, image.id, transform, frame.hovered);
    StartInteraction(state, panel, image, model, transform, frame);
    if (ghost >= 0 && panel->interaction.kind == DragKind::kNone) {
      AcceptGhostPinEdit(state, image.id, static_cast<size_t>(ghost));  // nothing to drag
    } else if (ghost >= 0) {
      panel->interaction.ghost_index = ghost;  // accepted on a release without a drag
    }
  }
  ContinueInteraction(state, panel, &view, frame);
  DrawSegmentContextMenu(state, panel);

  // Drawing (the project may have changed above: read it again). While View > Teach > Solver
  // steps steps the solve, the model and pins are drawn in its stepped state.
  const Project* stepped = TeachSteppedProject(*state);
  const Project& shown = stepped != nullptr ? *stepped : state->document.project();
  const Image* current_image = shown.FindImage(image.id);
  if (current_image == nullptr) return;
  const std::vector<ProjectedPrimitive> current_model = ProjectModel(shown, *current_image);
  OverlayInput overlay = MakeOverlayInput(state, *panel, *current_image, current_model, frame.hover);
  overlay.project = &shown;
  const float teach_text_top = DrawViewContents(*state, *panel, view, image, overlay, frame,
                                                [&](Id id) { return TextureFor(panel, *state, id); });  // insets
  if (teach_text_top < frame.rect_max.y) {  // the teach overlay's text, for the report
    state->item_rects["teach.text"] = {frame.rect_min.x, teach_text_top, frame.rect_size.x,
                                       frame.rect_max.y - teach_text_top};
  }
  DrawViewStatus(*state, *panel, view, frame);

  panel->report.image_id = image.id;
  panel->report.origin_x = view.origin.x;
  panel->report.origin_y = view.origin.y;
  panel->report.zoom = view.zoom;
  panel->report.rect_x = frame.rect_min.x;
  panel->report.rect_y = frame.rect_min.y;
  panel->report.rect_w = frame.rect_size.x;
  panel->report.rect_h = frame.rect_size.y;
}

}  // namespace

void DrawImagePanel(AppState* state, ImagePanelState* owner) {
  PanelState& panel = Panel(owner);
  if (panel.document_generation != state->document_generation) {
    // Another project: its images (whose ids start again) are shown fitted, not at the zoom
    // and place the last project's image of the same id had.
    panel.document_generation = state->document_generation;
    panel.views.clear();
    panel.interaction = Interaction();
    panel.fine_active = false;
  }
  CollectGarbage(&panel, *state);
  const Project& project = state->document.project();
  if (project.images.empty()) {
    panel.report = ImageViewReport();
    ImGui::TextDisabled("No images yet: add a photo to the project to start drawing lines.");
    return;
  }
  DrawTabs(state, &panel);
  const Image* image = state->document.project().FindImage(state->active_image_id);
  if (image == nullptr) return;
  // DrawImageView may replace the project (edits); keep the image by value.
  const Image image_copy = *image;
  ImGui::PushID(static_cast<int>(image_copy.id));
  DrawImageView(state, &panel, image_copy);
  ImGui::PopID();
}

ImageViewReport LastImageViewReport(const ImagePanelState& panel) {
  return panel.impl ? panel.impl->report : ImageViewReport();
}

void RequestImageFit(ImagePanelState* panel) { Panel(panel).fit_requested = true; }

void RequestImageViewLike(ImagePanelState* panel, const ImageViewReport& like) { Panel(panel).like_view = like; }

void ShutdownImagePanel(ImagePanelState* panel) {
  if (!panel->impl) return;
  for (auto& [id, cached] : panel->impl->textures) DestroyTiledTexture(&cached.texture);
  panel->impl.reset();
}

}  // namespace facet::app
