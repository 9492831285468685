// COLMAP models (core/io/colmap_model.h), which a user imports from a run made elsewhere: any
// bytes, given to each of the six file parsers, either parse or are refused with a message.
// What parses must write back and read back the same: text files through Facet's writer
// (core/io/colmap_model_write.h), binary ones through the tests' binary writer, byte for byte.
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/io/colmap_model.h"
#include "core/io/colmap_model_write.h"
#include "tests/colmap_binary_writer.h"
#include "tests/fuzz/fuzz_check.h"

namespace {

using facet::fuzz::Fail;
constexpr const char* kTarget = "fuzz_colmap_model";

template <typename Records, typename Parse, typename Write>
void CheckRoundTrip(const std::string& input, Parse parse, Write write, Records facet::ColmapModel::*records,
                    bool binary) {
  facet::ColmapModel model;
  const std::string error = parse(input, "file", &(model.*records));
  if (!error.empty()) return;
  const std::string written = write(model);
  facet::ColmapModel again;
  const std::string reread = parse(written, "file", &(again.*records));
  if (!reread.empty()) Fail(kTarget, "what was read does not read back once written: " + reread);
  if (write(again) != written) Fail(kTarget, "writing what was read back changes the file");
  if (binary && written != input) Fail(kTarget, "a binary file read and written again differs");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string input(reinterpret_cast<const char*>(data), size);
  using facet::ColmapModel;
  CheckRoundTrip(input, facet::ParseColmapCamerasText, facet::FormatColmapCamerasText, &ColmapModel::cameras, false);
  CheckRoundTrip(input, facet::ParseColmapImagesText, facet::FormatColmapImagesText, &ColmapModel::images, false);
  CheckRoundTrip(input, facet::ParseColmapPoints3DText, facet::FormatColmapPoints3DText, &ColmapModel::points3d, false);
  CheckRoundTrip(input, facet::ParseColmapCamerasBinary, facet::testing::ColmapCamerasBinary, &ColmapModel::cameras,
                 true);
  CheckRoundTrip(input, facet::ParseColmapImagesBinary, facet::testing::ColmapImagesBinary, &ColmapModel::images, true);
  CheckRoundTrip(input, facet::ParseColmapPoints3DBinary, facet::testing::ColmapPoints3DBinary, &ColmapModel::points3d,
                 true);
  return 0;
}
