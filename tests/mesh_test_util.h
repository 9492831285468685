// Shared fixtures of the mesh-operator tests: one posed primitive of every kind, a mesh
// built from one, and CHECK_VALID, which prints Validate()'s first complaint.
#pragma once

#include <string>
#include <vector>

#include <doctest/doctest.h>

#include "core/mesh/mesh.h"
#include "core/mesh/primitives.h"

namespace facet::testing {

// Every kind, each with its own rotation and translation so that no axis is special.
inline std::vector<PrimitiveShape> AllKinds() {
  std::vector<PrimitiveShape> p = {MakeBox(1, {2.0, 3.0, 1.5}),  MakeWedge(2, {4.0, 2.0, 1.0}),
                                   MakePrism(3, 5, 1.2, 2.0),    MakePyramid(4, {2.0, 2.5, 1.8}),
                                   MakeCylinder(5, 7, 0.7, 3.0), MakePlane(6, 3.0, 2.0)};
  for (std::size_t i = 0; i < p.size(); ++i) {
    p[i].rotation = Eigen::Vector3d(0.1 * i, -0.2, 0.3);
    p[i].translation = Eigen::Vector3d(5.0 * i, 1.0, -2.0);
  }
  return p;
}

inline PolyMesh MeshOf(const PrimitiveShape& p) {
  PolyMesh mesh;
  const AddPrimitiveResult r = AddPrimitive(&mesh, p);
  REQUIRE_MESSAGE(r.ok, r.message);
  return mesh;
}

inline std::string FirstProblem(const PolyMesh& mesh) {
  const auto report = Validate(mesh);
  return report.empty() ? std::string() : report.front();
}

}  // namespace facet::testing

#define CHECK_VALID(mesh)                                             \
  do {                                                                \
    const std::string problem = ::facet::testing::FirstProblem(mesh); \
    CHECK_MESSAGE(problem.empty(), problem);                          \
  } while (0)
