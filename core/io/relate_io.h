// The JSON adapter of two-view geometry (core/estimators/two_view.h), the core of
// `facet relate --matches MATCHES.json`: parses the matches, estimates F (and the relative
// pose when intrinsics are given), formats.
//
// Input (pixels, 0-based, core/geometry/conventions.h):
//   {"image_sizes": [[w1, h1], [w2, h2]],
//    "matches": [[u1, v1, u2, v2], ...]            (7 to kMaxRelateMatches, core/util/input_limits.h),
//    "K": [K1, K2]}                                 (optional; each 3x3 rows)
// Output (pretty JSON, doubles with enough digits to round-trip):
//   {"F": 3x3 rows (x2^T F x1 = 0, unit Frobenius norm, largest entry positive),
//    "symmetric_epipolar_rms_px": r (RMS over the inliers of both point-to-line distances),
//    "inliers": [bool per match], "outliers": [indices], "warnings": [...], "message": "...",
//    and with "K": "E": 3x3 ([t]x R), "R": 3x3 and "t": [x, y, z] (cam2_from_cam1, |t| = 1),
//    "points_in_front": n, "pose_symmetric_epipolar_rms_px": r, "time_ms": t}
// Malformed JSON, missing fields, wrong types and input the estimation rejects give
// ok() == false with a message; nothing throws.
#pragma once

#include <string>

namespace facet {

struct RelateIoResult {
  std::string json;   // the output document when ok()
  std::string error;  // what was wrong, when !ok()

  bool ok() const { return error.empty(); }
};

RelateIoResult RelateMatchesJson(const std::string& matches_json_text);
// Reads the file at path and calls RelateMatchesJson; an unreadable file is an error.
RelateIoResult RelateMatchesFile(const std::string& path);

}  // namespace facet
