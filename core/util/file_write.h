// The one way Facet writes a file (projects, exports, screenshots, settings, reports, recovery
// files): to a temporary file beside the target, flushed to disk, then renamed over it, so a
// failed write (a full disk, a killed process) leaves the old file intact. A symlinked target is written
// where the link points, keeping the link.
#pragma once

#include <string>

namespace facet {

// "" on success, else what failed and why (the old file, if any, is untouched).
std::string WriteFileAtomically(const std::string& path, const std::string& bytes);

// The one exception, for a journal whose reader drops a torn last record (the recovery file,
// core/io/recovery_io.h): appends `bytes` to the existing regular file `path` and flushes it to
// disk. "" on success; else what failed and why, and the file is cut back to its old length
// where that is still possible (a crash can leave part of `bytes` at the end). A missing file
// is an error (ENOENT), not created: the caller then writes the whole file atomically.
std::string AppendToFile(const std::string& path, const std::string& bytes);

}  // namespace facet
