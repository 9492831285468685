// Lines found for the user: line segments detected on a photo, grouped into the three
// orthogonal (Manhattan) vanishing directions plus outliers, then calibrated by the
// maximum-likelihood fit of core/estimators/calibrate_vp.h.
//
// Detection: OpenCV's line segment detector (LSD, von Gioi et al., PAMI 2010) on the
// full-resolution grey image; its endpoints are sub-pixel, pixel centres at integers (Facet's
// convention). Segments shorter than a fraction of the image diagonal are dropped: short
// segments fix a direction poorly and are mostly texture. Photos of 2 MP or more are detected
// in four horizontal bands in parallel (LSD is local; one thread per core, at most four), and
// the pieces of a line cut by a band boundary are joined again. The band count is fixed, so
// every machine finds the same segments.
//
// Grouping: a RANSAC search over minimal sets that each give a whole orthogonal frame
// (rotation and focal length), principal point at the image centre (or the fixed one):
// - four segments: two pairs give two vanishing points; their orthogonality gives f
//   (f^2 = -(v1 - c).(v2 - c)) and the third direction is the cross product (Wildenauer &
//   Hanbury, CVPR 2012, without their distortion term);
// - three segments with a focal length drawn from the prior (or log-uniformly over the
//   plausible range): two give a vanishing direction, the third's back-projected plane
//   fixes the second direction orthogonal to it (Lu et al., "2-line exhaustive searching",
//   WACV 2017), which works with a vanishing point at infinity where the four-segment set
//   cannot give f.
// Each hypothesis is scored by MSAC over all segments, each weighted by its length, with the
// endpoint-distance residual of calibrate_vp (distance of the endpoints to the line through the
// segment's midpoint and the vanishing point). The best frame's inliers, each assigned to its
// nearest vanishing point, feed CalibrateFromVanishingLines; the segments are then reassigned
// to the fitted camera's vanishing points and fitted once more. A segment within the inlier
// distance of two vanishing points (e.g. on the horizon) is ambiguous and left out.
//
// Naming (arbitrary from detection, so fixed by a rule): z is the family whose vanishing
// direction is closest to the image vertical (largest |camera y|), x the one of the other two
// closest to the image horizontal (largest |camera x|), y the last. Segments carry no sign;
// calibrate_vp chooses the rotation's signs (world z up in the image).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/estimators/calibrate_vp.h"
#include "core/geometry/segment.h"
#include "core/image/image_io.h"
#include "core/optim/solver_summary.h"

namespace facet {

struct LineDetectionOptions {
  // Segments shorter than this fraction of the image diagonal are dropped (20 px at 640 x 480).
  double min_length_rel_diagonal = 0.025;
};

// Raw detection: (x1, y1, x2, y2) per segment in px, of length >= the threshold. An empty or
// zero-sized image gives no segments.
std::vector<Eigen::Vector4d> DetectLineSegments(const ImageRgba8& image, const LineDetectionOptions& options);

struct ManhattanLinesOptions {
  LineDetectionOptions detection;
  // The calibration: width_px, height_px are set from the image (or must be set for
  // GroupManhattanLines); principal point mode, focal prior or fixed focal length pass
  // through. A fixed principal point is also the one the search assumes; otherwise the
  // image centre.
  VpCalibrationOptions calibration;
  // Inlier distance of the search: endpoint distance in px as a fraction of the image
  // diagonal (2 px at 640 x 480). Lens distortion bends lines in proportion to the image
  // size, hence relative; never below 1 px, LSD's own accuracy.
  double inlier_distance_rel_diagonal = 0.0025;
  // Plausible focal lengths for the search, as a fraction of the image diagonal: a 35 mm
  // equivalent of 12 mm to 170 mm (f / diagonal = f35 / 43.3).
  double min_focal_rel_diagonal = 0.28;
  double max_focal_rel_diagonal = 4.0;
  int num_hypotheses = 3000;
  // A family with fewer segments is dropped (two segments always meet somewhere).
  int min_segments_per_family = 3;
  std::uint32_t seed = 1;  // the search is deterministic for a given seed
};

// SolverSummary: termination and message those of the calibration (or why it could not run);
// iterations the calibration's; time_ms the whole of detection, search and calibration.
struct ManhattanLinesSummary : SolverSummary {
  int width_px = 0;
  int height_px = 0;
  // Every segment the detector kept (length threshold passed), and per segment its family
  // (0, 1, 2 for x, y, z) or -1 (outlier or ambiguous).
  std::vector<Eigen::Vector4d> segments_px;
  std::vector<int> segment_family;
  // The segments given to the final calibration, in segments_px order, with their axis.
  std::vector<Segment> labelled_segments;
  std::array<int, 3> segments_per_family = {0, 0, 0};
  int num_outliers = 0;
  // The best hypothesis of the search: its focal length and its score (sum over inliers of
  // length * (1 - (r / t)^2), px).
  double search_focal_px = 0.0;
  double search_score = 0.0;
  int num_hypotheses_scored = 0;
  double min_length_px = 0.0;
  double inlier_distance_px = 0.0;
  double detection_ms = 0.0;
  double search_ms = 0.0;
  double calibration_ms = 0.0;
  VpCalibrationSummary calibration;  // of labelled_segments
};

// Detects, groups and calibrates. A blank or tiny image, too few segments, or only one
// direction give a summary that is not IsUsable() with a message saying which; never throws.
ManhattanLinesSummary DetectManhattanLines(const ImageRgba8& image, const ManhattanLinesOptions& options);
// The grouping and calibration alone, on given segments (options.calibration's image size
// must be set).
ManhattanLinesSummary GroupManhattanLines(const std::vector<Eigen::Vector4d>& segments_px,
                                          const ManhattanLinesOptions& options);

}  // namespace facet
