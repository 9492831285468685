// Stable object ids: every object of a project is referred to by id, never by index.
#pragma once

#include <cstdint>

namespace facet {

using Id = std::uint64_t;
constexpr Id kNoId = 0;

}  // namespace facet
