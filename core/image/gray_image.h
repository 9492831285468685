// A photo as grey levels in float, for matching windows between photos (core/solve/
// pin_proposals.h): luma of the RGBA photo, optionally shrunk by an integer factor.
#pragma once

#include <algorithm>
#include <vector>

#include "core/image/image_io.h"

namespace facet {

// Row-major, top row first, grey levels in [0, 255]. Pixel centres at integers
// (core/geometry/conventions.h).
struct GrayImage {
  int width = 0;
  int height = 0;
  std::vector<float> pixels;

  bool empty() const { return width <= 0 || height <= 0; }
  float At(int x, int y) const { return pixels[static_cast<size_t>(y) * width + x]; }
  // Bilinear value at (x, y); false (value untouched) unless the four pixels around it are
  // inside the image, i.e. x in [0, width - 1], y in [0, height - 1].
  bool Sample(double x, double y, float* value) const {
    if (!(x >= 0.0 && y >= 0.0 && x <= width - 1 && y <= height - 1)) return false;
    const int x0 = std::min(static_cast<int>(x), width - 2 < 0 ? 0 : width - 2);
    const int y0 = std::min(static_cast<int>(y), height - 2 < 0 ? 0 : height - 2);
    const int x1 = std::min(x0 + 1, width - 1), y1 = std::min(y0 + 1, height - 1);
    const float fx = static_cast<float>(x - x0), fy = static_cast<float>(y - y0);
    const float top = At(x0, y0) + fx * (At(x1, y0) - At(x0, y0));
    const float bottom = At(x0, y1) + fx * (At(x1, y1) - At(x0, y1));
    *value = top + fy * (bottom - top);
    return true;
  }
};

// The photo's luma (0.299 R + 0.587 G + 0.114 B), each `shrink` x `shrink` block averaged into
// one pixel (shrink >= 1; a partial block at the right or bottom edge is dropped). Pixel i of
// the result is centred on photo pixel i * shrink + (shrink - 1) / 2, so a photo pixel uv maps
// to (uv + 0.5) / shrink - 0.5.
GrayImage GrayFromRgba(const ImageRgba8& photo, int shrink = 1);

}  // namespace facet
