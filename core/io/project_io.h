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
// "z_up", "visible"}, its mesh read from the file, never stored. A path (an image's or a
// reference's) is bytes, as the file system has it: a JSON string when it is valid UTF-8,
// else {"bytes_hex": "6dff2e6a7067"} (its bytes in hex), so that a photo in a folder named in
// another encoding round-trips exactly (such a file needs this build or later to open). Every
// other text (names, units) must be UTF-8: SaveProject refuses it by field otherwise.
// Numbers that are no camera are refused at load, naming the field, with the bounds of
// core/geometry/camera_checks.h: a calibrated camera's focal length and principal point,
// radial distortion that folds the photo or exceeds kMaxDistortionCoefficient, a fixed focal
// length, a focal prior (value and std) and a horizon. Older files are upgraded on
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
// Reads and validates `path`; image files missing on disk, or there with another size than
// the image's (WhyPhotoIsNotTheImages, read from the file's header), are warnings, not errors:
// pins, lines and cameras stay as saved.
ProjectLoadResult LoadProject(const std::string& path);
// Empty when the photo file at photo_path, width_px x height_px, can be image's photo (the
// size the image was added with: its pins, lines and camera are in those pixels); else one
// sentence naming both sizes. A photo replaced by one of another size is another photo: open
// warns and treats it as missing, export leaves its faces untextured, Relink refuses it.
std::string WhyPhotoIsNotTheImages(const Image& image, const std::string& photo_path, int width_px, int height_px);
// Resolves an image's stored path against the folder of the project file. Absolute paths
// stay absolute; both are lexically normalised.
std::string ResolveImagePath(const std::string& project_path, const std::string& image_path);
// The path to store for an image file: relative to the project file's folder, forward slashes.
std::string RelativeImagePath(const std::string& project_path, const std::string& image_file_path);
// For "Save as" into another folder: re-expresses every image path relative to the new file.
void RebaseImagePaths(const std::string& old_project_path, const std::string& new_project_path, Project* project);

}  // namespace facet
