// Lines found for the user (core/estimators/line_detection.h) on the York Urban DB train split:
// from the photos alone (the labelled segments are not read), detect, group into three
// vanishing directions and calibrate; the focal length against the ground-truth K.
// Data: FACET_SHARED_DATA/yorkurbandb-train (README.md and PROVENANCE.md there). The
// labelled-segment figures of the same photos are in test_yorkurban.cpp.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "app/state/calgui_exif_prior.h"
#include "core/estimators/line_detection.h"
#include "core/image/exif.h"
#include "core/image/image_io.h"

namespace facet {
namespace {

namespace fs = std::filesystem;

const fs::path kDataDir = fs::path(FACET_SHARED_DATA) / "yorkurbandb-train";

// The targets (issue 12, "Lines found for the user"), asserted for the default the
// app and `facet calibrate --image` use: the photo's EXIF focal length as a prior
// (app/state/calgui_exif_prior.h). Reached: median 1.72 %, p90 4.33 %, max 10.05 %, every
// photo calibrated (the search's default seed; seeds 2-4 gave 1.80-1.99 % / 4.33-4.62 % /
// 0-1 photos without a camera).
constexpr double kMaxMedianFocalErrorPercent = 3.0;
constexpr double kMaxP90FocalErrorPercent = 10.0;
constexpr int kMaxPhotosWithoutCamera = 2;
// From the lines alone the median target is met (2.24 %) but the p90 is not (18.3 %, two
// photos without a camera; before the camera checks of core/geometry/camera_checks.h one of
// them, P1040818, printed f = 5363 +- 3172 px against a true 674 px as an answer, and the p90
// was 22 %): a quarter of these photos are one-point perspectives of corridors and
// facades, where the vanishing point of the receding lines lies near the principal point and
// the other two near infinity, and the lines leave f loose (calibrate_vp's focal_std_px is
// 50 to 120 px on them, 100 px on the 25 % misses; drawn on the photos, their families
// are right).
// The bounds are the figures reached with a small margin, to catch regressions.
constexpr double kMaxMedianFocalErrorPercentLinesAlone = 2.5;
constexpr double kMaxP90FocalErrorPercentLinesAlone = 19.0;
constexpr int kMaxPhotosWithoutCameraLinesAlone = 2;

double TrueFocalPx() {
  std::ifstream in(kDataDir / "K.txt");
  REQUIRE_MESSAGE(in.good(), "cannot open " << (kDataDir / "K.txt"));
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    double f = 0.0;
    fields >> f;
    return f;
  }
  FAIL("no K in K.txt");
  return 0.0;
}

double Percentile(std::vector<double> values, double p) {
  std::sort(values.begin(), values.end());
  const double position = p * (values.size() - 1);
  const size_t lo = static_cast<size_t>(std::floor(position));
  const size_t hi = std::min(lo + 1, values.size() - 1);
  return values[lo] + (position - lo) * (values[hi] - values[lo]);
}

struct Figures {
  std::vector<double> focal_errors_percent;
  std::vector<double> times_ms;
  std::vector<std::string> failures;
};

TEST_CASE("York Urban train split: focal length from detected lines, without and with the EXIF prior") {
  REQUIRE_MESSAGE(fs::is_directory(kDataDir), kDataDir << " is missing");
  const double true_focal_px = TrueFocalPx();
  std::vector<fs::path> folders;
  for (const auto& entry : fs::directory_iterator(kDataDir))
    if (entry.is_directory()) folders.push_back(entry.path());
  std::sort(folders.begin(), folders.end());
  REQUIRE(folders.size() == 51);

  Figures lines_only, with_exif;
  for (const fs::path& folder : folders) {
    const std::string id = folder.filename().string();
    const std::string photo = (folder / (id + ".jpg")).string();
    const ImageReadResult read = ReadImage(photo);
    REQUIRE_MESSAGE(read.ok(), read.error);
    const ExifFocal exif = ReadExifFocalFromFile(photo, read.image.width, read.image.height);
    REQUIRE_MESSAGE(exif.found, id << ": " << exif.message);
    std::printf("%s", id.c_str());
    for (Figures* figures : {&lines_only, &with_exif}) {
      ManhattanLinesOptions options;
      if (figures == &with_exif) {
        options.calibration.focal_prior_px = exif.focal_px;
        options.calibration.focal_prior_std_px = app::ExifFocalPriorStdPx(exif);
      }
      const ManhattanLinesSummary s = DetectManhattanLines(read.image, options);
      if (!s.IsUsable()) {
        figures->failures.push_back(id + ": " + s.message);
        std::printf("  failed: %s", s.message.c_str());
        continue;
      }
      const double error = 100.0 * std::abs(s.calibration.focal_px - true_focal_px) / true_focal_px;
      figures->focal_errors_percent.push_back(error);
      figures->times_ms.push_back(s.time_ms);
      std::printf("  f %7.1f (%5.2f %%) x %3d y %3d z %3d out %3d, %5.1f ms", s.calibration.focal_px, error,
                  s.segments_per_family[0], s.segments_per_family[1], s.segments_per_family[2], s.num_outliers,
                  s.time_ms);
    }
    std::printf("\n");
  }
  for (const Figures* figures : {&lines_only, &with_exif}) {
    const char* name = figures == &lines_only ? "detected lines alone" : "detected lines + EXIF prior";
    REQUIRE(!figures->focal_errors_percent.empty());
    const double median = Percentile(figures->focal_errors_percent, 0.5);
    const double p90 = Percentile(figures->focal_errors_percent, 0.9);
    std::printf(
        "%s: focal error median %.2f %%, p90 %.2f %%, max %.2f %%, %d photos without a camera, "
        "median time %.1f ms\n",
        name, median, p90, Percentile(figures->focal_errors_percent, 1.0), static_cast<int>(figures->failures.size()),
        Percentile(figures->times_ms, 0.5));
    for (const std::string& f : figures->failures) std::printf("  %s\n", f.c_str());
    if (figures == &with_exif) {
      CHECK(median <= kMaxMedianFocalErrorPercent);
      CHECK(p90 <= kMaxP90FocalErrorPercent);
      CHECK(static_cast<int>(figures->failures.size()) <= kMaxPhotosWithoutCamera);
    } else {
      CHECK(median <= kMaxMedianFocalErrorPercentLinesAlone);
      CHECK(p90 <= kMaxP90FocalErrorPercentLinesAlone);
      CHECK(static_cast<int>(figures->failures.size()) <= kMaxPhotosWithoutCameraLinesAlone);
    }
  }
}

}  // namespace
}  // namespace facet
