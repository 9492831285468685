// Image corners for snapping (core/geometry/image_snap.h): Shi-Tomasi corners (the smaller
// eigenvalue of the gradient's structure tensor) found on a copy of the photo no larger than
// `detection_max_side_px`, then refined to sub-pixel on the full-resolution photo with
// cv::cornerSubPix (the least-squares point where the gradients around it are orthogonal to
// the lines towards it). Building corners, window corners and timber crossings are what the
// user pins, so snapping to them places a pin to a fraction of a pixel.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/image/image_io.h"

namespace facet {

struct CornerDetectionOptions {
  int max_corners = 1500;
  // A corner's response must reach this fraction of the strongest one in the photo.
  double quality_level = 0.02;
  // Corners closer than this fraction of the photo's diagonal are thinned to the strongest.
  double min_distance_fraction = 0.006;
  // Detection runs on a copy scaled to this longest side (12 MP photos in a few tens of ms);
  // the refinement always runs at full resolution.
  int detection_max_side_px = 1600;
  int refine_half_window_px = 4;

  bool Check(std::string* error) const;
};

struct CornerDetectionResult {
  std::vector<Eigen::Vector2d> corners_px;  // pixel centres at integers (core/geometry/conventions.h)
  std::string error;                        // empty on success
  double time_ms = 0.0;
  bool ok() const { return error.empty(); }
};

CornerDetectionResult DetectCorners(const ImageRgba8& image, const CornerDetectionOptions& options = {});

}  // namespace facet
