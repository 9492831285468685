// The project file: exact round-trips of every field, validation errors that name their
// location, atomic saves, path resolution and the frozen version-1 fixture.
#include <doctest/doctest.h>

#include <signal.h>
#include <stdlib.h>
#include <sys/resource.h>
#include <sys/stat.h>

#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/geometry/camera.h"
#include "core/image/image_io.h"
#include "core/io/project_io.h"
#include "core/util/input_limits.h"
#include "core/mesh/extrude.h"
#include "core/mesh/operators.h"
#include "core/scene/project.h"
#include "tests/synthetic_scene.h"
#include "tests/temp_files.h"

namespace fs = std::filesystem;
using facet::Axis;
using facet::Constraint;
using facet::Id;
using facet::Image;
using facet::Pin;
using facet::PolyMesh;
using facet::Primitive;
using facet::PrincipalPointMode;
using facet::Project;
using facet::Segment;

namespace {


std::set<std::string> ListDir(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) names.insert(entry.path().filename().string());
  return names;
}

void WriteFile(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out << bytes;
}

std::uint64_t Bits(double v) {
  std::uint64_t b;
  std::memcpy(&b, &v, sizeof(b));
  return b;
}

// The K-ops leave a mesh with holes in its id space: E_split, V_delete of another split
// vertex, V_connect then E_delete, a kept V_connect, an extrusion, and a free vertex with a
// solved offset. Returns the split vertex that was kept (free) and the extruded face's new
// vertices.
struct Operated {
  facet::VertexId free_vertex = facet::kNoElement;
  std::vector<facet::VertexId> extruded;
};
Operated OperateOn(Project* project, Primitive* prim) {
  PolyMesh& mesh = prim->mesh;
  Operated out;
  const facet::ESplitResult kept = facet::ESplit(&mesh, 0, 0.3);
  REQUIRE_MESSAGE(kept.ok, kept.message);
  out.free_vertex = kept.vertex;
  const facet::ESplitResult removed = facet::ESplit(&mesh, 1, 0.6);
  REQUIRE_MESSAGE(removed.ok, removed.message);
  const facet::VDeleteResult deleted = facet::VDelete(&mesh, removed.vertex);
  REQUIRE_MESSAGE(deleted.ok, deleted.message);
  facet::FaceId quad = facet::kNoFace;
  for (facet::FaceId f = 0; f < mesh.FaceIdEnd() && quad == facet::kNoFace; ++f)
    if (mesh.IsFace(f) && facet::FaceDegree(mesh, f) >= 4) quad = f;
  REQUIRE(quad != facet::kNoFace);
  std::vector<facet::VertexId> loop = facet::FaceVertices(mesh, quad);
  const facet::VConnectResult temporary = facet::VConnect(&mesh, quad, loop[0], loop[2]);
  REQUIRE_MESSAGE(temporary.ok, temporary.message);
  const facet::EDeleteResult merged = facet::EDelete(&mesh, temporary.edge);
  REQUIRE_MESSAGE(merged.ok, merged.message);
  loop = facet::FaceVertices(mesh, merged.kept_face);
  REQUIRE(loop.size() >= 4);
  const facet::VConnectResult connect = facet::VConnect(&mesh, merged.kept_face, loop[1], loop[3]);
  REQUIRE_MESSAGE(connect.ok, connect.message);
  const facet::ExtrudeResult extruded = facet::ExtrudeFace(&mesh, prim->shape, connect.new_face, 0.375);
  REQUIRE_MESSAGE(extruded.ok, extruded.message);
  out.extruded = extruded.new_vertices;
  mesh.vertex(out.free_vertex).local.free = true;
  mesh.vertex(out.free_vertex).local.offset = Eigen::Vector3d(0.01, -0.02, 1.0 / 3.0);
  facet::RefreshPrimitive(project, prim);
  const auto problems = facet::Validate(mesh);
  REQUIRE_MESSAGE(problems.empty(), problems.front());
  REQUIRE(mesh.VertexIdEnd() > static_cast<std::uint32_t>(mesh.NumVertices()));
  REQUIRE(mesh.EdgeIdEnd() > static_cast<std::uint32_t>(mesh.NumEdges()));
  REQUIRE(mesh.FaceIdEnd() > static_cast<std::uint32_t>(mesh.NumFaces()));
  return out;
}

facet::PrimitiveShape ShapeOfKind(int k) {
  switch (k % 6) {
    case 0: return facet::MakeBox(facet::kNoId, {1.0, 2.5, 0.75});
    case 1: return facet::MakeWedge(facet::kNoId, {2.0, 1.5, 0.5});
    case 2: return facet::MakePrism(facet::kNoId, 5, 1.25, 2.0);
    case 3: return facet::MakePyramid(facet::kNoId, {2.0, 2.5, 1.75});
    case 4: return facet::MakeCylinder(facet::kNoId, 7, 0.5, 3.0);
    default: return facet::MakePlane(facet::kNoId, 3.0, 2.0);
  }
}

// Every field away from its default: several images, segments on each axis, primitives of
// every kind with all lock combinations, one operated primitive of each kind (id holes, free
// vertex, extrusion), an attachment, pins on corners and on K-op vertices, and a constraint
// of every kind.
Project MakeFullProject() {
  Project p;
  p.units = "ft";
  const char* paths[] = {"photos/front.jpg", "../other/side view.png", "/abs/top.JPG"};
  for (int i = 0; i < 3; ++i) {
    Image im;
    im.id = p.NewId();
    im.path = paths[i];
    im.width_px = 4000 + i;
    im.height_px = 3000 - i;
    im.camera.width_px = 2000 + i;
    im.camera.height_px = 1500 - i;
    im.camera.focal_px = 3123.456789012345 + i;
    im.camera.principal_point_px = {1999.75 + 0.1 * i, 1499.125 - 0.3 * i};
    im.camera.cam_from_world_rotation = facet::RotationFromAngleAxis(Eigen::Vector3d(0.3 + 0.1 * i, -0.7, 1.1));
    im.camera.cam_from_world_translation = {1.5, -2.25 + i, 7.0 / 3.0};
    im.camera_calibrated = i != 1;
    im.principal_point_mode = static_cast<PrincipalPointMode>(i);
    im.fixed_principal_point_px = {12.5 + i, 8.25};
    im.pose_locked = i == 2;
    im.focal_locked = i != 0;
    im.principal_point_locked = i == 1;
    im.camera.k1 = -0.123456789012345 * i;
    im.camera.k2 = 0.0456 * i;
    im.focal_mode = static_cast<facet::FocalMode>(i);
    im.fixed_focal_px = 1234.5 + i;
    im.focal_prior_px = 2345.25 + i;
    im.focal_prior_std_px = 117.0 / 3.0;
    im.use_horizon = i == 2;
    im.horizon_px = {0.5, 480.25 + i, 3999.0, 470.125};
    im.estimate_distortion = i == 1;
    im.distortion_locked = i != 1;
    im.axis_quarter_turns = i - 1;  // unchosen, 0, 1
    p.images.push_back(im);
  }
  for (int i = 0; i < 3; ++i) {
    for (int a = 0; a < 3; ++a) {
      for (int k = 0; k < 2; ++k) {
        Segment s;
        s.id = p.NewId();
        s.image_id = p.images[i].id;
        s.axis = static_cast<Axis>(a);
        s.a_px = {0.1 * (i + 1) + a, -3.7 * k};
        s.b_px = {1e4 / 3.0 + a, 2.0 / 7.0 + k};
        p.segments.push_back(s);
      }
    }
  }
  for (int mask = 0; mask < 32; ++mask) {
    facet::PrimitiveShape shape = ShapeOfKind(mask);
    shape.params[0] += 0.1 * mask;
    shape.rotation = {0.01 * mask, -0.2, 0.3};
    shape.translation = {static_cast<double>(mask), -0.5 * mask, 0.125};
    const std::string name =
        mask == 5 ? "Turm \xC3\xBC \"quoted\" \\ tab\t \xE2\x98\x83" : "primitive " + std::to_string(mask);
    std::string message;
    REQUIRE_MESSAGE(facet::AddPrimitiveToProject(&p, shape, name, nullptr, &message), message);
    Primitive& prim = p.primitives.back();
    prim.param_locked = {(mask & 1) != 0, (mask & 2) != 0, (mask & 4) != 0, mask % 3 == 0};
    prim.rotation_locked = (mask & 8) != 0;
    prim.translation_locked = (mask & 16) != 0;
  }
  // A wedge roof on box 0.
  REQUIRE(p.primitives[1].shape.kind == facet::PrimitiveKind::kWedge);
  REQUIRE(facet::AttachOnTop(p.primitives[0].shape, &p.primitives[1].shape, nullptr));
  p.primitives[1].attached_to = p.primitives[0].id;
  facet::RefreshPrimitive(&p, &p.primitives[1]);
  std::vector<Operated> operated;
  for (int k = 0; k < 6; ++k) {
    facet::PrimitiveShape shape = ShapeOfKind(k);
    shape.translation = {-3.0 * k, 2.0, 0.0};
    shape.rotation = {0.0, 0.0, 0.25 * k};
    REQUIRE(facet::AddPrimitiveToProject(&p, shape, "operated " + std::to_string(k), nullptr, nullptr));
    operated.push_back(OperateOn(&p, &p.primitives.back()));
  }
  for (int c = 0; c < 10; ++c) {
    Pin pin;
    pin.id = p.NewId();
    pin.image_id = p.images[c % 3].id;
    pin.vertex = {p.primitives[c * 3].id, static_cast<facet::VertexId>(c % 5)};
    pin.uv_px = {100.5 * c + 0.1, -17.25 + 1.0 / (c + 3)};
    p.pins.push_back(pin);
  }
  for (int k = 0; k < 6; ++k) {
    const facet::Id id = p.primitives[32 + k].id;
    for (facet::VertexId v : {operated[k].free_vertex, operated[k].extruded[0]}) {
      Pin pin;
      pin.id = p.NewId();
      pin.image_id = p.images[k % 3].id;
      pin.vertex = {id, v};
      pin.uv_px = {7.5 * k, 1.0 / (k + 7)};
      p.pins.push_back(pin);
    }
  }
  const facet::Id a = p.primitives[32].id, b = p.primitives[35].id;
  const auto& x = operated[0].extruded;
  for (int kind = 0; kind <= static_cast<int>(facet::ConstraintKind::kEdgeOnImageLine); ++kind) {
    Constraint c;
    c.id = p.NewId();
    c.kind = static_cast<facet::ConstraintKind>(kind);
    switch (c.kind) {
      case facet::ConstraintKind::kCoplanar: c.vertices = {{a, x[0]}, {a, x[1]}, {a, x[2]}, {a, 0}, {b, 0}}; break;
      case facet::ConstraintKind::kCollinear: c.vertices = {{a, 0}, {a, operated[0].free_vertex}, {a, 1}}; break;
      case facet::ConstraintKind::kFixedPoint: c.vertices = {{b, 4}}; break;
      case facet::ConstraintKind::kDistance:
      case facet::ConstraintKind::kAlongAxis:
      case facet::ConstraintKind::kEdgeOnImageLine: c.vertices = {{a, 2}, {b, operated[3].free_vertex}}; break;
      default: c.vertices = {{a, 0}, {a, 1}, {b, 2}, {b, 3}}; break;
    }
    c.value = 2.5 + kind / 7.0;
    c.point = {0.1 * kind, -1.0 / 3.0, 4.0};
    c.axis = static_cast<Axis>(kind % 3);
    c.image_id = c.kind == facet::ConstraintKind::kEdgeOnImageLine ? p.images[2].id : facet::kNoId;
    c.line_a_px = {10.25 * kind, 3.0};
    c.line_b_px = {-1.5, 1e3 / 7.0};
    p.constraints.push_back(c);
  }
  // The user's texture choices (format version 3): a photo out of texturing, faces with a
  // forced photo and exclusions, and one override whose face and photo are gone (kept).
  p.images[1].use_for_texture = false;
  // Photos sharing a lens (format version 5): two in group 3, one on its own.
  p.images[0].lens_group = 3;
  p.images[2].lens_group = 3;
  facet::SetFaceTextureOverride(&p.primitives[32], {0, p.images[0].id, {p.images[2].id}});
  facet::SetFaceTextureOverride(&p.primitives[32], {2, facet::kNoId, {p.images[1].id, p.images[0].id}});
  facet::SetFaceTextureOverride(&p.primitives[3], {4000, p.next_id + 1000, {}});
  for (int k = 0; k < 2; ++k) {
    facet::Reference ref;
    ref.id = p.NewId();
    ref.path = k == 0 ? "survey/site plan.obj" : "../scans/church.glb";
    ref.y_up = k == 0;
    ref.visible = k == 1;
    p.references.push_back(ref);
  }
  p.next_id += 17;
  return p;
}

// A small valid project for loops over many variants of its text.
Project MakeSmallProject() {
  Project p;
  Image im;
  im.id = p.NewId();
  im.path = "a.jpg";
  im.width_px = 640;
  im.height_px = 480;
  im.camera.focal_px = 500.25;
  p.images.push_back(im);
  Segment s;
  s.id = p.NewId();
  s.image_id = im.id;
  s.axis = Axis::kZ;
  s.a_px = {1.5, 2.5};
  s.b_px = {3.5, 400.125};
  p.segments.push_back(s);
  facet::Id box_id = facet::kNoId;
  REQUIRE(facet::AddPrimitiveToProject(&p, facet::MakeBox(facet::kNoId, {1.0, 2.0, 3.0}), "b", &box_id, nullptr));
  Pin pin;
  pin.id = p.NewId();
  pin.image_id = im.id;
  pin.vertex = {box_id, 6};
  pin.uv_px = {10.0, 20.0};
  p.pins.push_back(pin);
  Constraint c;
  c.id = p.NewId();
  c.kind = facet::ConstraintKind::kDistance;
  c.vertices = {{box_id, 0}, {box_id, 6}};
  c.value = 4.5;
  p.constraints.push_back(c);
  facet::Reference ref;
  ref.id = p.NewId();
  ref.path = "site.obj";
  p.references.push_back(ref);
  return p;
}

void CheckRoundTrip(const Project& p) {
  const std::string text = facet::ProjectToJson(p);
  const facet::ProjectLoadResult r = facet::ProjectFromJson(text);
  INFO("error: " << r.error);
  REQUIRE(r.ok());
  CHECK(r.warnings.empty());
  CHECK(r.project == p);
  CHECK(facet::ProjectToJson(r.project) == text);
}

// Loads `text` and requires an error that contains `location`.
void CheckErrorNames(const std::string& text, const std::string& location) {
  const facet::ProjectLoadResult r = facet::ProjectFromJson(text);
  INFO("expected an error naming '" << location << "', got: '" << r.error << "'");
  CHECK_FALSE(r.ok());
  CHECK(r.error.find(location) != std::string::npos);
}

using Json = nlohmann::json;

Json SmallJson() { return Json::parse(facet::ProjectToJson(MakeSmallProject())); }

}  // namespace

TEST_CASE("every field round-trips exactly and re-saving is byte-identical") {
  const Project p = MakeFullProject();
  CheckRoundTrip(p);

  const facet::testing::TempDir dir("project_io");
  const std::string path = dir / "full.facet";
  REQUIRE(facet::SaveProject(p, path) == "");
  const std::string first = facet::testing::ReadText(path);
  CHECK(first == facet::ProjectToJson(p));
  const facet::ProjectLoadResult loaded = facet::LoadProject(path);
  INFO("error: " << loaded.error);
  REQUIRE(loaded.ok());
  CHECK(loaded.project == p);
  REQUIRE(facet::SaveProject(loaded.project, path) == "");
  CHECK(facet::testing::ReadText(path) == first);
  CHECK(ListDir(dir.path) == std::set<std::string>{"full.facet"});
}

TEST_CASE("each single field is written and read back") {
  // A field the writer forgot would read back as its default; changing each field alone
  // and requiring both a different text and an equal project catches that.
  const Project base = MakeFullProject();
  const std::string base_text = facet::ProjectToJson(base);
  std::vector<std::pair<const char*, std::function<void(Project&)>>> edits = {
      {"units", [](Project& p) { p.units = "mm"; }},
      {"next_id", [](Project& p) { p.next_id += 1; }},
      {"image.path", [](Project& p) { p.images[0].path = "x/y.png"; }},
      {"image.width_px", [](Project& p) { p.images[0].width_px += 1; }},
      {"image.height_px", [](Project& p) { p.images[0].height_px += 1; }},
      {"camera.width_px", [](Project& p) { p.images[0].camera.width_px += 1; }},
      {"camera.height_px", [](Project& p) { p.images[0].camera.height_px += 1; }},
      {"camera.focal_px", [](Project& p) { p.images[0].camera.focal_px *= 1.5; }},
      {"camera.pp.x", [](Project& p) { p.images[0].camera.principal_point_px.x() += 0.5; }},
      {"camera.pp.y", [](Project& p) { p.images[0].camera.principal_point_px.y() += 0.5; }},
      {"camera.rotation",
       [](Project& p) {
         p.images[1].camera.cam_from_world_rotation = facet::RotationFromAngleAxis(Eigen::Vector3d(0.1, 0.2, 0.3));
       }},
      {"camera.translation", [](Project& p) { p.images[1].camera.cam_from_world_translation.z() = -4.0; }},
      {"image.camera_calibrated", [](Project& p) { p.images[1].camera_calibrated = true; }},
      {"image.principal_point_mode", [](Project& p) { p.images[0].principal_point_mode = PrincipalPointMode::kFixed; }},
      {"image.fixed_principal_point_px", [](Project& p) { p.images[2].fixed_principal_point_px.y() = 99.0; }},
      {"image.pose_locked", [](Project& p) { p.images[0].pose_locked = true; }},
      {"image.focal_locked", [](Project& p) { p.images[0].focal_locked = true; }},
      {"image.principal_point_locked", [](Project& p) { p.images[0].principal_point_locked = true; }},
      {"camera.k1", [](Project& p) { p.images[0].camera.k1 = 0.01; }},
      {"camera.k2", [](Project& p) { p.images[0].camera.k2 = 0.01; }},
      {"image.focal_mode", [](Project& p) { p.images[0].focal_mode = facet::FocalMode::kPrior; }},
      {"image.fixed_focal_px", [](Project& p) { p.images[0].fixed_focal_px += 1.0; }},
      {"image.focal_prior_px", [](Project& p) { p.images[0].focal_prior_px += 1.0; }},
      {"image.focal_prior_std_px", [](Project& p) { p.images[0].focal_prior_std_px += 1.0; }},
      {"image.use_horizon", [](Project& p) { p.images[0].use_horizon = true; }},
      {"image.horizon_px", [](Project& p) { p.images[0].horizon_px.w() = 1.0; }},
      {"image.estimate_distortion", [](Project& p) { p.images[0].estimate_distortion = true; }},
      {"image.distortion_locked", [](Project& p) { p.images[0].distortion_locked = false; }},
      {"image.axis_quarter_turns", [](Project& p) { p.images[0].axis_quarter_turns = 3; }},
      {"image.use_for_texture", [](Project& p) { p.images[0].use_for_texture = false; }},
      {"image.lens_group", [](Project& p) { p.images[1].lens_group = 2; }},
      {"primitive.face_textures.face", [](Project& p) { p.primitives[32].face_textures[1].face = 3; }},
      {"primitive.face_textures.source_image",
       [](Project& p) { p.primitives[32].face_textures[0].source_image = p.images[1].id; }},
      {"primitive.face_textures.excluded_images",
       [](Project& p) { p.primitives[32].face_textures[1].excluded_images.push_back(p.images[2].id); }},
      {"primitive.face_textures (new entry)",
       [](Project& p) { facet::SetFaceTextureOverride(&p.primitives[0], {1, p.images[2].id, {}}); }},
      {"segment.id", [](Project& p) { p.segments[1].id = p.NewId(); }},
      {"segment.image_id", [](Project& p) { p.segments[0].image_id = p.images[2].id; }},
      {"segment.axis", [](Project& p) { p.segments[0].axis = Axis::kY; }},
      {"segment.a_px", [](Project& p) { p.segments[0].a_px.y() = 0.5; }},
      {"segment.b_px", [](Project& p) { p.segments[0].b_px.x() = 0.5; }},
      {"primitive.name", [](Project& p) { p.primitives[3].name = "renamed"; }},
      {"primitive.kind", [](Project& p) { p.primitives[6].shape.kind = facet::PrimitiveKind::kWedge; }},
      {"primitive.params", [](Project& p) { p.primitives[3].shape.params.z() = 9.0; }},
      {"primitive.params[3]", [](Project& p) { p.primitives[3].shape.params[3] = 0.5; }},
      {"primitive.segments", [](Project& p) { p.primitives[2].shape.segments = 9; }},
      {"primitive.rotation", [](Project& p) { p.primitives[3].shape.rotation.x() = 1.0; }},
      {"primitive.translation", [](Project& p) { p.primitives[3].shape.translation.y() = 1.0; }},
      {"primitive.param_locked[0]", [](Project& p) { p.primitives[0].param_locked[0] = true; }},
      {"primitive.param_locked[1]", [](Project& p) { p.primitives[0].param_locked[1] = true; }},
      {"primitive.param_locked[2]", [](Project& p) { p.primitives[0].param_locked[2] = true; }},
      {"primitive.param_locked[3]", [](Project& p) { p.primitives[1].param_locked[3] = true; }},
      {"primitive.rotation_locked", [](Project& p) { p.primitives[0].rotation_locked = true; }},
      {"primitive.translation_locked", [](Project& p) { p.primitives[0].translation_locked = true; }},
      {"primitive.attached_to", [](Project& p) { p.primitives[1].attached_to = p.primitives[6].id; }},
      {"vertex.a", [](Project& p) { p.primitives[32].mesh.vertex(0).local.a(1, 1) = 0.5; }},
      {"vertex.b", [](Project& p) { p.primitives[32].mesh.vertex(0).local.b(2, 2) = 0.25; }},
      {"vertex.t", [](Project& p) { p.primitives[32].mesh.vertex(0).local.t = 0.125; }},
      {"vertex.on_edge", [](Project& p) { p.primitives[32].mesh.vertex(1).local.on_edge = true; }},
      {"vertex.free", [](Project& p) { p.primitives[32].mesh.vertex(1).local.free = true; }},
      {"vertex.offset", [](Project& p) { p.primitives[33].mesh.vertex(2).local.offset.y() = -0.75; }},
      {"vertex.position", [](Project& p) { p.primitives[34].mesh.vertex(3).position.z() += 1e-9; }},
      {"halfedge.uv", [](Project& p) { p.primitives[35].mesh.halfedge(5).uv.x() = 2.0 / 3.0; }},
      {"face.material", [](Project& p) { p.primitives[36].mesh.face(0).material = 42; }},
      {"pin.image_id", [](Project& p) { p.pins[0].image_id = p.images[2].id; }},
      {"pin.primitive_id", [](Project& p) { p.pins[0].vertex.primitive_id = p.primitives[31].id; }},
      {"pin.vertex", [](Project& p) { p.pins[0].vertex.vertex = 3; }},
      {"pin.uv_px", [](Project& p) { p.pins[0].uv_px.x() = -1.0; }},
      {"constraint.kind", [](Project& p) { p.constraints[2].kind = facet::ConstraintKind::kEqualLength; }},
      {"constraint.vertices", [](Project& p) { p.constraints[2].vertices[1].vertex = 3; }},
      {"constraint.vertices.primitive",
       [](Project& p) { p.constraints[5].vertices[0].primitive_id = p.primitives[0].id; }},
      {"constraint.value", [](Project& p) { p.constraints[5].value = 1e-3; }},
      {"constraint.point", [](Project& p) { p.constraints[6].point.z() = -4.0; }},
      {"constraint.axis", [](Project& p) { p.constraints[7].axis = Axis::kX; }},
      {"constraint.image_id", [](Project& p) { p.constraints[8].image_id = p.images[0].id; }},
      {"constraint.line_a_px", [](Project& p) { p.constraints[8].line_a_px.y() = 0.5; }},
      {"constraint.line_b_px", [](Project& p) { p.constraints[8].line_b_px.x() = 0.5; }},
      {"reference.path", [](Project& p) { p.references[0].path = "other.obj"; }},
      {"reference.y_up", [](Project& p) { p.references[0].y_up = false; }},
      {"reference.visible", [](Project& p) { p.references[1].visible = false; }},
  };
  for (const auto& [name, edit] : edits) {
    const std::string& edit_name = name;  // clang 14 cannot capture a structured binding (INFO)
    INFO("edit: " << edit_name);
    Project changed = base;
    edit(changed);
    REQUIRE_FALSE(changed == base);
    const std::string text = facet::ProjectToJson(changed);
    CHECK(text != base_text);
    const facet::ProjectLoadResult r = facet::ProjectFromJson(text);
    INFO("error: " << r.error);
    REQUIRE(r.ok());
    CHECK(r.project == changed);
  }
}

TEST_CASE("the synthetic box scene round-trips") {
  CheckRoundTrip(facet::testing::MakeBoxScene().project);
  facet::testing::SyntheticSceneOptions o;
  o.noise_px = 0.7;
  o.scale = 1e-3;
  o.seed = 42;
  CheckRoundTrip(facet::testing::MakeBoxScene(o).project);
}

TEST_CASE("doubles round-trip bit-exactly") {
  const std::vector<double> awkward = {0.1 + 0.2,
                                       1e-310,  // subnormal
                                       -0.0,
                                       0.1,
                                       1.0 / 3.0,
                                       123456789.12345678,
                                       0.30000000000000004,
                                       5e-324,
                                       DBL_MAX,
                                       -DBL_MAX,
                                       DBL_MIN,
                                       std::nextafter(1.0, 2.0),
                                       std::nextafter(1.0, 0.0),
                                       M_PI * 1e20,
                                       -2.5e-300,
                                       9007199254740993.0,
                                       1e23,
                                       4.35,
                                       2.0};
  std::mt19937_64 rng(7);
  std::vector<double> values = awkward;
  while (values.size() < awkward.size() + 2000) {
    const std::uint64_t bits = rng();
    double v;
    std::memcpy(&v, &bits, sizeof(v));
    if (std::isfinite(v)) values.push_back(v);
  }

  Project p = MakeSmallProject();
  p.pins.clear();
  const Segment model = p.segments[0];
  p.segments.clear();
  for (size_t i = 0; i + 1 < values.size(); i += 2) {
    Segment s = model;
    s.id = p.NewId();
    s.a_px = {values[i], values[i + 1]};
    s.b_px = {values[i + 1], values[i]};
    p.segments.push_back(s);
  }
  // Shape values only: the mesh keeps its cached positions, which the file stores as they are.
  p.primitives[0].shape.params = {std::abs(values[1]), std::abs(values[7]), DBL_MAX, 5e-324};  // >= 0
  p.primitives[0].shape.translation = {values[2], values[5], values[14]};
  p.primitives[0].mesh.vertex(3).local.offset = {values[3], values[9], values[11]};

  const std::string text = facet::ProjectToJson(p);
  const facet::ProjectLoadResult r = facet::ProjectFromJson(text);
  INFO("error: " << r.error);
  REQUIRE(r.ok());
  REQUIRE(r.project.segments.size() == p.segments.size());
  int mismatches = 0;
  for (size_t i = 0; i < p.segments.size(); ++i) {
    for (int k = 0; k < 2; ++k) {
      if (Bits(p.segments[i].a_px(k)) != Bits(r.project.segments[i].a_px(k)) ||
          Bits(p.segments[i].b_px(k)) != Bits(r.project.segments[i].b_px(k))) {
        ++mismatches;
        MESSAGE("mismatch: " << p.segments[i].a_px(k) << " -> " << r.project.segments[i].a_px(k));
      }
    }
  }
  CHECK(mismatches == 0);
  // -0.0 == 0.0, so check the sign bit on its own: segment 1 holds values[2] = -0.0.
  CHECK(std::signbit(r.project.segments[1].a_px.x()));
  CHECK(std::signbit(r.project.primitives[0].shape.translation.x()));
  for (int k = 0; k < 3; ++k) {
    CHECK(Bits(r.project.primitives[0].shape.params(k)) == Bits(p.primitives[0].shape.params(k)));
    CHECK(Bits(r.project.primitives[0].shape.translation(k)) == Bits(p.primitives[0].shape.translation(k)));
    CHECK(Bits(r.project.primitives[0].mesh.vertex(3).local.offset(k)) ==
          Bits(p.primitives[0].mesh.vertex(3).local.offset(k)));
  }
  CHECK(r.project == p);
}

TEST_CASE("NaN and infinity are refused with the field's path, and nothing is written") {
  const facet::testing::TempDir dir("project_io");
  const std::string path = dir / "p.facet";
  {
    Project p = MakeFullProject();
    p.images[1].camera.focal_px = std::numeric_limits<double>::quiet_NaN();
    const std::string error = facet::SaveProject(p, path);
    INFO(error);
    CHECK(error.find("images[1].camera.focal_px") != std::string::npos);
    CHECK(error.find("NaN") != std::string::npos);
    CHECK(facet::CheckProjectSavable(p).find("images[1].camera.focal_px") != std::string::npos);
  }
  {
    Project p = MakeFullProject();
    p.primitives[4].shape.translation.z() = -std::numeric_limits<double>::infinity();
    const std::string error = facet::SaveProject(p, path);
    INFO(error);
    CHECK(error.find("primitives[4].translation[2]") != std::string::npos);
    CHECK(error.find("infinity") != std::string::npos);
  }
  {
    Project p = MakeFullProject();
    p.primitives[33].mesh.vertex(2).local.offset.x() = std::numeric_limits<double>::quiet_NaN();
    const std::string error = facet::SaveProject(p, path);
    INFO(error);
    CHECK(error.find("primitives[33].mesh.vertices[2].offset[0]") != std::string::npos);
  }
  {
    Project p = MakeFullProject();
    p.images[0].camera.cam_from_world_rotation(1, 2) = std::numeric_limits<double>::quiet_NaN();
    const std::string error = facet::SaveProject(p, path);
    INFO(error);
    CHECK(error.find("images[0].camera.rotation[5]") != std::string::npos);
  }
  CHECK(ListDir(dir.path).empty());
  CHECK(facet::CheckProjectSavable(MakeFullProject()) == "");
}

TEST_CASE("a project that would not load back is not saved, and the old file stays") {
  const facet::testing::TempDir dir("project_io");
  const std::string path = dir / "p.facet";
  WriteFile(path, "old contents");
  Project p = MakeFullProject();
  p.pins[2].vertex.primitive_id = p.next_id + 100;
  const std::string error = facet::SaveProject(p, path);
  INFO(error);
  CHECK(error.find("pins[2].vertex") != std::string::npos);
  Project q = MakeFullProject();
  q.primitives[1].name = "bad \xFF utf-8";
  const std::string error2 = facet::SaveProject(q, path);
  INFO(error2);
  CHECK(error2.find("primitives[1].name") != std::string::npos);
  Project r = MakeFullProject();
  r.constraints[0].vertices[0].vertex = 999;  // a vertex the primitive does not have
  const std::string error3 = facet::SaveProject(r, path);
  INFO(error3);
  CHECK(error3.find("constraints[0].vertices[0]") != std::string::npos);
  CHECK(facet::testing::ReadText(path) == "old contents");
  CHECK(ListDir(dir.path) == std::set<std::string>{"p.facet"});
}

TEST_CASE("every truncation of a valid file is an error with a line and column") {
  const std::string text = facet::ProjectToJson(MakeSmallProject());
  REQUIRE(text.size() > 500);
  REQUIRE(text.substr(text.size() - 2) == "}\n");
  // Cutting only the final newline leaves valid JSON; every shorter cut must fail.
  for (size_t length = 0; length + 1 < text.size(); ++length) {
    const std::string cut = text.substr(0, length);
    const facet::ProjectLoadResult r = facet::ProjectFromJson(cut);
    CAPTURE(length);
    INFO("error: " << r.error);
    REQUIRE_FALSE(r.ok());
    // The error is at the end of the input: its line is the last line of the prefix.
    const size_t lines = 1 + static_cast<size_t>(std::count(cut.begin(), cut.end(), '\n'));
    const size_t last_line_start = cut.rfind('\n') == std::string::npos ? 0 : cut.rfind('\n') + 1;
    CHECK(r.error.rfind("line " + std::to_string(lines) + ", column ", 0) == 0);
    if (cut.find_first_not_of(" \t\r\n") != std::string::npos && cut.back() != '\n') {
      // End of input: the column just past the last character.
      const size_t column = cut.size() - last_line_start + 1;
      CHECK(r.error.rfind("line " + std::to_string(lines) + ", column " + std::to_string(column) + ":", 0) == 0);
    }
    CHECK(r.project == Project());
  }
  // Truncated files on disk too, at a few cut points.
  const facet::testing::TempDir dir("project_io");
  for (size_t length : {size_t{0}, size_t{1}, text.size() / 3, text.size() / 2, text.size() - 2}) {
    const std::string path = dir / "cut.facet";
    WriteFile(path, text.substr(0, length));
    const facet::ProjectLoadResult r = facet::LoadProject(path);
    INFO("length " << length << ": " << r.error);
    CHECK_FALSE(r.ok());
    CHECK(r.error.find(path) != std::string::npos);
    CHECK(r.error.find("line ") != std::string::npos);
  }
}

TEST_CASE("syntax errors report the line and column of the offending character") {
  const std::string text = "{\n  \"format\": \"facet-project\",\n  \"version\": 1,\n  oops: 3\n}\n";
  const facet::ProjectLoadResult r = facet::ProjectFromJson(text);
  INFO(r.error);
  CHECK(r.error.rfind("line 4, column 3:", 0) == 0);
  const facet::ProjectLoadResult r2 = facet::ProjectFromJson("{\"a\": [1, 2,, 3]}");
  INFO(r2.error);
  CHECK(r2.error.rfind("line 1, column 13:", 0) == 0);
}

TEST_CASE("files that are not projects at all are errors, never crashes") {
  CheckErrorNames("", "the file is empty");
  CheckErrorNames(" \n\t \n", "the file is empty");
  CheckErrorNames("hello world", "line 1, column 1");
  CheckErrorNames(std::string("\x89PNG\r\n\x1a\n\0\0\0\rIHDR", 16), "line 1, column 1");
  CheckErrorNames("[1, 2, 3]", "(top level): expected a JSON object");
  CheckErrorNames("null", "(top level)");
  CheckErrorNames("42", "(top level)");
  CheckErrorNames("{}", "format: missing field");
  CheckErrorNames("{\"format\": \"something-else\", \"version\": 1}", "format: expected \"facet-project\"");
  CheckErrorNames(std::string(100000, '['), "line 1");
  CheckErrorNames(std::string(50000, '{'), "line 1");
  CheckErrorNames("{\"format\": \"facet-project\", \"version\": 1, \"units\": \"\xFF\xFE\"}", "line 1");
  std::mt19937 rng(3);
  for (int trial = 0; trial < 200; ++trial) {
    std::string garbage(rng() % 300, '\0');
    for (char& c : garbage) c = static_cast<char>(rng() & 0xFF);
    if (trial % 2) garbage = "{" + garbage;
    const facet::ProjectLoadResult r = facet::ProjectFromJson(garbage);
    CAPTURE(trial);
    CHECK_FALSE(r.ok());
  }
}

TEST_CASE("version: newer files are refused clearly, bad versions are errors") {
  Json j = SmallJson();
  j["version"] = 7;
  const facet::ProjectLoadResult r = facet::ProjectFromJson(j.dump());
  CHECK(r.error == "version: written by a newer Facet: version 7, this build reads up to " +
                   std::to_string(Project::kFormatVersion));
  j["version"] = 0;
  CheckErrorNames(j.dump(), "version: expected a positive integer");
  j["version"] = -3;
  CheckErrorNames(j.dump(), "version: expected a positive integer");
  j["version"] = "1";
  CheckErrorNames(j.dump(), "version: expected a positive integer");
  j["version"] = 1.0;
  CheckErrorNames(j.dump(), "version: expected a positive integer");
  j["version"] = 18446744073709551615ull;
  CheckErrorNames(j.dump(), "written by a newer Facet");
  j.erase("version");
  CheckErrorNames(j.dump(), "version: missing field");
}

namespace {
// Every value in the tree with its path as the loader names it ("primitives[0].params[1]").
void CollectPaths(const Json& j, const Json::json_pointer& ptr, const std::string& name,
                  std::vector<std::pair<Json::json_pointer, std::string>>* out) {
  if (!name.empty()) out->push_back({ptr, name});
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it)
      CollectPaths(it.value(), ptr / it.key(), name.empty() ? it.key() : name + "." + it.key(), out);
  } else if (j.is_array()) {
    for (size_t i = 0; i < j.size(); ++i) CollectPaths(j[i], ptr / i, name + "[" + std::to_string(i) + "]", out);
  }
}
}  // namespace

TEST_CASE("a version-2 file written before distortion and the focal modes loads with their defaults") {
  Json old = SmallJson();
  for (Json& image : old["images"]) {
    for (const char* key : {"focal_mode", "fixed_focal_px", "focal_prior_px", "focal_prior_std_px", "use_horizon",
                            "horizon_px", "estimate_distortion", "distortion_locked", "axis_quarter_turns"})
      image.erase(key);
    image["camera"].erase("k1");
    image["camera"].erase("k2");
  }
  const facet::ProjectLoadResult r = facet::ProjectFromJson(old.dump());
  INFO(r.error);
  REQUIRE(r.ok());
  const facet::Image defaults;
  for (const facet::Image& im : r.project.images) {
    CHECK(im.camera.k1 == 0.0);
    CHECK(im.camera.k2 == 0.0);
    CHECK(im.focal_mode == defaults.focal_mode);
    CHECK(im.fixed_focal_px == defaults.fixed_focal_px);
    CHECK(im.focal_prior_px == defaults.focal_prior_px);
    CHECK(im.focal_prior_std_px == defaults.focal_prior_std_px);
    CHECK(im.use_horizon == defaults.use_horizon);
    CHECK(im.horizon_px == defaults.horizon_px);
    CHECK(im.estimate_distortion == defaults.estimate_distortion);
    CHECK(im.distortion_locked == defaults.distortion_locked);
    CHECK(im.axis_quarter_turns == facet::Image::kAxisTurnsUnchosen);
  }
}

TEST_CASE("a world-frame turn outside -1..3 is an error naming the field") {
  Json bad = SmallJson();
  bad["images"][0]["axis_quarter_turns"] = 4;
  CheckErrorNames(bad.dump(), "images[0].axis_quarter_turns: expected an integer from -1 to 3");
}

TEST_CASE("a fixed focal or a focal prior without a positive value is an error naming the field") {
  Json fixed = SmallJson();
  fixed["images"][0]["focal_mode"] = "fixed";
  fixed["images"][0]["fixed_focal_px"] = 0.0;
  CheckErrorNames(fixed.dump(), "images[0].fixed_focal_px: must be positive");
  Json prior = SmallJson();
  prior["images"][0]["focal_mode"] = "prior";
  prior["images"][0]["focal_prior_std_px"] = -1.0;
  CheckErrorNames(prior.dump(), "images[0].focal_prior_px: a prior needs");
  Json unknown = SmallJson();
  unknown["images"][0]["focal_mode"] = "guess";
  CheckErrorNames(unknown.dump(), "images[0].focal_mode: expected \"solve\", \"fixed\" or \"prior\"");
}

TEST_CASE("every missing field and every wrong type is an error naming its path") {
  const Json good = SmallJson();
  REQUIRE(facet::ProjectFromJson(good.dump()).ok());
  std::vector<std::pair<Json::json_pointer, std::string>> paths;
  CollectPaths(good, Json::json_pointer(), "", &paths);
  REQUIRE(paths.size() > 50);
  int missing_cases = 0, type_cases = 0;
  // A constraint's vertex reference [primitive_id, vertex] is read as one value: errors inside
  // it name the reference.
  const std::regex inside_reference(R"((constraints\[\d+\]\.vertices\[\d+\])\[\d+\])");
  for (const auto& [ptr, name_in_tree] : paths) {
    std::smatch match;
    const std::string name = std::regex_match(name_in_tree, match, inside_reference) ? match[1].str() : name_in_tree;
    const std::string& path_in_tree = name_in_tree;  // clang 14 cannot capture a structured binding
    CAPTURE(path_in_tree);
    const bool in_object = good.at(ptr.parent_pointer()).is_object();
    // Fields added within version 2 (distortion, focal and horizon modes) may be absent:
    // files written before them load with the defaults (tested below).
    static const std::regex optional_field(
        R"(images\[\d+\]\.(camera\.k1|camera\.k2|focal_mode|fixed_focal_px|focal_prior_px|focal_prior_std_px|)"
        R"(use_horizon|horizon_px|estimate_distortion|distortion_locked|axis_quarter_turns))");
    if (in_object && !std::regex_match(name_in_tree, optional_field)) {
      Json removed = good;
      removed.at(ptr.parent_pointer()).erase(ptr.back());
      CheckErrorNames(removed.dump(), name + ": missing field");
      ++missing_cases;
    }
    // A value of the wrong kind: text where text is not expected, a number where it is.
    Json wrong = good;
    wrong.at(ptr) = good.at(ptr).is_string() ? Json(12345) : Json("oops");
    CheckErrorNames(wrong.dump(), name);
    // Booleans and integers are strict: 1 is not true, 1.5 is not an integer.
    if (good.at(ptr).is_boolean()) {
      wrong.at(ptr) = 1;
      CheckErrorNames(wrong.dump(), name + ": expected true or false");
    }
    if (good.at(ptr).is_number_integer()) {
      wrong.at(ptr) = 1.5;
      CheckErrorNames(wrong.dump(), name);
    }
    if (good.at(ptr).is_array() && !good.at(ptr).empty() && good.at(ptr)[0].is_primitive()) {
      wrong.at(ptr) = good.at(ptr);
      wrong.at(ptr).push_back(good.at(ptr)[0]);
      // "expected an array of 3 numbers", or "expected [primitive_id, vertex]".
      CheckErrorNames(wrong.dump(), name + ": expected ");
    }
    ++type_cases;
  }
  MESSAGE(missing_cases << " missing-field cases, " << type_cases << " wrong-type cases");
}

TEST_CASE("out-of-range values and bad references name their location") {
  const Json base = Json::parse(facet::ProjectToJson(MakeFullProject()));
  auto with = [&](const std::function<void(Json&)>& edit) {
    Json j = base;
    edit(j);
    return j.dump(2);
  };
  CheckErrorNames(with([](Json& j) { j["pins"][3]["vertex"] = 8; }),
                  "pins[3].vertex: refers to vertex 8, which primitive");
  CheckErrorNames(with([](Json& j) { j["pins"][3]["vertex"] = -1; }), "pins[3].vertex");
  CheckErrorNames(with([](Json& j) { j["primitives"][2]["params"][1] = -0.5; }),
                  "primitives[2].params[1]: a dimension cannot be negative");
  CheckErrorNames(with([](Json& j) {
                    j["primitives"][2]["params"] = {1.0, 2.0};
                  }),
                  "primitives[2].params: expected an array of 4 numbers");
  CheckErrorNames(with([](Json& j) { j["primitives"][2]["kind"] = "sphere"; }),
                  "primitives[2].kind: unknown primitive kind \"sphere\"");
  CheckErrorNames(with([](Json& j) { j["primitives"][1]["attached_to"] = 9999; }),
                  "primitives[1].attached_to: refers to a missing primitive");
  CheckErrorNames(with([](Json& j) { j["primitives"][1]["attached_to"] = j["primitives"][1]["id"]; }),
                  "primitives[1].attached_to");
  // Attachment cycles (issue 14: loaded, then the solve walked them): 2, 3 and all primitives.
  CheckErrorNames(with([](Json& j) {
                    j["primitives"][1]["attached_to"] = j["primitives"][2]["id"];
                    j["primitives"][2]["attached_to"] = j["primitives"][1]["id"];
                  }),
                  "primitives[1].attached_to: the chain of bases of primitive");
  CheckErrorNames(with([](Json& j) {
                    j["primitives"][1]["attached_to"] = j["primitives"][2]["id"];
                    j["primitives"][2]["attached_to"] = j["primitives"][3]["id"];
                    j["primitives"][3]["attached_to"] = j["primitives"][1]["id"];
                  }),
                  "loops (attachments must form trees)");
  CheckErrorNames(with([](Json& j) {
                    Json& prims = j["primitives"];
                    const size_t n = prims.size();
                    REQUIRE(n >= 4);
                    for (size_t i = 0; i < n; ++i) prims[i]["attached_to"] = prims[(i + 1) % n]["id"];
                  }),
                  "primitives[0].attached_to: the chain of bases");
  // A photo without pixels (issue 14: a solve then exited 0 and wrote the file).
  CheckErrorNames(with([](Json& j) { j["images"][0]["width_px"] = 0; }), "images[0].width_px");
  CheckErrorNames(with([](Json& j) { j["images"][1]["height_px"] = 0; }), "images[1].height_px");
  CheckErrorNames(with([](Json& j) { j["constraints"][0]["kind"] = "tangent"; }),
                  "constraints[0].kind: unknown constraint kind");
  CheckErrorNames(with([](Json& j) { j["constraints"][8]["image_id"] = 9999; }),
                  "constraints[8].image_id: refers to a missing image");
  CheckErrorNames(with([](Json& j) {
                    j["constraints"][1]["vertices"][0] = {1, 2, 3};
                  }),
                  "constraints[1].vertices[0]: expected [primitive_id, vertex]");
  CheckErrorNames(with([](Json& j) { j["constraints"][1]["vertices"][2][0] = j["images"][0]["id"]; }),
                  "constraints[1].vertices[2]: refers to a missing primitive");
  CheckErrorNames(with([](Json& j) { j["segments"][4]["axis"] = "w"; }), "segments[4].axis");
  CheckErrorNames(with([](Json& j) { j["segments"][4]["axis"] = "X"; }), "segments[4].axis");
  CheckErrorNames(with([](Json& j) { j["images"][1]["principal_point_mode"] = "auto"; }),
                  "images[1].principal_point_mode");
  CheckErrorNames(with([](Json& j) { j["primitives"][7]["id"] = j["primitives"][2]["id"]; }),
                  "primitives[7].id: duplicate id");
  CheckErrorNames(with([](Json& j) { j["constraints"][3]["id"] = j["pins"][0]["id"]; }),
                  "constraints[3].id: duplicate id");
  CheckErrorNames(with([](Json& j) { j["pins"][0]["id"] = j["images"][0]["id"]; }), "pins[0].id: duplicate id");
  CheckErrorNames(with([](Json& j) { j["segments"][3]["image_id"] = 9999; }),
                  "segments[3].image_id: refers to a missing image");
  CheckErrorNames(with([](Json& j) { j["pins"][5]["image_id"] = j["primitives"][0]["id"]; }),
                  "pins[5].image_id: refers to a missing image");
  CheckErrorNames(with([](Json& j) { j["pins"][5]["primitive_id"] = j["images"][0]["id"]; }),
                  "pins[5].vertex: refers to a missing primitive");
  CheckErrorNames(with([](Json& j) { j["next_id"] = j["constraints"].back()["id"]; }), "next_id: must be greater");
  CheckErrorNames(with([](Json& j) { j["primitives"][0]["id"] = 0; }),
                  "primitives[0].id: expected a positive integer id");
  CheckErrorNames(with([](Json& j) { j["primitives"][0]["id"] = -4; }), "primitives[0].id");
  CheckErrorNames(with([](Json& j) { j["images"][0]["width_px"] = -1; }), "images[0].width_px");
  CheckErrorNames(with([](Json& j) { j["images"][0]["width_px"] = 3000000000ull; }), "images[0].width_px");
  CheckErrorNames(with([](Json& j) { j["images"][2]["camera"]["focal_px"] = 0.0; }),
                  "images[2].camera.focal_px: must be positive");
  CheckErrorNames(with([](Json& j) { j["images"][2]["camera"]["rotation"][0] = 2.0; }),
                  "images[2].camera.rotation: not a rotation matrix");
  CheckErrorNames(with([](Json& j) {  // a reflection is orthonormal but not a rotation
                    for (int k = 0; k < 3; ++k)
                      j["images"][2]["camera"]["rotation"][k] = -j["images"][2]["camera"]["rotation"][k].get<double>();
                  }),
                  "images[2].camera.rotation: not a rotation matrix");
  {  // a number beyond the range of a double
    std::string text = with([](Json& j) { j["segments"][0]["a_px"][1] = 123.25; });
    REQUIRE(text.find("123.25") != std::string::npos);
    text.replace(text.find("123.25"), 6, "-1e400");
    const size_t at = text.find("-1e400");
    const size_t line = 1 + static_cast<size_t>(std::count(text.begin(), text.begin() + at, '\n'));
    const size_t column = at - text.rfind('\n', at);
    CheckErrorNames(
        text, "line " + std::to_string(line) + ", column " + std::to_string(column) + ": number out of range '-1e400'");
  }
}

TEST_CASE("unknown fields are warnings, not errors") {
  Json j = SmallJson();
  j["primitives"][0]["colour"] = "red";
  j["future_section"] = Json::array();
  const facet::ProjectLoadResult r = facet::ProjectFromJson(j.dump());
  INFO(r.error);
  REQUIRE(r.ok());
  CHECK(r.project == MakeSmallProject());
  REQUIRE(r.warnings.size() == 2);
  const std::string all = r.warnings[0] + "\n" + r.warnings[1];
  INFO(all);
  CHECK(all.find("primitives[0].colour: unknown field ignored") != std::string::npos);
  CHECK(all.find("future_section: unknown field ignored") != std::string::npos);
}

TEST_CASE("LoadProject: missing files are errors, missing images are warnings") {
  const facet::testing::TempDir dir("project_io");
  const facet::ProjectLoadResult missing = facet::LoadProject(dir / "nope.facet");
  INFO(missing.error);
  CHECK_FALSE(missing.ok());
  CHECK(missing.error.find("nope.facet") != std::string::npos);
  CHECK(missing.error.find("No such file") != std::string::npos);

  const facet::ProjectLoadResult folder = facet::LoadProject(dir.path.string());
  INFO(folder.error);
  CHECK_FALSE(folder.ok());

  const facet::ProjectLoadResult empty = (WriteFile(dir / "empty.facet", ""), facet::LoadProject(dir / "empty.facet"));
  CHECK(empty.error.find("empty") != std::string::npos);

  Project p = MakeSmallProject();
  p.references.clear();  // a missing reference mesh warns too (tested with the references)
  Image second = p.images[0];
  second.id = p.NewId();
  second.path = "photos/missing.jpg";
  p.images.push_back(second);
  p.images[0].path = "photos/present.jpg";
  fs::create_directories(dir.path / "project" / "photos");
  WriteFile((dir.path / "project" / "photos" / "present.jpg").string(), "not really a jpeg");
  const std::string path = (dir.path / "project" / "p.facet").string();
  REQUIRE(facet::SaveProject(p, path) == "");
  const facet::ProjectLoadResult r = facet::LoadProject(path);
  INFO(r.error);
  REQUIRE(r.ok());
  CHECK(r.project == p);
  REQUIRE(r.warnings.size() == 1);
  CHECK(r.warnings[0].find("images[1]") != std::string::npos);
  CHECK(r.warnings[0].find("missing.jpg") != std::string::npos);

  // The project moved without its photos folder, the photo copied beside it: found by name,
  // its stored path replaced, and said so; everything else as saved.
  fs::create_directories(dir.path / "moved");
  const std::string moved = (dir.path / "moved" / "p.facet").string();
  REQUIRE(facet::SaveProject(p, moved) == "");
  WriteFile((dir.path / "moved" / "present.jpg").string(), "not really a jpeg");
  const facet::ProjectLoadResult found = facet::LoadProject(moved);
  INFO(found.error);
  REQUIRE(found.ok());
  Project expected = p;
  expected.images[0].path = "present.jpg";
  CHECK(found.project == expected);
  REQUIRE(found.warnings.size() == 2);
  CHECK(found.warnings[0].find("images[0]: photo not found at") != std::string::npos);
  CHECK(found.warnings[0].find("beside the project (save to keep the new path)") != std::string::npos);
  CHECK(found.warnings[1].find("images[1]: image file not found") != std::string::npos);
  CHECK(found.warnings[1].find("nor missing.jpg beside the project") != std::string::npos);
}

TEST_CASE("atomic save: missing folder, replacing a file, failures leave no trace") {
  const facet::testing::TempDir dir("project_io");
  const Project p = MakeFullProject();

  SUBCASE("a path in a missing folder fails and creates nothing") {
    const std::string error = facet::SaveProject(p, dir / "no/such/folder/p.facet");
    INFO(error);
    CHECK_FALSE(error.empty());
    CHECK(ListDir(dir.path).empty());
  }
  SUBCASE("saving over an existing file replaces it and keeps its permissions") {
    const std::string path = dir / "p.facet";
    WriteFile(path, "old contents");
    ::chmod(path.c_str(), 0640);
    REQUIRE(facet::SaveProject(p, path) == "");
    CHECK(facet::testing::ReadText(path) == facet::ProjectToJson(p));
    CHECK((fs::status(path).permissions() & fs::perms::all) ==
          (fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read));
    CHECK(ListDir(dir.path) == std::set<std::string>{"p.facet"});
  }
  SUBCASE("a new file gets the usual 0644, not mkstemp's 0600") {
    const std::string path = dir / "new.facet";
    REQUIRE(facet::SaveProject(p, path) == "");
    CHECK((fs::status(path).permissions() & fs::perms::all) ==
          (fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read | fs::perms::others_read));
  }
  SUBCASE("saving through a symlink replaces the file it points to and keeps the link") {
    fs::create_directory(dir.path / "real");
    const std::string target = dir / "real/p.facet";
    WriteFile(target, "old contents");
    fs::create_symlink(target, dir.path / "link.facet");
    REQUIRE(facet::SaveProject(p, dir / "link.facet") == "");
    CHECK(fs::is_symlink(dir.path / "link.facet"));
    CHECK(facet::testing::ReadText(target) == facet::ProjectToJson(p));
    CHECK(ListDir(dir.path / "real") == std::set<std::string>{"p.facet"});
  }
  SUBCASE("a target that is a folder fails; the folder stays and no temp file remains") {
    fs::create_directory(dir.path / "taken.facet");
    WriteFile(dir / "taken.facet/inside.txt", "keep me");
    const std::string error = facet::SaveProject(p, dir / "taken.facet");
    INFO(error);
    CHECK_FALSE(error.empty());
    CHECK(fs::is_directory(dir.path / "taken.facet"));
    CHECK(facet::testing::ReadText(dir / "taken.facet/inside.txt") == "keep me");
    CHECK(ListDir(dir.path) == std::set<std::string>{"taken.facet"});
  }
  SUBCASE("a write that fails midway leaves the old file intact and no temp file") {
    // Permissions do not stop root, but a file-size limit does: write() fails with EFBIG.
    const std::string path = dir / "p.facet";
    const std::string old_text = facet::ProjectToJson(MakeSmallProject());
    WriteFile(path, old_text);
    const std::string new_text = facet::ProjectToJson(p);
    REQUIRE(new_text.size() > 4 * old_text.size());
    rlimit saved{};
    REQUIRE(::getrlimit(RLIMIT_FSIZE, &saved) == 0);
    auto* old_handler = ::signal(SIGXFSZ, SIG_IGN);
    rlimit limited = saved;
    limited.rlim_cur = static_cast<rlim_t>(2 * old_text.size());
    REQUIRE(::setrlimit(RLIMIT_FSIZE, &limited) == 0);
    const std::string error = facet::WriteFileAtomically(path, new_text);
    ::setrlimit(RLIMIT_FSIZE, &saved);
    ::signal(SIGXFSZ, old_handler);
    INFO(error);
    CHECK(error.find("writing") != std::string::npos);
    CHECK(facet::testing::ReadText(path) == old_text);
    CHECK(ListDir(dir.path) == std::set<std::string>{"p.facet"});
  }
}

TEST_CASE("image paths resolve against the project file's folder") {
  CHECK(facet::ResolveImagePath("/a/b/p.facet", "img/x.jpg") == "/a/b/img/x.jpg");
  CHECK(facet::ResolveImagePath("/a/b/p.facet", "../c/./x.jpg") == "/a/c/x.jpg");
  CHECK(facet::ResolveImagePath("/a/b/p.facet", "/abs/dir/../x.jpg") == "/abs/x.jpg");
  CHECK(facet::ResolveImagePath("/a/b/p.facet", "/abs/x.jpg") == "/abs/x.jpg");
  CHECK(facet::ResolveImagePath("p.facet", "x.jpg") == "x.jpg");
  CHECK(facet::ResolveImagePath("rel/dir/p.facet", "x.jpg") == "rel/dir/x.jpg");

  CHECK(facet::RelativeImagePath("/a/b/p.facet", "/a/b/img/x.jpg") == "img/x.jpg");
  CHECK(facet::RelativeImagePath("/a/b/p.facet", "/a/c/x.jpg") == "../c/x.jpg");

  Project p = MakeFullProject();  // paths: photos/front.jpg, ../other/side view.png, /abs/top.JPG
  std::vector<std::string> before;
  for (const Image& im : p.images) before.push_back(facet::ResolveImagePath("/a/b/p.facet", im.path));
  facet::RebaseImagePaths("/a/b/p.facet", "/a/d/e/q.facet", &p);
  CHECK(p.images[0].path == "../../b/photos/front.jpg");
  CHECK(p.images[1].path == "../../other/side view.png");
  for (size_t i = 0; i < p.images.size(); ++i)
    CHECK(facet::ResolveImagePath("/a/d/e/q.facet", p.images[i].path) == before[i]);
}

TEST_CASE("operated meshes round-trip exactly, id holes, free vertices and constraints included") {
  const Project p = MakeFullProject();
  int with_holes = 0;
  for (const Primitive& prim : p.primitives)
    if (prim.mesh.VertexIdEnd() > static_cast<std::uint32_t>(prim.mesh.NumVertices())) ++with_holes;
  REQUIRE(with_holes == 6);
  REQUIRE(p.constraints.size() == 9);
  CheckRoundTrip(p);
  const facet::ProjectLoadResult r = facet::ProjectFromJson(facet::ProjectToJson(p));
  REQUIRE(r.ok());
  for (size_t i = 0; i < p.primitives.size(); ++i) {
    CAPTURE(i);
    const PolyMesh& a = p.primitives[i].mesh;
    const PolyMesh& b = r.project.primitives[i].mesh;
    CHECK(a.VertexIdEnd() == b.VertexIdEnd());
    CHECK(a.EdgeIdEnd() == b.EdgeIdEnd());
    CHECK(a.FaceIdEnd() == b.FaceIdEnd());
    for (facet::VertexId v = 0; v < a.VertexIdEnd(); ++v) CHECK(a.IsVertex(v) == b.IsVertex(v));
  }
  // The loaded meshes keep working: new ids continue after the holes, never reusing them.
  Project loaded = r.project;
  PolyMesh& mesh = loaded.primitives[32].mesh;
  const std::uint32_t end = mesh.VertexIdEnd();
  const facet::ESplitResult split = facet::ESplit(&mesh, mesh.EdgeIdEnd() - 1, 0.5);
  REQUIRE_MESSAGE(split.ok, split.message);
  CHECK(split.vertex == end);
  CHECK(facet::Validate(mesh).empty());
}

TEST_CASE("a mesh written as \"from_shape\" is the primitive's unedited mesh") {
  const Project p = MakeSmallProject();
  Json j = Json::parse(facet::ProjectToJson(p));
  j["primitives"][0]["mesh"] = "from_shape";
  const facet::ProjectLoadResult r = facet::ProjectFromJson(j.dump());
  INFO(r.error);
  REQUIRE(r.ok());
  CHECK(r.project == p);
}

// Fuzzing (tests/fuzz/fuzz_project): an id end is a number in the file, and the loader
// allocated that many records (holes are allowed) before reading any: the sample project with
// "vertex_id_end": 2^29, 8.5 KB, asked for 154 GB. The project's mesh ids are now bounded.
TEST_CASE("regression: a mesh's id ends are bounded over the whole project before allocation (fuzz_project)") {
  Json sample = Json::parse(facet::testing::ReadText(std::string(FACET_SOURCE_DIR) + "/assets/samples/leuven/leuven.facet"));
  REQUIRE(facet::ProjectFromJson(sample.dump()).ok());
  Json j = sample;
  j["primitives"][0]["mesh"]["vertex_id_end"] = 1 << 29;
  facet::ProjectLoadResult r = facet::ProjectFromJson(j.dump());
  CHECK_FALSE(r.ok());
  CHECK(r.error ==
        "primitives[0].mesh: the meshes' ids go past the limit of 1048576 (vertex, edge and face id ends, over all "
        "primitives)");
  CHECK(r.project == Project());

  // Holes within the bound still load and round-trip: 1,000 vertex ids for the box's 8.
  j = sample;
  j["primitives"][0]["mesh"]["vertex_id_end"] = 1000;
  r = facet::ProjectFromJson(j.dump());
  REQUIRE_MESSAGE(r.ok(), r.error);
  CHECK(r.project.primitives[0].mesh.VertexIdEnd() == 1000);
  CHECK(facet::ProjectFromJson(facet::ProjectToJson(r.project)).project == r.project);

  // The bound is over all primitives: each unedited cylinder of kMaxPrimitiveSides sides
  // ("from_shape") takes a few thousand ids; as many as fit load, one more does not.
  j = sample;
  Json cylinder = j["primitives"][0];
  cylinder["kind"] = "cylinder";
  cylinder["segments"] = facet::kMaxPrimitiveSides;
  cylinder["mesh"] = "from_shape";
  j["pins"] = Json::array();
  j["primitives"] = Json::array({cylinder});
  r = facet::ProjectFromJson(j.dump());
  REQUIRE_MESSAGE(r.ok(), r.error);
  const auto& mesh = r.project.primitives[0].mesh;
  const std::uint64_t ids_per_cylinder = std::uint64_t{mesh.VertexIdEnd()} + mesh.EdgeIdEnd() + mesh.FaceIdEnd();
  const std::uint64_t fitting = facet::kMaxProjectMeshIds / ids_per_cylinder;
  REQUIRE(fitting >= 1);
  auto add_cylinder = [&]() {
    cylinder["id"] = j["next_id"];
    j["next_id"] = j["next_id"].get<int>() + 1;
    j["primitives"].push_back(cylinder);
  };
  while (j["primitives"].size() < fitting) add_cylinder();
  r = facet::ProjectFromJson(j.dump());
  REQUIRE_MESSAGE(r.ok(), r.error);
  add_cylinder();
  r = facet::ProjectFromJson(j.dump());
  CHECK_FALSE(r.ok());
  CHECK_MESSAGE(r.error.rfind("primitives[" + std::to_string(fitting) + "].mesh: the meshes' ids go past the limit", 0) == 0,
                r.error);
}

TEST_CASE("a wedge's ridge along y round-trips; absent means x; a bad value names its path") {
  Project p;
  facet::Id box = facet::kNoId, roof = facet::kNoId;
  REQUIRE(facet::AddPrimitiveToProject(&p, facet::MakeBox(facet::kNoId, {2.0, 5.0, 1.5}), "box", &box, nullptr));
  facet::PrimitiveShape wedge = facet::MakeWedge(facet::kNoId, {1.0, 1.0, 0.8});
  wedge.ridge_along_y = true;
  REQUIRE(facet::AddPrimitiveToProject(&p, wedge, "roof", &roof, nullptr));
  p.FindPrimitive(roof)->attached_to = box;
  facet::RefreshAllPrimitives(&p);
  CheckRoundTrip(p);
  Json j = Json::parse(facet::ProjectToJson(p));
  CHECK(j["primitives"][1]["ridge"] == "y");
  CHECK_FALSE(j["primitives"][0].contains("ridge"));  // written for turned wedges only
  // Built from the shape, the ridge chooses the mesh: the same vertices where they were
  // (the texture coordinates differ: they follow the dimensions the mesh was built with).
  Json from_shape = j;
  from_shape["primitives"][1]["mesh"] = "from_shape";
  const facet::ProjectLoadResult built = facet::ProjectFromJson(from_shape.dump());
  REQUIRE(built.ok());
  const facet::Primitive& rebuilt = *built.project.FindPrimitive(roof);
  CHECK(rebuilt.shape == p.FindPrimitive(roof)->shape);
  for (facet::VertexId v = 0; v < 6; ++v) {
    CHECK((rebuilt.mesh.vertex(v).position - p.FindPrimitive(roof)->mesh.vertex(v).position).norm() < 1e-12);
  }
  // A file from before the ridge could turn: along x.
  Json old = j;
  old["primitives"][1].erase("ridge");
  old["primitives"][1]["mesh"] = "from_shape";
  const facet::ProjectLoadResult along_x = facet::ProjectFromJson(old.dump());
  REQUIRE(along_x.ok());
  CHECK_FALSE(along_x.project.FindPrimitive(roof)->shape.ridge_along_y);
  j["primitives"][1]["ridge"] = "z";
  CheckErrorNames(j.dump(), "primitives[1].ridge");
  j["primitives"][1]["ridge"] = "x";
  j["primitives"][0]["ridge"] = "y";
  CheckErrorNames(j.dump(), "primitives[0].ridge");
}

TEST_CASE("malformed mesh content is an error naming its JSON path") {
  const Project full = MakeFullProject();
  const Json base = Json::parse(facet::ProjectToJson(full));
  // The operated box (primitives[32]) has holes in its ids: find a dead half-edge id.
  const PolyMesh& mesh = full.primitives[32].mesh;
  facet::HalfedgeId dead = facet::kNoElement;
  for (facet::HalfedgeId h = 0; h < 2 * mesh.EdgeIdEnd() && dead == facet::kNoElement; ++h)
    if (!mesh.IsHalfedge(h)) dead = h;
  REQUIRE(dead != facet::kNoElement);
  facet::VertexId dead_vertex = facet::kNoElement;
  for (facet::VertexId v = 0; v < mesh.VertexIdEnd() && dead_vertex == facet::kNoElement; ++v)
    if (!mesh.IsVertex(v)) dead_vertex = v;
  REQUIRE(dead_vertex != facet::kNoElement);
  auto with = [&](const std::function<void(Json&)>& edit) {
    Json j = base;
    edit(j);
    return j.dump(1);
  };
  const std::string at = "primitives[32].mesh";
  SUBCASE("a link to a dead half-edge (dangling)") {
    CheckErrorNames(with([&](Json& j) { j["primitives"][32]["mesh"]["edges"][3]["halfedges"][0]["next"] = dead; }),
                    at + ": broken mesh: ");
  }
  SUBCASE("a link beyond the id space") {
    CheckErrorNames(with([&](Json& j) { j["primitives"][32]["mesh"]["edges"][3]["halfedges"][1]["prev"] = 100000; }),
                    at + ".edges[3].halfedges[1].prev: expected -1 or an id below");
  }
  SUBCASE("a face pointing at a dead half-edge") {
    CheckErrorNames(with([&](Json& j) { j["primitives"][32]["mesh"]["faces"][0]["halfedge"] = dead; }),
                    at + ": broken mesh: ");
  }
  SUBCASE("a duplicate vertex, edge or face id") {
    CheckErrorNames(with([&](Json& j) {
                      auto& v = j["primitives"][32]["mesh"]["vertices"];
                      v[4]["id"] = v[1]["id"];
                    }),
                    at + ".vertices[4].id: missing or duplicate vertex id");
    CheckErrorNames(with([&](Json& j) {
                      auto& e = j["primitives"][32]["mesh"]["edges"];
                      e[5]["id"] = e[2]["id"];
                    }),
                    at + ".edges[5].id: missing or duplicate edge id");
    CheckErrorNames(with([&](Json& j) {
                      auto& f = j["primitives"][32]["mesh"]["faces"];
                      f[3]["id"] = f[0]["id"];
                    }),
                    at + ".faces[3].id: missing or duplicate face id");
  }
  SUBCASE("a broken face loop (two next links swapped)") {
    CheckErrorNames(with([&](Json& j) {
                      auto& e = j["primitives"][32]["mesh"]["edges"];
                      std::swap(e[0]["halfedges"][0]["next"], e[4]["halfedges"][1]["next"]);
                    }),
                    at + ": broken mesh: ");
  }
  SUBCASE("a half-edge whose face disagrees with its loop") {
    CheckErrorNames(with([&](Json& j) {
                      auto& h = j["primitives"][32]["mesh"]["edges"][0]["halfedges"][0]["face"];
                      h = h.get<int>() == 0 ? 1 : 0;
                    }),
                    at + ": broken mesh: ");
  }
  SUBCASE("a pin or a constraint naming a vertex that is gone") {
    Json j = base;
    size_t pin_index = 0;
    for (; pin_index < full.pins.size(); ++pin_index)
      if (full.pins[pin_index].vertex.primitive_id == full.primitives[32].id) break;
    REQUIRE(pin_index < full.pins.size());
    j["pins"][pin_index]["vertex"] = dead_vertex;
    CheckErrorNames(j.dump(), "pins[" + std::to_string(pin_index) + "].vertex: refers to vertex " +
                                  std::to_string(dead_vertex) + ", which primitive " +
                                  std::to_string(full.primitives[32].id) + " does not have");
    CheckErrorNames(with([&](Json& j2) { j2["constraints"][4]["vertices"][1][1] = dead_vertex; }),
                    "constraints[4].vertices[1]: refers to vertex " + std::to_string(dead_vertex));
  }
  SUBCASE("a constraint with the wrong number of vertices") {
    CheckErrorNames(with([](Json& j) { j["constraints"][2]["vertices"].erase(3); }),
                    "constraints[2].vertices: a parallel constraint takes 4 vertices, found 3");
    CheckErrorNames(with([](Json& j) {
                      j["constraints"][0]["vertices"] = Json::array({{1, 0}, {1, 1}, {1, 2}});
                    }),
                    "constraints[0].vertices: a coplanar constraint takes 4 or more vertices, found 3");
    CheckErrorNames(
        with([](Json& j) { j["constraints"][6]["vertices"].push_back(j["constraints"][6]["vertices"][0]); }),
        "constraints[6].vertices: a fixed_point constraint takes 1 vertices, found 2");
  }
}

TEST_CASE("the version-1 fixture keeps loading: boxes become box primitives, corner pins vertex pins") {
  // tests/fixtures/project_v1.facet is frozen: never regenerate it. If it stops loading,
  // a migration step is missing.
  const std::string path = std::string(FACET_SOURCE_DIR) + "/tests/fixtures/project_v1.facet";
  const facet::ProjectLoadResult r = facet::LoadProject(path);
  INFO(r.error);
  REQUIRE(r.ok());
  const Project& p = r.project;
  CHECK(p.units == "m");
  CHECK(p.next_id == 12);
  REQUIRE(p.images.size() == 2);
  CHECK(p.images[0].id == 1);
  CHECK(p.images[0].path == "photos/facade.jpg");
  CHECK(p.images[0].width_px == 4032);
  CHECK(p.images[0].height_px == 3024);
  CHECK(p.images[0].camera.focal_px == 3105.25);
  CHECK(p.images[0].camera.principal_point_px == Eigen::Vector2d(2015.5, 1511.5));
  CHECK(p.images[0].camera.cam_from_world_rotation(1, 2) == -1.0);
  CHECK(p.images[0].camera.cam_from_world_translation == Eigen::Vector3d(0.5, 1.25, 12.0));
  CHECK(p.images[0].camera_calibrated);
  CHECK(p.images[0].principal_point_mode == PrincipalPointMode::kImageCenter);
  CHECK(p.images[1].principal_point_mode == PrincipalPointMode::kFixed);
  CHECK(p.images[1].fixed_principal_point_px == Eigen::Vector2d(960.0, 540.0));
  CHECK(p.images[1].pose_locked);
  CHECK_FALSE(p.images[1].camera_calibrated);
  // Version 1 never refined intrinsics in the solve.
  for (const Image& im : p.images) {
    CHECK(im.focal_locked);
    CHECK(im.principal_point_locked);
  }
  REQUIRE(p.segments.size() == 3);
  CHECK(p.segments[0].axis == Axis::kX);
  CHECK(p.segments[1].axis == Axis::kY);
  CHECK(p.segments[2].axis == Axis::kZ);
  CHECK(p.segments[2].b_px == Eigen::Vector2d(1800.0, 2900.75));
  REQUIRE(p.primitives.size() == 2);
  for (const Primitive& prim : p.primitives) {
    CHECK(prim.shape.kind == facet::PrimitiveKind::kBox);
    CHECK(prim.shape.id == prim.id);
    CHECK(prim.attached_to == facet::kNoId);
    CHECK(prim.mesh.NumVertices() == 8);
    CHECK(prim.mesh.NumEdges() == 12);
    CHECK(prim.mesh.NumFaces() == 6);
    CHECK(facet::Validate(prim.mesh).empty());
  }
  CHECK(p.primitives[0].id == 6);
  CHECK(p.primitives[0].name == "building");
  CHECK(p.primitives[0].shape.params == Eigen::Vector4d(12.0, 8.5, 6.25, 0.0));
  CHECK(p.primitives[0].param_locked == std::array<bool, 4>{false, false, true, false});
  CHECK(p.primitives[0].rotation_locked);
  CHECK(p.primitives[1].id == 7);
  CHECK(p.primitives[1].shape.rotation == Eigen::Vector3d(0.0, 0.0, 0.7853981633974483));
  CHECK(p.primitives[1].shape.translation == Eigen::Vector3d(12.0, 1.0, 0.0));
  CHECK_FALSE(p.primitives[1].rotation_locked);
  CHECK_FALSE(p.primitives[1].translation_locked);
  CHECK(p.constraints.empty());
  REQUIRE(p.pins.size() == 3);
  CHECK(p.pins[2].vertex == facet::VertexRef{7, 7});
  CHECK(p.pins[2].uv_px == Eigen::Vector2d(1234.5, 876.25));
  // Corner pins became vertex pins at the right world positions (core/mesh/box.h bit code:
  // corner c is (c & 1, c >> 1 & 1, c >> 2 & 1) * size, then the box's pose).
  constexpr double kPositionTolerance = 1e-12;  // a few roundings of ~10 m coordinates
  const double s = std::sqrt(0.5);
  const Eigen::Vector3d expected[3] = {
      Eigen::Vector3d(0.0, 0.0, 0.0),                                            // box 6, corner 0
      Eigen::Vector3d(12.0, 0.0, 6.25),                                          // box 6, corner 5
      Eigen::Vector3d(12.0 + s * 3.0 - s * 2.0, 1.0 + s * 3.0 + s * 2.0, 2.5)};  // box 7 (45 deg), corner 7
  for (int i = 0; i < 3; ++i) {
    CAPTURE(i);
    REQUIRE(p.FindVertex(p.pins[i].vertex) != nullptr);
    const double error = (facet::VertexInWorld(p, p.pins[i].vertex) - expected[i]).norm();
    CAPTURE(error);
    CHECK(error < kPositionTolerance);
  }
  // The photos are not in the repository: the project still opens, with warnings.
  CHECK(r.warnings.size() == 2);

  // Saving writes the current version, which loads back equal.
  const facet::testing::TempDir dir("project_io");
  const std::string saved = dir / "upgraded.facet";
  REQUIRE(facet::SaveProject(p, saved) == "");
  const Json j = Json::parse(facet::testing::ReadText(saved));
  CHECK(j["version"] == Project::kFormatVersion);
  // Through version 2 to 3: no texture choices.
  for (const facet::Image& image : p.images) CHECK(image.use_for_texture);
  for (const facet::Primitive& primitive : p.primitives) CHECK(primitive.face_textures.empty());
  CHECK_FALSE(j.contains("boxes"));
  CHECK(j["primitives"].size() == 2);
  CHECK(j["pins"][2]["vertex"] == 7);
  CHECK_FALSE(j["pins"][2].contains("corner"));
  const facet::ProjectLoadResult again = facet::LoadProject(saved);
  INFO(again.error);
  REQUIRE(again.ok());
  CHECK(again.project == p);
}

TEST_CASE("version-1 content errors still name their location") {
  Json j = Json::parse(facet::testing::ReadText(std::string(FACET_SOURCE_DIR) + "/tests/fixtures/project_v1.facet"));
  {
    Json bad = j;
    bad["pins"][1]["corner"] = 8;
    CheckErrorNames(bad.dump(), "corner must be an integer from 0 to 7, found 8");
  }
  {
    Json bad = j;
    bad["boxes"][0]["size"][1] = -2.0;
    CheckErrorNames(bad.dump(), "primitives[0].params[1]: a dimension cannot be negative");
  }
  {
    Json bad = j;
    bad["pins"][0]["box_id"] = 99;
    CheckErrorNames(bad.dump(), "pins[0].vertex: refers to a missing primitive 99");
  }
}

TEST_CASE("texture choices: version 2 files migrate to none; the current version keeps them exactly") {
  // The shipped Leuven sample is a version-2 file: it loads with every photo used for texture
  // and no face override, and saves as the current version that loads back equal.
  const std::string sample_path = std::string(FACET_SOURCE_DIR) + "/assets/samples/leuven/leuven.facet";
  const Json sample = Json::parse(facet::testing::ReadText(sample_path));
  REQUIRE(sample["version"] == 2);
  REQUIRE_FALSE(sample["images"][0].contains("use_for_texture"));
  const facet::ProjectLoadResult old = facet::LoadProject(sample_path);
  INFO(old.error);
  REQUIRE(old.ok());
  REQUIRE_FALSE(old.project.images.empty());
  for (const facet::Image& image : old.project.images) CHECK(image.use_for_texture);
  for (const facet::Primitive& primitive : old.project.primitives) CHECK(primitive.face_textures.empty());
  const Json upgraded = Json::parse(facet::ProjectToJson(old.project));
  CHECK(upgraded["version"] == Project::kFormatVersion);
  CHECK(upgraded["images"][0]["use_for_texture"] == true);
  CHECK(upgraded["primitives"][0]["face_textures"] == Json::array());
  CheckRoundTrip(old.project);

  // The full project written as version 2 (without the new fields) migrates to the same
  // project without its choices and references; with them (the current version) it is exact, the override whose face
  // and photo are gone included.
  const Project full = MakeFullProject();
  REQUIRE_FALSE(full.images[1].use_for_texture);
  REQUIRE(full.primitives[32].face_textures.size() == 2);
  Json v2 = Json::parse(facet::ProjectToJson(full));
  v2["version"] = 2;
  for (Json& image : v2["images"]) {
    image.erase("use_for_texture");
    image.erase("lens_group");
  }
  for (Json& primitive : v2["primitives"]) primitive.erase("face_textures");
  v2.erase("references");
  const facet::ProjectLoadResult migrated = facet::ProjectFromJson(v2.dump());
  INFO(migrated.error);
  REQUIRE(migrated.ok());
  CHECK(migrated.warnings.empty());
  Project without_choices = full;
  without_choices.references.clear();
  for (facet::Image& image : without_choices.images) {
    image.use_for_texture = true;
    image.lens_group = 0;
  }
  for (facet::Primitive& primitive : without_choices.primitives) primitive.face_textures.clear();
  CHECK(migrated.project == without_choices);
  CheckRoundTrip(full);
  // Normalised on the way in: excluded images ascending, a default entry removed.
  CHECK(full.primitives[32].face_textures[1].excluded_images ==
        std::vector<Id>{full.images[0].id, full.images[1].id});
  Project cleared = full;
  facet::SetFaceTextureOverride(&cleared.primitives[32], {0, facet::kNoId, {}});
  REQUIRE(cleared.primitives[32].face_textures.size() == 1);
  CHECK(cleared.primitives[32].face_textures[0].face == 2);
}

TEST_CASE("texture choices: malformed overrides are errors naming their path") {
  const Json base = Json::parse(facet::ProjectToJson(MakeFullProject()));
  auto with = [&](const std::function<void(Json&)>& edit) {
    Json j = base;
    edit(j);
    return j.dump();
  };
  const std::string at = "primitives[32].face_textures";
  CheckErrorNames(with([](Json& j) { std::swap(j["primitives"][32]["face_textures"][0], j["primitives"][32]["face_textures"][1]); }),
                  at + "[1].face: overrides must be ascending by face");
  CheckErrorNames(with([](Json& j) {
                    j["primitives"][32]["face_textures"][1]["excluded_images"] = {3, 2};
                  }),
                  at + "[1].excluded_images[1]: excluded images must be ascending");
  CheckErrorNames(with([](Json& j) {
                    j["primitives"][32]["face_textures"][1]["excluded_images"] = Json::array();
                  }),
                  at + "[1]: names neither a source image nor an excluded one");
  CheckErrorNames(with([](Json& j) { j["primitives"][32]["face_textures"][0]["source_image"] = -2; }),
                  at + "[0].source_image: expected an image id or 0");
  CheckErrorNames(with([](Json& j) { j["primitives"][32]["face_textures"][0]["excluded_images"] = {0}; }),
                  at + "[0].excluded_images[0]: expected a positive integer id");
  CheckErrorNames(with([](Json& j) { j["primitives"][32]["face_textures"][0].erase("face"); }),
                  at + "[0].face: missing field");
  CheckErrorNames(with([](Json& j) { j["images"][1]["use_for_texture"] = 0; }),
                  "images[1].use_for_texture: expected true or false");
}

TEST_CASE("lens groups: version 4 files migrate to a lens per photo; the current version keeps them exactly") {
  const Project full = MakeFullProject();
  REQUIRE(full.images[0].lens_group == 3);
  REQUIRE(full.images[1].lens_group == 0);
  const Json current = Json::parse(facet::ProjectToJson(full));
  CHECK(current["images"][0]["lens_group"] == 3);
  CheckRoundTrip(full);
  Json v4 = current;
  v4["version"] = 4;
  for (Json& image : v4["images"]) image.erase("lens_group");
  const facet::ProjectLoadResult migrated = facet::ProjectFromJson(v4.dump());
  INFO(migrated.error);
  REQUIRE(migrated.ok());
  Project own_lenses = full;
  for (facet::Image& image : own_lenses.images) image.lens_group = 0;
  CHECK(migrated.project == own_lenses);
  // The current version needs the field, a whole number >= 0.
  Json bad = current;
  bad["images"][1].erase("lens_group");
  CheckErrorNames(bad.dump(), "images[1].lens_group: missing field");
  bad["images"][1]["lens_group"] = -1;
  CheckErrorNames(bad.dump(), "images[1].lens_group");
  bad["images"][1]["lens_group"] = 1.5;
  CheckErrorNames(bad.dump(), "images[1].lens_group");
}

TEST_CASE("the version-2 fixture loads without references and saves as the current version") {
  // tests/fixtures/project_v2.facet is a frozen copy of the Leuven sample as version 2 wrote it.
  const std::string fixture = std::string(FACET_SOURCE_DIR) + "/tests/fixtures/project_v2.facet";
  REQUIRE(Json::parse(facet::testing::ReadText(fixture))["version"] == 2);
  const facet::ProjectLoadResult r = facet::LoadProject(fixture);
  INFO(r.error);
  REQUIRE(r.ok());
  CHECK(r.project.references.empty());
  CHECK(r.project.primitives.size() == 1);
  CHECK(r.project.images.size() == 1);
  const facet::testing::TempDir dir("project_io");
  REQUIRE(facet::SaveProject(r.project, dir / "upgraded.facet") == "");
  const Json j = Json::parse(facet::testing::ReadText(dir / "upgraded.facet"));
  CHECK(j["version"] == Project::kFormatVersion);
  CHECK(j["references"] == Json::array());
  const facet::ProjectLoadResult again = facet::LoadProject(dir / "upgraded.facet");
  REQUIRE(again.ok());
  CHECK(again.project == r.project);
}

TEST_CASE("references: round trip, bad fields named, a missing mesh file is a warning that loses nothing") {
  Project p = MakeSmallProject();
  CheckRoundTrip(p);
  const Json good = Json::parse(facet::ProjectToJson(p));
  CHECK(good["references"][0]["path"] == "site.obj");
  CHECK(good["references"][0]["axes"] == "y_up");
  Json bad = good;
  bad["references"][0]["axes"] = "x_up";
  CheckErrorNames(bad.dump(), "references[0].axes: expected \"y_up\" or \"z_up\"");
  bad = good;
  bad["references"][0]["path"] = "";
  CheckErrorNames(bad.dump(), "references[0].path");
  bad = good;
  bad["references"][0]["id"] = good["images"][0]["id"];
  CheckErrorNames(bad.dump(), "references[0].id: duplicate id");

  // Saved beside no mesh file: the load warns with the resolved path and keeps the reference;
  // saving again writes it unchanged.
  const facet::testing::TempDir dir("project_io");
  const std::string path = dir / "p.facet";
  REQUIRE(facet::SaveProject(p, path) == "");
  const facet::ProjectLoadResult loaded = facet::LoadProject(path);
  REQUIRE(loaded.ok());
  bool warned = false;
  for (const std::string& w : loaded.warnings)
    warned = warned || (w.find("references[0]: reference mesh not found: " + (dir / "site.obj")) == 0);
  CHECK(warned);
  CHECK(loaded.project == p);
  const std::string first = facet::testing::ReadText(path);
  REQUIRE(facet::SaveProject(loaded.project, path) == "");
  CHECK(facet::testing::ReadText(path) == first);

  // Save as into another folder keeps pointing at the same mesh file.
  facet::RebaseImagePaths(path, dir / "sub/q.facet", &p);
  CHECK(p.references[0].path == "../site.obj");
}

// Issue 25: a path that is not UTF-8 (a folder named in another encoding) aborted the process
// when saved (nlohmann's error 316). Paths are bytes: they round-trip exactly, as a string when
// UTF-8 and as {"bytes_hex": ...} otherwise; every other text stays UTF-8 (names are refused).
TEST_CASE("paths that are not UTF-8 round-trip exactly as their bytes") {
  Project p = MakeFullProject();
  p.images[0].path = "d\xff/m\xfe\xc3.jpg";                  // invalid bytes, a truncated sequence
  p.images[1].path = "photos/\xed\xa0\x80 surrogate.jpg";    // UTF-8 of a surrogate: not UTF-8
  p.images[2].path = "photos/caf\xc3\xa9 \xe2\x98\x83.jpg";  // valid UTF-8 stays a plain string
  p.references.at(0).path = "refs/\xc0\xaf overlong.obj";
  CheckRoundTrip(p);
  const Json doc = Json::parse(facet::ProjectToJson(p));
  CHECK(doc["images"][0]["path"] == Json{{"bytes_hex", "64ff2f6dfec32e6a7067"}});
  CHECK(doc["images"][1]["path"].is_object());
  CHECK(doc["images"][2]["path"] == "photos/caf\xc3\xa9 \xe2\x98\x83.jpg");
  CHECK(doc["references"][0]["path"].is_object());
  CHECK(facet::CheckProjectSavable(p).empty());

  const facet::testing::TempDir dir("project_io");
  const std::string path = dir / "p.facet";
  REQUIRE(facet::SaveProject(p, path).empty());
  const facet::ProjectLoadResult loaded = facet::LoadProject(path);
  REQUIRE_MESSAGE(loaded.ok(), loaded.error);
  CHECK(loaded.project == p);

  // The encoded form, malformed, is an error naming its path.
  for (const Json& bad :
       {Json{{"bytes_hex", "6g"}}, Json{{"bytes_hex", "6"}}, Json{{"bytes_hex", 5}}, Json{{"bytes_hex", "00"}},
        Json{{"hex", "61"}}, Json{{"bytes_hex", "61"}, {"x", 1}}, Json::array()}) {
    Json j = SmallJson();
    j["images"][0]["path"] = bad;
    CAPTURE(bad.dump());
    CheckErrorNames(j.dump(), "images[0].path");
  }
}

// Issue 25: numbers that are no camera entered through the project file (focal 1e-300 px was
// exported as yfov = pi, k1 = 1e308 sent the solve's camera 4,728 km away). Refused at open,
// naming the field, with the bounds of core/geometry/camera_checks.h.
TEST_CASE("numbers that are no camera are refused at open, naming the field") {
  const auto calibrated = [](double focal_px) {
    Json j = SmallJson();
    j["images"][0]["camera_calibrated"] = true;
    j["images"][0]["camera"]["focal_px"] = focal_px;
    return j.dump();
  };
  for (const double focal_px : {1e-300, 1.0, 1e6, 1e308}) {
    CAPTURE(focal_px);
    CheckErrorNames(calibrated(focal_px), "images[0].camera.focal_px: f = ");
  }
  // An uncalibrated camera's focal is only a start: no check, the solve replaces it.
  {
    Json j = SmallJson();
    j["images"][0]["camera"]["focal_px"] = 1e-300;
    CHECK(facet::ProjectFromJson(j.dump()).ok());
  }
  for (const double k1 : {1e308, -1e308, -5.0}) {
    Json j = SmallJson();
    j["images"][0]["camera"]["k1"] = k1;
    CAPTURE(k1);
    CheckErrorNames(j.dump(), "images[0].camera.k1: ");
  }
  {
    Json j = SmallJson();
    j["images"][0]["camera"]["k1"] = -0.01;  // a mild barrel distortion that does not fold this photo
    CHECK(facet::ProjectFromJson(j.dump()).ok());
  }
  for (const double fixed : {1e-300, 1e308}) {
    Json j = SmallJson();
    j["images"][0]["focal_mode"] = "fixed";
    j["images"][0]["fixed_focal_px"] = fixed;
    CheckErrorNames(j.dump(), "images[0].fixed_focal_px: f = ");
  }
  {
    Json j = SmallJson();
    j["images"][0]["focal_mode"] = "prior";
    j["images"][0]["focal_prior_px"] = 600.0;
    j["images"][0]["focal_prior_std_px"] = 1e-300;
    CheckErrorNames(j.dump(), "images[0].focal_prior_px: the prior's standard deviation");
  }
  {
    Json j = SmallJson();
    j["images"][0]["use_horizon"] = true;
    j["images"][0]["horizon_px"] = {0.0, 1e308, 639.0, 1e308};
    CheckErrorNames(j.dump(), "images[0].horizon_px: ");
  }
}

// Issue 25: a photo replaced by one of another size opened, solved and exported without a word
// (the texture silently halved). Open says so, as for a missing photo, and keeps everything.
TEST_CASE("LoadProject: a photo of another size than its image is a warning, nothing moves") {
  const facet::testing::TempDir dir("project_io");
  Project p = MakeSmallProject();
  p.references.clear();
  p.images[0].path = "photo.png";
  const std::string path = dir / "p.facet";
  REQUIRE(facet::SaveProject(p, path).empty());
  facet::ImageRgba8 half;
  half.width = p.images[0].width_px / 2;
  half.height = p.images[0].height_px / 2;
  half.pixels.assign(static_cast<size_t>(half.width) * half.height * 4, 128);
  REQUIRE(facet::WritePng(dir / "photo.png", half).empty());
  const facet::ProjectLoadResult r = facet::LoadProject(path);
  REQUIRE_MESSAGE(r.ok(), r.error);
  CHECK(r.project == p);  // pins, lines and camera as saved
  REQUIRE(r.warnings.size() == 1);
  CHECK(r.warnings[0].find("images[0]: ") == 0);
  CHECK(r.warnings[0].find("320 x 240 px, the image 640 x 480 px: not the same photo") != std::string::npos);

  facet::ImageRgba8 same = half;
  same.width = p.images[0].width_px;
  same.height = p.images[0].height_px;
  same.pixels.assign(static_cast<size_t>(same.width) * same.height * 4, 128);
  REQUIRE(facet::WritePng(dir / "photo.png", same).empty());
  CHECK(facet::LoadProject(path).warnings.empty());
}
