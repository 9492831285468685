// Random user edits on a project, for the suites that need a varied history (the document's
// undo model, the recovery file): insertions, modifications and removals in every list, K-ops
// on meshes, units, attachments. Header-only, in an anonymous namespace per suite.
#pragma once

#include <doctest/doctest.h>

#include <algorithm>
#include <random>
#include <string>
#include <vector>

#include "core/mesh/extrude.h"
#include "core/mesh/operators.h"
#include "core/scene/project.h"

namespace facet::testing {
namespace {

using facet::Axis;
using facet::Constraint;
using facet::ConstraintKind;
using facet::Image;
using facet::Pin;
using facet::PolyMesh;
using facet::Primitive;
using facet::PrimitiveShape;
using facet::PrincipalPointMode;
using facet::Project;
using facet::Segment;
using facet::VertexId;
using facet::VertexRef;

double Real(std::mt19937& rng, double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }
size_t Pick(std::mt19937& rng, size_t n) {  // in [0, n)
  return std::uniform_int_distribution<size_t>(0, n - 1)(rng);
}

template <typename T>
void InsertAtRandom(std::vector<T>* list, const T& item, std::mt19937& rng) {
  list->insert(list->begin() + static_cast<std::ptrdiff_t>(Pick(rng, list->size() + 1)), item);
}

PrimitiveShape RandomShape(std::mt19937& rng) {
  const Eigen::Vector3d size{Real(rng, 0.1, 10), Real(rng, 0.1, 10), Real(rng, 0.1, 10)};
  PrimitiveShape shape;
  switch (Pick(rng, 6)) {
    case 0: shape = facet::MakeBox(facet::kNoId, size); break;
    case 1: shape = facet::MakeWedge(facet::kNoId, size); break;
    case 2: shape = facet::MakePrism(facet::kNoId, 3 + static_cast<int>(Pick(rng, 6)), size.x(), size.y()); break;
    case 3: shape = facet::MakePyramid(facet::kNoId, size); break;
    case 4: shape = facet::MakeCylinder(facet::kNoId, 3 + static_cast<int>(Pick(rng, 12)), size.x(), size.y()); break;
    default: shape = facet::MakePlane(facet::kNoId, size.x(), size.y()); break;
  }
  shape.rotation = {Real(rng, -0.5, 0.5), Real(rng, -0.5, 0.5), Real(rng, -3, 3)};
  shape.translation = {Real(rng, -5, 5), Real(rng, -5, 5), Real(rng, -5, 5)};
  return shape;
}

// Live ids below End(), in id order.
std::vector<VertexId> LiveVertices(const PolyMesh& mesh) {
  std::vector<VertexId> out;
  for (VertexId v = 0; v < mesh.VertexIdEnd(); ++v)
    if (mesh.IsVertex(v)) out.push_back(v);
  return out;
}
std::vector<facet::EdgeId> LiveEdges(const PolyMesh& mesh) {
  std::vector<facet::EdgeId> out;
  for (facet::EdgeId e = 0; e < mesh.EdgeIdEnd(); ++e)
    if (mesh.IsEdge(e)) out.push_back(e);
  return out;
}
std::vector<facet::FaceId> LiveFaces(const PolyMesh& mesh) {
  std::vector<facet::FaceId> out;
  for (facet::FaceId f = 0; f < mesh.FaceIdEnd(); ++f)
    if (mesh.IsFace(f)) out.push_back(f);
  return out;
}

VertexRef RandomVertex(const Project& p, std::mt19937& rng) {
  const Primitive& prim = p.primitives[Pick(rng, p.primitives.size())];
  const std::vector<VertexId> live = LiveVertices(prim.mesh);
  return {prim.id, live[Pick(rng, live.size())]};
}

bool NamesVertexOf(const std::vector<VertexRef>& refs, facet::Id primitive_id, VertexId v) {
  return std::any_of(refs.begin(), refs.end(),
                     [&](const VertexRef& r) { return r.primitive_id == primitive_id && r.vertex == v; });
}

// Removes what refers to a primitive that is gone (pins, constraints, attachments).
void DropReferencesTo(Project* p, facet::Id id) {
  std::erase_if(p->pins, [id](const Pin& pin) { return pin.vertex.primitive_id == id; });
  std::erase_if(p->constraints, [id](const Constraint& c) {
    return std::any_of(c.vertices.begin(), c.vertices.end(), [id](const VertexRef& r) { return r.primitive_id == id; });
  });
  for (Primitive& other : p->primitives)
    if (other.attached_to == id) other.attached_to = facet::kNoId;
}

size_t VertexCountOf(ConstraintKind kind, std::mt19937& rng) {
  switch (kind) {
    case ConstraintKind::kCoplanar: return 4 + Pick(rng, 3);
    case ConstraintKind::kCollinear: return 3 + Pick(rng, 2);
    case ConstraintKind::kParallel:
    case ConstraintKind::kPerpendicular:
    case ConstraintKind::kEqualLength: return 4;
    case ConstraintKind::kFixedPoint: return 1;
    default: return 2;
  }
}

// A K-op on a copy of one primitive's mesh (E_split, V_connect, V_delete of a split vertex
// nothing refers to, or a face extrusion), written back whole: how the app commits them.
void RandomKOp(Project* p, std::mt19937& rng) {
  Primitive& prim = p->primitives[Pick(rng, p->primitives.size())];
  PolyMesh mesh = prim.mesh;
  switch (Pick(rng, 4)) {
    case 0: {
      const auto edges = LiveEdges(mesh);
      const auto edge = edges[Pick(rng, edges.size())];
      if (!facet::ESplit(&mesh, edge, Real(rng, 0.05, 0.95)).ok) return;
      break;
    }
    case 1: {
      const auto faces = LiveFaces(mesh);
      const facet::FaceId f = faces[Pick(rng, faces.size())];
      const std::vector<VertexId> loop = facet::FaceVertices(mesh, f);
      const size_t n = loop.size();
      if (n < 4) return;
      const size_t i = Pick(rng, n), j = (i + 2 + Pick(rng, n - 3)) % n;
      if (!facet::VConnect(&mesh, f, loop[i], loop[j]).ok) return;
      break;
    }
    case 2: {
      std::vector<VertexId> candidates;
      for (VertexId v : LiveVertices(mesh)) {
        const VertexRef ref{prim.id, v};
        const bool referenced =
            std::any_of(p->pins.begin(), p->pins.end(), [&](const Pin& pin) { return pin.vertex == ref; }) ||
            std::any_of(p->constraints.begin(), p->constraints.end(),
                        [&](const Constraint& c) { return NamesVertexOf(c.vertices, prim.id, v); });
        if (mesh.vertex(v).local.on_edge && !referenced) candidates.push_back(v);
      }
      if (candidates.empty() || !facet::VDelete(&mesh, candidates[Pick(rng, candidates.size())]).ok) return;
      break;
    }
    default: {
      const auto faces = LiveFaces(mesh);
      const auto face = faces[Pick(rng, faces.size())];
      if (!facet::ExtrudeFace(&mesh, prim.shape, face, Real(rng, -1, 1)).ok) return;
      break;
    }
  }
  prim.mesh = std::move(mesh);
}

// One random user edit: 1 to 3 insertions, modifications or removals at random positions in
// any of the five lists (removing an image or a primitive also removes what refers to it), a
// K-op on a primitive's mesh, a change of units, or an id drawn and left unused.
Project RandomEdit(const Project& start, std::mt19937& rng) {
  Project p = start;
  const int ops = 1 + static_cast<int>(Pick(rng, 3));
  for (int op = 0; op < ops; ++op) {
    switch (Pick(rng, 20)) {
      case 0: {
        Image im;
        im.id = p.NewId();
        im.path = "img" + std::to_string(im.id) + ".jpg";
        im.width_px = 100 + static_cast<int>(Pick(rng, 4000));
        im.height_px = 100 + static_cast<int>(Pick(rng, 3000));
        im.camera.focal_px = Real(rng, 100, 5000);
        InsertAtRandom(&p.images, im, rng);
        break;
      }
      case 1: {
        if (p.images.empty()) break;
        Segment s;
        s.id = p.NewId();
        s.image_id = p.images[Pick(rng, p.images.size())].id;
        s.axis = static_cast<Axis>(Pick(rng, 3));
        s.a_px = {Real(rng, 0, 1000), Real(rng, 0, 1000)};
        s.b_px = {Real(rng, 0, 1000), Real(rng, 0, 1000)};
        InsertAtRandom(&p.segments, s, rng);
        break;
      }
      case 2: {
        facet::Id id = facet::kNoId;
        std::string message;
        REQUIRE_MESSAGE(facet::AddPrimitiveToProject(&p, RandomShape(rng), "primitive", &id, &message), message);
        Primitive added = std::move(p.primitives.back());
        p.primitives.pop_back();
        added.name = "primitive " + std::to_string(id);
        InsertAtRandom(&p.primitives, added, rng);
        break;
      }
      case 3: {
        if (p.images.empty() || p.primitives.empty()) break;
        Pin pin;
        pin.id = p.NewId();
        pin.image_id = p.images[Pick(rng, p.images.size())].id;
        pin.vertex = RandomVertex(p, rng);
        pin.uv_px = {Real(rng, 0, 1000), Real(rng, 0, 1000)};
        InsertAtRandom(&p.pins, pin, rng);
        break;
      }
      case 4: {
        if (p.images.empty()) break;
        Image& im = p.images[Pick(rng, p.images.size())];
        im.camera.focal_px = Real(rng, 100, 5000);
        im.camera.principal_point_px.x() = Real(rng, 0, 100);
        im.camera_calibrated = !im.camera_calibrated;
        im.principal_point_mode = static_cast<PrincipalPointMode>(Pick(rng, 3));
        im.focal_locked = !im.focal_locked;
        break;
      }
      case 5: {
        if (p.segments.empty()) break;
        Segment& s = p.segments[Pick(rng, p.segments.size())];
        s.a_px.y() = Real(rng, 0, 1000);
        s.axis = static_cast<Axis>(Pick(rng, 3));
        break;
      }
      case 6: {
        if (p.primitives.empty()) break;
        Primitive& prim = p.primitives[Pick(rng, p.primitives.size())];
        prim.shape.translation = {Real(rng, -5, 5), Real(rng, -5, 5), Real(rng, -5, 5)};
        prim.shape.params[0] *= Real(rng, 0.5, 2.0);
        prim.param_locked[Pick(rng, 3)] ^= true;
        prim.rotation_locked = !prim.rotation_locked;
        facet::RefreshPrimitive(&p, &prim);
        break;
      }
      case 7: {
        if (p.pins.empty()) break;
        Pin& pin = p.pins[Pick(rng, p.pins.size())];
        pin.uv_px.x() = Real(rng, 0, 1000);
        pin.vertex = RandomVertex(p, rng);
        break;
      }
      case 8: {
        if (p.images.empty()) break;
        const size_t i = Pick(rng, p.images.size());
        const facet::Id id = p.images[i].id;
        p.images.erase(p.images.begin() + static_cast<std::ptrdiff_t>(i));
        std::erase_if(p.segments, [id](const Segment& s) { return s.image_id == id; });
        std::erase_if(p.pins, [id](const Pin& pin) { return pin.image_id == id; });
        std::erase_if(p.constraints, [id](const Constraint& c) { return c.image_id == id; });
        break;
      }
      case 9: {
        if (p.segments.empty()) break;
        p.segments.erase(p.segments.begin() + static_cast<std::ptrdiff_t>(Pick(rng, p.segments.size())));
        break;
      }
      case 10: {
        if (p.primitives.empty()) break;
        const size_t i = Pick(rng, p.primitives.size());
        const facet::Id id = p.primitives[i].id;
        p.primitives.erase(p.primitives.begin() + static_cast<std::ptrdiff_t>(i));
        DropReferencesTo(&p, id);
        break;
      }
      case 11: {
        if (p.pins.empty()) break;
        p.pins.erase(p.pins.begin() + static_cast<std::ptrdiff_t>(Pick(rng, p.pins.size())));
        break;
      }
      case 12: p.units = p.units == "m" ? "ft" : "m"; break;
      case 13: p.NewId(); break;
      case 14:
      case 15: {
        if (p.primitives.empty()) break;
        RandomKOp(&p, rng);
        break;
      }
      case 16: {
        if (p.primitives.empty()) break;
        Constraint c;
        c.id = p.NewId();
        c.kind = static_cast<ConstraintKind>(Pick(rng, 9));
        for (size_t k = VertexCountOf(c.kind, rng); k > 0; --k) c.vertices.push_back(RandomVertex(p, rng));
        c.value = Real(rng, 0.1, 10);
        c.point = {Real(rng, -5, 5), Real(rng, -5, 5), Real(rng, -5, 5)};
        c.axis = static_cast<Axis>(Pick(rng, 3));
        if (c.kind == ConstraintKind::kEdgeOnImageLine && !p.images.empty()) {
          c.image_id = p.images[Pick(rng, p.images.size())].id;
          c.line_a_px = {Real(rng, 0, 1000), Real(rng, 0, 1000)};
          c.line_b_px = {Real(rng, 0, 1000), Real(rng, 0, 1000)};
        }
        InsertAtRandom(&p.constraints, c, rng);
        break;
      }
      case 17: {
        if (p.constraints.empty()) break;
        Constraint& c = p.constraints[Pick(rng, p.constraints.size())];
        c.value = Real(rng, 0.1, 10);
        c.vertices[Pick(rng, c.vertices.size())] = RandomVertex(p, rng);
        break;
      }
      case 18: {
        if (p.constraints.empty()) break;
        p.constraints.erase(p.constraints.begin() + static_cast<std::ptrdiff_t>(Pick(rng, p.constraints.size())));
        break;
      }
      case 19: {
        // Attach one primitive on a box, or detach it.
        if (p.primitives.size() < 2) break;
        Primitive& top = p.primitives[Pick(rng, p.primitives.size())];
        const Primitive& base = p.primitives[Pick(rng, p.primitives.size())];
        if (top.attached_to != facet::kNoId) {
          top.attached_to = facet::kNoId;
        } else if (base.id != top.id && base.attached_to == facet::kNoId &&
                   base.shape.kind == facet::PrimitiveKind::kBox &&
                   facet::AttachOnTop(base.shape, &top.shape, nullptr)) {
          top.attached_to = base.id;
          facet::RefreshPrimitive(&p, &top);
        }
        break;
      }
    }
  }
  return p;
}

}  // namespace
}  // namespace facet::testing
