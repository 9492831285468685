// Reading and writing photos and textures as 8-bit RGBA, behind Facet's own image type.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace facet {

// Row-major, top row first, 4 bytes per pixel (R, G, B, A).
struct ImageRgba8 {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> pixels;

  bool empty() const { return width <= 0 || height <= 0; }
  std::uint8_t* At(int x, int y) { return &pixels[(static_cast<size_t>(y) * width + x) * 4]; }
  const std::uint8_t* At(int x, int y) const { return &pixels[(static_cast<size_t>(y) * width + x) * 4]; }
};

struct ImageReadResult {
  ImageRgba8 image;
  std::string error;  // empty on success; otherwise names the file and what is wrong
  bool ok() const { return error.empty(); }
};

// The largest photo read, in pixels: 150 MP, above any camera of 2026 (a 100 MP medium
// format one included). Decoded as RGBA it is 600 MB; past it a photo is refused, with the
// limit in the message, before it is decoded.
constexpr std::uint64_t kMaxImagePixels = 150'000'000;

// Reads a JPEG, PNG, TIFF, BMP or WebP photo (told by its signature, whatever its name;
// other formats are refused, see IsPhotoFormat in image_io.cpp). A missing, unreadable or
// corrupt file gives an error, never a crash; so do a path that is not a regular file (a
// FIFO, a device), a file over kMaxImageFileBytes (core/util/file_read.h) and a photo over
// kMaxImagePixels.
ImageReadResult ReadImage(const std::string& path);
// The same decoding and checks for a file's bytes held in memory; `name` (a path, or what the
// bytes are) starts every error. max_pixels lowers the refusal limit (the fuzz targets use a
// few MP so that one input cannot take seconds).
ImageReadResult DecodeImage(const std::vector<std::uint8_t>& bytes, const std::string& name,
                            std::uint64_t max_pixels = kMaxImagePixels);
// Reads only the size of an image (fast). Returns false with *error set on failure.
bool ReadImageSize(const std::string& path, int* width, int* height, std::string* error);
// Encodes as PNG in memory.
std::vector<std::uint8_t> EncodePng(const ImageRgba8& image);
// Writes a PNG; returns an empty string on success, else the error.
std::string WritePng(const std::string& path, const ImageRgba8& image);

}  // namespace facet
