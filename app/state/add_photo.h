// File > Add photo: a photo joins the project as a new image (the start of every model, and
// the second and further views of the two-view and self-calibration paths, which then take
// their cameras from pins: core/solve/multiview_init.h). One undoable edit.
#pragma once

#include <string>

#include "app/state/app_state.h"

namespace facet::app {

// Adds the photo at `path` (absolute, or relative to the working directory) as a new image
// and makes it the active one. The stored path is relative to the project file's folder when
// the project has been saved, else absolute. The camera starts uncalibrated with its
// principal point at the centre and a focal length of 1.2 x the larger side; when the photo's
// EXIF gives a focal length, it becomes the image's focal prior (app/state/calgui_exif_prior.h) and
// the log says so. A missing or unreadable photo logs an error and changes nothing.
bool AddPhotoEdit(AppState* state, const std::string& path);

// File > Relink photo: points image `image_id` at the photo file at `path`, e.g. after the
// project or its photos moved. Camera, pins and lines stay. The photo must decode and have the
// image's size (else it is another photo: logged as an error, nothing changes). One undoable
// edit.
bool RelinkPhotoEdit(AppState* state, Id image_id, const std::string& path);

}  // namespace facet::app
