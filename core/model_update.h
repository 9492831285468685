// What runs after every edit (the paper: "after each operation the system re-solves cameras
// and geometry"): each image with line families is calibrated from its vanishing points (after
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

#include "core/calibrate_vp.h"
#include "core/joint_solve.h"
#include "core/plumb_line.h"
#include "core/project.h"
#include "core/scene_solve.h"

namespace facet {

struct ModelUpdateOptions {
  SceneSolveOptions solve;
  bool calibrate = true;  // false keeps every camera's intrinsics and rotation
  bool joint_solve = true;
  JointSolveOptions joint;
};

struct ModelUpdateSummary {
  std::map<Id, VpCalibrationSummary> calibration;  // by image id, images with segments only
  // By image id, images with estimate_distortion and segments only. The estimate is in the
  // plumb-line model (core/plumb_line.h); the camera's k1, k2 are its OpenCV conversion with
  // the calibrated focal length.
  std::map<Id, PlumbLineSummary> distortion;
  SceneSolveSummary solve;
  JointSolveSummary joint;  // termination kInvalidInput when it did not run
  std::vector<std::string> messages;  // user-facing: what failed and why
  double time_ms = 0.0;
  // False when a step failed; the project is then left as the edit made it (cameras and
  // primitives keep their previous values), never half-updated.
  bool ok = true;
};

// `edited` is the project after the user's edit; *updated receives it with re-solved cameras
// and primitives.
ModelUpdateSummary UpdateModel(const Project& edited, const ModelUpdateOptions& options, Project* updated);

}  // namespace facet
