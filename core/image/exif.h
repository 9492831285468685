// The photo's focal length in pixels from its EXIF block (read with libexif), to serve as
// the focal-length prior of single-image calibration (core/estimators/calibrate_vp.h).
//
// Sources, in order of preference:
// - FocalLengthIn35mmFilm (mm, the lens' 35 mm-equivalent focal length): the same angle of
//   view across the diagonal as on a 36 x 24 mm frame (the CIPA convention), so
//   f_px = f35 / 43.27 * sqrt(w^2 + h^2). For a 3:2 image that is f35 / 36 * w; for a 4:3
//   one it is 4 % longer than mapping 36 mm to the larger side, and closer to the truth on
//   both real cameras we have (iPhone 6: 629 px against 651.4; the York Urban camera: 647
//   against 674.9; the larger-side mapping gives 605 and 622). A photo cropped to another
//   aspect ratio than the sensor's breaks the convention.
// - FocalLength (mm) with FocalPlaneXResolution and FocalPlaneResolutionUnit (sensor pixels
//   per inch, cm or mm): f_px = f_mm * pixels per mm, scaled from the sensor's image size
//   (PixelXDimension / PixelYDimension when present, else the given size) to the given one.
// Both are approximations (the 35 mm figure is rounded to whole mm and some cameras compute
// it loosely, crops change it): use the result as a prior of a few percent, not as a fixed
// focal length. No EXIF block, no usable tag, a corrupt block or an unreadable file give
// found == false with a message; nothing throws.
#pragma once

#include <cstddef>
#include <string>

namespace facet {

struct ExifFocal {
  bool found = false;
  std::string message;    // where the value came from, or why there is none
  double focal_px = 0.0;  // for the image size given to the reader
  // The tags as read; 0 when absent.
  double focal_35mm_equivalent_mm = 0.0;
  double focal_length_mm = 0.0;
  double focal_plane_pixels_per_mm = 0.0;

  bool IsUsable() const { return found; }
};

// width_px, height_px: the size of the image the focal length is wanted for (the decoded
// photo, possibly downscaled from the camera's); both must be positive.
ExifFocal ReadExifFocalFromFile(const std::string& path, int width_px, int height_px);
// data: a whole JPEG file (or an EXIF block starting with "Exif\0\0"), size bytes.
ExifFocal ReadExifFocalFromBuffer(const unsigned char* data, std::size_t size, int width_px, int height_px);

}  // namespace facet
