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
#include "core/geometry/ray_pair.h"
#include "core/geometry/vanishing_construction.h"
#include "core/scene/modelling_state.h"
#include "core/estimators/fit_steps.h"
#include "core/solve/joint_solve_steps.h"
#include "core/texture/textured_mesh.h"

namespace facet::app {

struct AppState;

// Where the Solver steps window starts stepping from.
//   kPerturbed (the default): the document's project moved off its answer by PerturbForSteps
//     (core/solve/joint_solve_steps.h). A lecturer needs a start a visible distance from the
//     answer (residual vectors of tens of px, a cost falling over several orders of magnitude),
//     the same in every lecture and on every machine, with the distance in their hands (the
//     amount), and on any project: the document itself is always already solved, so stepping
//     it shows nothing. The joint solve's cold start is no better for this: it is the geometry
//     solve's own converged result (a linear initialisation followed by its Levenberg-Marquardt
//     run on the pins), so stepping from it shows only the last few iterations, and projects
//     over 300 parameters have none.
//   kAsIs: the document's project as it is (after an edit whose solve stopped early, or to show
//     that a converged solve takes one step and stops).
enum class TeachStepStart { kPerturbed, kAsIs };
const char* TeachStepStartName(TeachStepStart start);  // "perturbed", "as-is"
std::optional<TeachStepStart> TeachStepStartFromName(const std::string& name);

// What the Solver steps window steps: the joint solve (the project), the vanishing-point fit
// of the active photo, or the two-view refinement of F for the active photo and the second
// photo (core/estimators/fit_steps.h).
enum class TeachStepSubject { kJointSolve, kVanishingPoints, kTwoView };
const char* TeachStepSubjectName(TeachStepSubject subject);  // "joint", "vanishing", "two-view"
std::optional<TeachStepSubject> TeachStepSubjectFromName(const std::string& name);

// The vanishing-point fit of one photo stepped: from the window's start (perturbed: the fit's
// answer moved off by `perturbation`; as is: the fit's closed form), one round on the photo's
// segments as the calibration step reads them (straightened by the camera's distortion, if
// any). The document is never changed; the overlay draws the stepped vanishing points, their
// paths and each segment's residual.
struct TeachVpSteps {
  Id image_id = kNoId;
  std::optional<VpFitSteps> steps;
  std::vector<Id> segment_ids;  // per stepped segment, the project's segment
  // Residuals drawn this many times their length; fixed when stepping begins (the start's
  // largest residual drawn 6 % of the photo's diagonal, rounded to 1, 2 or 5 x 10^k).
  double residual_scale = 1.0;
};

// The two-view refinement stepped for the active photo (a) and the second photo (b), from the
// window's start (perturbed: the refined F moved off by `perturbation`; as is: the 8-point
// estimate): the matches are the pins of one vertex in both (7 or more), the stepped ones the
// inliers of a full estimate (RANSAC is not an iteration of the refinement).
struct TeachTwoViewSteps {
  Id image_a = kNoId, image_b = kNoId;
  std::optional<FundamentalFitSteps> steps;
  std::vector<Id> pins_a, pins_b;  // per stepped match
};

// The joint solve stepped one Levenberg-Marquardt iteration at a time (View > Teach > Solver
// steps). Stepping never edits the document: the image and 3D panels draw `steps->current`
// instead of the document's project while it exists, and the steps are dropped (the panels
// show the document again) when the document changes or the window closes.
struct TeachSolverSteps {
  TeachStepSubject subject = TeachStepSubject::kJointSolve;
  TeachVpSteps vp;            // subject kVanishingPoints
  TeachTwoViewSteps two_view;  // subject kTwoView
  TeachStepStart start = TeachStepStart::kPerturbed;
  // PerturbForSteps' amount, and the fits' (core/estimators/fit_steps.h). 0.2 (each camera
  // turned by 4 degrees): on the Leuven street the first two steps still leave residuals of
  // tens of px before the quadratic convergence shows (observation cost 48308, 8642, 1169,
  // 72.8, 72.2 px^2); from 0.05 the first step is already nearly the answer, which shows less.
  double perturbation = 0.2;
  // Begun by the first Step: empty while the panels show the document.
  std::optional<JointSolveSteps> steps;
  std::uint64_t document_revision = 0;  // Document::revision() the steps start from
  // The residual vectors are drawn this many times their length. Fixed when stepping begins
  // (the start's largest residual drawn 8 % of the photo's diagonal long, rounded to 1, 2 or
  // 5 x 10^k) so that the vectors visibly shrink as the solve converges.
  double residual_scale = 1.0;
  std::string message;  // what the last Step or Reset did, or why it did nothing
  // The stepped project's triangles (BuildUntexturedMesh: the document mesh's texture still
  // fits them, stepping changes no topology), for the 3D panel; the revision for its upload.
  TexturedMesh mesh;
  std::uint64_t mesh_revision = 0;
};

struct TeachView {
  bool vanishing_points = false;  // the construction on the photo, vanishing directions in 3D
  bool epipolar = false;          // epipolar lines and epipoles of a selected pin or the pointer
  bool numbers = false;           // the Numbers window: K, R, t, F with copy buttons
  bool modelling_state = false;   // the (K, F) counts per History entry
  bool solver_steps = false;      // the Solver steps window, residual vectors, stepped state
  TeachSolverSteps solver;
  Id second_image_id = kNoId;     // F between the active image and this one (Numbers window)
  // HistoryStateCounts of the document at history_counts_revision (Document::revision()).
  std::vector<ModellingStateCounts> history_counts;
  std::uint64_t history_counts_revision = ~std::uint64_t{0};
};

// Names of the overlays for menus and the `command teach NAME on|off` of input scripts:
// "vanishing", "epipolar", "numbers", "state", "steps". Null for an unknown name.
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

// The focal construction the overlay draws: of the valid ones, the pair with the smallest
// circle (the one most likely in view); null when there is none.
const FocalConstruction* ShownFocalConstruction(const VanishingConstruction& construction);

// The vanishing overlay extends at most this many segments of a family to its vanishing
// point (the longest): every one of a hundred-odd extensions hatched the photo.
constexpr size_t kTeachExtensionsPerFamily = 8;
// The segments of the image whose extensions the overlay draws: per family present in the
// construction, its kTeachExtensionsPerFamily longest.
std::vector<Id> TeachExtendedSegments(const AppState& state, Id image_id, const VanishingConstruction& construction);

// A vanishing point farther than this many photo diagonals from the photo's centre is left
// out of the view the overlay asks for (the overlay marks it at the panel's edge): the photo
// would shrink to a corner. At 2 the photo keeps about a third of the view's width.
constexpr double kMaxVanishingViewDiagonals = 2.0;
// The focal construction's circle is framed whole only up to this radius (photo diagonals).
constexpr double kMaxVanishingCircleViewDiagonals = 1.0;
// The rectangle (image px) the vanishing overlay needs in view: the photo of width_px x
// height_px, the finite vanishing points within kMaxVanishingViewDiagonals, the principal
// point and the shown focal construction (h's foot, C', the focal length's end, and its
// circle when it is within kMaxVanishingCircleViewDiagonals).
void TeachVanishingExtent(const TeachVanishing& teach, int width_px, int height_px, Eigen::Vector2d* min_px,
                          Eigen::Vector2d* max_px);

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

// The two rays of one vertex's pins in two calibrated photos and their closest points (the
// epipolar overlay in 3D): for each selected vertex (as TeachEpipolarLines selects them) and
// each pair of its pins in different calibrated photos, a before b in project order.
struct TeachRayPair {
  VertexRef vertex;
  Id pin_a = kNoId, pin_b = kNoId;
  Id image_a = kNoId, image_b = kNoId;
  Eigen::Vector3d center_a = Eigen::Vector3d::Zero(), center_b = Eigen::Vector3d::Zero();
  Eigen::Vector3d direction_a = Eigen::Vector3d::Zero(), direction_b = Eigen::Vector3d::Zero();  // unit
  RayPairClosestPoints closest;  // gap in project units
  // The gap as each photo sees it: the other ray's closest point projected into the photo,
  // its distance from the pin there (px; the own ray's point projects onto the pin).
  double gap_px_in_a = 0.0, gap_px_in_b = 0.0;
};
std::vector<TeachRayPair> TeachRayPairs(const AppState& state);

// --- The Solver steps window (TeachSolverSteps) ---

// The project the image and 3D panels draw: the stepped one while stepping, else null (the
// document's).
const Project* TeachSteppedProject(const AppState& state);
// One Levenberg-Marquardt iteration more of the chosen subject, beginning from its start
// first when not stepping yet. False (with solver.message saying why) when nothing changed:
// the fit had finished, or failed, or the subject has nothing to fit (no line families on the
// active photo, fewer than 7 matches with the second photo).
bool TeachStep(AppState* state);
// Back to the state before the first step, exactly (the start stays shown).
void TeachResetSteps(AppState* state);
// Drops the steps (the panels show the document again), e.g. to begin from a new start.
void TeachEndSteps(AppState* state);
// Once per frame: drops the steps when the window was closed or the document changed.
void UpdateTeachSteps(AppState* state);

// A pin's residual in the shown project (stepped or the document's): the projection of its
// vertex minus the pin, px, what the joint solve minimises.
struct TeachPinResidual {
  Id pin_id = kNoId;
  Id image_id = kNoId;
  Eigen::Vector2d uv_px = Eigen::Vector2d::Zero();
  Eigen::Vector2d projection_px = Eigen::Vector2d::Zero();
  Eigen::Vector2d residual_px = Eigen::Vector2d::Zero();
};
// Of the pins in calibrated images whose vertex exists and is in front of the camera.
std::vector<TeachPinResidual> TeachPinResiduals(const Project& project);

// The stepped vanishing-point fit's residual of one segment: each endpoint's offset to its
// foot on the line through the segment's midpoint and its family's current vanishing point
// (the two offsets are equal and opposite; their length is the fit's residual, px).
struct TeachVpSegmentResidual {
  Id segment_id = kNoId;
  int axis = 0;
  Eigen::Vector2d a_px = Eigen::Vector2d::Zero(), b_px = Eigen::Vector2d::Zero();  // as fitted
  Eigen::Vector2d offset_a_px = Eigen::Vector2d::Zero(), offset_b_px = Eigen::Vector2d::Zero();
  double residual_px = 0.0;  // the fit's own figure (VpCalibrationSummary::segment_residuals_px)
};
// Empty unless the vanishing-point fit is being stepped.
std::vector<TeachVpSegmentResidual> TeachVpResiduals(const AppState& state);

// The stepped two-view refinement for one match: its epipolar lines under the current F
// (line_in_a = F^T uv_b through photo a, line_in_b = F uv_a through photo b; (l0, l1) unit)
// and the start's, and the signed distances (SymmetricEpipolarDistances: uv_b to line_in_b,
// uv_a to line_in_a).
struct TeachEpipolarMatch {
  Id pin_a = kNoId, pin_b = kNoId;
  Eigen::Vector2d uv_a = Eigen::Vector2d::Zero(), uv_b = Eigen::Vector2d::Zero();
  Eigen::Vector3d line_in_a = Eigen::Vector3d::Zero(), line_in_b = Eigen::Vector3d::Zero();
  Eigen::Vector3d start_line_in_a = Eigen::Vector3d::Zero(), start_line_in_b = Eigen::Vector3d::Zero();
  Eigen::Vector2d distances_px = Eigen::Vector2d::Zero();
  bool drawn = false;  // one of the few matches whose lines the overlay draws
};
// Empty unless the two-view refinement is being stepped.
std::vector<TeachEpipolarMatch> TeachEpipolarMatches(const AppState& state);
// True while the chosen subject has a stepped state (the window's Reset applies).
bool TeachStepping(const AppState& state);

}  // namespace facet::app
