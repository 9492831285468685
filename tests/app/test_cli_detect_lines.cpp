// `facet calibrate --image PHOTO` as a user runs it: the camera of a rendered room corner with
// a known camera, the printed families re-read as LINES.json giving the same camera, the
// options (principal point, focal prior, known focal length), the EXIF prior by default on
// the Leuven sample, and clear errors for photos that give no camera.
#include <doctest/doctest.h>

#include <cmath>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "core/image/image_io.h"
#include "tests/app/app_test_util.h"
#include "tests/line_image.h"

namespace {

namespace fs = std::filesystem;
using facet::testing::CliResult;
using facet::testing::ReadText;
using facet::testing::RunFacet;
using facet::testing::TempDir;


constexpr int kWidth = 1200, kHeight = 900;
constexpr double kTrueFocalPx = 1000.0;

std::string WriteRoomCorner(const TempDir& dir) {
  const facet::testing::TestCamera camera =
      facet::testing::LookAt({5.0, 4.2, 1.6}, {0.0, 0.0, 1.1}, kTrueFocalPx, kWidth, kHeight);
  const std::string path = dir / "room.png";
  REQUIRE(facet::WritePng(path, facet::testing::RenderRoomCorner(camera, kWidth, kHeight)).empty());
  return path;
}

TEST_CASE("calibrate --help names --image and its options") {
  TempDir dir("facet_cli_image_help");
  const CliResult help = RunFacet(dir, "calibrate --help");
  CHECK(help.exit_code == 0);
  for (const char* option : {"--image", "--principal-point", "--focal-prior", "--focal"})
    CHECK(help.out.find(option) != std::string::npos);
}

TEST_CASE("calibrate --image finds the room corner's camera, and its families re-read as LINES.json give the same") {
  TempDir dir("facet_cli_image");
  const std::string photo = WriteRoomCorner(dir);
  const CliResult r = RunFacet(dir, "calibrate --image '" + photo + "' --focal-prior none");
  REQUIRE_MESSAGE(r.exit_code == 0, r.err);
  const nlohmann::json out = nlohmann::json::parse(r.out);
  const double focal = out["focal_px"].get<double>();
  // The same scene as tests/test_line_detection.cpp, where the fit lands 0.25 % off.
  CHECK(std::abs(focal - kTrueFocalPx) / kTrueFocalPx < 0.01);
  CHECK(out["principal_point"].size() == 2);
  CHECK(out["vanishing_point_axes"] == nlohmann::json({"x", "y", "z"}));
  CHECK(!out.contains("focal_prior_source"));
  const nlohmann::json& lines = out["lines"];
  CHECK(lines["image_size"] == nlohmann::json({kWidth, kHeight}));
  REQUIRE(lines["families"].size() == 3);
  int labelled = 0;
  for (const auto& family : lines["families"]) {
    CHECK(family["segments"].size() >= 10);
    labelled += static_cast<int>(family["segments"].size());
  }
  const nlohmann::json& detection = out["detection"];
  CHECK(detection["segments"].get<int>() == labelled + static_cast<int>(detection["outlier_segments"].size()));
  CHECK(detection["min_length_px"].get<double>() == doctest::Approx(0.025 * std::hypot(kWidth, kHeight)));

  const std::string lines_path = dir / "lines.json";
  std::ofstream(lines_path) << lines.dump(2);
  const CliResult again = RunFacet(dir, "calibrate --lines '" + lines_path + "'");
  REQUIRE_MESSAGE(again.exit_code == 0, again.err);
  const nlohmann::json reread = nlohmann::json::parse(again.out);
  // The same input to the same deterministic fit: equal to the last bit.
  CHECK(reread["focal_px"].get<double>() == focal);
  CHECK(reread["K"] == out["K"]);
  CHECK(reread["R"] == out["R"]);
  CHECK(reread["segment_residuals_px"] == out["segment_residuals_px"]);
}

TEST_CASE("calibrate --image takes the principal point, a focal prior or a known focal length") {
  TempDir dir("facet_cli_image_options");
  const std::string photo = WriteRoomCorner(dir);
  SUBCASE("principal point at the centre") {
    const CliResult r = RunFacet(dir, "calibrate --image '" + photo + "' --principal-point center --focal-prior none");
    REQUIRE_MESSAGE(r.exit_code == 0, r.err);
    const nlohmann::json out = nlohmann::json::parse(r.out);
    CHECK(out["principal_point"] == nlohmann::json({(kWidth - 1) / 2.0, (kHeight - 1) / 2.0}));
    CHECK(out["lines"]["principal_point"] == "center");
  }
  SUBCASE("a known focal length") {
    const CliResult r = RunFacet(dir, "calibrate --image '" + photo + "' --focal 1000");
    REQUIRE_MESSAGE(r.exit_code == 0, r.err);
    const nlohmann::json out = nlohmann::json::parse(r.out);
    CHECK(out["focal_px"].get<double>() == 1000.0);
    CHECK(out["focal_std_px"].get<double>() == 0.0);
    CHECK(out["lines"]["focal_px"].get<double>() == 1000.0);
  }
  SUBCASE("a focal prior") {
    const CliResult r = RunFacet(dir, "calibrate --image '" + photo + "' --focal-prior 1040,30");
    REQUIRE_MESSAGE(r.exit_code == 0, r.err);
    const nlohmann::json out = nlohmann::json::parse(r.out);
    CHECK(out["lines"]["focal_prior_px"].get<double>() == 1040.0);
    CHECK(out["lines"]["focal_prior_std_px"].get<double>() == 30.0);
    CHECK(out["focal_prior_source"] == "given on the command line");
    // The lines fix f to ~0.7 px here (the prior is 4 % off, 1.3 sigma): they win.
    CHECK(std::abs(out["focal_px"].get<double>() - kTrueFocalPx) / kTrueFocalPx < 0.01);
  }
  SUBCASE("a PNG without EXIF: the default prior is absent and says why") {
    const CliResult r = RunFacet(dir, "calibrate --image '" + photo + "'");
    REQUIRE_MESSAGE(r.exit_code == 0, r.err);
    const nlohmann::json out = nlohmann::json::parse(r.out);
    CHECK(out["focal_prior_source"].get<std::string>().rfind("No EXIF focal length", 0) == 0);
    CHECK(!out["lines"].contains("focal_prior_px"));
  }
  SUBCASE("bad options") {
    CliResult r = RunFacet(dir, "calibrate --image '" + photo + "' --principal-point middle");
    CHECK(r.exit_code == 1);
    CHECK(r.err.find("--principal-point must be solve, center or CX,CY") != std::string::npos);
    r = RunFacet(dir, "calibrate --image '" + photo + "' --focal-prior 900");
    CHECK(r.exit_code == 1);
    CHECK(r.err.find("--focal-prior must be exif, none or F,STD") != std::string::npos);
    r = RunFacet(dir, "calibrate --image '" + photo + "' --focal 900 --focal-prior none");
    CHECK(r.exit_code != 0);  // CLI11: --focal excludes --focal-prior
  }
}

TEST_CASE("calibrate --image uses the photo's EXIF focal length as a prior by default (Leuven sample)") {
  TempDir dir("facet_cli_image_leuven");
  const std::string photo = std::string(FACET_SOURCE_DIR) + "/assets/samples/leuven/leuvenA.jpg";
  const CliResult r = RunFacet(dir, "calibrate --image '" + photo + "'");
  REQUIRE_MESSAGE(r.exit_code == 0, r.err);
  const nlohmann::json out = nlohmann::json::parse(r.out);
  CHECK(out["focal_prior_source"] == "focal prior 629 px +- 20 from EXIF (29 mm equivalent)");
  CHECK(out["lines"]["focal_prior_px"].get<double>() == doctest::Approx(629.0).epsilon(0.002));
  // OpenCV's calibration of this iPhone gives 651.4 px (assets/samples/leuven/README.md);
  // EXIF says 629 +- 20 and the lines 651 +- 68 (lines alone): within 2 sigma of the prior.
  CHECK(std::abs(out["focal_px"].get<double>() - 651.4) / 651.4 < 0.06);
  CHECK(out["segments_per_axis"][2].get<int>() >= 20);  // the street's verticals
}

TEST_CASE("calibrate --image: photos that give no camera are clear errors") {
  TempDir dir("facet_cli_image_errors");
  SUBCASE("a blank photo") {
    const std::string path = dir / "blank.png";
    facet::ImageRgba8 blank;
    blank.width = 640;
    blank.height = 480;
    blank.pixels.assign(640 * 480 * 4, 128);
    REQUIRE(facet::WritePng(path, blank).empty());
    const CliResult r = RunFacet(dir, "calibrate --image '" + path + "'");
    CHECK(r.exit_code == 1);
    CHECK(r.out.empty());
    CHECK(r.err.find("no camera from the detected lines: too few line segments") != std::string::npos);
  }
  SUBCASE("a corrupt photo") {
    const std::string path = dir / "corrupt.jpg";
    std::ofstream(path) << "not a JPEG at all";
    const CliResult r = RunFacet(dir, "calibrate --image '" + path + "'");
    CHECK(r.exit_code == 1);
    CHECK(r.err.find("corrupt.jpg") != std::string::npos);
  }
}

}  // namespace
