// The bound on ids (core/geometry/ids.h) that a file may hold, checked once where ids enter:
// the project file's reader (core/io/project_io.cpp) and the recovery file's
// (core/io/recovery_io.cpp). Project::NewId counts up from a file's next_id; a next_id near
// 2^64 (issue 25: 2^64 - 1 restored silently) would wrap to kNoId at the next object and make
// the project unsavable.
#pragma once

#include "core/geometry/ids.h"

namespace facet {

// The largest id and next_id a file may hold: far beyond any real project (one object a
// nanosecond for 146 years), and far enough below 2^64 that counting up from it never wraps.
constexpr Id kMaxId = Id{1} << 62;

}  // namespace facet
