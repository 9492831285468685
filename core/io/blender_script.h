// `facet export --blender-script FILE.py`: a Python script for Blender that sets up what an
// fSpy user expects: one camera per calibrated photo with its focal length, sensor, principal
// point shift, pose and the photo as its background, and the exported model imported, so that
// looking through a camera shows the model on its photo.
//
// The cameras are written as data (an ASCII JSON block between the lines "# facet-cameras-begin"
// and "# facet-cameras-end", parsed by the script) so that a test can check the numbers against
// Blender's camera model without Blender. Any file name is safe: each camera's "name" and
// "photo" are UTF-8 (bytes that are not, as U+FFFD), "photo_hex" holds the photo path's exact
// bytes in hex, which the script opens (os.fsdecode), as it opens MODEL, also given in hex; no
// character of a name can end the JSON's string or fake a marker line.
// Blender's frame: world Z up, as Facet's; a camera looks down its local -Z with +Y up. Its sensor fits the photo's
// larger side (sensor 36 mm), so lens_mm = f_px * 36 / max(w, h), and its shift is in units of that side: shift_x = ((w
// - 1) / 2 - cx) / max(w, h), shift_y = (cy - (h - 1) / 2) / max(w, h) (pixel centres at integers,
// core/geometry/conventions.h). Blender's camera has no radial distortion: a camera with k1, k2 is written as its
// pinhole part, and the script says so.
#pragma once

#include <string>

#include "core/scene/project.h"

namespace facet {

// The script's text. `model_path` (the .glb or .obj, as the script should find it: absolute,
// or relative to the .blend's folder) is imported; photo paths are resolved against
// `project_path`'s folder and written absolute.
std::string BlenderSetupScript(const Project& project, const std::string& project_path,
                               const std::string& model_path);

}  // namespace facet
