// The constraint builder in the real application offscreen (`facet render` with an input
// script): a new box's x edge is selected, a known length of 2.5 typed and added, then an
// along-x constraint; the project is saved, one constraint removed with its row's button,
// and the last edit undone. A first run reads where the builder's buttons are drawn (the
// render report's item rectangles); the second clicks them.
#include <doctest/doctest.h>

#include <cmath>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "core/io/project_io.h"
#include "core/mesh/primitives.h"
#include "tests/app/app_test_util.h"

using namespace facet::testing;

namespace {

constexpr double kLength = 2.5;               // typed into the known-length field
constexpr double kLengthRelTolerance = 1e-6;  // the joint solve's constraint tolerance
constexpr double kAxisTolerance = 1e-9;       // a box edge stays axis-aligned exactly

// An edge of a box whose endpoints differ only in x.
facet::EdgeId XEdge(const facet::PolyMesh& mesh) {
  for (facet::EdgeId e = 0; e < mesh.EdgeIdEnd(); ++e) {
    if (!mesh.IsEdge(e)) continue;
    const Eigen::Vector3d d = mesh.vertex(mesh.Dest(2 * e)).position - mesh.vertex(mesh.Origin(2 * e)).position;
    if (std::abs(d.x()) > 0.5 && std::abs(d.y()) < 1e-12 && std::abs(d.z()) < 1e-12) return e;
  }
  return facet::kNoElement;
}

double EdgeLength(const facet::Primitive& p, facet::EdgeId e) {
  return (p.mesh.vertex(p.mesh.Dest(2 * e)).position - p.mesh.vertex(p.mesh.Origin(2 * e)).position).norm();
}

}  // namespace

TEST_CASE("constraint builder: known length and along-axis on a box edge, saved, solved, removed, undone") {
  TempDir dir("constraints_ui");
  facet::Project empty;
  const facet::Id box_id = empty.next_id;
  const std::string project_path = dir / "empty.facet";
  REQUIRE(facet::SaveProject(empty, project_path) == "");

  facet::Project scratch;
  facet::Id scratch_id = facet::kNoId;
  std::string message;
  REQUIRE(facet::AddPrimitiveToProject(&scratch, facet::MakeBox(facet::kNoId, Eigen::Vector3d::Ones()), "b",
                                       &scratch_id, &message));
  const facet::PolyMesh& scratch_mesh = scratch.FindPrimitive(scratch_id)->mesh;
  const facet::EdgeId edge = XEdge(scratch_mesh);
  REQUIRE(edge != facet::kNoElement);
  const facet::VertexId va = scratch_mesh.Origin(2 * edge), vb = scratch_mesh.Dest(2 * edge);
  // The start is not the answer: the new box's edge is 1 long.
  REQUIRE(std::abs(EdgeLength(*scratch.FindPrimitive(scratch_id), edge) - kLength) > 0.1);

  std::ostringstream setup;
  setup << "frames 2\ncommand add box\nframes 1\ncommand tool select\nframes 1\n";
  setup << "command select edge " << box_id << " " << edge << "\nframes 3\n";
  // The builder sits below the primitive's fields: scroll the properties panel to its end.
  setup << "wheel -30 1450 400\nframes 3\n";
  const nlohmann::json items = RenderScript(dir, project_path, "probe", setup.str()).at("items");
  INFO("items: " << items.dump());
  REQUIRE(items.contains("constraint.length_value"));
  REQUIRE(items.contains("constraint.length"));
  REQUIRE(items.contains("constraint.along_x"));

  // Each click is aimed with the rectangles of a run that stops just before it: the solve
  // figures above the builder grow after the first constraint.
  std::ostringstream s;
  s << setup.str();
  s << "click left " << ItemCenter(items, "constraint.length_value") << "\nframes 1\nkey ctrl+a\nframes 1\ntype "
    << kLength << "\nframes 1\n";
  s << "click left " << ItemCenter(items, "constraint.length") << "\nframes 3\n";
  s << "wheel -30 1450 400\nframes 3\n";
  const nlohmann::json items2 = RenderScript(dir, project_path, "probe2", s.str()).at("items");
  REQUIRE(items2.contains("constraint.along_x"));
  s << "click left " << ItemCenter(items2, "constraint.along_x") << "\nframes 2\n";
  s << "command save " << (dir / "after.facet") << "\nframes 2\n";
  const nlohmann::json report = RenderScript(dir, project_path, "script", s.str());
  INFO("log: " << report.at("log").dump());

  const facet::ProjectLoadResult after = facet::LoadProject(dir / "after.facet");
  REQUIRE(after.ok());
  REQUIRE(after.project.constraints.size() == 2);
  const facet::Constraint& length = after.project.constraints[0];
  const facet::Constraint& along = after.project.constraints[1];
  CHECK(length.kind == facet::ConstraintKind::kDistance);
  CHECK(length.value == kLength);
  REQUIRE(length.vertices.size() == 2);
  CHECK(length.vertices[0] == facet::VertexRef{box_id, va});
  CHECK(length.vertices[1] == facet::VertexRef{box_id, vb});
  CHECK(along.kind == facet::ConstraintKind::kAlongAxis);
  CHECK(along.axis == facet::Axis::kX);
  CHECK(along.vertices == length.vertices);

  // The re-solve made the edge 2.5 long and kept it along x.
  REQUIRE(after.project.primitives.size() == 1);
  const facet::Primitive& box = after.project.primitives[0];
  const double solved = EdgeLength(box, edge);
  CAPTURE(solved);
  CHECK(std::abs(solved - kLength) <= kLengthRelTolerance * kLength);
  const Eigen::Vector3d d = box.mesh.vertex(vb).position - box.mesh.vertex(va).position;
  CAPTURE(d.transpose());
  CHECK(std::abs(d.y()) < kAxisTolerance * kLength);
  CHECK(std::abs(d.z()) < kAxisTolerance * kLength);

  // The history: add, known length, along x; then undo removes the last constraint and the
  // first row's remove button the known length (each reported as a project).
  const nlohmann::json& undo = report.at("undo_stack");
  REQUIRE(undo.size() == 3);
  CHECK(undo[1].dump().find("Known length") != std::string::npos);
  CHECK(undo[2].dump().find("Along x") != std::string::npos);
  std::ostringstream s2;
  s2 << s.str() << "command undo\nframes 2\ncommand save " << (dir / "undone.facet") << "\nframes 2\n";
  const nlohmann::json undone_items = RenderScript(dir, project_path, "script2", s2.str()).at("items");
  REQUIRE(undone_items.contains("constraint.remove.0"));

  std::ostringstream s3;
  s3 << s2.str() << "click left " << ItemCenter(undone_items, "constraint.remove.0") << "\nframes 2\n";
  const nlohmann::json report2 = RenderScript(dir, project_path, "script3", s3.str());
  INFO("log 3: " << report2.at("log").dump());
  const facet::ProjectLoadResult undone = facet::LoadProject(dir / "undone.facet");
  REQUIRE(undone.ok());
  REQUIRE(undone.project.constraints.size() == 1);
  CHECK(undone.project.constraints[0].kind == facet::ConstraintKind::kDistance);
  const facet::ProjectLoadResult removed = facet::ProjectFromJson(report2.at("project").dump());
  REQUIRE(removed.ok());
  CHECK(removed.project.constraints.empty());
  CHECK(report2.at("undo_stack").back().dump().find("Remove constraint") != std::string::npos);
}

TEST_CASE("constrain script command: two-edge parallel and a fixed point, saved with the right vertices") {
  TempDir dir("constraints_cmd");
  facet::Project empty;
  const facet::Id box_id = empty.next_id;
  const std::string project_path = dir / "empty.facet";
  REQUIRE(facet::SaveProject(empty, project_path) == "");
  // A box's edges 0 and 1 (core/mesh/box.h order: both along x) and its vertex 0.
  std::ostringstream s;
  s << "frames 2\ncommand add box\nframes 1\ncommand tool select\nframes 1\n";
  s << "command select edge " << box_id << " 0\nframes 1\ncommand constrain parallel\nframes 1\n";
  s << "command select edge " << box_id << " 1\nframes 1\ncommand constrain parallel\nframes 2\n";
  s << "command select vertex " << box_id << " 0\nframes 1\ncommand constrain fix\nframes 2\n";
  s << "command save " << (dir / "after.facet") << "\nframes 1\n";
  RenderScript(dir, project_path, "script", s.str());
  const facet::ProjectLoadResult after = facet::LoadProject(dir / "after.facet");
  REQUIRE(after.ok());
  REQUIRE(after.project.constraints.size() == 2);
  const facet::Constraint& parallel = after.project.constraints[0];
  CHECK(parallel.kind == facet::ConstraintKind::kParallel);
  REQUIRE(parallel.vertices.size() == 4);
  const facet::PolyMesh& mesh = after.project.primitives.at(0).mesh;
  CHECK(parallel.vertices[0] == facet::VertexRef{box_id, mesh.Origin(0)});
  CHECK(parallel.vertices[1] == facet::VertexRef{box_id, mesh.Dest(0)});
  CHECK(parallel.vertices[2] == facet::VertexRef{box_id, mesh.Origin(2)});
  CHECK(parallel.vertices[3] == facet::VertexRef{box_id, mesh.Dest(2)});
  const facet::Constraint& fixed = after.project.constraints[1];
  CHECK(fixed.kind == facet::ConstraintKind::kFixedPoint);
  REQUIRE(fixed.vertices.size() == 1);
  CHECK(fixed.vertices[0] == facet::VertexRef{box_id, 0});
  CHECK((fixed.point - mesh.vertex(0).position).norm() < 1e-12);
}
