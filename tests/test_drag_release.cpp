// A drag ends as the app ends it (app/state/app_state.cpp, EndDrag): the commit update
// (CommitUpdateOptions) runs on the last preview state, which the per-frame updates
// (DragFrameUpdateOptions, a few warm iterations each) left short of convergence. The release
// must reach what the same edit reaches from the project before the drag (the state a user
// would get by typing the final value): the same cost, the same model within the solver's
// tolerance, and never a refusal. Covered for the three drags of the image panel: a vertex
// pin, a line segment (the camera's calibration moves) and a line pin's end (a hard
// constraint that the previews hold only approximately).
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "core/scene/project.h"
#include "core/solve/model_update.h"
#include "tests/synthetic_scene.h"

namespace facet {
namespace {

using testing::MakeBoxScene;
using testing::SyntheticScene;

std::string Messages(const ModelUpdateSummary& summary) {
  std::string out = "solve: " + summary.solve.message + "; joint: " + summary.joint.message;
  for (const auto& m : summary.messages) out += "; " + m;
  return out;
}

// Largest difference between two solved projects' cameras (centre, relative to the scene
// size; rotation in rad; focal relative) and box corners (relative to the scene size).
double StateDifference(const Project& a, const Project& b) {
  double scale = 0.0;
  for (const Primitive& p : a.primitives) scale = std::max(scale, p.shape.params.head<3>().norm());
  double worst = 0.0;
  for (size_t i = 0; i < a.images.size(); ++i) {
    const Camera& ca = a.images[i].camera;
    const Camera& cb = b.images[i].camera;
    worst = std::max(worst, (ca.CenterInWorld() - cb.CenterInWorld()).norm() / scale);
    worst = std::max(worst, Eigen::AngleAxisd(ca.cam_from_world_rotation * cb.cam_from_world_rotation.transpose()).angle());
    worst = std::max(worst, std::abs(ca.focal_px / cb.focal_px - 1.0));
  }
  for (size_t p = 0; p < a.primitives.size(); ++p) {
    const PolyMesh& ma = a.primitives[p].mesh;
    const PolyMesh& mb = b.primitives[p].mesh;
    for (VertexId v = 0; v < ma.VertexIdEnd(); ++v) {
      if (ma.IsVertex(v)) worst = std::max(worst, (ma.vertex(v).position - mb.vertex(v).position).norm() / scale);
    }
  }
  return worst;
}

// One drag: `edit(project, t)` sets the dragged value at fraction t of the way; `frames`
// preview updates, then the release. Checks the release against the cold commit of the
// final edit on the pre-drag project.
template <typename Edit>
void CheckReleaseFromPreview(const Project& before, int frames, const Edit& edit, const std::string& what) {
  CAPTURE(what);
  ModelUpdateCache cache;
  Project preview = before;
  for (int f = 1; f <= frames; ++f) {
    Project edited = preview;
    edit(&edited, static_cast<double>(f) / frames);
    Project updated;
    UpdateModel(edited, DragFrameUpdateOptions(), &updated, &cache);
    preview = std::move(updated);
  }
  Project released;
  const ModelUpdateSummary release = UpdateModel(preview, CommitUpdateOptions(), &released, &cache);
  Project edited = before;
  edit(&edited, 1.0);
  Project cold;
  const ModelUpdateSummary direct = UpdateModel(edited, CommitUpdateOptions(), &cold);
  INFO("release: " << Messages(release));
  INFO("direct: " << Messages(direct));
  REQUIRE(direct.ok);
  REQUIRE(direct.joint.IsUsable());
  CHECK(release.ok);
  // No refusal or warning; a pin left far from where the other pins put its vertex is named
  // (the robust commit flags it), and that is the only message allowed.
  for (const std::string& message : release.messages) {
    CAPTURE(message);
    CHECK(message.rfind("Joint solve: pin ", 0) == 0);
    CHECK(message.find(" px from where the model puts it") != std::string::npos);
  }
  REQUIRE(release.joint.IsUsable());
  const double difference = StateDifference(released, cold);
  MESSAGE(what << ": release from the preview: cost " << release.joint.final_cost << " px^2, RMS "
               << release.joint.reprojection_rms_px << " px; from before the drag: cost " << direct.joint.final_cost
               << " px^2; state difference " << difference);
  // Both ends are converged solves of the same problem: the costs agree to the solver's
  // relative tolerance, the states to what that cost difference allows.
  CHECK(std::abs(release.joint.final_cost - direct.joint.final_cost) <=
        1e-7 * direct.joint.final_cost + 1e-12);
  CHECK(difference < 1e-6);
}

// The synthetic box with 0.5 px noise on pins and segments (a cost to compare), solved.
Project SolvedScene(SyntheticScene* scene) {
  Project solved;
  const ModelUpdateSummary summary = UpdateModel(scene->project, CommitUpdateOptions(), &solved);
  INFO(Messages(summary));
  REQUIRE(summary.ok);
  return solved;
}

TEST_CASE("drag release from the preview: a vertex pin dragged 25 px reaches the cold commit") {
  testing::SyntheticSceneOptions options;
  options.noise_px = 0.5;
  SyntheticScene scene = MakeBoxScene(options);
  const Project before = SolvedScene(&scene);
  const Id pin_id = before.pins[6].id;
  const Eigen::Vector2d start = before.pins[6].uv_px;
  CheckReleaseFromPreview(before, 10, [&](Project* p, double t) {
    p->FindPin(pin_id)->uv_px = start + t * Eigen::Vector2d(25.0, -15.0);
  }, "vertex pin");
}

TEST_CASE("drag release from the preview: a segment moved 12 px reaches the cold commit") {
  testing::SyntheticSceneOptions options;
  options.noise_px = 0.5;
  SyntheticScene scene = MakeBoxScene(options);
  const Project before = SolvedScene(&scene);
  const Id segment_id = before.segments[1].id;
  const Segment start = before.segments[1];
  CheckReleaseFromPreview(before, 8, [&](Project* p, double t) {
    Segment* s = p->FindSegment(segment_id);
    s->a_px = start.a_px + t * Eigen::Vector2d(12.0, 4.0);
    s->b_px = start.b_px + t * Eigen::Vector2d(12.0, 4.0);
  }, "segment");
}

TEST_CASE("drag release from the preview: a line pin's end dragged reaches the cold commit") {
  SyntheticScene scene = MakeBoxScene();
  Project& p = scene.project;
  // The top corners free to follow the line pin (as tests/app's line-pin scene).
  std::erase_if(p.pins, [](const Pin& pin) { return pin.vertex.vertex >= 4; });
  const Camera& cam = scene.true_camera;
  const Eigen::Vector2d p4 = cam.Project(scene.true_box.mesh.vertex(4).position);
  const Eigen::Vector2d p5 = cam.Project(scene.true_box.mesh.vertex(5).position);
  const Eigen::Vector2d d = (p5 - p4).normalized();
  const Eigen::Vector2d n(-d.y(), d.x());
  Constraint line_pin;
  line_pin.id = p.NewId();
  line_pin.kind = ConstraintKind::kEdgeOnImageLine;
  line_pin.vertices = {{scene.box_id, 4}, {scene.box_id, 5}};
  line_pin.image_id = scene.image_id;
  line_pin.line_a_px = p4 + 0.1 * (p5 - p4) + 3.0 * n;
  line_pin.line_b_px = p4 + 0.9 * (p5 - p4) + 3.0 * n + Eigen::Vector2d(0.0, 6.0);
  p.constraints.push_back(line_pin);
  const Project before = SolvedScene(&scene);
  const Eigen::Vector2d b_start = line_pin.line_b_px;
  CheckReleaseFromPreview(before, 6, [&](Project* q, double t) {
    q->FindConstraint(line_pin.id)->line_b_px = b_start - t * Eigen::Vector2d(0.0, 6.0);
  }, "line pin end");
}

}  // namespace
}  // namespace facet
