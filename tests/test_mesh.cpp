// The polygon mesh (core/mesh/mesh.h), K_create primitives (core/mesh/primitives.h) and their
// triangulation (core/mesh/triangulate.h): invariants on every primitive kind, and
// Validate() naming exactly what a corrupted mesh breaks.
#include <doctest/doctest.h>

#include <cmath>
#include <set>
#include <string>

#include <Eigen/Geometry>

#include "core/geometry/camera.h"
#include "core/mesh/mesh.h"
#include "core/mesh/primitives.h"
#include "core/mesh/triangulate.h"

namespace facet {
namespace {

constexpr double kGeomTol = 1e-9;  // noise-free geometry, metres

std::vector<PrimitiveShape> AllKinds() {
  std::vector<PrimitiveShape> p = {MakeBox(1, {2.0, 3.0, 1.5}),   MakeWedge(2, {4.0, 2.0, 1.0}),
                                   MakePrism(3, 5, 1.2, 2.0),     MakePyramid(4, {2.0, 2.5, 1.8}),
                                   MakeCylinder(5, 12, 0.7, 3.0), MakePlane(6, 3.0, 2.0)};
  for (std::size_t i = 0; i < p.size(); ++i) {
    p[i].rotation = Eigen::Vector3d(0.1 * i, -0.2, 0.3);
    p[i].translation = Eigen::Vector3d(5.0 * i, 1.0, -2.0);
  }
  return p;
}

struct Expected {
  int v, e, f, euler;
};
Expected ExpectedCounts(const PrimitiveShape& p) {
  const int n = p.segments;
  switch (p.kind) {
    case PrimitiveKind::kBox: return {8, 12, 6, 2};
    case PrimitiveKind::kWedge: return {6, 9, 5, 2};
    case PrimitiveKind::kPyramid: return {5, 8, 5, 2};
    case PrimitiveKind::kPlane: return {4, 4, 1, 1};
    case PrimitiveKind::kPrism:
    case PrimitiveKind::kCylinder: return {2 * n, 3 * n, n + 2, 2};
  }
  return {};
}

// Signed volume of a closed mesh by the divergence theorem over the triangulation.
double SignedVolume(const PolyMesh& mesh) {
  double volume = 0.0;
  const MeshTriangulation t = TriangulateMesh(mesh);
  for (const auto& tris : t.by_face) {
    for (const CornerTriangle& c : tris) {
      const Eigen::Vector3d& a = mesh.vertex(mesh.Origin(c[0])).position;
      const Eigen::Vector3d& b = mesh.vertex(mesh.Origin(c[1])).position;
      const Eigen::Vector3d& d = mesh.vertex(mesh.Origin(c[2])).position;
      volume += a.dot(b.cross(d)) / 6.0;
    }
  }
  return volume;
}

double ExpectedVolume(const PrimitiveShape& p) {
  const double kPi = 3.14159265358979323846;
  switch (p.kind) {
    case PrimitiveKind::kBox: return p.params[0] * p.params[1] * p.params[2];
    case PrimitiveKind::kWedge: return 0.5 * p.params[0] * p.params[1] * p.params[2];
    case PrimitiveKind::kPyramid: return p.params[0] * p.params[1] * p.params[2] / 3.0;
    case PrimitiveKind::kPrism:
    case PrimitiveKind::kCylinder:
      return 0.5 * p.segments * p.params[0] * p.params[0] * std::sin(2.0 * kPi / p.segments) * p.params[1];
    case PrimitiveKind::kPlane: return 0.0;
  }
  return 0.0;
}

TEST_CASE("every primitive kind is a valid oriented manifold with the expected counts") {
  for (const PrimitiveShape& p : AllKinds()) {
    const std::string kind = PrimitiveKindName(p.kind);
    CAPTURE(kind);
    PolyMesh mesh;
    const AddPrimitiveResult r = AddPrimitive(&mesh, p);
    REQUIRE_MESSAGE(r.ok, r.message);
    const auto report = Validate(mesh);
    CHECK_MESSAGE(report.empty(), (report.empty() ? "" : report.front()));
    const Expected e = ExpectedCounts(p);
    CHECK(mesh.NumVertices() == e.v);
    CHECK(mesh.NumEdges() == e.e);
    CHECK(mesh.NumFaces() == e.f);
    CHECK(EulerCharacteristic(mesh) == e.euler);
    // Outward orientation: a closed primitive has its (positive) volume.
    if (p.kind == PrimitiveKind::kPlane) {
      // An open surface has no volume: its one face faces local +Z.
      const Eigen::Vector3d up = RotationFromAngleAxis(p.rotation) * Eigen::Vector3d::UnitZ();
      CHECK((FaceNormal(mesh, r.faces[0]) - up).norm() < kGeomTol);
      continue;
    }
    const double volume = SignedVolume(mesh);
    CAPTURE(volume);
    CHECK(std::abs(volume - ExpectedVolume(p)) < kGeomTol * std::max(1.0, ExpectedVolume(p)));
  }
}

TEST_CASE("a scene of several primitives keeps them as separate components") {
  PolyMesh mesh;
  int expected_euler = 0;
  for (const PrimitiveShape& p : AllKinds()) {
    REQUIRE(AddPrimitive(&mesh, p).ok);
    expected_euler += ExpectedCounts(p).euler;
  }
  CHECK(Validate(mesh).empty());
  CHECK(EulerCharacteristic(mesh) == expected_euler);
  for (FaceId f = 0; f < mesh.FaceIdEnd(); ++f) {
    for (VertexId v : FaceVertices(mesh, f)) CHECK(mesh.vertex(v).primitive == mesh.face(f).primitive);
  }
}

TEST_CASE("vertex world positions are the pose applied to local functions of the parameters") {
  for (PrimitiveShape p : AllKinds()) {
    const std::string kind = PrimitiveKindName(p.kind);
    CAPTURE(kind);
    PolyMesh mesh;
    const AddPrimitiveResult r = AddPrimitive(&mesh, p);
    REQUIRE(r.ok);
    p.params *= 1.7;
    p.translation += Eigen::Vector3d(0.5, -1.0, 2.0);
    const PolyMesh before = mesh;
    UpdatePrimitivePositions(&mesh, p);
    CHECK_FALSE(mesh == before);  // the update is not a no-op
    PolyMesh rebuilt;
    REQUIRE(AddPrimitive(&rebuilt, p).ok);
    for (VertexId v : r.vertices) {
      const double error = (mesh.vertex(v).position - rebuilt.vertex(v).position).norm();
      CAPTURE(error);
      CHECK(error < kGeomTol);
    }
  }
}

TEST_CASE("a wedge attached on top of a box follows the box when it is resized") {
  PrimitiveShape box = MakeBox(1, {2.0, 3.0, 1.5});
  box.rotation = Eigen::Vector3d(0.0, 0.0, 0.7);
  box.translation = Eigen::Vector3d(1.0, -2.0, 0.5);
  PrimitiveShape roof = MakeWedge(2, {1.0, 1.0, 0.8});
  std::string message;
  REQUIRE(AttachOnTop(box, &roof, &message));
  PolyMesh mesh;
  const AddPrimitiveResult b = AddPrimitive(&mesh, box);
  const AddPrimitiveResult w = AddPrimitive(&mesh, roof);
  REQUIRE((b.ok && w.ok));
  auto check_shared = [&](const char* when) {
    CAPTURE(when);
    // Wedge corners 0..3 are its footprint; box corners 4..7 (z = sz) its top face.
    const int box_top[4] = {4, 5, 7, 6};
    for (int i = 0; i < 4; ++i) {
      const double gap = (mesh.vertex(w.vertices[i]).position - mesh.vertex(b.vertices[box_top[i]]).position).norm();
      CAPTURE(gap);
      CHECK(gap < kGeomTol);
    }
  };
  check_shared("attached");
  const Eigen::Vector3d roof_apex_before = mesh.vertex(w.vertices[4]).position;
  box.params.head<3>() = Eigen::Vector3d(4.0, 1.0, 2.5);
  box.translation.z() += 1.0;
  REQUIRE(AttachOnTop(box, &roof, &message));
  UpdatePrimitivePositions(&mesh, box);
  UpdatePrimitivePositions(&mesh, roof);
  check_shared("after the box changed");
  CHECK((mesh.vertex(w.vertices[4]).position - roof_apex_before).norm() > 0.5);
  CHECK(roof.params[2] == 0.8);  // the roof keeps its own height
  PrimitiveShape cylinder = MakeCylinder(3, 8, 1.0, 1.0);
  const PrimitiveShape cylinder_before = cylinder;
  CHECK_FALSE(AttachOnTop(box, &cylinder, &message));
  CHECK(message.find("footprint") != std::string::npos);
  CHECK(cylinder.params == cylinder_before.params);
}

TEST_CASE("a wedge's ridge along y: a valid closed manifold of the same volume, ridge at x = sx / 2, on its box") {
  PrimitiveShape box = MakeBox(1, {2.0, 5.0, 1.5});
  box.rotation = Eigen::Vector3d(0.0, 0.0, 0.4);
  box.translation = Eigen::Vector3d(1.0, -2.0, 0.5);
  PrimitiveShape along_x = MakeWedge(2, {1.0, 1.0, 0.8});
  std::string message;
  REQUIRE(AttachOnTop(box, &along_x, &message));
  PrimitiveShape along_y = along_x;
  along_y.ridge_along_y = true;
  PolyMesh mx, my;
  REQUIRE(AddPrimitive(&mx, along_x).ok);
  REQUIRE(AddPrimitive(&my, along_y).ok);
  const auto report = Validate(my);
  CHECK_MESSAGE(report.empty(), (report.empty() ? "" : report.front()));
  CHECK(my.NumVertices() == 6);
  CHECK(my.NumEdges() == 9);
  CHECK(my.NumFaces() == 5);
  CHECK(EulerCharacteristic(my) == 2);
  // Outward faces: the same positive volume, sx * sy * sz / 2.
  CHECK(std::abs(SignedVolume(my) - 0.5 * 2.0 * 5.0 * 0.8) < kGeomTol);
  CHECK(std::abs(SignedVolume(my) - SignedVolume(mx)) < kGeomTol);
  // The ridge (vertices 4 -> 5) runs along the box's y side (5 long) over its middle; along x
  // it ran along the 2-long side.
  const Eigen::Vector3d box_y = RotationFromAngleAxis(box.rotation) * Eigen::Vector3d::UnitY();
  const Eigen::Vector3d ridge_y = my.vertex(5).position - my.vertex(4).position;
  CHECK((ridge_y - 5.0 * box_y).norm() < kGeomTol);
  CHECK(std::abs((mx.vertex(5).position - mx.vertex(4).position).norm() - 2.0) < kGeomTol);
  const Eigen::Vector3d top_middle = PrimitiveLocalToWorld(box, Eigen::Vector3d(1.0, 0.0, 1.5 + 0.8));
  CHECK((my.vertex(4).position - top_middle).norm() < kGeomTol);
  // The footprint is the box's top face either way.
  for (int i = 0; i < 4; ++i) CHECK((my.vertex(i).position - mx.vertex(i).position).norm() < kGeomTol);
}

TEST_CASE("AddPrimitive refuses bad parameters and leaves the mesh unchanged") {
  PolyMesh mesh;
  REQUIRE(AddPrimitive(&mesh, MakeBox(1, {1, 1, 1})).ok);
  const PolyMesh before = mesh;
  for (const PrimitiveShape& bad : {MakeBox(2, {1.0, 0.0, 1.0}), MakePrism(3, 2, 1.0, 1.0),
                                    MakeCylinder(4, 8, -1.0, 1.0), MakePlane(5, 1.0, NAN)}) {
    const AddPrimitiveResult r = AddPrimitive(&mesh, bad);
    CAPTURE(r.message);
    CHECK_FALSE(r.ok);
    CHECK_FALSE(r.message.empty());
    CHECK(mesh == before);
  }
}

TEST_CASE("mesh equality sees every field of live elements and ignores dead slots") {
  PolyMesh a;
  REQUIRE(AddPrimitive(&a, MakeBox(1, {1, 2, 3})).ok);
  CHECK(a == a);
  PolyMesh b = a;
  b.halfedge(3).uv.x() += 1e-12;
  CHECK_FALSE(a == b);
  b = a;
  b.face(2).material = 9;
  CHECK_FALSE(a == b);
  b = a;
  b.vertex(1).position.z() += 1e-12;
  CHECK_FALSE(a == b);
  b = a;
  b.vertex(1).local.t = 0.5;
  CHECK_FALSE(a == b);
  b = a;
  std::swap(b.halfedge(0).next, b.halfedge(2).next);
  CHECK_FALSE(a == b);
  b = a;
  const VertexId extra = b.NewVertex();
  CHECK_FALSE(a == b);
  b.KillVertex(extra);
  CHECK(a == b);  // a dead slot does not count
}

TEST_CASE("Validate names each kind of breakage") {
  PolyMesh good;
  REQUIRE(AddPrimitive(&good, MakeBox(1, {1, 2, 3})).ok);
  REQUIRE(Validate(good).empty());
  auto contains = [](const std::vector<std::string>& report, const std::string& text) {
    for (const auto& line : report) {
      if (line.find(text) != std::string::npos) return true;
    }
    return false;
  };
  const HalfedgeId h = good.face(0).halfedge;
  SUBCASE("next/prev inconsistency") {
    PolyMesh m = good;
    m.halfedge(h).prev = m.Next(h);
    const auto report = Validate(m);
    CHECK(contains(report, "next/prev inconsistency"));
  }
  SUBCASE("dangling twin") {
    PolyMesh m = good;
    m.halfedge(PolyMesh::Twin(h)).alive = false;
    CHECK(contains(Validate(m), "dangling twin"));
  }
  SUBCASE("inconsistent orientation") {
    PolyMesh m = good;
    m.halfedge(PolyMesh::Twin(h)).origin = m.Origin(h);
    CHECK(contains(Validate(m), "orientation"));
  }
  SUBCASE("face with fewer than 3 vertices") {
    PolyMesh m;
    std::vector<VertexId> v = {m.NewVertex(), m.NewVertex()};
    const EdgeId e = m.NewEdge();
    const FaceId f = m.NewFace();
    const FaceId g = m.NewFace();
    for (int side = 0; side < 2; ++side) {
      const HalfedgeId x = PolyMesh::EdgeHalfedge(e, side);
      m.halfedge(x).origin = v[side];
      m.halfedge(x).next = x;
      m.halfedge(x).prev = x;
      m.halfedge(x).face = side == 0 ? f : g;
      m.vertex(v[side]).halfedge = x;
    }
    m.face(f).halfedge = PolyMesh::EdgeHalfedge(e, 0);
    m.face(g).halfedge = PolyMesh::EdgeHalfedge(e, 1);
    CHECK(contains(Validate(m), "fewer than 3 vertices"));
  }
  SUBCASE("non-manifold edge: no face on either side") {
    PolyMesh m = good;
    const HalfedgeId t = PolyMesh::Twin(h);
    m.halfedge(h).face = kNoFace;
    m.halfedge(t).face = kNoFace;
    CHECK(contains(Validate(m), "non-manifold edge"));
  }
  SUBCASE("non-manifold vertex: two cones glued at a tip") {
    PolyMesh m;
    std::vector<VertexId> v;
    for (int i = 0; i < 7; ++i) v.push_back(m.NewVertex());
    std::string message;
    // Two closed tetrahedra sharing only vertex 0.
    REQUIRE(AddPolygons(&m, v, {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}, {0, 5, 4}, {0, 4, 6}, {4, 5, 6}, {0, 6, 5}},
                        {}, 1, &message)
                .size() == 8);
    CHECK(contains(Validate(m), "non-manifold vertex"));
  }
}

TEST_CASE("AddPolygons refuses inconsistent orientation and changes nothing") {
  PolyMesh m;
  std::vector<VertexId> v;
  for (int i = 0; i < 4; ++i) v.push_back(m.NewVertex());
  const PolyMesh before = m;
  std::string message;
  CHECK(AddPolygons(&m, v, {{0, 1, 2}, {0, 1, 3}}, {}, 1, &message).empty());
  CHECK(message.find("orientation") != std::string::npos);
  CHECK(m == before);
}

TEST_CASE("triangulation: n - 2 triangles per face, oriented with the face, each mapped once") {
  PolyMesh mesh;
  for (const PrimitiveShape& p : AllKinds()) REQUIRE(AddPrimitive(&mesh, p).ok);
  const MeshTriangulation t = TriangulateMesh(mesh);
  const FlatTriangles flat = Flatten(mesh, t);
  int expected = 0;
  for (FaceId f = 0; f < mesh.FaceIdEnd(); ++f) expected += FaceDegree(mesh, f) - 2;
  CHECK(static_cast<int>(flat.triangles.size()) == expected);
  std::set<int> covered;
  for (FaceId f = 0; f < mesh.FaceIdEnd(); ++f) {
    const Eigen::Vector3d normal = FaceNormal(mesh, f);
    double area = 0.0;
    for (std::size_t k = 0; k < t.by_face[f].size(); ++k) {
      const int index = flat.first_triangle[f] + static_cast<int>(k);
      CHECK(flat.triangle_face[index] == f);
      CHECK(covered.insert(index).second);
      const CornerTriangle& c = t.by_face[f][k];
      for (HalfedgeId h : c) CHECK(mesh.Face(h) == f);
      const Eigen::Vector3d& a = mesh.vertex(mesh.Origin(c[0])).position;
      const Eigen::Vector3d tri_normal =
          (mesh.vertex(mesh.Origin(c[1])).position - a).cross(mesh.vertex(mesh.Origin(c[2])).position - a);
      CAPTURE(f);
      CHECK(tri_normal.dot(normal) > 0.0);
      area += 0.5 * tri_normal.norm();
    }
    // Planar faces: the triangles tile the face (Newell area).
    Eigen::Vector3d newell = Eigen::Vector3d::Zero();
    for (HalfedgeId h : FaceHalfedges(mesh, f)) {
      newell += mesh.vertex(mesh.Origin(h)).position.cross(mesh.vertex(mesh.Dest(h)).position);
    }
    CHECK(std::abs(area - 0.5 * newell.norm()) < kGeomTol * std::max(1.0, area));
  }
  CHECK(static_cast<int>(covered.size()) == expected);
}

TEST_CASE("ear clipping handles a non-convex face (L shape)") {
  PolyMesh m;
  std::vector<VertexId> v;
  const std::vector<Eigen::Vector2d> l = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
  for (const auto& p : l) {
    v.push_back(m.NewVertex());
    m.vertex(v.back()).position = Eigen::Vector3d(p.x(), p.y(), 0.0);
  }
  std::string message;
  REQUIRE(AddPolygons(&m, v, {{0, 1, 2, 3, 4, 5}}, {}, 1, &message).size() == 1);
  const auto tris = TriangulateFace(m, 0);
  REQUIRE(tris.size() == 4);
  double area = 0.0;
  for (const auto& c : tris) {
    const Eigen::Vector3d a = m.vertex(m.Origin(c[0])).position;
    const Eigen::Vector3d n = (m.vertex(m.Origin(c[1])).position - a).cross(m.vertex(m.Origin(c[2])).position - a);
    CHECK(n.z() > 0.0);
    area += 0.5 * n.z();
  }
  CHECK(std::abs(area - 3.0) < kGeomTol);
}

}  // namespace
}  // namespace facet
