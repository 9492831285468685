// The project file (*.facet): versioned JSON. Image paths are stored relative to the
// project file's folder. Saving is atomic (write a temporary file, then rename). Loading a
// malformed or truncated file returns an error naming what is wrong and where (JSON pointer
// or line/column), and never crashes. Doubles are written in the shortest form that reads
// back to the same bits, so a save/load round-trip is exact.
//
// Layout (version 5): {"format": "facet-project", "version": 5, "units", "next_id", "images",
// "segments", "primitives", "pins", "constraints", "references"}; every field of core/scene/project.h is stored,
// camera rotations as 9 numbers row-major (exact), primitive rotations as angle-axis, each
// primitive's mesh record by record with its ids (holes included) so that pins and
// constraints keep naming the same vertices; a mesh may also be "from_shape" (the unedited
// primitive); each image's "use_for_texture" and each primitive's "face_textures" (per face:
// {"face", "source_image" (0: the bake chooses), "excluded_images"}) are the user's texture
// choices; each image's "lens_group" (0: its own lens) says which photos share intrinsics in
// the joint solve; a reference is {"id", "path" (relative to the project file), "axes": "y_up" |
// "z_up", "visible"}, its mesh read from the file, never stored. Older files are upgraded on
// load (project_io.cpp, kMigrationSteps): version 1 (boxes with corner pins,
// tests/fixtures/project_v1.facet), version 2 (no texture choices, no references;
// tests/fixtures/project_v2.facet, assets/samples/leuven/*.facet), version 3 (no references)
// and version 4 (no lens groups).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/scene/project.h"
#include "core/util/file_write.h"  // WriteFileAtomically, used by every writer of project files and exports

namespace facet {

// The most mesh ids a project file may declare, summed over its primitives' vertex, edge and
// face id ends. Ids keep their holes, so an id end sets memory, not the file's size: without
// a bound a 9 KB file asked for 154 GB (tests/fuzz/fuzz_project reproduces it). 2^20 is 25 times
// the largest scene of the benchmarks (40,000 ids).
constexpr std::uint64_t kMaxProjectMeshIds = std::uint64_t{1} << 20;

struct ProjectLoadResult {
  Project project;
  std::string error;                  // empty on success
  std::vector<std::string> warnings;  // e.g. an image file that is missing on disk
  bool ok() const { return error.empty(); }
};

// Pretty JSON (2-space indent, trailing newline). Total: NaN/infinity become null and invalid
// UTF-8 is replaced, so check CheckProjectSavable first (SaveProject does).
std::string ProjectToJson(const Project& project);
// Empty when every number is finite and every text valid UTF-8, else the first offending
// field by JSON path, e.g. "primitives[0].params[1]: NaN cannot be saved ...".
std::string CheckProjectSavable(const Project& project);
// Parses and validates; the error names a line/column (syntax) or a JSON path (content).
// Meshes past kMaxProjectMeshIds are refused before they are allocated.
ProjectLoadResult ProjectFromJson(const std::string& text);
// Returns an empty string on success, else the error. Refuses a project that would not load
// back equal (non-finite numbers, dangling references, duplicate ids). Nothing is left
// half-written; on failure the previous file at `path` is untouched.
std::string SaveProject(const Project& project, const std::string& path);
// Reads and validates `path`; image files missing on disk are warnings, not errors.
ProjectLoadResult LoadProject(const std::string& path);
// Resolves an image's stored path against the folder of the project file. Absolute paths
// stay absolute; both are lexically normalised.
std::string ResolveImagePath(const std::string& project_path, const std::string& image_path);
// The path to store for an image file: relative to the project file's folder, forward slashes.
std::string RelativeImagePath(const std::string& project_path, const std::string& image_file_path);
// For "Save as" into another folder: re-expresses every image path relative to the new file.
void RebaseImagePaths(const std::string& old_project_path, const std::string& new_project_path, Project* project);

}  // namespace facet
