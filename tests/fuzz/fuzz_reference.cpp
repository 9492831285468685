// The reference-mesh readers (core/io/reference_mesh.h, core/io/gltf_read.h), which the app runs
// on a file the user adds and on every reference a project names when it opens: any bytes
// either read or are refused with a message, never a crash, a hang or unbounded memory. Each
// input is read three ways: as a glTF (a .glb when it starts with the GLB magic, else JSON
// whose buffers are data: URIs or side files), as a Wavefront OBJ, and through ReadGltfBytes
// with cameras and images decoded. The side-file folder is a scratch folder made once, holding
// `side.bin` (a square's positions and indices, which the seeds name) and `link.bin`, a link
// to `outside.bin` one folder up. outside.bin is a FIFO: were it ever looked at, the file
// reader's refusal would say "FIFO", and no file inside the folder is one.
//
// Properties: a refusal starts with the file's name and leaves the mesh empty, its message is
// valid UTF-8 (the app's log and reports are JSON) and never names a side path as a FIFO; a mesh that reads has
// triangles whose indices name its vertices, finite positions inside its bounds, and at most
// kMaxReferenceVertices vertices and kMaxReferenceTriangles triangles.
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/io/gltf_read.h"
#include "core/io/reference_mesh.h"
#include "tests/fuzz/fuzz_check.h"

namespace {

using facet::fuzz::Fail;
constexpr const char* kTarget = "fuzz_reference";

std::string g_folder;  // the side-file folder

void WriteFile(const std::filesystem::path& path, const std::vector<std::uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

// The square the seeds' side file holds: 4 float positions (48 bytes), 6 16-bit indices.
std::vector<std::uint8_t> SquareBin() {
  const float positions[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  const std::uint16_t indices[6] = {0, 1, 2, 0, 2, 3};
  std::vector<std::uint8_t> bytes(sizeof(positions) + sizeof(indices));
  std::memcpy(bytes.data(), positions, sizeof(positions));
  std::memcpy(bytes.data() + sizeof(positions), indices, sizeof(indices));
  return bytes;
}

// What every message must be: valid UTF-8, and silent about the file outside the folder.
void CheckMessage(const std::string& name, const std::string& error) {
  try {
    (void)nlohmann::json(error).dump();
  } catch (const nlohmann::json::exception&) {
    Fail(kTarget, name + ": a message is not valid UTF-8");
  }
  // The file reader names the path it refused; the input itself may well say "FIFO".
  if (error.find(g_folder + "/") != std::string::npos && error.find("FIFO") != std::string::npos)
    Fail(kTarget, name + ": the file outside the folder was looked at: " + error);
}

void CheckMesh(const std::string& name, const std::string& error, const facet::ReferenceMesh& mesh) {
  CheckMessage(name, error);
  if (!error.empty()) {
    if (error.rfind(name + ": ", 0) != 0 && error.rfind(name + ", line ", 0) != 0)
      Fail(kTarget, "a refusal does not start with the file's name: " + error);
    if (!mesh.positions.empty() || !mesh.triangles.empty() || !mesh.edges.empty())
      Fail(kTarget, name + ": a refused file left a mesh");
    return;
  }
  if (mesh.triangles.empty()) Fail(kTarget, name + ": read with no triangles");
  if (mesh.positions.size() > facet::kMaxReferenceVertices) Fail(kTarget, name + ": more vertices than the cap");
  if (mesh.triangles.size() > facet::kMaxReferenceTriangles) Fail(kTarget, name + ": more triangles than the cap");
  for (const Eigen::Vector3d& p : mesh.positions) {
    if (!p.allFinite()) Fail(kTarget, name + ": a position is not finite");
    if ((p.array() < mesh.lo.array()).any() || (p.array() > mesh.hi.array()).any())
      Fail(kTarget, name + ": a position lies outside the bounds");
  }
  const auto n = static_cast<int>(mesh.positions.size());
  for (const auto& t : mesh.triangles)
    for (int v : t)
      if (v < 0 || v >= n) Fail(kTarget, name + ": a triangle names a vertex that is not there");
  for (const auto& e : mesh.edges)
    for (int v : e)
      if (v < 0 || v >= n) Fail(kTarget, name + ": an edge names a vertex that is not there");
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  char pattern[] = "/tmp/fuzz_reference.XXXXXX";
  const char* root = mkdtemp(pattern);
  if (root == nullptr) Fail(kTarget, "cannot make a scratch folder");
  const std::filesystem::path folder = std::filesystem::path(root) / "model";
  std::filesystem::create_directories(folder);
  WriteFile(folder / "side.bin", SquareBin());
  if (mkfifo((std::filesystem::path(root) / "outside.bin").c_str(), 0600) != 0)
    Fail(kTarget, "cannot make the FIFO outside the folder");
  std::error_code ec;
  std::filesystem::create_symlink("../outside.bin", folder / "link.bin", ec);
  g_folder = folder.string();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::vector<std::uint8_t> bytes(data, data + size);
  facet::ReferenceMesh mesh;
  std::string error =
      facet::ReadReferenceMeshBytes(bytes, facet::ReferenceFormat::kGltf, "fuzz.gltf", g_folder, true, &mesh);
  CheckMesh("fuzz.gltf", error, mesh);
  error = facet::ReadReferenceMeshBytes(bytes, facet::ReferenceFormat::kObj, "fuzz.obj", "", false, &mesh);
  CheckMesh("fuzz.obj", error, mesh);

  facet::GltfScene scene;
  error = facet::ReadGltfBytes(bytes, "scene.gltf", g_folder, facet::GltfReadOptions(), &scene);
  CheckMessage("scene.gltf", error);
  if (!error.empty()) {
    if (error.rfind("scene.gltf: ", 0) != 0) Fail(kTarget, "a refusal does not start with the file's name: " + error);
    if (!scene.positions.empty() || !scene.batches.empty() || !scene.cameras.empty() || !scene.images.empty())
      Fail(kTarget, "a refused glTF left a scene");
    return 0;
  }
  if (scene.normals.size() != scene.positions.size() || scene.uvs.size() != scene.positions.size())
    Fail(kTarget, "a scene's attributes differ in count");
  for (const facet::GltfBatch& batch : scene.batches) {
    if (batch.indices.size() % 3 != 0) Fail(kTarget, "a batch's index count is not a multiple of 3");
    for (std::uint32_t i : batch.indices)
      if (i >= scene.positions.size()) Fail(kTarget, "a batch names a vertex that is not there");
    if (batch.image >= static_cast<int>(scene.images.size())) Fail(kTarget, "a batch names an image that is not there");
  }
  for (const facet::GltfCamera& camera : scene.cameras) {
    if (camera.camera.width_px <= 0 || camera.camera.height_px <= 0) Fail(kTarget, "a camera has no image size");
    if (!std::isfinite(camera.camera.focal_px) || camera.camera.focal_px <= 0.0)
      Fail(kTarget, "a camera's focal length is not a positive number");
  }
  return 0;
}
