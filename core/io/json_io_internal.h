// Small readers and writers shared by core's JSON adapters (calibrate_io, calibrate_points_io,
// relate_io). Internal: include it only from core .cpp files, so nlohmann stays out of the
// public headers.
#pragma once

#include <string>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "core/scene/project.h"

namespace facet::json_io {

// A finite number.
bool ReadNumber(const nlohmann::json& value, double* out);
// An array of exactly `size` finite numbers.
bool ReadVector(const nlohmann::json& value, int size, double* out);
// Three rows of three finite numbers.
bool ReadMatrix3(const nlohmann::json& value, Eigen::Matrix3d* m);
// A 3x3 matrix as three rows.
nlohmann::json Rows(const Eigen::Matrix3d& m);
// Optional "principal_point": "solve" | "center" | [cx, cy]. Leaves *mode and *fixed_px as
// they are when the key is absent; false with *error for any other value.
bool ReadPrincipalPoint(const nlohmann::json& doc, PrincipalPointMode* mode, Eigen::Vector2d* fixed_px,
                        std::string* error);
// Empty when every number in `doc` is finite, else the JSON pointer of the first that is not
// (e.g. "/focal_std_px"). nlohmann writes NaN and infinity as null: a success output checks
// this so that no figure it prints is a null (an explicit null value is not a number, and
// passes).
std::string FirstNonFiniteNumber(const nlohmann::json& doc);
// The whole file as text; false with *error ("cannot open PATH") when it cannot be read.
bool ReadTextFile(const std::string& path, std::string* text, std::string* error);

// The file form of an adapter: reads `path` and passes its text to `from_text`, prefixing
// any error with the path. Result has `std::string error` and `bool ok()`.
template <typename Result, typename FromText>
Result FromFile(const std::string& path, FromText from_text) {
  std::string text, error;
  if (!ReadTextFile(path, &text, &error)) {
    Result failed;
    failed.error = error;
    return failed;
  }
  Result result = from_text(text);
  if (!result.ok()) result.error = path + ": " + result.error;
  return result;
}

}  // namespace facet::json_io
