// Reading the triangles of a reference mesh (core/scene/project.h, Reference): a Wavefront
// OBJ or a glTF (binary .glb, or JSON .gltf with its buffers beside it or in data: URIs),
// placed in the world as the reference's axes say.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace facet {

struct ReferenceMesh {
  std::vector<Eigen::Vector3d> positions;     // world frame (Z up)
  std::vector<std::array<int, 3>> triangles;  // indices into positions
  std::vector<std::array<int, 2>> edges;      // each polygon side of the file once, for outlines
  Eigen::Vector3d lo = Eigen::Vector3d::Zero(), hi = Eigen::Vector3d::Zero();  // bounds of positions
};

// The most vertices and triangles a reference may have: far above a survey's or a building's
// scan reduced for modelling against, and a bound on what one file can make the app draw every
// frame. A file over either is refused with the limit named, before it is read into memory.
constexpr size_t kMaxReferenceVertices = 2'000'000;
constexpr size_t kMaxReferenceTriangles = 4'000'000;

// Reads `path` (told by its extension: .obj, .glb or .gltf; other extensions are refused).
// OBJ: `v` and `f` records (polygons fanned into triangles; 1-based or negative indices, v/vt/vn
// forms), every other record ignored. glTF: every mesh node's triangles with their node
// transforms (core/io/gltf_read.h), its buffers read from data: URIs or files inside the
// glTF's folder only. y_up: file (x, y, z) is world (x, -z, y); otherwise file coordinates are
// world coordinates. Returns an empty string on success, else the error naming the file (and
// the line, for OBJ); *mesh is then empty. Never throws; a NaN or infinite coordinate is
// refused.
std::string ReadReferenceMesh(const std::string& path, bool y_up, ReferenceMesh* mesh);

enum class ReferenceFormat { kObj, kGltf /* .gltf or .glb, told by the GLB magic */ };

// ReadReferenceMesh on a file's `bytes` held in memory (what ReadReferenceMesh does after
// reading the file). `name` starts every error; `folder` is where a glTF's side files are
// read from (empty: data: URIs and a GLB's BIN chunk only; see ReadGltfBytes).
std::string ReadReferenceMeshBytes(const std::vector<std::uint8_t>& bytes, ReferenceFormat format,
                                   const std::string& name, const std::string& folder, bool y_up, ReferenceMesh* mesh);

}  // namespace facet
