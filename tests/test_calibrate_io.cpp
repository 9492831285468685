// The JSON adapter of single-image calibration (core/calibrate_io.h): a synthetic scene's
// line families written as LINES.json come back as its camera; bad input gives messages.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "core/calibrate_io.h"
#include "core/calibrate_vp.h"
#include "tests/synthetic_scene.h"

namespace facet {
namespace {

using nlohmann::json;

// Noise-free numerics, as in test_calibrate_vp.cpp.
constexpr double kNoiseFreeRelative = 1e-9;

// LINES.json text of a scene's segments, families in the given axis order.
std::string LinesJson(const testing::SyntheticScene& scene, const std::vector<Axis>& axes,
                      const std::string& principal_point_field) {
  std::ostringstream out;
  out << std::setprecision(17) << "{\"image_size\": [" << scene.true_camera.width_px << ", "
      << scene.true_camera.height_px << "], \"families\": [";
  for (size_t f = 0; f < axes.size(); ++f) {
    out << (f ? ", " : "") << "{\"axis\": \"" << AxisName(axes[f]) << "\", \"segments\": [";
    bool first = true;
    for (const Segment& s : scene.project.segments) {
      if (s.axis != axes[f]) continue;
      out << (first ? "" : ", ") << "[" << s.a_px.x() << ", " << s.a_px.y() << ", " << s.b_px.x() << ", "
          << s.b_px.y() << "]";
      first = false;
    }
    out << "]}";
  }
  out << "]" << principal_point_field << "}";
  return out.str();
}

Eigen::Matrix3d MatrixFromRows(const json& rows) {
  Eigen::Matrix3d m;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m(r, c) = rows.at(r).at(c).get<double>();
  return m;
}

void CheckError(const std::string& input, const std::string& expected_words) {
  const CalibrateIoResult result = CalibrateLinesJson(input);
  INFO("input: " << input);
  INFO("error: " << result.error);
  CHECK_FALSE(result.ok());
  CHECK(result.json.empty());
  CHECK(result.error.find(expected_words) != std::string::npos);
}

TEST_CASE("LINES.json of a synthetic scene gives its camera") {
  const testing::SyntheticScene scene = testing::MakeBoxScene();
  const Camera& truth = scene.true_camera;
  // Families deliberately not in x, y, z order: the output lists them in axis order.
  const CalibrateIoResult result = CalibrateLinesJson(LinesJson(scene, {Axis::kZ, Axis::kX, Axis::kY}, ""));
  INFO("error: " << result.error);
  REQUIRE(result.ok());
  const json out = json::parse(result.json);
  const double focal_px = out.at("focal_px").get<double>();
  CAPTURE(focal_px);
  CHECK(std::abs(focal_px - truth.focal_px) < kNoiseFreeRelative * truth.focal_px);
  const Eigen::Vector2d pp(out.at("principal_point").at(0).get<double>(), out.at("principal_point").at(1).get<double>());
  CHECK((pp - truth.principal_point_px).norm() < kNoiseFreeRelative * truth.focal_px);
  const Eigen::Matrix3d k = MatrixFromRows(out.at("K"));
  CHECK(k(0, 0) == focal_px);
  CHECK(k(1, 1) == focal_px);
  CHECK(k(0, 2) == pp.x());
  CHECK(k(1, 2) == pp.y());
  CHECK(k(2, 2) == 1.0);

  // The same answer as the core call, bit for bit: doubles are printed to round-trip.
  VpCalibrationOptions options;
  options.width_px = truth.width_px;
  options.height_px = truth.height_px;
  std::vector<Segment> reordered;
  for (Axis axis : {Axis::kZ, Axis::kX, Axis::kY})
    for (const Segment& s : scene.project.segments)
      if (s.axis == axis) reordered.push_back(s);
  const VpCalibrationSummary core = CalibrateFromVanishingLines(reordered, options);
  REQUIRE(core.success);
  CHECK(focal_px == core.focal_px);
  CHECK(MatrixFromRows(out.at("R")) == core.cam_from_world_rotation);
  // The rotation is the truth up to the sign convention of the world axes.
  const Eigen::Matrix3d r = MatrixFromRows(out.at("R"));
  for (int c = 0; c < 3; ++c) CHECK(std::abs(std::abs(r.col(c).dot(truth.cam_from_world_rotation.col(c))) - 1.0) < 1e-9);

  CHECK(out.at("vanishing_point_axes") == json({"x", "y", "z"}));
  REQUIRE(out.at("vanishing_points").size() == 3);
  REQUIRE(out.at("vanishing_points_homogeneous").size() == 3);
  for (int a = 0; a < 3; ++a) {
    const Eigen::Vector3d expected = truth.K() * truth.cam_from_world_rotation.col(a);
    const Eigen::Vector2d vp(out["vanishing_points"][a][0].get<double>(), out["vanishing_points"][a][1].get<double>());
    CHECK((vp - expected.head<2>() / expected.z()).norm() < 1e-9 * (expected.head<2>() / expected.z()).norm());
  }
  CHECK(out.at("segment_residuals_px").size() == scene.project.segments.size());
  CHECK(out.at("warnings").is_array());
  CHECK(out.at("segments_per_axis") == json({8, 8, 8}));
}

TEST_CASE("principal point choices and a vanishing point at infinity") {
  testing::SyntheticSceneOptions o;
  o.camera_center.z() = 1.25;  // zero pitch: vertical edges parallel in the image
  o.look_at.z() = 1.25;
  const testing::SyntheticScene scene = testing::MakeBoxScene(o);
  const Eigen::Vector2d pp = scene.true_camera.principal_point_px;
  std::ostringstream fixed;
  fixed << std::setprecision(17) << ", \"principal_point\": [" << pp.x() << ", " << pp.y() << "]";
  const CalibrateIoResult result = CalibrateLinesJson(LinesJson(scene, {Axis::kX, Axis::kY, Axis::kZ}, fixed.str()));
  INFO("error: " << result.error);
  REQUIRE(result.ok());
  const json out = json::parse(result.json);
  CHECK(std::abs(out.at("focal_px").get<double>() - scene.true_camera.focal_px) <
        kNoiseFreeRelative * scene.true_camera.focal_px);
  CHECK(out.at("vanishing_points").at(2).is_null());
  CHECK(out.at("vanishing_points").at(0).is_array());
  CHECK(std::abs(out.at("vanishing_points_homogeneous").at(2).at(2).get<double>()) < 1e-9);

  // "solve" cannot use a point at infinity.
  CheckError(LinesJson(scene, {Axis::kX, Axis::kY, Axis::kZ}, ", \"principal_point\": \"solve\""), "family z");

  // Two families default to the image centre (with a centred principal point: exact).
  testing::SyntheticSceneOptions centred;
  centred.principal_point_offset_px = Eigen::Vector2d::Zero();
  const testing::SyntheticScene two = testing::MakeBoxScene(centred);
  for (const std::string& field : {std::string(""), std::string(", \"principal_point\": \"center\"")}) {
    const CalibrateIoResult r = CalibrateLinesJson(LinesJson(two, {Axis::kX, Axis::kZ}, field));
    INFO("error: " << r.error);
    REQUIRE(r.ok());
    const json j = json::parse(r.json);
    CHECK(std::abs(j.at("focal_px").get<double>() - two.true_camera.focal_px) <
          kNoiseFreeRelative * two.true_camera.focal_px);
    CHECK(j.at("vanishing_point_axes") == json({"x", "z"}));
    CHECK(j.at("warnings").empty());
  }
}

TEST_CASE("bad LINES.json gives a message, never an exception") {
  const testing::SyntheticScene scene = testing::MakeBoxScene();
  const std::string valid = LinesJson(scene, {Axis::kX, Axis::kY, Axis::kZ}, "");
  REQUIRE(CalibrateLinesJson(valid).ok());

  CheckError("", "malformed JSON");
  CheckError(valid.substr(0, valid.size() / 2), "malformed JSON");
  CheckError("[1, 2]", "object");
  CheckError(R"({"families": []})", "image_size");
  CheckError(R"({"image_size": [640], "families": []})", "image_size");
  CheckError(R"({"image_size": ["640", 480], "families": []})", "image_size");
  CheckError(R"({"image_size": [640.5, 480], "families": []})", "image_size");
  CheckError(R"({"image_size": [640, 480]})", "families");
  CheckError(R"({"image_size": [640, 480], "families": {"axis": "x"}})", "families");
  CheckError(R"({"image_size": [640, 480], "families": [3]})", "families[0]");
  CheckError(R"({"image_size": [640, 480], "families": [{"segments": []}]})", "axis");
  CheckError(R"({"image_size": [640, 480], "families": [{"axis": "w", "segments": []}]})", "unknown axis");
  CheckError(R"({"image_size": [640, 480], "families": [{"axis": "x"}]})", "segments");
  CheckError(R"({"image_size": [640, 480], "families": [{"axis": "x", "segments": [[1, 2, 3]]}]})",
             "families[0].segments[0]");
  CheckError(R"({"image_size": [640, 480], "families": [{"axis": "x", "segments": [[1, 2, 3, "4"]]}]})",
             "families[0].segments[0]");
  CheckError(
      R"({"image_size": [640, 480], "families": [{"axis": "x", "segments": [[1, 2, 3, 4], [5, 6, 7, 9]]}, {"axis": "x", "segments": []}]})",
      "given twice");
  // A single family.
  CheckError(LinesJson(scene, {Axis::kY}, ""), "two line families");
  // Parallel segments in every family: no finite vanishing point, no focal length.
  CheckError(
      R"({"image_size": [640, 480], "families": [)"
      R"({"axis": "x", "segments": [[10, 10, 100, 10], [10, 50, 100, 50]]},)"
      R"({"axis": "z", "segments": [[10, 10, 10, 100], [50, 10, 50, 100]]}]})",
      "undetermined");
  CheckError(valid.substr(0, valid.size() - 1) + ", \"principal_point\": \"middle\"}", "principal_point");
  CheckError(valid.substr(0, valid.size() - 1) + ", \"principal_point\": [1]}", "principal_point");
  CheckError(
      R"({"image_size": [640, 480], "families": [)"
      R"({"axis": "x", "segments": [[10, 10, 10, 10], [10, 50, 100, 50]]},)"
      R"({"axis": "z", "segments": [[10, 10, 10, 100], [50, 10, 50, 100]]}]})",
      "zero length");
}

TEST_CASE("LINES.json from a file") {
  const testing::SyntheticScene scene = testing::MakeBoxScene();
  const std::string path = std::string(FACET_BINARY_DIR) + "/test_calibrate_io_lines.json";
  {
    std::ofstream out(path);
    out << LinesJson(scene, {Axis::kX, Axis::kY, Axis::kZ}, "");
  }
  const CalibrateIoResult result = CalibrateLinesFile(path);
  INFO("error: " << result.error);
  CHECK(result.ok());
  std::remove(path.c_str());

  const CalibrateIoResult missing = CalibrateLinesFile(path);
  CHECK_FALSE(missing.ok());
  CHECK(missing.error.find(path) != std::string::npos);
}

}  // namespace
}  // namespace facet
