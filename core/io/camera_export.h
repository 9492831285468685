// What the camera exports (the COLMAP text model, core/io/colmap_model_write.h; nerfstudio's
// transforms.json, core/io/transforms_json.h) write: the calibrated photos, each camera checked
// to be numbers another tool can use. One definition, so both exports refuse the same projects
// with the same words.
#pragma once

#include <string>
#include <vector>

#include "core/scene/project.h"

namespace facet {

// The calibrated images of `project`, in project order, into *images. "" when there is at least
// one and each of their cameras has a positive image size, a positive finite focal length and
// finite principal point, distortion and pose; else one sentence saying why not (naming the
// photo), and *images is empty.
std::string ImagesForCameraExport(const Project& project, std::vector<const Image*>* images);

}  // namespace facet
