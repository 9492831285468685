#include "core/solve/model_sanity.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "core/solve/vertex_move.h"

namespace facet {

namespace {

// A millionfold: far beyond any real edit or any noise, far inside double range.
constexpr double kChangeRatio = 1e6;
// Growth of a size is refused sooner: runaways stop wherever the iteration budget ends, and
// were seen at 5e3-2e4 times the reach (a box 4 wide seen from 12 becoming 7e4-1.8e5 wide after 5
// iterations; the Strecha band box 223,663 wide), while a real change of scale that large
// comes only from a length the user typed, which raises the bound with it.
constexpr double kGrowthRatio = 1e3;

// The largest length the user fixed: known lengths (distance constraints), locked sizes and
// fixed points' distances from the origin. 0 when nothing fixes the scale.
double LargestGivenLength(const Project& project) {
  double given = 0.0;
  for (const Constraint& c : project.constraints) {
    if (c.kind == ConstraintKind::kDistance) given = std::max(given, std::abs(c.value));
    if (c.kind == ConstraintKind::kFixedPoint) given = std::max(given, c.point.norm());
  }
  for (const Primitive& p : project.primitives) {
    for (int k = 0; k < ShapeParamCount(p.shape.kind); ++k)
      if (p.param_locked[k]) given = std::max(given, std::abs(p.shape.params(k)));
  }
  return given;
}

bool Centroid(const Primitive& p, Eigen::Vector3d* centroid) {
  *centroid = Eigen::Vector3d::Zero();
  int n = 0;
  for (VertexId v = 0; v < p.mesh.VertexIdEnd(); ++v) {
    if (!p.mesh.IsVertex(v)) continue;
    *centroid += p.mesh.vertex(v).position;
    ++n;
  }
  if (n == 0) return false;
  *centroid /= n;
  return true;
}

std::string Describe(const char* what, const Primitive& p, double was, double now) {
  char text[200];
  std::snprintf(text, sizeof(text), "%s of '%s' would go from %.4g to %.4g", what, p.name.c_str(), was, now);
  return text;
}

}  // namespace

double PrimitiveReach(const Primitive& p, const Project& project) {
  double reach = 0.0;
  for (int k = 0; k < ShapeParamCount(p.shape.kind); ++k) reach = std::max(reach, std::abs(p.shape.params(k)));
  Eigen::Vector3d centroid;
  if (!Centroid(p, &centroid)) return reach;
  double nearest = std::numeric_limits<double>::infinity();
  for (const Image& image : project.images) nearest = std::min(nearest, (image.camera.CenterInWorld() - centroid).norm());
  return std::isfinite(nearest) ? std::max(reach, nearest) : reach;
}

ModelChangeCheck CheckModelChange(const Project& before, const Project& after) {
  ModelChangeCheck check;
  const double given = LargestGivenLength(after);
  check.scale_given = given > 0.0;
  for (const Primitive& p : after.primitives) {
    const Primitive* old = before.FindPrimitive(p.id);
    if (old == nullptr || old->shape.kind != p.shape.kind) continue;
    const double reach_after = PrimitiveReach(p, after);
    const double reach_before = PrimitiveReach(*old, before);
    for (int k = 0; k < ShapeParamCount(p.shape.kind); ++k) {
      const double was = old->shape.params(k), now = p.shape.params(k);
      if (now == was) continue;
      ModelChangeFault fault = ModelChangeFault::kNone;
      if (!(now > 0.0)) {
        fault = ModelChangeFault::kNonPositive;
      } else if (was > 0.0 && now < was / kChangeRatio && now < reach_after / kChangeRatio) {
        fault = ModelChangeFault::kCollapsed;
      } else if (reach_before > 0.0 && now > kGrowthRatio * std::max(reach_before, given)) {
        fault = ModelChangeFault::kGrew;
      }
      if (fault == ModelChangeFault::kNone) continue;
      check.fault = fault;
      check.what = Describe(ShapeParamLabel(p.shape.kind, k), p, was, now);
      return check;
    }
    Eigen::Vector3d from, to;
    if (reach_before > 0.0 && Centroid(*old, &from) && Centroid(p, &to)) {
      const double moved = (to - from).norm();
      // NaN positions fail this test as well: !(moved <= ...).
      if (!(moved <= kChangeRatio * reach_before)) {
        char text[200];
        std::snprintf(text, sizeof(text), "the centre of '%s' would move by %.4g, %.3g times its size or distance from the cameras",
                      p.name.c_str(), moved, moved / reach_before);
        check.fault = ModelChangeFault::kRanAway;
        check.what = text;
        return check;
      }
    }
  }
  return check;
}

}  // namespace facet
