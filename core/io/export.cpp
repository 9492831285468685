// Hand-written GLB and OBJ writers: both formats are small enough that a library would add
// more than it saves, and writing the chunks ourselves keeps the axis conversion in one place.
#include "core/io/export.h"

#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "core/geometry/camera_checks.h"
#include "core/io/gltf_constants.h"

#include "core/image/image_io.h"
#include "core/io/project_io.h"

namespace facet {
namespace {

using namespace gltf;

using Json = nlohmann::ordered_json;

// glTF and OBJ viewers expect Y up: world (x, y, z) -> (x, z, -y), a proper rotation.
Eigen::Matrix3d YUpFromWorld() {
  Eigen::Matrix3d m;
  m << 1, 0, 0, 0, 0, 1, 0, -1, 0;
  return m;
}

Eigen::Vector3f ToYUp(const Eigen::Vector3f& p) { return {p.x(), p.z(), -p.y()}; }

constexpr std::uint32_t kGlbVersion = 2;
constexpr int kArrayBuffer = 34962;
constexpr int kElementArrayBuffer = 34963;
constexpr int kLinear = 9729;
constexpr int kLinearMipmapLinear = 9987;
constexpr int kClampToEdge = 33071;

std::string ValidateMesh(const TexturedMesh& mesh) {
  const size_t n = mesh.positions.size();
  if (n == 0 || mesh.indices.empty()) return "the mesh is empty (no primitive to export)";
  if (mesh.indices.size() % 3 != 0) return "the index count is not a multiple of 3";
  if (mesh.normals.size() != n || mesh.uvs.size() != n) return "normals or UVs do not match the vertex count";
  const size_t triangles = mesh.indices.size() / 3;
  if (!mesh.triangle_textured.empty() && mesh.triangle_textured.size() != triangles) {
    return "triangle_textured does not match the triangle count";
  }
  for (std::uint32_t index : mesh.indices) {
    if (index >= n) return "index " + std::to_string(index) + " is out of range";
  }
  for (size_t v = 0; v < n; ++v) {
    if (!mesh.positions[v].allFinite() || !mesh.normals[v].allFinite() || !mesh.uvs[v].allFinite()) {
      return "vertex " + std::to_string(v) + " is not finite";
    }
  }
  for (int page = 0; page < mesh.AtlasPageCount(); ++page) {
    const ImageRgba8& image = mesh.AtlasPage(page);
    if (image.empty() || image.pixels.size() != static_cast<size_t>(image.width) * image.height * 4) {
      return "the pixel buffer of atlas page " + std::to_string(page) + " does not match its size";
    }
  }
  if (!mesh.triangle_page.empty() && mesh.triangle_page.size() != triangles) {
    return "triangle_page does not match the triangle count";
  }
  for (size_t t = 0; t < mesh.triangle_page.size(); ++t) {
    if (mesh.triangle_textured.size() == triangles && mesh.triangle_textured[t] &&
        mesh.triangle_page[t] >= std::max(1, mesh.AtlasPageCount())) {
      return "triangle " + std::to_string(t) + " refers to a missing atlas page";
    }
  }
  return "";
}

bool HasAtlas(const TexturedMesh& mesh) { return !mesh.atlas.empty(); }

bool TriangleTextured(const TexturedMesh& mesh, size_t triangle) {
  return HasAtlas(mesh) && !mesh.triangle_textured.empty() && mesh.triangle_textured[triangle] != 0;
}

// Splits the triangle list into textured ones per atlas page and plain ones.
void SplitIndices(const TexturedMesh& mesh, std::vector<std::vector<std::uint32_t>>* textured_by_page,
                  std::vector<std::uint32_t>* plain) {
  textured_by_page->assign(std::max(1, mesh.AtlasPageCount()), {});
  for (size_t t = 0; t < mesh.indices.size() / 3; ++t) {
    std::vector<std::uint32_t>* target = TriangleTextured(mesh, t) ? &(*textured_by_page)[mesh.TrianglePage(t)] : plain;
    target->insert(target->end(), mesh.indices.begin() + 3 * t, mesh.indices.begin() + 3 * t + 3);
  }
}

bool AnyTextured(const std::vector<std::vector<std::uint32_t>>& textured_by_page) {
  for (const auto& indices : textured_by_page) {
    if (!indices.empty()) return true;
  }
  return false;
}

// Page 0 keeps the single-atlas names; page k > 0 adds "_pageK".
std::string PageSuffix(size_t page) { return page == 0 ? "" : "_page" + std::to_string(page); }

class BinaryBuffer {
 public:
  // Appends bytes at a 4-byte aligned offset and returns the bufferView index.
  int AddView(const void* data, size_t size, int target, Json* views) {
    while (bytes_.size() % 4 != 0) bytes_.push_back(0);
    Json view = {{"buffer", 0}, {"byteOffset", bytes_.size()}, {"byteLength", size}};
    if (target != 0) view["target"] = target;
    const auto* p = static_cast<const std::uint8_t*>(data);
    bytes_.insert(bytes_.end(), p, p + size);
    views->push_back(view);
    return static_cast<int>(views->size()) - 1;
  }
  const std::vector<std::uint8_t>& bytes() const { return bytes_; }

 private:
  std::vector<std::uint8_t> bytes_;
};

void AppendU32(std::string* out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out->push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
}

Json CameraNode(const Image& image, int camera_index) {
  const Camera& cam = image.camera;
  // glTF cameras look down their local -Z with +Y up; OpenCV's look down +Z with Y down.
  const Eigen::Matrix3d world_from_gltf_cam =
      cam.cam_from_world_rotation.transpose() * Eigen::Vector3d(1, -1, -1).asDiagonal();
  Eigen::Quaterniond q(YUpFromWorld() * world_from_gltf_cam);
  q.normalize();
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  const Eigen::Vector3d t = YUpFromWorld() * cam.CenterInWorld();
  return {{"name", image.path},
          {"camera", camera_index},
          {"rotation", {q.x(), q.y(), q.z(), q.w()}},
          {"translation", {t.x(), t.y(), t.z()}}};
}

ExportSummary Failure(const std::string& message) {
  ExportSummary summary;
  summary.success = false;
  summary.message = message;
  return summary;
}

// Shortest text that reads back to the same float.
std::string FloatText(float v) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.9g", static_cast<double>(v));
  return buffer;
}

// The mesh's vertices in glTF's Y-up frame, with their bounding box.
struct YUpVertices {
  std::vector<Eigen::Vector3f> positions, normals;
  Eigen::Vector3f lo, hi;  // the positions' bounds
};

YUpVertices ToYUpVertices(const TexturedMesh& mesh) {
  YUpVertices out;
  std::vector<Eigen::Vector3f>& positions = out.positions;
  std::vector<Eigen::Vector3f>& normals = out.normals;
  positions.resize(mesh.positions.size());
  normals.resize(mesh.normals.size());
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max());
  Eigen::Vector3f hi = -lo;
  for (size_t v = 0; v < positions.size(); ++v) {
    positions[v] = ToYUp(mesh.positions[v]);
    normals[v] = ToYUp(mesh.normals[v]);
    lo = lo.cwiseMin(positions[v]);
    hi = hi.cwiseMax(positions[v]);
  }
  out.lo = lo;
  out.hi = hi;
  return out;
}

// One glTF perspective camera and its node for each calibrated image with a size.
void AddCameras(const Project& project, double znear, Json* cameras, Json* nodes) {
  for (const Image& image : project.images) {
    int w = 0, h = 0;
    if (!ExportedCameraSize(image, &w, &h)) continue;
    const Camera& cam = image.camera;
    cameras->push_back({{"name", image.path},
                        {"type", "perspective"},
                        {"perspective",
                         {{"yfov", 2.0 * std::atan(h / (2.0 * cam.focal_px))},
                          {"aspectRatio", static_cast<double>(w) / h},
                          {"znear", znear}}},
                        // glTF has no principal point; keep the full intrinsics for tools that want them.
                        {"extras",
                         {{"focal_px", cam.focal_px},
                          {"principal_point_px", {cam.principal_point_px.x(), cam.principal_point_px.y()}},
                          {"image_size_px", {w, h}}}}});
    nodes->push_back(CameraNode(image, static_cast<int>(cameras->size()) - 1));
  }
}

// The GLB container: header, then the JSON and the binary chunk (both padded to 4 bytes).
std::string PackGlb(const std::string& json_text, const std::vector<std::uint8_t>& bin_bytes, size_t total) {
  std::string glb;
  glb.reserve(total);
  AppendU32(&glb, kGlbMagic);
  AppendU32(&glb, kGlbVersion);
  AppendU32(&glb, static_cast<std::uint32_t>(total));
  AppendU32(&glb, static_cast<std::uint32_t>(json_text.size()));
  AppendU32(&glb, kChunkJson);
  glb += json_text;
  AppendU32(&glb, static_cast<std::uint32_t>(bin_bytes.size()));
  AppendU32(&glb, kChunkBin);
  glb.append(reinterpret_cast<const char*>(bin_bytes.data()), bin_bytes.size());
  return glb;
}

}  // namespace

bool ExportedCameraSize(const Image& image, int* width_px, int* height_px) {
  const Camera& cam = image.camera;
  *width_px = cam.width_px > 0 ? cam.width_px : image.width_px;
  *height_px = cam.height_px > 0 ? cam.height_px : image.height_px;
  return image.camera_calibrated && *width_px > 0 && *height_px > 0 && cam.focal_px > 0.0;
}

ExportSummary ExportGlb(const TexturedMesh& mesh, const Project& project, const std::string& path) {
  const std::string invalid = ValidateMesh(mesh);
  if (!invalid.empty()) return Failure(path + ": " + invalid);
  // A focal length outside any lens wrote yfov = pi (1e-300 px) or 0 (1e308 px): no camera.
  for (const Image& image : project.images) {
    int w = 0, h = 0;
    if (!ExportedCameraSize(image, &w, &h)) continue;
    const std::string why = WhyNotACamera(image.camera.focal_px, image.camera.principal_point_px, w, h);
    if (!why.empty()) return Failure(path + ": not written: the camera of " + image.path + " is not a camera: " + why);
  }

  const YUpVertices vertices = ToYUpVertices(mesh);
  const std::vector<Eigen::Vector3f>& positions = vertices.positions;
  const std::vector<Eigen::Vector3f>& normals = vertices.normals;
  const Eigen::Vector3f& lo = vertices.lo;
  const Eigen::Vector3f& hi = vertices.hi;
  std::vector<std::vector<std::uint32_t>> textured_by_page;
  std::vector<std::uint32_t> plain_indices;
  SplitIndices(mesh, &textured_by_page, &plain_indices);
  const bool any_textured = AnyTextured(textured_by_page);

  Json views = Json::array(), accessors = Json::array();
  BinaryBuffer bin;
  const size_t n = positions.size();
  auto add_vertex_accessor = [&](const void* data, size_t bytes, const char* type) {
    accessors.push_back({{"bufferView", bin.AddView(data, bytes, kArrayBuffer, &views)},
                         {"componentType", kFloat},
                         {"count", n},
                         {"type", type}});
    return static_cast<int>(accessors.size()) - 1;
  };
  const int position_accessor = add_vertex_accessor(positions.data(), n * sizeof(Eigen::Vector3f), "VEC3");
  accessors[position_accessor]["min"] = {lo.x(), lo.y(), lo.z()};
  accessors[position_accessor]["max"] = {hi.x(), hi.y(), hi.z()};
  const int normal_accessor = add_vertex_accessor(normals.data(), n * sizeof(Eigen::Vector3f), "VEC3");
  // UVs only when some primitive samples the atlas; validators flag unused accessors.
  const int uv_accessor =
      !any_textured ? -1 : add_vertex_accessor(mesh.uvs.data(), n * sizeof(Eigen::Vector2f), "VEC2");
  static_assert(sizeof(Eigen::Vector3f) == 12 && sizeof(Eigen::Vector2f) == 8, "tightly packed vectors");

  Json materials = Json::array(), primitives = Json::array();
  Json root;
  root["asset"] = {{"version", "2.0"}, {"generator", "Facet"}};
  // One image, texture and material per atlas page that some triangle uses.
  if (any_textured) {
    root["images"] = Json::array();
    root["textures"] = Json::array();
    root["samplers"] = Json::array({{{"magFilter", kLinear},
                                     {"minFilter", kLinearMipmapLinear},
                                     {"wrapS", kClampToEdge},
                                     {"wrapT", kClampToEdge}}});
  }
  for (size_t page = 0; page < textured_by_page.size(); ++page) {
    const std::vector<std::uint32_t>& textured_indices = textured_by_page[page];
    if (textured_indices.empty()) continue;
    const std::vector<std::uint8_t> png = EncodePng(mesh.AtlasPage(static_cast<int>(page)));
    if (png.empty()) return Failure(path + ": encoding atlas page " + std::to_string(page) + " as PNG failed");
    const int image_view = bin.AddView(png.data(), png.size(), 0, &views);
    root["images"].push_back(
        {{"name", "atlas" + PageSuffix(page)}, {"bufferView", image_view}, {"mimeType", "image/png"}});
    root["textures"].push_back({{"sampler", 0}, {"source", root["images"].size() - 1}});
    materials.push_back({{"name", "facet_textured" + PageSuffix(page)},
                         {"pbrMetallicRoughness",
                          {{"baseColorTexture", {{"index", root["textures"].size() - 1}}},
                           {"metallicFactor", 0.0},
                           {"roughnessFactor", 1.0}}}});
    accessors.push_back(
        {{"bufferView", bin.AddView(textured_indices.data(), textured_indices.size() * 4, kElementArrayBuffer, &views)},
         {"componentType", kUnsignedInt},
         {"count", textured_indices.size()},
         {"type", "SCALAR"}});
    primitives.push_back(
        {{"attributes", {{"POSITION", position_accessor}, {"NORMAL", normal_accessor}, {"TEXCOORD_0", uv_accessor}}},
         {"indices", accessors.size() - 1},
         {"material", materials.size() - 1},
         {"mode", kTriangles}});
  }
  if (!plain_indices.empty()) {
    materials.push_back(
        {{"name", "facet_untextured"},
         {"pbrMetallicRoughness",
          {{"baseColorFactor", {0.7, 0.7, 0.7, 1.0}}, {"metallicFactor", 0.0}, {"roughnessFactor", 1.0}}}});
    accessors.push_back(
        {{"bufferView", bin.AddView(plain_indices.data(), plain_indices.size() * 4, kElementArrayBuffer, &views)},
         {"componentType", kUnsignedInt},
         {"count", plain_indices.size()},
         {"type", "SCALAR"}});
    primitives.push_back({{"attributes", {{"POSITION", position_accessor}, {"NORMAL", normal_accessor}}},
                          {"indices", accessors.size() - 1},
                          {"material", materials.size() - 1},
                          {"mode", kTriangles}});
  }

  Json nodes = Json::array({{{"name", "facet_model"}, {"mesh", 0}}});
  Json cameras = Json::array();
  // A near plane well inside the model's scale, so the views show the whole model.
  const double znear = std::max(1e-6, 1e-3 * static_cast<double>((hi - lo).norm()));
  AddCameras(project, znear, &cameras, &nodes);
  Json scene_nodes = Json::array();
  for (size_t i = 0; i < nodes.size(); ++i) scene_nodes.push_back(i);

  root["scene"] = 0;
  root["scenes"] = Json::array({{{"name", "facet"}, {"nodes", scene_nodes}}});
  root["nodes"] = nodes;
  root["meshes"] = Json::array({{{"name", "facet_model"}, {"primitives", primitives}}});
  root["materials"] = materials;
  if (!cameras.empty()) root["cameras"] = cameras;
  root["accessors"] = accessors;
  root["bufferViews"] = views;
  std::vector<std::uint8_t> bin_bytes = bin.bytes();
  while (bin_bytes.size() % 4 != 0) bin_bytes.push_back(0);
  root["buffers"] = Json::array({{{"byteLength", bin_bytes.size()}}});

  // glTF is UTF-8: a name from a path that is not (a photo's bytes) is written with U+FFFD.
  std::string json_text = root.dump(-1, ' ', false, Json::error_handler_t::replace);
  while (json_text.size() % 4 != 0) json_text.push_back(' ');
  const size_t total = 12 + 8 + json_text.size() + 8 + bin_bytes.size();
  if (total > std::numeric_limits<std::uint32_t>::max())
    return Failure(path + ": the model exceeds the 4 GiB GLB limit");
  const std::string glb = PackGlb(json_text, bin_bytes, total);

  const std::string error = WriteFileAtomically(path, glb);
  if (!error.empty()) return Failure(error);  // names the file
  ExportSummary summary;
  summary.success = true;
  summary.files_written = {path};
  summary.message =
      "wrote " + path + ": " + std::to_string(mesh.indices.size() / 3) + " triangles, " +
      std::to_string(cameras.size()) + " cameras" +
      (HasAtlas(mesh)
           ? ", " + std::to_string(mesh.atlas.width) + "x" + std::to_string(mesh.atlas.height) + " texture" +
                 (mesh.AtlasPageCount() > 1 ? " (+" + std::to_string(mesh.AtlasPageCount() - 1) + " pages)" : "")
           : "");
  return summary;
}

ExportSummary ExportObj(const TexturedMesh& mesh, const std::string& path) {
  namespace fs = std::filesystem;
  const std::string invalid = ValidateMesh(mesh);
  if (!invalid.empty()) return Failure(path + ": " + invalid);

  fs::path base(path);
  std::string extension = base.extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (extension == ".obj") base.replace_extension();
  const std::string obj_path = base.string() + ".obj";
  const std::string mtl_path = base.string() + ".mtl";
  const std::string stem = base.filename().string();

  std::vector<std::vector<std::uint32_t>> textured_by_page;
  std::vector<std::uint32_t> plain_indices;
  SplitIndices(mesh, &textured_by_page, &plain_indices);

  // Page 0 is FILE.png, page k FILE_pageK.png, each with its material.
  std::string mtl = "# Facet materials\n";
  for (size_t page = 0; page < textured_by_page.size(); ++page) {
    if (textured_by_page[page].empty()) continue;
    mtl += "newmtl facet_textured" + PageSuffix(page) + "\nKa 1 1 1\nKd 1 1 1\nKs 0 0 0\nd 1\nillum 1\nmap_Kd " + stem +
           PageSuffix(page) + ".png\n\n";
  }
  if (!plain_indices.empty())
    mtl += "newmtl facet_untextured\nKa 0.7 0.7 0.7\nKd 0.7 0.7 0.7\nKs 0 0 0\nd 1\nillum 1\n";

  std::string obj = "# Facet model, Y up (world z up written as y)\nmtllib " + stem + ".mtl\no facet_model\n";
  obj.reserve(mesh.positions.size() * 120 + mesh.indices.size() * 12);
  for (const Eigen::Vector3f& p : mesh.positions) {
    const Eigen::Vector3f q = ToYUp(p);
    obj += "v " + FloatText(q.x()) + " " + FloatText(q.y()) + " " + FloatText(q.z()) + "\n";
  }
  for (const Eigen::Vector2f& uv : mesh.uvs) obj += "vt " + FloatText(uv.x()) + " " + FloatText(1.0f - uv.y()) + "\n";
  for (const Eigen::Vector3f& nrm : mesh.normals) {
    const Eigen::Vector3f q = ToYUp(nrm);
    obj += "vn " + FloatText(q.x()) + " " + FloatText(q.y()) + " " + FloatText(q.z()) + "\n";
  }
  auto write_faces = [&](const std::vector<std::uint32_t>& indices, bool with_uv) {
    for (size_t i = 0; i < indices.size(); i += 3) {
      obj += "f";
      for (int k = 0; k < 3; ++k) {
        const std::string v = std::to_string(indices[i + k] + 1);
        obj += " " + v + (with_uv ? "/" + v + "/" : "//") + v;
      }
      obj += "\n";
    }
  };
  for (size_t page = 0; page < textured_by_page.size(); ++page) {
    if (textured_by_page[page].empty()) continue;
    obj += "usemtl facet_textured" + PageSuffix(page) + "\n";
    write_faces(textured_by_page[page], true);
  }
  if (!plain_indices.empty()) {
    obj += "usemtl facet_untextured\n";
    write_faces(plain_indices, false);
  }

  ExportSummary summary;
  // The OBJ goes last, so an OBJ on disk always finds its material and texture.
  for (size_t page = 0; page < textured_by_page.size(); ++page) {
    if (textured_by_page[page].empty()) continue;
    const std::string png_path = base.string() + PageSuffix(page) + ".png";
    const std::vector<std::uint8_t> png = EncodePng(mesh.AtlasPage(static_cast<int>(page)));
    if (png.empty()) return Failure(png_path + ": encoding the texture atlas as PNG failed");
    const std::string error = WriteFileAtomically(png_path, std::string(png.begin(), png.end()));
    if (!error.empty()) {
      ExportSummary failed = Failure(error);
      failed.files_written = summary.files_written;
      return failed;
    }
    summary.files_written.push_back(png_path);
  }
  for (const auto& [file, text] : {std::pair{mtl_path, &mtl}, std::pair{obj_path, &obj}}) {
    const std::string error = WriteFileAtomically(file, *text);
    if (!error.empty()) {
      ExportSummary failed = Failure(error);
      failed.files_written = summary.files_written;
      return failed;
    }
    summary.files_written.push_back(file);
  }
  summary.success = true;
  summary.message = "wrote " + obj_path + " (" + std::to_string(mesh.indices.size() / 3) + " triangles) with " +
                    std::to_string(summary.files_written.size() - 1) + " companion files";
  return summary;
}

}  // namespace facet
