// The JSON adapter of calibration from known 3D points (core/estimators/calibrate_dlt.h), the core of
// `facet calibrate --points POINTS.json`: parses the points, calibrates, formats.
//
// Input (world units of the user's choice; pixels 0-based, core/geometry/conventions.h):
//   {"image_size": [w, h],
//    "points": [{"xyz": [X, Y, Z], "uv": [u, v]}, ...],   (6 or more, or 4 or more coplanar)
//    "distortion": 0 | 1 | 2,                               (optional, default 0: radial terms)
//    "principal_point": "solve" | "center" | [cx, cy],      (optional, default "solve": free
//   for non-coplanar points; coplanar points then use the image centre, see calibrate_dlt.h)
//    "focal_px": f}                                         (optional: a known focal length,
//   held; only the pose and the free principal point are solved; refused by name outside the
//   lenses of core/geometry/camera_checks.h for this image size)
// Output (pretty JSON, doubles with enough digits to round-trip):
//   {"K": 3x3 rows, "R": 3x3 rows (cam_from_world), "t": [tx, ty, tz] (world units),
//    "focal_px": f, "principal_point": [cx, cy], "distortion": [k1, k2] (OpenCV's radial model),
//    "reprojection_rms_px": r, "initial_rms_px": r0 (linear step), "residuals_px": [...] (per
//    input point), "planar": bool, "focal_std_px": s (0 when held), "focal_fixed": bool,
//    "warnings": [...], "message": "...", "time_ms": t}
// Malformed JSON, missing fields, wrong types and input the calibration rejects give
// ok() == false with a message; nothing throws.
#pragma once

#include <string>

#include "core/io/calibrate_io.h"

namespace facet {

CalibrateIoResult CalibratePointsJson(const std::string& points_json_text);
// Reads the file at path and calls CalibratePointsJson; an unreadable file is an error.
CalibrateIoResult CalibratePointsFile(const std::string& path);

}  // namespace facet
