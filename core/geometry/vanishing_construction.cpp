#include "core/geometry/vanishing_construction.h"

#include <cmath>
#include <limits>

#include <Eigen/Dense>

namespace facet {
namespace {

constexpr double kAtInfinityRatio = 1e-12;

bool IsFinitePoint(const Eigen::Vector3d& v) { return std::abs(v.z()) > kAtInfinityRatio * v.norm(); }

// Unit-normal form of a line (l0, l1 unit, l1 >= 0, else l0 > 0); zero stays zero.
Eigen::Vector3d NormalizedLine(Eigen::Vector3d l) {
  const double n = l.head<2>().norm();
  if (!(n > 0.0) || !l.allFinite()) return Eigen::Vector3d::Zero();
  l /= n;
  if (l.y() < 0.0 || (l.y() == 0.0 && l.x() < 0.0)) l = -l;
  return l;
}

// The orthocentre of the triangle a, b, c: the altitude from a is perpendicular to b - c,
// the one from b to a - c. False when the points are collinear.
bool Orthocentre(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c, Eigen::Vector2d* out) {
  Eigen::Matrix2d m;
  m.row(0) = (b - c).transpose();
  m.row(1) = (a - c).transpose();
  const Eigen::Vector2d rhs((b - c).dot(a), (a - c).dot(b));
  const double scale = (b - c).norm() * (a - c).norm();
  if (!(std::abs(m.determinant()) > 1e-12 * scale)) return false;
  *out = m.partialPivLu().solve(rhs);
  return out->allFinite();
}

Eigen::Vector2d FootOnLine(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d d = b - a;
  return a + d * ((p - a).dot(d) / d.squaredNorm());
}

}  // namespace

const char* VanishingConstructionKindName(VanishingConstructionKind kind) {
  switch (kind) {
    case VanishingConstructionKind::kNone: return "none";
    case VanishingConstructionKind::kOnePoint: return "one point";
    case VanishingConstructionKind::kTwoPoints: return "two points";
    case VanishingConstructionKind::kThreePoints: return "three points";
  }
  return "none";
}

FocalConstruction ConstructFocal(const Eigen::Vector2d& v_i_px, const Eigen::Vector2d& v_j_px,
                                 const Eigen::Vector2d& principal_point_px) {
  FocalConstruction c;
  const Eigen::Vector2d& p = principal_point_px;
  c.circle_center_px = 0.5 * (v_i_px + v_j_px);
  c.circle_radius_px = 0.5 * (v_j_px - v_i_px).norm();
  if (!(c.circle_radius_px > 0.0)) return c;
  c.altitude_foot_px = FootOnLine(p, v_i_px, v_j_px);
  const double f_squared = -(v_i_px - p).dot(v_j_px - p);
  if (!(f_squared > 0.0)) return c;
  c.focal_px = std::sqrt(f_squared);
  const Eigen::Vector2d& h = c.altitude_foot_px;
  // |h q|^2 = |h p|^2 + f^2 (the camera centre is f above p; h p is perpendicular to v_i v_j).
  const double hq = std::sqrt((p - h).squaredNorm() + f_squared);
  const Eigen::Vector2d side = (v_j_px - v_i_px) / (2.0 * c.circle_radius_px);
  Eigen::Vector2d towards_p = p - h;
  // p on the line v_i v_j: either normal serves.
  towards_p =
      towards_p.norm() > 1e-12 * c.circle_radius_px ? towards_p.normalized() : Eigen::Vector2d(-side.y(), side.x());
  c.turned_center_px = h + hq * towards_p;
  c.focal_end_px = p + c.focal_px * side;
  c.valid = true;
  return c;
}

VanishingConstruction ConstructFromVanishingPoints(const VanishingConstructionInput& input) {
  VanishingConstruction out;
  std::vector<int> finite_axes;
  for (int a = 0; a < 3; ++a) {
    const Eigen::Vector3d& v = input.vanishing_points_px[a];
    out.present[a] = v.squaredNorm() > 0.0 && v.allFinite();
    out.finite[a] = out.present[a] && !input.at_infinity[a] && IsFinitePoint(v);
    if (out.finite[a]) {
      out.points_px[a] = v.head<2>() / v.z();
      finite_axes.push_back(a);
    }
  }
  out.principal_point_px = input.assumed_principal_point_px;
  out.principal_point_assumed = true;
  const int num_finite = static_cast<int>(finite_axes.size());
  if (num_finite == 3 && Orthocentre(out.points_px[0], out.points_px[1], out.points_px[2], &out.principal_point_px)) {
    out.principal_point_assumed = false;
    out.kind = VanishingConstructionKind::kThreePoints;
    for (int k = 0; k < 3; ++k)
      out.altitude_feet_px[k] = FootOnLine(out.points_px[k], out.points_px[(k + 1) % 3], out.points_px[(k + 2) % 3]);
  } else if (num_finite >= 2) {
    out.kind = VanishingConstructionKind::kTwoPoints;
  } else if (num_finite == 1) {
    out.kind = VanishingConstructionKind::kOnePoint;
  } else if (out.present[0] || out.present[1] || out.present[2]) {
    out.kind = VanishingConstructionKind::kOnePoint;  // points at infinity only: nothing to construct
  }

  auto construct_pairs = [&]() {
    out.focal_constructions.clear();
    for (int i = 0; i < 3; ++i) {
      for (int j = i + 1; j < 3; ++j) {
        if (!out.finite[i] || !out.finite[j]) continue;
        FocalConstruction c = ConstructFocal(out.points_px[i], out.points_px[j], out.principal_point_px);
        c.axes = {i, j};
        out.focal_constructions.push_back(c);
      }
    }
  };
  construct_pairs();
  const auto any_valid = [&]() {
    for (const FocalConstruction& c : out.focal_constructions)
      if (c.valid) return true;
    return false;
  };
  if (num_finite == 3 && (out.kind != VanishingConstructionKind::kThreePoints || !any_valid())) {
    out.triangle_failed = true;
    out.kind = VanishingConstructionKind::kTwoPoints;
    out.principal_point_px = input.assumed_principal_point_px;
    out.principal_point_assumed = true;
    out.altitude_feet_px.fill(Eigen::Vector2d::Zero());
    construct_pairs();
  }
  // The smallest circle: its points are the nearest, so the best conditioned pair.
  double smallest_radius = std::numeric_limits<double>::infinity();
  for (const FocalConstruction& c : out.focal_constructions) {
    if (!c.valid || !(c.circle_radius_px < smallest_radius)) continue;
    smallest_radius = c.circle_radius_px;
    out.focal_px = c.focal_px;
    out.focal_assumed = false;
  }
  if (!(out.focal_px > 0.0) && input.assumed_focal_px > 0.0) {
    out.focal_px = input.assumed_focal_px;
    out.focal_assumed = true;
  }

  const double f = out.focal_px;
  const Eigen::Vector2d& p = out.principal_point_px;
  if (f > 0.0) {
    // K^-1 v for v = (x, y, w): ((x - cx w) / f, (y - cy w) / f, w).
    for (int a = 0; a < 3; ++a) {
      if (!out.present[a]) continue;
      Eigen::Vector3d v = input.vanishing_points_px[a];
      if (v.z() < 0.0) v = -v;
      const Eigen::Vector3d d((v.x() - p.x() * v.z()) / f, (v.y() - p.y() * v.z()) / f, v.z());
      out.directions_in_cam[a] = d.normalized();
    }
  }
  if (out.present[0] && out.present[1]) {
    out.horizon = NormalizedLine(input.vanishing_points_px[0].cross(input.vanishing_points_px[1]));
  } else if (out.present[2] && f > 0.0) {
    // omega v_z with omega = K^-T K^-1: the vanishing line of the planes normal to z.
    const Eigen::Vector3d d = out.directions_in_cam[2];
    out.horizon = NormalizedLine(Eigen::Vector3d(d.x() / f, d.y() / f, d.z() - (p.x() * d.x() + p.y() * d.y()) / f));
  }
  return out;
}

}  // namespace facet
