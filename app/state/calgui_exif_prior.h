// The focal-length prior a photo's EXIF gives (core/image/exif.h): its value, a standard deviation
// that states how far EXIF focal lengths are off in practice, and the log line. No ImGui, so
// the unit tests include it directly; the app sets it on import, from the image panel's
// "From EXIF" button and from the script command `calibration focal exif`.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "core/image/exif.h"
#include "core/scene/project.h"

namespace facet::app {

// Relative std of the 35 mm-equivalent convention: cameras map the 36 x 24 mm frame to the
// sensor by its diagonal, its width or its larger side; for a 4:3 sensor, diagonal versus
// larger side differs by 4 % (36 / (0.8 * 43.27) = 1.04), and focus breathing adds ~1 %. A
// 3 % std keeps either convention within about 1.3 sigma. core/image/exif.h takes the diagonal;
// on the two real cameras we have it gives 3.4 % (iPhone 6) and 4.1 % (York Urban's) below
// the calibrated focal length, 1.1 and 1.3 sigma.
constexpr double kExifEquivalentConventionRelStd = 0.03;
// Relative std of a true focal length with the sensor's pixel pitch (FocalLength and
// FocalPlaneXResolution): the lens' nominal value (rounded to 0.1 mm, zoom steps) and focus
// breathing, ~2 %.
constexpr double kExifTrueFocalRelStd = 0.02;

// The prior's std in px. The 35 mm figure is also rounded to whole mm: uniform rounding
// error of width 1 mm has std 1 / sqrt(12) mm, added in quadrature (1.1 % at 26 mm, so
// 3.2 % in all there). 0 when the EXIF gave no focal length.
inline double ExifFocalPriorStdPx(const ExifFocal& exif) {
  if (!exif.found || !(exif.focal_px > 0.0)) return 0.0;
  double rel = kExifTrueFocalRelStd;
  if (exif.focal_35mm_equivalent_mm > 0.0) {
    const double rounding = (1.0 / std::sqrt(12.0)) / exif.focal_35mm_equivalent_mm;
    rel = std::hypot(kExifEquivalentConventionRelStd, rounding);
  }
  return rel * exif.focal_px;
}

struct ExifFocalPrior {
  bool found = false;
  double focal_px = 0.0;
  double std_px = 0.0;
  // "focal prior 3042 px +- 97 from EXIF (26 mm equivalent)", or why there is none.
  std::string message;
};

inline ExifFocalPrior ExifFocalPriorFrom(const ExifFocal& exif) {
  ExifFocalPrior prior;
  if (!exif.found || !(exif.focal_px > 0.0)) {
    prior.message = "No EXIF focal length: " + exif.message;
    return prior;
  }
  prior.found = true;
  prior.focal_px = exif.focal_px;
  prior.std_px = ExifFocalPriorStdPx(exif);
  char text[160];
  if (exif.focal_35mm_equivalent_mm > 0.0) {
    std::snprintf(text, sizeof(text), "focal prior %.0f px +- %.0f from EXIF (%.0f mm equivalent)", prior.focal_px,
                  prior.std_px, exif.focal_35mm_equivalent_mm);
  } else {
    std::snprintf(text, sizeof(text), "focal prior %.0f px +- %.0f from EXIF (%.1f mm lens)", prior.focal_px,
                  prior.std_px, exif.focal_length_mm);
  }
  prior.message = text;
  return prior;
}

// `photo_path` resolved (not relative to the project); the image's size must be set.
inline ExifFocalPrior ReadExifFocalPrior(const std::string& photo_path, const Image& image) {
  if (image.width_px <= 0 || image.height_px <= 0) {
    ExifFocalPrior prior;
    prior.message = "No EXIF focal length: the image has no size yet";
    return prior;
  }
  return ExifFocalPriorFrom(ReadExifFocalFromFile(photo_path, image.width_px, image.height_px));
}

// Makes the prior the image's focal mode (a found prior only).
inline void ApplyExifFocalPrior(const ExifFocalPrior& prior, Image* image) {
  if (!prior.found) return;
  image->focal_mode = FocalMode::kPrior;
  image->focal_prior_px = prior.focal_px;
  image->focal_prior_std_px = prior.std_px;
}

}  // namespace facet::app
