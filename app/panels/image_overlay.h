// What the image panel draws over a photo, as ImDrawList calls under an image-to-screen
// transform: line segments by family, vanishing points and the horizon, the projected
// primitives (every mesh edge, vertices, every selected element and the hovered one), the pins
// with their residual lines and the line pins (kEdgeOnImageLine) with their edges' distances
// and a draggable handle at each end. Also the projections
// the panel's hit tests share with the drawing, so that what is picked is what is shown.
#pragma once

#include <array>
#include <map>
#include <vector>

#include <imgui.h>
#include <Eigen/Core>

#include "app/platform/image_tiles.h"
#include "app/state/app_state.h"
#include "app/state/model_pick.h"

namespace facet::app {

// Colour of the projected model in every image: the shell's screenshot tests look for it.
constexpr ImU32 kModelEdgeColor = IM_COL32(255, 220, 0, 255);
constexpr float kModelEdgeThicknessPx = 2.0f;
// Reference geometry's outlines (app/state/reference_edits.h): see-through, thinner than the
// model's, in the 3D panel's reference colour.
constexpr ImU32 kReferenceEdgeColor = IM_COL32(70, 205, 215, 150);
constexpr float kReferenceEdgeThicknessPx = 1.5f;

// A line pin's end handle (a diamond at each of the two points its line was drawn through):
// its half-size in screen px, larger when hovered or dragged.
constexpr float kLinePinHandleRadiusPx = 4.0f;
constexpr float kLinePinHandleHotRadiusPx = 6.0f;

// Colour of a line family (x red, y green, z blue) with the given alpha.
ImU32 AxisColor(Axis axis, int alpha = 255);

// Clips the segment a-b (screen coordinates in double, so points far outside the float
// range still clip correctly) to the rectangle [min, max]. Returns false when nothing is left.
bool ClipSegmentToRect(Eigen::Vector2d* a, Eigen::Vector2d* b, const Eigen::Vector2d& rect_min,
                       const Eigen::Vector2d& rect_max);

// Image px to screen px in double (ViewTransform's own works in float, which loses points far
// off the photo, such as vanishing points).
Eigen::Vector2d ImageToScreen(const ViewTransform& view, const Eigen::Vector2d& uv_px);
ImVec2 ToImVec2(const Eigen::Vector2d& p);

// The screen end points (*a, *b) of a stretch of the image line l . (u, v, 1) = 0 that crosses
// the whole view [rect_min, rect_max] (screen px); false for the line at infinity.
bool ImageLineAcrossView(const ViewTransform& view, const Eigen::Vector3d& line, const Eigen::Vector2d& rect_min,
                         const Eigen::Vector2d& rect_max, Eigen::Vector2d* a, Eigen::Vector2d* b);

// The screen segment a-b clipped to [rect_min, rect_max] grown by a margin (so that thick lines
// at the border are not cut visibly short) and drawn; dashed (dash_px on, dash_px off) when
// dash_px > 0; each piece over a shadow 2 px wider when `shadow` is not 0.
void DrawClippedScreenLine(ImDrawList* draw_list, Eigen::Vector2d a, Eigen::Vector2d b, const Eigen::Vector2d& rect_min,
                           const Eigen::Vector2d& rect_max, ImU32 color, float thickness_px, double dash_px = 0.0,
                           ImU32 shadow = 0);

struct OverlayOptions {
  bool show_segments = true;
  bool show_vanishing_points = true;
  bool show_vp_lines = false;  // faint lines from each segment towards its vanishing point
  bool show_model = true;
  bool show_pins = true;
  bool show_labels = true;  // pin numbers, VP names
};

// What is under the cursor, highlighted in addition to the state's selection.
struct OverlayHover {
  Id segment_id = kNoId;
  int segment_endpoint = -1;  // 0 = a, 1 = b, -1 = the segment itself
  Id pin_id = kNoId;
  Id line_pin_id = kNoId;      // a kEdgeOnImageLine constraint of this image
  int line_pin_endpoint = -1;  // 0 = line_a_px, 1 = line_b_px, -1 = the line itself
  ElementRef element;          // a vertex, edge or face of the model
  double edge_t = 0.5;         // for an edge: where E_split would split
};

struct OverlayInput {
  const Project* project = nullptr;
  const Image* image = nullptr;
  const VpCalibrationSummary* calibration = nullptr;          // may be null
  const std::vector<ProjectedPrimitive>* model = nullptr;     // from ProjectModel
  const std::map<Id, LoadedReference>* references = nullptr;  // AppState::references; may be null
  ElementRef other_hover;                                     // hovered in the 3D panel: highlighted here too
  Tool tool = Tool::kSelect;
  Selection selection;
  Id selected_line_pin = kNoId;  // drawn highlighted (with its edge, which the selection holds)
  OverlayHover hover;
  // Pins the last solve found far beyond the others' spread (JointSolveSummary::flagged_pins):
  // drawn with a red warning ring and their distance in px. May be null.
  const std::vector<FlaggedPin>* flagged_pins = nullptr;
  // Pins proposed from the other photos (app/state/ghost_pins.h): drawn hollow, dashed, with
  // their NCC score. May be null.
  const PinProposalSummary* ghost_pins = nullptr;
};

// A ghost pin's marker radius (screen px): a click within it accepts the proposal.
constexpr float kGhostPinRadiusPx = 7.0f;

// Draws every overlay of input.image into the screen rectangle [clip_min, clip_max].
void DrawImageOverlays(ImDrawList* draw_list, const OverlayInput& input, const ViewTransform& view, ImVec2 clip_min,
                       ImVec2 clip_max, const OverlayOptions& options);

// A line between two image points, clipped to the rectangle (for previews).
void DrawImageLine(ImDrawList* draw_list, const ViewTransform& view, const Eigen::Vector2d& a_px,
                   const Eigen::Vector2d& b_px, ImVec2 clip_min, ImVec2 clip_max, ImU32 color, float thickness_px);

// The line-pin tool's preview while dragging from a_px to b_px (image pixels): the line as it
// will be stored, and dashed from the selected edge's projected ends to it.
void DrawLinePinPreview(ImDrawList* draw_list, const OverlayInput& input, const ViewTransform& view,
                        const Eigen::Vector2d& a_px, const Eigen::Vector2d& b_px, ImVec2 clip_min, ImVec2 clip_max);

// Text with a dark shadow so it reads on any photo.
void DrawShadowedText(ImDrawList* draw_list, ImVec2 pos, ImU32 color, const char* text);

}  // namespace facet::app
