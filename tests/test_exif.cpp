// The EXIF focal-length reader (core/image/exif.h) on JPEGs built here: a tiny image from OpenCV
// with an EXIF block written byte by byte (TIFF header, IFD0 pointing at the Exif IFD), so
// the test does not trust libexif's writer to check libexif's reader.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "core/image/exif.h"

namespace facet {
namespace {

// Focal lengths are products and quotients of a few doubles.
constexpr double kRelative = 1e-12;

constexpr uint16_t kShort = 3, kLong = 4, kRational = 5;

struct Tag {
  uint16_t tag;
  uint16_t type;
  std::vector<uint32_t> values;  // one for SHORT/LONG, numerator and denominator for RATIONAL
};

void Put16(std::vector<uint8_t>* out, size_t at, uint16_t v) {
  (*out)[at] = v & 0xff;
  (*out)[at + 1] = v >> 8;
}
void Put32(std::vector<uint8_t>* out, size_t at, uint32_t v) {
  for (int k = 0; k < 4; ++k) (*out)[at + k] = (v >> (8 * k)) & 0xff;
}

// Little-endian TIFF: IFD0 with one entry (the Exif IFD pointer), then the Exif IFD with
// the given tags (ascending), then the rationals' data.
std::vector<uint8_t> TiffWithExifTags(const std::vector<Tag>& tags) {
  const size_t exif_ifd = 8 + 2 + 12 + 4;
  const size_t data_start = exif_ifd + 2 + 12 * tags.size() + 4;
  std::vector<uint8_t> out(data_start, 0);
  out[0] = 'I', out[1] = 'I';
  Put16(&out, 2, 42);
  Put32(&out, 4, 8);
  Put16(&out, 8, 1);
  Put16(&out, 10, 0x8769);  // ExifIFDPointer
  Put16(&out, 12, kLong);
  Put32(&out, 14, 1);
  Put32(&out, 18, static_cast<uint32_t>(exif_ifd));
  Put32(&out, 22, 0);
  Put16(&out, exif_ifd, static_cast<uint16_t>(tags.size()));
  for (size_t i = 0; i < tags.size(); ++i) {
    const size_t e = exif_ifd + 2 + 12 * i;
    Put16(&out, e, tags[i].tag);
    Put16(&out, e + 2, tags[i].type);
    Put32(&out, e + 4, 1);
    if (tags[i].type == kShort) {
      Put16(&out, e + 8, static_cast<uint16_t>(tags[i].values[0]));
    } else if (tags[i].type == kLong) {
      Put32(&out, e + 8, tags[i].values[0]);
    } else {
      const size_t at = out.size();
      out.resize(at + 8);
      Put32(&out, e + 8, static_cast<uint32_t>(at));
      Put32(&out, at, tags[i].values[0]);
      Put32(&out, at + 4, tags[i].values[1]);
    }
  }
  return out;
}

// A 16 x 16 grey JPEG from OpenCV with an APP1 "Exif" segment right after its SOI marker.
std::vector<uint8_t> JpegWithExif(const std::vector<uint8_t>& tiff) {
  std::vector<uint8_t> jpeg;
  REQUIRE(cv::imencode(".jpg", cv::Mat(16, 16, CV_8UC1, cv::Scalar(128)), jpeg));
  REQUIRE(jpeg.size() > 2);
  if (tiff.empty()) return jpeg;
  const size_t length = 2 + 6 + tiff.size();
  std::vector<uint8_t> app1 = {
      0xff, 0xe1, static_cast<uint8_t>(length >> 8), static_cast<uint8_t>(length & 0xff), 'E', 'x', 'i', 'f', 0, 0};
  app1.insert(app1.end(), tiff.begin(), tiff.end());
  jpeg.insert(jpeg.begin() + 2, app1.begin(), app1.end());
  return jpeg;
}

ExifFocal Read(const std::vector<uint8_t>& bytes, int w, int h) {
  return ReadExifFocalFromBuffer(bytes.data(), bytes.size(), w, h);
}

void CheckRelative(double value, double expected) {
  CAPTURE(value);
  CAPTURE(expected);
  CHECK(std::abs(value - expected) <= kRelative * std::abs(expected));
}

// The 35 mm convention: the full frame's diagonal, sqrt(36^2 + 24^2) mm, spans the image's.
double EquivalentFocalPx(double focal_35mm, int width_px, int height_px) {
  return focal_35mm / std::sqrt(36.0 * 36.0 + 24.0 * 24.0) *
         std::sqrt(double(width_px) * width_px + double(height_px) * height_px);
}

TEST_CASE("FocalLengthIn35mmFilm maps the full frame's diagonal to the image's") {
  const std::vector<uint8_t> jpeg = JpegWithExif(TiffWithExifTags({{0xa405, kShort, {28}}}));
  CHECK(jpeg.size() < 5000);
  const ExifFocal full = Read(jpeg, 4000, 3000);
  INFO(full.message);
  REQUIRE(full.found);
  CHECK(full.IsUsable());
  CHECK(full.focal_35mm_equivalent_mm == 28.0);
  CHECK(full.focal_length_mm == 0.0);
  // 4:3: 28 / 43.27 * 5000 px, 4 % longer than 36 mm on the larger side would give.
  CheckRelative(full.focal_px, EquivalentFocalPx(28.0, 4000, 3000));
  CHECK(full.focal_px > 1.035 * 28.0 / 36.0 * 4000.0);
  // Downscaled and portrait copies of the same photo.
  CheckRelative(Read(jpeg, 800, 600).focal_px, EquivalentFocalPx(28.0, 800, 600));
  CheckRelative(Read(jpeg, 3000, 4000).focal_px, full.focal_px);
}

TEST_CASE("FocalLength with the focal-plane resolution, scaled to the given image size") {
  // 4.2 mm at 1000 sensor px per cm (100 px/mm): 420 px at the camera's 4000 x 3000.
  const std::vector<Tag> tags = {{0x920a, kRational, {42, 10}},
                                 {0xa002, kLong, {4000}},
                                 {0xa003, kLong, {3000}},
                                 {0xa20e, kRational, {1000, 1}},
                                 {0xa210, kShort, {3}}};
  const std::vector<uint8_t> jpeg = JpegWithExif(TiffWithExifTags(tags));
  const ExifFocal full = Read(jpeg, 4000, 3000);
  INFO(full.message);
  REQUIRE(full.found);
  CheckRelative(full.focal_length_mm, 4.2);
  CheckRelative(full.focal_plane_pixels_per_mm, 100.0);
  CheckRelative(full.focal_px, 420.0);
  CheckRelative(Read(jpeg, 2000, 1500).focal_px, 210.0);

  // Unit inch (2): 2540 px per inch is the same 100 px/mm.
  std::vector<Tag> inch = tags;
  inch[3].values = {2540, 1};
  inch[4].values = {2};
  CheckRelative(Read(JpegWithExif(TiffWithExifTags(inch)), 4000, 3000).focal_px, 420.0);

  // With the 35 mm figure present too, that one wins.
  std::vector<Tag> both = tags;
  both.insert(both.begin() + 3, {0xa405, kShort, {24}});
  CheckRelative(Read(JpegWithExif(TiffWithExifTags(both)), 4000, 3000).focal_px, EquivalentFocalPx(24.0, 4000, 3000));
}

TEST_CASE("absent, incomplete or corrupt EXIF gives found == false with a message") {
  const ExifFocal no_exif = Read(JpegWithExif({}), 640, 480);
  CHECK_FALSE(no_exif.found);
  CHECK(no_exif.focal_px == 0.0);
  CHECK_FALSE(no_exif.message.empty());

  const ExifFocal no_focal = Read(JpegWithExif(TiffWithExifTags({{0xa002, kLong, {4000}}})), 640, 480);
  INFO(no_focal.message);
  CHECK_FALSE(no_focal.found);
  CHECK(no_focal.message.find("no focal length") != std::string::npos);

  // FocalLength alone cannot be turned into pixels.
  const ExifFocal mm_only = Read(JpegWithExif(TiffWithExifTags({{0x920a, kRational, {42, 10}}})), 640, 480);
  INFO(mm_only.message);
  CHECK_FALSE(mm_only.found);
  CheckRelative(mm_only.focal_length_mm, 4.2);
  CHECK(mm_only.message.find("FocalLength") != std::string::npos);

  // A zero denominator, a truncated block and random bytes.
  CHECK_FALSE(
      Read(JpegWithExif(TiffWithExifTags({{0xa20e, kRational, {1000, 0}}, {0x920a, kRational, {42, 0}}})), 640, 480)
          .found);
  std::vector<uint8_t> truncated = JpegWithExif(TiffWithExifTags({{0xa405, kShort, {28}}}));
  truncated.resize(30);
  CHECK_FALSE(Read(truncated, 640, 480).found);
  std::vector<uint8_t> noise(2000);
  uint32_t state = 12345;
  for (auto& b : noise) b = static_cast<uint8_t>((state = state * 1664525u + 1013904223u) >> 24);
  CHECK_FALSE(Read(noise, 640, 480).found);
  CHECK_FALSE(ReadExifFocalFromBuffer(nullptr, 0, 640, 480).found);

  const ExifFocal bad_size = Read(JpegWithExif(TiffWithExifTags({{0xa405, kShort, {28}}})), 0, 480);
  CHECK_FALSE(bad_size.found);
  CHECK(bad_size.message.find("image size") != std::string::npos);
}

TEST_CASE("EXIF focal length from a file") {
  const std::string path = std::string(FACET_BINARY_DIR) + "/test_exif_focal.jpg";
  {
    const std::vector<uint8_t> jpeg = JpegWithExif(TiffWithExifTags({{0xa405, kShort, {50}}}));
    std::ofstream out(path, std::ios::binary);
    out.write(reinterpret_cast<const char*>(jpeg.data()), static_cast<std::streamsize>(jpeg.size()));
  }
  // OpenCV reads it back as an image: the EXIF segment left the JPEG valid.
  CHECK(cv::imread(path, cv::IMREAD_GRAYSCALE).cols == 16);
  const ExifFocal focal = ReadExifFocalFromFile(path, 1200, 800);
  INFO(focal.message);
  CHECK(focal.found);
  // 3:2, the full frame's own shape: the diagonal and the width conventions agree.
  CheckRelative(focal.focal_px, 50.0 / 36.0 * 1200.0);
  std::remove(path.c_str());
  const ExifFocal missing = ReadExifFocalFromFile(path, 1200, 800);
  CHECK_FALSE(missing.found);
  CHECK(missing.message.find(path) != std::string::npos);
}

}  // namespace
}  // namespace facet
