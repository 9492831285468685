#include "core/io/reference_mesh.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <filesystem>
#include <set>
#include <sstream>

#include "core/io/gltf_read.h"
#include "core/util/file_read.h"

namespace facet {
namespace {

// World from a Y-up file: (x, y, z) -> (x, -z, y), the inverse of ExportGlb's (x, z, -y).
Eigen::Vector3d WorldFromFile(const Eigen::Vector3d& p, bool y_up) {
  return y_up ? Eigen::Vector3d(p.x(), -p.z(), p.y()) : p;
}

// An OBJ index (1-based, or negative: counted back from the last vertex so far) as 0-based;
// -1 when it is 0 or out of range.
int ObjIndex(long value, size_t count) {
  if (value > 0 && static_cast<size_t>(value) <= count) return static_cast<int>(value - 1);
  if (value < 0 && static_cast<size_t>(-value) <= count) return static_cast<int>(count + value);
  return -1;
}

std::string ReadObj(const std::string& path, const std::string& text, bool y_up, ReferenceMesh* mesh) {
  std::istringstream in(text);
  std::string line;
  size_t line_number = 0;
  auto at = [&] { return path + ", line " + std::to_string(line_number) + ": "; };
  std::vector<int> face;
  while (std::getline(in, line)) {
    ++line_number;
    std::istringstream words(line);
    std::string tag;
    words >> tag;
    if (tag == "v") {
      Eigen::Vector3d p;
      if (!(words >> p.x() >> p.y() >> p.z()) || !p.allFinite()) return at() + "a vertex needs three finite numbers";
      if (mesh->positions.size() >= kMaxReferenceVertices)
        return path + ": more than " + std::to_string(kMaxReferenceVertices) + " vertices";
      mesh->positions.push_back(WorldFromFile(p, y_up));
    } else if (tag == "f") {
      face.clear();
      std::string corner;
      while (words >> corner) {
        // "v", "v/vt", "v//vn" or "v/vt/vn": the vertex is the first number.
        const std::string first = corner.substr(0, corner.find('/'));
        long value = 0;
        const auto [end, ec] = std::from_chars(first.data(), first.data() + first.size(), value);
        const int index = ec == std::errc() && end == first.data() + first.size()
                              ? ObjIndex(value, mesh->positions.size())
                              : -1;
        if (index < 0) return at() + "face corner '" + corner + "' names no vertex defined before it";
        face.push_back(index);
      }
      if (face.size() < 3) return at() + "a face needs at least three corners";
      for (size_t k = 1; k + 1 < face.size(); ++k) mesh->triangles.push_back({face[0], face[k], face[k + 1]});
      for (size_t k = 0; k < face.size(); ++k) mesh->edges.push_back({face[k], face[(k + 1) % face.size()]});
    }
  }
  return "";
}

std::string ReadGltfReference(const std::string& path, bool y_up, ReferenceMesh* mesh) {
  GltfScene scene;
  GltfReadOptions options;
  options.decode_images = false;
  const std::string error = ReadGltf(path, options, &scene);
  if (!error.empty()) return error;
  if (scene.positions.size() > kMaxReferenceVertices)
    return path + ": more than " + std::to_string(kMaxReferenceVertices) + " vertices";
  for (const Eigen::Vector3f& p : scene.positions) mesh->positions.push_back(WorldFromFile(p.cast<double>(), y_up));
  for (const GltfBatch& batch : scene.batches) {
    for (size_t i = 0; i + 2 < batch.indices.size(); i += 3) {
      const std::array<int, 3> t = {static_cast<int>(batch.indices[i]), static_cast<int>(batch.indices[i + 1]),
                                    static_cast<int>(batch.indices[i + 2])};
      mesh->triangles.push_back(t);
      for (int k = 0; k < 3; ++k) mesh->edges.push_back({t[k], t[(k + 1) % 3]});
    }
  }
  return "";
}

// Each undirected edge once; glTF's triangles keep their diagonals (the file has no polygons).
void DeduplicateEdges(ReferenceMesh* mesh) {
  std::set<std::pair<int, int>> seen;
  std::vector<std::array<int, 2>> unique;
  for (const auto& e : mesh->edges) {
    const auto key = std::minmax(e[0], e[1]);
    if (e[0] != e[1] && seen.insert(key).second) unique.push_back(e);
  }
  mesh->edges = std::move(unique);
}

}  // namespace

std::string ReadReferenceMesh(const std::string& path, bool y_up, ReferenceMesh* mesh) {
  *mesh = ReferenceMesh();
  std::string extension = std::filesystem::path(path).extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  std::string error;
  if (extension == ".obj") {
    std::string text;
    if (!ReadRegularFile(path, kMaxTextFileBytes, &text, &error)) return error;
    error = ReadObj(path, text, y_up, mesh);
  } else if (extension == ".glb" || extension == ".gltf") {
    error = ReadGltfReference(path, y_up, mesh);
  } else {
    return path + ": a reference mesh must be a Wavefront .obj or a glTF .glb or .gltf";
  }
  if (error.empty() && mesh->triangles.empty()) error = path + ": the file holds no triangles";
  if (!error.empty()) {
    *mesh = ReferenceMesh();
    return error;
  }
  DeduplicateEdges(mesh);
  mesh->lo = mesh->hi = mesh->positions.front();
  for (const Eigen::Vector3d& p : mesh->positions) {
    mesh->lo = mesh->lo.cwiseMin(p);
    mesh->hi = mesh->hi.cwiseMax(p);
  }
  return "";
}

}  // namespace facet
