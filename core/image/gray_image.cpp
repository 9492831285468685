#include "core/image/gray_image.h"

#include <cassert>

namespace facet {

GrayImage GrayFromRgba(const ImageRgba8& photo, int shrink) {
  assert(shrink >= 1 && "GrayFromRgba: shrink must be at least 1");
  GrayImage gray;
  if (photo.empty() || shrink < 1) return gray;
  gray.width = photo.width / shrink;
  gray.height = photo.height / shrink;
  gray.pixels.assign(static_cast<size_t>(gray.width) * gray.height, 0.0f);
  const float norm = 1.0f / static_cast<float>(shrink * shrink);
  for (int y = 0; y < gray.height; ++y) {
    for (int x = 0; x < gray.width; ++x) {
      float sum = 0.0f;
      for (int j = 0; j < shrink; ++j) {
        for (int i = 0; i < shrink; ++i) {
          const std::uint8_t* p = photo.At(x * shrink + i, y * shrink + j);
          sum += 0.299f * p[0] + 0.587f * p[1] + 0.114f * p[2];
        }
      }
      gray.pixels[static_cast<size_t>(y) * gray.width + x] = sum * norm;
    }
  }
  return gray;
}

}  // namespace facet
