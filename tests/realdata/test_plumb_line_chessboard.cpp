// Plumb-line radial distortion (core/estimators/plumb_line.h) on OpenCV's sample chessboard views, against
// the distortion that cv::calibrateCamera found for the same lens (left_intrinsics.yml).
// Data: FACET_SHARED_DATA/opencv-chessboard (PROVENANCE.md there): 13 left 640x480 views of a
// 9x6-inner-corner board through a lens with strong barrel distortion (OpenCV k1 = -0.266,
// k2 = -0.039, k3 = 0.238). The corners come from cv::findChessboardCorners + cv::cornerSubPix,
// standing in for the user's clicks; each board row (9 points) and column (6 points) is one
// polyline, rows and columns of one view forming two families (parallel on the board).
// The centre of distortion is OpenCV's principal point, so both models share it.
#include <doctest/doctest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <Eigen/Eigenvalues>

#include "core/estimators/plumb_line.h"
#include "core/util/stats.h"

namespace facet {
namespace {

namespace fs = std::filesystem;

const fs::path kDataDir = fs::path(FACET_SHARED_DATA) / "opencv-chessboard";
constexpr int kWidthPx = 640;
constexpr int kHeightPx = 480;
const cv::Size kPattern(9, 6);
// Largest disagreement of our undistorted board corners with OpenCV's radial undistortion, as
// a fraction of OpenCV's largest displacement of those corners (see the assertion).
constexpr double kMaxDisagreementFraction = 0.08;
// Board lines after correction: the corner detector's noise is ~0.1 px.
constexpr double kMaxStraightnessRmsPx = 0.3;

struct Reference {
  cv::Mat camera_matrix;
  cv::Mat distortion;  // k1, k2, p1, p2, k3
  double focal_px = 0.0;
  Eigen::Vector2d principal_point_px = Eigen::Vector2d::Zero();
};

Reference ReadReference() {
  Reference reference;
  cv::FileStorage file((kDataDir / "left_intrinsics.yml").string(), cv::FileStorage::READ);
  REQUIRE_MESSAGE(file.isOpened(), "cannot read left_intrinsics.yml");
  file["camera_matrix"] >> reference.camera_matrix;
  file["distortion_coefficients"] >> reference.distortion;
  REQUIRE(reference.camera_matrix.rows == 3);
  REQUIRE(reference.distortion.total() == 5);
  reference.focal_px = reference.camera_matrix.at<double>(0, 0);
  reference.principal_point_px = {reference.camera_matrix.at<double>(0, 2), reference.camera_matrix.at<double>(1, 2)};
  return reference;
}

// OpenCV's undistortion of pixels, back into pixels of the same K; radial_only drops the
// tangential terms p1, p2, which our model does not have.
std::vector<Eigen::Vector2d> OpenCvUndistort(const Reference& reference, const std::vector<Eigen::Vector2d>& uv_px,
                                             bool radial_only = false) {
  std::vector<cv::Point2d> in, out;
  for (const auto& uv : uv_px) in.emplace_back(uv.x(), uv.y());
  cv::Mat distortion = reference.distortion.clone();
  if (radial_only) distortion.at<double>(2) = distortion.at<double>(3) = 0.0;
  cv::undistortPoints(in, out, reference.camera_matrix, distortion, cv::noArray(), reference.camera_matrix,
                      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 200, 1e-12));
  std::vector<Eigen::Vector2d> result;
  for (const auto& p : out) result.emplace_back(p.x, p.y);
  return result;
}

struct View {
  std::string name;
  std::vector<Eigen::Vector2d> corners_px;  // row-major, 9 per row
};

std::vector<View> DetectLeftViews() {
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(kDataDir)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("left", 0) == 0 && entry.path().extension() == ".jpg") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  REQUIRE(files.size() == 13);
  std::vector<View> views;
  for (const auto& file : files) {
    const cv::Mat gray = cv::imread(file.string(), cv::IMREAD_GRAYSCALE);
    REQUIRE_MESSAGE(!gray.empty(), "cannot read " << file.string());
    REQUIRE(gray.cols == kWidthPx);
    REQUIRE(gray.rows == kHeightPx);
    std::vector<cv::Point2f> corners;
    const bool found =
        cv::findChessboardCorners(gray, kPattern, corners, cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE);
    REQUIRE_MESSAGE(found, "no board in " << file.filename().string());
    cv::cornerSubPix(gray, corners, cv::Size(11, 11), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 100, 1e-4));
    View view;
    view.name = file.filename().string();
    for (const auto& c : corners) view.corners_px.emplace_back(c.x, c.y);
    views.push_back(view);
  }
  return views;
}

// Rows (family first_family) and columns (first_family + 1) of one view.
void AppendBoardLines(const std::vector<Eigen::Vector2d>& corners, int first_family, std::vector<PlumbLine>* lines) {
  for (int row = 0; row < kPattern.height; ++row) {
    PlumbLine line;
    line.family = first_family;
    for (int col = 0; col < kPattern.width; ++col) line.points_px.push_back(corners[row * kPattern.width + col]);
    lines->push_back(line);
  }
  for (int col = 0; col < kPattern.width; ++col) {
    PlumbLine line;
    line.family = first_family + 1;
    for (int row = 0; row < kPattern.height; ++row) line.points_px.push_back(corners[row * kPattern.width + col]);
    lines->push_back(line);
  }
}

// Straightness of polylines: RMS over all points of the distance to each polyline's own
// best-fit line (independent of the estimator's cost, so OpenCV's undistortion is measured
// the same way).
double StraightnessRmsPx(const std::vector<PlumbLine>& lines) {
  double sum = 0.0;
  int count = 0;
  for (const auto& line : lines) {
    Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
    for (const auto& p : line.points_px) centroid += p;
    centroid /= static_cast<double>(line.points_px.size());
    Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
    for (const auto& p : line.points_px) scatter += (p - centroid) * (p - centroid).transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(scatter);
    sum += eigen.eigenvalues()(0);
    count += static_cast<int>(line.points_px.size());
  }
  return std::sqrt(sum / count);
}

PlumbLineOptions Options(const Reference& reference, bool estimate_k2) {
  PlumbLineOptions options;
  options.width_px = kWidthPx;
  options.height_px = kHeightPx;
  options.center_px = reference.principal_point_px;
  options.estimate_k2 = estimate_k2;
  return options;
}

// Largest distance between our undistortion and OpenCV's at the given pixels.
double MaxDisagreementPx(const RadialDistortion& ours, const Reference& reference,
                         const std::vector<Eigen::Vector2d>& uv_px, bool radial_only = false) {
  const std::vector<Eigen::Vector2d> theirs = OpenCvUndistort(reference, uv_px, radial_only);
  double worst = 0.0;
  for (size_t i = 0; i < uv_px.size(); ++i) worst = std::max(worst, (ours.Undistort(uv_px[i]) - theirs[i]).norm());
  return worst;
}

}  // namespace

TEST_CASE("Chessboard plumb lines: distortion agrees with calibrateCamera, lines become straight") {
  REQUIRE_MESSAGE(fs::exists(kDataDir), "missing " << kDataDir.string());
  const Reference reference = ReadReference();
  const std::vector<View> views = DetectLeftViews();

  std::vector<PlumbLine> all_lines;
  std::vector<Eigen::Vector2d> all_corners;
  for (size_t v = 0; v < views.size(); ++v) {
    AppendBoardLines(views[v].corners_px, 2 * static_cast<int>(v), &all_lines);
    all_corners.insert(all_corners.end(), views[v].corners_px.begin(), views[v].corners_px.end());
  }

  // OpenCV's model converted to ours (2 terms), over the radius of the farthest image corner.
  const RadialDistortion identity = MakeRadialDistortion(kWidthPx, kHeightPx, reference.principal_point_px);
  double max_radius_px = 0.0;
  for (const Eigen::Vector2d corner :
       {Eigen::Vector2d(0, 0), Eigen::Vector2d(kWidthPx - 1, 0), Eigen::Vector2d(0, kHeightPx - 1),
        Eigen::Vector2d(kWidthPx - 1, kHeightPx - 1)}) {
    max_radius_px = std::max(max_radius_px, (corner - identity.center_px).norm());
  }
  const OpenCvRadialCoefficients opencv{reference.distortion.at<double>(0), reference.distortion.at<double>(1),
                                        reference.distortion.at<double>(4)};
  double conversion_error_px = 0.0;
  const RadialDistortion opencv_as_ours = RadialDistortionFromOpenCv(
      opencv, reference.focal_px, identity.center_px, identity.scale_px, max_radius_px, true, &conversion_error_px);
  MESSAGE("OpenCV (k1 " << opencv.k1 << ", k2 " << opencv.k2 << ", k3 " << opencv.k3 << ") in our model: k1 "
                        << opencv_as_ours.k1 << ", k2 " << opencv_as_ours.k2 << " (fit error " << conversion_error_px
                        << " px up to r = " << max_radius_px << " px)");

  // Straightness of the board lines as detected and after OpenCV's own undistortion.
  std::vector<PlumbLine> opencv_lines = all_lines;
  for (auto& line : opencv_lines) line.points_px = OpenCvUndistort(reference, line.points_px);
  const double rms_detected_px = StraightnessRmsPx(all_lines);
  const double rms_opencv_px = StraightnessRmsPx(opencv_lines);

  // Joint estimate over all views.
  for (bool estimate_k2 : {false, true}) {
    std::vector<double> times_ms;
    PlumbLineSummary joint;
    for (int run = 0; run < 5; ++run) {
      joint = EstimateRadialDistortion(all_lines, Options(reference, estimate_k2));
      times_ms.push_back(joint.time_ms);
    }
    CAPTURE(joint.message);
    REQUIRE(joint.IsUsable());
    std::vector<PlumbLine> our_lines = all_lines;
    for (auto& line : our_lines) {
      for (auto& p : line.points_px) p = joint.distortion.Undistort(p);
    }
    const double rms_ours_px = StraightnessRmsPx(our_lines);
    const double corners_disagreement_px = MaxDisagreementPx(joint.distortion, reference, all_corners);
    const std::vector<Eigen::Vector2d> image_corners = {
        {0.0, 0.0}, {kWidthPx - 1.0, 0.0}, {0.0, kHeightPx - 1.0}, {kWidthPx - 1.0, kHeightPx - 1.0}};
    const double image_corner_disagreement_px = MaxDisagreementPx(joint.distortion, reference, image_corners);
    const double image_corner_shift_px = MaxDisagreementPx(identity, reference, image_corners);
    const double radial_disagreement_px = MaxDisagreementPx(joint.distortion, reference, all_corners, true);
    // The best 2-term version of OpenCV's model over the radii the board covers: how close
    // any 2-term model can come to OpenCV's 3-term one there.
    double board_radius_px = 0.0;
    for (const auto& p : all_corners) board_radius_px = std::max(board_radius_px, (p - identity.center_px).norm());
    const RadialDistortion opencv_over_board = RadialDistortionFromOpenCv(
        opencv, reference.focal_px, identity.center_px, identity.scale_px, board_radius_px, estimate_k2);
    const double conversion_floor_px = MaxDisagreementPx(opencv_over_board, reference, all_corners, true);
    const double board_shift_px = MaxDisagreementPx(identity, reference, all_corners, true);
    MESSAGE("board corners reach r = " << board_radius_px << " px, where OpenCV moves them up to " << board_shift_px
                                       << " px; OpenCV's model in ours over those radii: k1 " << opencv_over_board.k1
                                       << ", k2 " << opencv_over_board.k2);
    MESSAGE("radial part only (p1 = p2 = 0): ours vs OpenCV " << radial_disagreement_px
                                                              << " px max over board corners; OpenCV's own 2-term "
                                                                 "conversion vs OpenCV "
                                                              << conversion_floor_px << " px");
    double back_error_px = 0.0;
    const OpenCvRadialCoefficients ours_as_opencv =
        OpenCvFromRadialDistortion(joint.distortion, reference.focal_px, board_radius_px, true, &back_error_px);
    MESSAGE("joint over " << views.size() << " views, k2 " << std::string(estimate_k2 ? "on" : "off") << ": k1 "
                          << joint.distortion.k1 << " +- " << joint.k1_std << ", k2 " << joint.distortion.k2 << " +- "
                          << joint.k2_std << " (as OpenCV k1, k2 over the board radii: " << ours_as_opencv.k1 << ", "
                          << ours_as_opencv.k2 << "); straightness RMS " << rms_detected_px << " px detected, "
                          << rms_ours_px << " px ours, " << rms_opencv_px << " px OpenCV's; vs OpenCV undistortion: "
                          << corners_disagreement_px << " px max over board corners, " << image_corner_disagreement_px
                          << " px at the image corners (where OpenCV moves them " << image_corner_shift_px
                          << " px); median solve " << internal::Median(times_ms) << " ms, " << joint.iterations
                          << " iterations");
    CAPTURE(rms_ours_px);
    CAPTURE(corners_disagreement_px);
    CAPTURE(image_corner_disagreement_px);
    // The start is not the answer: detected lines are bent by more than a pixel.
    CHECK(rms_detected_px > 0.5);
    CHECK(std::abs(joint.initial_rms_px - rms_detected_px) < 0.2 * rms_detected_px);
    CHECK(rms_ours_px < kMaxStraightnessRmsPx);
    CHECK(rms_ours_px <= rms_opencv_px + 0.02);
    // Agreement with OpenCV's radial undistortion where there are data (the board corners,
    // r <= 278 px; the image corners at 420 px are an extrapolation for both models and are
    // only reported). Measured 1.16 px (k1) and 1.60 px (k1, k2) where OpenCV moves the
    // corners by up to 24.7 px; the best 2-term copy of OpenCV's own model comes within
    // 0.82 px (k1) and 0.14 px (k1, k2), so most of the gap is what plumb lines alone can
    // tell, not the model. Bound: 8 % of OpenCV's displacement.
    CHECK(radial_disagreement_px < kMaxDisagreementFraction * board_shift_px);
    CHECK(conversion_floor_px < radial_disagreement_px + 0.5);
  }
}

TEST_CASE("Chessboard plumb lines: one view at a time") {
  REQUIRE_MESSAGE(fs::exists(kDataDir), "missing " << kDataDir.string());
  const Reference reference = ReadReference();
  const std::vector<View> views = DetectLeftViews();
  std::vector<double> k1_values, rms_before, rms_after, disagreements;
  double board_shift_px = 0.0;  // largest displacement of a board corner by OpenCV's model
  for (size_t v = 0; v < views.size(); ++v) {
    std::vector<PlumbLine> lines;
    AppendBoardLines(views[v].corners_px, 0, &lines);
    const PlumbLineSummary summary = EstimateRadialDistortion(lines, Options(reference, false));
    CAPTURE(views[v].name);
    CAPTURE(summary.message);
    REQUIRE(summary.IsUsable());
    k1_values.push_back(summary.distortion.k1);
    rms_before.push_back(summary.initial_rms_px);
    rms_after.push_back(summary.final_rms_px);
    disagreements.push_back(MaxDisagreementPx(summary.distortion, reference, views[v].corners_px, true));
    board_shift_px = std::max(board_shift_px,
                              MaxDisagreementPx(MakeRadialDistortion(kWidthPx, kHeightPx, reference.principal_point_px),
                                                reference, views[v].corners_px, true));
    MESSAGE(views[v].name << ": k1 " << summary.distortion.k1 << " +- " << summary.k1_std << ", straightness "
                          << summary.initial_rms_px << " -> " << summary.final_rms_px
                          << " px, max disagreement with OpenCV's radial undistortion over its board corners "
                          << disagreements.back() << " px");
  }
  MESSAGE("per view: median k1 " << internal::Median(k1_values) << " (min "
                                 << *std::min_element(k1_values.begin(), k1_values.end()) << ", max "
                                 << *std::max_element(k1_values.begin(), k1_values.end()) << "), median straightness "
                                 << internal::Median(rms_before) << " -> " << internal::Median(rms_after)
                                 << " px, median disagreement " << internal::Median(disagreements) << " px");
  CHECK(internal::Median(rms_after) < kMaxStraightnessRmsPx);
  CHECK(internal::Median(disagreements) < kMaxDisagreementFraction * board_shift_px);
}

}  // namespace facet
