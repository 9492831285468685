// The focal prior from EXIF (app/state/calgui_exif_prior.h): its std combines the 35 mm
// convention's spread with the rounding of the 35 mm figure to whole mm; a true focal length
// with the sensor's pixel pitch gets the narrower lens tolerance; no EXIF gives no prior.
#include <doctest/doctest.h>

#include <cmath>

#include "app/state/calgui_exif_prior.h"

namespace facet::app {
namespace {

constexpr double kRelative = 1e-12;  // a few products and a square root

ExifFocal Equivalent(double focal_35mm, int larger_side_px) {
  ExifFocal exif;
  exif.found = true;
  exif.focal_35mm_equivalent_mm = focal_35mm;
  exif.focal_px = focal_35mm / 36.0 * larger_side_px;
  return exif;
}

TEST_CASE("a phone's 26 mm equivalent: 3 % convention and 1/sqrt(12) mm rounding in quadrature") {
  const ExifFocal exif = Equivalent(26.0, 4212);  // 3042 px
  const double expected_rel = std::sqrt(0.03 * 0.03 + (1.0 / 12.0) / (26.0 * 26.0));
  const double std_px = ExifFocalPriorStdPx(exif);
  CAPTURE(std_px);
  CHECK(std::abs(std_px - expected_rel * exif.focal_px) <= kRelative * exif.focal_px);
  // 3.2 %: between the convention's 3 % and the 4 % that diagonal vs larger side can differ.
  CHECK(std_px > 0.03 * exif.focal_px);
  CHECK(std_px < 0.04 * exif.focal_px);
  // Rounding matters less at a longer focal length.
  const ExifFocal tele = Equivalent(77.0, 4212);
  CHECK(ExifFocalPriorStdPx(tele) / tele.focal_px < std_px / exif.focal_px);

  const ExifFocalPrior prior = ExifFocalPriorFrom(exif);
  REQUIRE(prior.found);
  CHECK(prior.focal_px == exif.focal_px);
  CHECK(prior.std_px == std_px);
  CHECK(prior.message == "focal prior 3042 px +- 97 from EXIF (26 mm equivalent)");

  Image image;
  ApplyExifFocalPrior(prior, &image);
  CHECK(image.focal_mode == FocalMode::kPrior);
  CHECK(image.focal_prior_px == prior.focal_px);
  CHECK(image.focal_prior_std_px == prior.std_px);
}

TEST_CASE("a true focal length with the pixel pitch: 2 %") {
  ExifFocal exif;
  exif.found = true;
  exif.focal_length_mm = 4.2;
  exif.focal_plane_pixels_per_mm = 1000.0;
  exif.focal_px = 4200.0;
  CHECK(std::abs(ExifFocalPriorStdPx(exif) - 0.02 * 4200.0) <= kRelative * 4200.0);
  CHECK(ExifFocalPriorFrom(exif).message == "focal prior 4200 px +- 84 from EXIF (4.2 mm lens)");
}

TEST_CASE("no EXIF focal: no prior, the reader's reason, the image unchanged") {
  ExifFocal exif;
  exif.message = "no EXIF block";
  CHECK(ExifFocalPriorStdPx(exif) == 0.0);
  const ExifFocalPrior prior = ExifFocalPriorFrom(exif);
  CHECK_FALSE(prior.found);
  CHECK(prior.message == "No EXIF focal length: no EXIF block");
  Image image;
  ApplyExifFocalPrior(prior, &image);
  CHECK(image.focal_mode == FocalMode::kSolve);
  CHECK(ReadExifFocalPrior("/nonexistent/photo.jpg", image).found == false);
}

}  // namespace
}  // namespace facet::app
