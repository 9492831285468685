#include "core/image/corner_detection.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "core/util/timer.h"

namespace facet {

bool CornerDetectionOptions::Check(std::string* error) const {
  if (max_corners < 1) *error = "max_corners must be at least 1";
  else if (!(quality_level > 0.0 && quality_level < 1.0)) *error = "quality_level must lie in (0, 1)";
  else if (!(min_distance_fraction >= 0.0 && min_distance_fraction < 0.5)) *error = "min_distance_fraction must lie in [0, 0.5)";
  else if (detection_max_side_px < 16) *error = "detection_max_side_px must be at least 16";
  else if (refine_half_window_px < 1) *error = "refine_half_window_px must be at least 1";
  else return true;
  return false;
}

CornerDetectionResult DetectCorners(const ImageRgba8& image, const CornerDetectionOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  CornerDetectionResult result;
  std::string error;
  if (!options.Check(&error)) {
    result.error = "invalid corner options: " + error;
    return result;
  }
  if (image.empty() || image.pixels.size() != static_cast<size_t>(image.width) * image.height * 4) {
    result.error = "the photo has no pixels";
    return result;
  }
  const cv::Mat rgba(image.height, image.width, CV_8UC4, const_cast<std::uint8_t*>(image.pixels.data()));
  cv::Mat gray;
  cv::cvtColor(rgba, gray, cv::COLOR_RGBA2GRAY);

  const int longest = std::max(image.width, image.height);
  const double scale = std::min(1.0, static_cast<double>(options.detection_max_side_px) / longest);
  cv::Mat small = gray;
  if (scale < 1.0) cv::resize(gray, small, cv::Size(), scale, scale, cv::INTER_AREA);
  const double diagonal = std::hypot(small.cols, small.rows);
  std::vector<cv::Point2f> found;
  cv::goodFeaturesToTrack(small, found, options.max_corners, options.quality_level,
                          std::max(1.0, options.min_distance_fraction * diagonal));
  if (found.empty()) {
    result.time_ms = internal::MsSince(start);
    return result;
  }
  // Back to full-resolution pixel centres: a pixel centre x in the scaled copy covers
  // (x + 0.5) / scale - 0.5 in the photo.
  for (cv::Point2f& p : found) {
    p.x = static_cast<float>((p.x + 0.5) / scale - 0.5);
    p.y = static_cast<float>((p.y + 0.5) / scale - 0.5);
  }
  const int half = options.refine_half_window_px;
  // The search window must fit inside the photo.
  std::vector<cv::Point2f> refinable;
  for (const cv::Point2f& p : found) {
    if (p.x >= half + 1 && p.y >= half + 1 && p.x < image.width - half - 2 && p.y < image.height - half - 2) {
      refinable.push_back(p);
    }
  }
  if (!refinable.empty()) {
    cv::cornerSubPix(gray, refinable, cv::Size(half, half), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 100, 0.001));
  }
  result.corners_px.reserve(refinable.size());
  for (const cv::Point2f& p : refinable) {
    if (std::isfinite(p.x) && std::isfinite(p.y)) result.corners_px.emplace_back(p.x, p.y);
  }
  result.time_ms = internal::MsSince(start);
  return result;
}

}  // namespace facet
