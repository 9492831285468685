// Export: the GLB is parsed back byte by byte (header, chunks, accessors, embedded PNG,
// camera nodes), the OBJ line by line.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <doctest/doctest.h>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/io/blender_script.h"
#include "core/io/export.h"
#include "core/io/gltf_read.h"
#include "core/io/project_io.h"
#include "core/io/reference_mesh.h"
#include "core/mesh/operators.h"
#include "core/mesh/primitives.h"
#include "core/texture/textured_mesh.h"
#include "core/util/utf8.h"
#include "gltf_validator.h"
#include "synthetic_scene.h"
#include "tests/temp_files.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// Lower-case hex of a string's bytes, as the script writes paths.
std::string HexOf(const std::string& text) {
  std::string out;
  char byte[3];
  for (const char c : text) {
    std::snprintf(byte, sizeof(byte), "%02x", static_cast<unsigned char>(c));
    out += byte;
  }
  return out;
}

std::uint32_t U32(const std::vector<std::uint8_t>& b, size_t offset) {
  std::uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v |= static_cast<std::uint32_t>(b[offset + i]) << (8 * i);
  return v;
}

// A smooth colour ramp: every face the camera sees gets some texture.
facet::ImageRgba8 RampPhoto(int width, int height) {
  facet::ImageRgba8 photo;
  photo.width = width;
  photo.height = height;
  photo.pixels.resize(static_cast<size_t>(width) * height * 4);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      std::uint8_t* p = photo.At(x, y);
      p[0] = static_cast<std::uint8_t>(x * 255 / width);
      p[1] = static_cast<std::uint8_t>(y * 255 / height);
      p[2] = static_cast<std::uint8_t>((x + y) % 256);
      p[3] = 255;
    }
  }
  return photo;
}

struct Fixture {
  facet::testing::SyntheticScene scene;
  facet::TexturedMesh mesh;
};

Fixture BakedScene() {
  Fixture f;
  f.scene = facet::testing::MakeBoxScene();
  const auto summary = facet::BakeTexturedMesh(
      f.scene.project, {RampPhoto(f.scene.true_camera.width_px, f.scene.true_camera.height_px)}, {}, &f.mesh);
  REQUIRE_MESSAGE(summary.IsUsable(), summary.message);
  REQUIRE(summary.faces_textured == 3);
  return f;
}

struct Glb {
  json gltf;
  std::vector<std::uint8_t> bin;
};

// Parses and checks the container: header, exactly a JSON chunk then a BIN chunk.
Glb ParseGlb(const fs::path& path) {
  const std::vector<std::uint8_t> bytes = facet::testing::ReadBytes(path);
  REQUIRE(bytes.size() >= 28);
  CHECK(U32(bytes, 0) == 0x46546C67);  // "glTF"
  CHECK(U32(bytes, 4) == 2);
  CHECK(U32(bytes, 8) == bytes.size());
  const std::uint32_t json_length = U32(bytes, 12);
  CHECK(U32(bytes, 16) == 0x4E4F534A);  // "JSON"
  CHECK(json_length % 4 == 0);
  REQUIRE(20 + json_length + 8 <= bytes.size());
  const size_t bin_header = 20 + json_length;
  const std::uint32_t bin_length = U32(bytes, bin_header);
  CHECK(U32(bytes, bin_header + 4) == 0x004E4942);  // "BIN\0"
  CHECK(bin_length % 4 == 0);
  REQUIRE(bin_header + 8 + bin_length == bytes.size());
  Glb glb;
  glb.gltf = json::parse(bytes.begin() + 20, bytes.begin() + 20 + json_length);
  glb.bin.assign(bytes.begin() + static_cast<long>(bin_header + 8), bytes.end());
  return glb;
}

// The bytes of an accessor or a bufferView, bounds-checked against the BIN chunk.
const std::uint8_t* ViewData(const Glb& glb, int view_index, size_t* length) {
  const json& view = glb.gltf["bufferViews"][view_index];
  const size_t offset = view.value("byteOffset", 0);
  *length = view["byteLength"];
  CHECK(view["buffer"] == 0);
  CHECK(offset % 4 == 0);
  REQUIRE(offset + *length <= glb.bin.size());
  return glb.bin.data() + offset;
}

template <typename T>
std::vector<T> AccessorData(const Glb& glb, int accessor_index, int components) {
  const json& accessor = glb.gltf["accessors"][accessor_index];
  size_t length = 0;
  const std::uint8_t* data = ViewData(glb, accessor["bufferView"], &length);
  const size_t count = accessor["count"];
  REQUIRE(count * components * sizeof(T) <= length);
  std::vector<T> out(count * components);
  std::memcpy(out.data(), data, out.size() * sizeof(T));
  return out;
}

Eigen::Vector3d YUp(const Eigen::Vector3d& p) { return {p.x(), p.z(), -p.y()}; }

// Blender's camera model (source: BKE_camera_params_compute_viewplane): the camera looks down
// its local -Z with +Y up; with the sensor fitted to the larger side S, a focal length of lens
// mm on a sensor of sensor mm is lens / sensor * S px, and the view plane moves by shift * S
// px, so the optical axis meets the image at (w / 2 - shift_x S, h / 2 + shift_y S) from the
// top-left edge; OpenCV's pixel centres are half a pixel further.
Eigen::Vector2d BlenderPixel(const json& c, const Eigen::Vector3d& p_world) {
  Eigen::Matrix4d world_from_cam;
  for (int r = 0; r < 4; ++r)
    for (int k = 0; k < 4; ++k) world_from_cam(r, k) = c["matrix_world"][r][k].get<double>();
  const Eigen::Vector3d p = (world_from_cam.inverse() * p_world.homogeneous()).head<3>();
  const double w = c["width_px"].get<double>(), h = c["height_px"].get<double>();
  const double side = std::max(w, h);
  const double f = c["lens_mm"].get<double>() / c["sensor_mm"].get<double>() * side;
  return {w / 2 - c["shift_x"].get<double>() * side + f * p.x() / -p.z() - 0.5,
          h / 2 + c["shift_y"].get<double>() * side - f * p.y() / -p.z() - 0.5};
}

TEST_CASE("Blender script: each camera, in Blender's camera model, projects the model where Facet's does") {
  facet::testing::SyntheticScene scene = facet::testing::MakeBoxScene();  // principal point off centre
  facet::Image extra = scene.project.images[0];
  extra.id = scene.project.NewId();
  extra.path = "photos/it's uncalibrated.jpg";  // a quote in a name must not break the script
  extra.camera_calibrated = false;
  scene.project.images.push_back(extra);
  scene.project.images[0].path = "photos/o'clock.jpg";
  const std::string script = facet::BlenderSetupScript(scene.project, "/work/proj/p.facet", "/work/proj/model.glb");
  const size_t begin = script.find("# facet-cameras-begin\n");
  const size_t end = script.find("# facet-cameras-end");
  REQUIRE(begin != std::string::npos);
  REQUIRE(end != std::string::npos);
  std::string data = script.substr(begin + 22, end - begin - 22);
  CHECK(data.find('\'') == std::string::npos);
  const json cameras = json::parse(data);
  REQUIRE(cameras.size() == 1);  // the uncalibrated image has none
  const json& c = cameras[0];
  CHECK(c["photo"] == "/work/proj/photos/o'clock.jpg");
  CHECK(c["name"] == "o'clock.jpg");
  CHECK(script.find("MODEL = os.fsdecode(bytes.fromhex(\"" + HexOf("/work/proj/model.glb") + "\"))") !=
        std::string::npos);
  const facet::Camera& camera = scene.project.images[0].camera;
  REQUIRE_FALSE(camera.HasDistortion());
  REQUIRE(camera.principal_point_px != Eigen::Vector2d((camera.width_px - 1) / 2.0, (camera.height_px - 1) / 2.0));
  constexpr double kPixelTolerance = 1e-9;
  int checked = 0;
  for (const facet::Primitive& prim : scene.project.primitives) {
    for (int v = 0; v < prim.mesh.NumVertices(); ++v) {
      const Eigen::Vector3d p = facet::VertexInWorld(scene.project, {prim.id, static_cast<facet::VertexId>(v)});
      const Eigen::Vector2d facet_px = camera.Project(p);
      const Eigen::Vector2d blender_px = BlenderPixel(c, p);
      CAPTURE(v);
      CHECK((facet_px - blender_px).norm() < kPixelTolerance);
      ++checked;
    }
  }
  CHECK(checked >= 8);
}

// The cameras block of a Blender script, found as the script finds it (whole marker lines).
json CamerasBlock(const std::string& script) {
  const std::string begin_marker = "\n# facet-cameras-begin\n", end_marker = "\n# facet-cameras-end\n";
  const size_t begin = script.find(begin_marker);
  REQUIRE(begin != std::string::npos);
  const size_t end = script.find(end_marker, begin + begin_marker.size());
  REQUIRE(end != std::string::npos);
  CHECK(script.find(end_marker, end + 1) == std::string::npos);  // one block, one end
  return json::parse(script.substr(begin + begin_marker.size(), end - begin - begin_marker.size()));
}

// Names a careless user or an attacker gives a photo: quotes, backslashes, newlines, Python's
// string ends, the script's own markers, code, bytes that are not UTF-8, and unicode. 49 of
// them, as the probe's (issue 25: "x# facet-cameras-end.jpg" stopped the script in json.loads).
std::vector<std::string> HostileNames() {
  return {"x# facet-cameras-end.jpg",
          "# facet-cameras-end",
          "\n# facet-cameras-end\n.jpg",
          "# facet-cameras-begin.jpg",
          "\n# facet-cameras-begin\n[].jpg",
          "'''.jpg",
          "\"\"\".jpg",
          "''''''.jpg",
          "a'b.jpg",
          "a\"b.jpg",
          "back\\slash.jpg",
          "ends with backslash\\",
          "\\'''.jpg",
          "\\u0027.jpg",
          "\\x27.jpg",
          "\\n.jpg",
          "new\nline.jpg",
          "carriage\rreturn.jpg",
          "tab\tname.jpg",
          "form\ffeed.jpg",
          "bell\a.jpg",
          "del\x7f.jpg",
          "'''); __import__('os').system('touch CANARY') #.jpg",
          "\"\"\"); __import__('os').system('touch CANARY') #.jpg",
          "\n__import__('os').system('touch CANARY')\n.jpg",
          "'''.split('x')[0]); import os; os.system('touch CANARY'); print(r'''.jpg",
          "]}; import os; os.system('touch CANARY'); x = [{.jpg",
          "{\"name\": \"evil\"}.jpg",
          "[1, 2, 3].jpg",
          "null",
          "$(touch CANARY).jpg",
          "`touch CANARY`.jpg",
          "%s%n%x.jpg",
          "{0}{1}.jpg",
          "m\xff.jpg",
          "\xfe\xfd.jpg",
          "\xc3.jpg",
          "\xed\xa0\x80.jpg",
          "\xc0\xaf.jpg",
          "caf\xc3\xa9.jpg",
          "\xe2\x98\x83 snowman.jpg",
          "\xf0\x9f\x93\xb7 camera.jpg",
          "\xe5\x86\x99\xe7\x9c\x9f.jpg",
          "\xd8\xb5\xd9\x88\xd8\xb1\xd8\xa9.jpg",
          "\xe2\x80\xae"
          "gpj.exe",
          "zero\xe2\x80\x8bwidth.jpg",
          " leading and trailing spaces ",
          ".hidden",
          std::string(200, 'n') + ".jpg"};
}

// A stand-in for Blender's Python API, just enough for the script: it records each camera
// (name, lens, shifts, matrix, the photo path's bytes) and the model it imports, and writes
// them as JSON when the script ends.
constexpr const char* kFakeBpy = R"PY(import atexit, json, os

_record = {"model_hex": None, "cameras": []}


class _Any:
    def __init__(self, **kw):
        self.__dict__.update(kw)


class _Collection(list):
    def new(self, *args):
        item = _Any(name=args[0] if args else "", background_images=_Collection(), type="CAMERA")
        self.append(item)
        return item

    def remove(self, item, do_unlink=True):
        self[:] = [x for x in self if x is not item]

    def load(self, path, check_existing=True):
        return _Any(filepath=path)


class _Objects(_Collection):
    def new(self, name, data):
        obj = _Any(name=name, data=data, type="CAMERA", matrix_world=None)
        self.append(obj)
        return obj


def _import_gltf(filepath):
    _record["model_hex"] = os.fsencode(filepath).hex()


data = _Any(filepath="", objects=_Objects(), cameras=_Collection(), images=_Collection())
ops = _Any(import_scene=_Any(gltf=_import_gltf, obj=_import_gltf), wm=_Any(obj_import=_import_gltf))
_scene = _Any(collection=_Any(objects=_Any(link=lambda obj: None)), camera=None, render=_Any())
context = _Any(scene=_scene)


@atexit.register
def _write():
    for obj in data.objects:
        d = obj.data
        photo = d.background_images[0].image.filepath if d.background_images else None
        _record["cameras"].append({"name": obj.name, "lens": d.lens, "shift_x": d.shift_x, "shift_y": d.shift_y,
                                   "matrix": obj.matrix_world.rows,
                                   "photo_hex": None if photo is None else os.fsencode(photo).hex()})
    with open(os.environ["FACET_FAKE_BPY_OUT"], "w") as out:
        json.dump(_record, out)
)PY";

constexpr const char* kFakeMathutils = R"PY(class Matrix:
    def __init__(self, rows):
        self.rows = [list(r) for r in rows]
)PY";

TEST_CASE("Blender script: 49 hostile photo names load unchanged, and no code in them runs") {
  facet::testing::SyntheticScene scene = facet::testing::MakeBoxScene();
  const facet::testing::TempDir temp_dir("blender_hostile");
  const fs::path& dir = temp_dir.path;
  const std::vector<std::string> names = HostileNames();
  REQUIRE(names.size() == 49);
  const facet::Image base = scene.project.images[0];
  scene.project.images.clear();
  for (const std::string& name : names) {
    facet::Image image = base;
    image.id = scene.project.NewId();
    image.path = "photos/" + name;
    scene.project.images.push_back(image);
    // The photo exists, so the script loads it as the camera's background.
    fs::create_directories(dir / "photos");
    std::ofstream(dir / "photos" / name) << "not a real photo";
  }
  const std::string project_path = (dir / "p.facet").string();
  const std::string model_path = (dir / "m\xff'''\".glb").string();
  const std::string script = facet::BlenderSetupScript(scene.project, project_path, model_path);

  // The data block alone: the names as written (UTF-8, invalid bytes as U+FFFD), the photo
  // paths' exact bytes.
  const json cameras = CamerasBlock(script);
  REQUIRE(cameras.size() == names.size());
  for (size_t i = 0; i < names.size(); ++i) {
    CAPTURE(i);
    const std::string photo = (dir / "photos" / names[i]).lexically_normal().string();
    CHECK(cameras[i]["name"].get<std::string>() == facet::ValidUtf8OrReplaced(names[i]));
    CHECK(cameras[i]["photo_hex"].get<std::string>() == HexOf(photo));
  }

  // The script itself, run by Python with a fake bpy: when python3 is on the machine (it is
  // wherever the project's scripts run; otherwise the block check above is what is tested).
  if (std::system("python3 -c 'import json, os, atexit' > /dev/null 2>&1") != 0) {
    MESSAGE("python3 not found: the script was checked as data only");
    return;
  }
  const fs::path stubs = dir / "stubs";
  fs::create_directories(stubs);
  std::ofstream(stubs / "bpy.py") << kFakeBpy;
  std::ofstream(stubs / "mathutils.py") << kFakeMathutils;
  std::ofstream(dir / "setup.py", std::ios::binary) << script;
  const fs::path out = dir / "ran.json";
  const std::string command = "cd '" + dir.string() + "' && PYTHONPATH='" + stubs.string() + "' FACET_FAKE_BPY_OUT='" +
                              out.string() + "' python3 setup.py > '" + (dir / "python.log").string() + "' 2>&1";
  const int status = std::system(command.c_str());
  std::ifstream log_in(dir / "python.log");
  const std::string log((std::istreambuf_iterator<char>(log_in)), {});
  INFO("python: " << log);
  REQUIRE(status == 0);
  CHECK_FALSE(fs::exists(dir / "CANARY"));  // no name's code ran
  std::ifstream ran_in(out);
  const json ran = json::parse(ran_in);
  CHECK(ran["model_hex"] == HexOf(model_path));
  REQUIRE(ran["cameras"].size() == names.size());
  constexpr double kExact = 0.0;  // the numbers go through JSON with 17 digits: bit-exact
  for (size_t i = 0; i < names.size(); ++i) {
    CAPTURE(i);
    const json& got = ran["cameras"][i];
    CHECK(got["name"].get<std::string>() == facet::ValidUtf8OrReplaced(names[i]));
    CHECK(got["photo_hex"] == cameras[i]["photo_hex"]);
    CHECK(std::abs(got["lens"].get<double>() - cameras[i]["lens_mm"].get<double>()) <= kExact);
    CHECK(got["matrix"] == cameras[i]["matrix_world"]);
  }
}

}  // namespace

TEST_CASE("GLB: container, accessors, bounds, embedded atlas and triangles") {
  const Fixture f = BakedScene();
  const facet::testing::TempDir temp_dir("glb");
  const fs::path& dir = temp_dir.path;
  const fs::path path = dir / "model.glb";
  const facet::ExportSummary summary = facet::ExportGlb(f.mesh, f.scene.project, path.string());
  REQUIRE_MESSAGE(summary.success, summary.message);
  CHECK(summary.files_written == std::vector<std::string>{path.string()});
  CHECK_GLTF_VALID(path.string());
  // Atomic write leaves no temporary file behind.
  CHECK(std::distance(fs::directory_iterator(dir), fs::directory_iterator()) == 1);

  const Glb glb = ParseGlb(path);
  const json& g = glb.gltf;
  CHECK(g["asset"]["version"] == "2.0");
  CHECK(g["buffers"].size() == 1);
  CHECK(g["buffers"][0]["byteLength"].get<size_t>() <= glb.bin.size());
  REQUIRE(g["meshes"].size() == 1);
  const json& primitives = g["meshes"][0]["primitives"];
  REQUIRE(primitives.size() == 2);  // textured and plain faces

  const int position_accessor = primitives[0]["attributes"]["POSITION"];
  const json& pa = g["accessors"][position_accessor];
  CHECK(pa["count"] == f.mesh.positions.size());
  CHECK(pa["componentType"] == 5126);
  CHECK(pa["type"] == "VEC3");
  const std::vector<float> positions = AccessorData<float>(glb, position_accessor, 3);
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(1e30f), hi = -lo;
  constexpr double kPositionTolerance = 1e-6;  // float storage of metre-scale values
  for (size_t v = 0; v < f.mesh.positions.size(); ++v) {
    const Eigen::Vector3f p(positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]);
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
    CHECK((p.cast<double>() - YUp(f.mesh.positions[v].cast<double>())).norm() < kPositionTolerance);
  }
  for (int k = 0; k < 3; ++k) {
    CHECK(pa["min"][k].get<float>() == lo[k]);
    CHECK(pa["max"][k].get<float>() == hi[k]);
  }
  // The box spans z in [0, 2.5] in world, i.e. y in [0, 2.5] and z in [-3, 0] in glTF.
  CHECK(std::abs(pa["max"][1].get<double>() - 2.5) < kPositionTolerance);
  CHECK(std::abs(pa["min"][2].get<double>() + 3.0) < kPositionTolerance);

  const int normal_accessor = primitives[0]["attributes"]["NORMAL"];
  const std::vector<float> normals = AccessorData<float>(glb, normal_accessor, 3);
  const int uv_accessor = primitives[0]["attributes"]["TEXCOORD_0"];
  CHECK(g["accessors"][uv_accessor]["count"] == f.mesh.uvs.size());
  const std::vector<float> uvs = AccessorData<float>(glb, uv_accessor, 2);
  for (float u : uvs) CHECK((u >= 0.0f && u <= 1.0f));

  // Triangles: all indices present once, and each still counter-clockwise around its
  // (converted) normal, since the axis change is a rotation.
  size_t index_total = 0, textured_triangles = 0;
  for (size_t p = 0; p < primitives.size(); ++p) {
    const json& acc = g["accessors"][primitives[p]["indices"].get<int>()];
    CHECK(acc["componentType"] == 5125);
    const std::vector<std::uint32_t> idx = AccessorData<std::uint32_t>(glb, primitives[p]["indices"], 1);
    index_total += idx.size();
    if (primitives[p]["attributes"].contains("TEXCOORD_0")) textured_triangles += idx.size() / 3;
    for (size_t t = 0; t < idx.size(); t += 3) {
      REQUIRE((idx[t] < f.mesh.positions.size() && idx[t + 1] < f.mesh.positions.size() &&
               idx[t + 2] < f.mesh.positions.size()));
      auto pos = [&](std::uint32_t v) {
        return Eigen::Vector3d(positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]);
      };
      const Eigen::Vector3d n = (pos(idx[t + 1]) - pos(idx[t])).cross(pos(idx[t + 2]) - pos(idx[t])).normalized();
      const Eigen::Vector3d stored(normals[3 * idx[t]], normals[3 * idx[t] + 1], normals[3 * idx[t] + 2]);
      CHECK((n - stored).norm() < 1e-5);
    }
  }
  CHECK(index_total == f.mesh.indices.size());
  CHECK(textured_triangles == 6);  // 3 faces

  // Material, texture, sampler and the atlas PNG.
  const json& textured_material = g["materials"][primitives[0]["material"].get<int>()];
  const int texture = textured_material["pbrMetallicRoughness"]["baseColorTexture"]["index"];
  const json& image = g["images"][g["textures"][texture]["source"].get<int>()];
  CHECK(image["mimeType"] == "image/png");
  CHECK(g["textures"][texture].contains("sampler"));
  size_t png_length = 0;
  const std::uint8_t* png = ViewData(glb, image["bufferView"], &png_length);
  const cv::Mat decoded = cv::imdecode(
      cv::Mat(1, static_cast<int>(png_length), CV_8UC1, const_cast<std::uint8_t*>(png)), cv::IMREAD_UNCHANGED);
  REQUIRE(!decoded.empty());
  CHECK(decoded.cols == f.mesh.atlas.width);
  CHECK(decoded.rows == f.mesh.atlas.height);
  REQUIRE(decoded.type() == CV_8UC4);
  int differing = 0;
  for (int y = 0; y < decoded.rows; ++y) {
    for (int x = 0; x < decoded.cols; ++x) {
      const cv::Vec4b bgra = decoded.at<cv::Vec4b>(y, x);
      const std::uint8_t* rgba = f.mesh.atlas.At(x, y);
      differing += bgra[2] != rgba[0] || bgra[1] != rgba[1] || bgra[0] != rgba[2] || bgra[3] != rgba[3];
    }
  }
  CHECK(differing == 0);
  const json& plain_material = g["materials"][primitives[1]["material"].get<int>()];
  CHECK_FALSE(plain_material["pbrMetallicRoughness"].contains("baseColorTexture"));
}

TEST_CASE("GLB: one camera node per calibrated image, at the camera's pose in Y-up axes") {
  Fixture f = BakedScene();
  // A second, uncalibrated image must not produce a camera.
  facet::Image extra = f.scene.project.images[0];
  extra.id = f.scene.project.NewId();
  extra.path = "not_calibrated.jpg";
  extra.camera_calibrated = false;
  f.scene.project.images.push_back(extra);
  f.mesh.atlas = facet::ImageRgba8();  // plain mesh: one primitive, no image
  const facet::testing::TempDir temp_path("glb_camera");
  const fs::path path = temp_path.path / "model.glb";
  const facet::ExportSummary summary = facet::ExportGlb(f.mesh, f.scene.project, path.string());
  REQUIRE_MESSAGE(summary.success, summary.message);
  CHECK_GLTF_VALID(path.string());
  const Glb glb = ParseGlb(path);
  const json& g = glb.gltf;
  CHECK(g["meshes"][0]["primitives"].size() == 1);
  CHECK_FALSE(g.contains("images"));

  REQUIRE(g["cameras"].size() == 1);
  const facet::Camera& cam = f.scene.true_camera;
  const json& perspective = g["cameras"][0]["perspective"];
  CHECK(g["cameras"][0]["type"] == "perspective");
  const double yfov = perspective["yfov"];
  const double expected_yfov = 2.0 * std::atan(cam.height_px / (2.0 * cam.focal_px));
  constexpr double kAngleTolerance = 1e-12;
  CHECK(std::abs(yfov - expected_yfov) < kAngleTolerance);
  CHECK(std::abs(perspective["aspectRatio"].get<double>() - 1024.0 / 768.0) < 1e-12);
  CHECK(perspective["znear"].get<double>() > 0.0);

  const json* node = nullptr;
  for (const json& n : g["nodes"]) {
    if (n.contains("camera")) {
      CHECK(node == nullptr);
      node = &n;
    }
  }
  REQUIRE(node != nullptr);
  CHECK((*node)["name"] == "synthetic.png");
  const Eigen::Quaterniond q((*node)["rotation"][3].get<double>(), (*node)["rotation"][0].get<double>(),
                             (*node)["rotation"][1].get<double>(), (*node)["rotation"][2].get<double>());
  constexpr double kPoseTolerance = 1e-9;
  CHECK(std::abs(q.norm() - 1.0) < kPoseTolerance);
  const Eigen::Matrix3d r = q.normalized().toRotationMatrix();
  CHECK((r.transpose() * r - Eigen::Matrix3d::Identity()).norm() < kPoseTolerance);
  CHECK(std::abs(r.determinant() - 1.0) < kPoseTolerance);
  const Eigen::Vector3d t((*node)["translation"][0].get<double>(), (*node)["translation"][1].get<double>(),
                          (*node)["translation"][2].get<double>());
  const Eigen::Vector3d c = cam.CenterInWorld();
  CAPTURE(t.transpose());
  CAPTURE(c.transpose());
  CHECK((t - Eigen::Vector3d(c.x(), c.z(), -c.y())).norm() < kPoseTolerance);

  // A glTF viewer looking through this node (down -Z, +Y up) sees each box corner at the
  // pixel the Facet camera projects it to.
  const Eigen::Vector2d pp = cam.principal_point_px;
  constexpr double kPixelTolerance = 1e-6;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d corner = f.scene.true_box.mesh.vertex(c).position;
    const Eigen::Vector3d p_in_gltf_cam = r.transpose() * (YUp(corner) - t);
    REQUIRE(p_in_gltf_cam.z() < 0);
    const Eigen::Vector2d uv(pp.x() + cam.focal_px * p_in_gltf_cam.x() / -p_in_gltf_cam.z(),
                             pp.y() - cam.focal_px * p_in_gltf_cam.y() / -p_in_gltf_cam.z());
    const Eigen::Vector2d expected = cam.Project(corner);
    CAPTURE(uv.transpose());
    CAPTURE(expected.transpose());
    CHECK((uv - expected).norm() < kPixelTolerance);
  }
}

TEST_CASE("OBJ: counts, flipped UVs in [0,1], material and texture side by side") {
  const Fixture f = BakedScene();
  const facet::testing::TempDir temp_dir("obj");
  const fs::path& dir = temp_dir.path;
  const facet::ExportSummary summary = facet::ExportObj(f.mesh, (dir / "house.obj").string());
  REQUIRE_MESSAGE(summary.success, summary.message);
  CHECK(summary.files_written.size() == 3);
  REQUIRE(fs::exists(dir / "house.obj"));
  REQUIRE(fs::exists(dir / "house.mtl"));
  REQUIRE(fs::exists(dir / "house.png"));
  CHECK(std::distance(fs::directory_iterator(dir), fs::directory_iterator()) == 3);

  std::ifstream obj(dir / "house.obj");
  std::string line, mtllib;
  std::vector<Eigen::Vector3d> v;
  std::vector<Eigen::Vector2d> vt;
  size_t vn = 0, faces = 0, textured_faces = 0, bad_refs = 0;
  std::string material;
  while (std::getline(obj, line)) {
    std::istringstream in(line);
    std::string tag;
    in >> tag;
    if (tag == "v") {
      Eigen::Vector3d p;
      in >> p.x() >> p.y() >> p.z();
      v.push_back(p);
    } else if (tag == "vt") {
      Eigen::Vector2d t;
      in >> t.x() >> t.y();
      vt.push_back(t);
    } else if (tag == "vn") {
      ++vn;
    } else if (tag == "mtllib") {
      in >> mtllib;
    } else if (tag == "usemtl") {
      in >> material;
    } else if (tag == "f") {
      ++faces;
      textured_faces += material == "facet_textured";
      std::string corner;
      int corners = 0;
      while (in >> corner) {
        ++corners;
        int vi = 0, ti = 0, ni = 0;
        if (std::sscanf(corner.c_str(), "%d/%d/%d", &vi, &ti, &ni) != 3 &&
            std::sscanf(corner.c_str(), "%d//%d", &vi, &ni) != 2) {
          ++bad_refs;
          continue;
        }
        const size_t n = f.mesh.positions.size();
        bad_refs += vi < 1 || static_cast<size_t>(vi) > n || ti < 0 || static_cast<size_t>(ti) > n || ni < 1 ||
                    static_cast<size_t>(ni) > n;
      }
      CHECK(corners == 3);
    }
  }
  CHECK(v.size() == f.mesh.positions.size());
  CHECK(vt.size() == f.mesh.uvs.size());
  CHECK(vn == f.mesh.normals.size());
  CHECK(faces == f.mesh.indices.size() / 3);
  CHECK(textured_faces == 6);
  CHECK(bad_refs == 0);
  CHECK(mtllib == "house.mtl");
  constexpr double kTextTolerance = 1e-6;  // 9 significant digits of floats
  for (size_t i = 0; i < vt.size(); ++i) {
    CHECK((vt[i].x() >= 0 && vt[i].x() <= 1 && vt[i].y() >= 0 && vt[i].y() <= 1));
    CHECK(std::abs(vt[i].y() - (1.0 - f.mesh.uvs[i].y())) < kTextTolerance);
    CHECK((v[i] - YUp(f.mesh.positions[i].cast<double>())).norm() < kTextTolerance);
  }

  std::ifstream mtl(dir / "house.mtl");
  const std::string mtl_text((std::istreambuf_iterator<char>(mtl)), {});
  CHECK(mtl_text.find("newmtl facet_textured") != std::string::npos);
  CHECK(mtl_text.find("newmtl facet_untextured") != std::string::npos);
  CHECK(mtl_text.find("map_Kd house.png") != std::string::npos);
  const cv::Mat png = cv::imread((dir / "house.png").string(), cv::IMREAD_UNCHANGED);
  CHECK(png.cols == f.mesh.atlas.width);
  CHECK(png.rows == f.mesh.atlas.height);

  // Without texture: no PNG, no map.
  const facet::testing::TempDir temp_plain_dir("obj_plain");
  const fs::path& plain_dir = temp_plain_dir.path;
  const auto plain = facet::ExportObj(facet::BuildUntexturedMesh(f.scene.project), (plain_dir / "box").string());
  REQUIRE_MESSAGE(plain.success, plain.message);
  CHECK(fs::exists(plain_dir / "box.obj"));
  CHECK_FALSE(fs::exists(plain_dir / "box.png"));
  std::ifstream plain_mtl(plain_dir / "box.mtl");
  const std::string plain_mtl_text((std::istreambuf_iterator<char>(plain_mtl)), {});
  CHECK(plain_mtl_text.find("map_Kd") == std::string::npos);
}

TEST_CASE("GLB and OBJ round trip: vertex and triangle counts of a split box and a wedge roof") {
  Fixture f;
  f.scene = facet::testing::MakeBoxScene();
  facet::Project& project = f.scene.project;
  // E_split two opposite sides of one box face and V_connect them: 7 faces, two of them
  // with a straight corner.
  facet::PolyMesh& box = project.primitives[0].mesh;
  facet::FaceId face = 0;
  while (!box.IsFace(face)) ++face;
  const std::vector<facet::HalfedgeId> sides = facet::FaceHalfedges(box, face);
  const auto a = facet::ESplit(&box, facet::PolyMesh::EdgeOf(sides[0]), 0.5);
  const auto b = facet::ESplit(&box, facet::PolyMesh::EdgeOf(sides[2]), 0.5);
  REQUIRE(a.ok);
  REQUIRE(b.ok);
  REQUIRE(facet::VConnect(&box, face, a.vertex, b.vertex).ok);
  // A wedge roof on top of the box.
  facet::Id roof_id = facet::kNoId;
  std::string message;
  REQUIRE(facet::AddPrimitiveToProject(&project, facet::MakeWedge(facet::kNoId, {1.0, 1.0, 1.2}), "roof", &roof_id,
                                       &message));
  project.FindPrimitive(roof_id)->attached_to = f.scene.box_id;
  facet::RefreshAllPrimitives(&project);

  size_t expected_vertices = 0, expected_triangles = 0;
  for (const facet::Primitive& primitive : project.primitives) {
    for (facet::FaceId g = 0; g < primitive.mesh.FaceIdEnd(); ++g) {
      if (!primitive.mesh.IsFace(g)) continue;
      expected_vertices += facet::FaceDegree(primitive.mesh, g);
      expected_triangles += facet::FaceDegree(primitive.mesh, g) - 2;
    }
  }
  // Box quads; + 2 for the split face, + 1 for each neighbour given a straight corner; wedge.
  CHECK(expected_triangles == 12 + 2 + 2 + 8);
  const auto bake = facet::BakeTexturedMesh(
      project, {RampPhoto(f.scene.true_camera.width_px, f.scene.true_camera.height_px)}, {}, &f.mesh);
  REQUIRE_MESSAGE(bake.IsUsable(), bake.message);
  REQUIRE(f.mesh.positions.size() == expected_vertices);
  REQUIRE(f.mesh.indices.size() == 3 * expected_triangles);
  size_t textured_triangles = 0;
  for (auto t : f.mesh.triangle_textured) textured_triangles += t;
  CHECK(textured_triangles > 0);
  CHECK(textured_triangles < expected_triangles);

  const facet::testing::TempDir temp_dir("roundtrip");
  const fs::path& dir = temp_dir.path;
  const auto glb_summary = facet::ExportGlb(f.mesh, project, (dir / "m.glb").string());
  REQUIRE_MESSAGE(glb_summary.success, glb_summary.message);
  CHECK_GLTF_VALID((dir / "m.glb").string());
  const Glb glb = ParseGlb(dir / "m.glb");
  const json& primitives = glb.gltf["meshes"][0]["primitives"];
  REQUIRE(primitives.size() == 2);
  size_t glb_triangles = 0, glb_textured = 0;
  for (const json& p : primitives) {
    CHECK(glb.gltf["accessors"][p["attributes"]["POSITION"].get<int>()]["count"] == expected_vertices);
    const size_t n = glb.gltf["accessors"][p["indices"].get<int>()]["count"].get<size_t>() / 3;
    glb_triangles += n;
    if (p["attributes"].contains("TEXCOORD_0")) glb_textured += n;
  }
  CHECK(glb_triangles == expected_triangles);
  CHECK(glb_textured == textured_triangles);

  const auto obj_summary = facet::ExportObj(f.mesh, (dir / "m.obj").string());
  REQUIRE_MESSAGE(obj_summary.success, obj_summary.message);
  std::ifstream obj(dir / "m.obj");
  std::string line;
  size_t v = 0, vt = 0, vn = 0, faces = 0;
  while (std::getline(obj, line)) {
    v += line.rfind("v ", 0) == 0;
    vt += line.rfind("vt ", 0) == 0;
    vn += line.rfind("vn ", 0) == 0;
    faces += line.rfind("f ", 0) == 0;
  }
  CHECK(v == expected_vertices);
  CHECK(vt == expected_vertices);
  CHECK(vn == expected_vertices);
  CHECK(faces == expected_triangles);
}

TEST_CASE("export errors: unwritable path, empty or malformed mesh") {
  const Fixture f = BakedScene();
  const facet::testing::TempDir temp_missing("errors");
  const fs::path missing = temp_missing.path / "no_such_folder";
  auto s = facet::ExportGlb(f.mesh, f.scene.project, (missing / "m.glb").string());
  CHECK_FALSE(s.success);
  CHECK(s.message.find("m.glb") != std::string::npos);
  MESSAGE(s.message);
  s = facet::ExportObj(f.mesh, (missing / "m.obj").string());
  CHECK_FALSE(s.success);
  CHECK_FALSE(s.message.empty());
  CHECK_FALSE(fs::exists(missing));

  const facet::testing::TempDir temp_dir("errors_mesh");
  const fs::path& dir = temp_dir.path;
  s = facet::ExportGlb(facet::TexturedMesh(), f.scene.project, (dir / "e.glb").string());
  CHECK_FALSE(s.success);
  CHECK(s.message.find("empty") != std::string::npos);
  s = facet::ExportObj(facet::TexturedMesh(), (dir / "e.obj").string());
  CHECK_FALSE(s.success);
  facet::TexturedMesh broken = f.mesh;
  broken.indices.push_back(static_cast<std::uint32_t>(broken.positions.size()));
  broken.indices.push_back(0);
  broken.indices.push_back(1);
  broken.triangle_textured.push_back(0);
  s = facet::ExportGlb(broken, f.scene.project, (dir / "b.glb").string());
  CHECK_FALSE(s.success);
  CHECK(std::distance(fs::directory_iterator(dir), fs::directory_iterator()) == 0);
}

TEST_CASE("GLB and OBJ with a paged atlas: one image, texture and material per page, each face on its page") {
  // The box seen from four sides (five faces textured) baked into 512 px pages: two pages.
  facet::testing::SyntheticScene scene = facet::testing::MakeBoxScene();
  const facet::testing::SyntheticSceneOptions o;
  for (double azimuth : {90.0, 180.0, 270.0}) {
    facet::testing::SyntheticSceneOptions ov = o;
    ov.camera_center =
        o.look_at + Eigen::AngleAxisd(azimuth * M_PI / 180.0, Eigen::Vector3d::UnitZ()) * (o.camera_center - o.look_at);
    facet::Image image = scene.project.images[0];
    image.id = scene.project.NewId();
    image.camera = facet::testing::MakeLookAtCamera(ov);
    scene.project.images.push_back(image);
  }
  std::vector<facet::ImageRgba8> photos(scene.project.images.size(), RampPhoto(o.width_px, o.height_px));
  facet::TextureBakeOptions options;
  options.max_atlas_size = 512;
  options.max_atlas_pages = 4;
  facet::TexturedMesh mesh;
  const auto bake = facet::BakeTexturedMesh(scene.project, photos, options, &mesh);
  REQUIRE_MESSAGE(bake.IsUsable(), bake.message);
  REQUIRE(mesh.AtlasPageCount() >= 2);
  size_t textured_triangles = 0;
  for (auto t : mesh.triangle_textured) textured_triangles += t;

  const facet::testing::TempDir temp_dir("paged");
  const fs::path& dir = temp_dir.path;
  const facet::ExportSummary summary = facet::ExportGlb(mesh, scene.project, (dir / "paged.glb").string());
  REQUIRE_MESSAGE(summary.success, summary.message);
  CHECK_GLTF_VALID((dir / "paged.glb").string());
  const Glb glb = ParseGlb(dir / "paged.glb");
  const json& g = glb.gltf;
  const int pages = mesh.AtlasPageCount();
  CHECK(g["images"].size() == static_cast<size_t>(pages));
  CHECK(g["textures"].size() == static_cast<size_t>(pages));
  const json& primitives = g["meshes"][0]["primitives"];
  size_t exported_textured = 0;
  int textured_primitives = 0;
  for (const json& primitive : primitives) {
    const json& material = g["materials"][primitive["material"].get<int>()];
    if (!material["pbrMetallicRoughness"].contains("baseColorTexture")) continue;
    ++textured_primitives;
    // The material's name says its page; its image decodes to that page, pixel for pixel.
    const std::string name = material["name"];
    const int page = name == "facet_textured" ? 0 : std::stoi(name.substr(std::string("facet_textured_page").size()));
    CAPTURE(name);
    REQUIRE(page < pages);
    const int texture = material["pbrMetallicRoughness"]["baseColorTexture"]["index"];
    const json& image = g["images"][g["textures"][texture]["source"].get<int>()];
    size_t png_length = 0;
    const std::uint8_t* png = ViewData(glb, image["bufferView"], &png_length);
    const cv::Mat decoded = cv::imdecode(
        cv::Mat(1, static_cast<int>(png_length), CV_8UC1, const_cast<std::uint8_t*>(png)), cv::IMREAD_UNCHANGED);
    const facet::ImageRgba8& expected = mesh.AtlasPage(page);
    REQUIRE(decoded.cols == expected.width);
    REQUIRE(decoded.rows == expected.height);
    int differing = 0;
    for (int y = 0; y < decoded.rows; ++y) {
      for (int x = 0; x < decoded.cols; ++x) {
        const cv::Vec4b bgra = decoded.at<cv::Vec4b>(y, x);
        const std::uint8_t* rgba = expected.At(x, y);
        differing += bgra[2] != rgba[0] || bgra[1] != rgba[1] || bgra[0] != rgba[2] || bgra[3] != rgba[3];
      }
    }
    CHECK(differing == 0);
    // Exactly the triangles the bake put on that page.
    const std::vector<std::uint32_t> idx = AccessorData<std::uint32_t>(glb, primitive["indices"], 1);
    size_t on_page = 0;
    for (size_t t = 0; t < mesh.triangle_page.size(); ++t)
      on_page += mesh.triangle_textured[t] && mesh.triangle_page[t] == page;
    CHECK(idx.size() == 3 * on_page);
    exported_textured += idx.size() / 3;
  }
  CHECK(textured_primitives == pages);
  CHECK(exported_textured == textured_triangles);

  const facet::ExportSummary obj = facet::ExportObj(mesh, (dir / "paged.obj").string());
  REQUIRE_MESSAGE(obj.success, obj.message);
  std::ifstream mtl_in(dir / "paged.mtl");
  const std::string mtl((std::istreambuf_iterator<char>(mtl_in)), {});
  for (int page = 1; page < pages; ++page) {
    const std::string png_name = "paged_page" + std::to_string(page) + ".png";
    CHECK(fs::exists(dir / png_name));
    CHECK(mtl.find("newmtl facet_textured_page" + std::to_string(page)) != std::string::npos);
    CHECK(mtl.find("map_Kd " + png_name) != std::string::npos);
    const cv::Mat png = cv::imread((dir / png_name).string(), cv::IMREAD_UNCHANGED);
    CHECK(png.cols == mesh.AtlasPage(page).width);
  }
}

namespace {

// Writes a GLB from a JSON document and a BIN chunk (both padded), for the validator's own test.
void WriteGlb(const fs::path& path, const json& gltf, const std::vector<std::uint8_t>& bin) {
  std::string text = gltf.dump();
  while (text.size() % 4 != 0) text.push_back(' ');
  std::vector<std::uint8_t> padded = bin;
  while (padded.size() % 4 != 0) padded.push_back(0);
  std::string out;
  auto u32 = [&](std::uint32_t v) {
    for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
  };
  u32(0x46546C67);
  u32(2);
  u32(static_cast<std::uint32_t>(12 + 8 + text.size() + 8 + padded.size()));
  u32(static_cast<std::uint32_t>(text.size()));
  u32(0x4E4F534A);
  out += text;
  u32(static_cast<std::uint32_t>(padded.size()));
  u32(0x004E4942);
  out.append(padded.begin(), padded.end());
  std::ofstream(path, std::ios::binary) << out;
}

}  // namespace

TEST_CASE("glTF Validator: it runs, and it reports an error in a GLB that has one") {
  // Without this the zero-error checks above could pass on a validator that never looks.
  const Fixture f = BakedScene();
  const facet::testing::TempDir temp_dir("validator");
  const fs::path& dir = temp_dir.path;
  const fs::path good = dir / "good.glb";
  REQUIRE(facet::ExportGlb(f.mesh, f.scene.project, good.string()).success);
  CHECK_GLTF_VALID(good.string());
  Glb glb = ParseGlb(good);
  // An accessor that claims one vertex more than its bufferView holds.
  glb.gltf["accessors"][0]["count"] = glb.gltf["accessors"][0]["count"].get<size_t>() + 1;
  const fs::path bad = dir / "bad.glb";
  WriteGlb(bad, glb.gltf, glb.bin);
  const facet::testing::GltfValidation v = facet::testing::ValidateGltf(bad.string());
  INFO(v.error);
  REQUIRE(v.ran);
  CHECK(v.errors >= 1);
  CHECK(v.messages.find("ACCESSOR_TOO_LONG") != std::string::npos);
  MESSAGE("the validator on a broken GLB: " << v.messages);
}

TEST_CASE("ReadGlb gives back what ExportGlb wrote: vertices, triangles per material, atlas, camera") {
  const Fixture f = BakedScene();
  const facet::testing::TempDir temp_path("read_back");
  const fs::path path = temp_path.path / "m.glb";
  REQUIRE(facet::ExportGlb(f.mesh, f.scene.project, path.string()).success);
  facet::GltfScene scene;
  const std::string error = facet::ReadGlb(path.string(), {}, &scene);
  REQUIRE_MESSAGE(error.empty(), error);
  // One position run per primitive (textured and plain), each a copy of the mesh's vertices.
  REQUIRE(scene.batches.size() == 2);
  REQUIRE(scene.positions.size() == 2 * f.mesh.positions.size());
  constexpr double kPositionTolerance = 1e-6;
  for (size_t v = 0; v < f.mesh.positions.size(); ++v)
    CHECK((scene.positions[v].cast<double>() - YUp(f.mesh.positions[v].cast<double>())).norm() < kPositionTolerance);
  size_t triangles = 0, textured = 0;
  for (const facet::GltfBatch& b : scene.batches) {
    triangles += b.indices.size() / 3;
    if (b.image >= 0) textured += b.indices.size() / 3;
  }
  size_t expected_textured = 0;
  for (auto t : f.mesh.triangle_textured) expected_textured += t;
  CHECK(triangles == f.mesh.indices.size() / 3);
  CHECK(textured == expected_textured);
  REQUIRE(scene.images.size() == 1);
  CHECK(scene.images[0].pixels == f.mesh.atlas.pixels);
  REQUIRE(scene.cameras.size() == 1);
  const facet::GltfCamera& c = scene.cameras[0];
  CHECK(c.has_principal_point);
  CHECK(c.camera.width_px == f.scene.true_camera.width_px);
  CHECK(c.camera.height_px == f.scene.true_camera.height_px);

  // A damaged file is refused with its name, and the scene is left empty.
  std::string bytes = std::string(std::istreambuf_iterator<char>(std::ifstream(path, std::ios::binary).rdbuf()), {});
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes.substr(0, bytes.size() / 2);
  const std::string truncated = facet::ReadGlb(path.string(), {}, &scene);
  CHECK(truncated.find(path.string()) != std::string::npos);
  CHECK(truncated.find("truncated") != std::string::npos);
  CHECK(scene.positions.empty());
}

// The Leuven sample's model seen through the camera the exported file holds lands where the
// project's own camera projects it. Read from the file: the vertices (POSITION accessor) and
// each camera (node pose, yfov, aspect ratio and the principal point kept in the camera's
// extras, which glTF's camera cannot hold); compared with Camera::Project of the project.
// The render of the file itself over the photo is tests/app/test_cli.cpp.
TEST_CASE("Leuven sample: every exported camera projects the exported model onto the project's projection") {
  const std::string sample = std::string(FACET_SOURCE_DIR) + "/assets/samples/leuven/street.facet";
  facet::ProjectLoadResult loaded = facet::LoadProject(sample);
  REQUIRE_MESSAGE(loaded.ok(), loaded.error);
  const facet::Project& project = loaded.project;
  // Geometry and cameras are what this checks; the textured render is tests/app/test_cli.cpp's.
  const facet::TexturedMesh mesh = facet::BuildUntexturedMesh(project);
  REQUIRE(!mesh.positions.empty());
  const facet::testing::TempDir temp_path("leuven");
  const fs::path path = temp_path.path / "street.glb";
  const facet::ExportSummary summary = facet::ExportGlb(mesh, project, path.string());
  REQUIRE_MESSAGE(summary.success, summary.message);
  CHECK_GLTF_VALID(path.string());

  facet::GltfScene scene;
  const std::string error = facet::ReadGlb(path.string(), {}, &scene);
  REQUIRE_MESSAGE(error.empty(), error);
  int calibrated = 0;
  for (const facet::Image& image : project.images) calibrated += image.camera_calibrated;
  REQUIRE(calibrated >= 1);
  REQUIRE(scene.cameras.size() == static_cast<size_t>(calibrated));
  // The file's vertices are the mesh's, once per primitive that uses them.
  REQUIRE(scene.positions.size() % mesh.positions.size() == 0);

  size_t camera_index = 0;
  for (const facet::Image& image : project.images) {
    if (!image.camera_calibrated) continue;
    const facet::Camera& truth = image.camera;
    const facet::GltfCamera& exported = scene.cameras[camera_index++];
    CAPTURE(exported.name);
    // The sample's principal point is 23 px off the centre: without the extras every pixel
    // would be off by that much.
    const Eigen::Vector2d centre((truth.width_px - 1) / 2.0, (truth.height_px - 1) / 2.0);
    REQUIRE((truth.principal_point_px - centre).norm() > 10.0);
    CHECK(exported.has_principal_point);
    CHECK(exported.camera.width_px == truth.width_px);
    CHECK(exported.camera.height_px == truth.height_px);
    double worst_px = 0.0, worst_without_extras_px = 0.0;
    facet::Camera without_extras = exported.camera;
    without_extras.principal_point_px = centre;
    int visible = 0;
    for (size_t v = 0; v < scene.positions.size(); ++v) {
      const Eigen::Vector3d p_in_world = mesh.positions[v % mesh.positions.size()].cast<double>();
      if (truth.CamFromWorld(p_in_world).z() <= 0.0) continue;
      ++visible;
      const Eigen::Vector3d p_in_file = scene.positions[v].cast<double>();
      worst_px = std::max(worst_px, (exported.camera.Project(p_in_file) - truth.Project(p_in_world)).norm());
      worst_without_extras_px =
          std::max(worst_without_extras_px, (without_extras.Project(p_in_file) - truth.Project(p_in_world)).norm());
    }
    CHECK(visible >= 8);
    // Float positions 20 m from the camera (6e-8 relative) and the quaternion's doubles: far
    // below a thousandth of a pixel.
    constexpr double kProjectionTolerancePx = 1e-3;
    CHECK(worst_px < kProjectionTolerancePx);
    CHECK(worst_without_extras_px > 10.0);
    MESSAGE("Leuven, camera " << exported.name << ": exported vertices through the exported camera land within "
                              << worst_px << " px of the project's projection (" << worst_without_extras_px
                              << " px with the principal point at the image centre, as glTF alone says)");
  }
}

TEST_CASE("reference meshes: an exported OBJ and GLB read back as references land on the model") {
  const Fixture f = BakedScene();
  const facet::testing::TempDir temp_dir("reference");
  const fs::path& dir = temp_dir.path;
  REQUIRE(facet::ExportObj(f.mesh, (dir / "house.obj").string()).success);
  REQUIRE(facet::ExportGlb(f.mesh, f.scene.project, (dir / "house.glb").string()).success);
  CHECK_GLTF_VALID((dir / "house.glb").string());
  size_t textured = 0;
  for (auto t : f.mesh.triangle_textured) textured += t;
  for (const char* name : {"house.obj", "house.glb"}) {
    CAPTURE(name);
    facet::ReferenceMesh reference;
    const std::string error = facet::ReadReferenceMesh((dir / name).string(), /*y_up=*/true, &reference);
    REQUIRE_MESSAGE(error.empty(), error);
    CHECK(reference.triangles.size() == f.mesh.indices.size() / 3);
    // Every triangle corner is where the model's is, in the world frame (Z up): the Y-up
    // axes of both files are undone. OBJ text keeps 9 digits, GLB floats.
    constexpr double kPositionTolerance = 1e-6;
    double worst = 0.0;
    // OBJ keeps the mesh's vertices in order; the GLB repeats them per primitive.
    for (size_t v = 0; v < reference.positions.size(); ++v) {
      const Eigen::Vector3d model = f.mesh.positions[v % f.mesh.positions.size()].cast<double>();
      worst = std::max(worst, (reference.positions[v] - model).norm());
    }
    CHECK(worst < kPositionTolerance);
    CHECK(reference.lo.z() == doctest::Approx(0.0).epsilon(1e-6));
    CHECK(reference.hi.z() == doctest::Approx(2.5).epsilon(1e-6));
    CHECK(!reference.edges.empty());
  }
  // Z-up axes take the file's numbers as they are: the box's height is then along y.
  facet::ReferenceMesh z_up;
  REQUIRE(facet::ReadReferenceMesh((dir / "house.obj").string(), /*y_up=*/false, &z_up).empty());
  CHECK(z_up.hi.y() == doctest::Approx(2.5).epsilon(1e-6));
}

TEST_CASE("reference meshes: OBJ faces, negative indices and errors that name the file and line") {
  const facet::testing::TempDir temp_dir("reference_obj");
  const fs::path& dir = temp_dir.path;
  const std::string path = (dir / "plan.obj").string();
  std::ofstream(path) << "# a quad and a triangle\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\n"
                         "f 1/1 2/1 3/1 4/1\nv 0 0 1\nf -1 1 2\nusemtl x\n";
  facet::ReferenceMesh mesh;
  std::string error = facet::ReadReferenceMesh(path, /*y_up=*/false, &mesh);
  REQUIRE_MESSAGE(error.empty(), error);
  CHECK(mesh.positions.size() == 5);
  CHECK(mesh.triangles.size() == 3);  // the quad fanned into two
  CHECK(mesh.triangles[2] == std::array<int, 3>{4, 0, 1});
  CHECK(mesh.edges.size() == 6);  // the quad's 4 sides and 2 new ones (edge 0-1 is shared)

  std::ofstream(path, std::ios::trunc) << "v 0 0 0\nv 1 0 0\nf 1 2 3\n";
  error = facet::ReadReferenceMesh(path, true, &mesh);
  CHECK(error.find(path + ", line 3") == 0);
  CHECK(error.find("'3'") != std::string::npos);
  CHECK(mesh.positions.empty());
  std::ofstream(path, std::ios::trunc) << "v 0 0 zero\n";
  CHECK(facet::ReadReferenceMesh(path, true, &mesh).find("line 1: a vertex needs three finite numbers") !=
        std::string::npos);
  std::ofstream(path, std::ios::trunc) << "v 0 0 0\n";
  CHECK(facet::ReadReferenceMesh(path, true, &mesh).find("holds no triangles") != std::string::npos);
  const std::string missing = (dir / "gone.obj").string();
  error = facet::ReadReferenceMesh(missing, true, &mesh);
  CHECK(error.find(missing) != std::string::npos);
  MESSAGE("a missing reference: " << error);
  CHECK(facet::ReadReferenceMesh((dir / "plan.stl").string(), true, &mesh).find(".obj or a glTF .glb or .gltf") !=
        std::string::npos);
}

namespace {

// Base64 as RFC 4648 writes it, for the data: URIs of the .gltf tests (written here, apart from
// the reader's decoder, so that a mistake in one is not repeated in the other).
std::string Base64(const std::vector<std::uint8_t>& bytes) {
  static const char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (size_t i = 0; i < bytes.size(); i += 3) {
    const std::uint32_t n = (static_cast<std::uint32_t>(bytes[i]) << 16) |
                            (i + 1 < bytes.size() ? static_cast<std::uint32_t>(bytes[i + 1]) << 8 : 0u) |
                            (i + 2 < bytes.size() ? static_cast<std::uint32_t>(bytes[i + 2]) : 0u);
    out += kAlphabet[(n >> 18) & 63];
    out += kAlphabet[(n >> 12) & 63];
    out += i + 1 < bytes.size() ? kAlphabet[(n >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? kAlphabet[n & 63] : '=';
  }
  return out;
}

// A unit square at z = 0 (two triangles, 16-bit indices) under a node translated by
// `translation`, as a JSON glTF whose one buffer has the given uri; *bin gets its bytes.
nlohmann::json SquareGltf(const std::string& uri, const Eigen::Vector3d& translation, std::vector<std::uint8_t>* bin) {
  const float positions[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  const std::uint16_t indices[6] = {0, 1, 2, 0, 2, 3};
  bin->resize(sizeof(positions) + sizeof(indices));
  std::memcpy(bin->data(), positions, sizeof(positions));
  std::memcpy(bin->data() + sizeof(positions), indices, sizeof(indices));
  return {{"asset", {{"version", "2.0"}, {"generator", "test_export"}}},
          {"scene", 0},
          {"scenes", {{{"nodes", {0}}}}},
          {"nodes", {{{"mesh", 0}, {"translation", {translation.x(), translation.y(), translation.z()}}}}},
          {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}, {"indices", 1}}}}}}},
          {"buffers", {{{"uri", uri}, {"byteLength", bin->size()}}}},
          {"bufferViews",
           {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", sizeof(positions)}, {"target", 34962}},
            {{"buffer", 0}, {"byteOffset", sizeof(positions)}, {"byteLength", sizeof(indices)}, {"target", 34963}}}},
          {"accessors",
           {{{"bufferView", 0},
             {"componentType", 5126},
             {"count", 4},
             {"type", "VEC3"},
             {"min", {0, 0, 0}},
             {"max", {1, 1, 0}}},
            {{"bufferView", 1}, {"componentType", 5123}, {"count", 6}, {"type", "SCALAR"}}}}};
}

}  // namespace

TEST_CASE("reference meshes: a .gltf with its buffer in a .bin file or a data: URI; broken ones refused by name") {
  const facet::testing::TempDir temp_dir("reference_gltf");
  const fs::path& dir = temp_dir.path;
  const Eigen::Vector3d translation(2.0, -1.0, 0.5);
  std::vector<std::uint8_t> bin;
  // The .bin's name has a space, which a URI writes %20.
  const nlohmann::json with_file = SquareGltf("square%20data.bin", translation, &bin);
  {
    std::ofstream out(dir / "square data.bin", std::ios::binary);
    out.write(reinterpret_cast<const char*>(bin.data()), static_cast<std::streamsize>(bin.size()));
  }
  std::ofstream(dir / "square.gltf") << with_file.dump(1);
  std::ofstream(dir / "inline.gltf")
      << SquareGltf("data:application/octet-stream;base64," + Base64(bin), translation, &bin).dump(1);
  for (const std::string name : {"square.gltf", "inline.gltf"}) {
    CAPTURE(name);
    const std::string path = (dir / name).string();
    // The test's files are glTF as the specification has it (tests/gltf/validate.js reads no
    // external resource, so the data: URI one is validated; the other differs only in its uri).
    if (name == "inline.gltf") CHECK_GLTF_VALID(path);
    facet::ReferenceMesh mesh;
    const std::string error = facet::ReadReferenceMesh(path, /*y_up=*/false, &mesh);
    REQUIRE_MESSAGE(error.empty(), error);
    REQUIRE(mesh.positions.size() == 4);
    CHECK(mesh.triangles.size() == 2);
    CHECK(mesh.triangles[1] == std::array<int, 3>{0, 2, 3});
    CHECK(mesh.edges.size() == 5);  // the square's 4 sides and its diagonal
    // The node's translation is applied; the float positions are exact in this range.
    constexpr double kPositionTolerance = 1e-6;
    CHECK((mesh.positions[2] - (translation + Eigen::Vector3d(1, 1, 0))).norm() < kPositionTolerance);
    CHECK((mesh.lo - translation).norm() < kPositionTolerance);
    // Y-up axes turn the square upright: file y is world z.
    REQUIRE(facet::ReadReferenceMesh(path, /*y_up=*/true, &mesh).empty());
    CHECK(std::abs(mesh.hi.z() - (translation.y() + 1.0)) < kPositionTolerance);
  }

  // What is wrong is said after the file's name, and nothing is read.
  struct Broken {
    std::string name, text, says;
  };
  nlohmann::json short_buffer = with_file;
  short_buffer["buffers"][0]["byteLength"] = bin.size() + 40;
  nlohmann::json missing_bin = with_file;
  missing_bin["buffers"][0]["uri"] = "gone.bin";
  nlohmann::json remote = with_file;
  remote["buffers"][0]["uri"] = "https://example.com/square.bin";
  nlohmann::json no_uri = with_file;
  no_uri["buffers"][0].erase("uri");
  std::string bad_base64 = "data:application/octet-stream;base64," + Base64(bin);
  bad_base64[bad_base64.size() / 2] = '*';
  nlohmann::json not_base64 = with_file;
  not_base64["buffers"][0]["uri"] = bad_base64;
  const std::vector<Broken> broken = {
      {"short.gltf", short_buffer.dump(),
       "buffer 0 holds " + std::to_string(bin.size()) + " bytes, its byteLength says " +
           std::to_string(bin.size() + 40)},
      {"missing.gltf", missing_bin.dump(), "buffer 0: " + (dir / "gone.bin").string()},
      {"remote.gltf", remote.dump(), "buffer 0: its URI 'https:'... is not a file beside the glTF"},
      {"no_uri.gltf", no_uri.dump(), "buffer 0 has no uri"},
      {"not_base64.gltf", not_base64.dump(), "buffer 0: its data: URI holds a character that is not base64"},
      {"truncated.gltf", with_file.dump().substr(0, 80), "malformed glTF JSON"},
      {"array.gltf", "[1, 2]", "not a glTF file"},
  };
  for (const Broken& b : broken) {
    CAPTURE(b.name);
    const std::string path = (dir / b.name).string();
    std::ofstream(path) << b.text;
    facet::ReferenceMesh mesh;
    const std::string error = facet::ReadReferenceMesh(path, true, &mesh);
    CAPTURE(error);
    CHECK(error.find(path + ": ") == 0);
    CHECK(error.find(b.says) != std::string::npos);
    CHECK(mesh.positions.empty());
    CHECK(mesh.triangles.empty());
  }
}
