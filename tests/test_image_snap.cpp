// Snapping in image pixels (core/geometry/image_snap.h): points win over lines, the nearest
// within the radius, the vanishing direction and its crossings, corners where two segments meet.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>

#include "core/geometry/image_snap.h"

namespace facet {
namespace {

constexpr double kTol = 1e-12;

TEST_CASE("nothing within the radius leaves the pointer where it is") {
  SnapFeatures f;
  f.corners = {{100, 100}};
  f.segments = {{0, 0, 50, 0}};
  const SnapResult r = SnapToFeatures({10, 20}, f, 5.0);
  CHECK(r.kind == SnapKind::kNone);
  CHECK((r.position_px - Eigen::Vector2d(10, 20)).norm() == 0.0);
}

TEST_CASE("a corner within the radius wins over a nearer segment") {
  SnapFeatures f;
  f.corners = {{13, 3}};
  f.segments = {{0, 0, 50, 0}};  // 1 px below the pointer
  const SnapResult r = SnapToFeatures({10, 1}, f, 5.0);
  CHECK(r.kind == SnapKind::kCorner);
  CHECK((r.position_px - Eigen::Vector2d(13, 3)).norm() < kTol);
  CHECK(r.distance_px == doctest::Approx(std::hypot(3.0, 2.0)));
}

TEST_CASE("the nearest of several points, whatever its kind") {
  SnapFeatures f;
  f.corners = {{14, 10}};
  f.segment_ends = {{10, 12.5}};
  f.model_vertices = {{11, 11}};
  const SnapResult r = SnapToFeatures({10, 10}, f, 5.0);
  CHECK(r.kind == SnapKind::kModelVertex);
  CHECK((r.position_px - Eigen::Vector2d(11, 11)).norm() < kTol);
}

TEST_CASE("a detected segment's end only when no corner, drawn end or vertex is near") {
  SnapFeatures f;
  f.detected_segment_ends = {{10.5, 10}};
  f.corners = {{12, 12}};
  SnapResult r = SnapToFeatures({10, 10}, f, 5.0);
  CHECK(r.kind == SnapKind::kCorner);
  f.corners.clear();
  r = SnapToFeatures({10, 10}, f, 5.0);
  CHECK(r.kind == SnapKind::kSegmentEnd);
  CHECK((r.position_px - Eigen::Vector2d(10.5, 10)).norm() < kTol);
}

TEST_CASE("onto a segment, only within its extent") {
  SnapFeatures f;
  f.segments = {{0, 0, 40, 40}};
  const SnapResult on = SnapToFeatures({22, 18}, f, 5.0);
  CHECK(on.kind == SnapKind::kSegment);
  CHECK((on.position_px - Eigen::Vector2d(20, 20)).norm() < 1e-9);
  // Beyond the end the nearest point is the end itself, 5.8 px away: outside the radius.
  CHECK(SnapToFeatures({45, 43}, f, 5.0).kind == SnapKind::kNone);
}

TEST_CASE("a model edge and a segment: the nearer line") {
  SnapFeatures f;
  f.segments = {{0, 0, 100, 0}};
  f.model_edges = {{0, 4, 100, 4}};
  CHECK(SnapToFeatures({50, 3}, f, 5.0).kind == SnapKind::kModelEdge);
  CHECK(SnapToFeatures({50, 1}, f, 5.0).kind == SnapKind::kSegment);
}

TEST_CASE("the vanishing direction: a finite vanishing point and one at infinity") {
  SnapFeatures f;
  f.has_vanishing_direction = true;
  f.anchor_px = {100, 100};
  f.vanishing_point = Eigen::Vector3d(1100, 100, 1.0) * 0.5;  // (1100, 100), scaled homogeneous
  SnapResult r = SnapToFeatures({300, 103}, f, 5.0);
  CHECK(r.kind == SnapKind::kVanishingPoint);
  CHECK((r.position_px - Eigen::Vector2d(300, 100)).norm() < 1e-9);
  // The end rotates onto the line: the direction from the anchor is the vanishing point's.
  const Eigen::Vector2d along = (r.position_px - f.anchor_px).normalized();
  CHECK(std::abs(along.y()) < 1e-12);

  f.vanishing_point = {0.0, 1.0, 0.0};  // vertical, at infinity
  r = SnapToFeatures({102, 300}, f, 5.0);
  CHECK(r.kind == SnapKind::kVanishingPoint);
  CHECK((r.position_px - Eigen::Vector2d(100, 300)).norm() < 1e-9);
  // Too far from the line.
  CHECK(SnapToFeatures({110, 300}, f, 5.0).kind == SnapKind::kNone);
}

TEST_CASE("where the vanishing direction crosses an edge, the crossing wins") {
  SnapFeatures f;
  f.has_vanishing_direction = true;
  f.anchor_px = {0, 0};
  f.vanishing_point = {1.0, 1.0, 0.0};  // the diagonal
  f.model_edges = {{50, 0, 50, 100}};   // x = 50 crosses it at (50, 50)
  const SnapResult r = SnapToFeatures({51, 47}, f, 5.0);
  CHECK(r.kind == SnapKind::kLineIntersection);
  CHECK((r.position_px - Eigen::Vector2d(50, 50)).norm() < 1e-9);
  // An edge that the direction would cross outside its extent offers no crossing.
  f.model_edges = {{50, 60, 50, 100}};
  CHECK(SnapToFeatures({51, 49}, f, 5.0).kind == SnapKind::kVanishingPoint);
}

TEST_CASE("degenerate input never snaps to nonsense") {
  SnapFeatures f;
  f.corners = {{1, 1}};
  const double nan = std::numeric_limits<double>::quiet_NaN();
  CHECK(SnapToFeatures({nan, 1}, f, 5.0).kind == SnapKind::kNone);
  CHECK(SnapToFeatures({1, 1}, f, 0.0).kind == SnapKind::kNone);
  // A vanishing point on the anchor gives no direction; a zero-length segment is its end.
  f.corners.clear();
  f.has_vanishing_direction = true;
  f.anchor_px = {5, 5};
  f.vanishing_point = {5, 5, 1};
  f.segments = {{20, 20, 20, 20}};
  CHECK(SnapToFeatures({30, 5}, f, 5.0).kind == SnapKind::kNone);
  const SnapResult r = SnapToFeatures({21, 21}, f, 5.0);
  CHECK(r.kind == SnapKind::kSegment);
  CHECK((r.position_px - Eigen::Vector2d(20, 20)).norm() < kTol);
}


TEST_CASE("two segments stopping short of a corner: their lines' crossing, not their ends") {
  // A vertical and a horizontal edge, each stopped 3 px before the corner (20, 30), as a
  // segment detector leaves them.
  SnapFeatures f;
  f.segments = {{20, 80, 20, 33}, {70, 30, 23, 30}};
  f.segment_ends = {{20, 80}, {20, 33}, {70, 30}, {23, 30}};  // e.g. accepted as drawn lines
  SnapResult r = SnapToFeatures({22, 32}, f, 6.0);
  CHECK(r.kind == SnapKind::kSegmentCorner);
  CHECK((r.position_px - Eigen::Vector2d(20, 30)).norm() < kTol);
  // Two nearly parallel segments make no corner: the nearest end stays.
  f.segments = {{20, 80, 20, 33}, {20.5, 33, 21, 10}};
  f.segment_ends = {{20, 33}};
  r = SnapToFeatures({22, 32}, f, 6.0);
  CHECK(r.kind == SnapKind::kSegmentEnd);
  // A crossing beyond the radius of either segment's extent is no corner.
  f.segments = {{20, 80, 20, 45}, {70, 30, 23, 30}};
  f.segment_ends.clear();
  r = SnapToFeatures({21, 33}, f, 6.0);
  CHECK(r.kind != SnapKind::kSegmentCorner);
}

TEST_CASE("a detected corner near a segment corner wins: it is refined on the pixels") {
  SnapFeatures f;
  f.segments = {{20, 80, 20, 33}, {70, 30, 23, 30}};
  f.corners = {{20.2, 30.1}};
  const SnapResult r = SnapToFeatures({20.1, 30.0}, f, 6.0);  // nearer the segment corner
  CHECK(r.kind == SnapKind::kCorner);
  CHECK((r.position_px - Eigen::Vector2d(20.2, 30.1)).norm() < kTol);
}

}  // namespace
}  // namespace facet
