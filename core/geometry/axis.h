// The world axes a line family or a box edge can be parallel to (core/geometry/conventions.h:
// z is up).
#pragma once

#include <optional>
#include <string>

namespace facet {

enum class Axis { kX = 0, kY = 1, kZ = 2 };
const char* AxisName(Axis axis);                            // "x", "y", "z"
std::optional<Axis> AxisFromName(const std::string& name);  // inverse of AxisName

}  // namespace facet
