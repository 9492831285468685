#include "core/io/relate_io.h"

#include <cmath>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/io/json_io_internal.h"

#include "core/estimators/two_view.h"
#include "core/geometry/camera_checks.h"
#include "core/util/input_limits.h"

namespace facet {
namespace {

using json_io::ReadMatrix3;
using json_io::ReadNumber;
using json_io::Rows;
using nlohmann::json;

RelateIoResult Error(std::string message) {
  RelateIoResult result;
  result.error = std::move(message);
  return result;
}

struct Input {
  std::vector<Eigen::Vector2d> uv1, uv2;
  bool has_k = false;
  Eigen::Matrix3d k1 = Eigen::Matrix3d::Identity(), k2 = Eigen::Matrix3d::Identity();
};

bool ParseInput(const json& doc, Input* in, std::string* error) {
  if (!doc.is_object()) {
    *error = "the top level must be a JSON object";
    return false;
  }
  const auto sizes_it = doc.find("image_sizes");
  if (sizes_it == doc.end()) {
    *error = "missing \"image_sizes\": [[w1, h1], [w2, h2]]";
    return false;
  }
  bool sizes_ok = sizes_it->is_array() && sizes_it->size() == 2;
  for (size_t k = 0; sizes_ok && k < 2; ++k) {
    const json& s = (*sizes_it)[k];
    double w = 0, h = 0;
    sizes_ok = s.is_array() && s.size() == 2 && ReadNumber(s[0], &w) && ReadNumber(s[1], &h) && w == std::floor(w) &&
               h == std::floor(h) && w >= 1 && h >= 1 && w <= 1e9 && h <= 1e9;
  }
  if (!sizes_ok) {
    *error = "\"image_sizes\" must be [[w1, h1], [w2, h2]], positive integers, got " + sizes_it->dump();
    return false;
  }
  const auto matches_it = doc.find("matches");
  if (matches_it == doc.end() || !matches_it->is_array()) {
    *error = "missing \"matches\": [[u1, v1, u2, v2], ...]";
    return false;
  }
  if (matches_it->size() > kMaxRelateMatches) {
    *error = "relate takes at most " + std::to_string(kMaxRelateMatches) + " matches; this file has " +
             std::to_string(matches_it->size());
    return false;
  }
  for (size_t i = 0; i < matches_it->size(); ++i) {
    const json& m = (*matches_it)[i];
    double c[4];
    bool ok = m.is_array() && m.size() == 4;
    for (int k = 0; ok && k < 4; ++k) ok = ReadNumber(m[k], &c[k]);
    if (!ok) {
      *error = "matches[" + std::to_string(i) + "] must be [u1, v1, u2, v2], four finite numbers, got " + m.dump();
      return false;
    }
    in->uv1.emplace_back(c[0], c[1]);
    in->uv2.emplace_back(c[2], c[3]);
  }
  const auto k_it = doc.find("K");
  if (k_it != doc.end() && !k_it->is_null()) {
    if (!k_it->is_array() || k_it->size() != 2 || !ReadMatrix3((*k_it)[0], &in->k1) ||
        !ReadMatrix3((*k_it)[1], &in->k2)) {
      *error = "\"K\" must be [K1, K2], two 3x3 matrices of finite numbers given as rows, got " + k_it->dump();
      return false;
    }
    for (const auto& [name, k] : {std::pair<const char*, const Eigen::Matrix3d*>{"K1", &in->k1}, {"K2", &in->k2}}) {
      const std::string why = WhyNotACalibrationMatrix(*k);
      if (!why.empty()) {
        *error = std::string("\"K\": ") + name + " is not a camera: " + why;
        return false;
      }
    }
    in->has_k = true;
  }
  return true;
}

}  // namespace

RelateIoResult RelateMatchesJson(const std::string& matches_json_text) {
  try {
    json doc;
    try {
      doc = json::parse(matches_json_text);
    } catch (const json::parse_error& e) {
      return Error(std::string("malformed JSON: ") + e.what());
    }
    Input in;
    std::string error;
    if (!ParseInput(doc, &in, &error)) return Error(error);

    const FundamentalSummary f = EstimateFundamentalMatrix(in.uv1, in.uv2, FundamentalOptions());
    if (!f.IsUsable()) return Error("fundamental matrix failed: " + f.message);

    json out = json::object();
    out["F"] = Rows(f.F);
    out["symmetric_epipolar_rms_px"] = f.symmetric_epipolar_rms_px;
    out["inliers"] = f.inliers;
    json outliers = json::array();
    for (size_t i = 0; i < f.inliers.size(); ++i)
      if (!f.inliers[i]) outliers.push_back(i);
    out["outliers"] = outliers;
    std::vector<std::string> warnings = f.warnings;
    std::string message = f.message;
    double time_ms = f.time_ms;
    if (in.has_k) {
      const RelativePoseSummary pose =
          EstimateRelativePose(f.F, in.k1, in.k2, in.uv1, in.uv2, f.inliers, RelativePoseOptions());
      if (!pose.IsUsable()) return Error("relative pose failed: " + pose.message);
      const Eigen::Vector3d& t = pose.cam2_from_cam1_translation;
      out["E"] = Rows(pose.E);
      out["R"] = Rows(pose.cam2_from_cam1_rotation);
      out["t"] = {t.x(), t.y(), t.z()};
      out["points_in_front"] = pose.points_in_front;
      out["pose_symmetric_epipolar_rms_px"] = pose.symmetric_epipolar_rms_px;
      warnings.insert(warnings.end(), pose.warnings.begin(), pose.warnings.end());
      message += "; " + pose.message;
      time_ms += pose.time_ms;
    }
    out["warnings"] = warnings;
    out["message"] = message;
    out["time_ms"] = time_ms;
    RelateIoResult result;
    result.json = out.dump(2) + "\n";
    return result;
  } catch (const std::exception& e) {
    return Error(std::string("cannot read the matches: ") + e.what());
  }
}

RelateIoResult RelateMatchesFile(const std::string& path) {
  return json_io::FromFile<RelateIoResult>(path, RelateMatchesJson);
}

}  // namespace facet
