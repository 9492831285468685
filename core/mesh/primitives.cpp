#include "core/mesh/primitives.h"

#include <cmath>

#include <Eigen/Geometry>

#include "core/geometry/camera.h"
#include "core/mesh/box.h"
#include "core/util/input_limits.h"

namespace facet {

namespace {

constexpr double kPi = 3.14159265358979323846;

// The local topology and parameterisation of one primitive kind.
struct Template {
  std::vector<ParamCoefficients> coefficients;  // per vertex: p_in_primitive = C * params
  std::vector<std::vector<int>> polygons;       // counter-clockwise seen from outside
  std::vector<int> materials;
};

// Local position (x0 * params[0], x1 * params[1], x2 * params[2]): the boxy kinds.
ParamCoefficients Coeff(double x0, double x1, double x2) {
  ParamCoefficients c = ParamCoefficients::Zero();
  c(0, 0) = x0;
  c(1, 1) = x1;
  c(2, 2) = x2;
  return c;
}

Template BoxTemplate() {
  Template t;
  for (int i = 0; i < 8; ++i) t.coefficients.push_back(Coeff(i & 1, (i >> 1) & 1, (i >> 2) & 1));
  for (int f = 0; f < 6; ++f) {
    const auto& face = BoxFaces()[f];
    t.polygons.push_back({face[0], face[1], face[2], face[3]});
    t.materials.push_back(f);
  }
  return t;
}

// Bottom, the two slopes, the two gables (in that order, materials 0..4); the ridge is
// vertices 4 -> 5.
Template WedgeTemplate(bool ridge_along_y) {
  Template t;
  if (ridge_along_y) {
    t.coefficients = {Coeff(0, 0, 0),   Coeff(1, 0, 0),   Coeff(1, 1, 0),
                      Coeff(0, 1, 0),   Coeff(0.5, 0, 1), Coeff(0.5, 1, 1)};
    t.polygons = {{0, 3, 2, 1}, {0, 4, 5, 3}, {1, 2, 5, 4}, {0, 1, 4}, {2, 3, 5}};
  } else {
    t.coefficients = {Coeff(0, 0, 0),   Coeff(1, 0, 0),   Coeff(1, 1, 0),
                      Coeff(0, 1, 0),   Coeff(0, 0.5, 1), Coeff(1, 0.5, 1)};
    t.polygons = {{0, 3, 2, 1}, {0, 1, 5, 4}, {2, 3, 4, 5}, {0, 4, 3}, {1, 2, 5}};
  }
  t.materials = {0, 1, 2, 3, 4};
  return t;
}

Template PyramidTemplate() {
  Template t;
  t.coefficients = {Coeff(0, 0, 0), Coeff(1, 0, 0), Coeff(1, 1, 0), Coeff(0, 1, 0), Coeff(0.5, 0.5, 1)};
  t.polygons = {{0, 3, 2, 1}, {0, 1, 4}, {1, 2, 4}, {2, 3, 4}, {3, 0, 4}};
  t.materials = {0, 1, 2, 3, 4};
  return t;
}

Template PlaneTemplate() {
  Template t;
  t.coefficients = {Coeff(0, 0, 0), Coeff(1, 0, 0), Coeff(1, 1, 0), Coeff(0, 1, 0)};
  t.polygons = {{0, 1, 2, 3}};
  t.materials = {0};
  return t;
}

// Prism and cylinder: params (radius, height); vertex k at angle 2 pi k / n, bottom then top.
Template PrismTemplate(int n, bool cylinder) {
  Template t;
  for (int level = 0; level < 2; ++level) {
    for (int k = 0; k < n; ++k) {
      const double angle = 2.0 * kPi * k / n;
      ParamCoefficients c = ParamCoefficients::Zero();
      c(0, 0) = std::cos(angle);
      c(1, 0) = std::sin(angle);
      c(2, 1) = level;
      t.coefficients.push_back(c);
    }
  }
  std::vector<int> bottom, top;
  for (int k = 0; k < n; ++k) {
    bottom.push_back(n - 1 - k);
    top.push_back(n + k);
  }
  t.polygons.push_back(bottom);
  t.polygons.push_back(top);
  t.materials = {0, cylinder ? 0 : 1};
  for (int k = 0; k < n; ++k) {
    const int k1 = (k + 1) % n;
    t.polygons.push_back({k, k1, n + k1, n + k});
    t.materials.push_back(cylinder ? 1 : 2 + k);
  }
  return t;
}

int NumParams(PrimitiveKind kind) {
  switch (kind) {
    case PrimitiveKind::kPrism:
    case PrimitiveKind::kCylinder:
    case PrimitiveKind::kPlane: return 2;
    default: return 3;
  }
}

Template TemplateOf(const PrimitiveShape& p) {
  switch (p.kind) {
    case PrimitiveKind::kBox: return BoxTemplate();
    case PrimitiveKind::kWedge: return WedgeTemplate(p.ridge_along_y);
    case PrimitiveKind::kPyramid: return PyramidTemplate();
    case PrimitiveKind::kPlane: return PlaneTemplate();
    case PrimitiveKind::kPrism: return PrismTemplate(p.segments, false);
    case PrimitiveKind::kCylinder: return PrismTemplate(p.segments, true);
  }
  return BoxTemplate();
}

PrimitiveShape MakeSized(PrimitiveId id, PrimitiveKind kind, const Eigen::Vector3d& size) {
  PrimitiveShape p;
  p.id = id;
  p.kind = kind;
  p.params.head<3>() = size;
  return p;
}

}  // namespace

const char* PrimitiveKindName(PrimitiveKind kind) {
  switch (kind) {
    case PrimitiveKind::kBox: return "box";
    case PrimitiveKind::kWedge: return "wedge";
    case PrimitiveKind::kPrism: return "prism";
    case PrimitiveKind::kPyramid: return "pyramid";
    case PrimitiveKind::kCylinder: return "cylinder";
    case PrimitiveKind::kPlane: return "plane";
  }
  return "?";
}

PrimitiveShape MakeBox(PrimitiveId id, const Eigen::Vector3d& size) { return MakeSized(id, PrimitiveKind::kBox, size); }
PrimitiveShape MakeWedge(PrimitiveId id, const Eigen::Vector3d& size) {
  return MakeSized(id, PrimitiveKind::kWedge, size);
}
PrimitiveShape MakePyramid(PrimitiveId id, const Eigen::Vector3d& size) {
  return MakeSized(id, PrimitiveKind::kPyramid, size);
}
PrimitiveShape MakePlane(PrimitiveId id, double sx, double sy) {
  return MakeSized(id, PrimitiveKind::kPlane, Eigen::Vector3d(sx, sy, 0.0));
}
PrimitiveShape MakePrism(PrimitiveId id, int sides, double radius, double height) {
  PrimitiveShape p = MakeSized(id, PrimitiveKind::kPrism, Eigen::Vector3d(radius, height, 0.0));
  p.segments = sides;
  return p;
}
PrimitiveShape MakeCylinder(PrimitiveId id, int segments, double radius, double height) {
  PrimitiveShape p = MakeSized(id, PrimitiveKind::kCylinder, Eigen::Vector3d(radius, height, 0.0));
  p.segments = segments;
  return p;
}

Eigen::Vector3d PrimitiveLocalToWorld(const PrimitiveShape& primitive, const Eigen::Vector3d& p_in_primitive) {
  return RotationFromAngleAxis(primitive.rotation) * p_in_primitive + primitive.translation;
}

std::string PrimitiveSidesProblem(const PrimitiveShape& primitive) {
  if (primitive.segments <= kMaxPrimitiveSides) return "";
  return std::string("a ") + PrimitiveKindName(primitive.kind) + " may have at most " +
         std::to_string(kMaxPrimitiveSides) + " sides; this one has " + std::to_string(primitive.segments);
}

AddPrimitiveResult AddPrimitive(PolyMesh* mesh, const PrimitiveShape& primitive) {
  AddPrimitiveResult result;
  result.message = PrimitiveSidesProblem(primitive);
  if (!result.message.empty()) return result;
  const int num_params = NumParams(primitive.kind);
  for (int i = 0; i < num_params; ++i) {
    if (!(primitive.params[i] > 0.0) || !std::isfinite(primitive.params[i])) {
      result.message = std::string(PrimitiveKindName(primitive.kind)) + ": parameter " + std::to_string(i) +
                       " must be positive and finite";
      return result;
    }
  }
  const bool round = primitive.kind == PrimitiveKind::kPrism || primitive.kind == PrimitiveKind::kCylinder;
  if (round && primitive.segments < 3) {
    result.message = std::string(PrimitiveKindName(primitive.kind)) + ": needs at least 3 segments";
    return result;
  }
  const Template t = TemplateOf(primitive);
  const Eigen::Matrix3d world_from_primitive = RotationFromAngleAxis(primitive.rotation);
  std::vector<Eigen::Vector3d> local;
  for (const ParamCoefficients& c : t.coefficients) {
    const VertexId v = mesh->NewVertex();
    MeshVertex& vertex = mesh->vertex(v);
    vertex.primitive = primitive.id;
    vertex.local = LocalDefinition::Corner(c);
    local.push_back(vertex.LocalPosition(primitive.params));
    vertex.position = world_from_primitive * local.back() + primitive.translation;
    result.vertices.push_back(v);
  }
  result.faces = AddPolygons(mesh, result.vertices, t.polygons, t.materials, primitive.id, &result.message);
  if (result.faces.size() != t.polygons.size()) return result;  // templates are manifold: unreachable
  for (std::size_t i = 0; i < t.polygons.size(); ++i) {
    const auto& poly = t.polygons[i];
    const Eigen::Vector3d& p0 = local[poly[0]];
    const Eigen::Vector3d u = (local[poly[1]] - p0).normalized();
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();
    for (std::size_t k = 0; k < poly.size(); ++k) normal += local[poly[k]].cross(local[poly[(k + 1) % poly.size()]]);
    const Eigen::Vector3d v = normal.normalized().cross(u);
    for (HalfedgeId h : FaceHalfedges(*mesh, result.faces[i])) {
      const Eigen::Vector3d d = local[mesh->Origin(h) - result.vertices.front()] - p0;
      mesh->halfedge(h).uv = Eigen::Vector2d(d.dot(u), d.dot(v));
    }
  }
  result.ok = true;
  return result;
}

bool AttachOnTop(const PrimitiveShape& base, PrimitiveShape* top, std::string* message) {
  if (base.kind != PrimitiveKind::kBox) {
    if (message) *message = std::string("attach: the base must be a box, not a ") + PrimitiveKindName(base.kind);
    return false;
  }
  if (top->kind == PrimitiveKind::kPrism || top->kind == PrimitiveKind::kCylinder) {
    if (message) *message = std::string("attach: a ") + PrimitiveKindName(top->kind) + " has no rectangular footprint";
    return false;
  }
  top->params[0] = base.params[0];
  top->params[1] = base.params[1];
  top->rotation = base.rotation;
  top->translation = PrimitiveLocalToWorld(base, Eigen::Vector3d(0.0, 0.0, base.params[2]));
  return true;
}

void UpdatePrimitivePositions(PolyMesh* mesh, const PrimitiveShape& primitive) {
  const Eigen::Matrix3d world_from_primitive = RotationFromAngleAxis(primitive.rotation);
  for (VertexId v = 0; v < mesh->VertexIdEnd(); ++v) {
    if (!mesh->IsVertex(v) || mesh->vertex(v).primitive != primitive.id) continue;
    MeshVertex& vertex = mesh->vertex(v);
    vertex.position = world_from_primitive * vertex.LocalPosition(primitive.params) + primitive.translation;
  }
}

}  // namespace facet
