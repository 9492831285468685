// `facet calibrate --lines LINES.json` (core/io/calibrate_io.h): parse, validate, calibrate,
// format. Properties: fuzz_check.h, CheckJsonAdapter.
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/io/calibrate_io.h"
#include "tests/fuzz/fuzz_check.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  facet::fuzz::CheckJsonAdapter("fuzz_calibrate_lines", text,
                                [](const std::string& t) { return facet::CalibrateLinesJson(t); });
  return 0;
}
