// Picking vertices, edges and faces of the primitives' meshes: in an image (the model
// projected by the image's camera, distances in screen px) and along a 3D view ray. Both
// panels use these, so what is picked is what is drawn.
//
// Priorities: a vertex within the radius wins over an edge within the radius, which wins over
// a face under the point; among faces the one nearest the camera wins. Only front-facing
// faces are picked (their outward normal towards the camera), so a click on a box picks the
// face the user sees. In an image, a vertex or edge on the back of a primitive (all faces
// beside it turned away) is picked only where no front face covers the cursor; in the 3D
// panel a vertex or edge within the radius is picked unless a face hides it on its own line
// of sight (so the corners and edges of the face under the cursor win over that face).
#pragma once

#include <vector>

#include <Eigen/Core>
#include <glm/glm.hpp>

#include "app/state/app_state.h"

namespace facet::app {

// Distance from p to the segment a-b, and the parameter t in [0, 1] of the closest point.
double DistanceToSegment(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                         double* t = nullptr);

// Camera-frame depth below which a point counts as behind the camera.
constexpr double kNearDepth = 1e-6;

// One primitive's vertices seen by a camera, indexed by vertex id (dead ids: in_front false).
struct ProjectedPrimitive {
  Id primitive_id = kNoId;
  std::vector<Eigen::Vector2d> uv_px;
  std::vector<double> depth;  // camera z
  std::vector<char> in_front;
};

// All primitives projected with the image's camera; empty when it is not calibrated.
std::vector<ProjectedPrimitive> ProjectModel(const Project& project, const Image& image);

// An edge pick's parameter snaps to the edge's middle when the pick is this close to the
// projected middle (screen px), so that E_split's common case is exact.
constexpr double kMidpointSnapPx = 6.0;

// Which element kinds a pick considers.
struct PickFilter {
  bool vertices = true;
  bool edges = true;
  bool faces = true;
};
// The filter of a tool: select picks everything, the pin tool and the vertex operators
// vertices, the edge operators edges.
PickFilter PickFilterOf(Tool tool);

// A pick result; `t` is the edge parameter from the origin of half-edge 2 * edge (core/mesh/mesh.h)
// of the point nearest the pick, in 3D (perspective-correct), for edges only.
struct ElementPick {
  ElementRef element;
  double distance_px = 0.0;
  double t = 0.5;
};

// Picks in an image: `to_screen` maps image px to screen px (the panel's view), `mouse` is
// in screen px, `camera` is the image's camera (for the 3D edge parameter).
ElementPick PickInImage(const Project& project, const std::vector<ProjectedPrimitive>& projected, const Camera& camera,
                        double zoom, const Eigen::Vector2d& origin_screen, const Eigen::Vector2d& mouse_screen,
                        const PickFilter& filter, double radius_px);

// A view ray for picking in the 3D panel, with a projection to panel px. Origin and direction
// are world points in core's Eigen (they meet the meshes); clip_from_world is the frame's GL
// matrix in GLM (app/platform/gl_camera.h converts between the two).
struct PickRay {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();  // unit
  glm::dmat4 clip_from_world = glm::dmat4(1.0);          // GL's, as the frame drew (app/platform/gl_camera.h)
  int width_px = 1, height_px = 1;                       // the panel in px (device)
  Eigen::Vector2d mouse_px = Eigen::Vector2d::Zero();
};

// Panel px of a world point under the ray's projection, or false when behind the eye.
bool ProjectToPanel(const PickRay& ray, const Eigen::Vector3d& p_in_world, Eigen::Vector2d* px);

// Picks along the ray: a vertex, else an edge, within radius_px of the mouse that no other
// face hides from the ray's origin, else the nearest face hit (ray against the faces'
// triangles) when it is seen from outside.
ElementPick PickByRay(const Project& project, const PickRay& ray, const PickFilter& filter, double radius_px);

// Edge parameter (from the origin of half-edge 2 * edge) of the point on segment a-b closest
// to the ray origin + s * direction, clamped to [0, 1].
double ClosestEdgeParameter(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& ray_origin,
                            const Eigen::Vector3d& ray_direction);

// Whether the point lies inside the polygon (even-odd rule).
bool PointInPolygon(const Eigen::Vector2d& p, const std::vector<Eigen::Vector2d>& polygon);

}  // namespace facet::app
