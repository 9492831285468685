#include "core/io/blender_script.h"

#include <algorithm>
#include <filesystem>

#include <nlohmann/json.hpp>

#include "core/io/export.h"
#include "core/io/project_io.h"
#include "core/util/utf8.h"

namespace facet {
namespace {

// Lower-case hex of the bytes of `text`.
std::string Hex(const std::string& text) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string out;
  out.reserve(2 * text.size());
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    out += kDigits[byte >> 4];
    out += kDigits[byte & 15];
  }
  return out;
}

}  // namespace

std::string BlenderSetupScript(const Project& project, const std::string& project_path,
                               const std::string& model_path) {
  constexpr double kSensorMm = 36.0;
  nlohmann::json cameras = nlohmann::json::array();
  for (const Image& image : project.images) {
    int w = 0, h = 0;
    if (!ExportedCameraSize(image, &w, &h)) continue;  // the cameras the .glb has
    const Camera& cam = image.camera;
    const double side = std::max(w, h);
    // Blender's camera looks down -Z with +Y up; Facet's (OpenCV's) down +Z with Y down.
    const Eigen::Matrix3d world_from_blender_cam =
        cam.cam_from_world_rotation.transpose() * Eigen::Vector3d(1, -1, -1).asDiagonal();
    const Eigen::Vector3d center = cam.CenterInWorld();
    nlohmann::json matrix = nlohmann::json::array();
    for (int r = 0; r < 4; ++r) {
      nlohmann::json row = nlohmann::json::array();
      for (int c = 0; c < 4; ++c) {
        if (r == 3) {
          row.push_back(c == 3 ? 1.0 : 0.0);
        } else {
          row.push_back(c < 3 ? world_from_blender_cam(r, c) : center(r));
        }
      }
      matrix.push_back(row);
    }
    std::error_code ec;
    const std::string absolute_photo =
        std::filesystem::absolute(ResolveImagePath(project_path, image.path), ec).lexically_normal().string();
    const std::string photo = ec ? ResolveImagePath(project_path, image.path) : absolute_photo;
    const std::string name = std::filesystem::path(image.path).filename().string();
    // Names and paths are bytes: "name" and "photo" are their UTF-8 for Blender's names and
    // messages (invalid bytes as U+FFFD), "photo_hex" the exact bytes the script opens.
    cameras.push_back({{"name", ValidUtf8OrReplaced(name)},
                       {"photo", ValidUtf8OrReplaced(photo)},
                       {"photo_hex", Hex(photo)},
                       {"width_px", w},
                       {"height_px", h},
                       {"sensor_fit", w >= h ? "HORIZONTAL" : "VERTICAL"},
                       {"sensor_mm", kSensorMm},
                       {"lens_mm", cam.focal_px * kSensorMm / side},
                       {"shift_x", ((w - 1) / 2.0 - cam.principal_point_px.x()) / side},
                       {"shift_y", (cam.principal_point_px.y() - (h - 1) / 2.0) / side},
                       {"matrix_world", matrix},
                       {"has_distortion", cam.HasDistortion()}});
  }
  std::string script;
  script += "# Written by `facet export --blender-script`: run it in Blender (Scripting > Open > Run, or\n";
  script += "# `blender --python THIS.py`). It imports the exported model and adds one camera per\n";
  script += "# calibrated photo, with its photo as background: look through a camera (Numpad 0) to see\n";
  script += "# the model on the photo. Units: the project's; Blender's Z is up, as Facet's.\n";
  script += "import json\nimport os\n\nimport bpy\nfrom mathutils import Matrix\n\n";
  // Paths as the hex of their bytes: any name, in any encoding, reaches the file system
  // unchanged (os.fsdecode is Python's own file-name decoding) and no byte of it is syntax.
  script += "MODEL = os.fsdecode(bytes.fromhex(\"" + Hex(model_path) + "\"))\n";
  // The data is ASCII JSON (ensure_ascii) in a raw string: a quote in a name is \", a newline
  // \n, a backslash \\, and the apostrophe, the one character that could end the raw string,
  // is written \u0027. The marker lines are found as whole lines: every line of the dump
  // starts with a space or a bracket, so no name can fake one.
  std::string data = cameras.dump(1, ' ', true, nlohmann::json::error_handler_t::replace);
  for (size_t at = data.find('\''); at != std::string::npos; at = data.find('\'', at)) data.replace(at, 1, "\\u0027");
  script +=
      "CAMERAS = json.loads(r'''\n# facet-cameras-begin\n" + data +
      "\n# facet-cameras-end\n'''.split(\"\\n# facet-cameras-begin\\n\")[1].split(\"\\n# facet-cameras-end\\n\")[0])"
      "\n\n";
  script += R"PY(
def import_model(path):
    if not os.path.isabs(path) and bpy.data.filepath:
        path = os.path.join(os.path.dirname(bpy.data.filepath), path)
    before = set(bpy.data.objects)
    if path.lower().endswith(".obj"):
        if hasattr(bpy.ops.wm, "obj_import"):
            bpy.ops.wm.obj_import(filepath=path, forward_axis="NEGATIVE_Z", up_axis="Y")
        else:
            bpy.ops.import_scene.obj(filepath=path, axis_forward="-Z", axis_up="Y")
    else:
        bpy.ops.import_scene.gltf(filepath=path)
    # The glTF's own cameras carry no principal point: the cameras below replace them.
    for obj in set(bpy.data.objects) - before:
        if obj.type == "CAMERA":
            bpy.data.objects.remove(obj, do_unlink=True)


def add_camera(c):
    data = bpy.data.cameras.new(c["name"])
    data.sensor_fit = c["sensor_fit"]
    data.sensor_width = c["sensor_mm"]
    data.sensor_height = c["sensor_mm"]
    data.lens = c["lens_mm"]
    data.shift_x = c["shift_x"]
    data.shift_y = c["shift_y"]
    data.clip_start = 0.01
    obj = bpy.data.objects.new(c["name"], data)
    bpy.context.scene.collection.objects.link(obj)
    obj.matrix_world = Matrix(c["matrix_world"])
    photo = os.fsdecode(bytes.fromhex(c["photo_hex"]))
    if os.path.exists(photo):
        background = data.background_images.new()
        background.image = bpy.data.images.load(photo, check_existing=True)
        background.frame_method = "STRETCH"
        data.show_background_images = True
    else:
        print("facet: photo not found, camera without background:", c["photo"])
    if c["has_distortion"]:
        print("facet:", c["name"], "has radial distortion, which Blender's camera does not model: "
              "the photo lines up in its centre, less so towards its edges")
    return obj


import_model(MODEL)
cameras = [add_camera(c) for c in CAMERAS]
if cameras:
    scene = bpy.context.scene
    scene.camera = cameras[0]
    scene.render.resolution_x = CAMERAS[0]["width_px"]
    scene.render.resolution_y = CAMERAS[0]["height_px"]
    scene.render.resolution_percentage = 100
    scene.render.pixel_aspect_x = 1.0
    scene.render.pixel_aspect_y = 1.0
    # One render size per scene: it is the first photo's; set it to another photo's size
    # before looking through that photo's camera if the sizes differ.
)PY";
  return script;
}

}  // namespace facet
