#include "core/io/reference_mesh.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <filesystem>
#include <functional>
#include <new>
#include <set>
#include <sstream>

#include "core/io/gltf_read.h"
#include "core/util/file_read.h"
#include "core/util/utf8.h"

namespace facet {
namespace {

// World from a Y-up file: (x, y, z) -> (x, -z, y), the inverse of ExportGlb's (x, z, -y).
Eigen::Vector3d WorldFromFile(const Eigen::Vector3d& p, bool y_up) {
  return y_up ? Eigen::Vector3d(p.x(), -p.z(), p.y()) : p;
}

// An OBJ index (1-based, or negative: counted back from the last vertex so far) as 0-based;
// -1 when it is 0 or out of range. `count` is at most kMaxReferenceVertices.
int ObjIndex(long value, size_t count) {
  const long n = static_cast<long>(count);
  if (value > 0 && value <= n) return static_cast<int>(value - 1);
  if (value < 0 && value >= -n) return static_cast<int>(n + value);
  return -1;
}

// Text from the file quoted in a message: printable ASCII only (the app's log and reports are
// JSON, which holds UTF-8 only), shortened.
std::string Quoted(const std::string& text) { return QuotedAscii(text, 40); }

std::string TooManyTriangles(const std::string& name) {
  return name + ": more than " + std::to_string(kMaxReferenceTriangles) + " triangles, the most a reference may have";
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
        return path + ": more than " + std::to_string(kMaxReferenceVertices) +
               " vertices, the most a reference may have";
      mesh->positions.push_back(WorldFromFile(p, y_up));
    } else if (tag == "f") {
      face.clear();
      std::string corner;
      while (words >> corner) {
        // "v", "v/vt", "v//vn" or "v/vt/vn": the vertex is the first number.
        const std::string first = corner.substr(0, corner.find('/'));
        long value = 0;
        const auto [end, ec] = std::from_chars(first.data(), first.data() + first.size(), value);
        const int index =
            ec == std::errc() && end == first.data() + first.size() ? ObjIndex(value, mesh->positions.size()) : -1;
        if (index < 0) return at() + "face corner " + Quoted(corner) + " names no vertex defined before it";
        if (face.size() > kMaxReferenceTriangles + 2) return TooManyTriangles(path);
        face.push_back(index);
      }
      if (face.size() < 3) return at() + "a face needs at least three corners";
      if (face.size() - 2 > kMaxReferenceTriangles - mesh->triangles.size()) return TooManyTriangles(path);
      for (size_t k = 1; k + 1 < face.size(); ++k) mesh->triangles.push_back({face[0], face[k], face[k + 1]});
      for (size_t k = 0; k < face.size(); ++k) mesh->edges.push_back({face[k], face[(k + 1) % face.size()]});
    }
  }
  return "";
}

// The options a reference is read with: geometry only, within the reference's caps.
GltfReadOptions ReferenceGltfOptions() {
  GltfReadOptions options;
  options.decode_images = false;
  options.max_vertices = kMaxReferenceVertices;
  options.max_triangles = kMaxReferenceTriangles;
  return options;
}

// A glTF scene's triangles (ReadGltf checked their indices and the caps) as a reference.
void FromGltfScene(const GltfScene& scene, bool y_up, ReferenceMesh* mesh) {
  mesh->positions.reserve(scene.positions.size());
  for (const Eigen::Vector3f& p : scene.positions) mesh->positions.push_back(WorldFromFile(p.cast<double>(), y_up));
  for (const GltfBatch& batch : scene.batches) {
    for (size_t i = 0; i + 2 < batch.indices.size(); i += 3) {
      const std::array<int, 3> t = {static_cast<int>(batch.indices[i]), static_cast<int>(batch.indices[i + 1]),
                                    static_cast<int>(batch.indices[i + 2])};
      mesh->triangles.push_back(t);
      for (int k = 0; k < 3; ++k) mesh->edges.push_back({t[k], t[(k + 1) % 3]});
    }
  }
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

// What every reader ends with: an empty mesh on error, else its edges once each and bounds.
std::string Finish(const std::string& name, std::string error, ReferenceMesh* mesh) {
  if (error.empty() && mesh->triangles.empty()) error = name + ": the file holds no triangles";
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

// Reads into *mesh; any exception (out of memory) is a message too.
std::string Guarded(const std::string& name, ReferenceMesh* mesh, const std::function<std::string()>& read) {
  *mesh = ReferenceMesh();
  std::string error;
  try {
    error = read();
  } catch (const std::bad_alloc&) {
    error = name + ": too large to read (out of memory)";
  } catch (const std::exception& e) {
    error = name + ": cannot be read (" + std::string(e.what()) + ")";
  }
  return Finish(name, std::move(error), mesh);
}

}  // namespace

std::string ReadReferenceMesh(const std::string& path, bool y_up, ReferenceMesh* mesh) {
  std::string extension = std::filesystem::path(path).extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (extension == ".obj") {
    return Guarded(path, mesh, [&] {
      std::string text, error;
      if (!ReadRegularFile(path, kMaxTextFileBytes, &text, &error)) return error;
      return ReadObj(path, text, y_up, mesh);
    });
  }
  if (extension == ".glb" || extension == ".gltf") {
    return Guarded(path, mesh, [&] {
      GltfScene scene;
      const std::string error = ReadGltf(path, ReferenceGltfOptions(), &scene);
      if (error.empty()) FromGltfScene(scene, y_up, mesh);
      return error;
    });
  }
  *mesh = ReferenceMesh();
  return path + ": a reference mesh must be a Wavefront .obj or a glTF .glb or .gltf";
}

std::string ReadReferenceMeshBytes(const std::vector<std::uint8_t>& bytes, ReferenceFormat format,
                                   const std::string& name, const std::string& folder, bool y_up, ReferenceMesh* mesh) {
  return Guarded(name, mesh, [&] {
    if (format == ReferenceFormat::kObj) return ReadObj(name, std::string(bytes.begin(), bytes.end()), y_up, mesh);
    GltfScene scene;
    const std::string error = ReadGltfBytes(bytes, name, folder, ReferenceGltfOptions(), &scene);
    if (error.empty()) FromGltfScene(scene, y_up, mesh);
    return error;
  });
}

}  // namespace facet
