// The JSON adapter of single-image calibration (core/io/calibrate_io.h): a synthetic scene's
// line families written as LINES.json come back as its camera; bad input gives messages.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "core/estimators/calibrate_vp.h"
#include "core/geometry/camera_checks.h"
#include "core/io/calibrate_io.h"
#include "core/util/input_limits.h"
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
      out << (first ? "" : ", ") << "[" << s.a_px.x() << ", " << s.a_px.y() << ", " << s.b_px.x() << ", " << s.b_px.y()
          << "]";
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
  const Eigen::Vector2d pp(out.at("principal_point").at(0).get<double>(),
                           out.at("principal_point").at(1).get<double>());
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
  REQUIRE(core.IsUsable());
  CHECK(focal_px == core.focal_px);
  CHECK(MatrixFromRows(out.at("R")) == core.cam_from_world_rotation);
  // The rotation is the truth up to the sign convention of the world axes.
  const Eigen::Matrix3d r = MatrixFromRows(out.at("R"));
  for (int c = 0; c < 3; ++c)
    CHECK(std::abs(std::abs(r.col(c).dot(truth.cam_from_world_rotation.col(c))) - 1.0) < 1e-9);

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

  // Uncertainty and degeneracy figures, the same as the core's.
  CHECK(out.at("focal_std_px").get<double>() == core.focal_std_px);
  CHECK(out.at("focal_std_px").get<double>() < kNoiseFreeRelative * truth.focal_px);
  CHECK(out.at("principal_point_std_px").size() == 2);
  CHECK(out.at("outlier_segments") == json::array());
  CHECK(out.at("outlier_threshold_px").get<double>() == core.outlier_threshold_px);
  for (const char* key :
       {"vanishing_direction_std_deg", "family_angle_spread_deg", "vanishing_point_to_principal_point_px"})
    CHECK(out.at(key).size() == 3);
  for (int a = 0; a < 3; ++a) {
    CHECK(out["family_angle_spread_deg"][a].get<double>() == core.family_angle_spread_deg[a]);
    CHECK(out["vanishing_point_to_principal_point_px"][a].get<double>() ==
          core.vanishing_point_to_principal_point_px[a]);
  }
  CHECK(out.at("vanishing_point_triangle_max_angle_deg").get<double>() == core.vanishing_point_triangle_max_angle_deg);
  CHECK(out.at("min_family_angle_spread_deg").get<double>() == core.min_family_angle_spread_deg);
  CHECK(out.at("min_vanishing_point_to_principal_point_px").get<double>() ==
        core.min_vanishing_point_to_principal_point_px);
  CHECK_FALSE(out.contains("distortion"));
  CHECK_FALSE(out.contains("horizon_residual_px"));
}

std::string Fixed17(double x) {
  std::ostringstream out;
  out << std::setprecision(17) << x;
  return out.str();
}

TEST_CASE("focal length fixed or under a prior, the horizon, and flagged outliers") {
  const testing::SyntheticScene scene = testing::MakeBoxScene();
  const Camera& truth = scene.true_camera;
  const std::string pp_field = ", \"principal_point\": [" + Fixed17(truth.principal_point_px.x()) + ", " +
                               Fixed17(truth.principal_point_px.y()) + "]";

  SUBCASE("a fixed focal length is kept and has no std") {
    const std::string field = ", \"focal_px\": " + Fixed17(1.02 * truth.focal_px);
    const CalibrateIoResult r = CalibrateLinesJson(LinesJson(scene, {Axis::kX, Axis::kY, Axis::kZ}, field));
    INFO("error: " << r.error);
    REQUIRE(r.ok());
    const json out = json::parse(r.json);
    CHECK(out.at("focal_px").get<double>() == 1.02 * truth.focal_px);
    CHECK(out.at("focal_std_px").get<double>() == 0.0);
  }
  SUBCASE("a prior: exact data outweigh it") {
    const std::string field =
        pp_field + ", \"focal_prior_px\": " + Fixed17(1.05 * truth.focal_px) + ", \"focal_prior_std_px\": 20";
    const CalibrateIoResult r = CalibrateLinesJson(LinesJson(scene, {Axis::kX, Axis::kZ}, field));
    INFO("error: " << r.error);
    REQUIRE(r.ok());
    const json out = json::parse(r.json);
    CHECK(std::abs(out.at("focal_px").get<double>() - truth.focal_px) < kNoiseFreeRelative * truth.focal_px);
  }
  SUBCASE("one family, a known focal length and the horizon") {
    const Eigen::Vector3d line = truth.K().inverse().transpose() * truth.cam_from_world_rotation.col(2);
    const double x2 = truth.width_px - 1.0;
    const std::string field = pp_field + ", \"focal_px\": " + Fixed17(truth.focal_px) + ", \"horizon\": [0, " +
                              Fixed17(-line.z() / line.y()) + ", " + Fixed17(x2) + ", " +
                              Fixed17(-(line.x() * x2 + line.z()) / line.y()) + "]";
    const CalibrateIoResult r = CalibrateLinesJson(LinesJson(scene, {Axis::kY}, field));
    INFO("error: " << r.error);
    REQUIRE(r.ok());
    const json out = json::parse(r.json);
    const Eigen::Matrix3d rotation = MatrixFromRows(out.at("R"));
    for (int c = 0; c < 3; ++c)
      CHECK(std::abs(std::abs(rotation.col(c).dot(truth.cam_from_world_rotation.col(c))) - 1.0) < 1e-9);
    CHECK(out.at("horizon_residual_px").get<double>() < 1e-9);
    CHECK(out.at("vanishing_point_axes") == json({"y"}));
  }
  SUBCASE("a level horizon given as its row") {
    testing::SyntheticSceneOptions o;
    o.roll_deg = 0.0;
    const testing::SyntheticScene level = testing::MakeBoxScene(o);
    const Camera& cam = level.true_camera;
    const Eigen::Vector3d line = cam.K().inverse().transpose() * cam.cam_from_world_rotation.col(2);
    REQUIRE(std::abs(line.x()) < 1e-12 * std::abs(line.y()));
    const std::string field = ", \"principal_point\": [" + Fixed17(cam.principal_point_px.x()) + ", " +
                              Fixed17(cam.principal_point_px.y()) + "], \"focal_px\": " + Fixed17(cam.focal_px) +
                              ", \"horizon\": " + Fixed17(-line.z() / line.y());
    const CalibrateIoResult r = CalibrateLinesJson(LinesJson(level, {Axis::kX}, field));
    INFO("error: " << r.error);
    REQUIRE(r.ok());
    const Eigen::Matrix3d rotation = MatrixFromRows(json::parse(r.json).at("R"));
    for (int c = 0; c < 3; ++c)
      CHECK(std::abs(std::abs(rotation.col(c).dot(cam.cam_from_world_rotation.col(c))) - 1.0) < 1e-9);
  }
  SUBCASE("a wrong segment is listed in outlier_segments") {
    testing::SyntheticScene noisy = scene;
    // Segment 3 of the x family (families in x, y, z order: index 3 overall); 6 px off.
    int seen = -1, index = -1;
    for (size_t i = 0; i < noisy.project.segments.size() && index < 0; ++i)
      if (noisy.project.segments[i].axis == Axis::kX && ++seen == 3) index = static_cast<int>(i);
    REQUIRE(index >= 0);
    noisy.project.segments[index].a_px.y() += 6.0;
    const CalibrateIoResult r = CalibrateLinesJson(LinesJson(noisy, {Axis::kX, Axis::kY, Axis::kZ}, ""));
    INFO("error: " << r.error);
    REQUIRE(r.ok());
    const json out = json::parse(r.json);
    CHECK(out.at("outlier_segments") == json({3}));
    CHECK(out.at("refitted_without_outliers").get<bool>());
    CHECK(out.at("segment_residuals_px").at(3).get<double>() > out.at("outlier_threshold_px").get<double>());
  }
}

TEST_CASE("\"distortion\": true estimates it from the same segments first") {
  const testing::SyntheticScene scene = testing::MakeBoxScene();
  const CalibrateIoResult r =
      CalibrateLinesJson(LinesJson(scene, {Axis::kX, Axis::kY, Axis::kZ}, ", \"distortion\": true"));
  INFO("error: " << r.error);
  REQUIRE(r.ok());
  const json out = json::parse(r.json);
  REQUIRE(out.contains("distortion"));
  const json& d = out.at("distortion");
  // A pinhole scene: no distortion found, and the camera as without the option.
  CAPTURE(d.dump());
  CHECK(std::abs(d.at("k1").get<double>()) < 1e-9);
  CHECK(d.at("k2").get<double>() == 0.0);
  CHECK(d.at("center").size() == 2);
  CHECK(d.at("scale_px").get<double>() > 0.0);
  CHECK(std::abs(out.at("focal_px").get<double>() - scene.true_camera.focal_px) < 1e-7 * scene.true_camera.focal_px);
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
  // At infinity: said so, with the direction of the (parallel, here vertical) segments.
  const json& infinite = out.at("vanishing_points").at(2);
  REQUIRE(infinite.is_object());
  CHECK(infinite.at("at_infinity") == true);
  const Eigen::Vector2d direction(infinite.at("direction").at(0).get<double>(),
                                  infinite.at("direction").at(1).get<double>());
  CHECK(std::abs(direction.norm() - 1.0) < 1e-12);
  for (const Segment& z : scene.project.segments) {
    if (z.axis != Axis::kZ) continue;
    const Eigen::Vector2d d = (z.b_px - z.a_px).normalized();
    CHECK(std::abs(d.x() * direction.y() - d.y() * direction.x()) < 1e-9);
  }
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

TEST_CASE("regression: more than kMaxCalibrationSegments segments are refused by name, before any is read (issue 25)") {
  // 1e6 segments took tens of seconds; the count is checked first.
  std::string segments;
  for (size_t i = 0; i <= kMaxCalibrationSegments; ++i) segments += std::string(i ? ", " : "") + "[1, 2, 3, 4]";
  const std::string text = R"({"image_size": [640, 480], "families": [{"axis": "x", "segments": [)" + segments + "]}]}";
  const CalibrateIoResult result = CalibrateLinesJson(text);
  CHECK_FALSE(result.ok());
  CHECK(result.error == "a calibration takes at most " + std::to_string(kMaxCalibrationSegments) +
                            " line segments; this file has " + std::to_string(kMaxCalibrationSegments + 1));
}

TEST_CASE("at kMaxCalibrationSegments segments the synthetic camera comes back (issue 25)") {
  testing::SyntheticSceneOptions o;
  o.extra_lines_per_axis = static_cast<int>(kMaxCalibrationSegments / 3) - 4;  // 4 edges per axis besides
  testing::SyntheticScene scene = testing::MakeBoxScene(o);
  while (scene.project.segments.size() < kMaxCalibrationSegments)  // a repeated segment changes no solution
    scene.project.segments.push_back(scene.project.segments.front());
  REQUIRE(scene.project.segments.size() == kMaxCalibrationSegments);
  const CalibrateIoResult result = CalibrateLinesJson(LinesJson(scene, {Axis::kX, Axis::kY, Axis::kZ}, ""));
  INFO("error: " << result.error);
  REQUIRE(result.ok());
  const double focal_px = json::parse(result.json).at("focal_px").get<double>();
  CHECK(std::abs(focal_px - scene.true_camera.focal_px) < 1e-6 * scene.true_camera.focal_px);
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
  CheckError(R"({"image_size": [640, 480], "families": [)"
             R"({"axis": "x", "segments": [[10, 10, 100, 10], [10, 50, 100, 50]]},)"
             R"({"axis": "z", "segments": [[10, 10, 10, 100], [50, 10, 50, 100]]}]})",
             "undetermined");
  CheckError(valid.substr(0, valid.size() - 1) + ", \"principal_point\": \"middle\"}", "principal_point");
  CheckError(valid.substr(0, valid.size() - 1) + ", \"principal_point\": [1]}", "principal_point");
  CheckError(valid.substr(0, valid.size() - 1) + ", \"focal_px\": -5}", "focal_px");
  CheckError(valid.substr(0, valid.size() - 1) + ", \"focal_px\": \"900\"}", "focal_px");
  CheckError(valid.substr(0, valid.size() - 1) + ", \"focal_prior_px\": 900}", "go together");
  CheckError(valid.substr(0, valid.size() - 1) + ", \"focal_prior_px\": 900, \"focal_prior_std_px\": 0}",
             "focal_prior_std_px");
  CheckError(
      valid.substr(0, valid.size() - 1) + ", \"focal_px\": 900, \"focal_prior_px\": 900, \"focal_prior_std_px\": 9}",
      "not both");
  CheckError(valid.substr(0, valid.size() - 1) + ", \"horizon\": [1, 2, 3]}", "horizon");
  CheckError(valid.substr(0, valid.size() - 1) + ", \"horizon\": [1, 2, 1, 2]}", "horizon");
  CheckError(valid.substr(0, valid.size() - 1) + ", \"distortion\": 1}", "distortion");
  CheckError(valid.substr(0, valid.size() - 1) + ", \"refit_without_outliers\": \"yes\"}", "refit_without_outliers");
  // One family without a horizon, and with a horizon but no focal length.
  CheckError(LinesJson(scene, {Axis::kX}, ", \"horizon\": 300"), "known focal length");
  CheckError(R"({"image_size": [640, 480], "families": [)"
             R"({"axis": "x", "segments": [[10, 10, 10, 10], [10, 50, 100, 50]]},)"
             R"({"axis": "z", "segments": [[10, 10, 10, 100], [50, 10, 50, 100]]}]})",
             "zero length");
}

// Issue 25: a focal prior with std 1e-300 and a horizon at 1e308 were ignored and the output
// held nulls; a known focal length of 1e-300 or 1e308 px was no lens. Each is refused where it
// enters, by name.
TEST_CASE("LINES.json: focal lengths, priors and horizons that are no camera are refused by name") {
  const testing::SyntheticScene scene = testing::MakeBoxScene();
  const std::string valid = LinesJson(scene, {Axis::kX, Axis::kY, Axis::kZ}, "");
  REQUIRE(CalibrateLinesJson(valid).ok());
  const std::string open = valid.substr(0, valid.size() - 1);
  const double f = scene.true_camera.focal_px;
  for (const char* focal : {"1e-300", "1e308", "1e200", "0.5"})
    CheckError(open + ", \"focal_px\": " + focal + "}", "\"focal_px\"");
  CheckError(open + ", \"focal_prior_px\": " + Fixed17(f) + ", \"focal_prior_std_px\": 1e-300}", "standard deviation");
  CheckError(open + ", \"focal_prior_px\": 1e308, \"focal_prior_std_px\": 10}", "focal_prior_px");
  CheckError(open + ", \"focal_px\": " + Fixed17(f) + ", \"horizon\": 1e308}", "\"horizon\"");
  CheckError(open + ", \"focal_px\": " + Fixed17(f) + ", \"horizon\": [0, 1e308, 10, 1e308]}", "\"horizon\"");
  // A prior as tight as the floor allows is still taken: the check is on the number, not the use.
  const CalibrateIoResult tight =
      CalibrateLinesJson(open + ", \"focal_prior_px\": " + Fixed17(f) +
                         ", \"focal_prior_std_px\": " + Fixed17(2.0 * kMinFocalPriorRelativeStd * f) + "}");
  REQUIRE_MESSAGE(tight.ok(), tight.error);
  // No success output prints null for a figure the input determines.
  const json out = json::parse(tight.json);
  for (const char* key : {"focal_px", "residual_sigma_px", "min_family_angle_spread_deg"}) {
    CAPTURE(key);
    CHECK(out.at(key).is_number());
  }
}

// Issue 14: these inputs printed a focal length as an answer (f = 66,000 +- 1.6e7 px for an
// exactly parallel family with the principal point centred, f = 170 px for one family given
// twice); each is now an error that says why.
TEST_CASE("degenerate families give no camera, never a number") {
  const testing::SyntheticScene scene = testing::MakeBoxScene();
  const json valid = json::parse(LinesJson(scene, {Axis::kX, Axis::kY, Axis::kZ}, ""));
  REQUIRE(CalibrateLinesJson(valid.dump()).ok());
  auto with = [&](int family, const json& segments, const json& principal_point) {
    json doc = valid;
    if (family >= 0) doc["families"][family]["segments"] = segments;
    doc["principal_point"] = principal_point;
    return doc.dump();
  };
  const json parallel = json::array({{100, 100, 300, 100}, {100, 150, 300, 150}, {100, 200, 300, 200}});
  const json x_segments = valid["families"][0]["segments"];
  for (const json& pp : {json("center"), json("solve")}) {
    INFO("principal point: " << pp.dump());
    // An exactly parallel family: with the centre, f rests on nothing (it came out as 6.6e4 +- 1.6e7 px).
    CheckError(with(0, parallel, pp), pp == "center" ? "not determined" : "parallel");
    // The x family given again as y, then as z: one direction, not two.
    CheckError(with(1, x_segments, pp), "family x and family y meet at one vanishing point");
    CheckError(with(2, x_segments, pp), "family x and family z meet at one vanishing point");
  }
  // A fixed principal point far outside any photo is no camera, whatever the fit says.
  const CalibrateIoResult far = CalibrateLinesJson(with(-1, json(), json::array({1e12, -1e12})));
  CHECK_FALSE(far.ok());
  INFO("error: " << far.error);
  CHECK(far.error.find("calibration failed") != std::string::npos);
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
