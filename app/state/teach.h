// Teach mode (View > Teach, issue 15): overlays and numbers that show the geometry behind
// Facet's results, for a course. What each overlay draws is computed here, from the app state
// alone, by the functions below; the panels draw exactly that and the render report writes
// the same values, so tests check the drawn construction against the truth.
// Teach settings are view settings: not in the project, not undoable, all off at start.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/geometry/ids.h"
#include "core/geometry/vanishing_construction.h"
#include "core/scene/modelling_state.h"

namespace facet::app {

struct AppState;

struct TeachView {
  bool vanishing_points = false;  // the construction on the photo, vanishing directions in 3D
  bool epipolar = false;          // epipolar lines and epipoles of a selected pin or the pointer
  bool numbers = false;           // the Numbers window: K, R, t, F with copy buttons
  bool modelling_state = false;   // the (K, F) counts per History entry
  Id second_image_id = kNoId;     // F between the active image and this one (Numbers window)
  // HistoryStateCounts of the document at history_counts_revision (Document::revision()).
  std::vector<ModellingStateCounts> history_counts;
  std::uint64_t history_counts_revision = ~std::uint64_t{0};
};

// Names of the overlays for menus and the `command teach NAME on|off` of input scripts:
// "vanishing", "epipolar", "numbers", "state". Null for an unknown name.
bool* TeachFlag(TeachView* view, const std::string& name);

// The vanishing-point overlay of one image: the construction on each family's own fitted
// point (the calibration's closed form), the points' covariances, and what is assumed.
struct TeachVanishing {
  Id image_id = kNoId;
  VanishingConstruction construction;
  std::array<Eigen::Vector3d, 3> vanishing_points_px{};  // its input: homogeneous, zero if absent
  std::array<Eigen::Matrix2d, 3> covariance_px2{};  // NaN where unknown (2 segments, at infinity)
  // One sentence each, shown beside the construction: "principal point assumed at the image
  // centre (...)", "focal length known: ...", "horizon given".
  std::vector<std::string> assumptions;
  // The camera after the joint fit of all segments (and the pins), for comparison.
  double fitted_focal_px = 0.0;
  double fitted_focal_std_px = 0.0;
  Eigen::Vector2d fitted_principal_point_px = Eigen::Vector2d::Zero();
  // Vanishing directions as rays in the world from the camera centre (unit; zero if absent).
  Eigen::Vector3d camera_center_in_world = Eigen::Vector3d::Zero();
  std::array<Eigen::Vector3d, 3> directions_in_world{};
};
// Empty when the image has no usable calibration from line families.
std::optional<TeachVanishing> TeachVanishingFor(const AppState& state, Id image_id);

// An epipolar line the overlay draws in image `in_image_id`, of the point uv_px of image
// `from_image_id` (a pin of a selected vertex, or the pointer).
struct TeachEpipolarLine {
  Id from_image_id = kNoId;
  Id in_image_id = kNoId;
  Eigen::Vector2d from_uv_px = Eigen::Vector2d::Zero();
  bool from_pointer = false;  // else from a pin
  Id pin_id = kNoId;
  Eigen::Vector3d line = Eigen::Vector3d::Zero();  // l . (u, v, 1) = 0, (l0, l1) unit
  Eigen::Vector3d epipole = Eigen::Vector3d::Zero();  // in in_image_id, homogeneous
  // The same vertex's pin in in_image_id and its distance to the line (px); NaN when none.
  double pin_distance_px = std::numeric_limits<double>::quiet_NaN();
};
// The lines for the selected pins' vertices (pins in one image drawn in every other calibrated
// image) and for the pointer over a calibrated image (drawn in every other calibrated image).
std::vector<TeachEpipolarLine> TeachEpipolarLines(const AppState& state);

// The Numbers window's matrices: of the active image's camera and, with a second calibrated
// image, F (uv_b^T F uv_a = 0, a the active image, b the second; unit Frobenius norm, largest
// entry positive) and the epipoles.
struct TeachNumbers {
  Id image_id = kNoId;
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();  // cam_from_world
  Eigen::Vector3d t = Eigen::Vector3d::Zero();      // cam_from_world
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  // -R^T t
  Id second_image_id = kNoId;                        // kNoId: no F
  Eigen::Matrix3d F = Eigen::Matrix3d::Zero();
  Eigen::Vector3d epipole_in_a = Eigen::Vector3d::Zero();
  Eigen::Vector3d epipole_in_b = Eigen::Vector3d::Zero();
};
// Empty when the active image is not calibrated.
std::optional<TeachNumbers> TeachNumbersFor(const AppState& state);

// Refreshes state->teach.history_counts when the document changed.
void UpdateTeachHistoryCounts(AppState* state);

}  // namespace facet::app
