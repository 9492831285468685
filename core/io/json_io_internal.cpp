#include "core/io/json_io_internal.h"

#include "core/util/file_read.h"

#include <cmath>
#include <fstream>
#include <sstream>

namespace facet::json_io {

bool ReadNumber(const nlohmann::json& value, double* out) {
  if (!value.is_number()) return false;
  *out = value.get<double>();
  return std::isfinite(*out);
}

bool ReadVector(const nlohmann::json& value, int size, double* out) {
  if (!value.is_array() || static_cast<int>(value.size()) != size) return false;
  for (int k = 0; k < size; ++k)
    if (!ReadNumber(value[k], &out[k])) return false;
  return true;
}

bool ReadMatrix3(const nlohmann::json& value, Eigen::Matrix3d* m) {
  if (!value.is_array() || value.size() != 3) return false;
  for (int r = 0; r < 3; ++r) {
    double row[3];
    if (!ReadVector(value[r], 3, row)) return false;
    for (int c = 0; c < 3; ++c) (*m)(r, c) = row[c];
  }
  return true;
}

nlohmann::json Rows(const Eigen::Matrix3d& m) {
  nlohmann::json rows = nlohmann::json::array();
  for (int r = 0; r < 3; ++r) rows.push_back({m(r, 0), m(r, 1), m(r, 2)});
  return rows;
}

bool ReadPrincipalPoint(const nlohmann::json& doc, PrincipalPointMode* mode, Eigen::Vector2d* fixed_px,
                        std::string* error) {
  const auto it = doc.find("principal_point");
  if (it == doc.end()) return true;
  double pp[2] = {0, 0};
  if (it->is_string() && it->get<std::string>() == "solve") {
    *mode = PrincipalPointMode::kSolve;
  } else if (it->is_string() && it->get<std::string>() == "center") {
    *mode = PrincipalPointMode::kImageCenter;
  } else if (ReadVector(*it, 2, pp)) {
    *mode = PrincipalPointMode::kFixed;
    *fixed_px = {pp[0], pp[1]};
  } else {
    *error = "\"principal_point\" must be \"solve\", \"center\" or [cx, cy], got " + it->dump();
    return false;
  }
  return true;
}

std::string FirstNonFiniteNumber(const nlohmann::json& doc) {
  if (doc.is_number_float()) return std::isfinite(doc.get<double>()) ? std::string() : std::string("/");
  if (doc.is_array()) {
    for (size_t i = 0; i < doc.size(); ++i) {
      const std::string inner = FirstNonFiniteNumber(doc[i]);
      if (!inner.empty()) return "/" + std::to_string(i) + (inner == "/" ? "" : inner);
    }
  } else if (doc.is_object()) {
    for (auto it = doc.begin(); it != doc.end(); ++it) {
      const std::string inner = FirstNonFiniteNumber(it.value());
      if (!inner.empty()) return "/" + it.key() + (inner == "/" ? "" : inner);
    }
  }
  return {};
}

bool ReadTextFile(const std::string& path, std::string* text, std::string* error) {
  return ReadRegularFile(path, kMaxTextFileBytes, text, error);
}

}  // namespace facet::json_io
