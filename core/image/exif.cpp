#include "core/image/exif.h"

#include "core/util/file_read.h"
#include "core/util/format.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <memory>
#include <vector>

#include <libexif/exif-data.h>

namespace facet {
namespace {

// The diagonal of a full-frame 35 mm sensor (36 x 24 mm), in mm.
const double kFullFrameDiagonalMm = std::hypot(36.0, 24.0);

ExifFocal NotFound(std::string message) {
  ExifFocal result;
  result.message = std::move(message);
  return result;
}

// The first component of a numeric entry as a double; 0 when absent or of another type.
double EntryValue(ExifData* data, ExifTag tag) {
  ExifEntry* entry = exif_data_get_entry(data, tag);
  if (!entry || !entry->data || entry->components < 1) return 0.0;
  const ExifByteOrder order = exif_data_get_byte_order(data);
  switch (entry->format) {
    case EXIF_FORMAT_SHORT: return entry->size >= 2 ? exif_get_short(entry->data, order) : 0.0;
    case EXIF_FORMAT_LONG: return entry->size >= 4 ? exif_get_long(entry->data, order) : 0.0;
    case EXIF_FORMAT_RATIONAL: {
      if (entry->size < 8) return 0.0;
      const ExifRational r = exif_get_rational(entry->data, order);
      return r.denominator ? static_cast<double>(r.numerator) / r.denominator : 0.0;
    }
    default: return 0.0;
  }
}

}  // namespace

ExifFocal ReadExifFocalFromBuffer(const unsigned char* bytes, std::size_t size, int width_px, int height_px) {
  if (width_px <= 0 || height_px <= 0)
    return NotFound("the image size must be positive, got " + std::to_string(width_px) + " x " +
                    std::to_string(height_px));
  if (!bytes || size == 0) return NotFound("no data");
  std::unique_ptr<ExifData, void (*)(ExifData*)> data(
      exif_data_new_from_data(bytes, static_cast<unsigned int>(std::min<std::size_t>(size, 0xffffffffu))),
      exif_data_unref);
  if (!data) return NotFound("no EXIF block (or it could not be parsed)");

  ExifFocal result;
  result.focal_35mm_equivalent_mm = EntryValue(data.get(), EXIF_TAG_FOCAL_LENGTH_IN_35MM_FILM);
  result.focal_length_mm = EntryValue(data.get(), EXIF_TAG_FOCAL_LENGTH);
  const double plane_resolution = EntryValue(data.get(), EXIF_TAG_FOCAL_PLANE_X_RESOLUTION);
  const double unit = EntryValue(data.get(), EXIF_TAG_FOCAL_PLANE_RESOLUTION_UNIT);
  // Units of FocalPlaneResolutionUnit: 2 inch (the default), 3 cm; 4 mm and 5 um occur in
  // the wild although the standard stops at 3.
  const double unit_mm = unit == 3 ? 10.0 : unit == 4 ? 1.0 : unit == 5 ? 1e-3 : 25.4;
  if (plane_resolution > 0.0) result.focal_plane_pixels_per_mm = plane_resolution / unit_mm;
  const double image_side_px = std::max(width_px, height_px);

  if (result.focal_35mm_equivalent_mm > 0.0) {
    result.focal_px =
        result.focal_35mm_equivalent_mm / kFullFrameDiagonalMm * std::hypot(double(width_px), double(height_px));
    result.found = true;
    result.message = "FocalLengthIn35mmFilm " + internal::FormatNumber(result.focal_35mm_equivalent_mm, 6) +
                     " mm: f = " + internal::FormatNumber(result.focal_px, 6) + " px for " + std::to_string(width_px) +
                     " x " + std::to_string(height_px);
    return result;
  }
  if (result.focal_length_mm > 0.0 && result.focal_plane_pixels_per_mm > 0.0) {
    const double sensor_w = EntryValue(data.get(), EXIF_TAG_PIXEL_X_DIMENSION);
    const double sensor_h = EntryValue(data.get(), EXIF_TAG_PIXEL_Y_DIMENSION);
    const double sensor_side_px = sensor_w > 0.0 && sensor_h > 0.0 ? std::max(sensor_w, sensor_h) : image_side_px;
    result.focal_px = result.focal_length_mm * result.focal_plane_pixels_per_mm * image_side_px / sensor_side_px;
    result.found = true;
    result.message = "FocalLength " + internal::FormatNumber(result.focal_length_mm, 6) + " mm at " +
                     internal::FormatNumber(result.focal_plane_pixels_per_mm, 6) +
                     " sensor px/mm: f = " + internal::FormatNumber(result.focal_px, 6) + " px";
    return result;
  }
  result.message = result.focal_length_mm > 0.0
                       ? "EXIF gives FocalLength (" + internal::FormatNumber(result.focal_length_mm, 6) +
                             " mm) but neither FocalLengthIn35mmFilm nor the sensor resolution"
                       : "EXIF has no focal length";
  return result;
}

ExifFocal ReadExifFocalFromFile(const std::string& path, int width_px, int height_px) {
  std::vector<std::uint8_t> bytes;
  std::string error;
  if (!ReadRegularFile(path, kMaxImageFileBytes, &bytes, &error)) return NotFound(error);
  ExifFocal result = ReadExifFocalFromBuffer(bytes.data(), bytes.size(), width_px, height_px);
  if (!result.found) result.message = path + ": " + result.message;
  return result;
}

}  // namespace facet
