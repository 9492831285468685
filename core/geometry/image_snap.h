// Snapping a pointer in a photo to what is already there: points (image corners, segment
// ends, the model's projected vertices), lines (segments, the model's projected edges) and,
// for a segment being drawn, the direction to its family's vanishing point. Pure geometry in
// image pixels; the image panel decides which features to offer and draws the result.
#pragma once

#include <vector>

#include <Eigen/Core>

namespace facet {

enum class SnapKind {
  kNone,
  kCorner,           // an image corner (refined to sub-pixel)
  kSegmentEnd,       // an end of a drawn or detected segment
  kModelVertex,      // a projected vertex of the model
  kSegment,          // onto a drawn or detected segment (its supporting line, within its extent)
  kModelEdge,        // onto a projected edge of the model
  kVanishingPoint,   // rotated onto the line from the anchor through the family's vanishing point
  kLineIntersection,  // where two of the lines above cross (e.g. a vanishing direction and an edge)
  kSegmentCorner      // where two segments at an angle meet near their ends: a corner in the photo
};
const char* SnapKindName(SnapKind kind);  // "corner", "segment end", ...

struct SnapFeatures {
  std::vector<Eigen::Vector2d> corners;
  std::vector<Eigen::Vector2d> segment_ends;
  std::vector<Eigen::Vector2d> model_vertices;
  // Ends of automatically detected segments: where the detector stopped, less exact than a
  // corner, so taken only when none of the points above is within the radius.
  std::vector<Eigen::Vector2d> detected_segment_ends;
  std::vector<Eigen::Vector4d> segments;     // x1, y1, x2, y2
  std::vector<Eigen::Vector4d> model_edges;  // x1, y1, x2, y2
  // The direction constraint of a segment being drawn: its fixed end and its family's
  // vanishing point (homogeneous, third coordinate 0 for a point at infinity).
  bool has_vanishing_direction = false;
  Eigen::Vector2d anchor_px = Eigen::Vector2d::Zero();
  Eigen::Vector3d vanishing_point = Eigen::Vector3d::Zero();
};

struct SnapResult {
  SnapKind kind = SnapKind::kNone;
  Eigen::Vector2d position_px = Eigen::Vector2d::Zero();  // the pointer itself when kNone
  double distance_px = 0.0;                               // from the pointer to position_px
};

// The snapped position of `pointer_px` within `radius_px` (image pixels: the panel converts
// its few screen pixels with the zoom). Points win over lines: a point within the radius is
// taken even when a line is nearer, since the user aims at corners; among points the nearest
// (detected segment ends only when no other point is near). Two segments near the pointer at
// an angle of kSegmentCornerMinAngleDeg or more make a point too: their supporting lines'
// crossing (a segment detector stops a few pixels short of a corner, but its line is exact),
// which replaces the ends of those two segments as candidates; it is taken when no corner,
// drawn end or vertex is near (a detected corner is refined on the pixels), before detected
// segment ends.
// Among lines (segments, edges, the vanishing direction) the nearest, except that where the
// vanishing direction and another line cross within the radius, the crossing is taken (a
// segment drawn towards its vanishing point that ends on an edge). A non-finite pointer
// gives kNone.
constexpr double kSegmentCornerMinAngleDeg = 20.0;
SnapResult SnapToFeatures(const Eigen::Vector2d& pointer_px, const SnapFeatures& features, double radius_px);

}  // namespace facet
