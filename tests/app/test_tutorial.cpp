// The Leuven tutorial (assets/samples/leuven/tutorial.txt): the three houses of the photo's
// street, each a box with a gable roof, modelled from an empty project by the script of UI
// events a user makes, replayed through the real application with snapping on. Checks what
// the tutorial promises: the houses land on the photo (pin reprojection per house), stand on
// the ground at the scale of the one measured length, the half-timbered front is split at its
// storey line (E_split, V_connect: two faces, the line level and pinned on the photo's sill),
// the houses are textured wherever the photo sees them, take at most 40 UI events each
// (issue 12's target for a house; a new user took 101 for the first one), and the saved
// result is the sample the app opens (assets/samples/leuven/street.facet). Writes the step
// screenshots the README shows (FACET_BINARY_DIR/tutorial/; assets/samples/leuven/tutorial/
// holds the copies shown).
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "app/state/input_script.h"
#include "core/geometry/camera.h"
#include "core/image/image_io.h"
#include "core/io/project_io.h"
#include "core/scene/project.h"
#include "core/texture/textured_mesh.h"
#include "tests/app/app_test_util.h"

using namespace facet::testing;

namespace {

const std::string kSampleDir = std::string(FACET_SOURCE_DIR) + "/assets/samples/leuven";
const char* const kSteps[] = {"tutorial-1-detected-lines", "tutorial-2-box-pinned",  "tutorial-3-roof",
                              "tutorial-4-house",          "tutorial-5-storey-line", "tutorial-6-left-house",
                              "tutorial-7-street"};
constexpr int kMaxUiEventsPerHouse = 40;
// Pin reprojection RMS per house, in px. The half-timbered house: the rotation is the
// detected lines' (kept by the solve) and its corners are where snapping put them; the timber
// frame is not an exact rectangle in that frame, so its seven pins (five corners, the storey
// line's two ends) cannot all be met: 2.12 px measured (2.36 px over the five before the
// storey line), the bound leaves room for float noise in the line detection only. The two other
// houses have three pins each (six coordinates) for five free dimensions and positions (the
// foot on the ground, the depth typed and kept, the left house's turn typed), so one
// coordinate each is a check: 0.72 px (left) and 0.26 px (right)
// measured; 1.5 px fails a solve that leaves them (a roof whose ridge runs the wrong way, or
// the left house's gable taken as facing the street, is off by 5-80 px).
constexpr double kMaxFirstHouseRmsPx = 2.6;
constexpr double kMaxOtherHouseRmsPx = 1.5;
// The storey line (E_split on the front's two vertical edges, V_connect across the front).
// Each end is where its splitting click's ray passes the edge, so the line is level as far as
// the two clicks are on one horizontal line of the photo: 0.6 cm apart measured, a pixel is
// ~4 cm on the front (~27 px per m); 0.1 m fails one end split anywhere but at the sill (at
// its edge's middle, where the split snaps within 6 screen px, it is 0.28 m higher). Their
// pins, on the sill's ends where the clicks were, are met to 1.11 px measured: the ends lie on
// the box's vertical edges, which the corner pins put 1-2 px inside the corner posts (the
// timber frame is not an exact rectangle: the corners' own RMS above); 2 px fails an end
// split 0.1 m (~3 px) off the sill.
constexpr double kMaxSillTiltM = 0.1;
constexpr double kMaxSillPinRmsPx = 2.0;

Eigen::Vector3d FaceCentroid(const facet::PolyMesh& mesh, facet::FaceId face) {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  int n = 0;
  for (facet::HalfedgeId h : facet::FaceHalfedges(mesh, face)) {
    centroid += mesh.vertex(mesh.Origin(h)).position;
    ++n;
  }
  return centroid / n;
}

// Whether the face faces the camera and its centroid projects inside the photo.
bool SeenBy(const facet::Camera& camera, const facet::PolyMesh& mesh, facet::FaceId face) {
  const Eigen::Vector3d centroid = FaceCentroid(mesh, face);
  const Eigen::Vector3d normal = facet::FaceNormal(mesh, face);
  if (normal.dot(camera.CenterInWorld() - centroid) <= 0.0) return false;
  const Eigen::Vector2d uv = camera.Project(centroid);
  return camera.CamFromWorld(centroid).z() > 0.0 && uv.x() >= 0 && uv.y() >= 0 && uv.x() < camera.width_px &&
         uv.y() < camera.height_px;
}

// The UI events of each "# house:" section of the script (what a user does by hand).
std::vector<int> UiEventsPerHouse(const std::string& script_text) {
  std::vector<std::string> sections;
  std::istringstream in(script_text);
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("# house:", 0) == 0) sections.emplace_back();
    if (!sections.empty()) sections.back() += line + "\n";
  }
  std::vector<int> counts;
  for (const std::string& section : sections) {
    facet::app::Script script;
    std::string error;
    REQUIRE_MESSAGE(facet::app::ParseScript(section, &script, &error), error);
    counts.push_back(script.ui_events);
  }
  return counts;
}

// The house a primitive belongs to: its box (a roof's base).
facet::Id HouseOf(const facet::Project& project, facet::Id primitive_id) {
  const facet::Primitive* p = project.FindPrimitive(primitive_id);
  REQUIRE(p != nullptr);
  return p->attached_to != facet::kNoId ? p->attached_to : p->id;
}

}  // namespace

TEST_CASE("the tutorial builds the street's three houses from an empty project, at most 40 UI events each") {
  TempDir dir("tutorial");
  fs::copy_file(kSampleDir + "/leuvenA.jpg", dir / "leuvenA.jpg");
  facet::Project empty;
  const std::string empty_path = dir / "empty.facet";
  REQUIRE(facet::SaveProject(empty, empty_path) == "");
  const std::string saved = dir / "street.facet";
  const std::string tutorial = ReadText(kSampleDir + "/tutorial.txt");
  WriteText(dir / "run.txt", tutorial + "frames 2\ncommand save " + saved + "\n");

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
  const std::vector<int> per_house = UiEventsPerHouse(tutorial);
  REQUIRE(per_house.size() == 3);
  MESSAGE("tutorial: " << ui_events << " UI events; per house " << per_house[0] << ", " << per_house[1] << ", "
                       << per_house[2]);
  CHECK(per_house[0] + per_house[1] + per_house[2] == ui_events);
  for (int count : per_house) CHECK(count <= kMaxUiEventsPerHouse);

  const facet::Project street = LoadProjectFile(saved);
  REQUIRE(street.images.size() == 1);
  REQUIRE(street.images[0].camera_calibrated);
  const facet::Camera& camera = street.images[0].camera;
  REQUIRE(street.primitives.size() == 6);
  for (size_t h = 0; h < 3; ++h) {
    const facet::Primitive& box = street.primitives[2 * h];
    const facet::Primitive& roof = street.primitives[2 * h + 1];
    CAPTURE(h);
    CHECK(box.shape.kind == facet::PrimitiveKind::kBox);
    CHECK(box.attached_to == facet::kNoId);
    CHECK(roof.shape.kind == facet::PrimitiveKind::kWedge);
    CHECK(roof.attached_to == box.id);
    // Every house stands on the ground the first one defines (z = 0): the later ones by the
    // constraint B adds, which the solve meets.
    CHECK(std::abs(box.shape.translation.z()) < 1e-6);
  }
  // The scale (Measure's distance) and the two ground constraints, nothing else.
  REQUIRE(street.constraints.size() == 3);
  CHECK(street.constraints[0].kind == facet::ConstraintKind::kDistance);
  CHECK(street.constraints[1].kind == facet::ConstraintKind::kCoplanar);
  CHECK(street.constraints[2].kind == facet::ConstraintKind::kCoplanar);
  const facet::Primitive& house = street.primitives[0];
  const facet::Primitive& house_roof = street.primitives[1];
  const facet::Primitive& left = street.primitives[2];
  const facet::Primitive& left_roof = street.primitives[3];
  const facet::Primitive& right = street.primitives[4];
  const facet::Primitive& right_roof = street.primitives[5];
  CHECK(house_roof.shape.ridge_along_y);
  CHECK(left_roof.shape.ridge_along_y);  // its gable end faces the camera
  CHECK_FALSE(right_roof.shape.ridge_along_y);

  // The one known length: the half-timbered front's left edge is 5 m (Measure; it takes the
  // scale over from the first box's kept height, and says so); its typed depth, 8 m, kept.
  CHECK(ReportLog(report).find("box 1's Size z is no longer kept: the known length sets the scale") !=
        std::string::npos);
  CHECK_FALSE(house.param_locked[2]);
  CHECK(std::abs(house.shape.params[2] - 5.0) < 1e-6);
  CHECK(house.shape.params[1] == 8.0);
  CHECK(house.param_locked[1]);
  // The other houses' typed depths are kept as typed (the left house's, 8 m, seen by no pin;
  // the right house's, 10 m: its foot is hidden, so nothing else sets its distance); none of
  // their other dimensions is typed or kept.
  CHECK(left.shape.params[1] == 8.0);
  CHECK(right.shape.params[1] == 10.0);
  for (const facet::Primitive* p : {&left, &left_roof, &right, &right_roof}) {
    CAPTURE(p->name);
    for (int k = 0; k < 4; ++k) CHECK(p->param_locked[k] == (k == 1 && p->attached_to == facet::kNoId));
  }
  // What the pins give, at the scale of the 5 m edge: houses, not slivers. The half-timbered
  // front about as wide as the photo says (3.6 m for the hand-placed pins of leuven.facet), its
  // gable a real one; the left house's eaves above the first house's (the photo shows them
  // higher, nearer the camera) but below three storeys, under a steep roof (its visible gable
  // edge rises about as far as the house is half wide: a pitch of 45-65 degrees); the right
  // house's eaves at one or two storeys under a tall roof (the photo shows its roof about as
  // tall as its wall).
  MESSAGE("dimensions (m): half-timbered " << house.shape.params.head<3>().transpose() << " roof "
                                           << house_roof.shape.params[2] << "; left " << left.shape.params.head<3>().transpose()
                                           << " roof " << left_roof.shape.params[2] << "; right "
                                           << right.shape.params.head<3>().transpose() << " roof "
                                           << right_roof.shape.params[2]);
  CHECK(house.shape.params[0] > 3.0);
  CHECK(house.shape.params[0] < 4.0);
  CHECK(house_roof.shape.params[2] > 2.0);
  CHECK(left.shape.params[2] > 5.0);
  CHECK(left.shape.params[2] < 9.0);
  const double left_pitch_deg = std::atan2(left_roof.shape.params[2], 0.5 * left.shape.params[0]) * 180.0 / M_PI;
  MESSAGE("left roof pitch " << left_pitch_deg << " deg");
  CHECK(left_pitch_deg > 45.0);
  CHECK(left_pitch_deg < 65.0);
  CHECK(right.shape.params[2] > 4.0);
  CHECK(right.shape.params[2] < 8.0);
  CHECK(right_roof.shape.params[2] > 4.0);
  CHECK(right_roof.shape.params[2] < 9.0);
  // Each house on its side of the street: the left one left of the first, the right one right.
  double left_max_x = -1e300;
  for (const Eigen::Vector3d& corner : BoxCorners(left)) left_max_x = std::max(left_max_x, corner.x());
  CHECK(left_max_x < house.shape.translation.x());
  CHECK(right.shape.translation.x() > house.shape.translation.x() + house.shape.params[0]);

  // The left house is turned towards the camera (15 deg typed, kept): the photo shows no side
  // beside its right corner, and the model's right side faces away from the camera too.
  CHECK(std::abs(left.shape.rotation.z() * 180.0 / M_PI - 15.0) < 1e-9);
  CHECK(left.rotation_locked);
  const Eigen::Vector3d left_side_normal = facet::RotationFromAngleAxis(left.shape.rotation) * Eigen::Vector3d::UnitX();
  int left_sides = 0;
  for (facet::FaceId f = 0; f < left.mesh.FaceIdEnd(); ++f) {
    if (!left.mesh.IsFace(f) || facet::FaceNormal(left.mesh, f).dot(left_side_normal) < 0.99) continue;
    ++left_sides;
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    int n = 0;
    for (facet::HalfedgeId h : facet::FaceHalfedges(left.mesh, f)) {
      centroid += left.mesh.vertex(left.mesh.Origin(h)).position;
      ++n;
    }
    CHECK(left_side_normal.dot(camera.CenterInWorld() - centroid / n) < 0.0);
  }
  CHECK(left_sides == 1);

  // The storey line: Split edge on the front's two vertical edges adds vertices 8 and 9, each
  // at the fraction of its edge where it was clicked (not free: it follows the box), pinned on
  // the sill's ends; Connect vertices joins them across the front: 10 vertices, 15 edges, 7
  // faces, the front in two, the upper storeys and the ground floor.
  const facet::PolyMesh& house_mesh = house.mesh;
  CHECK(house_mesh.NumVertices() == 10);
  CHECK(house_mesh.NumEdges() == 15);
  CHECK(house_mesh.NumFaces() == 7);
  constexpr facet::VertexId kSillLeft = 8, kSillRight = 9;
  REQUIRE(house_mesh.IsVertex(kSillLeft));
  REQUIRE(house_mesh.IsVertex(kSillRight));
  for (facet::VertexId v : {kSillLeft, kSillRight}) {
    CHECK(house_mesh.vertex(v).local.on_edge);
    CHECK_FALSE(house_mesh.vertex(v).local.free);
  }
  facet::HalfedgeId storey = facet::kNoElement;
  for (facet::EdgeId e = 0; e < house_mesh.EdgeIdEnd(); ++e) {
    if (!house_mesh.IsEdge(e)) continue;
    const facet::VertexId a = house_mesh.Origin(2 * e), b = house_mesh.Dest(2 * e);
    if ((a == kSillLeft && b == kSillRight) || (a == kSillRight && b == kSillLeft)) storey = 2 * e;
  }
  REQUIRE(storey != facet::kNoElement);
  facet::FaceId upper = house_mesh.Face(storey), lower = house_mesh.Face(facet::PolyMesh::Twin(storey));
  REQUIRE(upper != facet::kNoFace);
  REQUIRE(lower != facet::kNoFace);
  if (FaceCentroid(house_mesh, upper).z() < FaceCentroid(house_mesh, lower).z()) std::swap(upper, lower);
  // Two halves of one front: the same plane, facing the camera.
  CHECK(facet::FaceNormal(house_mesh, upper).dot(facet::FaceNormal(house_mesh, lower)) > 1.0 - 1e-9);
  CHECK(SeenBy(camera, house_mesh, upper));
  CHECK(SeenBy(camera, house_mesh, lower));
  const Eigen::Vector3d sill_left = facet::VertexInWorld(street, {house.id, kSillLeft});
  const Eigen::Vector3d sill_right = facet::VertexInWorld(street, {house.id, kSillRight});
  MESSAGE("storey line at " << sill_left.z() << " m (left) and " << sill_right.z() << " m (right)");
  CHECK(std::abs(sill_left.z() - sill_right.z()) < kMaxSillTiltM);
  // A ground floor: the sill is above head height and below the 5 m eaves' half.
  CHECK(sill_left.z() > 1.8);
  CHECK(sill_left.z() < 3.0);

  // Pin reprojection RMS, per house, and on the storey line's ends.
  std::map<facet::Id, std::pair<double, int>> sum_sq;  // house -> (sum of squares, pins)
  double sill_sq = 0.0;
  int sill_pins = 0;
  for (const facet::Pin& pin : street.pins) {
    const Eigen::Vector3d x = facet::VertexInWorld(street, pin.vertex);
    REQUIRE(camera.CamFromWorld(x).z() > 0.0);
    auto& [sq, n] = sum_sq[HouseOf(street, pin.vertex.primitive_id)];
    const double residual_sq = (camera.Project(x) - pin.uv_px).squaredNorm();
    sq += residual_sq;
    ++n;
    if (pin.vertex.primitive_id == house.id && (pin.vertex.vertex == kSillLeft || pin.vertex.vertex == kSillRight)) {
      sill_sq += residual_sq;
      ++sill_pins;
    }
  }
  REQUIRE(sill_pins == 2);
  const double sill_rms_px = std::sqrt(sill_sq / sill_pins);
  MESSAGE("storey line: 2 pins, RMS " << sill_rms_px << " px");
  CHECK(sill_rms_px < kMaxSillPinRmsPx);
  const int expected_pins[3] = {7, 3, 3};
  for (size_t h = 0; h < 3; ++h) {
    const auto [sq, n] = sum_sq[street.primitives[2 * h].id];
    CAPTURE(h);
    REQUIRE(n == expected_pins[h]);
    const double rms_px = std::sqrt(sq / n);
    MESSAGE("house " << h + 1 << ": " << n << " pins, RMS " << rms_px << " px");
    CHECK(rms_px < (h == 0 ? kMaxFirstHouseRmsPx : kMaxOtherHouseRmsPx));
  }

  // Textured wherever the photo sees the houses.
  const facet::ImageReadResult photo = facet::ReadImage(dir / "leuvenA.jpg");
  REQUIRE(photo.ok());
  facet::TexturedMesh mesh;
  const std::vector<const facet::ImageRgba8*> photos = {&photo.image};
  const facet::TextureBakeSummary bake = facet::BakeTexturedMesh(street, photos, facet::TextureBakeOptions{}, &mesh);
  REQUIRE(bake.IsUsable());
  std::map<facet::Id, int> seen;
  int storey_faces_textured[2] = {0, 0};  // the front's upper and lower face: textured triangles
  for (size_t t = 0; t < mesh.triangle_face.size(); ++t) {
    const facet::Primitive* p = street.FindPrimitive(mesh.triangle_primitive[t]);
    REQUIRE(p != nullptr);
    if (p->id == house.id && mesh.triangle_textured[t]) {
      if (mesh.triangle_face[t] == upper) ++storey_faces_textured[0];
      if (mesh.triangle_face[t] == lower) ++storey_faces_textured[1];
    }
    if (!SeenBy(camera, p->mesh, mesh.triangle_face[t])) continue;
    // A roof's base lies on its box's top: inside the house, hidden from every view.
    if (p->attached_to != facet::kNoId && facet::FaceNormal(p->mesh, mesh.triangle_face[t]).z() < -0.99) continue;
    ++seen[HouseOf(street, p->id)];
    CAPTURE(p->name);
    CAPTURE(mesh.triangle_face[t]);
    CHECK(mesh.triangle_textured[t]);
  }
  // Each house has faces the photo sees (a face counts when its centroid is in the photo: 3
  // triangles for the half-timbered front and gable, the left house's front and gable, 3 for
  // the right house's gable side and roof).
  for (size_t h = 0; h < 3; ++h) CHECK(seen[street.primitives[2 * h].id] >= 2);
  // Each half of the split front is textured (a quad: two triangles each).
  CHECK(storey_faces_textured[0] == 2);
  CHECK(storey_faces_textured[1] == 2);

  // The shipped sample is this result: same model, to what float noise in the line detection
  // moves (0.5 % of a dimension, 0.5 px of a pin).
  const facet::Project shipped = LoadProjectFile(kSampleDir + "/street.facet");
  REQUIRE(shipped.primitives.size() == street.primitives.size());
  REQUIRE(shipped.pins.size() == street.pins.size());
  REQUIRE(shipped.constraints.size() == street.constraints.size());
  for (size_t i = 0; i < street.primitives.size(); ++i) {
    const facet::Primitive& a = shipped.primitives[i];
    const facet::Primitive& b = street.primitives[i];
    CAPTURE(b.name);
    CHECK(a.shape.kind == b.shape.kind);
    CHECK(a.param_locked == b.param_locked);
    CHECK(a.mesh.NumFaces() == b.mesh.NumFaces());
    CHECK(a.mesh.NumVertices() == b.mesh.NumVertices());
    for (int k = 0; k < 3; ++k) CHECK(std::abs(a.shape.params[k] - b.shape.params[k]) <= 0.005 * std::abs(b.shape.params[k]) + 1e-9);
    CHECK((a.shape.translation - b.shape.translation).norm() <= 0.005 * (b.shape.translation.norm() + 1.0));
  }
  for (size_t i = 0; i < street.pins.size(); ++i) CHECK((shipped.pins[i].uv_px - street.pins[i].uv_px).norm() < 0.5);
  CHECK(shipped.images[0].path == street.images[0].path);

  // The README's step pictures.
  const fs::path shots = fs::path(FACET_BINARY_DIR) / "tutorial";
  fs::create_directories(shots);
  for (const char* step : kSteps) {
    const cv::Mat shot = cv::imread(dir / (std::string(step) + ".png"));
    REQUIRE_MESSAGE(!shot.empty(), step);
    cv::Mat small;
    cv::resize(shot, small, cv::Size(), 0.6, 0.6, cv::INTER_AREA);  // 960 x 540: the six ~440 KB in all
    CHECK(cv::imwrite((shots / (std::string(step) + ".jpg")).string(), small, {cv::IMWRITE_JPEG_QUALITY, 70}));
  }
}

TEST_CASE("the app opens the street: what a new user sees first is the tutorial's result") {
  // `facet render` without a project opens what the GUI opens without one.
  TempDir dir("first_sight");
  const std::string report_path = dir / "report.json";
  const RunResult run = RunRender(dir, "-o '" + (dir / "shot.png") + "' --report '" + report_path + "'");
  INFO("stderr: " << run.stderr_text);
  REQUIRE(run.exit_code == 0);
  const nlohmann::json report = nlohmann::json::parse(ReadText(report_path));
  INFO("log:\n" << ReportLog(report));
  // The sample's path is canonical (symbolic links resolved): compare its end.
  const std::string opened_line = report.at("log").at(0).at("text").get<std::string>();
  const std::string expected_end = "/assets/samples/leuven/street.facet";
  CHECK(opened_line.rfind("Opened ", 0) == 0);
  CHECK(opened_line.size() > expected_end.size());
  CHECK(opened_line.compare(opened_line.size() - expected_end.size(), expected_end.size(), expected_end) == 0);
  const facet::ProjectLoadResult opened = facet::ProjectFromJson(report.at("project").dump());
  REQUIRE(opened.ok());
  const facet::Project shipped = LoadProjectFile(kSampleDir + "/street.facet");
  CHECK(opened.project.primitives.size() == shipped.primitives.size());
  CHECK(opened.project.pins.size() == shipped.pins.size());
  // The photo was found beside it and the joint solve ran on it: the pins met as the tutorial
  // left them (RMS over all 11 pins, the first house's bound).
  CHECK(report.at("joint_solve").at("rms_px").get<double>() < kMaxFirstHouseRmsPx);
}
