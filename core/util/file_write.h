// The one way Facet writes a file (projects, exports, screenshots, settings, reports, recovery
// files): to a temporary file beside the target, flushed to disk, then renamed over it, so a
// failed write (a full disk, a killed process) leaves the old file intact. A symlinked target is written
// where the link points, keeping the link.
#pragma once

#include <string>

namespace facet {

// "" on success, else what failed and why (the old file, if any, is untouched).
std::string WriteFileAtomically(const std::string& path, const std::string& bytes);

}  // namespace facet
