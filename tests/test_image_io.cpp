// Image I/O: PNG round-trip, size without decoding, and errors (missing, truncated, garbage).
#include <chrono>
#include <filesystem>
#include <fstream>
#include <random>

#include <doctest/doctest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/image/image_io.h"

namespace fs = std::filesystem;

namespace {

fs::path TempDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("facet_test_image_io_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

facet::ImageRgba8 MakePattern(int width, int height) {
  facet::ImageRgba8 image;
  image.width = width;
  image.height = height;
  image.pixels.resize(static_cast<size_t>(width) * height * 4);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      std::uint8_t* p = image.At(x, y);
      p[0] = static_cast<std::uint8_t>(x * 7 + y);
      p[1] = static_cast<std::uint8_t>(y * 5);
      p[2] = static_cast<std::uint8_t>((x ^ y) * 3);
      p[3] = static_cast<std::uint8_t>(255 - x);
    }
  }
  return image;
}

void WriteBytes(const fs::path& path, const std::vector<std::uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

std::vector<std::uint8_t> ReadBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<std::uint8_t>(std::istreambuf_iterator<char>(in), {});
}

// A noisy photo-like JPEG, so that the entropy-coded data is large.
fs::path MakeJpeg(const fs::path& dir, int width, int height) {
  cv::Mat bgr(height, width, CV_8UC3);
  cv::randu(bgr, cv::Scalar::all(0), cv::Scalar::all(255));
  const fs::path path = dir / "photo.jpg";
  REQUIRE(cv::imwrite(path.string(), bgr));
  return path;
}

}  // namespace

TEST_CASE("PNG round-trip keeps every RGBA byte") {
  const fs::path dir = TempDir("roundtrip");
  const facet::ImageRgba8 image = MakePattern(37, 23);  // odd sizes catch stride errors
  const std::string path = (dir / "pattern.png").string();
  REQUIRE(facet::WritePng(path, image).empty());

  const facet::ImageReadResult read = facet::ReadImage(path);
  REQUIRE_MESSAGE(read.ok(), read.error);
  CHECK(read.image.width == 37);
  CHECK(read.image.height == 23);
  REQUIRE(read.image.pixels.size() == image.pixels.size());
  size_t differing = 0;
  for (size_t i = 0; i < image.pixels.size(); ++i) differing += image.pixels[i] != read.image.pixels[i];
  CHECK_MESSAGE(differing == 0, "differing bytes: " << differing);

  // EncodePng produces the same kind of stream, decodable by OpenCV as BGRA.
  const std::vector<std::uint8_t> png = facet::EncodePng(image);
  const cv::Mat decoded = cv::imdecode(png, cv::IMREAD_UNCHANGED);
  REQUIRE(decoded.type() == CV_8UC4);
  const cv::Vec4b p = decoded.at<cv::Vec4b>(5, 11);
  const std::uint8_t* q = image.At(11, 5);
  CHECK(p[0] == q[2]);
  CHECK(p[1] == q[1]);
  CHECK(p[2] == q[0]);
  CHECK(p[3] == q[3]);
}

TEST_CASE("a colour JPEG reads as RGBA with opaque alpha and its colours in RGB order") {
  const fs::path dir = TempDir("jpeg_colour");
  cv::Mat bgr(16, 24, CV_8UC3, cv::Scalar(200, 100, 30));  // B, G, R
  const std::string path = (dir / "flat.jpg").string();
  REQUIRE(cv::imwrite(path, bgr));
  const facet::ImageReadResult read = facet::ReadImage(path);
  REQUIRE_MESSAGE(read.ok(), read.error);
  const std::uint8_t* p = read.image.At(10, 8);
  constexpr int kJpegTolerance = 4;  // lossy coding of a flat colour
  CAPTURE(int(p[0]));
  CAPTURE(int(p[1]));
  CAPTURE(int(p[2]));
  CHECK(std::abs(p[0] - 30) <= kJpegTolerance);
  CHECK(std::abs(p[1] - 100) <= kJpegTolerance);
  CHECK(std::abs(p[2] - 200) <= kJpegTolerance);
  CHECK(p[3] == 255);
}

TEST_CASE("ReadImageSize gives the size of PNG and JPEG, fast on a 12 MP photo") {
  const fs::path dir = TempDir("size");
  const std::string png = (dir / "p.png").string();
  REQUIRE(facet::WritePng(png, MakePattern(41, 19)).empty());
  int w = 0, h = 0;
  std::string error;
  REQUIRE_MESSAGE(facet::ReadImageSize(png, &w, &h, &error), error);
  CHECK(w == 41);
  CHECK(h == 19);

  const fs::path jpeg = MakeJpeg(dir, 4000, 3000);
  const auto start = std::chrono::steady_clock::now();
  REQUIRE_MESSAGE(facet::ReadImageSize(jpeg.string(), &w, &h, &error), error);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  CHECK(w == 4000);
  CHECK(h == 3000);
  MESSAGE("ReadImageSize of a 12 MP JPEG: " << ms << " ms");
  constexpr double kMaxSizeReadMs = 50.0;  // a full decode takes several hundred ms here
  CHECK(ms < kMaxSizeReadMs);
}

TEST_CASE("a missing file is an error naming the file") {
  const fs::path dir = TempDir("missing");
  const std::string path = (dir / "nope.jpg").string();
  const facet::ImageReadResult read = facet::ReadImage(path);
  CHECK_FALSE(read.ok());
  CHECK(read.image.empty());
  CHECK(read.error.find("nope.jpg") != std::string::npos);
  int w = 0, h = 0;
  std::string error;
  CHECK_FALSE(facet::ReadImageSize(path, &w, &h, &error));
  CHECK(error.find("nope.jpg") != std::string::npos);
}

TEST_CASE("a truncated JPEG is reported, not half-decoded") {
  const fs::path dir = TempDir("truncated");
  const fs::path jpeg = MakeJpeg(dir, 320, 240);
  const std::vector<std::uint8_t> bytes = ReadBytes(jpeg);
  REQUIRE(bytes.size() > 1000);
  // The intact file reads, so the failure below is due to the truncation alone.
  REQUIRE(facet::ReadImage(jpeg.string()).ok());
  for (double fraction : {0.3, 0.6, 0.95}) {
    CAPTURE(fraction);
    const fs::path cut = dir / "cut.jpg";
    WriteBytes(cut,
               std::vector<std::uint8_t>(bytes.begin(), bytes.begin() + static_cast<long>(bytes.size() * fraction)));
    const facet::ImageReadResult read = facet::ReadImage(cut.string());
    CHECK_FALSE(read.ok());
    CHECK(read.image.empty());
    MESSAGE(read.error);
  }
  // Just the last two bytes (the EOI marker) missing.
  const fs::path cut = dir / "cut_eoi.jpg";
  WriteBytes(cut, std::vector<std::uint8_t>(bytes.begin(), bytes.end() - 2));
  CHECK_FALSE(facet::ReadImage(cut.string()).ok());
}

TEST_CASE("random bytes, an empty file and a corrupt PNG are errors, not crashes") {
  const fs::path dir = TempDir("garbage");
  std::mt19937 rng(7);
  std::vector<std::uint8_t> noise(5000);
  for (auto& b : noise) b = static_cast<std::uint8_t>(rng());
  const fs::path random_path = dir / "random.jpg";
  WriteBytes(random_path, noise);
  CHECK_FALSE(facet::ReadImage(random_path.string()).ok());
  int w = 0, h = 0;
  std::string error;
  CHECK_FALSE(facet::ReadImageSize(random_path.string(), &w, &h, &error));

  // A JPEG signature followed by garbage.
  noise[0] = 0xFF;
  noise[1] = 0xD8;
  noise[2] = 0xFF;
  WriteBytes(random_path, noise);
  CHECK_FALSE(facet::ReadImage(random_path.string()).ok());

  const fs::path empty_path = dir / "empty.png";
  WriteBytes(empty_path, {});
  CHECK_FALSE(facet::ReadImage(empty_path.string()).ok());
  CHECK_FALSE(facet::ReadImageSize(empty_path.string(), &w, &h, &error));

  const fs::path png_path = dir / "p.png";
  REQUIRE(facet::WritePng(png_path.string(), MakePattern(64, 64)).empty());
  std::vector<std::uint8_t> png = ReadBytes(png_path);
  png.resize(png.size() / 2);
  WriteBytes(png_path, png);
  CHECK_FALSE(facet::ReadImage(png_path.string()).ok());
}

TEST_CASE("writing an empty image or to a missing folder fails with a message") {
  const fs::path dir = TempDir("write_errors");
  CHECK_FALSE(facet::WritePng((dir / "e.png").string(), facet::ImageRgba8()).empty());
  CHECK(facet::EncodePng(facet::ImageRgba8()).empty());
  CHECK_FALSE(facet::WritePng((dir / "no_such_dir" / "x.png").string(), MakePattern(4, 4)).empty());
}

TEST_CASE("grey, 16-bit and TIFF images read as 8-bit RGBA; the TIFF size is read from its header") {
  const fs::path dir = TempDir("formats");
  cv::Mat grey(10, 12, CV_8UC1, cv::Scalar(77));
  REQUIRE(cv::imwrite((dir / "grey.png").string(), grey));
  facet::ImageReadResult read = facet::ReadImage((dir / "grey.png").string());
  REQUIRE_MESSAGE(read.ok(), read.error);
  const std::uint8_t* p = read.image.At(3, 4);
  CHECK((p[0] == 77 && p[1] == 77 && p[2] == 77 && p[3] == 255));

  cv::Mat deep(8, 9, CV_16UC3, cv::Scalar(257 * 10, 257 * 20, 257 * 30));  // B, G, R
  REQUIRE(cv::imwrite((dir / "deep.png").string(), deep));
  read = facet::ReadImage((dir / "deep.png").string());
  REQUIRE_MESSAGE(read.ok(), read.error);
  p = read.image.At(2, 2);
  CHECK((p[0] == 30 && p[1] == 20 && p[2] == 10 && p[3] == 255));

  REQUIRE(cv::haveImageWriter(".tiff"));
  cv::Mat bgr(21, 34, CV_8UC3, cv::Scalar(1, 2, 3));
  const std::string tiff = (dir / "t.tiff").string();
  REQUIRE(cv::imwrite(tiff, bgr));
  int w = 0, h = 0;
  std::string error;
  REQUIRE_MESSAGE(facet::ReadImageSize(tiff, &w, &h, &error), error);
  CHECK(w == 34);
  CHECK(h == 21);
}

// Fuzzing (tests/fuzz/fuzz_image): OpenCV handed these 132 bytes, "DICM" at byte 128, to its
// DICOM reader (GDCM), whose assert aborted the process. Only photo formats reach a decoder.
TEST_CASE("regression: a DICOM-looking file is refused with a message, not decoded (fuzz_image)") {
  std::vector<std::uint8_t> dicom(132, 0);
  for (const auto& [at, byte] : std::vector<std::pair<int, std::uint8_t>>{{45, 0xFF},
                                                                          {46, 0x4F},
                                                                          {47, 0xFF},
                                                                          {48, 0x51},
                                                                          {126, 0xFF},
                                                                          {127, 0x51},
                                                                          {128, 'D'},
                                                                          {129, 'I'},
                                                                          {130, 'C'},
                                                                          {131, 'M'}}) {
    dicom[at] = byte;
  }
  const facet::ImageReadResult decoded = facet::DecodeImage(dicom, "scan.dcm");
  CHECK_FALSE(decoded.ok());
  CHECK(decoded.error == "scan.dcm: not a JPEG, PNG, TIFF, BMP or WebP file");
  CHECK(decoded.image.pixels.empty());

  // The file path gives the same refusal, named by the file.
  const fs::path path = TempDir("dicom") / "scan.jpg";
  WriteBytes(path, dicom);
  const facet::ImageReadResult read = facet::ReadImage(path.string());
  CHECK(read.error == path.string() + ": not a JPEG, PNG, TIFF, BMP or WebP file");
}

// Fuzzing (tests/fuzz/fuzz_image): a 50-byte BMP that stb's header parser refuses declared
// 16400 x 63771 px (1,046 MP) and OpenCV allocated 3.1 GB to decode it. Its size is now read
// from the BMP header and refused against the pixel limit before any decoding.
TEST_CASE("regression: a BMP declaring 1,046 MP in 50 bytes is refused from its header (fuzz_image)") {
  const std::string hex =
      "424d7602000000000000000028000036000810400000"
      "1bf90000010018000000000025b4632db45a3ca0000996a0a54d4d00";
  std::vector<std::uint8_t> bmp;
  for (size_t i = 0; i + 1 < hex.size(); i += 2)
    bmp.push_back(static_cast<std::uint8_t>(std::stoi(hex.substr(i, 2), nullptr, 16)));
  REQUIRE(bmp.size() == 50);
  const facet::ImageReadResult decoded = facet::DecodeImage(bmp, "tiny.bmp");
  CHECK_FALSE(decoded.ok());
  CHECK(decoded.error == "tiny.bmp: 16400 x 63771 px (1045 MP) is more than the limit of 150 MP");
  CHECK(decoded.image.pixels.empty());
}

TEST_CASE("DecodeImage reads a photo held in memory as ReadImage reads its file, and applies its pixel limit") {
  const fs::path dir = TempDir("decode_memory");
  const fs::path png_path = dir / "p.png";
  REQUIRE(facet::WritePng(png_path.string(), MakePattern(40, 30)).empty());
  const std::vector<std::uint8_t> bytes = ReadBytes(png_path);
  const facet::ImageReadResult from_file = facet::ReadImage(png_path.string());
  const facet::ImageReadResult from_memory = facet::DecodeImage(bytes, "p.png");
  REQUIRE_MESSAGE(from_memory.ok(), from_memory.error);
  CHECK(from_memory.image.width == 40);
  CHECK(from_memory.image.height == 30);
  CHECK(from_memory.image.pixels == from_file.image.pixels);
  // 1,200 px over a 1,000 px limit: refused from the header, the limit in the message.
  const facet::ImageReadResult limited = facet::DecodeImage(bytes, "p.png", 1000);
  CHECK_FALSE(limited.ok());
  CHECK(limited.error == "p.png: 40 x 30 px (0 MP) is more than the limit of 1000 px");
}

TEST_CASE("WritePng is atomic: a failed write leaves the old PNG whole; a symlink stays a link") {
  const fs::path dir = TempDir("atomic_png");
  const std::string shot = (dir / "shot.png").string();
  REQUIRE(facet::WritePng(shot, MakePattern(8, 6)).empty());
  const auto old_size = fs::file_size(shot);
  // An invalid image is refused before anything is written: the old file is untouched.
  CHECK_FALSE(facet::WritePng(shot, facet::ImageRgba8()).empty());
  CHECK(fs::file_size(shot) == old_size);
  // A folder that does not exist: an error naming the path, no stray temporary file.
  const std::string error = facet::WritePng((dir / "missing" / "x.png").string(), MakePattern(8, 6));
  CHECK(error.find("missing") != std::string::npos);
  // Through a dangling symlink the picture lands where the link points; the link stays.
  fs::create_symlink(dir / "target.png", dir / "link.png");
  REQUIRE(facet::WritePng((dir / "link.png").string(), MakePattern(8, 6)).empty());
  CHECK(fs::is_symlink(dir / "link.png"));
  CHECK(fs::is_regular_file(dir / "target.png"));
  int files = 0;
  for (const auto& e : fs::directory_iterator(dir)) files += e.path().filename().string().find(".tmp-") == std::string::npos;
  CHECK(files == 3);  // shot.png, link.png, target.png: no temporary left behind
}

// The declared size of a TIFF (its first directory) or a WebP (its VP8X, VP8L or VP8 chunk) is
// checked against the pixel limit before OpenCV allocates it, as for JPEG, PNG and BMP.
static std::vector<std::uint8_t> TiffDeclaring(std::uint32_t width, std::uint32_t height, bool big_endian) {
  std::vector<std::uint8_t> b;
  const auto put = [&](std::uint32_t v, int bytes) {
    for (int k = 0; k < bytes; ++k) b.push_back(static_cast<std::uint8_t>(v >> (8 * (big_endian ? bytes - 1 - k : k))));
  };
  b.push_back(big_endian ? 'M' : 'I');
  b.push_back(big_endian ? 'M' : 'I');
  put(42, 2);
  put(8, 4);  // the first directory follows the header
  put(2, 2);  // two entries: ImageWidth (LONG), ImageLength (SHORT when it fits)
  put(256, 2), put(4, 2), put(1, 4), put(width, 4);
  put(257, 2), put(height < 65536 ? 3 : 4, 2), put(1, 4);
  if (height < 65536) put(height, 2), put(0, 2); else put(height, 4);
  put(0, 4);  // no next directory
  return b;
}

TEST_CASE("regression: a TIFF or WebP declaring more than the pixel limit is refused from its header") {
  for (const bool big_endian : {false, true}) {
    const facet::ImageReadResult r = facet::DecodeImage(TiffDeclaring(100000, 20000, big_endian), "huge.tif");
    CHECK_FALSE(r.ok());
    CHECK(r.error == "huge.tif: 100000 x 20000 px (2000 MP) is more than the limit of 150 MP");
    CHECK(r.image.pixels.empty());
  }
  // Within the limit the header passes, and the missing pixel data is then a decoding error.
  const facet::ImageReadResult small = facet::DecodeImage(TiffDeclaring(64, 48, false), "small.tif");
  CHECK_FALSE(small.ok());
  CHECK(small.error.find("more than the limit") == std::string::npos);
  // A TIFF directory without ImageWidth: no size, no decoding.
  std::vector<std::uint8_t> sizeless = TiffDeclaring(64, 48, false);
  sizeless[10] = 0x99;  // the first entry's tag is no longer 256
  CHECK(facet::DecodeImage(sizeless, "t.tif").error == "t.tif: corrupt TIFF header (no image size in it)");

  // WebP, extended format: a 16384 x 16384 canvas (24-bit sizes minus one).
  std::vector<std::uint8_t> vp8x = {'R', 'I', 'F', 'F', 22, 0, 0, 0, 'W', 'E', 'B', 'P', 'V', 'P', '8', 'X',
                                    10,  0,   0,   0,   0,  0, 0, 0, 0xFF, 0x3F, 0, 0xFF, 0x3F, 0};
  const facet::ImageReadResult webp = facet::DecodeImage(vp8x, "huge.webp");
  CHECK(webp.error == "huge.webp: 16384 x 16384 px (268 MP) is more than the limit of 150 MP");
}

TEST_CASE("the WebP header's size (lossy and lossless) is the decoded size, and is checked before decoding") {
  REQUIRE(cv::haveImageWriter(".webp"));
  const fs::path dir = TempDir("webp");
  cv::Mat bgr(37, 53, CV_8UC3);
  cv::randu(bgr, 0, 255);
  for (const int quality : {80, 101}) {  // 101: lossless (VP8L)
    const fs::path path = dir / ("q" + std::to_string(quality) + ".webp");
    REQUIRE(cv::imwrite(path.string(), bgr, {cv::IMWRITE_WEBP_QUALITY, quality}));
    int w = 0, h = 0;
    std::string error;
    REQUIRE_MESSAGE(facet::ReadImageSize(path.string(), &w, &h, &error), error);
    CHECK(w == 53);
    CHECK(h == 37);
    const facet::ImageReadResult read = facet::ReadImage(path.string());
    REQUIRE_MESSAGE(read.ok(), read.error);
    CHECK(read.image.width == 53);
    CHECK(read.image.height == 37);
    // Only the header is left: a refusal by size can only have come from it.
    std::vector<std::uint8_t> head = ReadBytes(path);
    head.resize(32);
    const facet::ImageReadResult limited = facet::DecodeImage(head, "h.webp", 1000);
    CHECK(limited.error == "h.webp: 53 x 37 px (0 MP) is more than the limit of 1000 px");
  }
}
