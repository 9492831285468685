// UTF-8 checks for text that goes where UTF-8 is required (JSON, glTF, Blender names): file
// paths and user strings are bytes, and a byte sequence that is not UTF-8 made nlohmann's
// dump() throw (error 316) and abort the process.
#pragma once

#include <string>

namespace facet {

// True when `text` is valid UTF-8 (shortest forms, no surrogates, at most U+10FFFF).
bool IsValidUtf8(const std::string& text);
// `text` itself when valid UTF-8, else with each byte that starts no valid sequence replaced
// by U+FFFD: for reports, messages and names, never for what must round-trip.
std::string ValidUtf8OrReplaced(const std::string& text);

}  // namespace facet
