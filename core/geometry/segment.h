// A user-drawn (or detected) line segment in one image, assigned to a vanishing-point family.
#pragma once

#include <Eigen/Core>

#include "core/geometry/axis.h"
#include "core/geometry/ids.h"

namespace facet {

struct Segment {
  Id id = kNoId;
  Id image_id = kNoId;
  Axis axis = Axis::kX;
  Eigen::Vector2d a_px = Eigen::Vector2d::Zero();
  Eigen::Vector2d b_px = Eigen::Vector2d::Zero();
};

inline bool operator==(const Segment& a, const Segment& b) {
  return a.id == b.id && a.image_id == b.image_id && a.axis == b.axis && a.a_px == b.a_px && a.b_px == b.b_px;
}

}  // namespace facet
