// V_op (core/solve/vertex_move.h): a dragged vertex reaches its target by the smallest change of its
// primitive. Checked on a box, wedge, pyramid, cylinder, a split vertex and a free vertex:
// the target reached to 1e-12, the step optimal (KKT: the objective's gradient lies in the
// span of the dragged vertex's constraint rows, with the Jacobians measured independently by
// finite differences of the world positions, exact since they are linear), locks respected,
// refusals, attached primitives, MovePrimitive, and that the model update starts from the
// moved state (an undetermined depth keeps the dragged value).
#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "core/mesh/operators.h"
#include "core/solve/model_update.h"
#include "core/solve/vertex_move.h"
#include "tests/synthetic_scene.h"

using namespace facet;

namespace {

constexpr double kReachTolerance = 1e-12;  // noise-free: the move is exact when reachable
constexpr double kKktTolerance = 1e-9;     // optimality residual, relative
constexpr double kUnchangedTolerance = 1e-15;

struct Single {
  Project project;
  Id id = kNoId;
  Primitive& primitive() { return *project.FindPrimitive(id); }
};

Single MakeSingle(const PrimitiveShape& shape, bool translation_locked) {
  Single s;
  std::string message;
  REQUIRE(AddPrimitiveToProject(&s.project, shape, "p", &s.id, &message));
  s.primitive().translation_locked = translation_locked;
  s.primitive().shape.rotation = Eigen::Vector3d(0.1, -0.2, 0.3);  // a general pose
  s.primitive().shape.translation = Eigen::Vector3d(0.5, -1.0, 0.25);
  RefreshAllPrimitives(&s.project);
  return s;
}

VertexId HighestVertex(const PolyMesh& mesh, const Eigen::Matrix3d& world_from_primitive) {
  VertexId best = kNoElement;
  double best_z = -1e300;
  for (VertexId v = 0; v < mesh.VertexIdEnd(); ++v) {
    if (!mesh.IsVertex(v)) continue;
    const double z = (world_from_primitive.transpose() * mesh.vertex(v).position).z();
    if (z > best_z + 1e-9) {
      best_z = z;
      best = v;
    }
  }
  return best;
}

// The unknowns the locks leave free, in the order params (unlocked, < count, >= 2 when
// attached), then translation x, y, z.
std::vector<int> FreeUnknowns(const Primitive& p) {
  std::vector<int> u;
  const bool attached = p.attached_to != kNoId;
  for (int k = 0; k < ShapeParamCount(p.shape.kind); ++k) {
    if (!p.param_locked[k] && !(attached && k < 2)) u.push_back(k);
  }
  if (!p.translation_locked && !attached) {
    for (int j = 0; j < 3; ++j) u.push_back(4 + j);
  }
  return u;
}

Eigen::VectorXd Pack(const PrimitiveShape& shape, const std::vector<int>& unknowns) {
  Eigen::VectorXd x(unknowns.size());
  for (size_t i = 0; i < unknowns.size(); ++i) {
    x(i) = unknowns[i] < 4 ? shape.params[unknowns[i]] : shape.translation[unknowns[i] - 4];
  }
  return x;
}

// d(world position of every live vertex) / d(unknowns), by unit finite differences of the
// primitive's own position update (exact: positions are linear in the unknowns).
std::vector<Eigen::MatrixXd> MeasureJacobians(const Primitive& p, const std::vector<int>& unknowns) {
  std::vector<Eigen::MatrixXd> jacobians(p.mesh.VertexIdEnd(), Eigen::MatrixXd::Zero(3, unknowns.size()));
  for (size_t i = 0; i < unknowns.size(); ++i) {
    PrimitiveShape shifted = p.shape;
    if (unknowns[i] < 4) {
      shifted.params[unknowns[i]] += 1.0;
    } else {
      shifted.translation[unknowns[i] - 4] += 1.0;
    }
    PolyMesh mesh = p.mesh;
    UpdatePrimitivePositions(&mesh, shifted);
    for (VertexId v = 0; v < mesh.VertexIdEnd(); ++v) {
      if (mesh.IsVertex(v)) jacobians[v].col(i) = mesh.vertex(v).position - p.mesh.vertex(v).position;
    }
  }
  return jacobians;
}

// KKT of  min sum_{i != d} |A_i dx|^2  s.t.  A_d dx = b: the gradient H dx lies in the row
// span of A_d. Returns the relative residual of its projection.
double KktResidual(const Primitive& before, const Primitive& after, VertexId dragged) {
  const std::vector<int> unknowns = FreeUnknowns(before);
  const std::vector<Eigen::MatrixXd> a = MeasureJacobians(before, unknowns);
  const Eigen::VectorXd dx = Pack(after.shape, unknowns) - Pack(before.shape, unknowns);
  const int n = static_cast<int>(unknowns.size());
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(n, n);
  for (VertexId v = 0; v < before.mesh.VertexIdEnd(); ++v) {
    if (v != dragged && before.mesh.IsVertex(v)) h += a[v].transpose() * a[v];
  }
  const Eigen::VectorXd gradient = h * dx;
  const Eigen::MatrixXd rows_t = a[dragged].transpose();  // n x 3
  const Eigen::VectorXd lambda = rows_t.completeOrthogonalDecomposition().solve(gradient);
  return (rows_t * lambda - gradient).norm() / std::max(1.0, h.norm() * dx.norm());
}

// Feasible perturbations (keeping the dragged vertex at the target) never lower the objective.
void CheckNoBetterNeighbour(const Primitive& before, const Primitive& after, VertexId dragged) {
  const std::vector<int> unknowns = FreeUnknowns(before);
  const std::vector<Eigen::MatrixXd> a = MeasureJacobians(before, unknowns);
  const Eigen::VectorXd dx = Pack(after.shape, unknowns) - Pack(before.shape, unknowns);
  Eigen::FullPivLU<Eigen::MatrixXd> lu(a[dragged]);
  const Eigen::MatrixXd kernel = lu.kernel();
  if (lu.rank() == static_cast<int>(unknowns.size())) return;
  auto objective = [&](const Eigen::VectorXd& step) {
    double sum = 0.0;
    for (VertexId v = 0; v < before.mesh.VertexIdEnd(); ++v) {
      if (v != dragged && before.mesh.IsVertex(v)) sum += (a[v] * step).squaredNorm();
    }
    return sum;
  };
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  const double best = objective(dx);
  for (int trial = 0; trial < 50; ++trial) {
    Eigen::VectorXd z(kernel.cols());
    for (int i = 0; i < z.size(); ++i) z(i) = 1e-3 * normal(rng);
    const double other = objective(dx + kernel * z);
    CAPTURE(best);
    CAPTURE(other);
    CHECK(other >= best - 1e-12 * std::max(1.0, best));
  }
}

// Runs a reachable move and checks target, optimality and the cached positions.
VertexMoveSummary CheckReachableMove(Single* s, VertexId v, const Eigen::Vector3d& step) {
  const Primitive before = s->primitive();
  const Eigen::Vector3d target = before.mesh.vertex(v).position + step;
  Project moved;
  const VertexMoveSummary summary = MoveVertex(s->project, {s->id, v}, target, {}, &moved);
  INFO("message: " << summary.message);
  REQUIRE(summary.IsUsable());
  const Primitive& after = *moved.FindPrimitive(s->id);
  const double miss = (after.mesh.vertex(v).position - target).norm();
  CAPTURE(miss);
  CHECK(miss < kReachTolerance);
  CHECK(summary.reached);
  CHECK(summary.limited_by.empty());
  const double kkt = KktResidual(before, after, v);
  CAPTURE(kkt);
  CHECK(kkt < kKktTolerance);
  CheckNoBetterNeighbour(before, after, v);
  // The cached positions are the shape's.
  PolyMesh recomputed = after.mesh;
  UpdatePrimitivePositions(&recomputed, after.shape);
  CHECK(recomputed == after.mesh);
  // The rotation never changes.
  CHECK(after.shape.rotation == before.shape.rotation);
  s->project = moved;
  return summary;
}

}  // namespace

TEST_CASE("vertex move: box corner, free translation: only the dimensions that carry it change") {
  Single s = MakeSingle(MakeBox(kNoId, Eigen::Vector3d(4.0, 3.0, 2.5)), /*translation_locked=*/false);
  const Primitive before = s.primitive();
  const Eigen::Matrix3d r = RotationFromAngleAxis(before.shape.rotation);
  // Corner 7 (x, y, z bits set): a step in local coordinates (0.3, -0.2, 0.5).
  const Eigen::Vector3d local_step(0.3, -0.2, 0.5);
  const VertexMoveSummary summary = CheckReachableMove(&s, 7, r * local_step);
  const Primitive& after = s.primitive();
  // Growing the dimensions moves 3 other corners per axis; shifting would move all 7: the
  // optimum changes the sizes only.
  CHECK(std::abs(after.shape.params[0] - 4.3) < kReachTolerance);
  CHECK(std::abs(after.shape.params[1] - 2.8) < kReachTolerance);
  CHECK(std::abs(after.shape.params[2] - 3.0) < kReachTolerance);
  CHECK((after.shape.translation - before.shape.translation).norm() < kReachTolerance);
  MESSAGE("box: " << summary.message);
  CHECK(summary.message.find("shifted") == std::string::npos);

  // Corner 0 (the origin corner) moves by shifting and shrinking: still optimal and exact.
  CheckReachableMove(&s, 0, Eigen::Vector3d(0.2, 0.1, -0.3));
}

TEST_CASE("vertex move: wedge ridge, pyramid apex, cylinder rim") {
  SUBCASE("wedge ridge up: the height grows") {
    Single s = MakeSingle(MakeWedge(kNoId, Eigen::Vector3d(4.0, 3.0, 1.5)), true);
    const Eigen::Matrix3d r = RotationFromAngleAxis(s.primitive().shape.rotation);
    const VertexId ridge = HighestVertex(s.primitive().mesh, r);
    const double height = s.primitive().shape.params[2];
    CheckReachableMove(&s, ridge, r * Eigen::Vector3d(0.0, 0.0, 0.4));
    CHECK(std::abs(s.primitive().shape.params[2] - (height + 0.4)) < kReachTolerance);
    // Free translation as well: a general step.
    s.primitive().translation_locked = false;
    CheckReachableMove(&s, ridge, Eigen::Vector3d(0.3, -0.25, 0.1));
  }
  SUBCASE("pyramid apex sideways with the translation locked: the base grows twice as much") {
    Single s = MakeSingle(MakePyramid(kNoId, Eigen::Vector3d(2.0, 2.0, 3.0)), true);
    const Eigen::Matrix3d r = RotationFromAngleAxis(s.primitive().shape.rotation);
    const VertexId apex = HighestVertex(s.primitive().mesh, r);
    CheckReachableMove(&s, apex, r * Eigen::Vector3d(0.2, 0.0, 0.0));
    CHECK(std::abs(s.primitive().shape.params[0] - 2.4) < kReachTolerance);
    s.primitive().translation_locked = false;
    CheckReachableMove(&s, apex, Eigen::Vector3d(-0.1, 0.3, -0.5));
  }
  SUBCASE("cylinder rim outwards: the radius grows; along the rim it cannot move") {
    Single s = MakeSingle(MakeCylinder(kNoId, 12, 1.0, 2.0), true);
    const Primitive& p = s.primitive();
    const Eigen::Matrix3d r = RotationFromAngleAxis(p.shape.rotation);
    const VertexId rim = 1;
    const Eigen::Vector3d local = r.transpose() * (p.mesh.vertex(rim).position - p.shape.translation);
    const Eigen::Vector3d radial = Eigen::Vector3d(local.x(), local.y(), 0.0).normalized();
    CheckReachableMove(&s, rim, r * (0.25 * radial));
    CHECK(std::abs(s.primitive().shape.params[0] - 1.25) < kReachTolerance);

    const Eigen::Vector3d tangent = Eigen::Vector3d::UnitZ().cross(radial);
    Project moved;
    const Eigen::Vector3d target = s.primitive().mesh.vertex(rim).position + r * (0.3 * tangent);
    const VertexMoveSummary refused = MoveVertex(s.project, {s.id, rim}, target, {}, &moved);
    INFO("message: " << refused.message);
    CHECK_FALSE(refused.IsUsable());
    CHECK(moved == s.project);
    REQUIRE(!refused.limited_by.empty());
    CHECK(refused.limited_by.front().find("translation is locked") != std::string::npos);
    // With the translation free, the same target is reached (the whole cylinder shifts).
    s.primitive().translation_locked = false;
    CheckReachableMove(&s, rim, r * (0.3 * tangent));
  }
}

TEST_CASE("vertex move: a split vertex changes the primitive; a free vertex only its offset") {
  Single s = MakeSingle(MakeBox(kNoId, Eigen::Vector3d(4.0, 3.0, 2.5)), false);
  // Split the edge from corner 4 to corner 5 (top, along x) at t = 0.25.
  PolyMesh& mesh = s.primitive().mesh;
  const HalfedgeId h = FindHalfedge(mesh, 4, 5);
  REQUIRE(h != kNoElement);
  const double t = (h % 2 == 0) ? 0.25 : 0.75;
  const ESplitResult split = ESplit(&mesh, PolyMesh::EdgeOf(h), t);
  REQUIRE(split.ok);
  RefreshAllPrimitives(&s.project);
  const VertexId v = split.vertex;

  SUBCASE("split vertex") {
    const double edge_t = s.primitive().mesh.vertex(v).local.t;
    CheckReachableMove(&s, v, Eigen::Vector3d(0.1, 0.2, 0.3));
    CHECK(s.primitive().mesh.vertex(v).local.t == edge_t);  // stays on its edge at the same t
  }
  SUBCASE("free vertex") {
    s.primitive().mesh.vertex(v).local.free = true;
    const Project before = s.project;
    const Eigen::Vector3d target = before.FindPrimitive(s.id)->mesh.vertex(v).position + Eigen::Vector3d(0.0, 0.0, 0.7);
    Project moved;
    const VertexMoveSummary summary = MoveVertex(before, {s.id, v}, target, {}, &moved);
    INFO("message: " << summary.message);
    REQUIRE(summary.IsUsable());
    CHECK(summary.moved_offset);
    const Primitive& after = *moved.FindPrimitive(s.id);
    const double miss = (after.mesh.vertex(v).position - target).norm();
    CAPTURE(miss);
    CHECK(miss < kReachTolerance);
    CHECK(after.shape == before.FindPrimitive(s.id)->shape);
    CHECK(summary.max_other_displacement == 0.0);
  }
}

TEST_CASE("vertex move: locks are respected and named when they limit the move") {
  Single s = MakeSingle(MakeBox(kNoId, Eigen::Vector3d(4.0, 3.0, 2.5)), true);
  s.primitive().param_locked[2] = true;  // the height is a known length
  const Primitive before = s.primitive();
  const Eigen::Matrix3d r = RotationFromAngleAxis(before.shape.rotation);
  const Eigen::Vector3d start = before.mesh.vertex(7).position;
  const Eigen::Vector3d target = start + r * Eigen::Vector3d(0.3, 0.0, 0.5);
  Project moved;
  const VertexMoveSummary summary = MoveVertex(s.project, {s.id, 7}, target, {}, &moved);
  INFO("message: " << summary.message);
  REQUIRE(summary.IsUsable());
  CHECK_FALSE(summary.reached);
  const Primitive& after = *moved.FindPrimitive(s.id);
  // The closest reachable point: the x part of the step, not the z part.
  const Eigen::Vector3d expected = start + r * Eigen::Vector3d(0.3, 0.0, 0.0);
  const double miss = (after.mesh.vertex(7).position - expected).norm();
  CAPTURE(miss);
  CHECK(miss < kReachTolerance);
  CHECK(std::abs(summary.distance_to_target - 0.5) < kReachTolerance);
  CHECK(after.shape.params[2] == before.shape.params[2]);
  CHECK(after.shape.translation == before.shape.translation);
  bool names_height = false, names_translation = false;
  for (const std::string& reason : summary.limited_by) {
    names_height |= reason.find("Size z is locked") != std::string::npos;
    names_translation |= reason.find("translation is locked") != std::string::npos;
  }
  CHECK(names_height);
  CHECK(names_translation);
  CHECK(summary.message.find("unlock") != std::string::npos);

  // Corner 0 depends on the translation only: locked, it cannot move at all.
  const VertexMoveSummary corner0 =
      MoveVertex(s.project, {s.id, 0}, before.mesh.vertex(0).position + Eigen::Vector3d(0.1, 0, 0), {}, &moved);
  INFO("corner 0: " << corner0.message);
  CHECK_FALSE(corner0.IsUsable());
  CHECK(moved == s.project);

  // With the height unlocked the same target is reached and the translation still holds.
  s.primitive().param_locked[2] = false;
  const VertexMoveSummary unlocked = MoveVertex(s.project, {s.id, 7}, target, {}, &moved);
  CHECK(unlocked.reached);
  CHECK(moved.FindPrimitive(s.id)->shape.translation == before.shape.translation);
}

TEST_CASE("vertex move: refusals leave the project unchanged") {
  Single s = MakeSingle(MakeBox(kNoId, Eigen::Vector3d(4.0, 3.0, 2.5)), true);
  const Eigen::Matrix3d r = RotationFromAngleAxis(s.primitive().shape.rotation);
  Project moved;
  // Through the opposite face: x of corner 7 goes below corner 0's.
  const Eigen::Vector3d through = s.primitive().mesh.vertex(7).position + r * Eigen::Vector3d(-5.0, 0.0, 0.0);
  VertexMoveSummary summary = MoveVertex(s.project, {s.id, 7}, through, {}, &moved);
  INFO("message: " << summary.message);
  CHECK_FALSE(summary.IsUsable());
  CHECK(summary.message.find("opposite face") != std::string::npos);
  CHECK(moved == s.project);

  summary = MoveVertex(s.project, {s.id, 99}, Eigen::Vector3d::Zero(), {}, &moved);
  CHECK_FALSE(summary.IsUsable());
  summary = MoveVertex(s.project, {s.id + 100, 0}, Eigen::Vector3d::Zero(), {}, &moved);
  CHECK_FALSE(summary.IsUsable());
  summary = MoveVertex(s.project, {s.id, 7}, Eigen::Vector3d(NAN, 0, 0), {}, &moved);
  CHECK_FALSE(summary.IsUsable());
  CHECK(moved == s.project);

  // Issue 14: a drag ray almost parallel to its plane puts the target 1e9 away; a box 4 wide
  // becoming 1e9 wide (growth beyond a million times its reach) is no model. Nor is a size
  // dragged to nothing (a millionth of its value and of its reach). A free vertex dragged that
  // far takes its primitive's centre with it.
  const double far = 1e9;
  summary = MoveVertex(s.project, {s.id, 7}, s.primitive().mesh.vertex(7).position + r * Eigen::Vector3d(far, 0, 0),
                       {}, &moved);
  INFO("far: " << summary.message);
  CHECK_FALSE(summary.IsUsable());
  CHECK(summary.message.find("beyond any camera's reach: Size x of 'p' would go from 4 to") != std::string::npos);
  CHECK(moved == s.project);
  const double sliver = 1e-7;  // of 4: below 1e-6 of the size and of the reach
  summary = MoveVertex(s.project, {s.id, 7}, s.primitive().mesh.vertex(7).position + r * Eigen::Vector3d(sliver - 4.0, 0, 0),
                       {}, &moved);
  INFO("sliver: " << summary.message);
  CHECK_FALSE(summary.IsUsable());
  CHECK(summary.message.find("collapse the model: Size x of 'p' would go from 4 to") != std::string::npos);
  CHECK(moved == s.project);
  {
    Project free_vertex = s.project;
    free_vertex.FindPrimitive(s.id)->mesh.vertex(7).local.free = true;
    RefreshAllPrimitives(&free_vertex);
    summary = MoveVertex(free_vertex, {s.id, 7}, Eigen::Vector3d(far, far, far), {}, &moved);
    INFO("free vertex far: " << summary.message);
    CHECK_FALSE(summary.IsUsable());
    CHECK(summary.message.find("the centre of 'p' would move by") != std::string::npos);
    CHECK(moved == free_vertex);
    // A reasonable drag of the same free vertex still applies.
    summary = MoveVertex(free_vertex, {s.id, 7}, free_vertex.FindPrimitive(s.id)->mesh.vertex(7).position +
                                                     Eigen::Vector3d(0.5, 0.0, 0.0), {}, &moved);
    CHECK(summary.IsUsable());
  }

  s.primitive().param_locked = {true, true, true, false};
  summary = MoveVertex(s.project, {s.id, 7}, Eigen::Vector3d::Zero(), {}, &moved);
  CHECK_FALSE(summary.IsUsable());
  CHECK(summary.message.find("locked") != std::string::npos);
}

TEST_CASE("vertex move: a roof on a box changes its own height; the base carries it") {
  Project project;
  Id box_id = kNoId, roof_id = kNoId;
  std::string message;
  REQUIRE(AddPrimitiveToProject(&project, MakeBox(kNoId, Eigen::Vector3d(4.0, 3.0, 2.5)), "box", &box_id, &message));
  REQUIRE(
      AddPrimitiveToProject(&project, MakeWedge(kNoId, Eigen::Vector3d(1.0, 1.0, 1.2)), "roof", &roof_id, &message));
  project.FindPrimitive(roof_id)->attached_to = box_id;
  project.FindPrimitive(roof_id)->translation_locked = false;  // still follows the base
  RefreshAllPrimitives(&project);
  const Primitive roof = *project.FindPrimitive(roof_id);
  const VertexId ridge = HighestVertex(roof.mesh, Eigen::Matrix3d::Identity());

  Project moved;
  VertexMoveSummary summary =
      MoveVertex(project, {roof_id, ridge}, roof.mesh.vertex(ridge).position + Eigen::Vector3d(0, 0, 0.5), {}, &moved);
  INFO("roof up: " << summary.message);
  REQUIRE(summary.IsUsable());
  CHECK(summary.reached);
  CHECK(std::abs(moved.FindPrimitive(roof_id)->shape.params[2] - 1.7) < kReachTolerance);
  CHECK(moved.FindPrimitive(box_id)->shape == project.FindPrimitive(box_id)->shape);
  CHECK(KktResidual(roof, *moved.FindPrimitive(roof_id), ridge) < kKktTolerance);

  // Sideways the footprint would have to change: it follows the base, so not reachable.
  summary =
      MoveVertex(project, {roof_id, ridge}, roof.mesh.vertex(ridge).position + Eigen::Vector3d(0.4, 0, 0), {}, &moved);
  INFO("roof sideways: " << summary.message);
  CHECK_FALSE(summary.IsUsable());
  REQUIRE(!summary.limited_by.empty());
  CHECK(summary.limited_by.front().find("follow") != std::string::npos);

  // The base's top corner up: the box grows and the roof rides on it.
  const Primitive box = *project.FindPrimitive(box_id);
  summary = MoveVertex(project, {box_id, 7}, box.mesh.vertex(7).position + Eigen::Vector3d(0, 0, 0.5), {}, &moved);
  INFO("base up: " << summary.message);
  REQUIRE(summary.IsUsable());
  CHECK(summary.reached);
  const Primitive& roof_after = *moved.FindPrimitive(roof_id);
  for (VertexId v = 0; v < roof.mesh.VertexIdEnd(); ++v) {
    if (!roof.mesh.IsVertex(v)) continue;
    const double error =
        (roof_after.mesh.vertex(v).position - (roof.mesh.vertex(v).position + Eigen::Vector3d(0, 0, 0.5))).norm();
    CAPTURE(v);
    CAPTURE(error);
    CHECK(error < kReachTolerance);
  }
}

TEST_CASE("primitive move: translation by a delta, locks and attachment refuse") {
  Project project;
  Id box_id = kNoId, roof_id = kNoId;
  std::string message;
  REQUIRE(AddPrimitiveToProject(&project, MakeBox(kNoId, Eigen::Vector3d(4.0, 3.0, 2.5)), "box", &box_id, &message));
  REQUIRE(
      AddPrimitiveToProject(&project, MakeWedge(kNoId, Eigen::Vector3d(1.0, 1.0, 1.2)), "roof", &roof_id, &message));
  project.FindPrimitive(roof_id)->attached_to = box_id;
  RefreshAllPrimitives(&project);
  Project moved;
  const Eigen::Vector3d delta(1.0, -0.5, 0.25);

  PrimitiveMoveSummary summary = MovePrimitive(project, box_id, delta, &moved);
  INFO("locked: " << summary.message);
  CHECK_FALSE(summary.IsUsable());
  CHECK(summary.message.find("locked") != std::string::npos);
  CHECK(moved == project);

  summary = MovePrimitive(project, roof_id, delta, &moved);
  INFO("attached: " << summary.message);
  CHECK_FALSE(summary.IsUsable());
  CHECK(moved == project);

  project.FindPrimitive(box_id)->translation_locked = false;
  // Issue 14: a move of 1e9 (a grazing drag ray) takes the box a million times its reach away.
  summary = MovePrimitive(project, box_id, Eigen::Vector3d(1e9, 0.0, 0.0), &moved);
  INFO("far: " << summary.message);
  CHECK_FALSE(summary.IsUsable());
  CHECK(summary.message.find("the centre of 'box' would move by 1e+09") != std::string::npos);
  CHECK(moved == project);

  summary = MovePrimitive(project, box_id, delta, &moved);
  INFO("free: " << summary.message);
  REQUIRE(summary.IsUsable());
  for (Id id : {box_id, roof_id}) {
    const Primitive& a = *project.FindPrimitive(id);
    const Primitive& b = *moved.FindPrimitive(id);
    for (VertexId v = 0; v < a.mesh.VertexIdEnd(); ++v) {
      if (!a.mesh.IsVertex(v)) continue;
      const double error = (b.mesh.vertex(v).position - a.mesh.vertex(v).position - delta).norm();
      CAPTURE(id);
      CAPTURE(error);
      CHECK(error < kReachTolerance);
    }
  }
}

TEST_CASE("vertex move then model update: the solve starts from the moved state") {
  // The box's back (y = sy) corners are not pinned, so nothing in the photo determines its
  // depth: a V_op sets it and the warm-started update (the app's) must keep it. The camera is
  // moved off its true centre so that the solve has work to do.
  testing::SyntheticScene scene = testing::MakeBoxScene();
  Project& project = scene.project;
  std::vector<Pin> front;
  for (const Pin& pin : project.pins) {
    if ((pin.vertex.vertex & 2) == 0) front.push_back(pin);
  }
  project.pins = front;
  REQUIRE(project.pins.size() == 4);
  Camera& camera = project.images[0].camera;
  camera.SetPose(camera.cam_from_world_rotation, camera.CenterInWorld() + Eigen::Vector3d(0.3, -0.2, 0.1));

  const double true_depth = scene.true_box.shape.params[1];
  const double dragged_depth = true_depth + 1.0;
  const Primitive& box = *project.FindPrimitive(scene.box_id);
  Project moved;
  const VertexMoveSummary move =
      MoveVertex(project, {scene.box_id, 2}, box.mesh.vertex(2).position + Eigen::Vector3d(0, 1.0, 0), {}, &moved);
  INFO("move: " << move.message);
  REQUIRE(move.IsUsable());
  REQUIRE(move.reached);
  REQUIRE(std::abs(moved.FindPrimitive(scene.box_id)->shape.params[1] - dragged_depth) < kReachTolerance);

  const ModelUpdateOptions warm = CommitUpdateOptions();  // what the app runs after a commit
  Project updated;
  const ModelUpdateSummary summary = UpdateModel(moved, warm, &updated);
  INFO("solve: " << summary.solve.message << ", joint: " << summary.joint.message);
  REQUIRE(summary.ok);
  CHECK(summary.solve.initial_cost > 1.0);  // the start is not the answer
  CHECK(summary.solve.reprojection_rms_px < 1e-6);
  const double depth = updated.FindPrimitive(scene.box_id)->shape.params[1];
  CAPTURE(depth);
  CHECK(std::abs(depth - dragged_depth) < 1e-9);
  const double width = updated.FindPrimitive(scene.box_id)->shape.params[0];
  CHECK(std::abs(width - scene.true_box.shape.params[0]) < 1e-6);

  // A cold start keeps it too: a free size that appears in no pin is held at its value (not
  // a parameter), so the linear initialisation runs on the rest.
  ModelUpdateOptions cold = warm;
  cold.solve.warm_start = false;
  Project cold_updated;
  const ModelUpdateSummary cold_summary = UpdateModel(moved, cold, &cold_updated);
  const double cold_depth = cold_updated.FindPrimitive(scene.box_id)->shape.params[1];
  MESSAGE("undetermined depth after the update: warm " << depth << ", cold " << cold_depth << " (dragged "
                                                       << dragged_depth << ", before the drag " << true_depth << ")");
  CHECK(cold_summary.ok);
  CHECK(cold_summary.solve.linear_initialization_used);
  CHECK(cold_depth == moved.FindPrimitive(scene.box_id)->shape.params[1]);
  REQUIRE(cold_summary.solve.held_parameters.size() == 1);
  CHECK(cold_summary.solve.held_parameters[0].find("depth") != std::string::npos);
}
