// The ruler-and-compass construction behind calibration from vanishing points, as a course
// draws it (Caprile & Torre 1990; Hartley & Zisserman, 2nd ed., section 8.8, example 8.27):
// the vanishing points of three orthogonal directions form the vanishing triangle, whose
// orthocentre is the principal point p. For a side v_i v_j, the camera centre C sees v_i and
// v_j at a right angle, so C turned about the line v_i v_j into the image plane lands on the
// circle with v_i v_j as diameter (Thales), at q on the perpendicular to v_i v_j through the
// foot h of the altitude (which passes through p). Then |h q|^2 = |h p|^2 + f^2: the point s
// on the line through p parallel to v_i v_j with |h s| = |h q| gives f = |p s|, the same as
// f^2 = -(v_i - p).(v_j - p). With two vanishing points the principal point is assumed (the
// image centre or a given point) and the same construction gives f; with one, f is assumed
// too. The horizon is the vanishing line of the ground plane: the line through the x and y
// vanishing points, or omega v_z (omega = K^-T K^-1, the image of the absolute conic) when
// one of them is missing.
// Pixels and frames: core/geometry/conventions.h. Every point is an image point in px.
#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>

namespace facet {

enum class VanishingConstructionKind {
  kNone,         // no vanishing point
  kOnePoint,     // one finite vanishing point: principal point and focal length assumed
  kTwoPoints,    // two finite: principal point assumed, focal length constructed
  kThreePoints,  // three finite: principal point (orthocentre) and focal length constructed
};
const char* VanishingConstructionKindName(VanishingConstructionKind kind);

struct VanishingConstructionInput {
  // Homogeneous vanishing point per world axis (x, y, z) in px; the zero vector when the
  // family is absent. A point whose third coordinate is below 1e-12 of its norm is at
  // infinity: it takes no part in the triangle or the focal construction.
  std::array<Eigen::Vector3d, 3> vanishing_points_px{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                                                     Eigen::Vector3d::Zero()};
  // The principal point when fewer than three finite points fix it (e.g. the image centre).
  Eigen::Vector2d assumed_principal_point_px = Eigen::Vector2d::Zero();
  // The focal length when fewer than two finite points fix it (a known lens, EXIF); 0: none.
  double assumed_focal_px = 0.0;
  // Points the caller treats as at infinity although their third coordinate is not zero
  // (e.g. the calibration's VpCalibrationSummary::vanishing_point_at_infinity: a point 1e5
  // image sizes out is a direction, not a vertex of a usable triangle).
  std::array<bool, 3> at_infinity = {false, false, false};
};

// The construction of f on one pair of finite vanishing points v_i, v_j (axes i < j).
struct FocalConstruction {
  std::array<int, 2> axes = {0, 1};
  Eigen::Vector2d circle_center_px = Eigen::Vector2d::Zero();  // midpoint of v_i v_j
  double circle_radius_px = 0.0;                               // |v_i - v_j| / 2
  Eigen::Vector2d altitude_foot_px = Eigen::Vector2d::Zero();  // h: p projected onto line v_i v_j
  // q: the camera centre turned about v_i v_j into the image plane, on the circle and on the
  // ray from h through p (beyond p).
  Eigen::Vector2d turned_center_px = Eigen::Vector2d::Zero();
  // s: on the line through p parallel to v_i v_j, |h s| = |h q|; |p s| = f.
  Eigen::Vector2d focal_end_px = Eigen::Vector2d::Zero();
  double focal_px = 0.0;
  // False when f^2 = -(v_i - p).(v_j - p) <= 0 (p outside the circle: no real camera sees
  // these two points at a right angle); the points above are then not set.
  bool valid = false;
};

struct VanishingConstruction {
  VanishingConstructionKind kind = VanishingConstructionKind::kNone;
  std::array<bool, 3> present = {false, false, false};
  std::array<bool, 3> finite = {false, false, false};
  std::array<Eigen::Vector2d, 3> points_px{Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero(),
                                           Eigen::Vector2d::Zero()};  // the finite points
  // The orthocentre (kThreePoints) or the assumed point.
  Eigen::Vector2d principal_point_px = Eigen::Vector2d::Zero();
  bool principal_point_assumed = true;
  // Three finite points whose triangle gives no camera (collinear points, or an orthocentre
  // outside every pair's circle: an obtuse triangle, typically one point nearly at infinity):
  // the construction then falls back to kTwoPoints with the assumed principal point.
  bool triangle_failed = false;
  // kThreePoints: per vertex axis k, the foot of the altitude from v_k onto the opposite side.
  std::array<Eigen::Vector2d, 3> altitude_feet_px{Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero(),
                                                  Eigen::Vector2d::Zero()};
  // One per pair of finite points: (x, y), (x, z), (y, z) in that order, those present.
  std::vector<FocalConstruction> focal_constructions;
  // The focal length the construction gives: the valid pair's with the smallest circle (with
  // the orthocentre all pairs agree exactly; with an assumed principal point, for exact
  // orthogonal points), or the assumed one; 0 when neither.
  double focal_px = 0.0;
  bool focal_assumed = false;
  // The horizon as a line l with l . (u, v, 1) = 0, (l0, l1) unit norm and l1 >= 0; zero
  // when undetermined (no x or y vanishing point, or z alone without a focal length).
  Eigen::Vector3d horizon = Eigen::Vector3d::Zero();
  // Unit vanishing direction per axis in the camera frame, K^-1 v (the side in front of the
  // camera for finite points), with K from principal_point_px and focal_px; zero when the
  // family is absent or there is no focal length.
  std::array<Eigen::Vector3d, 3> directions_in_cam{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                                                   Eigen::Vector3d::Zero()};
};

// The construction for the given vanishing points. Degenerate input is reported, not
// refused: three points without a camera (triangle_failed) fall back to the assumed principal
// point and kTwoPoints; a pair with p outside its circle is not valid.
VanishingConstruction ConstructFromVanishingPoints(const VanishingConstructionInput& input);

// One finite pair's construction for a given principal point (what the above runs per pair).
FocalConstruction ConstructFocal(const Eigen::Vector2d& v_i_px, const Eigen::Vector2d& v_j_px,
                                 const Eigen::Vector2d& principal_point_px);

}  // namespace facet
