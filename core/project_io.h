// The project file (*.facet): versioned JSON. Image paths are stored relative to the
// project file's folder. Saving is atomic (write a temporary file, then rename). Loading a
// malformed or truncated file returns an error naming what is wrong and where (JSON pointer
// or line/column), and never crashes. Doubles are written with 17 significant digits so a
// save/load round-trip is exact.
#pragma once

#include <string>

#include "core/project.h"

namespace facet {

struct ProjectLoadResult {
  Project project;
  std::string error;  // empty on success
  std::vector<std::string> warnings;  // e.g. an image file that is missing on disk
  bool ok() const { return error.empty(); }
};

std::string ProjectToJson(const Project& project);
ProjectLoadResult ProjectFromJson(const std::string& text);
// Returns an empty string on success, else the error. Nothing is left half-written.
std::string SaveProject(const Project& project, const std::string& path);
ProjectLoadResult LoadProject(const std::string& path);
// Resolves an image's stored path against the folder of the project file.
std::string ResolveImagePath(const std::string& project_path, const std::string& image_path);
// Writes bytes atomically: a temporary file in the same folder, fsync, then rename.
std::string WriteFileAtomically(const std::string& path, const std::string& bytes);

}  // namespace facet
