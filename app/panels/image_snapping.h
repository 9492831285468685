// Snapping in the image panel: what a new segment end, a pin or a line pin may snap to
// (core/geometry/image_snap.h), the photo's own features (corners, core/image/corner_detection.h,
// and line segments, core/estimators/line_detection.h, found once per photo on a worker
// thread), and the marker drawn at the target before the click.
#pragma once

#include <future>
#include <map>
#include <vector>

#include <imgui.h>
#include <Eigen/Core>

#include "app/state/app_state.h"
#include "app/state/model_pick.h"
#include "core/geometry/image_snap.h"
#include "core/estimators/line_detection.h"
#include "core/image/corner_detection.h"

namespace facet::app {

// Snap targets fit in this many screen pixels of the pointer (the panel divides by the zoom).
constexpr double kSnapRadiusScreenPx = 8.0;

// What the current tool or drag is placing, and what it must not snap to (itself).
struct SnapRequest {
  bool active = false;
  Id exclude_segment = kNoId;    // the segment whose end is dragged
  Id exclude_primitive = kNoId;  // the primitive whose vertex or edge is being pinned
  bool vanishing_direction = false;
  Axis axis = Axis::kX;
  Eigen::Vector2d anchor_px = Eigen::Vector2d::Zero();  // the segment's fixed end
};

// What a photo offers to snap to by itself.
struct PhotoSnapFeatures {
  std::vector<Eigen::Vector2d> corners;
  std::vector<Eigen::Vector4d> segments;  // the line segment detector's, x1, y1, x2, y2
};

// Features per image, found on a worker thread from a copy of the photo. With
// BakeMode::kFinishNextFrame (offscreen scripts) the first request waits for them, so a
// script snaps the same way however fast the machine is.
class PhotoFeatures {
 public:
  // The features of the image's loaded photo; null while they are being found or without a photo.
  const PhotoSnapFeatures* Get(const AppState& state, Id image_id);
  // Forgets images that left the project or whose photo changed.
  void CollectGarbage(const AppState& state);

 private:
  struct Entry {
    const std::uint8_t* pixels = nullptr;  // the photo the corners belong to
    std::future<PhotoSnapFeatures> pending;
    PhotoSnapFeatures features;
    bool ready = false;
  };
  std::map<Id, Entry> entries_;
};

// The features of `image` that `request` may snap to: the photo's corners and detected
// segments with their ends, the image's drawn segments and their ends, the projected model's
// vertices and edges in front of the camera, and the vanishing direction of the segment's
// family when the image is calibrated.
SnapFeatures CollectSnapFeatures(const AppState& state, const Image& image, const std::vector<ProjectedPrimitive>& model,
                                 const PhotoSnapFeatures* photo, const SnapRequest& request);

// A diamond at the target and its kind's name beside it.
void DrawSnapMarker(ImDrawList* draw_list, ImVec2 screen, SnapKind kind, bool with_label);

}  // namespace facet::app
