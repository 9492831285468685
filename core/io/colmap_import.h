// A COLMAP reconstruction's cameras into a Facet project: each photo of the project takes the
// camera of the COLMAP image with the same file name (last path component); a photo the
// reconstruction lacks keeps its own camera. ApplyColmapCameras leaves the cameras in the
// reconstruction's frame (its axes and scale); ApplyAlignedColmapCameras also aligns them to
// the project's.
#pragma once

#include <string>
#include <vector>

#include "core/io/colmap_model.h"
#include "core/scene/project.h"
#include "core/solve/colmap_alignment.h"

namespace facet {

struct ColmapImportReport {
  std::vector<Id> updated_images;           // project images that took a COLMAP camera
  std::vector<std::string> missing_photos;  // project photos (file names) the reconstruction lacks
  std::vector<std::string> unused_images;   // COLMAP image names no project photo has
  std::vector<Id> rescaled_images;          // updated images whose photo is a resized copy of COLMAP's
};

// Sets the intrinsics and pose of every matched image (and camera_calibrated), and holds it:
// camera_from_reconstruction (its lines no longer calibrate it) and its pose and intrinsics
// locked (Image's locks; the user may free them). A COLMAP
// camera whose size differs from the project photo's by a uniform scale (a resized copy: both
// sides within half a pixel of COLMAP's times project width / COLMAP width) is rescaled
// exactly; any other size difference, a camera model Facet cannot represent
// (core/io/colmap_camera.h) or two COLMAP images with one file name is refused by name.
// "" on success, else the error; on error *project is unchanged (nothing half-applied).
std::string ApplyColmapCameras(const ColmapModel& model, Project* project, ColmapImportReport* report);

// ApplyColmapCameras, then the cameras it set brought into the project's frame
// (core/solve/colmap_alignment.h) against the project as it was: what `facet cameras` and File >
// Cameras from all photos apply. "" on success, else the error of either step; on error
// *project is unchanged.
std::string ApplyAlignedColmapCameras(const ColmapModel& model, const ColmapAlignmentOptions& options, Project* project,
                                      ColmapImportReport* report, ColmapAlignmentSummary* alignment);

}  // namespace facet
