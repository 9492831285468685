// The 3D panel's viewpoint (UI state, not part of the document): a turntable orbit about a
// target point with world Z kept up (core/geometry/conventions.h), or, after "View from photo",
// exactly a photo's camera until the user moves. Either way the view is a facet::Camera,
// so the one OpenCV-to-OpenGL conversion (app/platform/gl_camera.h) serves both.
#pragma once

#include <Eigen/Core>

#include "core/geometry/camera.h"
#include "core/scene/project.h"

namespace facet::app {

struct OrbitCamera {
  Eigen::Vector3d target = Eigen::Vector3d::Zero();  // world point the view turns about
  double yaw_rad = -0.9;                             // direction from target to eye, about world Z from +X
  double pitch_rad = 0.45;                           // elevation of the eye above the target's horizontal plane
  double distance = 10.0;                            // eye to target, world units
  double fov_y_deg = 45.0;                           // vertical field of view of the panel

  // While photo_image_id is set, the view is photo_camera (its pose, focal length and
  // principal point, the photo fitted into the panel).
  Id photo_image_id = kNoId;
  Camera photo_camera;
};

// A bounding sphere of what the panel should show (primitives, or camera centres).
struct SceneBounds {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  double radius = 1.0;  // > 0
};

// The camera of the current view for a panel of width_px x height_px pixels: image size =
// panel size, principal point at the panel centre for the orbit (the photo's own camera
// while viewing from a photo: fitting it to the panel is the GL conversion's job).
Camera ViewCameraOf(const OrbitCamera& orbit, int width_px, int height_px);
Eigen::Vector3d EyeOf(const OrbitCamera& orbit);

// Mouse gestures, in panel pixels. Each leaves photo view first (keeping the viewpoint as
// nearly as a turntable can: roll and principal point offset are dropped). None takes the
// eye below the ground (ClampAboveGround).
// Turntable: horizontal motion turns about world Z, vertical tilts (clamped short of the
// poles and above the ground).
void OrbitRotate(OrbitCamera* orbit, double dx_px, double dy_px, int width_px, int height_px);
// Moves the target in the view plane so that the point under the cursor follows it.
void OrbitPan(OrbitCamera* orbit, double dx_px, double dy_px, int width_px, int height_px);
// Dolly towards the target: distance scales by exp(-steps * 0.15); steps > 0 zooms in.
void OrbitZoom(OrbitCamera* orbit, double steps, int width_px, int height_px);
// Keeps the direction, centres the target on the bounds and sets the distance so the whole
// sphere fits the narrower field of view.
void OrbitFrame(OrbitCamera* orbit, const SceneBounds& bounds, int width_px, int height_px);
// Looks through `camera` (of image `image_id`); the orbit target is placed on its optical
// axis at the depth of the bounds' centre, for when the user starts to move.
void OrbitViewFromPhoto(OrbitCamera* orbit, Id image_id, const Camera& camera, const SceneBounds& bounds);
// Turns a photo view into the nearest turntable view (no-op otherwise).
void OrbitLeavePhotoView(OrbitCamera* orbit, int width_px, int height_px);

// The lowest pitch (radians) that keeps the eye of a turntable about a target at height
// target_z, `distance` away, above the ground plane z = 0 by kGroundClearance * distance;
// the pole's limit when no pitch does (a target deep below the ground).
constexpr double kGroundClearance = 0.02;
double MinPitchAboveGround(double target_z, double distance);
// Raises the turntable's pitch to MinPitchAboveGround, and a target too deep for any pitch
// to the depth the steepest view allows (photo views are left as they are: they are the
// photo's camera).
void ClampAboveGround(OrbitCamera* orbit);

// Whether the model changed so much since the view last framed `framed` that the view should
// frame `now` again (its size grew or shrank by kReframeRatio, or it moved by more than its
// size): large edits reframe, a solve's or a drag's small changes leave the user's view.
constexpr double kReframeRatio = 2.5;
bool NeedsReframe(const SceneBounds& framed, const SceneBounds& now);

}  // namespace facet::app
