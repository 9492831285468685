#include "core/io/calibrate_points_io.h"

#include <cmath>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/io/json_io_internal.h"

#include "core/estimators/calibrate_dlt.h"
#include "core/geometry/camera_checks.h"

namespace facet {
namespace {

using json_io::ReadNumber;
using json_io::ReadVector;
using json_io::Rows;
using nlohmann::json;

CalibrateIoResult Error(std::string message) {
  CalibrateIoResult result;
  result.error = std::move(message);
  return result;
}

// Fills *error and returns false when the document does not have the documented shape.
bool ParseInput(const json& doc, std::vector<PointCorrespondence>* points, DltCalibrationOptions* options,
                std::string* error) {
  if (!doc.is_object()) {
    *error = "the top level must be a JSON object";
    return false;
  }
  const auto size_it = doc.find("image_size");
  if (size_it == doc.end()) {
    *error = "missing \"image_size\": [width, height]";
    return false;
  }
  double size[2] = {0, 0};
  if (!ReadVector(*size_it, 2, size) || size[0] != std::floor(size[0]) || size[1] != std::floor(size[1]) ||
      size[0] < 1 || size[1] < 1 || size[0] > 1e9 || size[1] > 1e9) {
    *error = "\"image_size\" must be [width, height], two positive integers, got " + size_it->dump();
    return false;
  }
  options->width_px = static_cast<int>(size[0]);
  options->height_px = static_cast<int>(size[1]);

  const auto points_it = doc.find("points");
  if (points_it == doc.end()) {
    *error = "missing \"points\": [{\"xyz\": [X, Y, Z], \"uv\": [u, v]}, ...]";
    return false;
  }
  if (!points_it->is_array()) {
    *error = "\"points\" must be an array";
    return false;
  }
  for (size_t i = 0; i < points_it->size(); ++i) {
    const json& p = (*points_it)[i];
    const std::string where = "points[" + std::to_string(i) + "]";
    if (!p.is_object()) {
      *error = where + " must be an object {\"xyz\": [X, Y, Z], \"uv\": [u, v]}, got " + p.dump();
      return false;
    }
    const auto xyz_it = p.find("xyz");
    const auto uv_it = p.find("uv");
    PointCorrespondence c;
    if (xyz_it == p.end() || !ReadVector(*xyz_it, 3, c.xyz.data())) {
      *error = where + ": \"xyz\" must be [X, Y, Z], three finite numbers";
      return false;
    }
    if (uv_it == p.end() || !ReadVector(*uv_it, 2, c.uv_px.data())) {
      *error = where + ": \"uv\" must be [u, v], two finite numbers";
      return false;
    }
    points->push_back(c);
  }

  const auto distortion_it = doc.find("distortion");
  if (distortion_it != doc.end()) {
    double terms = -1;
    if (!ReadNumber(*distortion_it, &terms) || (terms != 0 && terms != 1 && terms != 2)) {
      *error = "\"distortion\" must be 0, 1 or 2 (radial terms), got " + distortion_it->dump();
      return false;
    }
    options->radial_distortion_terms = static_cast<int>(terms);
  }

  const auto focal_it = doc.find("focal_px");
  if (focal_it != doc.end()) {
    double focal_px = 0.0;
    if (!ReadNumber(*focal_it, &focal_px) || !(focal_px > 0.0)) {
      *error = "\"focal_px\" must be a positive number (a known focal length), got " + focal_it->dump();
      return false;
    }
    // Checked where it enters (1e-300 and 1e308 crashed the pose's SVD): a lens for this photo.
    const std::string why = WhyNotAFocalLength(focal_px, options->width_px, options->height_px);
    if (!why.empty()) {
      *error = "\"focal_px\": " + why;
      return false;
    }
    options->fixed_focal_px = focal_px;
  }

  if (!json_io::ReadPrincipalPoint(doc, &options->principal_point_mode, &options->fixed_principal_point_px, error))
    return false;
  return true;
}

}  // namespace

CalibrateIoResult CalibratePointsJson(const std::string& points_json_text) {
  try {
    json doc;
    try {
      doc = json::parse(points_json_text);
    } catch (const json::parse_error& e) {
      return Error(std::string("malformed JSON: ") + e.what());
    }
    std::vector<PointCorrespondence> points;
    DltCalibrationOptions options;
    std::string error;
    if (!ParseInput(doc, &points, &options, &error)) return Error(error);

    const DltCalibrationSummary summary = CalibrateFromPoints(points, options);
    if (!summary.IsUsable()) return Error("calibration failed: " + summary.message);

    const Camera& camera = summary.camera;
    const Eigen::Vector3d& t = camera.cam_from_world_translation;
    json out = json::object();
    out["K"] = Rows(camera.K());
    out["R"] = Rows(camera.cam_from_world_rotation);
    out["t"] = {t.x(), t.y(), t.z()};
    out["focal_px"] = camera.focal_px;
    out["principal_point"] = {camera.principal_point_px.x(), camera.principal_point_px.y()};
    out["distortion"] = {summary.k1, summary.k2};
    out["reprojection_rms_px"] = summary.reprojection_rms_px;
    out["initial_rms_px"] = summary.initial_rms_px;
    out["residuals_px"] = summary.residuals_px;
    out["planar"] = summary.planar;
    out["focal_std_px"] = summary.focal_std_px;
    out["focal_fixed"] = summary.focal_fixed;
    out["warnings"] = summary.warnings;
    out["message"] = summary.message;
    out["time_ms"] = summary.time_ms;
    const std::string non_finite = json_io::FirstNonFiniteNumber(out);
    if (!non_finite.empty()) return Error("calibration gave no number for " + non_finite + "; check the points");
    CalibrateIoResult result;
    result.json = out.dump(2) + "\n";
    return result;
  } catch (const std::exception& e) {
    // Type errors and the like that slipped past the checks: still a message, never a throw.
    return Error(std::string("cannot read the points: ") + e.what());
  }
}

CalibrateIoResult CalibratePointsFile(const std::string& path) {
  return json_io::FromFile<CalibrateIoResult>(path, CalibratePointsJson);
}

}  // namespace facet
