#include "core/estimators/line_detection.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <future>
#include <limits>
#include <random>
#include <system_error>
#include <thread>

#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>

#include "core/estimators/vanishing_point.h"
#include "core/util/timer.h"

namespace facet {
namespace {

using internal::FailedSummary;
using internal::MsSince;

// Fewer segments than a four-segment minimal set cannot make a hypothesis at all.
constexpr int kMinSegmentsForSearch = 4;
// Two normalised image lines whose cross product is shorter than this are one line: their
// intersection (the would-be vanishing point) is undetermined.
constexpr double kMinLineCrossNorm = 1e-9;

// One detected segment in the conditioned frame of the search: (px - centre) / scale.
struct SearchSegment {
  Eigen::Vector3d a;         // homogeneous endpoint, w = 1
  Eigen::Vector3d midpoint;  // homogeneous, w = 1
  Eigen::Vector3d line;      // a x b, scaled so that (line.x, line.y) is a unit normal
  double length_px = 0.0;
};

// A hypothesis of the search: three orthonormal vanishing directions (camera frame, columns)
// and the focal length, in conditioned units.
struct Frame {
  Eigen::Matrix3d directions = Eigen::Matrix3d::Identity();
  double focal = 0.0;
};

struct SearchSpace {
  std::vector<SearchSegment> segments;
  std::vector<double> cumulative_length;  // for length-weighted sampling
  Eigen::Vector2d center_px = Eigen::Vector2d::Zero();
  double scale_px = 1.0;
  double inlier_distance = 0.0;  // conditioned
  double min_focal = 0.0, max_focal = 0.0;
};

SearchSpace MakeSearchSpace(const std::vector<Eigen::Vector4d>& segments_px, const Eigen::Vector2d& center_px,
                            double scale_px) {
  SearchSpace space;
  space.center_px = center_px;
  space.scale_px = scale_px;
  double total = 0.0;
  for (const Eigen::Vector4d& s : segments_px) {
    SearchSegment seg;
    const Eigen::Vector2d a = (s.head<2>() - center_px) / scale_px;
    const Eigen::Vector2d b = (s.tail<2>() - center_px) / scale_px;
    seg.a = a.homogeneous();
    seg.midpoint = (0.5 * (a + b)).homogeneous();
    seg.line = seg.a.cross(b.homogeneous());
    const double normal = seg.line.head<2>().norm();
    if (normal > 0.0) seg.line /= normal;
    seg.length_px = (s.tail<2>() - s.head<2>()).norm();
    total += seg.length_px;
    space.segments.push_back(seg);
    space.cumulative_length.push_back(total);
  }
  return space;
}

// Squared distance (conditioned) of a segment's endpoint to the line through its midpoint
// and the homogeneous vanishing point v; +infinity when v is the midpoint.
double SquaredResidual(const SearchSegment& s, const Eigen::Vector3d& v) {
  const Eigen::Vector3d through = s.midpoint.cross(v);
  const double normal2 = through.head<2>().squaredNorm();
  if (!(normal2 > 1e-30)) return std::numeric_limits<double>::infinity();
  const double d = through.dot(s.a);
  return d * d / normal2;
}

// Vanishing points (conditioned, homogeneous) of a frame: K d with K = diag(f, f, 1).
std::array<Eigen::Vector3d, 3> FrameVanishingPoints(const Frame& frame) {
  std::array<Eigen::Vector3d, 3> v;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d d = frame.directions.col(k);
    v[k] = Eigen::Vector3d(frame.focal * d.x(), frame.focal * d.y(), d.z());
  }
  return v;
}

// MSAC: sum over segments of length * (1 - (r / t)^2) for the nearest vanishing point within t.
double ScoreFrame(const SearchSpace& space, const Frame& frame) {
  const std::array<Eigen::Vector3d, 3> v = FrameVanishingPoints(frame);
  const double t2 = space.inlier_distance * space.inlier_distance;
  double score = 0.0;
  for (const SearchSegment& s : space.segments) {
    const double r2 = std::min({SquaredResidual(s, v[0]), SquaredResidual(s, v[1]), SquaredResidual(s, v[2])});
    if (r2 < t2) score += s.length_px * (1.0 - r2 / t2);
  }
  return score;
}

class Sampler {
 public:
  Sampler(const SearchSpace& space, std::uint32_t seed) : space_(space), random_(seed) {}

  // A segment index drawn with probability proportional to its length.
  int Segment() {
    const double total = space_.cumulative_length.back();
    const double u = std::uniform_real_distribution<double>(0.0, total)(random_);
    const auto it = std::upper_bound(space_.cumulative_length.begin(), space_.cumulative_length.end(), u);
    return static_cast<int>(std::min<std::ptrdiff_t>(it - space_.cumulative_length.begin(),
                                                     static_cast<std::ptrdiff_t>(space_.segments.size()) - 1));
  }

  // The intersection of two distinct segments that are not on one line (within the inlier
  // distance), conditioned and normalised; false when the draw is unusable.
  bool VanishingPoint(Eigen::Vector3d* v) {
    const int i = Segment(), j = Segment();
    if (i == j) return false;
    const SearchSegment& a = space_.segments[i];
    const SearchSegment& b = space_.segments[j];
    if (std::abs(a.line.dot(b.midpoint)) < space_.inlier_distance &&
        std::abs(b.line.dot(a.midpoint)) < space_.inlier_distance)
      return false;  // pieces of one line: their intersection is noise
    *v = a.line.cross(b.line);
    const double n = v->norm();
    if (!(n > kMinLineCrossNorm)) return false;
    *v /= n;
    return true;
  }

  double LogUniform(double lo, double hi) {
    return std::exp(std::uniform_real_distribution<double>(std::log(lo), std::log(hi))(random_));
  }
  double Gaussian(double mean, double std) { return std::normal_distribution<double>(mean, std)(random_); }

 private:
  const SearchSpace& space_;
  std::mt19937 random_;
};

// Four segments: two vanishing points, f from their orthogonality, the third by the cross
// product. Needs both points finite.
bool FourSegmentFrame(Sampler* sampler, const SearchSpace& space, Frame* frame) {
  Eigen::Vector3d v1, v2;
  if (!sampler->VanishingPoint(&v1) || !sampler->VanishingPoint(&v2)) return false;
  const double w = v1.z() * v2.z();
  if (std::abs(w) < 1e-12) return false;
  const double f2 = -(v1.x() * v2.x() + v1.y() * v2.y()) / w;
  if (!(f2 > space.min_focal * space.min_focal && f2 < space.max_focal * space.max_focal)) return false;
  const double f = std::sqrt(f2);
  const Eigen::Vector3d d1 = Eigen::Vector3d(v1.x(), v1.y(), f * v1.z()).normalized();
  const Eigen::Vector3d d2 = Eigen::Vector3d(v2.x(), v2.y(), f * v2.z()).normalized();
  const Eigen::Vector3d d3 = d1.cross(d2);
  if (!(d3.norm() > 0.5)) return false;
  frame->directions.col(0) = d1;
  frame->directions.col(2) = d3.normalized();
  frame->directions.col(1) = frame->directions.col(2).cross(d1);
  frame->focal = f;
  return true;
}

// Three segments and a focal length: a vanishing direction from two, the second direction
// orthogonal to it in the third's back-projected plane.
bool ThreeSegmentFrame(Sampler* sampler, const SearchSpace& space, double focal, Frame* frame) {
  Eigen::Vector3d v1;
  if (!sampler->VanishingPoint(&v1)) return false;
  const SearchSegment& third = space.segments[sampler->Segment()];
  const Eigen::Vector3d d1 = Eigen::Vector3d(v1.x(), v1.y(), focal * v1.z()).normalized();
  const Eigen::Vector3d plane_normal(focal * third.line.x(), focal * third.line.y(), third.line.z());
  Eigen::Vector3d d2 = d1.cross(plane_normal.normalized());
  if (!(d2.norm() > 1e-3)) return false;  // the third segment points at v1 itself
  d2.normalize();
  frame->directions.col(0) = d1;
  frame->directions.col(1) = d2;
  frame->directions.col(2) = d1.cross(d2);
  frame->focal = focal;
  return true;
}

// Columns of the frame reordered to x, y, z by the header's naming rule.
Eigen::Matrix3d NameAxes(const Eigen::Matrix3d& d) {
  int z = 0;
  for (int k = 1; k < 3; ++k)
    if (std::abs(d(1, k)) > std::abs(d(1, z))) z = k;
  int x = (z + 1) % 3, y = (z + 2) % 3;
  if (std::abs(d(0, y)) > std::abs(d(0, x))) std::swap(x, y);
  Eigen::Matrix3d named;
  named << d.col(x), d.col(y), d.col(z);
  return named;
}

// Homogeneous pixel vanishing points K R e_axis of a camera.
std::array<Eigen::Vector3d, 3> PixelVanishingPoints(double focal_px, const Eigen::Vector2d& pp_px,
                                                    const Eigen::Matrix3d& directions) {
  Eigen::Matrix3d k = Eigen::Matrix3d::Identity();
  k(0, 0) = k(1, 1) = focal_px;
  k(0, 2) = pp_px.x();
  k(1, 2) = pp_px.y();
  std::array<Eigen::Vector3d, 3> v;
  for (int a = 0; a < 3; ++a) v[a] = (k * directions.col(a)).normalized();
  return v;
}

// Each segment to the vanishing point it is nearest to within inlier_px, -1 when none is
// or when a second one is too (ambiguous).
std::vector<int> AssignSegments(const std::vector<Eigen::Vector4d>& segments_px,
                                const std::array<Eigen::Vector3d, 3>& vps_px, double inlier_px) {
  std::vector<int> family(segments_px.size(), -1);
  for (size_t i = 0; i < segments_px.size(); ++i) {
    int best = -1, within = 0;
    double best_r = inlier_px;
    for (int a = 0; a < 3; ++a) {
      const double r = SegmentVanishingPointResidualPx(segments_px[i], vps_px[a]);
      if (!(r < inlier_px)) continue;
      ++within;
      if (r < best_r || best < 0) {
        best_r = r;
        best = a;
      }
    }
    family[i] = within == 1 ? best : -1;
  }
  return family;
}

// Drops families with too few segments (their members become outliers); returns how many
// families remain.
int DropSmallFamilies(int min_segments, std::vector<int>* family, std::array<int, 3>* counts) {
  *counts = {0, 0, 0};
  for (int f : *family)
    if (f >= 0) ++(*counts)[f];
  int present = 0;
  for (int a = 0; a < 3; ++a) {
    if ((*counts)[a] >= min_segments) {
      ++present;
      continue;
    }
    for (int& f : *family)
      if (f == a) f = -1;
    (*counts)[a] = 0;
  }
  return present;
}

std::vector<Segment> LabelledSegments(const std::vector<Eigen::Vector4d>& segments_px, const std::vector<int>& family) {
  std::vector<Segment> labelled;
  for (size_t i = 0; i < segments_px.size(); ++i) {
    if (family[i] < 0) continue;
    Segment s;
    s.axis = static_cast<Axis>(family[i]);
    s.a_px = segments_px[i].head<2>();
    s.b_px = segments_px[i].tail<2>();
    labelled.push_back(s);
  }
  return labelled;
}

// Photos of this many pixels or more are detected in horizontal bands, in parallel; the
// band count is fixed (not the machine's thread count) so that every machine finds the same
// segments.
constexpr double kBandedMinPixels = 2.0e6;
constexpr int kBands = 4;
// Pieces of one line cut by a band boundary: LSD leaves a pixel or two at an image border,
// so each piece ends within this many rows of the boundary, and the two pieces lie on one
// line within LSD's accuracy.
constexpr double kBoundaryReachPx = 4.0;
constexpr double kPieceLineDistancePx = 1.5;
constexpr double kPieceMaxAngleRad = 2.0 * M_PI / 180.0;

// The segment with endpoints ordered by image row (top first).
Eigen::Vector4d TopFirst(const Eigen::Vector4d& s) {
  return s[1] <= s[3] ? s : Eigen::Vector4d(s[2], s[3], s[0], s[1]);
}

double DistanceToLine(const Eigen::Vector4d& s, const Eigen::Vector2d& p) {
  const Eigen::Vector2d d = (s.tail<2>() - s.head<2>()).normalized();
  const Eigen::Vector2d r = p - s.head<2>();
  return std::abs(d.x() * r.y() - d.y() * r.x());
}

// Joins the pieces of lines that cross row `boundary`: `above` ends there, `below` starts
// there. A joined line replaces its piece in `below` (so it can be joined again at the next
// boundary); its piece in `above` is removed.
void JoinAcrossBoundary(double boundary, std::vector<Eigen::Vector4d>* above, std::vector<Eigen::Vector4d>* below) {
  std::vector<bool> above_used(above->size(), false), below_used(below->size(), false);
  for (size_t i = 0; i < above->size(); ++i) {
    const Eigen::Vector4d a = TopFirst((*above)[i]);
    if (a[3] < boundary - kBoundaryReachPx) continue;
    const Eigen::Vector2d da = (a.tail<2>() - a.head<2>()).normalized();
    int best = -1;
    double best_distance = kPieceLineDistancePx;
    for (size_t j = 0; j < below->size(); ++j) {
      if (below_used[j]) continue;
      const Eigen::Vector4d b = TopFirst((*below)[j]);
      if (b[1] > boundary + kBoundaryReachPx) continue;
      const Eigen::Vector2d db = (b.tail<2>() - b.head<2>()).normalized();
      if (std::abs(da.x() * db.y() - da.y() * db.x()) > std::sin(kPieceMaxAngleRad) || da.dot(db) < 0.0) continue;
      const double distance = std::max(DistanceToLine(a, b.head<2>()), DistanceToLine(b, a.tail<2>()));
      if (distance < best_distance) {
        best_distance = distance;
        best = static_cast<int>(j);
      }
    }
    if (best < 0) continue;
    const Eigen::Vector4d b = TopFirst((*below)[best]);
    (*below)[best] = Eigen::Vector4d(a[0], a[1], b[2], b[3]);
    below_used[best] = true;
    above_used[i] = true;
  }
  std::vector<Eigen::Vector4d> kept;
  for (size_t i = 0; i < above->size(); ++i)
    if (!above_used[i]) kept.push_back((*above)[i]);
  *above = std::move(kept);
}

}  // namespace

std::vector<Eigen::Vector4d> DetectLineSegments(const ImageRgba8& image, const LineDetectionOptions& options) {
  std::vector<Eigen::Vector4d> segments;
  if (image.empty() || image.pixels.size() < static_cast<size_t>(image.width) * image.height * 4) return segments;
  const cv::Mat rgba(image.height, image.width, CV_8UC4, const_cast<std::uint8_t*>(image.pixels.data()));

  // LSD is local (regions grown from pixel gradients), so bands of a large photo can be
  // detected on their own, in parallel; lines cut by a band boundary are joined again.
  const int bands = static_cast<double>(image.width) * image.height >= kBandedMinPixels ? kBands : 1;
  std::vector<int> band_start(bands + 1);
  for (int b = 0; b <= bands; ++b) band_start[b] = static_cast<int>(static_cast<long>(image.height) * b / bands);
  std::vector<std::vector<Eigen::Vector4d>> found(bands);
  // Each band is converted to grey and detected by whichever thread claims it next (the
  // bands differ in cost by up to ~1.5x on real photos). Our own threads rather than
  // cv::parallel_for_: OpenCV runs a parallel_for_ serially while any other thread of the
  // process is inside one (one global flag), which in the app is often the case (the
  // snapping worker's detection, the bake).
  std::atomic<int> next_band{0};
  auto detect_bands = [&] {
    for (int b = next_band++; b < bands; b = next_band++) {
      cv::Mat grey;
      cv::cvtColor(rgba.rowRange(band_start[b], band_start[b + 1]), grey, cv::COLOR_RGBA2GRAY);
      std::vector<cv::Vec4f> lines;
      cv::createLineSegmentDetector(cv::LSD_REFINE_STD)->detect(grey, lines);
      for (const cv::Vec4f& l : lines) found[b].emplace_back(l[0], l[1] + band_start[b], l[2], l[3] + band_start[b]);
    }
  };
  // At most one band per core (each band's LSD buffers are ~40 bytes per pixel); this thread
  // is one of the workers.
  const int threads = std::min(bands, std::max(1, static_cast<int>(std::thread::hardware_concurrency())));
  std::vector<std::future<void>> helpers;
  for (int t = 1; t < threads; ++t) {
    try {
      helpers.push_back(std::async(std::launch::async, detect_bands));
    } catch (const std::system_error&) {
      break;  // no thread to be had: the bands left are detected here
    }
  }
  detect_bands();
  for (std::future<void>& helper : helpers) helper.get();  // rethrows an OpenCV exception of a band
  // A boundary at row r lies between pixel rows r - 1 and r: at r - 0.5 in pixel-centre units.
  for (int b = 0; b + 1 < bands; ++b) JoinAcrossBoundary(band_start[b + 1] - 0.5, &found[b], &found[b + 1]);

  const double min_length = options.min_length_rel_diagonal * std::hypot(image.width, image.height);
  for (const auto& band : found)
    for (const Eigen::Vector4d& s : band)
      if ((s.tail<2>() - s.head<2>()).norm() >= min_length) segments.push_back(s);
  return segments;
}

ManhattanLinesSummary GroupManhattanLines(const std::vector<Eigen::Vector4d>& segments_px,
                                          const ManhattanLinesOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  ManhattanLinesSummary summary;
  const VpCalibrationOptions& cal = options.calibration;
  summary.width_px = cal.width_px;
  summary.height_px = cal.height_px;
  summary.segments_px = segments_px;
  summary.segment_family.assign(segments_px.size(), -1);
  summary.num_outliers = static_cast<int>(segments_px.size());
  if (cal.width_px <= 0 || cal.height_px <= 0)
    return FailedSummary(summary, "the image size is not set", start, SolverTermination::kInvalidInput);
  if (!(options.inlier_distance_rel_diagonal > 0.0) || !(options.min_focal_rel_diagonal > 0.0) ||
      !(options.max_focal_rel_diagonal > options.min_focal_rel_diagonal) || options.num_hypotheses < 1 ||
      options.min_segments_per_family < 2)
    return FailedSummary(summary, "invalid line grouping options", start, SolverTermination::kInvalidInput);
  for (const Eigen::Vector4d& s : segments_px)
    if (!s.allFinite() || s.head<2>() == s.tail<2>())
      return FailedSummary(summary, "a segment is degenerate (zero length or not finite)", start,
                           SolverTermination::kInvalidInput);

  const double diagonal = std::hypot(cal.width_px, cal.height_px);
  summary.inlier_distance_px = std::max(1.0, options.inlier_distance_rel_diagonal * diagonal);
  summary.min_length_px = options.detection.min_length_rel_diagonal * diagonal;
  if (static_cast<int>(segments_px.size()) < kMinSegmentsForSearch) {
    char text[200];
    std::snprintf(text, sizeof(text),
                  "too few line segments to find vanishing directions: %d of length >= %.0f px (at least %d needed)",
                  static_cast<int>(segments_px.size()), summary.min_length_px, kMinSegmentsForSearch);
    return FailedSummary(summary, text, start);
  }

  // The search.
  const Eigen::Vector2d center_px = cal.principal_point_mode == PrincipalPointMode::kFixed
                                        ? cal.fixed_principal_point_px
                                        : Eigen::Vector2d(0.5 * (cal.width_px - 1), 0.5 * (cal.height_px - 1));
  const double scale_px = 0.5 * diagonal;
  SearchSpace space = MakeSearchSpace(segments_px, center_px, scale_px);
  space.inlier_distance = summary.inlier_distance_px / scale_px;
  space.min_focal = options.min_focal_rel_diagonal * diagonal / scale_px;
  space.max_focal = options.max_focal_rel_diagonal * diagonal / scale_px;
  Sampler sampler(space, options.seed);
  Frame best;
  double best_score = 0.0;
  const bool fixed_focal = cal.fixed_focal_px > 0.0;
  const bool focal_prior = cal.focal_prior_px > 0.0 && cal.focal_prior_std_px > 0.0;
  for (int h = 0; h < options.num_hypotheses; ++h) {
    Frame frame;
    bool made = false;
    if (!fixed_focal && h % 2 == 1) {
      made = FourSegmentFrame(&sampler, space, &frame);
    } else {
      double focal = 0.0;
      if (fixed_focal) {
        focal = cal.fixed_focal_px / scale_px;
      } else if (focal_prior) {
        focal = sampler.Gaussian(cal.focal_prior_px, cal.focal_prior_std_px) / scale_px;
        focal = std::clamp(focal, space.min_focal, space.max_focal);
      } else {
        focal = sampler.LogUniform(space.min_focal, space.max_focal);
      }
      made = ThreeSegmentFrame(&sampler, space, focal, &frame);
    }
    if (!made) continue;
    ++summary.num_hypotheses_scored;
    const double score = ScoreFrame(space, frame);
    if (score > best_score) {
      best_score = score;
      best = frame;
    }
  }
  summary.search_score = best_score;
  summary.search_focal_px = best.focal * scale_px;
  summary.search_ms = MsSince(start);
  if (!(best_score > 0.0)) return FailedSummary(summary, "no orthogonal vanishing directions fit the segments", start);

  // Assignment to the best frame, calibration, reassignment to the fitted camera, final fit.
  const auto calibrate_start = std::chrono::steady_clock::now();
  std::vector<int> family =
      AssignSegments(segments_px, PixelVanishingPoints(best.focal * scale_px, center_px, NameAxes(best.directions)),
                     summary.inlier_distance_px);
  std::array<int, 3> counts{};
  if (DropSmallFamilies(options.min_segments_per_family, &family, &counts) < 2) {
    summary.calibration_ms = MsSince(calibrate_start);
    return FailedSummary(summary,
                         "only one vanishing direction found in the line segments: two or three are needed "
                         "(a photo of a flat facade seen head-on, or of one set of parallel lines, has too few)",
                         start);
  }
  VpCalibrationOptions cal_options = cal;
  VpCalibrationSummary fit = CalibrateFromVanishingLines(LabelledSegments(segments_px, family), cal_options);
  if (fit.IsUsable()) {
    std::vector<int> refined = AssignSegments(
        segments_px, PixelVanishingPoints(fit.focal_px, fit.principal_point_px, fit.cam_from_world_rotation),
        summary.inlier_distance_px);
    std::array<int, 3> refined_counts{};
    if (DropSmallFamilies(options.min_segments_per_family, &refined, &refined_counts) >= 2) {
      VpCalibrationSummary refit = CalibrateFromVanishingLines(LabelledSegments(segments_px, refined), cal_options);
      if (refit.IsUsable()) {
        fit = std::move(refit);
        family = std::move(refined);
        counts = refined_counts;
      }
    }
  }
  summary.calibration_ms = MsSince(calibrate_start);
  summary.segment_family = family;
  summary.labelled_segments = LabelledSegments(segments_px, family);
  summary.segments_per_family = counts;
  summary.num_outliers = static_cast<int>(std::count(family.begin(), family.end(), -1));
  summary.termination = fit.termination;
  summary.iterations = fit.iterations;
  summary.initial_cost = fit.initial_cost;
  summary.final_cost = fit.final_cost;
  summary.warnings = fit.warnings;
  char text[200];
  std::snprintf(text, sizeof(text), "%d line segments: x %d, y %d, z %d, %d outliers; ",
                static_cast<int>(segments_px.size()), counts[0], counts[1], counts[2], summary.num_outliers);
  summary.message = text + fit.message;
  summary.calibration = std::move(fit);
  summary.time_ms = MsSince(start);
  return summary;
}

ManhattanLinesSummary DetectManhattanLines(const ImageRgba8& image, const ManhattanLinesOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  if (image.empty() || image.pixels.size() < static_cast<size_t>(image.width) * image.height * 4) {
    ManhattanLinesSummary summary;
    return FailedSummary(summary, "the image is empty", start, SolverTermination::kInvalidInput);
  }
  const std::vector<Eigen::Vector4d> segments = DetectLineSegments(image, options.detection);
  const double detection_ms = MsSince(start);
  ManhattanLinesOptions grouping = options;
  grouping.calibration.width_px = image.width;
  grouping.calibration.height_px = image.height;
  ManhattanLinesSummary summary = GroupManhattanLines(segments, grouping);
  summary.detection_ms = detection_ms;
  summary.time_ms = MsSince(start);
  return summary;
}

}  // namespace facet
