// Issue 12: a real-photo modelling run driven through the app's input scripts, on Strecha's
// fountain-P11 (FACET_SHARED_DATA/strecha-fountain-p11-subset). From an empty project the
// script adds two of the photos (0006, 0004, halved to 1536 x 1024 in the test's temp folder),
// draws line families in each with the Line X / Line Z tools (mouse drags in the image panel),
// adds one box on the fountain's wall (its frieze band) and pins its corners in each photo
// (clicks), and saves. The saved project's cameras are compared with the ground truth: the
// relative rotation, each rotation after the best common rotation, the baseline direction and
// the focal length; the figures are printed with MESSAGE. The runs differ in what the user
// says about the lens: nothing (each photo's focal length from its lines), that both photos
// share one lens (Image::lens_group, focal-lock off), its focal length, or nothing but a box
// with depth on the basin and the focal lengths freed (the last case).
//
// Snapping is off (render --no-snap): every line end and pin below is a pixel read off the
// photo and stated here; snapping would move it onto whatever corner the detector finds near
// it on carved stone, and the test would no longer say what it put in.
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/scene/project.h"
#include "tests/app/app_test_util.h"
#include "tests/realdata/strecha_cameras.h"

using namespace facet::testing;

namespace {

const bool kRenderWithoutSnapping = (RenderWithoutSnapping() = true);

// The photos are halved (runtime: the app loads and tiles 1536 x 1024, not 3072 x 2048).
constexpr double kPhotoScale = 0.5;
constexpr double kRadToDeg = 180.0 / M_PI;
// The issue's bound on every relative rotation between the photos.
constexpr double kMaxRelativeRotationErrorDeg = 1.0;

struct Line {
  char axis;                    // 'x' (along the wall) or 'z' (vertical)
  std::array<double, 4> ab_px;  // x1 y1 x2 y2 in the halved photo
};
struct BoxPin {
  // The box's corner (core/mesh/box.h bit code); on its front face: 0 bottom left, 1 bottom
  // right, 4 top left, 5 top right.
  int vertex;
  Eigen::Vector2d uv_px;
};
struct Photo {
  std::string name;
  std::vector<Line> lines;
  std::vector<BoxPin> pins;
};

// The lines: long straight edges of each halved photo, traced with the line detector's segments
// (core/estimators/line_detection.h, as `facet calibrate --image` lists them) and kept by eye:
// for x the horizontal edges of the fountain's front (the crowning cornice, the ledge over the
// carved band, the basin's front rim and foot, which parallel the wall) and a stone course at
// the wall's foot; for z the longest vertical edges (the fountain's uprights, the wall's
// corners, the window frames of the building on the right; not the drainpipe). None is
// perpendicular to the wall: these photos face it, so edges along its normal are short stubs
// at the ends of mouldings, and the depth family is left out (see the focal length below).
// The pins: corners of the front face of the carved band above the basin, along the wall,
// read by eye on 4x-8x crops of the halved photo where the band's frame meets its top edge and
// the ledge under it: vertex 4 top left, 5 top right, 0 bottom left, 1 bottom right. In 0006
// the basin's rim hides the lower right corner, so it has three pins.
const std::vector<Photo>& Photos() {
  static const std::vector<Photo> photos = {
      {"0006",
       {{'x', {1073.1, 560.0, 621.9, 563.5}},
        {'x', {364.4, 562.0, 619.4, 562.1}},
        {'x', {616.9, 1.7, 946.9, 26.0}},
        {'x', {641.9, 88.8, 910.7, 106.1}},
        {'x', {723.1, 731.4, 1061.9, 724.3}},
        {'x', {740.6, 694.5, 1010.6, 690.6}},
        {'x', {1091.8, 882.6, 646.8, 903.3}},
        {'x', {0.6, 831.6, 184.4, 825.1}},
        {'z', {635.6, 335.6, 635.6, 548.1}},
        {'z', {1497.5, 369.3, 1501.7, 554.4}},
        {'z', {1487.3, 0.6, 1491.3, 181.9}},
        {'z', {837.7, 339.4, 838.2, 483.1}},
        {'z', {649.8, 744.4, 650.2, 869.4}},
        {'z', {1430.6, 446.9, 1432.4, 570.7}},
        {'z', {1083.1, 735.6, 1084.5, 853.1}},
        {'z', {376.8, 436.9, 376.1, 548.1}}},
       {{4, {338.5, 593.0}}, {5, {1175.0, 590.0}}, {0, {339.5, 670.0}}}},
      {"0004",
       {{'x', {1064.4, 574.5, 605.6, 573.9}},
        {'x', {368.1, 720.3, 791.9, 732.3}},
        {'x', {365.7, 865.2, 767.0, 883.7}},
        {'x', {518.1, 67.6, 826.9, 46.9}},
        {'x', {548.1, 142.3, 803.1, 128.6}},
        {'x', {366.9, 687.6, 698.2, 695.6}},
        {'x', {43.2, 783.4, 225.6, 790.0}},
        {'x', {948.0, 818.5, 1108.2, 822.8}},
        {'z', {556.8, 366.9, 555.8, 560.6}},
        {'z', {743.7, 363.1, 743.6, 510.6}},
        {'z', {1413.6, 0.6, 1416.8, 140.6}},
        {'z', {1533.5, 674.4, 1529.5, 551.8}},
        {'z', {787.5, 745.6, 787.5, 856.9}},
        {'z', {55.8, 369.4, 59.6, 265.5}},
        {'z', {63.2, 188.2, 66.6, 90.7}},
        {'z', {380.1, 771.9, 379.4, 838.1}}},
       {{4, {291.0, 599.0}}, {5, {1087.5, 600.0}}, {0, {291.0, 661.0}}, {1, {1087.0, 671.0}}}},
  };
  return photos;
}

// A third photo, 0005, for the run with one lens for three photos: its lines and pins chosen
// as above, after the other two cases' figures were measured, and not changed after its
// figures were seen. Lines from `facet calibrate --image` on the halved photo (the longest
// segment of each edge, kept by eye as above); the four band corners read on 5x crops where
// the band's frame meets the ledges over and under it.
const std::vector<Photo>& ThreePhotos() {
  static const std::vector<Photo> photos = [] {
    std::vector<Photo> three = Photos();
    three.push_back({"0005",
                     {{'x', {569.4, 572.1, 1029.4, 569.7}},
                      {'x', {478.1, 720.2, 938.1, 719.9}},
                      {'x', {931.9, 896.9, 478.1, 899.1}},
                      {'x', {444.4, 700.8, 896.9, 701.5}},
                      {'x', {546.9, 40.4, 874.4, 41.4}},
                      {'x', {576.9, 121.4, 844.4, 122.6}},
                      {'x', {550.6, 601.8, 290.6, 603.1}},
                      {'x', {624.4, 673.6, 954.4, 671.2}},
                      {'z', {577.7, 356.9, 577.9, 561.9}},
                      {'z', {777.7, 356.9, 778.4, 500.6}},
                      {'z', {334.7, 459.4, 334.4, 563.1}},
                      {'z', {1076.7, 456.9, 1076.8, 531.9}},
                      {'z', {929.9, 748.1, 931.2, 863.1}},
                      {'z', {488.4, 789.4, 488.5, 865.6}},
                      {'z', {1404.7, 693.2, 1402.0, 586.8}},
                      {'z', {1528.3, 596.9, 1522.3, 353.1}}},
                     {{4, {288.0, 604.0}}, {5, {1131.0, 601.0}}, {0, {287.5, 672.0}}, {1, {1131.5, 667.0}}}});
    return three;
  }();
  return photos;
}

// The ground truth in the halved photo's pixels (pixel centres at integers in both).
Eigen::Matrix3d HalvedK(const Eigen::Matrix3d& k_full) {
  Eigen::Matrix3d k = k_full;
  k(0, 0) *= kPhotoScale;
  k(1, 1) *= kPhotoScale;
  k(0, 2) = (k_full(0, 2) + 0.5) * kPhotoScale - 0.5;
  k(1, 2) = (k_full(1, 2) + 0.5) * kPhotoScale - 0.5;
  return k;
}

double AngleDeg(const Eigen::Matrix3d& r) { return Eigen::AngleAxisd(r).angle() * kRadToDeg; }

double AngleBetweenDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) * kRadToDeg;
}

// The rotation Q minimising sum_i |R_i Q - G_i|_F: the world rotation that best aligns the
// recovered cameras with the true ones (the gauge a similarity leaves for rotations).
Eigen::Matrix3d BestWorldRotation(const std::vector<Eigen::Matrix3d>& recovered,
                                  const std::vector<Eigen::Matrix3d>& truth) {
  Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < recovered.size(); ++i) sum += recovered[i].transpose() * truth[i];
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(sum, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
  return svd.matrixU() * d * svd.matrixV().transpose();
}

// Placing a point to a fraction of a photo pixel the way a user does: zoom in with the wheel
// about the spot, click or drag, then Fit. ImGui floors the mouse position to whole screen
// pixels, so the script sends the nearest one: a point lands within 0.5 / zoom image px of
// the stated pixel in x and in y, at the zoom used for it.
constexpr float kWheelZoomStep = 1.2f;  // app/panels/image_panel.cpp
constexpr int kMaxWheelNotches = 10;    // zoom x 6.2

Eigen::Vector2d ScreenPixel(const View& view, const Eigen::Vector2d& uv) {
  const Eigen::Vector2d s = view.ToScreen(uv);
  return {std::round(s.x()), std::round(s.y())};
}

// The view after `notches` wheel steps with the mouse at `anchor` (ZoomImageViewAbout).
View ZoomedAbout(const View& view, const Eigen::Vector2d& anchor, int notches) {
  View zoomed = view;
  zoomed.zoom = view.zoom * std::pow(kWheelZoomStep, notches);
  const double ratio = zoomed.zoom / view.zoom;
  zoomed.origin_x = anchor.x() - (anchor.x() - view.origin_x) * ratio;
  zoomed.origin_y = anchor.y() - (anchor.y() - view.origin_y) * ratio;
  return zoomed;
}

// Zooms in as far as the image points `uvs` all stay in the panel (at most kMaxWheelNotches),
// about their middle or one of them (a point near the photo's edge stays in view when the
// zoom is about it); returns the script line (empty without zoom) and the zoomed view.
std::string ZoomInOn(const View& fitted, const std::vector<Eigen::Vector2d>& uvs, View* zoomed) {
  Eigen::Vector2d middle = Eigen::Vector2d::Zero();
  for (const Eigen::Vector2d& uv : uvs) middle += uv / static_cast<double>(uvs.size());
  std::vector<Eigen::Vector2d> anchors = {ScreenPixel(fitted, middle)};
  for (const Eigen::Vector2d& uv : uvs) anchors.push_back(ScreenPixel(fitted, uv));
  const auto fits = [&](const View& view) {
    return std::all_of(uvs.begin(), uvs.end(),
                       [&](const Eigen::Vector2d& uv) { return view.Inside(view.ToScreen(uv), 8.0); });
  };
  REQUIRE(fits(fitted));
  *zoomed = fitted;
  int best_notches = 0;
  Eigen::Vector2d best_anchor;
  for (const Eigen::Vector2d& anchor : anchors) {
    if (!fitted.Inside(anchor, 1.0)) continue;
    for (int notches = kMaxWheelNotches; notches > best_notches; --notches) {
      const View candidate = ZoomedAbout(fitted, anchor, notches);
      if (!fits(candidate)) continue;
      best_notches = notches;
      best_anchor = anchor;
      *zoomed = candidate;
      break;
    }
  }
  if (best_notches == 0) return "";
  return "wheel " + std::to_string(best_notches) + " " + FormatXY(best_anchor) + "\n";
}

std::string Drag(const View& fitted, const std::array<double, 4>& ab) {
  const Eigen::Vector2d a_uv(ab[0], ab[1]), b_uv(ab[2], ab[3]);
  View zoomed;
  const std::string zoom = ZoomInOn(fitted, {a_uv, b_uv}, &zoomed);
  return zoom + "drag left " + FormatXY(ScreenPixel(zoomed, a_uv)) + " " + FormatXY(ScreenPixel(zoomed, b_uv)) +
         " 1\ncommand fit\n";
}

std::string Click(const View& fitted, const Eigen::Vector2d& uv) {
  View zoomed;
  const std::string zoom = ZoomInOn(fitted, {uv}, &zoomed);
  return zoom + "click left " + FormatXY(ScreenPixel(zoomed, uv)) + "\ncommand fit\n";
}

// The largest distance in x or y (image px) at which ImGui's whole screen pixels may put a
// point placed by Drag or Click from its stated pixel.
double PlacementTolerancePx(const View& fitted, const std::vector<Eigen::Vector2d>& uvs) {
  View zoomed;
  ZoomInOn(fitted, uvs, &zoomed);
  return 0.5 / zoomed.zoom + 1e-6;
}

// A smaller window than render's default 1600 x 900: the suite's CPU time falls from ~26 s to
// ~15 s, and zooming in about each point keeps the placement under a photo pixel.
const std::string kWindowSize = "--size 1024x576 ";

nlohmann::json Run(const TempDir& dir, const std::string& project_path, const std::string& name,
                   const std::string& script) {
  WriteText(dir / (name + ".txt"), script);
  const RunResult run =
      RunRender(dir, kWindowSize + "'" + project_path + "' -o '" + (dir / (name + ".png")) + "' --script '" +
                         (dir / (name + ".txt")) + "' --report '" + (dir / (name + ".json")) + "'");
  INFO("stderr: " << run.stderr_text);
  REQUIRE(run.exit_code == 0);
  return ReadJson(dir / (name + ".json"));
}

// Steps 1 and 2, shared by the test cases: from an empty project, File > Add photo for each
// halved photo, then its line families drawn with the Line X and Line Z tools.
struct DrawnLines {
  const std::vector<Photo>* photos = nullptr;  // Photos() or ThreePhotos()
  std::unique_ptr<TempDir> dir;
  std::string path;  // the saved project with the photos and their lines
  View view;         // the image panel's view (the photos have one size, so one fit)
  facet::Id next_id = 0;
};

DrawnLines DrawLinesThroughTheApp(const std::vector<Photo>& photos, const std::string& dir_name) {
  DrawnLines f;
  f.photos = &photos;
  f.dir = std::make_unique<TempDir>(dir_name);
  const TempDir& dir = *f.dir;
  REQUIRE_MESSAGE(std::filesystem::exists(StrechaFountainDir()), "missing " << StrechaFountainDir());
  // The photos, halved, in the test's folder (never in the repo).
  std::vector<std::string> photo_paths;
  for (const Photo& photo : photos) {
    const std::string source = (StrechaFountainDir() / "images" / (photo.name + ".jpg")).string();
    const cv::Mat full = cv::imread(source, cv::IMREAD_COLOR);
    REQUIRE_MESSAGE(!full.empty(), "cannot read " << source);
    cv::Mat half;
    cv::resize(full, half, cv::Size(), kPhotoScale, kPhotoScale, cv::INTER_AREA);
    REQUIRE(half.cols == 1536);
    REQUIRE(half.rows == 1024);
    photo_paths.push_back(dir / (photo.name + ".jpg"));
    REQUIRE(cv::imwrite(photo_paths.back(), half, {cv::IMWRITE_JPEG_QUALITY, 95}));
  }
  // An empty project, as File > New leaves it.
  const std::string empty_path = dir / "empty.facet";
  WriteText(empty_path, R"({"format": "facet-project", "version": 2, "units": "m", "next_id": 1, "images": [], )"
                        R"("segments": [], "primitives": [], "pins": [], "constraints": []})");
  const std::string photos_path = dir / "photos.facet";
  std::string script = "frames 2\n";
  for (const std::string& path : photo_paths) script += "command add-photo " + path + "\nframes 1\n";
  script += "command select-image 0\nframes 2\ncommand save " + photos_path + "\nframes 1\n";
  f.view = ViewFromReport(Run(dir, empty_path, "add_photos", script));
  REQUIRE(f.view.zoom > 0.05);
  REQUIRE(LoadProjectFile(photos_path).images.size() == photos.size());

  f.path = dir / "lines.facet";
  script = "frames 2\n";
  std::vector<const Line*> drawn_order;
  for (size_t i = 0; i < photos.size(); ++i) {
    script += "command select-image " + std::to_string(i) + "\nframes 1\n";
    for (const char axis : {'x', 'z'}) {
      script += std::string("command tool line-") + axis + "\n";
      for (const Line& line : photos[i].lines) {
        if (line.axis != axis) continue;
        script += Drag(f.view, line.ab_px);
        drawn_order.push_back(&line);
      }
    }
  }
  script += "frames 1\ncommand save " + f.path + "\nframes 1\n";
  Run(dir, photos_path, "lines", script);
  const facet::Project with_lines = LoadProjectFile(f.path);
  REQUIRE(with_lines.segments.size() == drawn_order.size());
  // Every line has the ends the script dragged between, to ImGui's whole screen pixels.
  for (size_t k = 0; k < drawn_order.size(); ++k) {
    const facet::Segment& segment = with_lines.segments[k];
    const Line& line = *drawn_order[k];
    const Eigen::Vector2d a(line.ab_px[0], line.ab_px[1]), b(line.ab_px[2], line.ab_px[3]);
    CAPTURE(k);
    CHECK(segment.axis == (line.axis == 'x' ? facet::Axis::kX : facet::Axis::kZ));
    const double tolerance_px = PlacementTolerancePx(f.view, {a, b});
    CHECK((segment.a_px - a).cwiseAbs().maxCoeff() <= tolerance_px);
    CHECK((segment.b_px - b).cwiseAbs().maxCoeff() <= tolerance_px);
  }
  f.next_id = with_lines.next_id;
  return f;
}

const DrawnLines& LinesDrawnThroughTheApp() {
  static const DrawnLines drawn = DrawLinesThroughTheApp(Photos(), "strecha_fountain");
  return drawn;
}

// Step 3: one box on the wall, its corners pinned in each photo with the Pin tool; `before`
// runs first (e.g. calibration settings). Returns the saved project; *log gets the app's log.
facet::Project PinTheBox(const DrawnLines& lines, const std::string& name, const std::string& before,
                         std::string* log) {
  const facet::Id box_id = lines.next_id;  // the id the script's new box gets
  const std::string saved = *lines.dir / (name + ".facet");
  std::string script =
      "frames 2\n" + before + "command select-image 0\nframes 1\ncommand add box\nframes 1\ncommand tool pin\n";
  for (size_t i = 0; i < (*lines.photos).size(); ++i) {
    script += "command select-image " + std::to_string(i) + "\nframes 1\n";
    for (const BoxPin& pin : (*lines.photos)[i].pins) {
      script += "command select vertex " + std::to_string(box_id) + " " + std::to_string(pin.vertex) + "\n" +
                Click(lines.view, pin.uv_px);
    }
  }
  script += "frames 2\ncommand save " + saved + "\nframes 1\n";
  *log = ReportLog(Run(*lines.dir, lines.path, name, script));
  facet::Project model = LoadProjectFile(saved);
  REQUIRE(model.images.size() == (*lines.photos).size());
  REQUIRE(model.primitives.size() == 1);
  size_t num_pins = 0;
  for (const Photo& photo : (*lines.photos)) num_pins += photo.pins.size();
  REQUIRE(model.pins.size() == num_pins);
  // Every pin sits on the screen pixel the script clicked (the view read once holds for every photo).
  for (const facet::Pin& pin : model.pins) {
    const facet::Image* image = model.FindImage(pin.image_id);
    REQUIRE(image != nullptr);
    const size_t index = static_cast<size_t>(image - model.images.data());
    const auto& pins = (*lines.photos)[index].pins;
    const auto stated =
        std::find_if(pins.begin(), pins.end(), [&](const BoxPin& p) { return p.vertex == pin.vertex.vertex; });
    REQUIRE(stated != pins.end());
    CHECK((pin.uv_px - stated->uv_px).cwiseAbs().maxCoeff() <= PlacementTolerancePx(lines.view, {stated->uv_px}));
  }
  return model;
}

// Depth for the focal length: a second box on the basin in front of the wall, its top the
// basin rim's. Pinned in each photo: the rim's two front corners (vertex 4 top left, 5 top
// right: where the rim's top front edge turns onto the chamfers) and, as a line pin, its top
// back edge (corners 6-7) on the line where the rim meets the pedestal behind it (the rim's
// ends are chamfered, so that edge's ends are no points of the photo). Read by eye on 3x-5x
// crops of the halved photos, to a pixel or two. With the band's pins these are points on two
// planes, the wall's and the rim's, seen in both photos.
struct BasinReading {
  Eigen::Vector2d front_left, front_right;
  std::array<double, 4> back_line;
};
const std::vector<BasinReading>& BasinReadings() {
  static const std::vector<BasinReading> readings = {
      {{643.0, 695.5}, {1097.0, 685.0}, {510.0, 667.0, 1000.0, 655.5}},  // 0006
      {{363.0, 687.0}, {790.0, 695.0}, {400.0, 665.5, 850.0, 668.5}},    // 0004
  };
  return readings;
}

// PinTheBox, then the basin box: added, its two front corners pinned and its top back edge
// line-pinned in each photo; `before` runs first.
facet::Project PinTheBoxAndBasin(const DrawnLines& lines, const std::string& name, const std::string& before,
                                 std::string* log) {
  REQUIRE(lines.photos == &Photos());  // the basin is read in these two
  const facet::Id box_id = lines.next_id;
  size_t num_band_pins = 0;
  for (const Photo& photo : Photos()) num_band_pins += photo.pins.size();
  // The ids the script's objects get: the band box, its pins, two known lengths, then the basin
  // box and the ground constraint Add box gives it.
  const facet::Id basin_id = box_id + 1 + static_cast<facet::Id>(num_band_pins) + 2;
  const facet::Id basin_ground_id = basin_id + 1;
  constexpr int kTopBackEdge = 10;  // corners 6-7 in a new box's mesh (core/mesh/box.cpp's order)
  const std::string saved = *lines.dir / (name + ".facet");
  std::string script =
      "frames 2\n" + before + "command select-image 0\nframes 1\ncommand add box\nframes 1\ncommand tool pin\n";
  for (size_t i = 0; i < Photos().size(); ++i) {
    script += "command select-image " + std::to_string(i) + "\nframes 1\n";
    for (const BoxPin& pin : Photos()[i].pins) {
      script += "command select vertex " + std::to_string(box_id) + " " + std::to_string(pin.vertex) + "\n" +
                Click(lines.view, pin.uv_px);
    }
  }
  // The band box's depth is seen by nothing, and its height sets the scale: both typed as known
  // lengths (edges 0-2 and 0-4), as a user who measured the band would. (Before the joint solve
  // held an unseen size, the depth drifted below zero here with the focal lengths free.)
  script += "command select edge " + std::to_string(box_id) + " 3\ncommand constrain length 1\nframes 1\n";
  script += "command select edge " + std::to_string(box_id) + " 0\ncommand constrain length 1\nframes 1\n";
  script += "command select-image 0\nframes 1\ncommand select none\ncommand add box\nframes 1\n";
  // The basin does not stand on the band's base.
  script += "command constrain remove " + std::to_string(basin_ground_id) + "\nframes 1\n";
  // Its height is seen by nothing either (every observation is on its top): typed too (edge 0-4).
  script += "command select edge " + std::to_string(basin_id) +
            " 0\ncommand constrain length 0.1\nframes 1\ncommand tool pin\n";
  for (size_t i = 0; i < Photos().size(); ++i) {
    const BasinReading& basin = BasinReadings()[i];
    script += "command select-image " + std::to_string(i) + "\nframes 1\n";
    script += "command select vertex " + std::to_string(basin_id) + " 4\n" + Click(lines.view, basin.front_left);
    script += "command select vertex " + std::to_string(basin_id) + " 5\n" + Click(lines.view, basin.front_right);
    std::ostringstream line_pin;
    line_pin.precision(17);
    line_pin << "command select edge " << basin_id << " " << kTopBackEdge << "\ncommand line-pin " << i;
    for (double v : basin.back_line) line_pin << " " << v;
    script += line_pin.str() + "\nframes 1\n";
  }
  script += "frames 2\ncommand save " + saved + "\nframes 1\n";
  *log = ReportLog(Run(*lines.dir, lines.path, name, script));
  facet::Project model = LoadProjectFile(saved);
  REQUIRE(model.images.size() == Photos().size());
  REQUIRE(model.primitives.size() == 2);
  REQUIRE(model.primitives[1].id == basin_id);
  REQUIRE(model.pins.size() == num_band_pins + 2 * Photos().size());
  return model;
}

// The recovered cameras against the ground truth.
struct Comparison {
  std::vector<double> relative_rotation_error_deg;   // per pair (a < b)
  std::vector<double> aligned_rotation_error_deg;    // per photo, after the best common rotation
  std::vector<double> baseline_direction_error_deg;  // per pair
  std::vector<double> focal_error;                   // per photo, relative
  double pin_rms_px = 0.0;
  std::string figures;  // for MESSAGE
};

Comparison CompareWithGroundTruth(const facet::Project& model, const std::vector<Photo>& photos = Photos()) {
  Comparison out;
  std::vector<Eigen::Matrix3d> recovered, truth;
  std::vector<Eigen::Vector3d> recovered_centres, true_centres;
  std::ostringstream figures;
  figures.precision(3);
  for (size_t i = 0; i < photos.size(); ++i) {
    const facet::Image& image = model.images[i];
    CAPTURE(image.path);
    REQUIRE(image.camera_calibrated);
    // Each photo's world frame was chosen once (core/solve/world_frames.h).
    CHECK(image.axis_quarter_turns != facet::Image::kAxisTurnsUnchosen);
    const GroundTruthCamera gt = ReadStrechaCamera(photos[i].name);
    const Eigen::Matrix3d k = HalvedK(gt.K);
    recovered.push_back(image.camera.cam_from_world_rotation);
    truth.push_back(gt.cam_from_world_rotation);
    recovered_centres.push_back(image.camera.CenterInWorld());
    true_centres.push_back(gt.CenterInWorld());
    out.focal_error.push_back(image.camera.focal_px / (0.5 * (k(0, 0) + k(1, 1))) - 1.0);
    figures << photos[i].name << ": f " << image.camera.focal_px << " px (true " << k(0, 0) << "), "
            << 100.0 * out.focal_error.back() << " %; principal point " << image.camera.principal_point_px.transpose()
            << " (true " << k(0, 2) << " " << k(1, 2) << ")\n";
  }
  out.pin_rms_px = PinRmsPx(model);
  figures << "pin RMS " << out.pin_rms_px << " px\n";
  const Eigen::Matrix3d world_rotation = BestWorldRotation(recovered, truth);
  for (size_t i = 0; i < recovered.size(); ++i) {
    out.aligned_rotation_error_deg.push_back(AngleDeg(recovered[i] * world_rotation * truth[i].transpose()));
    figures << photos[i].name << ": rotation error after the best common rotation "
            << out.aligned_rotation_error_deg.back() << " deg\n";
  }
  for (size_t a = 0; a < recovered.size(); ++a) {
    for (size_t b = a + 1; b < recovered.size(); ++b) {
      const Eigen::Matrix3d relative = recovered[b] * recovered[a].transpose();
      const Eigen::Matrix3d true_relative = truth[b] * truth[a].transpose();
      out.relative_rotation_error_deg.push_back(AngleDeg(relative * true_relative.transpose()));
      // The direction from b's centre to a's in b's frame: free of the world's gauge.
      const Eigen::Vector3d baseline = recovered[b] * (recovered_centres[a] - recovered_centres[b]);
      const Eigen::Vector3d true_baseline = truth[b] * (true_centres[a] - true_centres[b]);
      out.baseline_direction_error_deg.push_back(AngleBetweenDeg(baseline, true_baseline));
      figures << photos[a].name << "-" << photos[b].name << ": relative rotation " << AngleDeg(relative)
              << " deg (true " << AngleDeg(true_relative) << "), error " << out.relative_rotation_error_deg.back()
              << " deg; baseline direction error " << out.baseline_direction_error_deg.back() << " deg\n";
    }
  }
  out.figures = figures.str();
  return out;
}

}  // namespace

// The issue's run as a user without a known lens makes it: each photo's focal length comes
// from its two line families (x, z). Figures on this build: f 0006 +25 %, 0004 -38 %; the
// relative rotation off by 1.9 deg, the baseline direction by 62 deg. They swing with
// sub-pixel changes of the line ends (the same lines drawn in a 1280 x 720 window: +37 %,
// -42 %, 1.4 deg; 1600 x 900: +30 %, -32 %, 1.1 deg). The cause is the photos' view of the
// wall, not the solve: with the true focal length the same lines and pins give 0.12 deg and
// 2.3 deg (the last case). These photos face the wall, so its horizontal vanishing point lies
// ~7,300 px from the principal point and the vertical one 28,000-40,000 px:
// f^2 = -(v_x - p).(v_z - p) is then a difference of large, poorly known terms (the
// calibration says so: f = 1730 +- 181 px and 853 +- 316 px); the depth family that would
// fix f has only short stubs at the ends of mouldings, and its vanishing point lies ~250 px
// from the principal point, where a 1 deg error in one stub moves it by tens of px. Freeing
// each photo's focal length in the joint solve (focal-lock off) makes it worse: three or four
// pins on one face of one box do not fix f either (f +58 % / -20 %, relative rotation 3.9 deg,
// baseline 53 deg). (The line detector, `lines detect`, does no better on these photos:
// f = 3,400-5,300 px, its depth family made of carving and the basin's slanted faces.) One
// lens for both photos does (the next case).
TEST_CASE("Strecha fountain through the app, focal length unknown: cameras and box solve; rotations reported") {
  const auto started = std::chrono::steady_clock::now();
  std::string log;
  const facet::Project model = PinTheBox(LinesDrawnThroughTheApp(), "model_unknown_focal", "", &log);
  INFO("log:\n" << log);
  const Comparison c = CompareWithGroundTruth(model);
  const double worst_deg =
      *std::max_element(c.relative_rotation_error_deg.begin(), c.relative_rotation_error_deg.end());
  // The issue's 1 deg is reported, not asserted: each photo's lines do not fix its focal
  // length (see above); the next cases assert it with one lens for both photos and with the
  // focal length known.
  MESSAGE("Strecha fountain, focal length from the lines:\n"
          << c.figures << "worst relative rotation error " << worst_deg << " deg: the issue's "
          << kMaxRelativeRotationErrorDeg << " deg is "
          << std::string(worst_deg < kMaxRelativeRotationErrorDeg ? "met" : "NOT met") << "\ntime "
          << std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count()
          << " s (with the photos and lines)");
  CHECK(log.find("error:") == std::string::npos);
  // The box lands on its pins (their reading is good to a pixel or two of the halved photo).
  constexpr double kMaxPinRmsPx = 3.0;
  CHECK(c.pin_rms_px < kMaxPinRmsPx);
  // A sanity bound, not an accuracy claim (see above: 25-42 % off): the calibration gave a
  // focal length of the right order.
  constexpr double kMaxFocalFactor = 2.0;
  for (const double error : c.focal_error) CHECK(std::abs(std::log1p(error)) < std::log(kMaxFocalFactor));
}

// The same run by a user who does not know the lens but knows that both photos come from one
// camera (Properties > "Same lens as other photos" with "Lock focal" off; the script's
// `calibration lens-group 1` and `calibration focal-lock off`, core/scene/project.h,
// Image::lens_group): the joint solve then has one focal length for both photos, fixed by the
// lines and pins of both together, where each photo's own lines leave it loose (the first
// case). Nothing of the ground truth enters the run. Figures on this build: f -2.2 % (both),
// relative rotation 0.50 deg, baseline direction 2.5 deg; the same lines drawn in a
// 1280 x 720 window: +0.8 %, 0.07 deg, 2.2 deg; 1600 x 900: +2.9 %, 0.65 deg, 2.0 deg. This
// holds for this pair, 21 deg apart, not for every pair: with 0005 (ThreePhotos, read after
// these figures) the same run gives 0004 + 0005 (11 deg apart) f -7.2 %, 1.17 deg, and
// 0006 + 0005 (10 deg apart) f +101 %, 9.5 deg (each photo's lines alone: 4.8 and 3.2 deg);
// all three photos, the next case, f +11 % and 2.45 deg.
TEST_CASE(
    "Strecha fountain through the app, focal length unknown, one lens for both photos: every camera within 1 deg") {
  std::ostringstream before;
  for (size_t i = 0; i < Photos().size(); ++i) {
    before << "command select-image " << i << "\nframes 1\ncommand calibration focal-lock off\nframes 1\n"
           << "command calibration lens-group 1\nframes 1\n";
  }
  std::string log;
  const facet::Project model = PinTheBox(LinesDrawnThroughTheApp(), "model_shared_lens", before.str(), &log);
  INFO("log:\n" << log);
  const Comparison c = CompareWithGroundTruth(model);
  const double worst_deg =
      *std::max_element(c.relative_rotation_error_deg.begin(), c.relative_rotation_error_deg.end());
  MESSAGE("Strecha fountain, focal length unknown, one lens:\n"
          << c.figures << "worst relative rotation error " << worst_deg << " deg: the issue's "
          << kMaxRelativeRotationErrorDeg << " deg is "
          << std::string(worst_deg < kMaxRelativeRotationErrorDeg ? "met" : "NOT met"));
  CHECK(log.find("error:") == std::string::npos);
  // One focal length for both photos, to the last bit (one parameter of the solve).
  CHECK(model.images[0].camera.focal_px == model.images[1].camera.focal_px);
  // The lens within 5 % (-2.2 % measured; 0.8-2.9 % in the other window sizes above), against
  // 25-38 % from each photo's lines alone.
  constexpr double kMaxFocalError = 0.05;
  for (const double error : c.focal_error) CHECK(std::abs(error) < kMaxFocalError);
  for (const double error_deg : c.relative_rotation_error_deg) CHECK(error_deg < kMaxRelativeRotationErrorDeg);
  for (const double error_deg : c.aligned_rotation_error_deg) CHECK(error_deg < kMaxRelativeRotationErrorDeg);
  // As with the known lens: the baselines from 3-4 pins per photo on one face (2.5 deg measured).
  constexpr double kMaxBaselineDirectionErrorDeg = 5.0;
  for (const double error_deg : c.baseline_direction_error_deg) CHECK(error_deg < kMaxBaselineDirectionErrorDeg);
  constexpr double kMaxPinRmsPx = 3.0;
  CHECK(c.pin_rms_px < kMaxPinRmsPx);
}

// The same with a third photo from the camera, 0005 (ThreePhotos): its lines and band pins as
// the other two have them, the lens shared by all three. The issue's 1 deg is NOT met, and is
// reported, not asserted: f +11.3 %, relative rotations 2.45 / 1.51 / 1.27 deg (0006-0004,
// 0006-0005, 0004-0005), baselines 1.3-3.9 deg. 0005 faces the wall squarely: its own lines
// give f +204 % (each photo's focal length freed: +81 / -12 / +230 %, up to 7.6 deg), and
// even with the true focal length its rotation is the least sure (relative rotations 0.13,
// 0.85, 0.75 deg), so its many far-vanishing segments pull the shared focal length long
// rather than fixing it. A second photo at an angle to the wall is what fixes the lens.
TEST_CASE("Strecha fountain through the app, focal length unknown, one lens for three photos: rotations reported") {
  const DrawnLines lines = DrawLinesThroughTheApp(ThreePhotos(), "strecha_fountain_three");
  std::ostringstream before;
  for (size_t i = 0; i < ThreePhotos().size(); ++i) {
    before << "command select-image " << i << "\nframes 1\ncommand calibration focal-lock off\nframes 1\n"
           << "command calibration lens-group 1\nframes 1\n";
  }
  std::string log;
  const facet::Project model = PinTheBox(lines, "model_shared_lens_three", before.str(), &log);
  INFO("log:\n" << log);
  const Comparison c = CompareWithGroundTruth(model, ThreePhotos());
  const double worst_deg =
      *std::max_element(c.relative_rotation_error_deg.begin(), c.relative_rotation_error_deg.end());
  MESSAGE("Strecha fountain, focal length unknown, one lens, three photos:\n"
          << c.figures << "worst relative rotation error " << worst_deg << " deg: the issue's "
          << kMaxRelativeRotationErrorDeg << " deg is "
          << std::string(worst_deg < kMaxRelativeRotationErrorDeg ? "met" : "NOT met"));
  CHECK(log.find("error:") == std::string::npos);
  for (const facet::Image& image : model.images) CHECK(image.camera.focal_px == model.images[0].camera.focal_px);
  // What the shared lens still buys against each photo's own (81-230 % off): within 15 %
  // (11.3 % measured); the pins met as in the other cases.
  constexpr double kMaxFocalError = 0.15;
  for (const double error : c.focal_error) CHECK(std::abs(error) < kMaxFocalError);
  constexpr double kMaxPinRmsPx = 3.0;
  CHECK(c.pin_rms_px < kMaxPinRmsPx);
}

// The same run by a user who knows the lens (Properties > Focal > Fixed, the script's
// `calibration focal fixed F`, before the box): here the dataset's focal length halved, the
// only ground truth the run reads; rotations and positions still come from the lines and pins.
TEST_CASE("Strecha fountain through the app, focal length known: every camera within 1 deg of the truth") {
  const DrawnLines& lines = LinesDrawnThroughTheApp();
  const GroundTruthCamera first = ReadStrechaCamera(Photos()[0].name);
  const double focal_px = 0.5 * (HalvedK(first.K)(0, 0) + HalvedK(first.K)(1, 1));
  std::ostringstream before;
  before.precision(17);
  for (size_t i = 0; i < Photos().size(); ++i) {
    // The dataset's photos share one K.
    REQUIRE((ReadStrechaCamera(Photos()[i].name).K - first.K).norm() == 0.0);
    before << "command select-image " << i << "\nframes 1\ncommand calibration focal fixed " << focal_px
           << "\nframes 1\n";
  }
  std::string log;
  const facet::Project model = PinTheBox(lines, "model_known_focal", before.str(), &log);
  INFO("log:\n" << log);
  const Comparison c = CompareWithGroundTruth(model);
  MESSAGE("Strecha fountain, focal length known:\n" << c.figures);
  for (const double error : c.focal_error) CHECK(std::abs(error) < 1e-9);
  for (const double error_deg : c.relative_rotation_error_deg) CHECK(error_deg < kMaxRelativeRotationErrorDeg);
  for (const double error_deg : c.aligned_rotation_error_deg) CHECK(error_deg < kMaxRelativeRotationErrorDeg);
  // The baselines come from 3-4 pins per photo on one face of the box, read to a pixel or two:
  // their direction is good to a few degrees (2.3 deg on this build).
  constexpr double kMaxBaselineDirectionErrorDeg = 5.0;
  for (const double error_deg : c.baseline_direction_error_deg) CHECK(error_deg < kMaxBaselineDirectionErrorDeg);
  constexpr double kMaxPinRmsPx = 3.0;
  CHECK(c.pin_rms_px < kMaxPinRmsPx);
}

// What a PhotoModeler user does without the lens: give the model depth, here a box on the
// basin in front of the wall (PinTheBoxAndBasin), and let the joint solve free the focal
// lengths (focal-lock off) with points on two planes in both photos. Figures on this build:
// f 0006 +7.1 %, 0004 +8.1 % (the lines alone: +25 %, -38 %), the baseline direction off by
// 0.35 deg (62 deg), but the relative rotation still off by 1.82 deg (1.89 deg): the issue's
// 1 deg is not met. With f 7-8 % long the line families turn each camera by ~0.9 deg (the
// rotation error after the best common rotation); the known focal length gives 0.12 deg. The
// rim is read to a pixel or two over ~30 px of depth in each photo, so f is good to several
// per cent, not to the ~2 % that 1 deg would need here; the readings were not adjusted
// towards the ground truth. (The same run with one lens for both photos does not get the
// basin: from its first pin on, every solve stops with "Size z of 'box 2' would go from 0.1 to
// -0.08" (the known height 0.1 is a distance, met by -0.1 too) and leaves the model as it
// was, so the basin's pins end ~200 px off; the band alone meets 1 deg there, the case above.)
TEST_CASE("Strecha fountain through the app, focal length unknown, a box with depth on the basin: rotations reported") {
  std::ostringstream before;
  for (size_t i = 0; i < Photos().size(); ++i) {
    before << "command select-image " << i << "\nframes 1\ncommand calibration focal-lock off\nframes 1\n";
  }
  std::string log;
  const facet::Project model = PinTheBoxAndBasin(LinesDrawnThroughTheApp(), "model_basin", before.str(), &log);
  INFO("log:\n" << log);
  const Comparison c = CompareWithGroundTruth(model);
  const double worst_deg =
      *std::max_element(c.relative_rotation_error_deg.begin(), c.relative_rotation_error_deg.end());
  const facet::Primitive& basin = model.primitives[1];
  MESSAGE("Strecha fountain, focal length free, band and basin:\n"
          << c.figures << "basin box " << basin.shape.params.head<3>().transpose() << " (band box "
          << model.primitives[0].shape.params.head<3>().transpose() << ")\nworst relative rotation error " << worst_deg
          << " deg: the issue's " << kMaxRelativeRotationErrorDeg << " deg is "
          << std::string(worst_deg < kMaxRelativeRotationErrorDeg ? "met" : "NOT met"));
  CHECK(log.find("error:") == std::string::npos);
  // What the depth buys, with bounds that the lines alone fail (25-38 % and 62 deg above):
  // each focal length within 15 % (7-8 % measured), the baseline direction within the
  // known-focal case's 5 deg (0.35 deg measured); the pins met as there.
  constexpr double kMaxFocalError = 0.15;
  for (const double error : c.focal_error) CHECK(std::abs(error) < kMaxFocalError);
  constexpr double kMaxBaselineDirectionErrorDeg = 5.0;
  for (const double error_deg : c.baseline_direction_error_deg) CHECK(error_deg < kMaxBaselineDirectionErrorDeg);
  constexpr double kMaxPinRmsPx = 3.0;
  CHECK(c.pin_rms_px < kMaxPinRmsPx);
  // The basin box has depth: its top's front and back are apart by more than a tenth of its width.
  CHECK(model.primitives[1].shape.params[1] > 0.1 * model.primitives[1].shape.params[0]);
}
