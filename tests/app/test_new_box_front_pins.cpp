// A new user's first model, replayed through the real application offscreen: the Leuven photo
// with its line families (assets/samples/leuven), its camera not calibrated yet; add a box, pin
// the four corners of its front face on the half-timbered house's front. No pin sees the box's
// depth: the solve holds it at its value (the box as made), says so in the log with the fix,
// and the box lands on the pins. Before, this never solved and the log blamed "a pinned vertex
// lies in the plane of its camera".
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "core/io/project_io.h"
#include "core/scene/project.h"
#include "tests/app/app_test_util.h"

using namespace facet::testing;


// These cases check that points land exactly where the mouse went: the Snap option off
// (render --no-snap); tests/app/test_snapping.cpp covers snapping.
const bool kRenderWithoutSnapping = (RenderWithoutSnapping() = true);

namespace {

const std::string kSampleDir = std::string(FACET_SOURCE_DIR) + "/assets/samples/leuven";

// The house front's corners in the photo (image px), read off leuvenA.jpg where its timber
// frame meets the ground line and the eaves beam (the sample's own box is pinned there too):
// vertex 0 bottom left, 1 bottom right, 4 top left, 5 top right of the box's y = 0 face.
struct FrontCorner {
  int vertex;
  Eigen::Vector2d uv;
};
const FrontCorner kFront[4] = {
    {0, {318.5, 395.5}}, {1, {416.0, 395.5}}, {4, {318.0, 258.3}}, {5, {416.0, 260.0}}};


}  // namespace

TEST_CASE("a new box pinned by its front face's four corners solves, its depth held, the log names why") {
  TempDir dir("new_box_front");
  std::filesystem::copy_file(kSampleDir + "/leuvenA.jpg", dir / "leuvenA.jpg");
  // The sample's photo and lines, as a user who drew them: no box, no pins, camera not
  // calibrated yet (the first update calibrates it, at the world origin).
  const facet::ProjectLoadResult sample = facet::LoadProject(kSampleDir + "/leuven.facet");
  REQUIRE(sample.ok());
  facet::Project p = sample.project;
  p.primitives.clear();
  p.pins.clear();
  p.constraints.clear();
  facet::Image& image = p.images.at(0);
  const facet::Camera fresh_camera;
  image.camera = fresh_camera;
  image.camera.width_px = image.width_px;
  image.camera.height_px = image.height_px;
  image.camera_calibrated = false;
  const facet::Id box_id = p.next_id;  // the id the script's new box gets
  const std::string path = dir / "leuven_new.facet";
  REQUIRE(facet::SaveProject(p, path) == "");

  const nlohmann::json probe = RenderScript(dir, path, "probe", "frames 3\n");
  const View view = ViewFromReport(probe);
  REQUIRE(view.zoom > 0.1);

  std::ostringstream s;
  s << "frames 2\ncommand add box\nframes 1\ncommand tool pin\n";
  for (const FrontCorner& c : kFront) {
    const Eigen::Vector2d screen = view.ToScreen(c.uv);
    REQUIRE(view.Inside(screen, 5.0));
    s << "command select vertex " << box_id << " " << c.vertex << "\nclick left " << FormatXY(screen, 10)
      << "\nframes 1\n";
  }
  const std::string saved = dir / "pinned.facet";
  s << "frames 2\ncommand save " << saved << "\nframes 1\n";
  const nlohmann::json report = RenderScript(dir, path, "pinned", s.str());
  const std::string log = ReportLog(report);
  INFO("log:\n" << log);

  const facet::Project solved = LoadProjectFile(saved);
  REQUIRE(solved.primitives.size() == 1);
  REQUIRE(solved.pins.size() == 4);
  for (const FrontCorner& c : kFront) {
    CAPTURE(c.vertex);
    const auto pin = std::find_if(solved.pins.begin(), solved.pins.end(),
                                  [&](const facet::Pin& q) { return q.vertex.vertex == c.vertex; });
    REQUIRE(pin != solved.pins.end());
    CHECK((pin->uv_px - c.uv).norm() < 1.0 / view.zoom);  // on the clicked whole screen pixel
  }
  const facet::Primitive& box = solved.primitives[0];
  const facet::Image& photo = solved.images.at(0);
  REQUIRE(photo.camera_calibrated);

  // The pins' RMS with the saved camera and box. The rotation is the lines', so the four
  // clicks on the timber cannot all be met; the shipped sample's box on the same four pixels
  // (its depth and height locked) is the reference a sensible fit must not exceed.
  const double rms_px = PinRmsPx(solved);
  const double sample_rms_px = PinRmsPx(sample.project);
  const double width = box.shape.params[0], depth = box.shape.params[1], height = box.shape.params[2];
  const double camera_distance = (photo.camera.CenterInWorld() - box.mesh.vertex(0).position).norm();
  MESSAGE("front pins: RMS " << rms_px << " px (the sample's box " << sample_rms_px << " px); box " << width << " x " << depth << " x " << height
                             << ", camera " << camera_distance << " from corner 0");
  CHECK(rms_px <= sample_rms_px);
  // The depth no pin sees keeps the new box's value; width over height is the front's
  // (the sample's box, fitted with a known height and depth: 3.592 / 5).
  CHECK(depth == 1.0);
  constexpr double kSampleAspect = 3.592244427160711 / 5.0;
  CHECK(std::abs(width / height / kSampleAspect - 1.0) < 0.03);
  CHECK(camera_distance > 2.0 * height);  // the camera moved off the box's corner

  // The log: the real cause with the fix, and not the old misleading cause once four pins are in.
  CHECK(log.find("depth (y size) of box") != std::string::npos);
  CHECK(log.find("is seen by no pin") != std::string::npos);
  CHECK(log.find("back face") != std::string::npos);
  // The first pin alone cannot place anything: the log says so as the cause a user acts on.
  CHECK(log.find("no start yet") != std::string::npos);
  const size_t last_pin = log.rfind("Pin vertex");
  REQUIRE(last_pin != std::string::npos);
  CHECK(log.find("plane of its camera", last_pin) == std::string::npos);
  CHECK(log.find("error:", last_pin) == std::string::npos);
}
