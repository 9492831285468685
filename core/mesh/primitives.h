// K_create: parametric primitives (Facade style) added to a scene mesh. Every vertex's
// local position is a linear function of the primitive's parameters (LocalDefinition), and
// world = R * local + t with R from the angle-axis `rotation` (core/geometry/conventions.h).
//
// A PolyMesh may hold any number of primitives as disjoint components (a project keeps one
// mesh per primitive, core/scene/project.h); vertices
// and faces carry their primitive's id. Faces are counter-clockwise seen from outside, so
// FaceNormal points outwards. Local frame: Z up; boxes, wedges, pyramids and planes span
// [0, sx] x [0, sy] from the local origin; prisms and cylinders are centred on the local Z axis.
//
// Attachment is a pose/footprint rule (AttachOnTop) re-applied after each change of the
// base; the mesh keeps the primitives as separate components. Face extrusion is in
// core/mesh/extrude.h.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/mesh/mesh.h"

namespace facet {

enum class PrimitiveKind { kBox, kWedge, kPrism, kPyramid, kCylinder, kPlane };
const char* PrimitiveKindName(PrimitiveKind kind);

// Parameters, in world units, by kind (unused entries stay 0):
//   kBox      (sx, sy, sz)
//   kWedge    (sx, sy, sz): triangular prism, ridge along x at y = sy / 2, height sz (gable roof);
//             with ridge_along_y, the ridge runs along y at x = sx / 2 (the same footprint)
//   kPrism    (radius, height), `segments` sides (>= 3), circumscribed radius
//   kCylinder (radius, height), `segments` sides (>= 3); side faces share material 1
//   kPyramid  (sx, sy, height): rectangular base, apex above the base centre
//   kPlane    (sx, sy): one quad at local z = 0 facing +Z, with a boundary
struct PrimitiveShape {
  PrimitiveId id = 0;
  PrimitiveKind kind = PrimitiveKind::kBox;
  PrimitiveParams params = PrimitiveParams::Zero();
  int segments = 0;
  // kWedge only: the ridge along local y (the gables face -y, +y) instead of x. It chooses the
  // vertices' local definitions, so changing it means building the mesh again.
  bool ridge_along_y = false;
  Eigen::Vector3d rotation = Eigen::Vector3d::Zero();     // world_from_primitive, angle-axis
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();  // world_from_primitive
};

PrimitiveShape MakeBox(PrimitiveId id, const Eigen::Vector3d& size);
PrimitiveShape MakeWedge(PrimitiveId id, const Eigen::Vector3d& size);
PrimitiveShape MakePrism(PrimitiveId id, int sides, double radius, double height);
PrimitiveShape MakeCylinder(PrimitiveId id, int segments, double radius, double height);
PrimitiveShape MakePyramid(PrimitiveId id, const Eigen::Vector3d& size);
PrimitiveShape MakePlane(PrimitiveId id, double sx, double sy);

struct AddPrimitiveResult {
  bool ok = false;
  std::string message;
  std::vector<VertexId> vertices;
  std::vector<FaceId> faces;
};

// Empty when the primitive's side count is within kMaxPrimitiveSides (core/util/input_limits.h),
// else the refusal that names the limit ("a cylinder may have at most 1024 sides; this one
// has 100000"). The project reader, AddPrimitive and the GUI check it where a count enters.
std::string PrimitiveSidesProblem(const PrimitiveShape& primitive);

// K_create: adds the primitive's vertices and faces to the mesh with world positions from
// its pose, per-corner UVs (the corner's local position projected on the face's first edge
// and its in-plane normal, in world units) and per-face materials (face index, or 0/1 for
// caps/sides of a cylinder). Refuses non-positive dimensions, too few segments and more
// than kMaxPrimitiveSides.
AddPrimitiveResult AddPrimitive(PolyMesh* mesh, const PrimitiveShape& primitive);

// Recomputes the world positions of every vertex of `primitive.id` from its local
// definitions, parameters and pose, e.g. after the solve changed its dimensions. O(V).
void UpdatePrimitivePositions(PolyMesh* mesh, const PrimitiveShape& primitive);

// Sets `top` on the top face of the box `base`: top's footprint (params 0 and 1) becomes the
// box's (sx, sy) and its pose the box's, raised by sz, so the top's bottom corners coincide
// with the box's top corners. Call it again whenever the box changes ("one drag moves both").
// Refuses a base that is not a box and a top kind without a rectangular [0, sx] x [0, sy]
// footprint (prism, cylinder); `top` is then unchanged.
bool AttachOnTop(const PrimitiveShape& base, PrimitiveShape* top, std::string* message);

Eigen::Vector3d PrimitiveLocalToWorld(const PrimitiveShape& primitive, const Eigen::Vector3d& p_in_primitive);

}  // namespace facet
