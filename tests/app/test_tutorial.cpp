// The Leuven tutorial (assets/samples/leuven/tutorial.txt): the half-timbered house, a box
// with a gable roof, modelled from an empty project by the script of UI events a user makes,
// replayed through the real application with snapping on. Checks what the tutorial promises:
// the house lands on the photo, at the typed scale and depth, textured wherever the photo
// sees it, in at most 40 UI events (issue 12's target for this house; a new user took 101).
// Writes the step screenshots the README shows (FACET_BINARY_DIR/tutorial/; assets/samples/leuven/tutorial/
// holds the copies shown).
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "core/image/image_io.h"
#include "core/io/project_io.h"
#include "core/scene/project.h"
#include "core/texture/textured_mesh.h"
#include "tests/app/app_test_util.h"

using namespace facet::testing;

namespace {

const std::string kSampleDir = std::string(FACET_SOURCE_DIR) + "/assets/samples/leuven";
const char* const kSteps[] = {"tutorial-1-detected-lines", "tutorial-2-box-pinned", "tutorial-3-roof",
                              "tutorial-4-house"};
constexpr int kMaxUiEvents = 40;
// The reprojection RMS of the five pins. The rotation is the detected lines' (kept by the
// solve), the corners are where snapping put them; the timber frame is not an exact rectangle
// in that frame, so the pins cannot all be met: 2.35 px measured, the bound leaves room for
// float noise in the line detection only.
constexpr double kMaxPinRmsPx = 2.6;

// Whether the face faces the camera and its centroid projects inside the photo.
bool SeenBy(const facet::Camera& camera, const facet::PolyMesh& mesh, facet::FaceId face) {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  int n = 0;
  for (facet::HalfedgeId h : facet::FaceHalfedges(mesh, face)) {
    centroid += mesh.vertex(mesh.Origin(h)).position;
    ++n;
  }
  centroid /= n;
  const Eigen::Vector3d normal = facet::FaceNormal(mesh, face);
  if (normal.dot(camera.CenterInWorld() - centroid) <= 0.0) return false;
  const Eigen::Vector2d uv = camera.Project(centroid);
  return camera.CamFromWorld(centroid).z() > 0.0 && uv.x() >= 0 && uv.y() >= 0 && uv.x() < camera.width_px &&
         uv.y() < camera.height_px;
}

}  // namespace

TEST_CASE("the tutorial builds the house from an empty project in at most 40 UI events") {
  TempDir dir("tutorial");
  fs::copy_file(kSampleDir + "/leuvenA.jpg", dir / "leuvenA.jpg");
  facet::Project empty;
  const std::string empty_path = dir / "empty.facet";
  REQUIRE(facet::SaveProject(empty, empty_path) == "");
  const std::string saved = dir / "house.facet";
  WriteText(dir / "run.txt", ReadText(kSampleDir + "/tutorial.txt") + "frames 2\ncommand save " + saved + "\n");

  const std::string report_path = dir / "report.json";
  const RunResult run = RunRender(dir, "'" + empty_path + "' -o '" + (dir / "final.png") + "' --script run.txt --report '" +
                                           report_path + "'",
                                  dir.path.string());
  INFO("stderr: " << run.stderr_text);
  REQUIRE(run.exit_code == 0);
  const nlohmann::json report = nlohmann::json::parse(ReadText(report_path));
  INFO("log:\n" << ReportLog(report));

  // The script counts one event for the save it was given here; the tutorial itself has one less.
  const int ui_events = report.at("script_ui_events").get<int>() - 1;
  MESSAGE("tutorial: " << ui_events << " UI events");
  CHECK(ui_events <= kMaxUiEvents);

  const facet::Project house = LoadProjectFile(saved);
  REQUIRE(house.images.size() == 1);
  REQUIRE(house.images[0].camera_calibrated);
  REQUIRE(house.primitives.size() == 2);
  CHECK(house.pins.size() == 5);
  const facet::Primitive& box = house.primitives[0];
  const facet::Primitive& roof = house.primitives[1];
  CHECK(box.shape.kind == facet::PrimitiveKind::kBox);
  CHECK(roof.shape.kind == facet::PrimitiveKind::kWedge);
  CHECK(roof.attached_to == box.id);
  CHECK(roof.shape.ridge_along_y);
  // Measure: the front's left edge is 5 m (the known length takes the scale over from the
  // first box's kept height, and says so); the typed depth, 8 m, kept.
  CHECK(ReportLog(report).find("box 1's Size z is no longer kept: the known length sets the scale") !=
        std::string::npos);
  CHECK_FALSE(box.param_locked[2]);
  CHECK(std::abs(box.shape.params[2] - 5.0) < 1e-6);
  CHECK(box.shape.params[1] == 8.0);
  CHECK(box.param_locked[1]);
  // A house, not a sliver: the front about as wide as the photo says (3.6 m for the sample's
  // hand-placed pins), the roof a real gable.
  CHECK(box.shape.params[0] > 3.0);
  CHECK(box.shape.params[0] < 4.0);
  CHECK(roof.shape.params[2] > 2.0);

  const double rms_px = report.at("joint_solve").at("rms_px").get<double>();
  MESSAGE("tutorial: pin RMS " << rms_px << " px");
  CHECK(rms_px < kMaxPinRmsPx);

  // Textured wherever the photo sees the house.
  const facet::ImageReadResult photo = facet::ReadImage(dir / "leuvenA.jpg");
  REQUIRE(photo.ok());
  facet::TexturedMesh mesh;
  const std::vector<const facet::ImageRgba8*> photos = {&photo.image};
  const facet::TextureBakeSummary bake = facet::BakeTexturedMesh(house, photos, facet::TextureBakeOptions{}, &mesh);
  REQUIRE(bake.IsUsable());
  int seen = 0;
  for (size_t t = 0; t < mesh.triangle_face.size(); ++t) {
    const facet::Primitive* p = house.FindPrimitive(mesh.triangle_primitive[t]);
    REQUIRE(p != nullptr);
    if (!SeenBy(house.images[0].camera, p->mesh, mesh.triangle_face[t])) continue;
    // A roof's base lies on its box's top: inside the house, hidden from every view.
    if (p->attached_to != facet::kNoId && facet::FaceNormal(p->mesh, mesh.triangle_face[t]).z() < -0.99) continue;
    ++seen;
    CAPTURE(p->name);
    CAPTURE(mesh.triangle_face[t]);
    CHECK(mesh.triangle_textured[t]);
  }
  CHECK(seen >= 3);  // the front's two triangles and the gable's

  // The README's step pictures.
  const fs::path shots = fs::path(FACET_BINARY_DIR) / "tutorial";
  fs::create_directories(shots);
  for (const char* step : kSteps) {
    const cv::Mat shot = cv::imread(dir / (std::string(step) + ".png"));
    REQUIRE_MESSAGE(!shot.empty(), step);
    cv::Mat small;
    cv::resize(shot, small, cv::Size(), 0.75, 0.75, cv::INTER_AREA);
    CHECK(cv::imwrite((shots / (std::string(step) + ".jpg")).string(), small, {cv::IMWRITE_JPEG_QUALITY, 85}));
  }
}
