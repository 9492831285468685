// Lines found for the user (core/estimators/line_detection.h): detection, grouping and
// calibration of a whole photo, against OpenCV's line segment detector alone on the same grey
// image in the same run (the detector is most of the cost). Photos: the shipped Leuven sample
// (751 x 563) resized to 640 x 480 and to 4000 x 3000 (12 MP, but blurred by the 5.3x upscale:
// LSD finds few long segments on it), and a real 6 MP photo, the Strecha fountain's 0004
// (3072 x 2048, FACET_SHARED_DATA), resized to 4243 x 2829 (12 MP, 1.38x).
#include <benchmark/benchmark.h>

#include <string>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/estimators/line_detection.h"

namespace {

struct Photo {
  facet::ImageRgba8 rgba;
  cv::Mat grey;
};

Photo ReadAt(const std::string& path, int width, int height) {
  const cv::Mat bgr = cv::imread(path);
  if (bgr.empty()) return {};
  cv::Mat resized, rgba;
  cv::resize(bgr, resized, cv::Size(width, height), 0, 0, width > bgr.cols ? cv::INTER_CUBIC : cv::INTER_AREA);
  cv::cvtColor(resized, rgba, cv::COLOR_BGR2RGBA);
  Photo photo;
  photo.rgba.width = width;
  photo.rgba.height = height;
  photo.rgba.pixels.assign(rgba.data, rgba.data + rgba.total() * 4);
  cv::cvtColor(resized, photo.grey, cv::COLOR_BGR2GRAY);
  return photo;
}

const std::string kLeuven = std::string(FACET_SOURCE_DIR) + "/assets/samples/leuven/leuvenA.jpg";
const std::string kFountain = std::string(FACET_SHARED_DATA) + "/strecha-fountain-p11-subset/images/0004.jpg";

const Photo& PhotoFor(int width) {
  static const Photo small = ReadAt(kLeuven, 640, 480);
  static const Photo upscaled = ReadAt(kLeuven, 4000, 3000);
  static const Photo fountain = ReadAt(kFountain, 4243, 2829);
  return width == 640 ? small : width == 4000 ? upscaled : fountain;
}

void BM_DetectManhattanLines(benchmark::State& state) {
  const Photo& photo = PhotoFor(static_cast<int>(state.range(0)));
  if (photo.rgba.empty()) {
    state.SkipWithError("cannot read the photo (Leuven sample, or the fountain in FACET_SHARED_DATA)");
    return;
  }
  facet::ManhattanLinesSummary summary;
  for (auto _ : state)
    benchmark::DoNotOptimize(summary = facet::DetectManhattanLines(photo.rgba, facet::ManhattanLinesOptions{}));
  if (!summary.IsUsable()) state.SkipWithError(summary.message.c_str());
  state.counters["segments"] = static_cast<double>(summary.segments_px.size());
  state.counters["detection_ms"] = summary.detection_ms;
  state.counters["search_ms"] = summary.search_ms;
  state.counters["calibration_ms"] = summary.calibration_ms;
  state.counters["focal_px"] = summary.calibration.focal_px;
}
// Wall time (the detection runs in parallel bands on 2 MP and more) and the CPU time of all threads.
BENCHMARK(BM_DetectManhattanLines)
    ->Arg(640)
    ->Arg(4000)
    ->Arg(4243)
    ->UseRealTime()
    ->MeasureProcessCPUTime()
    ->Unit(benchmark::kMillisecond);

void BM_OpenCvLineSegmentDetector(benchmark::State& state) {
  const Photo& photo = PhotoFor(static_cast<int>(state.range(0)));
  if (photo.grey.empty()) {
    state.SkipWithError("cannot read the photo (Leuven sample, or the fountain in FACET_SHARED_DATA)");
    return;
  }
  std::vector<cv::Vec4f> lines;
  for (auto _ : state) cv::createLineSegmentDetector(cv::LSD_REFINE_STD)->detect(photo.grey, lines);
  state.counters["segments"] = static_cast<double>(lines.size());
}
BENCHMARK(BM_OpenCvLineSegmentDetector)
    ->Arg(640)
    ->Arg(4000)
    ->Arg(4243)
    ->UseRealTime()
    ->MeasureProcessCPUTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace
