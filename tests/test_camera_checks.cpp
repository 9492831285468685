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

// The radial distortion must map the photo one to one: the distorted radius
// r (1 + k1 r^2 + k2 r^4) may peak only beyond the farthest corner. The joint solve gave
// k1 = 0.315, k2 = -3.04 for a pinhole photo (8 pins, distortion unlocked): its peak, 0.45 of
// f, lies inside the corner at 0.73 of f, so the corners are images of no ray.
TEST_CASE("a distortion that folds the photo back is no camera") {
  const Eigen::Vector2d pp(520.25, 370.75);
  constexpr double kFocal = 892.2;
  const std::string folded = facet::WhyDistortionFolds(0.315, -3.04, kFocal, pp, 1024, 768);
  INFO(folded);
  CHECK(folded.find("folds the photo") != std::string::npos);
  CHECK(folded.find("0.45") != std::string::npos);
  // Real lenses: a barrel of 5 % at the corner (k1 = -0.1), a pincushion, a mustache; none.
  CHECK(facet::WhyDistortionFolds(-0.1, 0.0, kFocal, pp, 1024, 768).empty());
  CHECK(facet::WhyDistortionFolds(0.2, 0.05, kFocal, pp, 1024, 768).empty());
  CHECK(facet::WhyDistortionFolds(-0.25, 0.1, kFocal, pp, 1024, 768).empty());
  CHECK(facet::WhyDistortionFolds(0.0, 0.0, kFocal, pp, 1024, 768).empty());
  // k1 < 0 alone peaks at r^2 = -1 / (3 k1): r_d = (2/3) r there. With k1 = -1 that is 0.385,
  // inside the corner; the same lens on a photo cropped to its centre (corner 0.3) is fine.
  CHECK_FALSE(facet::WhyDistortionFolds(-1.0, 0.0, kFocal, pp, 1024, 768).empty());
  const double half = 0.3 * kFocal / std::sqrt(2.0);
  CHECK(facet::WhyDistortionFolds(-1.0, 0.0, kFocal, Eigen::Vector2d(half, half), static_cast<int>(2 * half),
                           static_cast<int>(2 * half))
            .empty());
  CHECK_FALSE(facet::WhyDistortionFolds(std::numeric_limits<double>::quiet_NaN(), 0.0, kFocal, pp, 1024, 768).empty());
}
