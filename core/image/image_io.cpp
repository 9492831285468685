// Decoding goes through OpenCV's imgcodecs (libjpeg-turbo, libpng): faster than stb_image on
// 12 MP JPEGs and it reads every format the header promises. Sizes come from stb_image's
// header parser, which reads a few bytes instead of decoding. Neither decoder reports a
// truncated JPEG (both pad the missing scan data), so a JPEG is checked for its end-of-image
// marker before decoding.
#include "core/image/image_io.h"

#include "core/util/file_read.h"
#include "core/util/file_write.h"

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>

#include <stb_image.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace facet {
namespace {

// TIFF: the first image file directory (IFD) holds ImageWidth (tag 256) and ImageLength (257),
// both required, as SHORT or LONG, in the file's byte order ("II" little, "MM" big endian).
// OpenCV decodes the first directory's image. False when the directory is not within b.
bool TiffHeaderSize(const std::vector<std::uint8_t>& b, int* w, int* h) {
  if (b.size() < 8) return false;
  const bool little = b[0] == 'I' && b[1] == 'I' && b[2] == 42 && b[3] == 0;
  const bool big = b[0] == 'M' && b[1] == 'M' && b[2] == 0 && b[3] == 42;
  if (!little && !big) return false;
  const auto read = [&](std::uint64_t at, int bytes) {
    std::uint32_t v = 0;
    for (int k = 0; k < bytes; ++k) {
      const std::uint32_t byte = b[static_cast<size_t>(at) + (little ? bytes - 1 - k : k)];
      v = (v << 8) | byte;
    }
    return v;
  };
  const std::uint64_t ifd = read(4, 4);
  if (ifd + 2 > b.size()) return false;
  const std::uint32_t entries = read(ifd, 2);
  std::int64_t width = -1, height = -1;
  for (std::uint32_t i = 0; i < entries; ++i) {
    const std::uint64_t at = ifd + 2 + 12ull * i;
    if (at + 12 > b.size()) return false;
    const std::uint32_t tag = read(at, 2), type = read(at + 2, 2);
    if (tag != 256 && tag != 257) continue;
    if (type != 3 && type != 4) return false;  // SHORT or LONG, the only types the standard allows
    const std::int64_t value = type == 3 ? read(at + 8, 2) : read(at + 8, 4);
    (tag == 256 ? width : height) = value;
  }
  if (width <= 0 || height <= 0) return false;
  *w = static_cast<int>(std::min<std::int64_t>(width, INT32_MAX));
  *h = static_cast<int>(std::min<std::int64_t>(height, INT32_MAX));
  return true;
}

// WebP: a RIFF container whose first chunk is VP8X (extended: the canvas size, 24-bit minus
// one), VP8L (lossless: 14-bit sizes minus one after the 0x2F signature) or "VP8 " (lossy: the
// key frame's 14-bit sizes after its start code 9D 01 2A).
bool WebpHeaderSize(const std::vector<std::uint8_t>& b, int* w, int* h) {
  if (b.size() < 30 || std::memcmp(b.data(), "RIFF", 4) != 0 || std::memcmp(b.data() + 8, "WEBP", 4) != 0) {
    return false;
  }
  const auto le = [&](size_t at, int bytes) {
    std::uint32_t v = 0;
    for (int k = bytes - 1; k >= 0; --k) v = (v << 8) | b[at + k];
    return v;
  };
  std::uint32_t width = 0, height = 0;
  if (std::memcmp(b.data() + 12, "VP8X", 4) == 0) {
    width = 1 + le(24, 3);
    height = 1 + le(27, 3);
  } else if (std::memcmp(b.data() + 12, "VP8L", 4) == 0) {
    if (b[20] != 0x2F) return false;
    const std::uint32_t bits = le(21, 4);
    width = 1 + (bits & 0x3FFF);
    height = 1 + ((bits >> 14) & 0x3FFF);
  } else if (std::memcmp(b.data() + 12, "VP8 ", 4) == 0) {
    if (b[23] != 0x9D || b[24] != 0x01 || b[25] != 0x2A) return false;
    width = le(26, 2) & 0x3FFF;
    height = le(28, 2) & 0x3FFF;
  } else {
    return false;
  }
  if (width == 0 || height == 0) return false;
  *w = static_cast<int>(width);
  *h = static_cast<int>(height);
  return true;
}

// The size a photo's header declares: stb's header parser, and for a PNG the IHDR chunk itself
// (stb refuses to parse a PNG header over 1 GB decoded, the very photos to refuse by size).
bool HeaderSize(const std::vector<std::uint8_t>& b, int* w, int* h) {
  int channels = 0;
  if (stbi_info_from_memory(b.data(), static_cast<int>(std::min<size_t>(b.size(), INT32_MAX)), w, h, &channels) != 0) {
    return true;
  }
  // A BMP whose header stb refuses but OpenCV decodes: a 50-byte one declared 16400 x 63771
  // px and OpenCV allocated 3.1 GB for it (found by tests/fuzz/fuzz_image). Width and height
  // are at bytes 18 and 22 (32-bit little-endian, the height negative for top-down rows), or
  // 16-bit ones in the 12-byte OS/2 header, as OpenCV reads them.
  if (b.size() >= 26 && b[0] == 'B' && b[1] == 'M') {
    const auto le = [&](size_t i, int bytes) {
      std::uint32_t v = 0;
      for (int k = bytes - 1; k >= 0; --k) v = (v << 8) | b[i + k];
      return v;
    };
    const bool os2 = le(14, 4) == 12;
    const std::int64_t bw = os2 ? le(18, 2) : static_cast<std::int32_t>(le(18, 4));
    const std::int64_t bh = os2 ? le(20, 2) : static_cast<std::int32_t>(le(22, 4));
    const std::int64_t aw = bw < 0 ? -bw : bw, ah = bh < 0 ? -bh : bh;
    if (aw == 0 || ah == 0) return false;
    *w = static_cast<int>(std::min<std::int64_t>(aw, INT32_MAX));
    *h = static_cast<int>(std::min<std::int64_t>(ah, INT32_MAX));
    return true;
  }
  if (TiffHeaderSize(b, w, h) || WebpHeaderSize(b, w, h)) return true;
  static const std::uint8_t kPng[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  if (b.size() < 24 || !std::equal(kPng, kPng + 8, b.begin()) || std::memcmp(&b[12], "IHDR", 4) != 0) return false;
  const auto be32 = [&](size_t i) {
    return (std::uint32_t{b[i]} << 24) | (std::uint32_t{b[i + 1]} << 16) | (std::uint32_t{b[i + 2]} << 8) | b[i + 3];
  };
  const std::uint32_t pw = be32(16), ph = be32(20);
  if (pw == 0 || ph == 0 || pw > INT32_MAX || ph > INT32_MAX) return false;
  *w = static_cast<int>(pw);
  *h = static_cast<int>(ph);
  return true;
}

// "" when a w x h photo is within max_pixels, else the refusal naming the limit.
std::string PixelLimitRefusal(const std::string& path, int w, int h, std::uint64_t max_pixels) {
  const auto pixels = static_cast<std::uint64_t>(std::max(w, 0)) * static_cast<std::uint64_t>(std::max(h, 0));
  if (pixels <= max_pixels) return "";
  const std::string limit =
      max_pixels >= 1000000 ? std::to_string(max_pixels / 1000000) + " MP" : std::to_string(max_pixels) + " px";
  return path + ": " + std::to_string(w) + " x " + std::to_string(h) + " px (" + std::to_string(pixels / 1000000) +
         " MP) is more than the limit of " + limit;
}

bool StartsWith(const std::vector<std::uint8_t>& b, const char* prefix, size_t n, size_t at = 0) {
  return b.size() >= at + n && std::memcmp(b.data() + at, prefix, n) == 0;
}

// The formats a photo may be in (app/state/file_browser_model.h offers the same): JPEG, PNG,
// TIFF, BMP and WebP, told by their signatures. OpenCV's imdecode tries every codec it was
// built with, and Debian's includes DICOM (GDCM), whose reader asserts, aborting the whole
// app, on a 134-byte file with "DICM" at byte 128 (found by tests/fuzz/fuzz_image); no other
// codec is handed the bytes. Each allowed signature is claimed by its own codec, which OpenCV
// tries before DICOM.
bool IsPhotoFormat(const std::vector<std::uint8_t>& b) {
  return StartsWith(b, "\xFF\xD8\xFF", 3) || StartsWith(b, "\x89PNG\r\n\x1A\n", 8) || StartsWith(b, "II*\0", 4) ||
         StartsWith(b, "MM\0*", 4) || StartsWith(b, "BM", 2) ||
         (StartsWith(b, "RIFF", 4) && StartsWith(b, "WEBP", 4, 8));
}

bool IsJpeg(const std::vector<std::uint8_t>& b) {
  return b.size() >= 3 && b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF;
}

// Walks the marker segments of the primary image and its entropy-coded scans and returns
// true when the end-of-image marker is reached. Segment payloads are skipped by their
// length field, so an EOI inside an embedded EXIF thumbnail does not count.
bool JpegIsComplete(const std::vector<std::uint8_t>& b) {
  size_t i = 2;
  const size_t n = b.size();
  while (i + 1 < n) {
    if (b[i] != 0xFF) return false;
    const std::uint8_t marker = b[i + 1];
    if (marker == 0xFF) {  // fill byte
      ++i;
      continue;
    }
    if (marker == 0xD9) return true;
    if ((marker >= 0xD0 && marker <= 0xD7) || marker == 0x01) {  // no payload
      i += 2;
      continue;
    }
    if (i + 3 >= n) return false;
    const size_t length = (static_cast<size_t>(b[i + 2]) << 8) | b[i + 3];
    if (length < 2) return false;
    i += 2 + length;
    if (i > n) return false;
    if (marker == 0xDA) {
      // Entropy-coded data: 0xFF is followed by 0x00 (stuffing), a restart marker or a
      // fill byte; anything else is the next marker.
      while (i + 1 < n) {
        if (b[i] == 0xFF && b[i + 1] != 0x00 && !(b[i + 1] >= 0xD0 && b[i + 1] <= 0xD7) && b[i + 1] != 0xFF) break;
        ++i;
      }
      if (i + 1 >= n) return false;
    }
  }
  return false;
}

bool MatToRgba(const cv::Mat& decoded, ImageRgba8* out, std::string* what) {
  cv::Mat eight_bit;
  if (decoded.depth() == CV_8U) {
    eight_bit = decoded;
  } else if (decoded.depth() == CV_16U) {
    decoded.convertTo(eight_bit, CV_8U, 1.0 / 257.0);
  } else if (decoded.depth() == CV_32F || decoded.depth() == CV_64F) {
    decoded.convertTo(eight_bit, CV_8U, 255.0);  // saturating: HDR values above 1 clip
  } else {
    *what = "unsupported pixel depth";
    return false;
  }
  cv::Mat rgba;
  switch (eight_bit.channels()) {
    case 1: cv::cvtColor(eight_bit, rgba, cv::COLOR_GRAY2RGBA); break;
    case 3: cv::cvtColor(eight_bit, rgba, cv::COLOR_BGR2RGBA); break;
    case 4: cv::cvtColor(eight_bit, rgba, cv::COLOR_BGRA2RGBA); break;
    default: *what = "unsupported channel count " + std::to_string(eight_bit.channels()); return false;
  }
  out->width = rgba.cols;
  out->height = rgba.rows;
  out->pixels.resize(static_cast<size_t>(rgba.cols) * rgba.rows * 4);
  for (int y = 0; y < rgba.rows; ++y) {
    std::memcpy(&out->pixels[static_cast<size_t>(y) * rgba.cols * 4], rgba.ptr<std::uint8_t>(y),
                static_cast<size_t>(rgba.cols) * 4);
  }
  return true;
}

bool ValidImage(const ImageRgba8& image) {
  return !image.empty() && image.pixels.size() == static_cast<size_t>(image.width) * image.height * 4;
}

}  // namespace

ImageReadResult ReadImage(const std::string& path) {
  ImageReadResult result;
  std::vector<std::uint8_t> bytes;
  if (!ReadRegularFile(path, kMaxImageFileBytes, &bytes, &result.error)) return result;
  return DecodeImage(bytes, path);
}

ImageReadResult DecodeImage(const std::vector<std::uint8_t>& bytes, const std::string& path, std::uint64_t max_pixels) {
  ImageReadResult result;
  if (bytes.empty()) {
    result.error = path + ": file is empty";
    return result;
  }
  if (bytes.size() > kMaxImageFileBytes) {  // ReadImage's file limit, for bytes from elsewhere
    result.error = path + ": " + std::to_string(bytes.size() >> 20) + " MB, larger than the limit of " +
                   std::to_string(kMaxImageFileBytes >> 20) + " MB for a photo";
    return result;
  }
  // The header's size, before a decoder allocates it (a 20000 x 20000 photo is 1.6 GB RGBA).
  int header_w = 0, header_h = 0;
  if (HeaderSize(bytes, &header_w, &header_h)) {
    const std::string refusal = PixelLimitRefusal(path, header_w, header_h, max_pixels);
    if (!refusal.empty()) {
      result.error = refusal;
      return result;
    }
  }
  if (!IsPhotoFormat(bytes)) {
    result.error = path + ": not a JPEG, PNG, TIFF, BMP or WebP file";
    return result;
  }
  // Every other format's size was read above when its header had one; TIFF and WebP are
  // decoded only once their declared size has passed the limit (OpenCV allocates it first).
  if (header_w == 0 && (StartsWith(bytes, "II*\0", 4) || StartsWith(bytes, "MM\0*", 4) || StartsWith(bytes, "RIFF", 4))) {
    result.error = path + ": corrupt " + std::string(StartsWith(bytes, "RIFF", 4) ? "WebP" : "TIFF") +
                   " header (no image size in it)";
    return result;
  }
  if (IsJpeg(bytes) && !JpegIsComplete(bytes)) {
    result.error = path + ": JPEG is truncated or corrupt (no end-of-image marker)";
    return result;
  }
  cv::Mat decoded;
  try {
    // UNCHANGED keeps alpha and ignores the EXIF orientation, so pixel coordinates match
    // the stored raster, ReadImageSize and the ground truth of research datasets.
    decoded = cv::imdecode(cv::Mat(1, static_cast<int>(bytes.size()), CV_8UC1, const_cast<std::uint8_t*>(bytes.data())),
                           cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    result.error = path + ": cannot decode (" + e.what() + ")";
    return result;
  }
  if (decoded.empty()) {
    result.error = path + ": not a readable image or corrupt";
    return result;
  }
  std::string what;
  if (!MatToRgba(decoded, &result.image, &what)) {
    result.image = ImageRgba8();
    result.error = path + ": " + what;
    return result;
  }
  if (result.image.empty()) result.error = path + ": image has zero size";
  if (result.error.empty()) {
    const std::string refusal = PixelLimitRefusal(path, result.image.width, result.image.height, max_pixels);
    if (!refusal.empty()) {
      result.image = ImageRgba8();
      result.error = refusal;
    }
  }
  return result;
}

bool ReadImageSize(const std::string& path, int* width, int* height, std::string* error) {
  std::string local_error;
  std::string* err = error != nullptr ? error : &local_error;
  // A JPEG's or PNG's size is in its first bytes (after EXIF, itself at most 64 KB).
  constexpr std::uint64_t kHeaderBytes = 256u << 10;
  std::vector<std::uint8_t> bytes;
  if (!ReadRegularFileHead(path, kHeaderBytes, &bytes, err)) return false;
  int w = 0, h = 0;
  if (bytes.empty() || !HeaderSize(bytes, &w, &h)) {
    // A format stb does not parse (TIFF, WebP, ...): decode it fully.
    ImageReadResult full = ReadImage(path);
    if (!full.ok()) {
      *err = full.error;
      return false;
    }
    w = full.image.width;
    h = full.image.height;
  }
  if (w <= 0 || h <= 0) {
    *err = path + ": image has zero size";
    return false;
  }
  *width = w;
  *height = h;
  return true;
}

std::vector<std::uint8_t> EncodePng(const ImageRgba8& image) {
  if (!ValidImage(image)) return {};
  try {
    const cv::Mat rgba(image.height, image.width, CV_8UC4, const_cast<std::uint8_t*>(image.pixels.data()));
    cv::Mat bgra;
    cv::cvtColor(rgba, bgra, cv::COLOR_RGBA2BGRA);
    std::vector<std::uint8_t> png;
    if (!cv::imencode(".png", bgra, png, {cv::IMWRITE_PNG_COMPRESSION, 3})) return {};
    return png;
  } catch (const cv::Exception&) {
    return {};
  }
}

std::string WritePng(const std::string& path, const ImageRgba8& image) {
  if (!ValidImage(image)) return path + ": cannot write an empty or malformed image";
  const std::vector<std::uint8_t> png = EncodePng(image);
  if (png.empty()) return path + ": PNG encoding failed";
  return WriteFileAtomically(path, std::string(png.begin(), png.end()));
}

}  // namespace facet
