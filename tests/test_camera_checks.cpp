// What Facet accepts as a camera (core/geometry/camera_checks.h): the bounds and their
// messages, one definition for the estimators and the command line.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>

#include "core/geometry/camera_checks.h"

namespace facet {
namespace {

bool Says(const std::string& why, const std::string& words) { return why.find(words) != std::string::npos; }

TEST_CASE("a focal length and principal point make a camera within the stated bounds") {
  const Eigen::Vector2d centre(399.5, 299.5);  // 800 x 600: diagonal 1000 px
  CHECK(WhyNotACamera(700.0, centre, 800, 600).empty());
  CHECK(WhyNotACamera(1000.0 * kMinFocalPerDiagonal * 1.001, centre, 800, 600).empty());
  CHECK(WhyNotACamera(1000.0 * kMaxFocalPerDiagonal * 0.999, centre, 800, 600).empty());
  CHECK(Says(WhyNotACamera(1000.0 * kMinFocalPerDiagonal * 0.999, centre, 800, 600), "outside any lens"));
  CHECK(Says(WhyNotACamera(5e237, centre, 800, 600), "outside any lens"));
  CHECK(Says(WhyNotACamera(-700.0, centre, 800, 600), "not a positive number"));
  CHECK(Says(WhyNotACamera(std::numeric_limits<double>::quiet_NaN(), centre, 800, 600), "not a positive number"));
  CHECK(Says(WhyNotACamera(std::numeric_limits<double>::infinity(), centre, 800, 600), "not a positive number"));
  // A crop moves the principal point off the image; 10 diagonals away is no photo.
  CHECK(WhyNotACamera(700.0, centre + Eigen::Vector2d(9990.0, 0.0), 800, 600).empty());
  CHECK(Says(WhyNotACamera(700.0, centre + Eigen::Vector2d(10010.0, 0.0), 800, 600), "from the centre"));
  CHECK(Says(WhyNotACamera(700.0, Eigen::Vector2d(1e12, -1e12), 800, 600), "from the centre"));
  CHECK(Says(WhyNotACamera(700.0, Eigen::Vector2d(NAN, 0.0), 800, 600), "not finite"));
  CHECK(Says(WhyNotACamera(700.0, centre, 0, 600), "no size"));
}

TEST_CASE("an estimated focal length with a standard deviation over half of it is undetermined") {
  CHECK(WhyFocalIsUndetermined(700.0, 0.0).empty());   // fixed: not estimated
  CHECK(WhyFocalIsUndetermined(700.0, NAN).empty());   // too few segments for a deviation
  CHECK(WhyFocalIsUndetermined(700.0, 349.0).empty());
  CHECK(Says(WhyFocalIsUndetermined(700.0, 351.0), "not determined"));
  CHECK(Says(WhyFocalIsUndetermined(65903.8, 1.5541e7), "65903.8 +- 1.5541e+07"));
}

TEST_CASE("a user's K must be a calibration matrix") {
  Eigen::Matrix3d k;
  k << 700, 0, 400, 0, 700, 300, 0, 0, 1;
  CHECK(WhyNotACalibrationMatrix(k).empty());
  Eigen::Matrix3d bad = k;
  bad(0, 0) = -700;
  CHECK(Says(WhyNotACalibrationMatrix(bad), "focal lengths must be positive"));
  bad = k;
  bad(2, 1) = 1e-3;
  CHECK(Says(WhyNotACalibrationMatrix(bad), "upper triangular"));
  bad = k;
  bad(2, 2) = 0;
  CHECK(Says(WhyNotACalibrationMatrix(bad), "K(2,2)"));
  bad = k;
  bad(0, 2) = std::numeric_limits<double>::infinity();
  CHECK(Says(WhyNotACalibrationMatrix(bad), "non-finite"));
}

}  // namespace
}  // namespace facet
