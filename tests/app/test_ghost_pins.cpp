// Ghost pins (issue 26), through the real application offscreen: a textured box ray-cast into
// three photos from known cameras, the corners pinned in photo 1 where they are. Showing photo
// 2 proposes its pins (hollow markers with their score, app/state/ghost_pins.h); the button
// above the photo accepts them all as one undoable edit, and undo takes them all back.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "core/image/image_io.h"
#include "core/io/project_io.h"
#include "core/mesh/primitives.h"
#include "core/scene/project.h"
#include "tests/app/app_test_util.h"
#include "tests/textured_scene.h"

using namespace facet::testing;

namespace {

double Lattice(size_t face, std::int64_t i, std::int64_t j) {
  std::uint64_t h = face * 0x9E3779B97F4A7C15ull ^ static_cast<std::uint64_t>(i) * 0xBF58476D1CE4E5B9ull ^
                    static_cast<std::uint64_t>(j) * 0x94D049BB133111EBull;
  h ^= h >> 31;
  h *= 0xD6E8FEB86659FD93ull;
  h ^= h >> 32;
  return static_cast<double>(h % 1000) / 999.0;
}

// Value noise on each face: blobs without a period, for the matcher to lock on.
double Noise(size_t face, const Eigen::Vector2d& st, double cell) {
  const Eigen::Vector2d q = st / cell;
  const double fx = std::floor(q.x()), fy = std::floor(q.y());
  const double tx = q.x() - fx, ty = q.y() - fy;
  const auto i = static_cast<std::int64_t>(fx), j = static_cast<std::int64_t>(fy);
  return (Lattice(face, i, j) * (1 - tx) + Lattice(face, i + 1, j) * tx) * (1 - ty) +
         (Lattice(face, i, j + 1) * (1 - tx) + Lattice(face, i + 1, j + 1) * tx) * ty;
}

facet::Camera LookAt(const Eigen::Vector3d& center, double focal_px) {
  SyntheticSceneOptions o;
  o.width_px = 640;
  o.height_px = 480;
  o.focal_px = focal_px;
  o.camera_center = center;
  o.look_at = Eigen::Vector3d(2.0, 1.5, 1.25);
  o.roll_deg = 2.0;
  return MakeLookAtCamera(o);
}

}  // namespace

TEST_CASE("pins in photo 1 are proposed as ghosts in photo 2; accepting adds them as one edit, undo removes them") {
  TempDir dir("ghost_pins");
  facet::Project p;
  facet::Id box = facet::kNoId;
  REQUIRE(facet::AddPrimitiveToProject(&p, facet::MakeBox(facet::kNoId, Eigen::Vector3d(4.0, 3.0, 2.5)), "box", &box,
                                       nullptr));
  p.primitives[0].param_locked = {true, true, true, false};
  const auto faces = PaintedFaces(p);
  const Paint paint = [](const PaintedFace& face, const Eigen::Vector3d& x) {
    const Eigen::Vector2d st = face.InPlane(x);
    const double v = 40.0 + 140.0 * Noise(face.index, st, 0.12) + 60.0 * Noise(face.index + 17, st, 0.05);
    return Eigen::Vector3d(0.9 * v, v, 0.8 * v);
  };
  const std::vector<Eigen::Vector3d> centers = {{10.0, -7.0, 5.0}, {14.0, -4.0, 6.0}, {4.0, -11.0, 7.0}};
  const std::vector<double> focals = {700.0, 700.0, 650.0};
  for (size_t k = 0; k < centers.size(); ++k) {
    facet::Image image;
    image.id = p.NewId();
    image.path = "photo" + std::to_string(k) + ".png";
    image.camera = LookAt(centers[k], focals[k]);
    image.width_px = image.camera.width_px;
    image.height_px = image.camera.height_px;
    image.camera_calibrated = true;
    image.pose_locked = true;  // the solve keeps the known cameras
    p.images.push_back(image);
    REQUIRE(facet::WritePng(dir / image.path, RenderTexturedPhoto(faces, image.camera, paint, 1.0, 2)) == "");
  }
  const facet::Camera& camera_a = p.images[0].camera;
  const facet::Camera& camera_b = p.images[1].camera;
  // Photo 1's pins: every corner it sees, where it is.
  const auto corners = BoxCorners(p.primitives[0]);
  for (facet::VertexId v = 0; v < 8; ++v) {
    bool seen = false;
    const facet::PolyMesh& mesh = p.primitives[0].mesh;
    for (facet::FaceId f = 0; f < mesh.FaceIdEnd(); ++f) {
      const auto vs = facet::FaceVertices(mesh, f);
      if (std::find(vs.begin(), vs.end(), v) != vs.end() &&
          facet::FaceNormal(mesh, f).dot(camera_a.CenterInWorld() - corners[v]) > 0.0)
        seen = true;
    }
    if (!seen) continue;
    facet::Pin pin;
    pin.id = p.NewId();
    pin.image_id = p.images[0].id;
    pin.vertex = {box, v};
    pin.uv_px = camera_a.Project(corners[v]);
    p.pins.push_back(pin);
  }
  const size_t pins_before = p.pins.size();
  REQUIRE(pins_before == 7);
  const std::string path = dir / "scene.facet";
  REQUIRE(facet::SaveProject(p, path) == "");

  // Showing photo 2 proposes: the report lists the ghosts, on the corners' true projections.
  const nlohmann::json shown = RenderScript(dir, path, "ghosts", "frames 2\ncommand select-image 1\nframes 3\n");
  INFO("log:\n" << ReportLog(shown));
  const nlohmann::json& ghosts = shown.at("pin_proposals");
  REQUIRE(ghosts.at("image_id").get<facet::Id>() == p.images[1].id);
  // Computed when the photo was shown, not every frame (5 frames drawn).
  CHECK(ghosts.at("computations").get<int>() <= 2);
  int proposed = 0;
  constexpr double kTolerancePx = 0.5;  // the core suite's corners: at most 0.35 px
  for (const nlohmann::json& g : ghosts.at("proposals")) {
    if (!g.at("proposed").get<bool>()) continue;
    ++proposed;
    const auto v = g.at("vertex").get<facet::VertexId>();
    const Eigen::Vector2d uv(g.at("u").get<double>(), g.at("v").get<double>());
    CHECK((uv - camera_b.Project(corners[v])).norm() <= kTolerancePx);
  }
  MESSAGE(proposed << " ghost pins in photo 2");
  REQUIRE(proposed >= 4);
  REQUIRE(shown.at("items").contains("image.accept_pin_proposals"));

  // Accept all (the button), save, undo, save.
  std::ostringstream s;
  s << "frames 2\ncommand select-image 1\nframes 3\nclick left item image.accept_pin_proposals\nframes 3\n";
  const std::string accepted = dir / "accepted.facet", undone = dir / "undone.facet";
  s << "command save " << accepted << "\nframes 1\ncommand undo\nframes 2\ncommand save " << undone << "\nframes 1\n";
  const nlohmann::json report = RenderScript(dir, path, "accept", s.str());
  INFO("log:\n" << ReportLog(report));
  const facet::Project after = LoadProjectFile(accepted);
  CHECK(after.pins.size() == pins_before + proposed);
  int in_b = 0;
  for (const facet::Pin& pin : after.pins) {
    if (pin.image_id != p.images[1].id) continue;
    ++in_b;
    CHECK((pin.uv_px - camera_b.Project(corners[pin.vertex.vertex])).norm() <= kTolerancePx);
  }
  CHECK(in_b == proposed);
  const facet::Project back = LoadProjectFile(undone);
  CHECK(back.pins.size() == pins_before);
  const nlohmann::json& redo = report.at("redo_stack");
  REQUIRE(redo.size() == 1);
  CHECK(redo[0].get<std::string>() == "Accept " + std::to_string(proposed) + " proposed pins");

  // A click on one ghost pins that one; Enter then pins the rest (one edit each).
  Eigen::Vector2d ghost_uv;
  facet::VertexId ghost_vertex = 0;
  for (const nlohmann::json& g : ghosts.at("proposals")) {
    if (!g.at("proposed").get<bool>()) continue;
    ghost_uv = Eigen::Vector2d(g.at("u").get<double>(), g.at("v").get<double>());
    ghost_vertex = g.at("vertex").get<facet::VertexId>();
    break;
  }
  std::ostringstream one;
  const std::string clicked = dir / "clicked.facet", entered = dir / "entered.facet";
  one << "frames 2\ncommand select-image 1\nframes 3\nclick left image " << FormatXY(ghost_uv)
      << "\nframes 3\ncommand save " << clicked << "\nframes 1\nmove image 5 5\nkey enter\nframes 3\ncommand save "
      << entered << "\nframes 1\n";
  const nlohmann::json clicks = RenderScript(dir, path, "click", one.str());
  INFO("log:\n" << ReportLog(clicks));
  const facet::Project after_click = LoadProjectFile(clicked);
  REQUIRE(after_click.pins.size() == pins_before + 1);
  const facet::Pin& new_pin = after_click.pins.back();
  CHECK(new_pin.image_id == p.images[1].id);
  CHECK(new_pin.vertex.vertex == ghost_vertex);
  CHECK((new_pin.uv_px - ghost_uv).norm() < 1e-9);
  CHECK(LoadProjectFile(entered).pins.size() == pins_before + proposed);
  const nlohmann::json& undo = clicks.at("undo_stack");
  REQUIRE(undo.size() >= 2);
  CHECK(undo[undo.size() - 2].get<std::string>() == "Accept proposed pin");
  CHECK(undo.back().get<std::string>() ==
        "Accept " + std::to_string(proposed - 1) + " proposed pin" + (proposed == 2 ? "" : "s"));
}
