// Snapping in the image panel, driven through `facet render` scripts: a segment drawn with a
// line tool starts and ends on the photo's corners (found by core/image/corner_detection.h)
// when the pointer is within a few screen pixels of them, Alt turns snapping off, and the
// target is drawn before the click.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>

#include "core/image/corner_detection.h"
#include "core/image/image_io.h"
#include "tests/app/app_test_util.h"

namespace facet {
namespace {

using testing::FormatXY;
using testing::LoadProjectFile;
using testing::RenderScript;
using testing::TempDir;
using testing::View;
using testing::ViewFromReport;

struct SnapScene {
  std::string project_path;
  std::string photo_path;
  std::vector<Eigen::Vector2d> corners;  // what the app's detector finds on the photo
  View view;
};

// A project with one uncalibrated photo: a checkerboard whose squares are 40 px, shifted by a
// fraction of a pixel so that corners are not on pixel centres.
SnapScene WriteScene(const TempDir& dir) {
  SnapScene s;
  cv::Mat photo(300, 400, CV_8UC3, cv::Scalar(220, 220, 220));
  constexpr double kSquare = 40.0;
  const Eigen::Vector2d origin(60.4, 50.6);
  cv::Mat big(300 * 8, 400 * 8, CV_8UC3, cv::Scalar(220, 220, 220));
  for (int y = 0; y < big.rows; ++y) {
    for (int x = 0; x < big.cols; ++x) {
      const double u = ((x + 0.5) / 8.0 - 0.5 - origin.x()) / kSquare, v = ((y + 0.5) / 8.0 - 0.5 - origin.y()) / kSquare;
      if (u >= 0 && v >= 0 && u < 7 && v < 5 && ((static_cast<int>(u) + static_cast<int>(v)) & 1)) {
        big.at<cv::Vec3b>(y, x) = cv::Vec3b(30, 30, 30);
      }
    }
  }
  cv::resize(big, photo, photo.size(), 0, 0, cv::INTER_AREA);
  s.photo_path = dir / "board.png";
  REQUIRE(cv::imwrite(s.photo_path, photo));

  Project project;
  Image image;
  image.id = project.NewId();
  image.path = "board.png";
  image.width_px = photo.cols;
  image.height_px = photo.rows;
  project.images.push_back(image);
  s.project_path = dir / "board.facet";
  REQUIRE(SaveProject(project, s.project_path) == "");

  const ImageReadResult read = ReadImage(s.photo_path);
  REQUIRE(read.ok());
  const CornerDetectionResult detected = DetectCorners(read.image);
  REQUIRE(detected.ok());
  s.corners = detected.corners_px;
  s.view = ViewFromReport(RenderScript(dir, s.project_path, "probe", "frames 3\n"));
  REQUIRE(s.view.zoom > 0.5);
  return s;
}

// The detected corner nearest to p.
Eigen::Vector2d NearestCorner(const SnapScene& s, const Eigen::Vector2d& p) {
  Eigen::Vector2d best = p;
  double d = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector2d& c : s.corners) {
    if ((c - p).norm() < d) d = (c - p).norm(), best = c;
  }
  return best;
}

Eigen::Vector2d ToImage(const View& v, const Eigen::Vector2d& screen) {
  return {(screen.x() - v.origin_x) / v.zoom, (screen.y() - v.origin_y) / v.zoom};
}

TEST_CASE("a line drawn near two corners starts and ends on them; with Alt held it does not snap") {
  TempDir dir("snap_line");
  const SnapScene s = WriteScene(dir);
  // Two inner corners of the board, as the detector placed them (within 0.1 px of the truth,
  // tests/test_corner_detection.cpp).
  const Eigen::Vector2d a = NearestCorner(s, {60.4 + 80, 50.6 + 40});
  const Eigen::Vector2d b = NearestCorner(s, {60.4 + 200, 50.6 + 120});
  REQUIRE((a - Eigen::Vector2d(140.4, 90.6)).norm() < 0.1);
  REQUIRE((b - Eigen::Vector2d(260.4, 170.6)).norm() < 0.1);
  // The pointer 3 screen px off each corner: inside the snap radius (8 screen px), and off
  // the board's edges' lines by more than a pixel so no segment is nearer than the corner.
  // Whole screen pixels, as a mouse reports them.
  const Eigen::Vector2d press = (s.view.ToScreen(a) + Eigen::Vector2d(2.2, -2.0)).array().round();
  const Eigen::Vector2d release = (s.view.ToScreen(b) + Eigen::Vector2d(-1.8, 2.4)).array().round();
  const std::string drag = "drag left " + FormatXY(press) + " " + FormatXY(release) + " 12\n";

  RenderScript(dir, s.project_path, "snapped",
               "frames 2\ncommand tool line-x\n" + drag + "frames 2\ncommand save " + (dir / "snapped.facet") + "\n");
  const Project snapped = LoadProjectFile(dir / "snapped.facet");
  REQUIRE(snapped.segments.size() == 1);
  CHECK((snapped.segments[0].a_px - a).norm() < 1e-6);
  CHECK((snapped.segments[0].b_px - b).norm() < 1e-6);

  RenderScript(dir, s.project_path, "free",
               "frames 2\ncommand tool line-x\nhold alt\n" + drag + "release alt\nframes 2\ncommand save " +
                   (dir / "free.facet") + "\n");
  const Project free = LoadProjectFile(dir / "free.facet");
  REQUIRE(free.segments.size() == 1);
  // Where the pointer was.
  CHECK((free.segments[0].a_px - ToImage(s.view, press)).norm() < 1e-3);
  CHECK((free.segments[0].b_px - ToImage(s.view, release)).norm() < 1e-3);
  CHECK((free.segments[0].a_px - a).norm() > 1.0);
}

// Pixels of the snap marker's colour (app/panels/image_snapping.cpp) within r px of p.
int MarkerPixelsNear(const cv::Mat& shot, const Eigen::Vector2d& p, int r) {
  int count = 0;
  for (int y = static_cast<int>(p.y()) - r; y <= static_cast<int>(p.y()) + r; ++y) {
    for (int x = static_cast<int>(p.x()) - r; x <= static_cast<int>(p.x()) + r; ++x) {
      if (x < 0 || y < 0 || x >= shot.cols || y >= shot.rows) continue;
      const cv::Vec3b bgr = shot.at<cv::Vec3b>(y, x);
      count += std::abs(bgr[0] - 230) < 40 && std::abs(bgr[1] - 255) < 40 && std::abs(bgr[2] - 80) < 40;
    }
  }
  return count;
}

TEST_CASE("the snap target is drawn before the click, and not with Alt held") {
  TempDir dir("snap_marker");
  const SnapScene s = WriteScene(dir);
  const Eigen::Vector2d corner = NearestCorner(s, {60.4 + 120, 50.6 + 80});
  const Eigen::Vector2d hover = s.view.ToScreen(corner) + Eigen::Vector2d(3.0, 2.0);
  RenderScript(dir, s.project_path, "marker",
               "frames 2\ncommand tool line-y\nmove " + FormatXY(hover) + "\nframes 2\nscreenshot " +
                   (dir / "marker_shot.png") + "\n");
  RenderScript(dir, s.project_path, "nomarker",
               "frames 2\ncommand tool line-y\nhold alt\nmove " + FormatXY(hover) + "\nframes 2\nscreenshot " +
                   (dir / "nomarker_shot.png") + "\n");
  const cv::Mat with = cv::imread(dir / "marker_shot.png");
  const cv::Mat without = cv::imread(dir / "nomarker_shot.png");
  REQUIRE(!with.empty());
  REQUIRE(!without.empty());
  const int lit = MarkerPixelsNear(with, s.view.ToScreen(corner), 8);
  MESSAGE("marker pixels at the corner: " << lit << " (Alt held: " << MarkerPixelsNear(without, s.view.ToScreen(corner), 8)
                                           << ")");
  CHECK(lit >= 10);
  CHECK(MarkerPixelsNear(without, s.view.ToScreen(corner), 8) == 0);
}

}  // namespace
}  // namespace facet
