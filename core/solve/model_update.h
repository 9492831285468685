// What runs after every edit (the paper: "after each operation the system re-solves cameras
// and geometry"): each image with line families is calibrated from its vanishing points (its
// rotation turned about the vertical into the model's world frame, core/solve/world_frames.h;
// after
// a plumb-line estimate of its radial distortion when Image::estimate_distortion is set; the
// segments are undistorted with the camera's k1, k2 whenever those are non-zero), the
// geometry solve (linear start + LM over camera centres and primitive parameters) fits the
// model to the pins, then the joint solve refines everything at once: intrinsics that are not
// locked, camera rotations against the line families, free vertices and the spatial
// constraints.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "core/estimators/calibrate_vp.h"
#include "core/estimators/plumb_line.h"
#include "core/scene/project.h"
#include "core/solve/joint_solve.h"
#include "core/solve/multiview_init.h"
#include "core/solve/scene_solve.h"
#include "core/solve/world_frames.h"

namespace facet {

struct ModelUpdateOptions {
  SceneSolveOptions solve;
  bool calibrate = true;  // false keeps every camera's intrinsics and rotation
  // Images with pins but no line families get cameras from their pins after the geometry
  // solve (core/solve/multiview_init.h: resection, two views, self-calibration), then the geometry
  // solve runs again with them. Off on the per-frame drag path (a new image is initialised
  // once, by the commit that gives it enough pins).
  bool initialize_from_pins = true;
  MultiViewInitOptions multiview;
  bool joint_solve = true;
  JointSolveOptions joint;
  // Warm start (solve.warm_start) with the joint solve on: when false, the geometry solve runs
  // only if the joint solve's warm result is not usable or above 3 px RMS, since the joint
  // solve already covers every parameter of the geometry solve (the per-frame drag path:
  // the dense geometry solve was most of a 10-box frame).
  bool geometry_solve_when_warm = true;

  // The steps' own Check()s; UpdateModel needs no call, since each step checks its options
  // and a step with invalid ones fails with the reason in its summary.
  bool Check(std::string* error) const;
};

// What the app runs after a commit or a released drag: warm full solves, the SLSQP polish so
// that constraints hold exactly, and the diagnostics the properties panel shows.
ModelUpdateOptions CommitUpdateOptions();

// What the app runs per frame while a pin or endpoint is dragged: `iterations` warm-started
// iterations of each solve so that the frame never stalls, the joint solve alone (the
// geometry solve only when its warm result does not hold), no polish, no diagnostics (their
// SVD of the Jacobian is the expensive part and the panel shows them after release), no
// camera initialisation from pins. Benchmarks of a drag frame time exactly this.
ModelUpdateOptions DragFrameUpdateOptions(int iterations = 5);

// The options the calibration step gives CalibrateFromVanishingLines for this image (its size,
// principal point and focal modes, horizon); Teach mode steps the same fit.
VpCalibrationOptions CalibrationOptionsFor(const Image& image);

// What the calibration step of one image read and what it gave, kept between UpdateModel
// calls so that a drag frame (which moves a pin, not a line) does not calibrate again. Owned
// by the caller (e.g. the app's state), passed to UpdateModel by pointer; empty at first.
// A result is reused only when every input equals the stored one by content (the project's
// operator==, so undo, redo and loading a project need no invalidation): the image with its
// pose cleared (size, calibration modes, estimate_distortion, camera_calibrated, ...), its
// segments in order, and the camera intrinsics (focal, principal point, k1, k2) whenever the
// calibration reads them (segments undistorted by the camera's own non-zero k). NaN inputs
// never compare equal, so they are calibrated each time.
struct ImageCalibrationCacheEntry {
  Image image;  // camera = Camera(): the intrinsics the calibration read are in `camera`
  std::vector<Segment> segments;
  bool camera_read = false;
  Camera camera;  // intrinsics only (pose cleared); default when !camera_read
  bool estimated_distortion = false;
  PlumbLineSummary distortion;  // when estimated_distortion
  VpCalibrationSummary calibration;
  double k1 = 0.0;  // the camera's k1, k2 the calibration gave (OpenCV model)
  double k2 = 0.0;
};
struct ModelUpdateCache {
  std::map<Id, ImageCalibrationCacheEntry> images;  // by image id; images calibrated last call
};

// Not a solver summary itself but the summaries of the steps it ran (each a SolverSummary or
// an estimator's), with `ok` for the update as a whole and its user-facing messages.
struct ModelUpdateSummary {
  std::map<Id, VpCalibrationSummary> calibration;  // by image id, images with segments only
  // By image id, images with estimate_distortion and segments only. The estimate is in the
  // plumb-line model (core/estimators/plumb_line.h); the camera's k1, k2 are its OpenCV conversion with
  // the calibrated focal length.
  std::map<Id, PlumbLineSummary> distortion;
  SceneSolveSummary solve;            // termination kInvalidInput with an empty message when it did not run
  MultiViewInitSummary multiview;     // cameras initialised from pins (num_initialized 0: none)
  JointSolveSummary joint;            // termination kInvalidInput when it did not run
  std::vector<std::string> messages;  // user-facing: what failed and why
  // User-facing: what an unfinished drawing still needs (an image whose line families are not
  // complete yet, VpCalibrationSummary::incomplete). Progress, not failures.
  std::vector<std::string> progress;
  // Images whose world-frame turn this update chose (core/solve/world_frames.h), in order.
  std::vector<WorldFrameChoice> world_frames;
  // User-facing, informational: what the update decided for the user (e.g. a photo's world
  // axes turned to agree with the model), for the log.
  std::vector<std::string> notes;
  // User-facing: what the update did but the user should look at (a photo's world axes chosen
  // by too small a margin to keep). Not failures: `ok` stays true.
  std::vector<std::string> warnings;
  // The calibration step per image with segments: run, or taken from the cache (the plumb-line
  // estimate counts apart: it is reused whenever the image and its segments are unchanged,
  // even when the vanishing-point calibration runs again for a camera whose k changed).
  int images_calibrated = 0;
  int images_reused = 0;
  int distortion_estimates_run = 0;
  double calibration_ms = 0.0;  // the calibration step (all images)
  double time_ms = 0.0;
  // False when a step failed (the joint solve included: a joint solve that diverges does not
  // leave the geometry solve's result behind); the project is then left as the edit made it
  // (cameras and primitives keep their previous values), never half-updated.
  bool ok = true;
};

// `edited` is the project after the user's edit; *updated receives it with re-solved cameras
// and primitives. With a cache (may be null: everything is computed), an image whose
// calibration inputs equal the cached ones takes the cached result: *updated is then the same,
// bit for bit, as without the cache. The cache is updated to this call's images (entries of
// images without segments or no longer in the project are dropped); options.calibrate = false
// leaves it untouched.
ModelUpdateSummary UpdateModel(const Project& edited, const ModelUpdateOptions& options, Project* updated,
                               ModelUpdateCache* cache = nullptr);

}  // namespace facet
