// What runs after every edit (the paper: "after each operation the system re-solves cameras
// and geometry"): each image with line families is calibrated from its vanishing points,
// then the geometry solve fits cameras and boxes to the pins.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "core/calibrate_vp.h"
#include "core/project.h"
#include "core/scene_solve.h"

namespace facet {

struct ModelUpdateOptions {
  SceneSolveOptions solve;
  bool calibrate = true;  // false keeps every camera's intrinsics and rotation
};

struct ModelUpdateSummary {
  std::map<Id, VpCalibrationSummary> calibration;  // by image id, images with segments only
  SceneSolveSummary solve;
  std::vector<std::string> messages;  // user-facing: what failed and why
  double time_ms = 0.0;
  // False when a step failed; the project is then left as the edit made it (cameras and
  // boxes keep their previous values), never half-updated.
  bool ok = true;
};

// `edited` is the project after the user's edit; *updated receives it with re-solved cameras
// and boxes.
ModelUpdateSummary UpdateModel(const Project& edited, const ModelUpdateOptions& options, Project* updated);

}  // namespace facet
