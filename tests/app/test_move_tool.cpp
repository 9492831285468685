// The Move tool (V_op) in the real application offscreen: a vertex dragged with the mouse in
// the 3D panel follows the mouse in the plane facing the camera, a face drag moves the whole
// primitive over the ground, undo restores the project exactly, the script command
// `move-selection` moves a vertex to a position and a primitive by a delta, and in a scene
// whose box depth no pin sees, the dragged depth survives the app's re-solve (it starts from
// the moved state) while the camera is re-solved.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/io/project_io.h"
#include "core/mesh/primitives.h"
#include "tests/app/app_test_util.h"
#include "tests/gltf_validator.h"
#include "tests/synthetic_scene.h"

using namespace facet::testing;

namespace {

constexpr double kExact = 1e-12;         // moves without a solve are exact
constexpr double kMousePx = 0.05;        // the dragged vertex under the (integer) release pixel
constexpr double kPlaneRelative = 1e-9;  // the vertex stays in its plane facing the camera
constexpr double kSolvedDepth = 1e-9;    // an undetermined depth is not touched by the solve

std::string LogText(const nlohmann::json& report) {
  std::string text;
  for (const auto& e : report.at("log"))
    text += e.at("level").get<std::string>() + ": " + e.at("text").get<std::string>() + "\n";
  return text;
}

nlohmann::json Render(const TempDir& dir, const std::string& project_path, const std::string& name,
                      const std::string& script) {
  WriteText(dir / (name + ".txt"), script);
  const RunResult run = RunRender(dir, "'" + project_path + "' -o '" + (dir / (name + ".png")) + "' --script '" +
                                           (dir / (name + ".txt")) + "' --report '" + (dir / (name + ".json")) + "'");
  INFO("stderr: " << run.stderr_text);
  REQUIRE(run.exit_code == 0);
  return ReadJson(dir / (name + ".json"));
}

facet::Project Load(const std::string& path) {
  facet::ProjectLoadResult loaded = facet::LoadProject(path);
  REQUIRE_MESSAGE(loaded.ok(), loaded.error);
  return loaded.project;
}

facet::Project FromReport(const nlohmann::json& report) {
  facet::ProjectLoadResult loaded = facet::ProjectFromJson(report.at("project").dump());
  REQUIRE_MESSAGE(loaded.ok(), loaded.error);
  return loaded.project;
}

// A project holding one box whose dimensions and translation the user may change.
std::string WriteFreeBox(const TempDir& dir, facet::Id* box_id) {
  facet::Project p;
  std::string message;
  REQUIRE(facet::AddPrimitiveToProject(&p, facet::MakeBox(facet::kNoId, Eigen::Vector3d(4.0, 3.0, 2.0)), "box", box_id,
                                       &message));
  p.FindPrimitive(*box_id)->translation_locked = false;
  const std::string path = dir / "box.facet";
  REQUIRE(facet::SaveProject(p, path) == "");
  return path;
}

Eigen::Vector2d Rounded(const Eigen::Vector2d& p) { return {std::round(p.x()), std::round(p.y())}; }

// Press at `from`, move there in `steps` frames, optional screenshot while held, release.
std::string DragScript(const Eigen::Vector2d& from, const Eigen::Vector2d& to, int steps, const std::string& shot) {
  std::ostringstream s;
  s << "move " << FormatXY(from, 6) << "\nframes 1\ndown left\nframes 1\n";
  for (int i = 1; i <= steps; ++i) s << "move " << FormatXY(from + (to - from) * i / steps, 6) << "\nframes 1\n";
  if (!shot.empty()) s << "screenshot " << shot << "\n";
  s << "up left\nframes 2\n";
  return s.str();
}

// The start every move-tool case shares: a free box, the Move tool chosen (M), the first
// frame's report, the 3D view it was drawn with and the project before any drag.
struct MoveToolStart {
  facet::Id box_id = facet::kNoId;
  std::string path;
  std::string prefix = "frames 3\nkey m\nframes 2\n";
  nlohmann::json report;
  Viewport3d view;
  facet::Project before;
};

MoveToolStart StartWithFreeBox(const TempDir& dir) {
  MoveToolStart start;
  start.path = WriteFreeBox(dir, &start.box_id);
  start.report = Render(dir, start.path, "start", start.prefix);
  start.view = ViewportFromReport(start.report);
  start.before = FromReport(start.report);
  return start;
}

}  // namespace

TEST_CASE("move tool: a vertex dragged in the 3D panel follows the mouse; undo restores it exactly") {
  TempDir dir("move_vertex");
  const MoveToolStart start = StartWithFreeBox(dir);
  CHECK(start.report.at("tool").get<std::string>() == "Move");
  const facet::Primitive& box0 = *start.before.FindPrimitive(start.box_id);
  const facet::VertexId corner = 7;  // x, y and z bits: the top far corner
  const Eigen::Vector3d p0 = box0.mesh.vertex(corner).position;
  const Eigen::Vector2d from = Rounded(start.view.ToScreen(p0));
  const Eigen::Vector2d to = from + Eigen::Vector2d(40.0, -25.0);

  std::ostringstream s;
  s << start.prefix << DragScript(from, to, 6, dir / "dragging.png") << "command save " << (dir / "after.facet")
    << "\nframes 1\ncommand undo\nframes 2\n";
  const nlohmann::json report = Render(dir, start.path, "drag", s.str());
  INFO("log:\n" << LogText(report));
  const facet::Project after = Load(dir / "after.facet");
  const Eigen::Vector3d p1 = after.FindPrimitive(start.box_id)->mesh.vertex(corner).position;
  CAPTURE(p0.transpose());
  CAPTURE(p1.transpose());
  // The vertex lies under the release pixel, in the plane through it facing the camera (the
  // press ray through the floored press pixel: a slightly different normal than eye->p0, so
  // compare with the plane of the ray the app used: through the eye and the press pixel).
  const double under_mouse_px = (start.view.ToScreen(p1) - to).norm();
  CAPTURE(under_mouse_px);
  CHECK(under_mouse_px < kMousePx);
  const Eigen::Vector3d eye = start.view.Eye();
  const double off_plane = std::abs((p1 - p0).dot((p0 - eye).normalized())) / (p1 - p0).norm();
  CAPTURE(off_plane);
  CHECK(off_plane < 0.01);  // the press pixel is within half a pixel of the vertex
  CHECK((p1 - p0).norm() > 0.1);
  MESSAGE("vertex drag: " << under_mouse_px << " px from the release pixel, off its plane by " << off_plane
                          << " (relative), moved " << (p1 - p0).norm());
  // Smallest change: the opposite corner (0) stays.
  CHECK((after.FindPrimitive(start.box_id)->mesh.vertex(0).position - box0.mesh.vertex(0).position).norm() < kExact);

  REQUIRE(report.at("redo_stack").size() == 1);
  CHECK(report.at("redo_stack").back().get<std::string>() == "Move vertex");
  const facet::Project undone = FromReport(report);
  CHECK(undone == start.before);

  // The screenshot during the drag was written (looked at by hand: the box stretched, the hint).
  const cv::Mat shot = cv::imread(dir / "dragging.png");
  CHECK_FALSE(shot.empty());
}

TEST_CASE("move tool: a face drag moves the whole primitive over the ground; the move command") {
  TempDir dir("move_primitive");
  const MoveToolStart start = StartWithFreeBox(dir);
  const facet::Primitive& box0 = *start.before.FindPrimitive(start.box_id);
  // The top face's centre (z = 2): seen from above by the default view.
  const Eigen::Vector3d top_centre = box0.shape.translation + Eigen::Vector3d(2.0, 1.5, 2.0);
  const Eigen::Vector2d from = Rounded(start.view.ToScreen(top_centre));
  const Eigen::Vector2d to = from + Eigen::Vector2d(-30.0, 20.0);
  // Escape during a vertex drag cancels it: nothing changes, no history entry.
  const Eigen::Vector2d corner7 = Rounded(start.view.ToScreen(box0.mesh.vertex(7).position));
  std::ostringstream s;
  s << start.prefix << "move " << FormatXY(corner7, 6) << "\nframes 1\ndown left\nframes 1\n";
  for (int i = 1; i <= 3; ++i)
    s << "move " << FormatXY(corner7 + Eigen::Vector2d(10.0 * i, 5.0 * i), 6) << "\nframes 1\n";
  s << "key escape\nframes 1\nmove " << FormatXY(corner7 + Eigen::Vector2d(50.0, 25.0), 6)
    << "\nframes 1\nup left\nframes 2\n";
  s << "command save " << (dir / "escaped.facet") << "\nframes 1\n";
  s << DragScript(from, to, 5, "") << "command save " << (dir / "dragged.facet") << "\nframes 1\n";
  // The command: the vertex to a position, then the primitive by a delta.
  const Eigen::Vector3d target(4.5, 3.25, 2.5);
  const Eigen::Vector3d delta(0.5, -0.25, 0.75);
  s << "command select vertex " << start.box_id << " 7\nframes 1\ncommand move-selection vertex " << target.x() << " "
    << target.y() << " " << target.z() << "\nframes 1\ncommand save " << (dir / "vertex.facet") << "\nframes 1\n";
  s << "command select primitive " << start.box_id << "\nframes 1\ncommand move-selection primitive " << delta.x()
    << " " << delta.y() << " " << delta.z() << "\nframes 1\ncommand save " << (dir / "primitive.facet")
    << "\nframes 1\n";
  const nlohmann::json report = Render(dir, start.path, "face", s.str());
  INFO("log:\n" << LogText(report));

  const facet::Primitive dragged = *Load(dir / "dragged.facet").FindPrimitive(start.box_id);
  const Eigen::Vector3d shift = dragged.shape.translation - box0.shape.translation;
  CAPTURE(shift.transpose());
  CHECK(std::abs(shift.z()) < kExact);  // over the ground
  CHECK(shift.norm() > 0.1);
  CHECK(dragged.shape.params == box0.shape.params);
  // The pressed point of the top face follows the mouse.
  const double under_mouse_px = (start.view.ToScreen(top_centre + shift) - to).norm();
  CAPTURE(under_mouse_px);
  CHECK(under_mouse_px < 1.0);  // the press point is the floored pixel's hit, within a pixel of the centre

  const facet::Primitive vertex_moved = *Load(dir / "vertex.facet").FindPrimitive(start.box_id);
  const double miss = (vertex_moved.mesh.vertex(7).position - target).norm();
  CAPTURE(miss);
  CHECK(miss < kExact);
  const facet::Primitive primitive_moved = *Load(dir / "primitive.facet").FindPrimitive(start.box_id);
  for (facet::VertexId v = 0; v < 8; ++v) {
    const double error =
        (primitive_moved.mesh.vertex(v).position - vertex_moved.mesh.vertex(v).position - delta).norm();
    CAPTURE(v);
    CAPTURE(error);
    CHECK(error < kExact);
  }
  const facet::Project escaped = Load(dir / "escaped.facet");
  CHECK(escaped == start.before);
  CHECK(report.at("log").dump().find("Move cancelled") == std::string::npos);  // a hint, not a log line

  const auto& undo = report.at("undo_stack");
  REQUIRE(undo.size() == 3);
  CHECK(undo[0].get<std::string>() == "Move primitive");
  CHECK(undo[1].get<std::string>() == "Move vertex");
  CHECK(undo[2].get<std::string>() == "Move primitive");

  // Shift: the vertex moves along the world z axis only. A run of its own: saving under a new
  // name re-frames the 3D view, so the start view holds only until the model changes and is saved.
  std::ostringstream z;
  z << start.prefix << "hold shift\n"
    << DragScript(corner7, corner7 + Eigen::Vector2d(0.0, -30.0), 4, "") << "release shift\ncommand save "
    << (dir / "shift.facet") << "\nframes 1\n";
  const nlohmann::json shift_report = Render(dir, start.path, "shift", z.str());
  INFO("shift log:\n" << LogText(shift_report));
  const Eigen::Vector3d p7_before = box0.mesh.vertex(7).position;
  const Eigen::Vector3d p7 = Load(dir / "shift.facet").FindPrimitive(start.box_id)->mesh.vertex(7).position;
  CAPTURE(p7_before.transpose());
  CAPTURE(p7.transpose());
  CHECK(std::abs(p7.x() - p7_before.x()) < 1e-9);
  CHECK(std::abs(p7.y() - p7_before.y()) < 1e-9);
  CHECK(p7.z() - p7_before.z() > 0.05);  // up the screen is up

  // Issue 14: a vertex sent 1e9 away makes a box 1e9 wide, no model: the command is refused by
  // name and nothing is committed (the move never reaches the document).
  const std::string far = RenderScriptRefused(
      dir, start.path, "far",
      start.prefix + "command select vertex " + std::to_string(start.box_id) +
          " 7\nframes 1\ncommand move-selection vertex 1e9 3 2\n");
  CHECK(far.find("move-selection vertex: the move would take the model beyond any camera's reach: Size x of 'box'") !=
        std::string::npos);
}

TEST_CASE("move tool: an undetermined depth keeps the dragged value through the app's re-solve") {
  TempDir dir("move_depth");
  SyntheticScene scene = MakeBoxScene();
  facet::Project& p = scene.project;
  // Only the front (y = 0) corners are pinned: nothing sees the depth.
  std::vector<facet::Pin> front;
  for (const facet::Pin& pin : p.pins) {
    if ((pin.vertex.vertex & 2) == 0) front.push_back(pin);
  }
  p.pins = front;
  // The camera a little off, so that the re-solve has work to do.
  facet::Camera& camera = p.images[0].camera;
  const Eigen::Vector3d true_center = camera.CenterInWorld();
  camera.SetPose(camera.cam_from_world_rotation, true_center + Eigen::Vector3d(0.3, -0.2, 0.1));
  REQUIRE(cv::imwrite(dir / "synthetic.png", cv::Mat(768, 1024, CV_8UC3, cv::Scalar(90, 110, 130))));
  const std::string path = dir / "scene.facet";
  REQUIRE(facet::SaveProject(p, path) == "");

  const facet::Primitive& box = *p.FindPrimitive(scene.box_id);
  const Eigen::Vector3d target = box.mesh.vertex(2).position + Eigen::Vector3d(0.0, 1.0, 0.0);
  std::ostringstream s;
  s << "frames 2\ncommand select vertex " << scene.box_id << " 2\nframes 1\ncommand move-selection vertex "
    << target.x() << " " << target.y() << " " << target.z() << "\nframes 2\ncommand save " << (dir / "moved.facet")
    << "\nframes 1\n";
  const nlohmann::json report = Render(dir, path, "depth", s.str());
  INFO("log:\n" << LogText(report));
  const facet::Project moved = Load(dir / "moved.facet");
  const facet::Primitive& after = *moved.FindPrimitive(scene.box_id);
  const double depth = after.shape.params[1];
  const double dragged_depth = scene.true_box.shape.params[1] + 1.0;
  CAPTURE(depth);
  CHECK(std::abs(depth - dragged_depth) < kSolvedDepth);
  // The solve ran: the camera is back at its true centre.
  const double center_error = (moved.images[0].camera.CenterInWorld() - true_center).norm();
  CAPTURE(center_error);
  CHECK(center_error < 1e-6);
  MESSAGE("undetermined depth after the app's re-solve: " << depth << " (dragged " << dragged_depth
                                                          << "), camera centre error " << center_error);
}

namespace {

// Pixels of the reference geometry's colour (app/panels/image_overlay.h, viewport_panel.cpp:
// cyan, green and blue alike and well above red, as it shows blended over the photo or the
// model; the z family's blue and the y family's green are not) inside a panel's rect.
int ReferencePixels(const cv::Mat& shot, const nlohmann::json& panel_rect) {
  const int x0 = std::max(0, static_cast<int>(panel_rect.at("x").get<double>()));
  const int y0 = std::max(0, static_cast<int>(panel_rect.at("y").get<double>()));
  const int x1 = std::min(shot.cols, static_cast<int>(x0 + panel_rect.at("w").get<double>()));
  const int y1 = std::min(shot.rows, static_cast<int>(y0 + panel_rect.at("h").get<double>()));
  int count = 0;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      const cv::Vec3b bgr = shot.at<cv::Vec3b>(y, x);
      count += bgr[1] > bgr[2] + 50 && bgr[0] > bgr[2] + 50 && std::abs(bgr[1] - bgr[0]) < 30;
    }
  return count;
}

}  // namespace

TEST_CASE("reference geometry: added by script and drawn; a dragged vertex snaps onto it; undo; a missing file") {
  TempDir dir("reference_snap");
  const MoveToolStart start = StartWithFreeBox(dir);
  const facet::VertexId corner = 7;
  const Eigen::Vector3d p0 = start.before.FindPrimitive(start.box_id)->mesh.vertex(corner).position;
  // A reference triangle (Z-up file: its numbers are world coordinates) whose first vertex
  // lies up and beside the box's corner.
  const Eigen::Vector3d target = p0 + Eigen::Vector3d(0.75, -0.5, 0.625);
  {
    std::ofstream obj(dir / "plan.obj");
    obj.precision(17);
    // Its other corners reach back over the box's top, so that the panel shows most of it.
    obj << "v " << target.x() << " " << target.y() << " " << target.z() << "\nv " << target.x() - 3 << " "
        << target.y() << " " << target.z() << "\nv " << target.x() << " " << target.y() - 2.5 << " " << target.z()
        << "\nf 1 2 3\n";
  }
  const std::string add = "command reference add-z-up " + (dir / "plan.obj") + "\nframes 2\n";
  // Released 3 px right and 2 px below where the reference vertex shows: within the 8 px snap.
  const Eigen::Vector2d from = Rounded(start.view.ToScreen(p0));
  const Eigen::Vector2d to = Rounded(start.view.ToScreen(target)) + Eigen::Vector2d(3.0, 2.0);
  std::ostringstream s;
  s << start.prefix << add << "screenshot " << (dir / "added.png") << "\n"
    << DragScript(from, to, 6, "") << "command save " << (dir / "after.facet") << "\nframes 1\n"
    << "command undo\nframes 2\ncommand undo\nframes 2\nscreenshot " << (dir / "undone.png") << "\n";
  const nlohmann::json report = Render(dir, start.path, "snap", s.str());
  INFO("log:\n" << LogText(report));
  CHECK(LogText(report).find("Add reference plan.obj (1 triangles)") != std::string::npos);
  CHECK(LogText(report).find("snapped to a reference vertex") != std::string::npos);
  // Undo took the move and then the reference away.
  CHECK(report.at("references").empty());
  CHECK(report.at("undo_stack").empty());
  CHECK(report.at("redo_stack").get<std::vector<std::string>>() ==
        std::vector<std::string>{"Move vertex", "Add reference plan.obj"});
  // Drawn in the 3D panel (see-through faces and outlines) while it was there, not after.
  const cv::Mat added = cv::imread(dir / "added.png", cv::IMREAD_COLOR);
  const cv::Mat undone_shot = cv::imread(dir / "undone.png", cv::IMREAD_COLOR);
  REQUIRE(!added.empty());
  REQUIRE(!undone_shot.empty());
  CHECK(ReferencePixels(added, report.at("panels").at("3D")) > 200);
  CHECK(ReferencePixels(undone_shot, report.at("panels").at("3D")) == 0);

  const facet::Project after = Load(dir / "after.facet");
  REQUIRE(after.references.size() == 1);
  CHECK(after.references[0].path == "plan.obj");  // relative to the project file
  CHECK_FALSE(after.references[0].y_up);
  const Eigen::Vector3d p1 = after.FindPrimitive(start.box_id)->mesh.vertex(corner).position;
  CAPTURE(p1.transpose());
  CAPTURE(target.transpose());
  // Exactly on the reference vertex, not under the mouse 3.6 px away.
  constexpr double kOnReference = 1e-9;
  CHECK((p1 - target).norm() < kOnReference);
  CHECK((p1 - p0).norm() > 0.5);

  // The mesh file gone: the project opens, says which file is missing, keeps the reference and
  // saves it again as it was.
  std::filesystem::rename(dir / "plan.obj", dir / "plan.obj.away");
  const nlohmann::json missing =
      Render(dir, dir / "after.facet", "missing", "frames 3\ncommand save " + (dir / "again.facet") + "\nframes 1\n");
  REQUIRE(missing.at("references").size() == 1);
  CHECK_FALSE(missing["references"][0]["loaded"].get<bool>());
  CHECK(missing["references"][0]["error"].get<std::string>().find(dir / "plan.obj") != std::string::npos);
  CHECK(LogText(missing).find("plan.obj") != std::string::npos);
  CHECK(Load(dir / "again.facet").references == after.references);
}

TEST_CASE("reference geometry: the Leuven street exported and added back lies on the model in both panels") {
  TempDir dir("reference_leuven");
  const std::string sample_dir = std::string(FACET_SOURCE_DIR) + "/assets/samples/leuven";
  const CliResult exported =
      RunFacet(dir, "export '" + sample_dir + "/street.facet' -o '" + (dir / "street.glb") + "'");
  REQUIRE(exported.exit_code == 0);
  CHECK_GLTF_VALID(dir / "street.glb");
  const nlohmann::json report =
      Render(dir, sample_dir + "/street.facet", "leuven",
             "frames 3\ncommand reference add " + (dir / "street.glb") + "\nframes 3\nscreenshot " +
                 (dir / "shown.png") + "\ncommand reference hide 0\nframes 3\n");
  INFO("log:\n" << LogText(report));
  REQUIRE(report.at("references").size() == 1);
  CHECK(report["references"][0]["loaded"].get<bool>());
  const cv::Mat shown = cv::imread(dir / "shown.png", cv::IMREAD_COLOR);
  REQUIRE(!shown.empty());
  const int in_image = ReferencePixels(shown, report.at("panels").at("Image"));
  const int in_3d = ReferencePixels(shown, report.at("panels").at("3D"));
  MESSAGE("reference pixels: " << in_image << " in the image panel, " << in_3d << " in the 3D panel");
  CHECK(in_image > 200);
  CHECK(in_3d > 200);
  // Hidden (an undoable edit, stored in the project): drawn in neither panel.
  CHECK(report.at("undo_stack").back() == "Hide reference street.glb");
  const cv::Mat hidden = cv::imread(dir / "leuven.png", cv::IMREAD_COLOR);
  CHECK(ReferencePixels(hidden, report.at("panels").at("Image")) == 0);
  CHECK(ReferencePixels(hidden, report.at("panels").at("3D")) == 0);
  // Stored relative to the project file, as photos are.
  const facet::Project project = FromReport(report);
  CHECK_FALSE(project.references[0].visible);
  CHECK(facet::ResolveImagePath(sample_dir + "/street.facet", project.references[0].path) ==
        std::filesystem::path(dir / "street.glb").lexically_normal().string());
}

// A JSON glTF with its buffer in a .bin beside it comes in as a reference through the app's
// command, stored by its relative path; one whose .bin is missing is refused with the file's
// name and the buffer's, and the project keeps no reference.
TEST_CASE("reference geometry: a .gltf with its .bin is added by the app; one without its .bin is refused by name") {
  TempDir dir("reference_gltf");
  facet::Id box_id = facet::kNoId;
  const std::string path = WriteFreeBox(dir, &box_id);
  // Two triangles: a unit square at height 3 (a Z-up file: world coordinates).
  const float positions[12] = {0, 0, 3, 1, 0, 3, 1, 1, 3, 0, 1, 3};
  const std::uint16_t indices[6] = {0, 1, 2, 0, 2, 3};
  {
    std::ofstream bin(dir / "square.bin", std::ios::binary);
    bin.write(reinterpret_cast<const char*>(positions), sizeof(positions));
    bin.write(reinterpret_cast<const char*>(indices), sizeof(indices));
  }
  const nlohmann::json gltf = {
      {"asset", {{"version", "2.0"}}},
      {"nodes", {{{"mesh", 0}}}},
      {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}, {"indices", 1}}}}}}},
      {"buffers", {{{"uri", "square.bin"}, {"byteLength", sizeof(positions) + sizeof(indices)}}}},
      {"bufferViews",
       {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", sizeof(positions)}},
        {{"buffer", 0}, {"byteOffset", sizeof(positions)}, {"byteLength", sizeof(indices)}}}},
      {"accessors",
       {{{"bufferView", 0}, {"componentType", 5126}, {"count", 4}, {"type", "VEC3"}},
        {{"bufferView", 1}, {"componentType", 5123}, {"count", 6}, {"type", "SCALAR"}}}}};
  std::ofstream(dir / "square.gltf") << gltf.dump();
  nlohmann::json broken = gltf;
  broken["buffers"][0]["uri"] = "gone.bin";
  std::ofstream(dir / "broken.gltf") << broken.dump();

  const nlohmann::json report = Render(dir, path, "gltf",
                                       "frames 2\ncommand reference add-z-up " + (dir / "square.gltf") +
                                           "\nframes 2\ncommand save " + (dir / "with.facet") + "\nframes 1\n");
  INFO("log:\n" << LogText(report));
  REQUIRE(report.at("references").size() == 1);
  CHECK(report["references"][0]["loaded"].get<bool>());
  CHECK(report["references"][0]["triangles"].get<int>() == 2);
  CHECK(LogText(report).find("Add reference square.gltf (2 triangles)") != std::string::npos);
  const facet::Project with = Load(dir / "with.facet");
  REQUIRE(with.references.size() == 1);
  CHECK(with.references[0].path == "square.gltf");

  const std::string refused = RenderScriptRefused(
      dir, path, "broken", "frames 2\ncommand reference add " + (dir / "broken.gltf") + "\nframes 1\n");
  CHECK(refused.find(dir / "broken.gltf") != std::string::npos);
  CHECK(refused.find("buffer 0") != std::string::npos);
  CHECK(refused.find("gone.bin") != std::string::npos);
}

// Issue 25: a saved project naming hostile reference files (the import probe's) crashed every
// time it opened. It opens, says for each file what is wrong, keeps the references and the
// model, and saves them again as they were.
TEST_CASE("reference geometry: a project naming hostile glTF files opens with a message for each, nothing lost") {
  TempDir dir("reference_hostile");
  facet::Id box_id = facet::kNoId;
  const std::string box_path = WriteFreeBox(dir, &box_id);
  const float positions[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  std::string bin(reinterpret_cast<const char*>(positions), sizeof(positions));
  const nlohmann::json square = {
      {"asset", {{"version", "2.0"}}},
      {"nodes", {{{"mesh", 0}}}},
      {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}, {"material", 0}}}}}}},
      {"materials", {{{"pbrMetallicRoughness", {{"baseColorFactor", {1, 1, 1, 1}}}}}}},
      {"cameras", {{{"type", "perspective"}, {"perspective", {{"yfov", 0.8}}}, {"extras", nlohmann::json::object()}}}},
      {"buffers", {{{"uri", "tri.bin"}, {"byteLength", bin.size()}}}},
      {"bufferViews", {{{"buffer", 0}, {"byteLength", bin.size()}}}},
      {"accessors", {{{"bufferView", 0}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}}}}};
  WriteText(dir / "tri.bin", bin);
  struct Hostile {
    std::string file, pointer;
    nlohmann::json value;
    std::string says;
  };
  const std::vector<Hostile> hostile = {
      {"wrap.gltf", "/accessors/0/count", 6148914691236517206ull, "accessor 0 (POSITION).count"},
      {"stride.gltf", "/bufferViews/0/byteStride", 1ull << 63, "byteStride"},
      {"image_size.gltf", "/cameras/0/extras/image_size_px", nlohmann::json::array(), "image_size_px"},
      {"color.gltf", "/materials/0/pbrMetallicRoughness/baseColorFactor", nlohmann::json::array(), "baseColorFactor"},
      {"escape.gltf", "/buffers/0/uri", "..%2F..%2F..%2Fetc%2Fpasswd", "leaves the glTF's folder"},
  };
  facet::Project project = Load(box_path);
  for (const Hostile& h : hostile) {
    nlohmann::json file = square;
    file[nlohmann::json::json_pointer(h.pointer)] = h.value;
    if (h.file == "image_size.gltf") file["nodes"][0]["camera"] = 0;
    WriteText(dir / h.file, file.dump());
    facet::Reference reference;
    reference.id = project.NewId();
    reference.path = h.file;
    project.references.push_back(reference);
  }
  const std::string path = dir / "hostile.facet";
  REQUIRE(facet::SaveProject(project, path) == "");
  const nlohmann::json report =
      Render(dir, path, "hostile", "frames 3\ncommand save " + (dir / "again.facet") + "\nframes 1\n");
  INFO("log:\n" << LogText(report));
  REQUIRE(report.at("references").size() == hostile.size());
  for (size_t i = 0; i < hostile.size(); ++i) {
    CAPTURE(hostile[i].file);
    CHECK_FALSE(report["references"][i]["loaded"].get<bool>());
    const std::string error = report["references"][i]["error"].get<std::string>();
    CHECK(error.find(hostile[i].file) != std::string::npos);
    CHECK(error.find(hostile[i].says) != std::string::npos);
    CHECK(LogText(report).find(hostile[i].file) != std::string::npos);
  }
  const facet::Project again = Load(dir / "again.facet");
  CHECK(again.references == project.references);
  CHECK(again.primitives.size() == project.primitives.size());
}
