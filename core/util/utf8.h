// UTF-8 checks for text that goes where UTF-8 is required (JSON, glTF, Blender names): file
// paths and user strings are bytes, and a byte sequence that is not UTF-8 made nlohmann's
// dump() throw (error 316) and abort the process.
#pragma once

#include <string>

namespace facet {

// True when `text` is valid UTF-8 (shortest forms, no surrogates, at most U+10FFFF).
bool IsValidUtf8(const std::string& text);
// `text` itself when valid UTF-8, else with each byte that starts no valid sequence replaced
// by `replacement` (U+FFFD unless asked, e.g. "?" where a message must stay ASCII when it
// was): for reports, messages and names, never for what must round-trip.
std::string ValidUtf8OrReplaced(const std::string& text, const char* replacement = "\xEF\xBF\xBD");
// Text from a file quoted in a message: 'text' with every byte outside printable ASCII shown
// as '?', cut after `max_chars` with "...".
std::string QuotedAscii(const std::string& text, size_t max_chars);

}  // namespace facet
