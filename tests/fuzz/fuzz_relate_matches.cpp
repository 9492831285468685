// `facet relate --matches MATCHES.json` (core/io/relate_io.h): parse, validate, estimate,
// format. Properties: fuzz_check.h, CheckJsonAdapter.
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/io/relate_io.h"
#include "tests/fuzz/fuzz_check.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  facet::fuzz::CheckJsonAdapter("fuzz_relate_matches", text,
                                [](const std::string& t) { return facet::RelateMatchesJson(t); });
  return 0;
}
