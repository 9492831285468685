// The JSON adapter of single-image calibration (core/calibrate_vp.h), the core of
// `facet calibrate --lines LINES.json`: parses the line families, calibrates, formats.
//
// Input (pixels, 0-based, core/conventions.h):
//   {"image_size": [w, h],
//    "families": [{"axis": "x" | "y" | "z", "segments": [[x1, y1, x2, y2], ...]}, ...],
//    "principal_point": "solve" | "center" | [cx, cy]}   (optional: "solve" with three
//   families, "center" with two; "solve" with two falls back to the centre with a warning)
// Output (pretty JSON, doubles with enough digits to round-trip):
//   {"focal_px": f, "principal_point": [cx, cy], "K": 3x3 rows, "R": 3x3 rows (cam_from_world),
//    "vanishing_point_axes": ["x", ...] (the given families in x, y, z order),
//    "vanishing_points": [[x, y] or null for a point at infinity, ...] (same order),
//    "vanishing_points_homogeneous": [[x, y, w], ...] (unit norm, same order),
//    "segment_residuals_px": [...] (per input segment, families in input order),
//    "segments_per_axis": [nx, ny, nz], "warnings": [...], "message": "...", "time_ms": t}
// Malformed JSON, missing fields, wrong types, an unknown or repeated axis, and input the
// calibration rejects give ok() == false with a message; nothing throws.
#pragma once

#include <string>

namespace facet {

struct CalibrateIoResult {
  std::string json;   // the output document when ok()
  std::string error;  // what was wrong, when !ok()

  bool ok() const { return error.empty(); }
};

CalibrateIoResult CalibrateLinesJson(const std::string& lines_json_text);
// Reads the file at path and calls CalibrateLinesJson; an unreadable file is an error.
CalibrateIoResult CalibrateLinesFile(const std::string& path);

}  // namespace facet
