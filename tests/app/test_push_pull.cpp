// Push/pull in the real application offscreen (`facet render` with an input script): a new
// box's top face is selected, the Push/pull tool chosen by its shortcut (U), a distance typed
// into the focused field and Enter pressed. The project saved before and after, and the
// report after an undo, are checked: the topology counts, the moved face and the history.
#include <doctest/doctest.h>

#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/io/project_io.h"
#include "core/mesh/primitives.h"
#include "tests/app/app_test_util.h"

using namespace facet::testing;

namespace {

constexpr double kPositionTolerance = 1e-9;  // noise-free: the core moves vertices exactly
constexpr double kDistance = 0.25;           // typed into the field; the default would be 0.1

// The id of the face of a box whose vertices all lie at its largest z (its top).
facet::FaceId TopFace(const facet::PolyMesh& mesh) {
  double top_z = -1e300;
  for (facet::VertexId v = 0; v < mesh.VertexIdEnd(); ++v) {
    if (mesh.IsVertex(v)) top_z = std::max(top_z, mesh.vertex(v).position.z());
  }
  for (facet::FaceId f = 0; f < mesh.FaceIdEnd(); ++f) {
    if (!mesh.IsFace(f)) continue;
    bool all_top = true;
    for (facet::VertexId v : facet::FaceVertices(mesh, f))
      all_top &= std::abs(mesh.vertex(v).position.z() - top_z) < 1e-12;
    if (all_top) return f;
  }
  return facet::kNoFace;
}

}  // namespace

TEST_CASE("push/pull: a box's top face extruded by a typed distance, one undoable edit") {
  TempDir dir("push_pull");
  facet::Project empty;
  const facet::Id box_id = empty.next_id;  // the id the script's new box gets
  const std::string project_path = dir / "empty.facet";
  REQUIRE(facet::SaveProject(empty, project_path) == "");

  // The top face's id: the box's topology does not depend on its size or pose.
  facet::Project scratch;
  facet::Id scratch_id = facet::kNoId;
  std::string message;
  REQUIRE(facet::AddPrimitiveToProject(&scratch, facet::MakeBox(facet::kNoId, Eigen::Vector3d::Ones()), "b",
                                       &scratch_id, &message));
  const facet::FaceId top = TopFace(scratch.FindPrimitive(scratch_id)->mesh);
  REQUIRE(top != facet::kNoFace);

  std::ostringstream s;
  s << "frames 2\ncommand add box\nframes 1\n";
  s << "command select face " << box_id << " " << top << "\nframes 1\n";
  s << "command save " << (dir / "before.facet") << "\nframes 1\n";
  s << "key u\nframes 3\ntype " << kDistance << "\nframes 1\nkey enter\nframes 2\n";
  s << "command save " << (dir / "after.facet") << "\nframes 1\n";
  s << "command undo\nframes 2\n";
  WriteText(dir / "script.txt", s.str());
  const RunResult run = RunRender(dir, "'" + project_path + "' -o '" + (dir / "out.png") + "' --script '" +
                                           (dir / "script.txt") + "' --report '" + (dir / "report.json") + "'");
  INFO("stderr: " << run.stderr_text);
  REQUIRE(run.exit_code == 0);
  const nlohmann::json report = ReadJson(dir / "report.json");
  INFO("log: " << report.at("log").dump());

  const facet::ProjectLoadResult before = facet::LoadProject(dir / "before.facet");
  const facet::ProjectLoadResult after = facet::LoadProject(dir / "after.facet");
  REQUIRE(before.ok());
  REQUIRE(after.ok());
  REQUIRE(before.project.primitives.size() == 1);
  REQUIRE(after.project.primitives.size() == 1);
  const facet::PolyMesh& mesh0 = before.project.primitives[0].mesh;
  const facet::PolyMesh& mesh1 = after.project.primitives[0].mesh;
  REQUIRE(TopFace(mesh0) == top);

  CHECK(mesh1.NumVertices() == mesh0.NumVertices() + 4);
  CHECK(mesh1.NumEdges() == mesh0.NumEdges() + 8);
  CHECK(mesh1.NumFaces() == mesh0.NumFaces() + 4);

  // Each of the top face's corners, in order, now sits kDistance above where it was.
  const std::vector<facet::VertexId> old_corners = facet::FaceVertices(mesh0, top);
  REQUIRE(mesh1.IsFace(top));
  const std::vector<facet::VertexId> new_corners = facet::FaceVertices(mesh1, top);
  REQUIRE(new_corners.size() == old_corners.size());
  for (const facet::VertexId w : new_corners) {
    const Eigen::Vector3d moved = mesh1.vertex(w).position;
    double best = 1e300;
    for (const facet::VertexId v : old_corners) {
      best = std::min(best, (moved - (mesh0.vertex(v).position + Eigen::Vector3d(0, 0, kDistance))).norm());
    }
    CAPTURE(w);
    CAPTURE(best);
    CHECK(best < kPositionTolerance);
  }

  // The history names the edit; the undo (the last step) restores the counts.
  CHECK(report.at("undo_stack").size() == 1);  // "Add box": selecting and saving are not edits
  const nlohmann::json& redo = report.at("redo_stack");
  REQUIRE(redo.size() == 1);
  CHECK(redo.back().dump().find("Push/pull face") != std::string::npos);
  const facet::ProjectLoadResult undone = facet::ProjectFromJson(report.at("project").dump());
  REQUIRE(undone.ok());
  REQUIRE(undone.project.primitives.size() == 1);
  const facet::PolyMesh& mesh2 = undone.project.primitives[0].mesh;
  CHECK(mesh2.NumVertices() == mesh0.NumVertices());
  CHECK(mesh2.NumEdges() == mesh0.NumEdges());
  CHECK(mesh2.NumFaces() == mesh0.NumFaces());
}
