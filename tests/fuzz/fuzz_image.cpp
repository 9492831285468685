// Photo decoding (core/image/image_io.h, DecodeImage; and core/image/exif.h on the same
// bytes): any bytes either decode to a well-formed RGBA image within the pixel limit or are
// refused with a message. A decoded image survives PNG encoding and decoding unchanged (PNG
// is lossless at 8 bits RGBA). The EXIF reader finds a positive, finite focal length or
// none.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core/utils/logger.hpp>

#include "core/image/exif.h"
#include "core/image/image_io.h"
#include "tests/fuzz/fuzz_check.h"

namespace {

using facet::fuzz::Fail;
constexpr const char* kTarget = "fuzz_image";
// Far below the product's 150 MP: a small input that declares a large photo would otherwise
// cost seconds and gigabytes per execution. The refusal path is the same code.
constexpr std::uint64_t kFuzzMaxPixels = 4'000'000;

}  // namespace

// OpenCV's codecs log every corrupt input; thousands of lines a second would bury the report.
extern "C" int LLVMFuzzerInitialize(int*, char***) {
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::vector<std::uint8_t> bytes(data, data + size);
  const facet::ImageReadResult read = facet::DecodeImage(bytes, "input", kFuzzMaxPixels);
  int width = 640, height = 480;  // the EXIF reader's size when the photo does not decode
  if (!read.ok()) {
    if (!read.image.pixels.empty()) Fail(kTarget, "a refused photo left pixels: " + read.error);
  } else {
    const facet::ImageRgba8& image = read.image;
    if (image.empty()) Fail(kTarget, "an accepted photo is empty");
    const std::uint64_t pixels = static_cast<std::uint64_t>(image.width) * static_cast<std::uint64_t>(image.height);
    if (pixels > kFuzzMaxPixels) Fail(kTarget, "an accepted photo is over the pixel limit");
    if (image.pixels.size() != pixels * 4) Fail(kTarget, "the pixel buffer does not match the size");
    const std::vector<std::uint8_t> png = facet::EncodePng(image);
    if (png.empty()) Fail(kTarget, "a decoded photo cannot be encoded as PNG");
    const facet::ImageReadResult back = facet::DecodeImage(png, "re-encoded", kFuzzMaxPixels);
    if (!back.ok()) Fail(kTarget, "the re-encoded PNG does not decode: " + back.error);
    if (back.image.width != image.width || back.image.height != image.height || back.image.pixels != image.pixels) {
      Fail(kTarget, "the PNG round trip changed the photo");
    }
    width = image.width;
    height = image.height;
  }
  const facet::ExifFocal exif = facet::ReadExifFocalFromBuffer(data, size, width, height);
  if (exif.found && !(std::isfinite(exif.focal_px) && exif.focal_px > 0.0)) {
    Fail(kTarget, "EXIF gave focal_px " + std::to_string(exif.focal_px) + ": " + exif.message);
  }
  return 0;
}
