// The JSON adapter of single-image calibration (core/estimators/calibrate_vp.h), the core of
// `facet calibrate --lines LINES.json`: parses the line families, calibrates, formats.
//
// Input (pixels, 0-based, core/geometry/conventions.h):
//   {"image_size": [w, h],
//    "families": [{"axis": "x" | "y" | "z", "segments": [[x1, y1, x2, y2], ...]}, ...],
//    optional:
//    "principal_point": "solve" | "center" | [cx, cy]   ("solve" by default with three
//        families, "center" otherwise; "solve" with fewer falls back to the centre with a
//        warning; [cx, cy] may lie outside the image),
//    "focal_px": f                 a known focal length, not solved,
//    "focal_prior_px": f0, "focal_prior_std_px": s    a Gaussian prior on f (e.g. EXIF's,
//        core/image/exif.h); both or neither, and not with "focal_px",
//    "horizon": [x1, y1, x2, y2] | v    two points on the horizon, or the row of a level one;
//        with one horizontal family and a known focal length it fixes the rotation,
//    "distortion": true            radial distortion first, from the same segments
//        (core/estimators/plumb_line.h, each family a common vanishing point); the calibration then
//        runs on the undistorted segments,
//    "refit_without_outliers": bool (default true)}
// Output (pretty JSON, doubles with enough digits to round-trip; NaN and infinity as null):
//   {"focal_px": f, "focal_std_px": s (0 when fixed, null when there are too few segments),
//    "principal_point": [cx, cy], "principal_point_std_px": [sx, sy] (0 unless solved),
//    "residual_sigma_px": noise sigma estimated from the fit (dof-corrected),
//    "K": 3x3 rows, "R": 3x3 rows (cam_from_world),
//    "vanishing_point_axes": ["x", ...] (the given families in x, y, z order),
//    "vanishing_points": [[x, y] or, for a point at infinity, {"at_infinity": true,
//        "direction": [dx, dy]} (the unit image direction of its segments), ...] (same order),
//    "vanishing_points_homogeneous": [[x, y, w], ...] (unit norm, same order),
//    "vanishing_direction_std_deg", "family_angle_spread_deg",
//    "vanishing_point_to_principal_point_px" (null at infinity): per family, same order,
//    "min_family_angle_spread_deg", "min_vanishing_point_to_principal_point_px",
//    "vanishing_point_triangle_max_angle_deg" (0 unless three finite points),
//    "segment_residuals_px": [...] (per input segment, families in input order; in
//        undistorted px when "distortion" was asked),
//    "outlier_segments": [i, ...] (indices into segment_residuals_px),
//    "outlier_threshold_px": t, "refitted_without_outliers": bool,
//    "horizon_residual_px": r (only with "horizon"),
//    "distortion": {"k1", "k2", "k1_std", "center", "scale_px", "model"} (only when asked;
//        k1 = k2 = 0 with a warning when it could not be estimated),
//    "segments_per_axis": [nx, ny, nz], "warnings": [...], "message": "...", "time_ms": t}
//   core/estimators/calibrate_vp.h documents each figure.
// Malformed JSON, missing fields, wrong types, an unknown or repeated axis, and input the
// calibration rejects give ok() == false with a message; nothing throws. A known focal length
// or a prior outside the lenses of core/geometry/camera_checks.h (a prior's std below
// kMinFocalPriorRelativeStd of its value), and a horizon further than
// kMaxHorizonOffsetPerDiagonal diagonals, are refused by name. A success output has a number
// for every figure but the documented nulls (undetermined uncertainties, points at infinity).
#pragma once

#include <string>

#include <Eigen/Core>

#include "core/geometry/intrinsics_modes.h"

namespace facet {

struct CalibrateIoResult {
  std::string json;   // the output document when ok()
  std::string error;  // what was wrong, when !ok()

  bool ok() const { return error.empty(); }
};

CalibrateIoResult CalibrateLinesJson(const std::string& lines_json_text);
// Reads the file at path and calls CalibrateLinesJson; an unreadable file is an error.
CalibrateIoResult CalibrateLinesFile(const std::string& path);

// `facet calibrate --image PHOTO`: the options a LINES.json carries besides its segments.
struct CalibrateImageOptions {
  PrincipalPointMode principal_point_mode = PrincipalPointMode::kSolve;
  Eigen::Vector2d fixed_principal_point_px = Eigen::Vector2d::Zero();  // kFixed
  double focal_px = 0.0;                                               // > 0: known, not solved
  double focal_prior_px = 0.0;  // with focal_prior_std_px > 0: a Gaussian prior
  double focal_prior_std_px = 0.0;
  std::string focal_prior_source;  // e.g. the EXIF message; written out when not empty
};

// Detects the line families of the photo (core/estimators/line_detection.h) and calibrates
// them exactly as CalibrateLinesJson calibrates the LINES.json they make. Output: that
// document, plus
//   "lines": the LINES.json (image_size, families x, y, z as found, principal_point and the
//       focal options), to re-use or edit,
//   "detection": {"segments": n (kept by the length threshold), "outlier_segments": [[x1, y1,
//       x2, y2], ...] (in no family), "min_length_px", "inlier_distance_px", "search_focal_px",
//       "detection_ms", "search_ms"},
//   "focal_prior_source" (when given).
// An unreadable or corrupt photo, and photos whose lines give no camera (blank, one
// direction), are errors with the detector's message.
CalibrateIoResult CalibrateImageFile(const std::string& photo_path, const CalibrateImageOptions& options);

}  // namespace facet
