#include "core/io/calibrate_io.h"

#include <cmath>
#include <limits>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/io/json_io_internal.h"

#include "core/estimators/calibrate_vp.h"
#include "core/estimators/line_detection.h"
#include "core/estimators/plumb_line.h"
#include "core/geometry/camera_checks.h"
#include "core/image/image_io.h"
#include "core/util/input_limits.h"
#include "core/util/utf8.h"

namespace facet {
namespace {

using json_io::ReadNumber;
using json_io::Rows;
using nlohmann::json;

CalibrateIoResult Error(std::string message) {
  CalibrateIoResult result;
  result.error = std::move(message);
  return result;
}

// Fills *error and returns false when the document does not have the documented shape.
// An optional positive number; false with *error for any other value.
bool ReadOptionalPositive(const json& doc, const char* key, double* out, std::string* error) {
  const auto it = doc.find(key);
  if (it == doc.end()) return true;
  if (!ReadNumber(*it, out) || !(*out > 0.0)) {
    *error = std::string("\"") + key + "\" must be a positive number, got " + it->dump();
    return false;
  }
  return true;
}

json FiniteOrNull(double value) { return std::isfinite(value) ? json(value) : json(nullptr); }

bool ReadOptionalBool(const json& doc, const char* key, bool* out, std::string* error) {
  const auto it = doc.find(key);
  if (it == doc.end()) return true;
  if (!it->is_boolean()) {
    *error = std::string("\"") + key + "\" must be true or false, got " + it->dump();
    return false;
  }
  *out = it->get<bool>();
  return true;
}

bool ParseInput(const json& doc, std::vector<Segment>* segments, VpCalibrationOptions* options,
                std::vector<int>* family_order, bool* distortion, std::string* error) {
  if (!doc.is_object()) {
    *error = "the top level must be a JSON object";
    return false;
  }
  const auto size_it = doc.find("image_size");
  if (size_it == doc.end()) {
    *error = "missing \"image_size\": [width, height]";
    return false;
  }
  double w = 0, h = 0;
  if (!size_it->is_array() || size_it->size() != 2 || !ReadNumber((*size_it)[0], &w) ||
      !ReadNumber((*size_it)[1], &h) || w != std::floor(w) || h != std::floor(h) || w < 1 || h < 1 || w > 1e9 ||
      h > 1e9) {
    *error = "\"image_size\" must be [width, height], two positive integers, got " + size_it->dump();
    return false;
  }
  options->width_px = static_cast<int>(w);
  options->height_px = static_cast<int>(h);

  const auto families_it = doc.find("families");
  if (families_it == doc.end()) {
    *error = "missing \"families\": [{\"axis\": \"x\", \"segments\": [[x1, y1, x2, y2], ...]}, ...]";
    return false;
  }
  if (!families_it->is_array()) {
    *error = "\"families\" must be an array";
    return false;
  }
  // Counted before any is read: a million segments are refused at once (input_limits.h).
  size_t total_segments = 0;
  for (const json& family : *families_it) {
    if (!family.is_object()) continue;
    const auto segments_it = family.find("segments");
    if (segments_it != family.end() && segments_it->is_array()) total_segments += segments_it->size();
  }
  if (total_segments > kMaxCalibrationSegments) {
    *error = "a calibration takes at most " + std::to_string(kMaxCalibrationSegments) +
             " line segments; this file has " + std::to_string(total_segments);
    return false;
  }
  std::array<bool, 3> seen{};
  for (size_t f = 0; f < families_it->size(); ++f) {
    const json& family = (*families_it)[f];
    const std::string where = "families[" + std::to_string(f) + "]";
    if (!family.is_object()) {
      *error = where + " must be an object with \"axis\" and \"segments\"";
      return false;
    }
    const auto axis_it = family.find("axis");
    if (axis_it == family.end() || !axis_it->is_string()) {
      *error = where + ": missing \"axis\" (\"x\", \"y\" or \"z\")";
      return false;
    }
    const std::optional<Axis> axis = AxisFromName(axis_it->get<std::string>());
    if (!axis) {
      *error = where + ": unknown axis " + axis_it->dump() + " (expected \"x\", \"y\" or \"z\")";
      return false;
    }
    const int a = static_cast<int>(*axis);
    if (seen[a]) {
      *error = where + ": axis \"" + AxisName(*axis) + "\" is given twice";
      return false;
    }
    seen[a] = true;
    family_order->push_back(a);
    const auto segments_it = family.find("segments");
    if (segments_it == family.end() || !segments_it->is_array()) {
      *error = where + ": missing \"segments\": [[x1, y1, x2, y2], ...]";
      return false;
    }
    for (size_t i = 0; i < segments_it->size(); ++i) {
      const json& s = (*segments_it)[i];
      double c[4];
      bool ok = s.is_array() && s.size() == 4;
      for (int k = 0; ok && k < 4; ++k) ok = ReadNumber(s[k], &c[k]);
      if (!ok) {
        *error = where + ".segments[" + std::to_string(i) + "] must be [x1, y1, x2, y2], four finite numbers, got " +
                 s.dump();
        return false;
      }
      Segment segment;
      segment.axis = *axis;
      segment.a_px = {c[0], c[1]};
      segment.b_px = {c[2], c[3]};
      segments->push_back(segment);
    }
  }

  const int num_families = static_cast<int>(family_order->size());
  options->principal_point_mode = num_families >= 3 ? PrincipalPointMode::kSolve : PrincipalPointMode::kImageCenter;
  if (!json_io::ReadPrincipalPoint(doc, &options->principal_point_mode, &options->fixed_principal_point_px, error))
    return false;
  if (!ReadOptionalPositive(doc, "focal_px", &options->fixed_focal_px, error) ||
      !ReadOptionalPositive(doc, "focal_prior_px", &options->focal_prior_px, error) ||
      !ReadOptionalPositive(doc, "focal_prior_std_px", &options->focal_prior_std_px, error) ||
      !ReadOptionalBool(doc, "distortion", distortion, error) ||
      !ReadOptionalBool(doc, "refit_without_outliers", &options->refit_without_outliers, error))
    return false;
  if ((options->focal_prior_px > 0.0) != (options->focal_prior_std_px > 0.0)) {
    *error = "\"focal_prior_px\" and \"focal_prior_std_px\" go together";
    return false;
  }
  // Checked here, where they enter: a focal length outside any lens, or a prior whose std is
  // ~0, was ignored downstream and the output held nulls.
  if (options->fixed_focal_px > 0.0) {
    const std::string why = WhyNotAFocalLength(options->fixed_focal_px, options->width_px, options->height_px);
    if (!why.empty()) {
      *error = "\"focal_px\": " + why;
      return false;
    }
  }
  if (options->focal_prior_px > 0.0) {
    const std::string why =
        WhyNotAFocalPrior(options->focal_prior_px, options->focal_prior_std_px, options->width_px, options->height_px);
    if (!why.empty()) {
      *error = "\"focal_prior_px\", \"focal_prior_std_px\": " + why;
      return false;
    }
  }
  const auto horizon_it = doc.find("horizon");
  if (horizon_it != doc.end()) {
    double row = 0.0, h[4];
    if (ReadNumber(*horizon_it, &row)) {
      options->horizon_px = Eigen::Vector4d(0.0, row, options->width_px - 1.0, row);
    } else if (json_io::ReadVector(*horizon_it, 4, h)) {
      options->horizon_px = Eigen::Vector4d(h[0], h[1], h[2], h[3]);
    } else {
      *error = "\"horizon\" must be [x1, y1, x2, y2] or the row v of a level horizon, got " + horizon_it->dump();
      return false;
    }
    const std::string why = WhyNotALineOnPhoto(options->horizon_px, options->width_px, options->height_px);
    if (!why.empty()) {
      *error = "\"horizon\": " + why;
      return false;
    }
    options->use_horizon = true;
  }
  return true;
}

}  // namespace

CalibrateIoResult CalibrateLinesJson(const std::string& lines_json_text) {
  try {
    json doc;
    try {
      doc = json::parse(lines_json_text);
    } catch (const json::parse_error& e) {
      return Error(std::string("malformed JSON: ") + e.what());
    }
    std::vector<Segment> segments;
    VpCalibrationOptions options;
    std::vector<int> family_order;
    bool distortion = false;
    std::string error;
    if (!ParseInput(doc, &segments, &options, &family_order, &distortion, &error)) return Error(error);

    // Distortion first (plumb lines: each segment a 2-point line, its family a common
    // vanishing point), then the pinhole calibration of the undistorted segments.
    json distortion_out = nullptr;
    std::vector<std::string> distortion_warnings;
    if (distortion) {
      PlumbLineOptions plumb_options;
      plumb_options.width_px = options.width_px;
      plumb_options.height_px = options.height_px;
      if (options.principal_point_mode == PrincipalPointMode::kFixed)
        plumb_options.center_px = options.fixed_principal_point_px;
      std::vector<PlumbLine> lines;
      for (const Segment& s : segments) lines.push_back({{s.a_px, s.b_px}, static_cast<int>(s.axis)});
      const PlumbLineSummary plumb = EstimateRadialDistortion(lines, plumb_options);
      const RadialDistortion& d = plumb.distortion;
      distortion_out = {{"k1", d.k1},
                        {"k2", d.k2},
                        {"k1_std", plumb.k1_std},
                        {"center", {d.center_px.x(), d.center_px.y()}},
                        {"scale_px", d.scale_px},
                        {"model", "uv_u = c + (uv_d - c) (1 + k1 r^2 + k2 r^4), r = |uv_d - c| / scale_px"}};
      if (plumb.IsUsable()) {
        for (Segment& s : segments) {
          s.a_px = d.Undistort(s.a_px);
          s.b_px = d.Undistort(s.b_px);
        }
        for (const std::string& w : plumb.warnings) distortion_warnings.push_back("distortion: " + w);
      } else {
        distortion_warnings.push_back("distortion not estimated: " + plumb.message);
      }
    }

    const VpCalibrationSummary summary = CalibrateFromVanishingLines(segments, options);
    if (!summary.IsUsable()) return Error("calibration failed: " + summary.message);

    Eigen::Matrix3d k = Eigen::Matrix3d::Identity();
    k(0, 0) = k(1, 1) = summary.focal_px;
    k(0, 2) = summary.principal_point_px.x();
    k(1, 2) = summary.principal_point_px.y();

    json out = json::object();
    out["focal_px"] = summary.focal_px;
    out["principal_point"] = {summary.principal_point_px.x(), summary.principal_point_px.y()};
    out["K"] = Rows(k);
    out["R"] = Rows(summary.cam_from_world_rotation);
    json axes = json::array(), points = json::array(), homogeneous = json::array();
    for (int a = 0; a < 3; ++a) {
      if (summary.segments_per_axis[a] == 0) continue;
      const Eigen::Vector3d& v = summary.vanishing_points[a];
      axes.push_back(AxisName(static_cast<Axis>(a)));
      // A point at infinity is its direction in the image, said as such, not a null that a
      // reader could take for a missing value (issue 14).
      if (summary.vanishing_point_at_infinity[a])
        points.push_back({{"at_infinity", true}, {"direction", {v.x() / v.head<2>().norm(), v.y() / v.head<2>().norm()}}});
      else
        points.push_back({v.x() / v.z(), v.y() / v.z()});
      homogeneous.push_back({v.x(), v.y(), v.z()});
    }
    out["vanishing_point_axes"] = axes;
    out["vanishing_points"] = points;
    out["vanishing_points_homogeneous"] = homogeneous;
    // The uncertainties are undetermined (NaN) with too few segments: said as null, as
    // documented; every other figure must be a number (checked below).
    out["focal_std_px"] = FiniteOrNull(summary.focal_std_px);
    out["principal_point_std_px"] = {FiniteOrNull(summary.principal_point_std_px.x()),
                                     FiniteOrNull(summary.principal_point_std_px.y())};
    out["residual_sigma_px"] = FiniteOrNull(summary.residual_sigma_px);
    out["segment_residuals_px"] = summary.segment_residuals_px;
    out["outlier_segments"] = summary.outlier_segments;
    out["outlier_threshold_px"] = summary.outlier_threshold_px;
    out["refitted_without_outliers"] = summary.refitted_without_outliers;
    // Per given family, in vanishing_point_axes order; infinity (a point at infinity) as null.
    json direction_std = json::array(), spread = json::array(), to_pp = json::array();
    for (int a = 0; a < 3; ++a) {
      if (summary.segments_per_axis[a] == 0) continue;
      direction_std.push_back(FiniteOrNull(summary.vanishing_direction_std_deg[a]));
      spread.push_back(summary.family_angle_spread_deg[a]);
      to_pp.push_back(std::isfinite(summary.vanishing_point_to_principal_point_px[a])
                          ? json(summary.vanishing_point_to_principal_point_px[a])
                          : json(nullptr));
    }
    out["vanishing_direction_std_deg"] = direction_std;
    out["family_angle_spread_deg"] = spread;
    out["vanishing_point_to_principal_point_px"] = to_pp;
    out["min_family_angle_spread_deg"] = summary.min_family_angle_spread_deg;
    out["min_vanishing_point_to_principal_point_px"] = std::isfinite(summary.min_vanishing_point_to_principal_point_px)
                                                           ? json(summary.min_vanishing_point_to_principal_point_px)
                                                           : json(nullptr);
    out["vanishing_point_triangle_max_angle_deg"] = summary.vanishing_point_triangle_max_angle_deg;
    if (options.use_horizon) out["horizon_residual_px"] = summary.horizon_residual_px;
    if (distortion) out["distortion"] = distortion_out;
    out["segments_per_axis"] = summary.segments_per_axis;
    std::vector<std::string> warnings = distortion_warnings;
    warnings.insert(warnings.end(), summary.warnings.begin(), summary.warnings.end());
    out["warnings"] = warnings;
    out["message"] = summary.message;
    out["time_ms"] = summary.time_ms;
    const std::string non_finite = json_io::FirstNonFiniteNumber(out);
    if (!non_finite.empty()) return Error("calibration gave no number for " + non_finite + "; check the input");
    CalibrateIoResult result;
    result.json = out.dump(2) + "\n";
    return result;
  } catch (const std::exception& e) {
    // Type errors and the like that slipped past the checks: still a message, never a throw.
    return Error(std::string("cannot read the line families: ") + e.what());
  }
}

CalibrateIoResult CalibrateLinesFile(const std::string& path) {
  return json_io::FromFile<CalibrateIoResult>(path, CalibrateLinesJson);
}

CalibrateIoResult CalibrateImageFile(const std::string& photo_path, const CalibrateImageOptions& options) {
  try {
    if ((options.focal_px > 0.0) && (options.focal_prior_px > 0.0))
      return Error("a known focal length and a focal prior cannot be given together");
    const ImageReadResult read = ReadImage(photo_path);
    if (!read.ok()) return Error(read.error);
    ManhattanLinesOptions detect;
    detect.calibration.principal_point_mode = options.principal_point_mode;
    detect.calibration.fixed_principal_point_px = options.fixed_principal_point_px;
    detect.calibration.fixed_focal_px = options.focal_px;
    if (options.focal_prior_px > 0.0 && options.focal_prior_std_px > 0.0) {
      detect.calibration.focal_prior_px = options.focal_prior_px;
      detect.calibration.focal_prior_std_px = options.focal_prior_std_px;
    }
    const ManhattanLinesSummary found = DetectManhattanLines(read.image, detect);
    if (!found.IsUsable()) return Error(photo_path + ": no camera from the detected lines: " + found.message);

    // The LINES.json the detection makes; calibrating it is the output, so that re-reading
    // it gives the same camera.
    json lines = json::object();
    lines["image_size"] = {read.image.width, read.image.height};
    json families = json::array();
    for (int a = 0; a < 3; ++a) {
      json segments = json::array();
      for (const Segment& s : found.labelled_segments)
        if (static_cast<int>(s.axis) == a) segments.push_back({s.a_px.x(), s.a_px.y(), s.b_px.x(), s.b_px.y()});
      if (!segments.empty()) families.push_back({{"axis", AxisName(static_cast<Axis>(a))}, {"segments", segments}});
    }
    lines["families"] = families;
    switch (options.principal_point_mode) {
      case PrincipalPointMode::kSolve: lines["principal_point"] = "solve"; break;
      case PrincipalPointMode::kImageCenter: lines["principal_point"] = "center"; break;
      case PrincipalPointMode::kFixed:
        lines["principal_point"] = {options.fixed_principal_point_px.x(), options.fixed_principal_point_px.y()};
        break;
    }
    if (options.focal_px > 0.0) lines["focal_px"] = options.focal_px;
    if (detect.calibration.focal_prior_px > 0.0) {
      lines["focal_prior_px"] = detect.calibration.focal_prior_px;
      lines["focal_prior_std_px"] = detect.calibration.focal_prior_std_px;
    }
    CalibrateIoResult calibrated = CalibrateLinesJson(lines.dump());
    if (!calibrated.ok()) return Error(photo_path + ": " + calibrated.error);

    json out = json::parse(calibrated.json);
    json outliers = json::array();
    for (size_t i = 0; i < found.segments_px.size(); ++i) {
      if (found.segment_family[i] >= 0) continue;
      const Eigen::Vector4d& s = found.segments_px[i];
      outliers.push_back({s[0], s[1], s[2], s[3]});
    }
    out["lines"] = lines;
    out["detection"] = {{"segments", found.segments_px.size()},
                        {"outlier_segments", outliers},
                        {"min_length_px", found.min_length_px},
                        {"inlier_distance_px", found.inlier_distance_px},
                        {"search_focal_px", found.search_focal_px},
                        {"detection_ms", found.detection_ms},
                        {"search_ms", found.search_ms}};
    // The EXIF message may quote the camera's own strings: never a reason for dump() to throw.
    if (!options.focal_prior_source.empty())
      out["focal_prior_source"] = ValidUtf8OrReplaced(options.focal_prior_source);
    CalibrateIoResult result;
    result.json = out.dump(2) + "\n";
    return result;
  } catch (const std::exception& e) {
    return Error(std::string("cannot calibrate from the photo: ") + e.what());
  }
}

}  // namespace facet
