// The focal length the bundled Leuven sample gives (core/estimators/calibrate_vp.h, the sample's own
// options: principal point at the image centre, and the focal-length prior from the photo's
// EXIF that File > Add photo sets) against the photo's reference K, which OpenCV ships with
// it (FACET_SHARED_DATA/opencv-leuven/essential_mat_data.txt; how OpenCV obtained it is
// undocumented, see PROVENANCE.md there). Prints what limits the figure: per-family
// residuals, vanishing points and the fit's own focal standard deviation.
//
// Issue 3's target, f within 2 % of the reference from lines drawn on one photo, is met with
// the EXIF prior (the tool's default for a photo that has one): 661.5 px against 651.4 px,
// 1.55 %. Each source alone misses it, in opposite directions: the lines give 689 px +- 22
// (5.8 %), the EXIF's 29 mm equivalent gives 629 px +- 20 (3.4 %). The lines are weak here:
// the x family (the house fronts facing the camera) has its vanishing point ~14000 px away,
// which leaves f to the product of the y vanishing point's offset below the principal point
// (~78 px: 1 px there is 0.6 % of f) and the vertical vanishing point's distance (~6100 px:
// the camera is tilted 6 deg, so 0.1 deg of vertical convergence is 0.8 % of f). The bounds
// below are the figures reached, with a margin, and the reference's consistency with each
// fit's uncertainty.
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "core/estimators/calibrate_vp.h"
#include "core/io/project_io.h"

namespace facet {
namespace {

namespace fs = std::filesystem;

const std::string kSamplePath = std::string(FACET_SOURCE_DIR) + "/assets/samples/leuven/leuven.facet";
const fs::path kReferencePath = fs::path(FACET_SHARED_DATA) / "opencv-leuven" / "essential_mat_data.txt";

// The issue's target: met with the EXIF prior (1.55 %), not by the lines alone (reported as
// a warning).
constexpr double kTargetFocalError = 0.02;
// Reached by the lines alone: 5.8 %.
constexpr double kMaxFocalErrorLinesOnly = 0.065;
// The reference lies within this many of the fit's own standard deviations (1.7 reached).
constexpr double kMaxFocalErrorSigmas = 2.0;
// The fit's own standard deviation relative to f (3.2 % reached): more and longer segments
// than the first version of the sample (3.5 %) and no worse.
constexpr double kMaxRelativeFocalStd = 0.035;

// fx of the reference K: the file holds two image names, then K's three rows.
double ReadReferenceFocalPx() {
  std::ifstream in(kReferencePath);
  REQUIRE_MESSAGE(in.good(), "cannot open " << kReferencePath);
  std::string first_image, second_image;
  double fx = 0.0;
  in >> first_image >> second_image >> fx;
  REQUIRE_MESSAGE(in.good(), "cannot read K from " << kReferencePath);
  return fx;
}

struct SampleCalibration {
  VpCalibrationSummary summary;
  Project project;
};

// `mode` unset: the sample's own (its image's principal_point_mode). use_focal_prior: the
// sample's own focal prior (its photo's EXIF); false: the lines alone.
SampleCalibration CalibrateSample(std::optional<PrincipalPointMode> mode = std::nullopt, bool use_focal_prior = false) {
  const ProjectLoadResult loaded = LoadProject(kSamplePath);
  INFO(loaded.error);
  REQUIRE(loaded.ok());
  REQUIRE(loaded.project.images.size() == 1);
  const Image& image = loaded.project.images[0];
  VpCalibrationOptions options;
  options.width_px = image.width_px;
  options.height_px = image.height_px;
  options.principal_point_mode = mode.value_or(image.principal_point_mode);
  options.fixed_principal_point_px = image.fixed_principal_point_px;
  if (use_focal_prior && image.focal_mode == FocalMode::kPrior) {
    options.focal_prior_px = image.focal_prior_px;
    options.focal_prior_std_px = image.focal_prior_std_px;
  }
  std::vector<Segment> segments;
  for (const Segment& s : loaded.project.segments)
    if (s.image_id == image.id) segments.push_back(s);
  return {CalibrateFromVanishingLines(segments, options), loaded.project};
}

std::string DescribeFamilies(const VpCalibrationSummary& s) {
  std::ostringstream out;
  for (int axis = 0; axis < 3; ++axis) {
    const Eigen::Vector3d& vp = s.vanishing_points[axis];
    out << "\n  " << AxisName(static_cast<Axis>(axis)) << ": " << s.segments_per_axis[axis] << " segments, RMS "
        << s.vanishing_point_rms_px[axis] << " px, spread " << s.family_angle_spread_deg[axis] << " deg, direction std "
        << s.vanishing_direction_std_deg[axis] << " deg, vanishing point ";
    if (std::abs(vp.z()) > 1e-12)
      out << "(" << vp.x() / vp.z() << ", " << vp.y() / vp.z() << "), " << s.vanishing_point_to_principal_point_px[axis]
          << " px from the principal point";
    else
      out << "at infinity";
  }
  out << "\n  outliers:";
  for (int i : s.outlier_segments) out << " #" << i << " (" << s.segment_residuals_px[i] << " px)";
  for (const std::string& w : s.warnings) out << "\n  warning: " << w;
  return out.str();
}

}  // namespace

TEST_CASE("the Leuven sample's lines with its EXIF prior give the reference focal length within 2 %") {
  const double reference_focal_px = ReadReferenceFocalPx();
  const SampleCalibration calibration = CalibrateSample(std::nullopt, /*use_focal_prior=*/true);
  const Image& image = calibration.project.images[0];
  REQUIRE(image.principal_point_mode == PrincipalPointMode::kImageCenter);
  REQUIRE(image.focal_mode == FocalMode::kPrior);
  const VpCalibrationSummary& s = calibration.summary;
  INFO(s.message);
  REQUIRE(s.IsUsable());
  const double focal_error = std::abs(s.focal_px - reference_focal_px) / reference_focal_px;
  const double prior_error = std::abs(image.focal_prior_px - reference_focal_px) / reference_focal_px;
  MESSAGE("Leuven sample with the EXIF prior ("
          << image.focal_prior_px << " px +- " << image.focal_prior_std_px << ", " << 100.0 * prior_error
          << " % off alone): f " << s.focal_px << " px +- " << s.focal_std_px << ", reference " << reference_focal_px
          << " px, error " << 100.0 * focal_error
          << " % = " << std::abs(s.focal_px - reference_focal_px) / s.focal_std_px << " sigma");
  CHECK(focal_error < kTargetFocalError);
  CHECK(std::abs(s.focal_px - reference_focal_px) < kMaxFocalErrorSigmas * s.focal_std_px);
  // The prior and the lines each carry weight: the result lies strictly between them.
  const SampleCalibration lines_only = CalibrateSample();
  REQUIRE(lines_only.summary.IsUsable());
  CHECK(s.focal_px > image.focal_prior_px + 0.25 * image.focal_prior_std_px);
  CHECK(s.focal_px < lines_only.summary.focal_px - 0.25 * lines_only.summary.focal_std_px);
  // What the app computes for the sample is this calibration (its stored camera).
  CHECK(std::abs(image.camera.focal_px - s.focal_px) < 1e-6 * s.focal_px);
}

TEST_CASE("the Leuven sample's lines alone give the reference focal length within their own uncertainty") {
  const double reference_focal_px = ReadReferenceFocalPx();
  const SampleCalibration calibration = CalibrateSample();
  const VpCalibrationSummary& s = calibration.summary;
  INFO(s.message);
  REQUIRE(s.IsUsable());
  const double focal_error = std::abs(s.focal_px - reference_focal_px) / reference_focal_px;
  MESSAGE("Leuven sample, lines alone (" << calibration.project.segments.size()
                                         << " segments, principal point at the centre): f " << s.focal_px << " px +- "
                                         << s.focal_std_px << " (1 sigma), reference " << reference_focal_px
                                         << " px, error " << 100.0 * focal_error
                                         << " % = " << std::abs(s.focal_px - reference_focal_px) / s.focal_std_px
                                         << " sigma; residual sigma " << s.residual_sigma_px << " px"
                                         << DescribeFamilies(s));
  CHECK(focal_error < kMaxFocalErrorLinesOnly);
  CHECK(std::abs(s.focal_px - reference_focal_px) < kMaxFocalErrorSigmas * s.focal_std_px);
  CHECK(s.focal_std_px < kMaxRelativeFocalStd * s.focal_px);
  WARN_MESSAGE(focal_error < kTargetFocalError, "the lines alone do not reach issue 3's 2 % on this photo");
}

TEST_CASE("on the Leuven sample the x family's vanishing point is what leaves the focal length weak") {
  const SampleCalibration calibration = CalibrateSample(PrincipalPointMode::kImageCenter);
  const VpCalibrationSummary& s = calibration.summary;
  REQUIRE(s.IsUsable());
  // Far from the principal point compared with f: the x direction is nearly parallel to the
  // image plane, so its vanishing point says little about f (it would fix f alone with the y
  // or z point if it were within a few f).
  constexpr double kFarVanishingPointInFocalLengths = 10.0;
  INFO(DescribeFamilies(s));
  CHECK(s.vanishing_point_to_principal_point_px[0] > kFarVanishingPointInFocalLengths * s.focal_px);
  // The street's vanishing point sits close to the principal point: its offset is what f
  // rests on together with the vertical point.
  CHECK(s.vanishing_point_to_principal_point_px[1] < 0.25 * s.focal_px);
  // The vertical point is far too (the camera is tilted ~6 deg), so its distance must be
  // measured from a small convergence of the verticals.
  constexpr double kFarVerticalInFocalLengths = 5.0;
  CHECK(s.vanishing_point_to_principal_point_px[2] > kFarVerticalInFocalLengths * s.focal_px);
}

TEST_CASE("on the Leuven sample a solved principal point leaves the focal length far weaker than a centred one") {
  const double reference_focal_px = ReadReferenceFocalPx();
  const SampleCalibration centred = CalibrateSample(PrincipalPointMode::kImageCenter);
  const SampleCalibration solved = CalibrateSample(PrincipalPointMode::kSolve);
  REQUIRE(centred.summary.IsUsable());
  REQUIRE(solved.summary.IsUsable());
  MESSAGE("principal point solved (prior at the centre, default std): f "
          << solved.summary.focal_px << " px +- " << solved.summary.focal_std_px << ", principal point ("
          << solved.summary.principal_point_px.x() << ", " << solved.summary.principal_point_px.y() << ") +- "
          << solved.summary.principal_point_std_px.y() << " px vertically; reference f " << reference_focal_px
          << " px");
  // The near-infinite x point leaves the principal point's row to the prior alone, and f
  // moves with that row (f^2 ~ its distance to the horizon times the vertical point's
  // distance): the sample keeps the principal point at the centre for this reason.
  constexpr double kMinStdRatio = 2.0;
  CHECK(solved.summary.focal_std_px > kMinStdRatio * centred.summary.focal_std_px);
}

}  // namespace facet
