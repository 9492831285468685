// Face extrusion (core/mesh/extrude.h): on every face of every primitive kind the mesh stays
// valid with exact element-count deltas, the face moves along its normal, resizing the
// primitive keeps the extrusion attached, refusals change nothing, push/pull again changes
// only the offsets, and the inverse restores the mesh identically, also after random
// sequences of extrusions mixed with the K-operators.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <variant>
#include <vector>

#include <Eigen/Geometry>

#include "core/geometry/camera.h"
#include "core/mesh/extrude.h"
#include "core/mesh/mesh.h"
#include "core/mesh/operators.h"
#include "core/mesh/primitives.h"
#include "core/mesh/triangulate.h"
#include "tests/mesh_test_util.h"

namespace facet {
namespace {

constexpr double kGeomTol = 1e-9;  // noise-free geometry, scene units ~1 to 10

using testing::AllKinds;
using testing::FirstProblem;
using testing::MeshOf;

TEST_CASE("extruding every face of every primitive, out and in: counts, geometry, exact inverse") {
  for (const PrimitiveShape& p : AllKinds()) {
    const std::string kind = PrimitiveKindName(p.kind);
    CAPTURE(kind);
    const PolyMesh start = MeshOf(p);
    const Eigen::Matrix3d world_from_primitive = RotationFromAngleAxis(p.rotation);
    for (FaceId f = 0; f < start.FaceIdEnd(); ++f) {
      for (const double distance : {0.75, -0.25}) {
        CAPTURE(f);
        CAPTURE(distance);
        PolyMesh mesh = start;
        const int n = FaceDegree(start, f);
        const Eigen::Vector3d normal_before = FaceNormal(start, f);
        const std::vector<VertexId> base = FaceVertices(start, f);
        const ExtrudeResult x = ExtrudeFace(&mesh, p, f, distance);
        REQUIRE_MESSAGE(x.ok, x.message);
        CHECK_VALID(mesh);
        CHECK(mesh.NumVertices() == start.NumVertices() + n);
        CHECK(mesh.NumEdges() == start.NumEdges() + 2 * n);
        CHECK(mesh.NumFaces() == start.NumFaces() + n);
        CHECK(EulerCharacteristic(mesh) == EulerCharacteristic(start));
        REQUIRE(x.new_vertices.size() == static_cast<size_t>(n));
        CHECK(x.base_vertices == base);
        // The face keeps its id, material and corner UVs, and now runs through the new vertices.
        CHECK(FaceVertices(mesh, f) == x.new_vertices);
        CHECK(mesh.face(f).material == start.face(f).material);
        const std::vector<HalfedgeId> corners_before = FaceHalfedges(start, f);
        const std::vector<HalfedgeId> corners_after = FaceHalfedges(mesh, f);
        for (int i = 0; i < n; ++i) CHECK(mesh.halfedge(corners_after[i]).uv == start.halfedge(corners_before[i]).uv);
        // Moved along its world normal by the distance; same normal.
        const double normal_error = (FaceNormal(mesh, f) - normal_before).norm();
        CAPTURE(normal_error);
        CHECK(normal_error < kGeomTol);
        CHECK((world_from_primitive * x.direction_in_primitive - normal_before).norm() < kGeomTol);
        for (int i = 0; i < n; ++i) {
          const Eigen::Vector3d expected = start.vertex(base[i]).position + distance * normal_before;
          const double error = (mesh.vertex(x.new_vertices[i]).position - expected).norm();
          CAPTURE(i);
          CAPTURE(error);
          CHECK(error < kGeomTol);
          CHECK(VertexDegree(mesh, x.new_vertices[i]) == 3);
          CHECK_FALSE(mesh.vertex(x.new_vertices[i]).local.on_edge);
          CHECK_FALSE(mesh.vertex(x.new_vertices[i]).local.free);
        }
        // Side faces: quads whose normals are perpendicular to the face's, pointing out of
        // the solid when pulled (away from the face's centre).
        Eigen::Vector3d centre = Eigen::Vector3d::Zero();
        for (VertexId v : base) centre += start.vertex(v).position;
        centre /= n;
        for (int i = 0; i < n; ++i) {
          const FaceId side = x.side_faces[i];
          CHECK(FaceDegree(mesh, side) == 4);
          CHECK(mesh.face(side).primitive == p.id);
          const Eigen::Vector3d side_normal = FaceNormal(mesh, side);
          CHECK(std::abs(side_normal.dot(normal_before)) < kGeomTol);
          const Eigen::Vector3d edge_mid =
              0.5 * (start.vertex(base[i]).position + start.vertex(base[(i + 1) % n]).position);
          const double outward = side_normal.dot(edge_mid - centre);
          CHECK((distance > 0 ? outward > 0 : outward < 0));
        }
        // Rendering needs n - 2 triangles per face, the new side quads included.
        const MeshTriangulation triangles = TriangulateMesh(mesh);
        for (FaceId g = 0; g < mesh.FaceIdEnd(); ++g)
          if (mesh.IsFace(g)) CHECK(triangles.by_face[g].size() == static_cast<size_t>(FaceDegree(mesh, g) - 2));

        const PolyMesh extruded = mesh;
        std::string message;
        REQUIRE_MESSAGE(UndoExtrudeFace(&mesh, x, &message), message);
        CHECK(mesh == start);
        CHECK_VALID(mesh);
        mesh = extruded;
        ApplyUndo(&mesh, x.undo);
        CHECK(mesh == start);
      }
    }
  }
}

TEST_CASE("the extrusion is defined in primitive-local coordinates: resizing and moving keep it attached") {
  PrimitiveShape box = MakeBox(7, {2.0, 3.0, 1.5});
  box.rotation = {0.2, -0.1, 0.4};
  box.translation = {1.0, -2.0, 0.5};
  PolyMesh mesh = MeshOf(box);
  constexpr FaceId kTop = 5;  // BoxFaces(): -X, +X, -Y, +Y, -Z, +Z
  constexpr double kDistance = 0.8;
  const ExtrudeResult x = ExtrudeFace(&mesh, box, kTop, kDistance);
  REQUIRE_MESSAGE(x.ok, x.message);
  CHECK((x.direction_in_primitive - Eigen::Vector3d::UnitZ()).norm() < kGeomTol);
  for (VertexId w : x.new_vertices)
    CHECK((mesh.vertex(w).local.offset - Eigen::Vector3d(0, 0, kDistance)).norm() < kGeomTol);

  PrimitiveShape resized = box;
  resized.params.head<3>() = Eigen::Vector3d(3.5, 1.25, 2.75);
  resized.rotation = {-0.3, 0.25, 1.0};
  resized.translation = {-4.0, 2.0, 1.0};
  UpdatePrimitivePositions(&mesh, resized);
  const Eigen::Matrix3d r = RotationFromAngleAxis(resized.rotation);
  for (size_t i = 0; i < x.new_vertices.size(); ++i) {
    const Eigen::Vector3d base = mesh.vertex(x.base_vertices[i]).position;
    const Eigen::Vector3d expected = base + r * Eigen::Vector3d(0, 0, kDistance);
    const double error = (mesh.vertex(x.new_vertices[i]).position - expected).norm();
    CAPTURE(i);
    CAPTURE(error);
    CHECK(error < kGeomTol);
  }
  // The base ring is the resized box's top: corners 4..7 at local z = sz.
  for (VertexId v : x.base_vertices) {
    const Eigen::Vector3d local = r.transpose() * (mesh.vertex(v).position - resized.translation);
    CHECK(std::abs(local.z() - resized.params[2]) < kGeomTol);
  }
  CHECK_VALID(mesh);
}

TEST_CASE("an E_split on a side edge of an extrusion follows a resize like any other") {
  PrimitiveShape box = MakeBox(8, {2.0, 2.0, 2.0});
  PolyMesh mesh = MeshOf(box);
  const ExtrudeResult x = ExtrudeFace(&mesh, box, 1, 0.5);  // +X face
  REQUIRE_MESSAGE(x.ok, x.message);
  const ESplitResult split = ESplit(&mesh, x.side_edges[0], 0.25);
  REQUIRE_MESSAGE(split.ok, split.message);
  box.params.head<3>() = Eigen::Vector3d(4.0, 1.0, 3.0);
  UpdatePrimitivePositions(&mesh, box);
  const Eigen::Vector3d a = mesh.vertex(x.base_vertices[0]).position;
  const Eigen::Vector3d b = mesh.vertex(x.new_vertices[0]).position;
  const double error = (mesh.vertex(split.vertex).position - (0.75 * a + 0.25 * b)).norm();
  CAPTURE(error);
  CHECK(error < kGeomTol);
  CHECK(std::abs((b - a).norm() - 0.5) < kGeomTol);
}

TEST_CASE("refusals say why and change nothing") {
  const PrimitiveShape box = MakeBox(9, {2.0, 3.0, 1.5});
  const PolyMesh start = MeshOf(box);
  auto refused = [&](const PolyMesh& mesh, const PrimitiveShape& shape, FaceId f, double d, const std::string& why) {
    PolyMesh copy = mesh;
    const ExtrudeResult x = ExtrudeFace(&copy, shape, f, d);
    INFO("message: " << x.message);
    CHECK_FALSE(x.ok);
    CHECK(x.message.find(why) != std::string::npos);
    CHECK(copy == mesh);
  };
  refused(start, box, 2, 0.0, "non-zero");
  refused(start, box, 2, std::numeric_limits<double>::quiet_NaN(), "non-zero and finite");
  refused(start, box, 2, std::numeric_limits<double>::infinity(), "finite");
  refused(start, box, 99, 1.0, "does not exist");
  PrimitiveShape other = box;
  other.id = 10;
  refused(start, other, 2, 1.0, "belongs to primitive 9");

  // A free vertex moved off its faces' planes bends them: corner 7 is on +X, +Y and +Z.
  PolyMesh bent = start;
  bent.vertex(7).local.free = true;
  bent.vertex(7).local.offset = Eigen::Vector3d(0.1, 0.1, 0.1);
  UpdatePrimitivePositions(&bent, box);
  int bent_faces = 0;
  for (FaceId f = 0; f < bent.FaceIdEnd(); ++f) {
    CAPTURE(f);
    const std::vector<VertexId> loop = FaceVertices(bent, f);
    if (std::find(loop.begin(), loop.end(), 7u) != loop.end()) {
      refused(bent, box, f, 1.0, "not planar");
      ++bent_faces;
    } else {
      PolyMesh copy = bent;
      CHECK(ExtrudeFace(&copy, box, f, 1.0).ok);
    }
  }
  CHECK(bent_faces == 3);
  // A zero-area sliver: V_connect between the two ends of a split edge.
  PolyMesh sliver = start;
  const HalfedgeId h = sliver.face(2).halfedge;
  const VertexId a = sliver.Origin(h), b = sliver.Dest(h);
  const ESplitResult split = ESplit(&sliver, PolyMesh::EdgeOf(h), 0.5);
  REQUIRE(split.ok);
  const VConnectResult connect = VConnect(&sliver, 2, a, b);
  REQUIRE_MESSAGE(connect.ok, connect.message);
  const FaceId thin = FaceDegree(sliver, 2) == 3 ? 2 : connect.new_face;
  REQUIRE(FaceDegree(sliver, thin) == 3);
  refused(sliver, box, thin, 1.0, "degenerate");

  // The inverse refuses once the ring was edited, and changes nothing.
  PolyMesh mesh = start;
  const ExtrudeResult x = ExtrudeFace(&mesh, box, 5, 1.0);
  REQUIRE(x.ok);
  REQUIRE(ESplit(&mesh, x.cap_edges[1], 0.5).ok);
  const PolyMesh edited = mesh;
  std::string message;
  CHECK_FALSE(UndoExtrudeFace(&mesh, x, &message));
  INFO(message);
  CHECK(message.find("edited") != std::string::npos);
  CHECK(mesh == edited);
  ExtrudeResult copy_x = x;
  const ExtrusionDistanceResult again = SetExtrusionDistance(&mesh, box, &copy_x, 2.0);
  CHECK_FALSE(again.ok);
  CHECK(mesh == edited);
  CHECK(copy_x.distance == x.distance);
}

TEST_CASE("push/pull again changes only the offsets; the original distance restores the mesh exactly") {
  for (const PrimitiveShape& p : AllKinds()) {
    const std::string kind = PrimitiveKindName(p.kind);
    CAPTURE(kind);
    PolyMesh mesh = MeshOf(p);
    ExtrudeResult x = ExtrudeFace(&mesh, p, 0, 0.6);
    REQUIRE_MESSAGE(x.ok, x.message);
    const PolyMesh extruded = mesh;
    const Eigen::Vector3d normal = FaceNormal(mesh, 0);
    for (const double distance : {1.7, -0.4, 0.05}) {
      CAPTURE(distance);
      const PolyMesh before = mesh;
      const ExtrusionDistanceResult r = SetExtrusionDistance(&mesh, p, &x, distance);
      REQUIRE_MESSAGE(r.ok, r.message);
      CHECK(x.distance == distance);
      CHECK_VALID(mesh);
      CHECK(mesh.NumVertices() == extruded.NumVertices());
      CHECK(mesh.NumEdges() == extruded.NumEdges());
      CHECK(mesh.NumFaces() == extruded.NumFaces());
      for (size_t i = 0; i < x.new_vertices.size(); ++i) {
        const Eigen::Vector3d expected = mesh.vertex(x.base_vertices[i]).position + distance * normal;
        const double error = (mesh.vertex(x.new_vertices[i]).position - expected).norm();
        CAPTURE(error);
        CHECK(error < kGeomTol);
      }
      PolyMesh reverted = mesh;
      ApplyUndo(&reverted, r.undo);
      CHECK(reverted == before);
    }
    const ExtrusionDistanceResult zero = SetExtrusionDistance(&mesh, p, &x, 0.0);
    CHECK_FALSE(zero.ok);
    CHECK(zero.message.find("non-zero") != std::string::npos);
    REQUIRE(SetExtrusionDistance(&mesh, p, &x, 0.6).ok);
    CHECK(mesh == extruded);
    std::string message;
    REQUIRE_MESSAGE(UndoExtrudeFace(&mesh, x, &message), message);
    CHECK(mesh == MeshOf(p));
  }
}

// One step of a random sequence, with what undoes it.
using Step = std::variant<ESplitResult, VConnectResult, ExtrudeResult>;

TEST_CASE("property: random extrusions mixed with K-ops, then the inverses in reverse, end in the start mesh") {
  const std::vector<PrimitiveShape> kinds = AllKinds();
  constexpr int kSequences = 300;
  constexpr int kStepsPerSequence = 12;
  int extrusions = 0, refused_slivers = 0;
  for (unsigned seed = 1; seed <= kSequences; ++seed) {
    CAPTURE(seed);
    std::mt19937 rng(seed);
    const PrimitiveShape& p = kinds[rng() % kinds.size()];
    const PolyMesh start = MeshOf(p);
    PolyMesh mesh = start;
    std::vector<Step> steps;
    std::vector<PolyMesh> states = {mesh};
    for (int step = 0; step < kStepsPerSequence; ++step) {
      CAPTURE(step);
      const int op = static_cast<int>(rng() % 4);
      if (op == 0) {
        const EdgeId e = static_cast<EdgeId>(rng() % mesh.EdgeIdEnd());
        if (!mesh.IsEdge(e)) continue;
        const double t = std::uniform_real_distribution<double>(0.1, 0.9)(rng);
        ESplitResult r = ESplit(&mesh, e, t);
        REQUIRE_MESSAGE(r.ok, r.message);
        steps.emplace_back(std::move(r));
      } else if (op == 1) {
        const FaceId f = static_cast<FaceId>(rng() % mesh.FaceIdEnd());
        if (!mesh.IsFace(f) || FaceDegree(mesh, f) < 4) continue;
        const std::vector<VertexId> loop = FaceVertices(mesh, f);
        const size_t n = loop.size();
        const size_t i = rng() % n, j = (i + 2 + rng() % (n - 3)) % n;
        VConnectResult r = VConnect(&mesh, f, loop[i], loop[j]);
        if (!r.ok) continue;  // e.g. the two vertices are already joined across another face
        steps.emplace_back(std::move(r));
      } else {
        const FaceId f = static_cast<FaceId>(rng() % mesh.FaceIdEnd());
        if (!mesh.IsFace(f)) continue;
        const double d = std::uniform_real_distribution<double>(-1.0, 1.0)(rng);
        const PolyMesh before = mesh;
        ExtrudeResult r = ExtrudeFace(&mesh, p, f, d);
        if (!r.ok) {
          // V_connect between the two ends of a split edge leaves a zero-area sliver.
          REQUIRE_MESSAGE(r.message.find("degenerate") != std::string::npos, r.message);
          REQUIRE(mesh == before);
          ++refused_slivers;
          continue;
        }
        steps.emplace_back(std::move(r));
        ++extrusions;
      }
      const std::string problem = FirstProblem(mesh);
      REQUIRE_MESSAGE(problem.empty(), problem);
      REQUIRE(EulerCharacteristic(mesh) == EulerCharacteristic(start));
      states.push_back(mesh);
    }
    for (size_t k = steps.size(); k-- > 0;) {
      CAPTURE(k);
      if (const auto* split = std::get_if<ESplitResult>(&steps[k])) {
        const VDeleteResult r = UndoESplit(&mesh, *split);
        REQUIRE_MESSAGE(r.ok, r.message);
      } else if (const auto* connect = std::get_if<VConnectResult>(&steps[k])) {
        const EDeleteResult r = UndoVConnect(&mesh, *connect);
        REQUIRE_MESSAGE(r.ok, r.message);
      } else {
        std::string message;
        REQUIRE_MESSAGE(UndoExtrudeFace(&mesh, std::get<ExtrudeResult>(steps[k]), &message), message);
      }
      REQUIRE(mesh == states[k]);
    }
    REQUIRE(mesh == start);
  }
  MESSAGE(extrusions << " random extrusions undone exactly; " << refused_slivers << " slivers refused");
  CHECK(extrusions > kSequences);
}

}  // namespace
}  // namespace facet
