#include "core/geometry/image_snap.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

namespace facet {
namespace {

struct Line {
  Eigen::Vector2d origin;
  Eigen::Vector2d direction;  // unit
};

// The nearest point of segment (a, b) to p.
Eigen::Vector2d NearestOnSegment(const Eigen::Vector2d& p, const Eigen::Vector4d& s) {
  const Eigen::Vector2d a = s.head<2>(), b = s.tail<2>();
  const Eigen::Vector2d ab = b - a;
  const double length2 = ab.squaredNorm();
  if (!(length2 > 0.0)) return a;
  const double t = std::clamp((p - a).dot(ab) / length2, 0.0, 1.0);
  return a + t * ab;
}

// The line from the anchor through the vanishing point; none when they coincide.
std::optional<Line> VanishingLine(const SnapFeatures& f) {
  if (!f.has_vanishing_direction || !f.anchor_px.allFinite() || !f.vanishing_point.allFinite()) return std::nullopt;
  Eigen::Vector2d direction;
  const double w = f.vanishing_point.z();
  if (std::abs(w) < 1e-12 * f.vanishing_point.head<2>().norm()) {
    direction = f.vanishing_point.head<2>();
  } else {
    direction = f.vanishing_point.head<2>() / w - f.anchor_px;
  }
  const double n = direction.norm();
  if (!(n > 1e-9)) return std::nullopt;
  return Line{f.anchor_px, direction / n};
}

// Where the line crosses segment s (within the segment), if it does.
std::optional<Eigen::Vector2d> Crossing(const Line& line, const Eigen::Vector4d& s) {
  const Eigen::Vector2d a = s.head<2>(), ab = s.tail<2>() - s.head<2>();
  // line.origin + u * d = a + t * ab
  const double det = line.direction.x() * (-ab.y()) - line.direction.y() * (-ab.x());
  if (std::abs(det) < 1e-9 * ab.norm()) return std::nullopt;  // parallel
  const Eigen::Vector2d r = a - line.origin;
  const double t = (line.direction.x() * r.y() - line.direction.y() * r.x()) / det;
  if (t < 0.0 || t > 1.0) return std::nullopt;
  return a + t * ab;
}

// Where the supporting lines of two segments cross, when they meet at kSegmentCornerMinAngleDeg
// or more and the crossing lies within `reach` of both segments (past an end by at most that).
std::optional<Eigen::Vector2d> SegmentCorner(const Eigen::Vector4d& s1, const Eigen::Vector4d& s2, double reach) {
  const Eigen::Vector2d a = s1.head<2>(), d1 = s1.tail<2>() - a;
  const Eigen::Vector2d b = s2.head<2>(), d2 = s2.tail<2>() - b;
  const double n1 = d1.norm(), n2 = d2.norm();
  if (!(n1 > 0.0) || !(n2 > 0.0)) return std::nullopt;
  const double sine = (d1.x() * d2.y() - d1.y() * d2.x()) / (n1 * n2);
  if (std::abs(sine) < std::sin(kSegmentCornerMinAngleDeg * M_PI / 180.0)) return std::nullopt;
  // a + t d1 = b + u d2
  const Eigen::Vector2d r = b - a;
  const double det = d1.x() * d2.y() - d1.y() * d2.x();
  const double t = (r.x() * d2.y() - r.y() * d2.x()) / det;
  const Eigen::Vector2d x = a + t * d1;
  if ((NearestOnSegment(x, s1) - x).norm() > reach || (NearestOnSegment(x, s2) - x).norm() > reach) {
    return std::nullopt;
  }
  return x;
}

void Consider(SnapKind kind, const Eigen::Vector2d& candidate, const Eigen::Vector2d& pointer, double radius,
              SnapResult* best) {
  const double d = (candidate - pointer).norm();
  if (!(d <= radius) || (best->kind != SnapKind::kNone && d >= best->distance_px)) return;
  best->kind = kind;
  best->position_px = candidate;
  best->distance_px = d;
}

}  // namespace

const char* SnapKindName(SnapKind kind) {
  switch (kind) {
    case SnapKind::kNone: return "none";
    case SnapKind::kCorner: return "corner";
    case SnapKind::kSegmentEnd: return "segment end";
    case SnapKind::kModelVertex: return "model vertex";
    case SnapKind::kSegment: return "segment";
    case SnapKind::kModelEdge: return "model edge";
    case SnapKind::kVanishingPoint: return "vanishing direction";
    case SnapKind::kLineIntersection: return "crossing";
    case SnapKind::kSegmentCorner: return "segment corner";
  }
  return "?";
}

SnapResult SnapToFeatures(const Eigen::Vector2d& pointer_px, const SnapFeatures& features, double radius_px) {
  SnapResult none;
  none.position_px = pointer_px;
  if (!pointer_px.allFinite() || !(radius_px > 0.0)) return none;

  // Corners where two segments meet; the ends of those segments are where the detector (or
  // the user) stopped near the same corner, so the crossing replaces them.
  SnapResult point;  // corners, drawn segment ends, model vertices: the nearest
  std::vector<Eigen::Vector2d> replaced_ends;
  std::vector<const Eigen::Vector4d*> near;  // segments within the radius of the pointer
  for (const Eigen::Vector4d& s : features.segments) {
    if ((NearestOnSegment(pointer_px, s) - pointer_px).norm() <= radius_px) near.push_back(&s);
  }
  SnapResult segment_corner;
  for (size_t i = 0; i < near.size(); ++i) {
    for (size_t j = i + 1; j < near.size(); ++j) {
      if (const auto c = SegmentCorner(*near[i], *near[j], radius_px)) {
        Consider(SnapKind::kSegmentCorner, *c, pointer_px, radius_px, &segment_corner);
        for (const Eigen::Vector4d* s : {near[i], near[j]}) {
          replaced_ends.push_back(s->head<2>());
          replaced_ends.push_back(s->tail<2>());
        }
      }
    }
  }
  const auto replaced = [&](const Eigen::Vector2d& p) {
    return std::find(replaced_ends.begin(), replaced_ends.end(), p) != replaced_ends.end();
  };
  for (const Eigen::Vector2d& p : features.corners) Consider(SnapKind::kCorner, p, pointer_px, radius_px, &point);
  for (const Eigen::Vector2d& p : features.segment_ends) {
    if (!replaced(p)) Consider(SnapKind::kSegmentEnd, p, pointer_px, radius_px, &point);
  }
  for (const Eigen::Vector2d& p : features.model_vertices) {
    Consider(SnapKind::kModelVertex, p, pointer_px, radius_px, &point);
  }
  // A detected corner is refined on the pixels themselves: where it is near, it is the same
  // corner more exactly, so segment corners come after the points above.
  if (point.kind != SnapKind::kNone) return point;
  if (segment_corner.kind != SnapKind::kNone) return segment_corner;
  for (const Eigen::Vector2d& p : features.detected_segment_ends) {
    if (!replaced(p)) Consider(SnapKind::kSegmentEnd, p, pointer_px, radius_px, &point);
  }
  if (point.kind != SnapKind::kNone) return point;

  const std::optional<Line> vanishing = VanishingLine(features);
  if (vanishing) {
    // A crossing of the vanishing direction with a segment or an edge near the pointer.
    SnapResult crossing;
    for (const auto* lines : {&features.segments, &features.model_edges}) {
      for (const Eigen::Vector4d& s : *lines) {
        if (const auto c = Crossing(*vanishing, s)) {
          Consider(SnapKind::kLineIntersection, *c, pointer_px, radius_px, &crossing);
        }
      }
    }
    if (crossing.kind != SnapKind::kNone) return crossing;
  }

  SnapResult line;
  for (const Eigen::Vector4d& s : features.segments) {
    Consider(SnapKind::kSegment, NearestOnSegment(pointer_px, s), pointer_px, radius_px, &line);
  }
  for (const Eigen::Vector4d& s : features.model_edges) {
    Consider(SnapKind::kModelEdge, NearestOnSegment(pointer_px, s), pointer_px, radius_px, &line);
  }
  if (vanishing) {
    const Eigen::Vector2d along =
        vanishing->origin + (pointer_px - vanishing->origin).dot(vanishing->direction) * vanishing->direction;
    Consider(SnapKind::kVanishingPoint, along, pointer_px, radius_px, &line);
  }
  return line.kind != SnapKind::kNone ? line : none;
}

}  // namespace facet
