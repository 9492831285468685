// A reconstruction's cameras (COLMAP's, put on a project's images by ApplyColmapCameras,
// core/io/colmap_import.h) into the project's frame. A reconstruction has its own axes, scale
// and origin; the similarity project_from_reconstruction (x_in_project = s R x + t) is chosen
// from what the project knows, each of rotation, scale and position from the best source it
// has:
// - cameras in common (images calibrated in the project and registered by the reconstruction):
//   the rotation is the chordal mean of their frame rotations R_project_i^T R_reconstruction_i,
//   which holds even when the centres lie near one line (four centres on a gentle arc left the
//   turn about that line ~0.45 deg off in the fountain test); with two or more distinct
//   centres, scale and position are the least-squares fit of the centres given that rotation,
//   and with three or more the centres' own similarity (FitSimilarity, Umeyama) is reported
//   as a check of the rotation. With one camera (or centres that coincide), the rotation and
//   position come from it, the scale from a known length or is kept;
// - no camera in common: the up axis from the vertical (z) line families drawn or detected on
//   the registered photos, the heading from their horizontal (x, y) families, as a
//   vanishing-point calibration would set them (core/estimators/calibrate_vp.h,
//   core/solve/world_frames.h: an image's recorded quarter turn says which world axis its
//   families are, an image without one is taken modulo 90 deg); without any line family, up is
//   the mean of the cameras' up vectors (photos are taken mostly upright) and the heading is
//   the reconstruction's;
// - scale without two common centres: the project's known lengths (distance constraints, kept
//   box sizes) whose two vertices are pinned in two or more registered photos, triangulated in
//   the reconstruction; else the reconstruction's own scale is kept;
// - position without a common camera: the reconstruction's origin is kept.
// The summary and its message say which source fixed each ("rotation: 3 cameras in common;
// scale: 3 camera centres; position: 3 camera centres").
#pragma once

#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "core/estimators/similarity_fit.h"
#include "core/geometry/ids.h"
#include "core/optim/solver_summary.h"
#include "core/scene/project.h"

namespace facet {

enum class AlignmentSource {
  kCommonCameras,  // rotations, centres or the one camera in common with the project
  kLineFamilies,   // vanishing directions of the photos' line families
  kCameraUp,       // the mean up vector of the cameras (rotation only)
  kKnownLength,    // triangulated known lengths (scale only)
  kKept,           // the reconstruction's own (nothing in the project fixes it)
};
const char* AlignmentSourceName(AlignmentSource source);  // "cameras in common", ...

struct ColmapAlignmentOptions {
  // A warning when the rotation of the centres' own fit differs from the common cameras' by
  // more than this, or when a common camera's aligned rotation differs from its project
  // rotation by more than this (a wrong match, or a project camera that was off).
  double max_rotation_disagreement_deg = 2.0;
  // Common camera centres count as distinct when they spread (RMS about their mean) more than
  // this fraction of their distance from the origin plus 1 project unit.
  double min_center_spread = 1e-9;
  // A horizontal vanishing direction whose forward component in the camera is below this
  // (a family parallel to the photo) has no reliable sign: it is used modulo 180 deg.
  double min_forward_component = 0.05;
  // A warning when the up of the vertical lines is this far from the cameras' mean up.
  double max_up_disagreement_deg = 30.0;

  bool Check(std::string* error) const;
};

// SolverSummary: message is the three sources in one sentence; warnings name disagreements
// (centre fit against rotations, a common camera that does not agree, lines against the
// cameras' up). Not IsUsable() (kInvalidInput) without registered images; kFailed when the
// fit gives no proper similarity (a non-positive scale: the common cameras are mirrored).
struct ColmapAlignmentSummary : SolverSummary {
  SimilarityTransform project_from_reconstruction;
  AlignmentSource rotation_source = AlignmentSource::kKept;
  AlignmentSource scale_source = AlignmentSource::kKept;
  AlignmentSource position_source = AlignmentSource::kKept;
  // Each source with its count, e.g. "3 cameras in common", "2 known lengths", "kept".
  std::string rotation_note, scale_note, position_note;
  std::vector<Id> common_images;  // calibrated in the project and in the reconstruction
  int num_distinct_centers = 0;   // of the common images, when they fixed scale and position (else 0)
  int num_line_families = 0;      // vanishing directions used (vertical and horizontal)
  int num_known_lengths = 0;      // triangulated known lengths used for the scale
  // After alignment, over the common images: RMS distance of the centres from the project's
  // (project units) and RMS angle between the rotations (deg); 0 without common images.
  double center_rms = 0.0;
  double rotation_rms_deg = 0.0;
  // With three or more common centres not on one line: the angle (deg) between the rotation
  // of the centres' own similarity and the one used; -1 when it was not computed.
  double center_fit_rotation_deg = -1.0;
  // Registered images with horizontal line families and no recorded quarter turn
  // (Image::axis_quarter_turns) get the turn that puts their families where the aligned camera
  // sees them (within 20 deg), so that the calibration from their lines after the edit keeps
  // this heading: (image id, turns), in project order.
  std::vector<std::pair<Id, int>> chosen_turns;
};

// The similarity from the reconstruction's frame into the project's. `before`: the project as
// it was (its cameras are the target frame's). *project: the same project with the
// reconstruction's cameras on the images listed in `reconstructed_images` (ids of *project);
// their cameras are moved into the project's frame (and turns recorded, see chosen_turns).
// Other images, the model and the pins are not changed. On a summary that is not IsUsable(), *project is unchanged.
ColmapAlignmentSummary AlignReconstructionToProject(const Project& before, const std::vector<Id>& reconstructed_images,
                                                    const ColmapAlignmentOptions& options, Project* project);

// The camera seen from the other frame: centre transform.Apply(centre), rotation R * rotation^T
// (intrinsics unchanged); a scene point x maps to the same pixel as transform.Apply(x) does.
void TransformCamera(const SimilarityTransform& transform, Camera* camera);

}  // namespace facet
