// One world frame for every photo. A photo's line families give its camera rotation only up to
// a turn about the vertical by a multiple of 90 deg: the vanishing-point rotation points x and
// y towards their vanishing points' side in front of the camera (core/estimators/calibrate_vp.h),
// so photos from opposite sides of a building come out turned 180 deg, and which horizontal
// family is x is the labeller's (or the line detector's) choice. Each image records its turn
// (Image::axis_quarter_turns); the camera's rotation is the vanishing-point rotation times
// AxisTurn(turns). This file chooses the turn of images that have none yet:
// - from pins shared with the model: with the rotation known, resection is linear in the
//   camera centre; each of the 4 turns gets its least-squares centre, and the turn whose
//   centre puts every pinned vertex in front with the lowest reprojection RMS wins;
// - else from the relative pose to a photo already in the model (vertices pinned in both):
//   with both rotations known the epipolar constraint is linear in the baseline; the turn
//   whose baseline triangulates every shared vertex in front with the lowest epipolar error
//   wins;
// - the first image with lines and no reference keeps turn 0: it sets the world axes.
// A turn chosen from pins is kept only when the pins tell it clearly from the next best (3 or
// more pins, 4 or more shared vertices, and a next best turn that fits several times worse
// and pixels worse): two pins often fit two turns within a pixel, and a turn kept from them
// turned cameras by 90-180 deg. Below that margin the best turn is used but provisional
// (Image::axis_turn_provisional): it is chosen again from all pins at every update, and the
// update warns until the pins settle it.
// An image that shares no pins with the model stays unchosen (turn 0 meanwhile, not
// recorded) until it does. Each choice is said in one sentence for the app's log.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/geometry/ids.h"
#include "core/scene/project.h"

namespace facet {

// The world-from-lines turn: a rotation about z by turns x 90 deg (exact integers).
Eigen::Matrix3d AxisTurn(int quarter_turns);

// The world axis a line family of an image with this turn runs along: x and y swap on an odd
// turn (vanishing-point residuals do not see the sign).
int WorldAxisOfFamily(int family_axis, int quarter_turns);

struct WorldFrameChoice {
  Id image_id = kNoId;
  int quarter_turns = 0;
  enum class Source { kFirstImage, kSharedPins, kRelativePose } source = Source::kFirstImage;
  int num_points = 0;      // pins (resection) or shared vertices (relative pose) it used
  double error = 0.0;      // the chosen turn's RMS: px (resection) or epipolar px
  double runner_up = 0.0;  // the next best turn's, infinite when no other kept points in front
  bool provisional = false;  // too small a margin to keep (see above): chosen again next update
  std::string note;        // the sentence for the log
};

// Chooses the turn of each image listed in `unchosen` (calibrated from its lines, camera
// rotation currently vanishing-point x AxisTurn(0)); `project` is updated in place: the
// chosen images get axis_quarter_turns, their rotation turned and, from resection, their
// centre. Reference images are the calibrated images not listed; the model's vertex positions
// are the cached ones (right after the previous solve). Returns the choices made, in order.
std::vector<WorldFrameChoice> ReconcileWorldFrames(const std::vector<Id>& unchosen, Project* project);

}  // namespace facet
