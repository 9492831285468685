// Facet's cameras out as a COLMAP text model (cameras.txt, images.txt, points3D.txt), for the
// tools people use next (dense reconstruction, Gaussian splatting, NeRF trainers) where
// structure from motion fails: few photos, little texture.
#pragma once

#include <string>

#include "core/io/colmap_model.h"
#include "core/scene/project.h"

namespace facet {

struct ColmapExportOptions {
  // Also the model's vertices as 3D points, each with its pins as its track (the pins as the
  // images' 2D points). Off: points3D.txt is written empty and the images have no 2D points.
  bool include_points = true;
};

// The model of `project`'s calibrated images: one camera per image (COLMAP camera id = image
// id = Facet's image id), named by the photo's file name (its last path component, which the
// COLMAP importer matches on). Images without a calibrated camera are left out; vertices are
// numbered 1, 2, ... over the primitives in order. "" on success, else why (no calibrated
// photo or a camera that is no camera, core/io/camera_export.h; an id beyond COLMAP's 32 bits,
// two photos with one file name, a name images.txt cannot hold); *model is then empty.
// Every Facet camera has an exact COLMAP model (core/io/colmap_camera.h): nothing is rounded.
std::string ColmapModelFromProject(const Project& project, const ColmapExportOptions& options, ColmapModel* model);

// The three text files as COLMAP 3.8 writes them, every number with 17 significant digits
// (so they read back exactly).
std::string FormatColmapCamerasText(const ColmapModel& model);
std::string FormatColmapImagesText(const ColmapModel& model);
std::string FormatColmapPoints3DText(const ColmapModel& model);

// Writes the three files into folder `dir` (created when missing), each atomically
// (core/util/file_write.h), after checking that none of the three names is taken by a folder,
// a device or a FIFO (then nothing is written). "" on success, else what failed.
std::string WriteColmapModelText(const std::string& dir, const ColmapModel& model);

}  // namespace facet
