#include "core/texture/photo_pyramid.h"

#include <algorithm>
#include <cmath>

namespace facet {
namespace {

ImageRgba8 HalfSize(const ImageRgba8& in) {
  ImageRgba8 out;
  out.width = std::max(1, (in.width + 1) / 2);
  out.height = std::max(1, (in.height + 1) / 2);
  out.pixels.resize(static_cast<size_t>(out.width) * out.height * 4);
  for (int y = 0; y < out.height; ++y) {
    const int y0 = std::min(2 * y, in.height - 1), y1 = std::min(2 * y + 1, in.height - 1);
    const std::uint8_t* row0 = in.At(0, y0);
    const std::uint8_t* row1 = in.At(0, y1);
    std::uint8_t* dst = out.At(0, y);
    // Whole 2 x 2 blocks without clamping, then the odd last column averaged with itself.
    const int pairs = in.width / 2;
    for (int x = 0; x < pairs; ++x) {
      const std::uint8_t* a = row0 + 8 * x;
      const std::uint8_t* b = row1 + 8 * x;
      std::uint8_t* o = dst + 4 * x;
      for (int c = 0; c < 4; ++c) o[c] = static_cast<std::uint8_t>((a[c] + a[c + 4] + b[c] + b[c + 4] + 2) / 4);
    }
    for (int x = pairs; x < out.width; ++x) {
      const int x0 = std::min(2 * x, in.width - 1) * 4, x1 = std::min(2 * x + 1, in.width - 1) * 4;
      for (int c = 0; c < 4; ++c) {
        dst[4 * x + c] = static_cast<std::uint8_t>((row0[x0 + c] + row0[x1 + c] + row1[x0 + c] + row1[x1 + c] + 2) / 4);
      }
    }
  }
  return out;
}

// Bilinear at level coordinates (x, y), edges clamped.
void Bilinear(const ImageRgba8& image, double x, double y, float rgba[4]) {
  const double fx = std::floor(x), fy = std::floor(y);
  const float ax = static_cast<float>(x - fx), ay = static_cast<float>(y - fy);
  const int ix = static_cast<int>(fx), iy = static_cast<int>(fy);
  if (ix >= 0 && iy >= 0 && ix + 1 < image.width && iy + 1 < image.height) {
    // Inside: the four pixels without clamping (nearly every tap of a bake).
    const std::uint8_t* p00 = image.At(ix, iy);
    const std::uint8_t* p01 = p00 + static_cast<size_t>(image.width) * 4;
    for (int c = 0; c < 4; ++c) {
      const float top = p00[c] + ax * (p00[c + 4] - p00[c]);
      const float bottom = p01[c] + ax * (p01[c + 4] - p01[c]);
      rgba[c] = top + ay * (bottom - top);
    }
    return;
  }
  const int x0 = std::clamp(static_cast<int>(fx), 0, image.width - 1);
  const int y0 = std::clamp(static_cast<int>(fy), 0, image.height - 1);
  const int x1 = std::clamp(static_cast<int>(fx) + 1, 0, image.width - 1);
  const int y1 = std::clamp(static_cast<int>(fy) + 1, 0, image.height - 1);
  const std::uint8_t* p00 = image.At(x0, y0);
  const std::uint8_t* p10 = image.At(x1, y0);
  const std::uint8_t* p01 = image.At(x0, y1);
  const std::uint8_t* p11 = image.At(x1, y1);
  for (int c = 0; c < 4; ++c) {
    const float top = p00[c] + ax * (p10[c] - p00[c]);
    const float bottom = p01[c] + ax * (p11[c] - p01[c]);
    rgba[c] = top + ay * (bottom - top);
  }
}

}  // namespace

PhotoPyramid::PhotoPyramid(const ImageRgba8* photo, bool build_levels) : photo_(photo) {
  if (!build_levels || photo == nullptr || photo->empty()) return;
  const ImageRgba8* previous = photo;
  while (previous->width > 1 || previous->height > 1) {
    levels_.push_back(HalfSize(*previous));
    previous = &levels_.back();
  }
}

bool PhotoPyramid::Sample(double x, double y, const Eigen::Vector2d& axis_u, const Eigen::Vector2d& axis_v,
                          float rgba[4]) const {
  if (photo_ == nullptr || !(x >= -0.5 && x <= photo_->width - 0.5 && y >= -0.5 && y <= photo_->height - 0.5)) {
    return false;
  }
  const double length_u = axis_u.norm(), length_v = axis_v.norm();
  const double footprint = std::max(length_u, length_v);
  if (!(footprint > 1.0)) {
    Bilinear(*photo_, x, y, rgba);
    return true;
  }
  // The level where the longer axis spans [2, 4) of its pixels: at most 4 x 4 taps, each a
  // bilinear lookup, whose own blur (a level pixel) stays within half the footprint.
  const int level = std::clamp(static_cast<int>(std::floor(std::log2(footprint))) - 1, 0, levels() - 1);
  const double s = std::ldexp(1.0, -level);
  const Eigen::Vector2d u = axis_u * s, v = axis_v * s;
  // |axis * 2^-level| is |axis| * 2^-level exactly: the lengths need no second square root.
  const int taps_u = std::max(1, static_cast<int>(std::ceil(length_u * s - 1e-9)));
  const int taps_v = std::max(1, static_cast<int>(std::ceil(length_v * s - 1e-9)));
  // Level k's pixel centres sit at 2^k (i + 0.5) - 0.5 in photo pixels.
  const Eigen::Vector2d centre((x + 0.5) * s - 0.5, (y + 0.5) * s - 0.5);
  const ImageRgba8& image = Level(level);
  float sum[4] = {0, 0, 0, 0};
  for (int b = 0; b < taps_v; ++b) {
    for (int a = 0; a < taps_u; ++a) {
      const Eigen::Vector2d p = centre + ((a + 0.5) / taps_u - 0.5) * u + ((b + 0.5) / taps_v - 0.5) * v;
      float tap[4];
      Bilinear(image, p.x(), p.y(), tap);
      for (int c = 0; c < 4; ++c) sum[c] += tap[c];
    }
  }
  const float inv = 1.0f / static_cast<float>(taps_u * taps_v);
  for (int c = 0; c < 4; ++c) rgba[c] = sum[c] * inv;
  return true;
}

}  // namespace facet
