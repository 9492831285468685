// The paper's K-operators (core/mesh/operators.h): on every primitive kind, invariants hold
// after each operator, element counts change exactly, refusals change nothing, and every
// operator is undone exactly by its inverse (same ids, links, positions, attributes).
#include <doctest/doctest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>
#include <string>
#include <variant>

#include <Eigen/Geometry>

#include "core/mesh/mesh.h"
#include "core/mesh/operators.h"
#include "core/mesh/primitives.h"
#include "core/mesh/triangulate.h"
#include "tests/mesh_test_util.h"

namespace facet {
namespace {

constexpr double kGeomTol = 1e-9;  // noise-free geometry, metres

using testing::AllKinds;
using testing::FirstProblem;
using testing::MeshOf;

TEST_CASE("E_split then V_delete on every edge of every primitive") {
  for (const PrimitiveShape& p : AllKinds()) {
    const std::string kind = PrimitiveKindName(p.kind);
    CAPTURE(kind);
    const PolyMesh start = MeshOf(p);
    for (EdgeId e = 0; e < start.EdgeIdEnd(); ++e) {
      CAPTURE(e);
      PolyMesh mesh = start;
      const ESplitResult split = ESplit(&mesh, e, 0.3);
      REQUIRE_MESSAGE(split.ok, split.message);
      CHECK_VALID(mesh);
      CHECK(mesh.NumVertices() == start.NumVertices() + 1);
      CHECK(mesh.NumEdges() == start.NumEdges() + 1);
      CHECK(mesh.NumFaces() == start.NumFaces());
      CHECK(EulerCharacteristic(mesh) == EulerCharacteristic(start));
      CHECK(VertexDegree(mesh, split.vertex) == 2);
      // Attributes: in each face beside the edge, the new corner's UV is the interpolation
      // of its neighbours' at t along the edge; the world position likewise.
      for (int side = 0; side < 2; ++side) {
        const HalfedgeId into = side == 0 ? PolyMesh::EdgeHalfedge(e, 0) : mesh.Prev(PolyMesh::EdgeHalfedge(e, 1));
        const HalfedgeId at_m = mesh.Next(into), after = mesh.Next(at_m);
        REQUIRE(mesh.Origin(at_m) == split.vertex);
        const double s = side == 0 ? 0.3 : 0.7;  // measured from `into`'s origin
        const Eigen::Vector2d expected = (1.0 - s) * mesh.halfedge(into).uv + s * mesh.halfedge(after).uv;
        CHECK((mesh.halfedge(at_m).uv - expected).norm() < kGeomTol);
      }
      const Eigen::Vector3d pa = mesh.vertex(mesh.Origin(PolyMesh::EdgeHalfedge(e, 0))).position;
      const Eigen::Vector3d pb = mesh.vertex(mesh.Dest(split.new_edge * 2)).position;
      CHECK((mesh.vertex(split.vertex).position - (0.7 * pa + 0.3 * pb)).norm() < kGeomTol);
      const PolyMesh split_mesh = mesh;

      const VDeleteResult undo = UndoESplit(&mesh, split);
      REQUIRE_MESSAGE(undo.ok, undo.message);
      CHECK(mesh == start);

      // V_delete as the forward operator, undone by E_split re-creating the same ids.
      const ESplitResult redo = UndoVDelete(&mesh, undo);
      REQUIRE_MESSAGE(redo.ok, redo.message);
      CHECK(redo.vertex == split.vertex);
      CHECK(mesh == split_mesh);
      CHECK_VALID(mesh);

      // The generic record restores as well.
      ApplyUndo(&mesh, split.undo);
      CHECK(mesh == start);
    }
  }
}

TEST_CASE("V_connect then E_delete on every non-adjacent vertex pair of every face") {
  for (const PrimitiveShape& p : AllKinds()) {
    const std::string kind = PrimitiveKindName(p.kind);
    CAPTURE(kind);
    PolyMesh base = MeshOf(p);
    // Split every edge once so that triangles gain connectable vertices too.
    const EdgeId original_edges = base.EdgeIdEnd();
    for (EdgeId e = 0; e < original_edges; ++e) REQUIRE(ESplit(&base, e, 0.5).ok);
    REQUIRE(Validate(base).empty());
    int connects = 0;
    for (FaceId f = 0; f < base.FaceIdEnd(); ++f) {
      const std::vector<VertexId> loop = FaceVertices(base, f);
      const int n = static_cast<int>(loop.size());
      for (int i = 0; i < n; ++i) {
        for (int j = i + 2; j < n; ++j) {
          if (i == 0 && j == n - 1) continue;  // adjacent around the loop
          CAPTURE(f);
          CAPTURE(i);
          CAPTURE(j);
          PolyMesh mesh = base;
          const VConnectResult c = VConnect(&mesh, f, loop[i], loop[j]);
          if (!c.ok) {
            // Only refusal possible here: the two vertices already share an edge elsewhere.
            CHECK(c.message.find("already joined") != std::string::npos);
            CHECK(mesh == base);
            continue;
          }
          ++connects;
          CHECK_VALID(mesh);
          CHECK(mesh.NumVertices() == base.NumVertices());
          CHECK(mesh.NumEdges() == base.NumEdges() + 1);
          CHECK(mesh.NumFaces() == base.NumFaces() + 1);
          CHECK(EulerCharacteristic(mesh) == EulerCharacteristic(base));
          CHECK(FaceDegree(mesh, f) + FaceDegree(mesh, c.new_face) == n + 2);
          // Convex planar input gives convex parts: no corner turns against the normal.
          for (FaceId part : {f, c.new_face}) {
            const Eigen::Vector3d normal = FaceNormal(mesh, part);
            for (HalfedgeId h : FaceHalfedges(mesh, part)) {
              const Eigen::Vector3d& p0 = mesh.vertex(mesh.Origin(mesh.Prev(h))).position;
              const Eigen::Vector3d& p1 = mesh.vertex(mesh.Origin(h)).position;
              const Eigen::Vector3d& p2 = mesh.vertex(mesh.Dest(h)).position;
              CHECK((p1 - p0).cross(p2 - p1).dot(normal) > -kGeomTol);
            }
          }
          const PolyMesh connected = mesh;

          const EDeleteResult d = UndoVConnect(&mesh, c);
          REQUIRE_MESSAGE(d.ok, d.message);
          CHECK(mesh == base);
          const VConnectResult redo = UndoEDelete(&mesh, d);
          REQUIRE_MESSAGE(redo.ok, redo.message);
          CHECK(mesh == connected);
          ApplyUndo(&mesh, c.undo);
          CHECK(mesh == base);
        }
      }
    }
    CHECK(connects > 0);
  }
}

TEST_CASE("E_delete as the forward operator on every interior edge, undone by V_connect") {
  for (const PrimitiveShape& p : AllKinds()) {
    const std::string kind = PrimitiveKindName(p.kind);
    CAPTURE(kind);
    const PolyMesh start = MeshOf(p);
    int deletes = 0;
    for (EdgeId e = 0; e < start.EdgeIdEnd(); ++e) {
      CAPTURE(e);
      PolyMesh mesh = start;
      const EDeleteResult d = EDelete(&mesh, e);
      if (!d.ok) {
        CHECK(mesh == start);
        continue;
      }
      ++deletes;
      CHECK_VALID(mesh);
      CHECK(mesh.NumVertices() == start.NumVertices());
      CHECK(mesh.NumEdges() == start.NumEdges() - 1);
      CHECK(mesh.NumFaces() == start.NumFaces() - 1);
      CHECK(EulerCharacteristic(mesh) == EulerCharacteristic(start));
      const VConnectResult c = UndoEDelete(&mesh, d);
      REQUIRE_MESSAGE(c.ok, c.message);
      CHECK(c.edge == e);
      CHECK(mesh == start);
    }
    if (p.kind != PrimitiveKind::kPlane) CHECK(deletes > 0);
  }
}

TEST_CASE("after E_split on a box edge at t = 0.3, resizing the box keeps the vertex on that edge at t") {
  PrimitiveShape box = MakeBox(7, {2.0, 3.0, 1.5});
  box.rotation = Eigen::Vector3d(0.2, 0.1, -0.4);
  box.translation = Eigen::Vector3d(1.0, 2.0, 3.0);
  PolyMesh mesh = MeshOf(box);
  constexpr double kT = 0.3;
  for (EdgeId e = 0; e < 12; ++e) {
    CAPTURE(e);
    PolyMesh m = mesh;
    const HalfedgeId h = PolyMesh::EdgeHalfedge(e, 0);
    const VertexId a = m.Origin(h), b = m.Dest(h);
    const ESplitResult split = ESplit(&m, e, kT);
    REQUIRE(split.ok);
    PrimitiveShape resized = box;
    resized.params.head<3>() = Eigen::Vector3d(5.0, 0.5, 4.0);
    resized.rotation = Eigen::Vector3d(-0.3, 0.6, 0.1);
    resized.translation = Eigen::Vector3d(-2.0, 0.0, 7.0);
    const Eigen::Vector3d before = m.vertex(split.vertex).position;
    UpdatePrimitivePositions(&m, resized);
    const Eigen::Vector3d pa = m.vertex(a).position, pb = m.vertex(b).position, pm = m.vertex(split.vertex).position;
    CHECK((pm - before).norm() > 0.1);  // it did move
    const double error = (pm - ((1.0 - kT) * pa + kT * pb)).norm();
    CAPTURE(error);
    CHECK(error < kGeomTol);
    // Local coordinates too: the local position is on the local edge.
    const Eigen::Vector3d la = m.vertex(a).LocalPosition(resized.params);
    const Eigen::Vector3d lb = m.vertex(b).LocalPosition(resized.params);
    CHECK((m.vertex(split.vertex).LocalPosition(resized.params) - ((1.0 - kT) * la + kT * lb)).norm() < kGeomTol);
  }
}

TEST_CASE("a split of a split stays on the original edge when the primitive changes") {
  PrimitiveShape box = MakeBox(1, {1.0, 1.0, 1.0});
  PolyMesh m = MeshOf(box);
  const HalfedgeId h = PolyMesh::EdgeHalfedge(0, 0);
  const VertexId a = m.Origin(h), b = m.Dest(h);
  const ESplitResult s1 = ESplit(&m, 0, 0.5);  // edge 0 now runs a -> s1
  REQUIRE(s1.ok);
  const ESplitResult s2 = ESplit(&m, 0, 0.5);  // midpoint of a -> s1: t = 0.25 of a -> b
  REQUIRE(s2.ok);
  const ESplitResult s3 = ESplit(&m, s1.new_edge, 0.5);  // midpoint of s1 -> b: t = 0.75
  REQUIRE(s3.ok);
  // Deleting the middle vertex must not disturb the others' definitions (stored by value).
  const VDeleteResult d = VDelete(&m, s1.vertex);
  REQUIRE_MESSAGE(d.ok, d.message);
  CHECK(Validate(m).empty());
  box.params.head<3>() = Eigen::Vector3d(4.0, 2.0, 3.0);
  UpdatePrimitivePositions(&m, box);
  const Eigen::Vector3d pa = m.vertex(a).position, pb = m.vertex(b).position;
  CHECK((m.vertex(s2.vertex).position - (0.75 * pa + 0.25 * pb)).norm() < kGeomTol);
  CHECK((m.vertex(s3.vertex).position - (0.25 * pa + 0.75 * pb)).norm() < kGeomTol);
}

TEST_CASE("refusals say why and change nothing") {
  PolyMesh box = MeshOf(MakeBox(1, {1.0, 2.0, 3.0}));
  auto refused = [](const PolyMesh& before, const PolyMesh& after, bool ok, const std::string& message,
                    const std::string& expected) {
    CAPTURE(message);
    CHECK_FALSE(ok);
    CHECK(message.find(expected) != std::string::npos);
    CHECK(after == before);
  };
  const FaceId f = 0;
  const std::vector<VertexId> loop = FaceVertices(box, f);
  SUBCASE("V_connect: vertices of different faces") {
    PolyMesh m = box;
    VertexId other = kNoElement;
    for (VertexId v = 0; v < m.VertexIdEnd(); ++v) {
      if (std::find(loop.begin(), loop.end(), v) == loop.end()) other = v;
    }
    const auto r = VConnect(&m, f, loop[0], other);
    refused(box, m, r.ok, r.message, "same face");
  }
  SUBCASE("V_connect: adjacent vertices") {
    PolyMesh m = box;
    const auto r = VConnect(&m, f, loop[0], loop[1]);
    refused(box, m, r.ok, r.message, "adjacent");
  }
  SUBCASE("V_connect: self-loop") {
    PolyMesh m = box;
    const auto r = VConnect(&m, f, loop[0], loop[0]);
    refused(box, m, r.ok, r.message, "self-loop");
  }
  SUBCASE("V_connect: missing face or vertex") {
    PolyMesh m = box;
    const auto r = VConnect(&m, 99, loop[0], loop[2]);
    refused(box, m, r.ok, r.message, "does not exist");
    const auto r2 = VConnect(&m, f, 12345, loop[2]);
    refused(box, m, r2.ok, r2.message, "does not exist");
  }
  SUBCASE("V_delete: a primitive corner") {
    PolyMesh m = box;
    const auto r = VDelete(&m, loop[0]);
    refused(box, m, r.ok, r.message, "corner");
  }
  SUBCASE("V_delete: a vertex of a triangle") {
    PolyMesh m = box;
    const HalfedgeId h = m.face(f).halfedge;
    const VertexId a = m.Origin(h), b = m.Dest(h);
    const ESplitResult s = ESplit(&m, PolyMesh::EdgeOf(h), 0.4);
    REQUIRE(s.ok);
    // a and b are no longer adjacent: connecting them cuts off the triangle (b, a, s), whose
    // vertex s would leave a two-vertex face (its neighbours are joined by the triangle's edge).
    const VConnectResult c = VConnect(&m, m.Face(h), a, b);
    REQUIRE_MESSAGE(c.ok, c.message);
    const PolyMesh before = m;
    const auto r = VDelete(&m, s.vertex);
    refused(before, m, r.ok, r.message, "already joined");
  }
  SUBCASE("V_delete: a split vertex with three edges") {
    PolyMesh m = box;
    const HalfedgeId h = m.face(f).halfedge;
    const ESplitResult s = ESplit(&m, PolyMesh::EdgeOf(h), 0.4);
    REQUIRE(s.ok);
    const VertexId opposite = m.Dest(m.Next(m.Next(h)));
    REQUIRE(VConnect(&m, m.Face(h), s.vertex, opposite).ok);
    const PolyMesh before = m;
    const auto r = VDelete(&m, s.vertex);
    refused(before, m, r.ok, r.message, "3 edges");
  }
  SUBCASE("E_delete: a boundary edge") {
    PolyMesh plane = MeshOf(MakePlane(1, 1.0, 1.0));
    PolyMesh m = plane;
    const auto r = EDelete(&m, 0);
    refused(plane, m, r.ok, r.message, "boundary");
  }
  SUBCASE("E_delete: an endpoint left with one edge") {
    PolyMesh m = box;
    const ESplitResult s = ESplit(&m, 0, 0.5);
    REQUIRE(s.ok);
    const PolyMesh before = m;
    const auto r = EDelete(&m, 0);
    refused(before, m, r.ok, r.message, "single edge");
  }
  SUBCASE("E_split: t outside (0, 1) and a missing edge") {
    PolyMesh m = box;
    for (double t : {0.0, 1.0, -0.5, 2.0, std::nan("")}) {
      const auto r = ESplit(&m, 0, t);
      refused(box, m, r.ok, r.message, "strictly between");
    }
    const auto r = ESplit(&m, 500, 0.5);
    refused(box, m, r.ok, r.message, "does not exist");
  }
}

// One applied operator and how to invert it.
struct Step {
  std::variant<ESplitResult, VDeleteResult, VConnectResult, EDeleteResult> result;
};

template <typename Pick>
std::uint32_t RandomLive(std::mt19937& rng, std::uint32_t end, Pick live) {
  if (end == 0) return kNoElement;
  std::uniform_int_distribution<std::uint32_t> id(0, end - 1);
  for (int tries = 0; tries < 64; ++tries) {
    const std::uint32_t x = id(rng);
    if (live(x)) return x;
  }
  return kNoElement;
}

PrimitiveShape RandomPrimitive(std::mt19937& rng) {
  std::uniform_real_distribution<double> size(0.2, 5.0), angle(-1.0, 1.0);
  std::uniform_int_distribution<int> kind(0, 5), segments(3, 9);
  PrimitiveShape p;
  switch (kind(rng)) {
    case 0: p = MakeBox(1, {size(rng), size(rng), size(rng)}); break;
    case 1: p = MakeWedge(1, {size(rng), size(rng), size(rng)}); break;
    case 2: {  // one draw per statement: the order of a call's arguments is unspecified
      const int n = segments(rng);
      const double radius = size(rng), height = size(rng);
      p = MakePrism(1, n, radius, height);
      break;
    }
    case 3: p = MakePyramid(1, {size(rng), size(rng), size(rng)}); break;
    case 4: {
      const int n = segments(rng);
      const double radius = size(rng), height = size(rng);
      p = MakeCylinder(1, n, radius, height);
      break;
    }
    default: {
      const double width = size(rng), height = size(rng);
      p = MakePlane(1, width, height);
      break;
    }
  }
  p.rotation = Eigen::Vector3d{angle(rng), angle(rng), angle(rng)};
  p.translation = 10.0 * Eigen::Vector3d{angle(rng), angle(rng), angle(rng)};
  return p;
}

// Applies one random operator (any of the four); returns false if it was refused.
bool RandomStep(std::mt19937& rng, PolyMesh* mesh, std::vector<Step>* steps) {
  std::uniform_int_distribution<int> which(0, 9);
  std::uniform_real_distribution<double> t(0.05, 0.95);
  const PolyMesh before = *mesh;
  bool ok = false;
  std::string message;
  const int op = which(rng);
  if (op < 4) {
    const EdgeId e = RandomLive(rng, mesh->EdgeIdEnd(), [&](std::uint32_t x) { return mesh->IsEdge(x); });
    ESplitResult r = ESplit(mesh, e, t(rng));
    ok = r.ok;
    message = r.message;
    if (ok) steps->push_back({std::move(r)});
  } else if (op < 7) {
    const FaceId f = RandomLive(rng, mesh->FaceIdEnd(), [&](std::uint32_t x) { return mesh->IsFace(x); });
    if (f != kNoFace) {
      const std::vector<VertexId> loop = FaceVertices(*mesh, f);
      std::uniform_int_distribution<std::size_t> corner(0, loop.size() - 1);
      const std::size_t a = corner(rng), b = corner(rng);
      VConnectResult r = VConnect(mesh, f, loop[a], loop[b]);
      ok = r.ok;
      message = r.message;
      if (ok) steps->push_back({std::move(r)});
    }
  } else if (op < 9) {
    const VertexId v = RandomLive(rng, mesh->VertexIdEnd(),
                                  [&](std::uint32_t x) { return mesh->IsVertex(x) && mesh->vertex(x).local.on_edge; });
    VDeleteResult r = VDelete(mesh, v);
    ok = r.ok;
    message = r.message;
    if (ok) steps->push_back({std::move(r)});
  } else {
    const EdgeId e = RandomLive(rng, mesh->EdgeIdEnd(), [&](std::uint32_t x) { return mesh->IsEdge(x); });
    EDeleteResult r = EDelete(mesh, e);
    ok = r.ok;
    message = r.message;
    if (ok) steps->push_back({std::move(r)});
  }
  if (!ok) {
    CAPTURE(message);
    CHECK_FALSE(message.empty());
    CHECK(*mesh == before);  // a refusal changes nothing
  }
  return ok;
}

bool Invert(PolyMesh* mesh, const Step& step, std::string* message) {
  if (const auto* s = std::get_if<ESplitResult>(&step.result)) {
    const auto r = UndoESplit(mesh, *s);
    *message = r.message;
    return r.ok;
  }
  if (const auto* s = std::get_if<VDeleteResult>(&step.result)) {
    const auto r = UndoVDelete(mesh, *s);
    *message = r.message;
    return r.ok;
  }
  if (const auto* s = std::get_if<VConnectResult>(&step.result)) {
    const auto r = UndoVConnect(mesh, *s);
    *message = r.message;
    return r.ok;
  }
  const auto r = UndoEDelete(mesh, std::get<EDeleteResult>(step.result));
  *message = r.message;
  return r.ok;
}

const MeshUndo& UndoOf(const Step& step) {
  return std::visit([](const auto& r) -> const MeshUndo& { return r.undo; }, step.result);
}

TEST_CASE("property: random operator sequences followed by their inverses end in the start mesh") {
  constexpr int kSequences = 10000;
  constexpr int kMaxLength = 24;
  const auto t0 = std::chrono::steady_clock::now();
  int applied = 0, refused = 0;
  for (int seed = 1; seed <= kSequences; ++seed) {
    CAPTURE(seed);
    std::mt19937 rng(seed);
    const PrimitiveShape p = RandomPrimitive(rng);
    const std::string kind = PrimitiveKindName(p.kind);
    CAPTURE(kind);
    const PolyMesh start = MeshOf(p);
    PolyMesh mesh = start;
    std::vector<Step> steps;
    std::vector<PolyMesh> states = {start};
    const int length = std::uniform_int_distribution<int>(1, kMaxLength)(rng);
    for (int i = 0; i < length; ++i) {
      if (RandomStep(rng, &mesh, &steps)) {
        ++applied;
        states.push_back(mesh);
        const std::string problem = FirstProblem(mesh);
        REQUIRE_MESSAGE(problem.empty(), problem);
        REQUIRE(EulerCharacteristic(mesh) == EulerCharacteristic(start));
      } else {
        ++refused;
      }
    }
    // Alternate the two ways back: the inverse operators, or the generic undo records.
    const bool use_records = seed % 2 == 0;
    for (int i = static_cast<int>(steps.size()) - 1; i >= 0; --i) {
      CAPTURE(i);
      if (use_records) {
        ApplyUndo(&mesh, UndoOf(steps[i]));
      } else {
        std::string message;
        REQUIRE_MESSAGE(Invert(&mesh, steps[i], &message), message);
      }
      REQUIRE(mesh == states[i]);
    }
    CHECK(mesh == start);
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  MESSAGE("property test: " << kSequences << " sequences, " << applied << " operators applied, " << refused
                            << " refused, " << seconds << " s");
  CHECK(applied > kSequences);  // the sequences are not all refusals
  CHECK(refused > 0);           // and the refusal path was exercised
}

TEST_CASE("re-triangulating only the faces an operator touched matches a full triangulation") {
  PolyMesh mesh = MeshOf(MakeBox(1, {1.0, 2.0, 3.0}));
  MeshTriangulation tri = TriangulateMesh(mesh);
  const HalfedgeId h = mesh.face(5).halfedge;
  const ESplitResult s = ESplit(&mesh, PolyMesh::EdgeOf(h), 0.5);
  REQUIRE(s.ok);
  RetriangulateFaces(mesh, {mesh.Face(h), mesh.Face(PolyMesh::Twin(h))}, &tri);
  const std::vector<VertexId> loop = FaceVertices(mesh, 5);
  const std::size_t at = std::find(loop.begin(), loop.end(), s.vertex) - loop.begin();
  REQUIRE(at < loop.size());
  const VConnectResult c = VConnect(&mesh, 5, s.vertex, loop[(at + 2) % loop.size()]);
  REQUIRE_MESSAGE(c.ok, c.message);
  RetriangulateFaces(mesh, {5, c.new_face}, &tri);
  const MeshTriangulation full = TriangulateMesh(mesh);
  REQUIRE(tri.by_face.size() == full.by_face.size());
  for (FaceId f = 0; f < full.by_face.size(); ++f) CHECK(tri.by_face[f] == full.by_face[f]);
  // Convex input stays convex: both parts of the split top face triangulate without slivers.
  for (FaceId f : {FaceId(5), c.new_face}) {
    for (const CornerTriangle& t : full.by_face[f]) {
      const Eigen::Vector3d a = mesh.vertex(mesh.Origin(t[0])).position;
      const double area =
          0.5 * (mesh.vertex(mesh.Origin(t[1])).position - a).cross(mesh.vertex(mesh.Origin(t[2])).position - a).norm();
      CHECK(area > 1e-6);
    }
  }
}

}  // namespace
}  // namespace facet
