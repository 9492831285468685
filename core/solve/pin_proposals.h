// Pins proposed across photos (issue 26): a vertex pinned in one calibrated photo A and seen
// by another calibrated photo B gets a proposed pin in B, so that each extra photo does not
// cost every pin again. The pin in A fixes a ray; the model fixes roughly where on it the
// vertex is. Along the epipolar line in B of the pin, over the depths the model allows, the
// window around the pin in A is warped into B (by the homography of each modelled face
// through the vertex, a fronto-parallel plane where there is none) and compared by normalised
// cross-correlation (NCC). The best peak is refined to sub-pixel by a quadratic (a parabola
// along and across the line, with their cross term) fitted to the NCC on a 3 x 3 grid about
// it, at finer grids in turn, and kept only when it is unique (no second peak nearly as good further
// along the line) and, where a third calibrated photo sees the point, consistent there (the
// point triangulated from A and B lands on that photo's pin, or on a good NCC peak).
//
// Pixels are camera px (core/geometry/conventions.h) of each image's camera; the grey photos
// may be smaller than the cameras' images (a working resolution, GrayFromRgba's shrink): a
// camera px uv is photo px (uv + 0.5) * photo.width / camera.width_px - 0.5. Windows and
// search steps are in the photos' px.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/geometry/camera.h"
#include "core/geometry/ids.h"
#include "core/image/gray_image.h"
#include "core/scene/project.h"

namespace facet {

struct PinProposalOptions {
  // The window around the pin in A: (2 h + 1)^2 samples, one per photo px of A.
  int window_half_px = 7;
  // The depths searched along A's ray: the model's depth d0 of the vertex times
  // [1 - fraction, 1 + fraction] ...
  double depth_range_fraction = 0.15;
  // ... and at least this far (photo px of B) either side of the model's own projection, at
  // most max_search_half_px.
  double min_search_half_px = 6.0;
  double max_search_half_px = 200.0;
  // A's window must vary: its grey levels' standard deviation at least this (0-255 scale).
  double min_window_std = 3.0;
  // A face is compared in a photo only when seen at least this steeply there (cosine of the
  // angle between its normal and the direction to the camera): a face seen edge on shows its
  // texture squeezed into a few pixels.
  double min_view_cos = 0.25;
  // With faces given, only the window's samples on them are compared (the rest is what the
  // model does not hold: sky, another building); with fewer than this share of the window on
  // them, the fronto-parallel plane warps the whole window instead.
  double min_face_fraction = 0.15;
  // Share of those samples that must be compared at a position (inside B's photo, on a face
  // that B sees), else the position is not scored.
  double min_compared_fraction = 0.6;
  // A proposal's NCC at its peak.
  double min_score = 0.8;
  // 1 - second / best, the second best peak (a local maximum of the NCC along the line) more
  // than unique_radius_px from the best: periodic texture has a second peak nearly as good.
  double min_uniqueness = 0.1;
  double unique_radius_px = 3.0;
  // A third photo that sees the point: with its own pin there, the triangulated point must
  // project within check_pin_max_px of it; without, the best NCC within check_radius_px of
  // its projection must reach check_min_score.
  double check_pin_max_px = 3.0;
  double check_radius_px = 2.0;
  double check_min_score = 0.6;

  bool Check(std::string* error) const;
};

// Why a vertex gets no proposal in B.
enum class PinProposalRefusal {
  kNone,             // proposed
  kBehindCamera,     // the vertex is behind B's camera
  kOutsidePhoto,     // it projects outside B's photo (or too near its border for the window)
  kFacesAway,        // every face at the vertex turns away from B (or is seen edge on)
  kOccluded,         // another face of the model is in front of it from B
  kNoBaseline,       // A and B share a centre: the line is a point
  kFlatWindow,       // A's window has too little texture to match
  kNoMatch,          // no position on the line compared enough of the window
  kLowScore,         // the best NCC is below min_score
  kPeakAtSearchEnd,  // the best NCC is at an end of the searched depths: the match lies beyond
  kNotUnique,        // a second peak nearly as good (periodic texture)
  kInconsistent,     // a third photo disagrees
};
const char* PinProposalRefusalName(PinProposalRefusal refusal);  // "not unique", ...

// One photo as the matcher sees it.
struct ProposalView {
  Id image_id = kNoId;
  const Camera* camera = nullptr;         // calibrated
  const GrayImage* photo = nullptr;       // the same aspect as camera's image
  std::optional<Eigen::Vector2d> pin_px;  // the point's pin in this photo (camera px), if any
};

// A modelled planar face through the point (world), whose homography warps the part of A's
// window it covers.
struct ProposalFace {
  std::vector<Eigen::Vector3d> corners_in_world;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // unit, outward
};

struct PointMatch {
  Eigen::Vector2d uv_px = Eigen::Vector2d::Zero();  // in B, camera px (also when refused, if matched)
  double score = -1.0;                              // NCC at the refined peak, in [-1, 1]
  double second_score = -1.0;                       // best other local maximum beyond unique_radius_px (-1: none)
  double uniqueness = 0.0;                          // 1 - max(second_score, 0) / score
  int checked_views = 0;                            // third photos that confirmed it
  int searched_px = 0;                              // positions compared along the line
  PinProposalRefusal refusal = PinProposalRefusal::kNone;
  std::string reason;  // empty when proposed
  bool Proposed() const { return refusal == PinProposalRefusal::kNone; }
};

// Matches the point pinned in `a` (a.pin_px set) along its epipolar line in `b`, around
// `x_estimate_in_world` (the model's current position of the point; its depth along A's ray
// centres the search). `faces`: the modelled faces through the point (empty: a fronto-parallel
// plane to A). `checks`: further photos for the consistency test (those that do not see the
// point are skipped). Needs no project: the real-data suite calls it with points alone.
PointMatch MatchPointAlongEpipolar(const ProposalView& a, const ProposalView& b,
                                   const std::vector<ProposalView>& checks, const Eigen::Vector3d& x_estimate_in_world,
                                   const std::vector<ProposalFace>& faces, const PinProposalOptions& options);

struct PinProposal {
  VertexRef vertex;
  Id image_id = kNoId;         // B: where the pin is proposed
  Id source_image_id = kNoId;  // A: the photo whose pin was matched
  Id source_pin_id = kNoId;
  PointMatch match;
  bool Proposed() const { return match.Proposed(); }
};

struct PinProposalSummary {
  Id image_id = kNoId;
  // One entry per vertex pinned in another calibrated photo with a loaded photo and not
  // pinned in B, in the order of their first pins; proposed and refused.
  std::vector<PinProposal> proposals;
  int proposed = 0;
  double time_ms = 0.0;
  std::string error;  // empty when the proposals could be computed (B calibrated, its photo)
  bool IsUsable() const { return error.empty(); }
};

// The grey photo of an image (null when it is not loaded).
using GrayPhotoLookup = std::function<const GrayImage*(Id image_id)>;

// Proposals in image `image_id` for the vertices pinned elsewhere: checks that B sees the
// vertex (in front, inside the photo, a face at it turned to B, no other face in front), picks
// as A the photo with a pin of it whose view of it is nearest B's, and matches
// (MatchPointAlongEpipolar) with the vertex's faces and every other calibrated photo as checks.
PinProposalSummary ProposePins(const Project& project, Id image_id, const GrayPhotoLookup& photo_of,
                               const PinProposalOptions& options = {});

}  // namespace facet
