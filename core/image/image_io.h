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

// Reads a JPEG or PNG (any format OpenCV's imgcodecs reads). A missing, unreadable or
// corrupt file gives an error, never a crash.
ImageReadResult ReadImage(const std::string& path);
// Reads only the size of an image (fast). Returns false with *error set on failure.
bool ReadImageSize(const std::string& path, int* width, int* height, std::string* error);
// Encodes as PNG in memory.
std::vector<std::uint8_t> EncodePng(const ImageRgba8& image);
// Writes a PNG; returns an empty string on success, else the error.
std::string WritePng(const std::string& path, const ImageRgba8& image);

}  // namespace facet
