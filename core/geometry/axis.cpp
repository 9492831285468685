#include "core/geometry/axis.h"

namespace facet {

const char* AxisName(Axis axis) {
  switch (axis) {
    case Axis::kX: return "x";
    case Axis::kY: return "y";
    case Axis::kZ: return "z";
  }
  return "?";
}

std::optional<Axis> AxisFromName(const std::string& name) {
  if (name == "x") return Axis::kX;
  if (name == "y") return Axis::kY;
  if (name == "z") return Axis::kZ;
  return std::nullopt;
}

}  // namespace facet
