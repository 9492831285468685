// The command-line verbs that work without a window: calibrate, relate, solve, export,
// render-glb (offscreen EGL). Each prints its result (JSON where a program may read it) on stdout, errors on stderr,
// and returns the process exit code (0 success, 1 unusable input).
#pragma once

#include <string>

namespace facet::app {

// Exactly one of the two inputs is set: line families (vanishing points) or known 3D points (DLT).
int RunCalibrateCommand(const std::string& lines_path, const std::string& points_path);
// Lines detected on the photo (core/io/calibrate_io.h, CalibrateImageFile). principal_point:
// "solve", "center" or "CX,CY"; focal_prior: "exif" (the photo's, if it has one), "none" or
// "F,STD"; focal_px > 0: a known focal length (then focal_prior is ignored).
int RunCalibrateImageCommand(const std::string& photo_path, const std::string& principal_point,
                             const std::string& focal_prior, double focal_px);
int RunRelateCommand(const std::string& matches_path);
int RunSolveCommand(const std::string& project_path, const std::string& output_path);
// `format`: "glb" or "obj" (the textured model), "colmap" (the calibrated cameras as a COLMAP
// text model in the folder output_path, core/io/colmap_model_write.h) or "transforms" (as
// nerfstudio's transforms.json, core/io/transforms_json.h); empty: from output_path (.glb,
// .obj, .json; a folder, existing or written with a trailing '/', for colmap).
// With a non-empty blender_script_path, also writes the Blender set-up script
// (core/io/blender_script.h) that imports output_path and adds the photos' cameras.
// texels_per_unit > 0 sets the texture's resolution (TextureBakeOptions::texels_per_unit);
// 0 keeps the rule from the photos. Both only for a model (glb, obj).
int RunExportCommand(const std::string& project_path, const std::string& output_path, const std::string& format = "",
                     const std::string& blender_script_path = "", double texels_per_unit = 0.0);

// Renders a .glb through its camera node number camera_index (0-based, in node order) with
// the 3D panel's renderer in an offscreen EGL context, at the camera's image size
// (extras.image_size_px, else 1000 px high), to an RGBA PNG whose alpha is 0 where no
// triangle is; prints the camera used as JSON (app/platform/gltf_camera_render.h).
int RunRenderGlbCommand(const std::string& glb_path, int camera_index, const std::string& output_png);

}  // namespace facet::app
