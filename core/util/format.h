// The compact number format of solver and calibration messages.
#pragma once

#include <cstdio>
#include <string>

namespace facet::internal {

// "%.<significant>g": short, exact enough for a message.
inline std::string FormatNumber(double x, int significant = 4) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*g", significant, x);
  return buffer;
}

}  // namespace facet::internal
