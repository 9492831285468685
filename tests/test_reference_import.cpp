// Reference-mesh import against hostile files (issue 25): counts and strides that wrap, deep
// and cyclic node hierarchies, JSON fields of the wrong shape, files that would allocate
// without bound, URIs that lead out of the glTF's folder, NaN and infinite coordinates, OBJ
// indices at the ends of their range. Every one is refused with a message that names what is
// wrong, after the file's name, and leaves the mesh empty; none throws or crashes. The hostile
// files are made here (the big ones are small JSON that describes a lot).
#include <chrono>
#include <cmath>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include <doctest/doctest.h>
#include <nlohmann/json.hpp>

#include "core/io/gltf_read.h"
#include "core/io/reference_mesh.h"
#include "tests/temp_files.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr const char* kName = "hostile.gltf";

// RFC 4648 base64, written apart from the reader's decoder.
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

std::string DataUri(const std::vector<std::uint8_t>& bytes) {
  return "data:application/octet-stream;base64," + Base64(bytes);
}

template <typename T>
void Append(std::vector<std::uint8_t>* bin, const std::vector<T>& values) {
  const size_t at = bin->size();
  bin->resize(at + values.size() * sizeof(T));
  std::memcpy(bin->data() + at, values.data(), values.size() * sizeof(T));
}

// The square every hostile file is a mutant of: two triangles with normals and texture
// coordinates (buffer bytes 0-47 positions, 48-95 normals, 96-127 uvs, 128-139 16-bit
// indices), a coloured material, and a camera node under the mesh node, its extras as
// ExportGlb writes them. *bin gets the buffer, which the data: URI holds.
json Square(std::vector<std::uint8_t>* bin) {
  bin->clear();
  Append<float>(bin, {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0});
  Append<float>(bin, {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1});
  Append<float>(bin, {0, 0, 1, 0, 1, 1, 0, 1});
  Append<std::uint16_t>(bin, {0, 1, 2, 0, 2, 3});
  return {
      {"asset", {{"version", "2.0"}}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0}}}}},
      {"nodes", {{{"mesh", 0}, {"children", {1}}}, {{"camera", 0}, {"translation", {0.5, 0.5, 3}}}}},
      {"meshes",
       {{{"primitives",
          {{{"attributes", {{"POSITION", 0}, {"NORMAL", 1}, {"TEXCOORD_0", 2}}}, {"indices", 3}, {"material", 0}}}}}}},
      {"materials", {{{"pbrMetallicRoughness", {{"baseColorFactor", {1.0, 0.5, 0.25, 1.0}}}}}}},
      {"cameras",
       {{{"type", "perspective"},
         {"perspective", {{"yfov", 0.8}, {"aspectRatio", 4.0 / 3.0}, {"znear", 0.1}}},
         {"extras", {{"image_size_px", {640, 480}}, {"principal_point_px", {321.5, 238.25}}}}}}},
      {"buffers", {{{"uri", DataUri(*bin)}, {"byteLength", bin->size()}}}},
      {"bufferViews",
       {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 48}},
        {{"buffer", 0}, {"byteOffset", 48}, {"byteLength", 48}},
        {{"buffer", 0}, {"byteOffset", 96}, {"byteLength", 32}},
        {{"buffer", 0}, {"byteOffset", 128}, {"byteLength", 12}}}},
      {"accessors",
       {{{"bufferView", 0}, {"componentType", 5126}, {"count", 4}, {"type", "VEC3"}},
        {{"bufferView", 1}, {"componentType", 5126}, {"count", 4}, {"type", "VEC3"}},
        {{"bufferView", 2}, {"componentType", 5126}, {"count", 4}, {"type", "VEC2"}},
        {{"bufferView", 3}, {"componentType", 5123}, {"count", 6}, {"type", "SCALAR"}}}}};
}

std::vector<std::uint8_t> Bytes(const std::string& text) { return std::vector<std::uint8_t>(text.begin(), text.end()); }

std::string ReadGltfText(const std::string& text, facet::ReferenceMesh* mesh, const std::string& folder = "") {
  return facet::ReadReferenceMeshBytes(Bytes(text), facet::ReferenceFormat::kGltf, kName, folder, /*y_up=*/false, mesh);
}

std::string ReadObjText(const std::string& text, facet::ReferenceMesh* mesh) {
  return facet::ReadReferenceMeshBytes(Bytes(text), facet::ReferenceFormat::kObj, "hostile.obj", "", false, mesh);
}

// Every byte printable ASCII or a line break: what a message quoting the file may hold.
bool IsPlainAscii(const std::string& text) {
  for (char c : text)
    if (static_cast<unsigned char>(c) >= 0x80) return false;
  return true;
}

// `text` is refused: the message starts with the file's name and contains `says`, the mesh
// is empty.
void CheckRefused(const std::string& text, const std::string& says, const std::string& folder = "") {
  facet::ReferenceMesh mesh;
  mesh.positions.push_back(Eigen::Vector3d::Ones());  // must be cleared
  const std::string error = ReadGltfText(text, &mesh, folder);
  CAPTURE(error);
  CHECK(error.rfind(std::string(kName) + ": ", 0) == 0);
  CHECK(error.find(says) != std::string::npos);
  CHECK(mesh.positions.empty());
  CHECK(mesh.triangles.empty());
}

struct Mutant {
  std::string pointer;  // JSON pointer into the square
  json value;
  std::string says;
};

void CheckMutants(const std::vector<Mutant>& mutants) {
  std::vector<std::uint8_t> bin;
  const json square = Square(&bin);
  for (const Mutant& m : mutants) {
    CAPTURE(m.pointer);
    CAPTURE(m.value.dump());
    json hostile = square;
    hostile[json::json_pointer(m.pointer)] = m.value;
    CheckRefused(hostile.dump(), m.says);
  }
}

}  // namespace

TEST_CASE("reference import: the square every hostile file is made from reads, camera and colour included") {
  std::vector<std::uint8_t> bin;
  const std::string text = Square(&bin).dump();
  facet::ReferenceMesh mesh;
  const std::string error = ReadGltfText(text, &mesh);
  REQUIRE_MESSAGE(error.empty(), error);
  CHECK(mesh.positions.size() == 4);
  CHECK(mesh.triangles.size() == 2);
  facet::GltfScene scene;
  REQUIRE(facet::ReadGltfBytes(Bytes(text), kName, "", {}, &scene).empty());
  REQUIRE(scene.cameras.size() == 1);
  CHECK(scene.cameras[0].camera.width_px == 640);
  CHECK(scene.cameras[0].camera.principal_point_px.x() == 321.5);
  REQUIRE(scene.batches.size() == 1);
  CHECK(scene.batches[0].base_color.y() == 0.5f);
}

TEST_CASE("reference import: accessor counts, strides and offsets that wrap or overrun are refused before allocating") {
  // The probe's counts: 6148914691236517206 * 3 components wraps a 64-bit size; 2^62 + 1 and
  // 2^63 made std::length_error. A count just inside 2^53 overruns the 48-byte view.
  CheckMutants({
      {"/accessors/0/count", 6148914691236517206ull, "accessor 0 (POSITION).count is 6148914691236517206"},
      {"/accessors/0/count", (1ull << 62) + 1, "not a whole number in [0, 9007199254740992]"},
      {"/accessors/0/count", 1ull << 63, "not a whole number"},
      {"/accessors/0/count", std::numeric_limits<std::uint64_t>::max(), "not a whole number"},
      {"/accessors/0/count", -1, "accessor 0 (POSITION).count is -1"},
      {"/accessors/0/count", 4.5, "accessor 0 (POSITION).count is 4.5"},
      {"/accessors/0/count", (1ull << 53) - 1, "count 9007199254740991 runs past its bufferView (48 bytes)"},
      {"/accessors/0/count", 5, "count 5 runs past its bufferView (48 bytes)"},
      {"/accessors/3/count", 1ull << 40, "accessor 3 (indices): count 1099511627776 runs past"},
      // byteStride 2^63 with count 3 (the probe's), and strides outside the specification's.
      {"/bufferViews/0/byteStride", 1ull << 63, "bufferView 0.byteStride is 9223372036854775808"},
      {"/bufferViews/0/byteStride", 256, "byteStride 256 is outside [4, 252]"},
      {"/bufferViews/0/byteStride", 8, "byteStride 8 is less than an element's 12 bytes"},
      {"/bufferViews/0/byteStride", 16, "count 4 runs past its bufferView"},
      {"/accessors/0/byteOffset", 1000, "byteOffset 1000 is past its bufferView"},
      {"/accessors/0/byteOffset", 4, "count 4 runs past its bufferView"},
      {"/bufferViews/0/byteOffset", 1ull << 52, "bufferView 0 runs past its buffer"},
      {"/bufferViews/0/byteLength", 141, "bufferView 0 runs past its buffer"},
      {"/buffers/0/byteLength", 1ull << 31, "add up to more than 1073741824 bytes"},
      {"/buffers/0/byteLength", 200, "buffer 0 holds 140 bytes, its byteLength says 200"},
      {"/accessors/3/componentType", 5126, "accessor 3 (indices) holds floats; indices must be integers"},
      {"/accessors/0/componentType", 5120, "component type 5120 is not supported"},
      {"/accessors/0/sparse", json::object(), "is sparse"},
  });
  // An index past the primitive's vertices.
  std::vector<std::uint8_t> bin;
  json square = Square(&bin);
  bin[128] = 4;
  square["buffers"][0]["uri"] = DataUri(bin);
  CheckRefused(square.dump(), "mesh 0.primitives[0]'s index 4 is out of range");
}

TEST_CASE("reference import: a chain of 100,000 nested nodes reads without recursion; cycles and two parents refused") {
  constexpr int kDepth = 100'000;
  std::vector<std::uint8_t> bin;
  json chain = Square(&bin);
  json nodes = json::array();
  // Each node moves its children 1 mm along x; the mesh hangs under the deepest.
  for (int i = 0; i < kDepth; ++i) {
    json node = {{"translation", {0.001, 0.0, 0.0}}};
    if (i + 1 < kDepth)
      node["children"] = {i + 1};
    else
      node["mesh"] = 0;
    nodes.push_back(node);
  }
  chain["nodes"] = nodes;
  facet::ReferenceMesh mesh;
  const auto start = std::chrono::steady_clock::now();
  const std::string error = ReadGltfText(chain.dump(), &mesh);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  REQUIRE_MESSAGE(error.empty(), error);
  MESSAGE("100,000 nested nodes read in " << seconds << " s");
  REQUIRE(mesh.positions.size() == 4);
  // 100,000 translations of 1 mm: 100 m, the doubles' sum within 1e-6 m, the float within 1e-5.
  constexpr double kSumTolerance = 1e-5;
  CHECK(std::abs(mesh.positions[0].x() - 0.001 * kDepth) < kSumTolerance);

  json cycle = Square(&bin);
  cycle["nodes"][1]["children"] = {0};
  CheckRefused(cycle.dump(), "node 0 is reached twice (the node hierarchy has a cycle or a node with two parents)");
  json two_parents = Square(&bin);
  two_parents["nodes"].push_back({{"children", {1}}});
  two_parents["scenes"][0]["nodes"] = {0, 2};
  CheckRefused(two_parents.dump(), "node 1 is reached twice");
  json repeated_child = Square(&bin);
  repeated_child["nodes"][0]["children"] = {1, 1};
  CheckRefused(repeated_child.dump(), "node 1 is reached twice");
  // Without scenes the roots are the nodes no node names as a child: a cycle has none.
  json cycle_only = Square(&bin);
  cycle_only.erase("scenes");
  cycle_only.erase("scene");
  cycle_only["nodes"][1]["children"] = {0};
  CheckRefused(cycle_only.dump(), "holds no triangles");

  // JSON nested 100,000 deep (in extras, which the reader otherwise ignores).
  std::string deep = Square(&bin).dump();
  deep.insert(deep.rfind('}'), ",\"extras\":" + std::string(kDepth, '[') + std::string(kDepth, ']'));
  CheckRefused(deep, "its JSON nests deeper than 64 levels");
}

TEST_CASE("reference import: JSON fields of the wrong shape are refused by name, never thrown") {
  CheckMutants({
      // The probe's three.
      {"/cameras/0/extras/image_size_px", json::array(), "camera 0.extras.image_size_px is not an array of 2 numbers"},
      {"/cameras/0/extras/principal_point_px", json::array(),
       "camera 0.extras.principal_point_px is not an array of 2 numbers"},
      {"/materials/0/pbrMetallicRoughness/baseColorFactor", json::array(),
       "material 0.pbrMetallicRoughness.baseColorFactor is not an array of 4 numbers"},
      // Their neighbours.
      {"/cameras/0/extras/image_size_px", {640}, "image_size_px is not an array of 2 numbers"},
      {"/cameras/0/extras/image_size_px",
       {1e9, 480},
       "image_size_px[0] is 1000000000.0, not a whole number in [0, 65536]"},
      {"/cameras/0/extras/image_size_px", {0, 480}, "camera 0 has no image size"},
      {"/cameras/0/extras/image_size_px", {"640", 480}, "image_size_px[0] is not a number"},
      {"/cameras/0/extras/principal_point_px", {"a", 1}, "principal_point_px[0] is not a number"},
      {"/cameras/0/extras/principal_point_px", 7, "principal_point_px is not an array of 2 numbers"},
      {"/materials/0/pbrMetallicRoughness/baseColorFactor", "red", "baseColorFactor is not an array of 4 numbers"},
      {"/materials/0/pbrMetallicRoughness/baseColorFactor", {1e300, 1, 1, 1}, "baseColorFactor is out of range"},
      {"/materials/0/pbrMetallicRoughness", 3, "material 0.pbrMetallicRoughness is not a JSON object"},
      {"/materials/0", "x", "material 0 is not a JSON object"},
      {"/materials/0/pbrMetallicRoughness/baseColorTexture", {{"index", 0}}, "texture 0 missing"},
      {"/cameras/0/perspective/yfov", "1", "camera 0.perspective.yfov is not a number"},
      {"/cameras/0/perspective/yfov", 4, "camera 0 has a yfov outside (0, pi)"},
      {"/cameras/0/perspective/aspectRatio", -1, "camera 0 has a negative aspectRatio"},
      {"/cameras/0/perspective", json::array(), "camera 0.perspective is not a JSON object"},
      {"/cameras/0/type", 5, "camera 0.type is not a string"},
      {"/nodes/0/translation", json::array(), "node 0.translation is not an array of 3 numbers"},
      {"/nodes/0/translation", {"a", 0, 0}, "node 0.translation[0] is not a number"},
      {"/nodes/0/matrix", std::vector<double>(15, 0.0), "node 0.matrix is not an array of 16 numbers"},
      {"/nodes/0/rotation", {0, 0, 0, 2}, "node 0.rotation is not a unit quaternion"},
      {"/nodes/0/scale", {1e300, 1e300, 1e300}, "POSITION 1 is not finite once its node transforms are applied"},
      {"/nodes/0/mesh", "0", "node 0.mesh is not a number"},
      {"/nodes/0/mesh", -1, "node 0.mesh is -1"},
      {"/nodes/0/mesh", 9, "mesh 9 missing"},
      {"/nodes/0/children", 3, "node 0.children is not an array"},
      {"/nodes/0/children", {99}, "node 99 missing"},
      {"/nodes/0", json::array(), "node 0 is not a JSON object"},
      {"/nodes", json::object(), "the glTF.nodes is not an array"},
      {"/meshes/0/primitives", json::object(), "mesh 0.primitives is not an array"},
      {"/meshes/0/primitives/0", 1, "mesh 0.primitives[0] is not a JSON object"},
      {"/meshes/0/primitives/0/attributes", json::array(), "attributes is not a JSON object"},
      {"/meshes/0/primitives/0/attributes/POSITION", "0", "attributes.POSITION is not a number"},
      {"/meshes/0/primitives/0/mode", 1, "is not made of triangles"},
      {"/meshes/0/primitives/0/material", 3, "mesh 0.primitives[0]'s material is missing"},
      {"/accessors/0/type", 3, "accessor 0 (POSITION).type is not a string"},
      {"/accessors/0/type", "MAT4", "accessor type 'MAT4' is not supported"},
      {"/accessors/0/componentType", "float", "componentType is not a number"},
      {"/accessors/0", json::array(), "accessor 0 is not a JSON object"},
      {"/bufferViews/0", json::array(), "bufferView 0 is not a JSON object"},
      {"/buffers/0/uri", 5, "buffer 0.uri is not a string"},
      {"/buffers/0/byteLength", "140", "buffer 0.byteLength is not a number"},
      {"/buffers/0", json::array(), "buffer 0 is not a JSON object"},
      {"/asset", "2.0", "not a glTF 2.0 asset"},
      {"/asset/version", 2, "asset.version is not a string"},
      {"/scene", 5, "scene 5 missing"},
      {"/scene", "0", "the glTF.scene is not a number"},
      {"/scenes/0", json::array(), "scene 0 is not a JSON object"},
      {"/scenes/0/nodes", {"0"}, "scene 0.nodes[0] is not a number"},
  });
  CheckRefused("[1, 2]", "not a glTF file");
  CheckRefused("{\"asset\": {\"version\": \"2.0\"", "malformed glTF JSON");
}

TEST_CASE("reference import: files that describe more than a reference may hold are refused with the limit, quickly") {
  std::vector<std::uint8_t> bin;
  // The probe's 20,000 nodes x 2,000 primitives (bad_alloc after 31 s before): each node is a
  // root using the one mesh.
  json wide = Square(&bin);
  wide.erase("scenes");
  wide.erase("scene");
  wide["meshes"][0]["primitives"] = json::array();
  for (int i = 0; i < 2000; ++i) wide["meshes"][0]["primitives"].push_back({{"attributes", {{"POSITION", 0}}}});
  wide["accessors"][0]["count"] = 3;
  wide["nodes"] = json::array();
  for (int i = 0; i < 20000; ++i) wide["nodes"].push_back({{"mesh", 0}});
  // Processor time, not wall time: the bound must hold on a loaded machine too.
  const std::clock_t start = std::clock();
  CheckRefused(wide.dump(), "more than 100000 primitives (a mesh counted once per node that uses it), the most read");
  const double seconds = static_cast<double>(std::clock() - start) / CLOCKS_PER_SEC;
  MESSAGE("20,000 nodes x 2,000 primitives refused in " << seconds << " s of processor time");
  // Refused after reading 100,000 triangles: well inside the 31 s the probe waited for bad_alloc.
  constexpr double kRefusedWithinSeconds = 10.0;
  CHECK(seconds < kRefusedWithinSeconds);

  // 2,000 instances of a 1,002-vertex mesh: the 1,997th goes over kMaxReferenceVertices.
  json many_vertices = Square(&bin);
  bin.assign(12024, 0);
  many_vertices["buffers"][0] = {{"uri", DataUri(bin)}, {"byteLength", bin.size()}};
  many_vertices["bufferViews"] = {{{"buffer", 0}, {"byteLength", 12024}}};
  many_vertices["accessors"] = {{{"bufferView", 0}, {"componentType", 5126}, {"count", 1002}, {"type", "VEC3"}}};
  many_vertices["meshes"][0]["primitives"] = {{{"attributes", {{"POSITION", 0}}}}};
  many_vertices.erase("scenes");
  many_vertices["nodes"] = json::array();
  for (int i = 0; i < 2000; ++i) many_vertices["nodes"].push_back({{"mesh", 0}});
  static_assert(facet::kMaxReferenceVertices == 2'000'000);
  CheckRefused(many_vertices.dump(), "more than 2000000 vertices");

  // 1,000 instances of 4,001 triangles (8-bit indices, all 0): one over kMaxReferenceTriangles.
  json many_triangles = many_vertices;
  bin.assign(36 + 12003, 0);
  many_triangles["buffers"][0] = {{"uri", DataUri(bin)}, {"byteLength", bin.size()}};
  many_triangles["bufferViews"] = {{{"buffer", 0}, {"byteLength", 36}},
                                   {{"buffer", 0}, {"byteOffset", 36}, {"byteLength", 12003}}};
  many_triangles["accessors"] = {{{"bufferView", 0}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}},
                                 {{"bufferView", 1}, {"componentType", 5121}, {"count", 12003}, {"type", "SCALAR"}}};
  many_triangles["meshes"][0]["primitives"][0]["indices"] = 1;
  many_triangles["nodes"] = json::array();
  for (int i = 0; i < 1000; ++i) many_triangles["nodes"].push_back({{"mesh", 0}});
  static_assert(facet::kMaxReferenceTriangles == 4'000'000);
  CheckRefused(many_triangles.dump(), "more than 4000000 triangles");

  // An OBJ face of 4,000,003 corners fans into one triangle too many.
  std::string obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf";
  for (int i = 0; i < 4'000'003; ++i) obj += " 1";
  facet::ReferenceMesh mesh;
  const std::string error = ReadObjText(obj + "\n", &mesh);
  CHECK(error.find("hostile.obj: more than 4000000 triangles") == 0);
  CHECK(mesh.positions.empty());
}

TEST_CASE("reference import: buffer URIs stay inside the glTF's folder, and nothing outside is opened or described") {
  const facet::testing::TempDir temp_dir("uri");
  const fs::path& dir = temp_dir.path;
  const fs::path folder = dir / "model";
  fs::create_directories(folder / "sub");
  std::vector<std::uint8_t> bin;
  const json square = Square(&bin);
  // outside.bin is a valid buffer with a length of its own (4242 bytes): were it followed, the
  // file would read, or an error would print its size.
  std::vector<std::uint8_t> outside = bin;
  outside.resize(4242, 0);
  auto write = [](const fs::path& path, const std::vector<std::uint8_t>& bytes) {
    std::ofstream out(path, std::ios::binary);
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  };
  write(dir / "outside.bin", outside);
  write(folder / "sub" / "part.bin", bin);
  fs::create_symlink(dir / "outside.bin", folder / "link.bin");
  fs::create_directory_symlink(dir, folder / "up");
  fs::create_symlink("sub/part.bin", folder / "inner_link.bin");

  auto read = [&](const std::string& uri, facet::ReferenceMesh* mesh) {
    json file = square;
    file["buffers"][0]["uri"] = uri;
    const fs::path path = folder / "model.gltf";
    std::ofstream(path) << file.dump();
    return facet::ReadReferenceMesh(path.string(), false, mesh);
  };
  // Inside the folder, written plainly or with escapes, through a link that stays inside.
  for (const std::string uri : {"sub/part.bin", "sub%2Fpart.bin", "./sub/part.bin", "inner_link.bin"}) {
    CAPTURE(uri);
    facet::ReferenceMesh mesh;
    const std::string error = read(uri, &mesh);
    CHECK_MESSAGE(error.empty(), error);
    CHECK(mesh.triangles.size() == 2);
  }
  const std::string passwd_size = fs::exists("/etc/passwd") ? std::to_string(fs::file_size("/etc/passwd")) : "";
  const std::vector<std::pair<std::string, std::string>> hostile = {
      {"/etc/passwd", "is an absolute path"},
      {"%2Fetc%2Fpasswd", "is an absolute path"},
      {(dir / "outside.bin").string(), "is an absolute path"},
      {"../outside.bin", "leaves the glTF's folder ('..')"},
      {"..%2Foutside.bin", "leaves the glTF's folder ('..')"},
      {"%2E%2E/outside.bin", "leaves the glTF's folder ('..')"},
      {"sub/../../outside.bin", "leaves the glTF's folder ('..')"},
      {"sub%2F..%2F..%2F..%2F..%2F..%2F..%2Fetc%2Fpasswd", "leaves the glTF's folder ('..')"},
      {"..\\outside.bin", "leaves the glTF's folder ('..')"},
      {"link.bin", "leaves the glTF's folder through a symbolic link"},
      {"up/outside.bin", "leaves the glTF's folder through a symbolic link"},
      {"sub/%00part.bin", "holds a NUL byte"},
      {"", "is empty"},
      {"file:///etc/passwd", "is not a file beside the glTF"},
  };
  for (const auto& entry : hostile) {
    // Named copies: clang 14 cannot capture structured bindings in doctest's CAPTURE lambda.
    const auto& uri = entry.first;
    const auto& says = entry.second;
    CAPTURE(uri);
    facet::ReferenceMesh mesh;
    const std::string error = read(uri, &mesh);
    CAPTURE(error);
    CHECK(error.find(says) != std::string::npos);
    CHECK(mesh.triangles.empty());
    CHECK(error.find("4242") == std::string::npos);
    if (!passwd_size.empty()) CHECK(error.find(" " + passwd_size + " ") == std::string::npos);
    CHECK(error.find("bytes") == std::string::npos);
  }
  // Read from memory without a folder, a side file is refused; a data: URI reads.
  json side = square;
  side["buffers"][0]["uri"] = "part.bin";
  CheckRefused(side.dump(), "names a side file, and this glTF is read without its folder");
  facet::ReferenceMesh mesh;
  CHECK(ReadGltfText(square.dump(), &mesh).empty());
}

TEST_CASE("reference import: NaN and infinite coordinates are refused by name, in glTF as in OBJ") {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  struct Poison {
    size_t float_index;  // into the buffer's floats
    float value;
    std::string says;
  };
  const std::vector<Poison> poisons = {
      {4, nan, "POSITION 1 is not finite (NaN or infinite)"},    {9, inf, "POSITION 3 is not finite (NaN or infinite)"},
      {0, -inf, "POSITION 0 is not finite (NaN or infinite)"},   {14, nan, "NORMAL 0 is not finite (NaN or infinite)"},
      {25, inf, "TEXCOORD_0 0 is not finite (NaN or infinite)"},
  };
  for (const Poison& p : poisons) {
    CAPTURE(p.says);
    std::vector<std::uint8_t> bin;
    json square = Square(&bin);
    std::memcpy(bin.data() + 4 * p.float_index, &p.value, 4);
    square["buffers"][0]["uri"] = DataUri(bin);
    CheckRefused(square.dump(), p.says);
  }
  // Finite in the file, not once the node's transform moves it past a float's range.
  std::vector<std::uint8_t> bin;
  json far = Square(&bin);
  far["nodes"][0]["translation"] = {3e38, 0, 0};
  far["nodes"][0]["scale"] = {3e38, 1, 1};
  CheckRefused(far.dump(), "POSITION 1 is not finite once its node transforms are applied");

  for (const std::string line : {"v nan 0 0", "v 0 inf 0", "v 0 0 -inf", "v 1e999 0 0", "v NaN 0 0"}) {
    CAPTURE(line);
    facet::ReferenceMesh mesh;
    const std::string error = ReadObjText(line + "\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", &mesh);
    CHECK(error.find("hostile.obj, line 1: a vertex needs three finite numbers") == 0);
    CHECK(mesh.positions.empty());
  }
}

TEST_CASE("reference import: OBJ indices at the ends of their range and bytes that are not text") {
  const std::string vertices = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  for (const std::string corner :
       {"-9223372036854775808", "9223372036854775807", "99999999999999999999", "0", "-4", "4", "1x", "/1"}) {
    CAPTURE(corner);
    facet::ReferenceMesh mesh;
    const std::string error = ReadObjText(vertices + "f " + corner + " 1 2\n", &mesh);
    CHECK(error.find("hostile.obj, line 4: face corner '" + corner + "' names no vertex defined before it") == 0);
    CHECK(mesh.triangles.empty());
  }
  facet::ReferenceMesh mesh;
  CHECK(ReadObjText(vertices + "f -3 -2 -1\n", &mesh).empty());
  CHECK(mesh.triangles.size() == 1);
  // A corner of bytes that are not UTF-8 is quoted as '?'s: the app's log and reports are JSON.
  const std::string error = ReadObjText(vertices + "f \xff\xfe 1 2\n", &mesh);
  CHECK(error.find("face corner '?"
                   "?' names no vertex") != std::string::npos);
  CHECK(IsPlainAscii(error));
}

TEST_CASE("reference import: GLB chunks that overrun, and a parser message quoting bytes that are not UTF-8") {
  std::vector<std::uint8_t> bin;
  json square = Square(&bin);
  square["buffers"][0].erase("uri");
  std::string text = square.dump();
  text.resize((text.size() + 3) / 4 * 4, ' ');
  auto glb = [&](std::uint32_t json_length, std::uint32_t bin_length) {
    std::vector<std::uint8_t> out;
    auto u32 = [&](std::uint32_t v) {
      for (int i = 0; i < 4; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
    };
    u32(0x46546C67);
    u32(2);
    u32(static_cast<std::uint32_t>(12 + 8 + text.size() + 8 + bin.size()));
    u32(json_length);
    u32(0x4E4F534A);
    out.insert(out.end(), text.begin(), text.end());
    u32(bin_length);
    u32(0x004E4942);
    out.insert(out.end(), bin.begin(), bin.end());
    return out;
  };
  auto read = [](const std::vector<std::uint8_t>& bytes) {
    facet::ReferenceMesh mesh;
    const std::string error =
        facet::ReadReferenceMeshBytes(bytes, facet::ReferenceFormat::kGltf, "hostile.glb", "", false, &mesh);
    CHECK(mesh.positions.empty() == !error.empty());
    return error;
  };
  const auto json_length = static_cast<std::uint32_t>(text.size());
  const auto bin_length = static_cast<std::uint32_t>(bin.size());
  CHECK(read(glb(json_length, bin_length)).empty());
  CHECK(read(glb(0xFFFFFFF0u, bin_length)).find("the first GLB chunk is not a complete JSON chunk") !=
        std::string::npos);
  CHECK(read(glb(json_length, 0xFFFFFFF0u)).find("the BIN chunk runs past the file") != std::string::npos);
  std::vector<std::uint8_t> truncated = glb(json_length, bin_length);
  truncated.resize(truncated.size() - 10);
  CHECK(read(truncated).find("does not match the file (truncated?)") != std::string::npos);
  CHECK(read({0x67, 0x6C, 0x54, 0x46, 2}).find("shorter than its header") != std::string::npos);

  facet::ReferenceMesh mesh;
  const std::string error = ReadGltfText("{\"asset\": \xff\xfe}", &mesh);
  CHECK(error.find("malformed glTF JSON") != std::string::npos);
  CHECK(IsPlainAscii(error));
}
