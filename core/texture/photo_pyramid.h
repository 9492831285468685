// A photo's mip pyramid for sampling it down without aliasing: level 0 is the photo itself
// (read in place, never copied), level k + 1 the 2 x 2 box average of level k (an odd last
// row or column averaged with itself), down to 1 x 1. Sampling averages the photo over the
// texel's footprint, the parallelogram spanned by the texel's two axes in photo pixels: on the
// level where the longer axis spans 2 to 4 pixels, ceil(length) bilinear taps per axis spread
// evenly over the parallelogram (area averaging; the pyramid bounds the taps at 4 x 4). A
// footprint within one pixel is a plain bilinear lookup of the photo. Unlike a trilinear mip
// lookup, the average does not reach beyond the footprint by more than a level's pixel, so a
// texel near a face's outline does not pick up the neighbour's colour.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "core/image/image_io.h"

namespace facet {

class PhotoPyramid {
 public:
  PhotoPyramid() = default;
  // Keeps a pointer to `photo`, which must outlive the pyramid unchanged. With
  // build_levels false only level 0 exists (every sample is bilinear).
  PhotoPyramid(const ImageRgba8* photo, bool build_levels);

  int width() const { return photo_ == nullptr ? 0 : photo_->width; }
  int height() const { return photo_ == nullptr ? 0 : photo_->height; }
  int levels() const { return static_cast<int>(levels_.size()) + (photo_ != nullptr ? 1 : 0); }

  // RGBA at photo pixel (x, y) (centres at integers; the photo covers [-0.5, w - 0.5]) averaged
  // over the footprint spanned by axis_u and axis_v (photo px per texel step; zero vectors: a
  // bilinear lookup), as floats in [0, 255]. False (rgba untouched) outside the photo.
  bool Sample(double x, double y, const Eigen::Vector2d& axis_u, const Eigen::Vector2d& axis_v, float rgba[4]) const;

 private:
  const ImageRgba8& Level(int k) const { return k == 0 ? *photo_ : levels_[k - 1]; }
  const ImageRgba8* photo_ = nullptr;
  std::vector<ImageRgba8> levels_;  // levels 1, 2, ...
};

}  // namespace facet
