// The model edits the tools, menus and script commands share: K_create of a primitive (alone
// or attached on top of a box), the paper's K-operators on a primitive's mesh, freeing a
// vertex, a planar-face constraint, push/pull of a face and vertex pins. Each is one undoable document edit with a
// label, followed by the re-solve (CommitEdit); a refusal logs the core's message as an error
// (shown in the log and the status bar) and changes nothing. Each returns whether it edited.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "app/state/app_state.h"

namespace facet::app {

// Default parameters of a new primitive of `kind` (unit size; 8 sides for prism/cylinder).
PrimitiveShape DefaultShape(PrimitiveKind kind);
// Names of the kind's parameters in shape.params order, and how many it has.
int NumShapeParams(PrimitiveKind kind);
const char* ShapeParamName(PrimitiveKind kind, int index);
// Whether a primitive of `kind` can sit on top of a box (AttachOnTop).
bool CanAttachOnTop(PrimitiveKind kind);
// The selected primitive when it is a box that a new `kind` can sit on, or null.
const Primitive* AttachBaseFor(const AppState& state, PrimitiveKind kind);

// Where K_create puts a primitive that sits on no base. With a calibrated `view` camera it
// stands in front of that camera, in view, on the ground plane (z = 0) under `aim_px` (image
// px; default the principal point; an aim above the horizon is replaced by one three
// quarters down the image): where the aim's ray meets the ground, else (a camera not above
// the ground) at the model's depth along the ray. Its size is what the view shows there: its
// largest side a quarter of the photo's height at that depth, rounded down to a round length
// (1, 1.5, 2, 3, 4, 5, 6, 8 x 10^k), halved until its nearest vertex is at least half that
// depth in front of the camera (never straddling or behind it). The first primitive of a
// project stays at the origin with its default size, which fix origin and unit, and every
// camera moves by `camera_shift` instead so that it stands under the aim a framing distance
// away (nothing pins a camera's centre yet). Without a calibrated view: the first at the
// origin, the others as large as `scale_from` (else the last primitive) and beside
// everything there is.
struct NewPrimitivePlacement {
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();   // world_from_primitive
  double scale = 1.0;                                      // of the default dimensions
  Eigen::Vector3d camera_shift = Eigen::Vector3d::Zero();  // added to every camera centre
  bool on_ground = false;  // stands on the ground plane (z = 0) under the aim
};
NewPrimitivePlacement PlaceNewPrimitive(const Project& project, const PrimitiveShape& shape, const Image* view,
                                        const std::optional<Eigen::Vector2d>& aim_px, Id scale_from);

// K_create: adds a primitive of `kind`, on top of `base_id` (a box) when given, else where
// PlaceNewPrimitive puts it in the active image (aimed at `aim_px`, image px), and selects it.
// The first primitive of a project gets its last dimension locked (a known length for scale).
// A later box placed on the ground is kept there: its base corners and the world's origin
// (the first box's corner 0, which its kept position holds at z = 0) are one coplanar
// constraint, i.e. its base on the ground plane z = 0, since from one photo a box whose foot
// no pin sees (or whose depth along the view ray nothing fixes) could otherwise float or
// sink; the log says so, and removing the constraint lifts it. The first box's other corners
// are not read: they would tie the new box to that box's size (its depth, on a box pinned on
// its front only, drifted to zero and below).
bool AddPrimitiveEdit(AppState* state, PrimitiveKind kind, Id base_id,
                      const std::optional<Eigen::Vector2d>& aim_px = std::nullopt);

// Turns a wedge's ridge along its local y (along_y) or x, over the same footprint, so that a
// roof on a box can run either way. Refused: not a wedge, the ridge already that way, a mesh
// the K-operators or a freed vertex changed (the ridge is in the vertices' definitions).
bool SetWedgeRidgeEdit(AppState* state, Id primitive_id, bool along_y);

// Deletes a primitive with its pins and the constraints naming it; primitives attached to it
// stay where they are, detached.
bool DeletePrimitiveEdit(AppState* state, Id primitive_id);

// E_split on an edge at parameter t in (0, 1) from the origin of half-edge 2 * edge.
bool SplitEdgeEdit(AppState* state, Id primitive_id, EdgeId edge, double t);
// V_delete; pins and constraints naming the vertex go with it (in the same edit).
bool DeleteVertexEdit(AppState* state, Id primitive_id, VertexId vertex);
// V_connect between two vertices of one face of the primitive (the face is found).
bool ConnectVerticesEdit(AppState* state, Id primitive_id, VertexId a, VertexId b);
// E_delete.
bool DeleteEdgeEdit(AppState* state, Id primitive_id, EdgeId edge);
// Toggles LocalDefinition::free; un-freeing puts the vertex back on its definition.
bool ToggleFreeVertexEdit(AppState* state, Id primitive_id, VertexId vertex);
// A kCoplanar constraint on the face's vertices ("keep this face planar"), or its removal
// when the same constraint exists.
bool TogglePlanarFaceEdit(AppState* state, Id primitive_id, FaceId face);

// Spatial constraints (issue 5, core/scene/project.h Constraint). Each adds one constraint as one
// edit; the joint solve then enforces it. Edges are ElementRefs of kind kEdge (vertices a -> b
// of half-edge 2 * edge); a refusal (a missing element, the same edge twice, a length <= 0,
// a constraint already there) is logged and changes nothing.
// kAlongAxis: the edge parallel to a world axis.
bool ConstrainAlongAxisEdit(AppState* state, const ElementRef& edge, Axis axis);
// kDistance: the edge's length is `length` project units (it sets the scale).
bool ConstrainLengthEdit(AppState* state, const ElementRef& edge, double length);
// kDistance between two vertices (the Measure tool): `length` project units apart. Refused:
// not two distinct live vertices, a length <= 0, the same constraint already there.
bool ConstrainDistanceEdit(AppState* state, const ElementRef& a, const ElementRef& b, double length);
// The Measure tool's pair: exactly two distinct vertices selected (element, then extra[0]).
bool MeasuredPair(const Selection& selection, ElementRef* a, ElementRef* b);
// kParallel, kPerpendicular or kEqualLength between two distinct edges.
bool ConstrainEdgePairEdit(AppState* state, ConstraintKind kind, const ElementRef& first, const ElementRef& second);
// kFixedPoint at the vertex's current world position.
bool FixVertexEdit(AppState* state, const ElementRef& vertex);
// Removes one constraint ("Remove constraint").
bool RemoveConstraintEdit(AppState* state, Id constraint_id);
// The world vertices of a set of elements (a vertex itself, an edge's two ends, a face's
// corners), each once, in the order met.
std::vector<VertexRef> VerticesOfElements(const Project& project, const std::vector<ElementRef>& elements);
// kCoplanar (4+ distinct vertices) or kCollinear (3+) on the vertices of `elements` (any
// primitives; faces only for coplanar). Refused: too few distinct vertices, points that are
// collinear (coplanar: all of them, or 3 of 4, which makes the 4 always coplanar) or that
// coincide (collinear), the same set constrained already. `label` names the edit; empty
// gives "Coplanar" / "Collinear".
bool ConstrainVertexSetEdit(AppState* state, ConstraintKind kind, const std::vector<ElementRef>& elements,
                            const std::string& label = "");
// "Parallel faces": a face's plane parallel to another's, as two kParallel constraints (one
// edit) between the two most nearly parallel pairs of their edges whose directions in the
// first face differ. Parallel planes are not an edge kind; two parallel edge pairs also hold
// the faces' turn within their planes, so the edit is refused when the faces have no two
// such pairs within kParallelFacesMaxAngleDeg (it would turn them).
constexpr double kParallelFacesMaxAngleDeg = 15.0;
bool ConstrainParallelFacesEdit(AppState* state, const ElementRef& first, const ElementRef& second);
// kEdgeOnImageLine: the edge projects, in the image, onto the line through a_px and b_px
// (image pixels). A line pin of the same edge in the same image is replaced. Refused: not an
// edge, an image that is missing or not calibrated, points closer than kMinLinePinLengthPx.
constexpr double kMinLinePinLengthPx = 2.0;
bool LinePinEdit(AppState* state, const ElementRef& edge, Id image_id, const Eigen::Vector2d& a_px,
                 const Eigen::Vector2d& b_px);
// The line pins of an image (kEdgeOnImageLine constraints naming it), in project order: the
// PIN_INDEX of `line-pin-move`.
std::vector<Id> LinePinsOfImage(const Project& project, Id image_id);
// The edge a line pin names (its two vertices' edge), or an empty ref when the edge is gone.
ElementRef LinePinEdge(const Project& project, const Constraint& line_pin);
// Sets end `end` (0: line_a_px, 1: line_b_px) of a line pin's image line to `uv_px` in
// `project` (the drag preview and the edit share it). False, project unchanged, when the
// constraint is not a line pin, `end` is not 0 or 1, the point is not finite or the line
// would get shorter than kMinLinePinLengthPx.
bool MoveLinePinEnd(Project* project, Id constraint_id, int end, const Eigen::Vector2d& uv_px);
// MoveLinePinEnd as one undoable edit with the re-solve; also refused when nothing moves.
bool MoveLinePinEndEdit(AppState* state, Id constraint_id, int end, const Eigen::Vector2d& uv_px);
// The builder's two-click step for a two-edge kind with the selected edge: the first call
// stores it (state->constraint_first_edge), a call with a different edge selected adds the
// constraint and clears the stored one. Returns whether it stored or edited.
bool ConstraintPairStep(AppState* state, ConstraintKind kind);
// "box 1 v3" for a constraint row.
std::string DescribeVertex(const Project& project, const VertexRef& ref);
// The label of a builder button's edit ("Along x", "Known length", "Parallel", ...).
std::string ConstraintEditLabel(ConstraintKind kind);
// The script command `constrain KIND [VALUE]` on the current selection (app/state/input_script.h). On a
// multi-selection: coplanar, collinear, parallel-faces, and parallel / perpendicular /
// equal-length between exactly two selected edges at once.
bool RunConstrainCommand(AppState* state, const std::string& arg, std::string* error);

// A script's name for a primitive: its id (ids count every object made, lines and pins
// included, so the same box is 175 in one session and 506 in another), `@N` (the N-th
// primitive of the project, from 1, in the order they were made) or `last` (the newest).
// False with *error naming what was asked when no primitive answers.
bool ResolvePrimitiveToken(const Project& project, const std::string& token, Id* id, std::string* error);

// The script command `select-add KIND PRIMITIVE ELEMENT_ID`: adds an element to the
// selection (multi-selection for coplanar/collinear on vertex sets).
bool RunSelectAddCommand(AppState* state, const std::string& arg, std::string* error);
// The script command `line-pin IMAGE_INDEX X1 Y1 X2 Y2`: the selected edge on the line
// through (X1, Y1) and (X2, Y2), pixels of the project's image IMAGE_INDEX (LinePinEdit).
bool RunLinePinCommand(AppState* state, const std::string& arg, std::string* error);
// The script command `line-pin-move IMAGE_INDEX PIN_INDEX END X Y`: end END (0 or a, 1 or b)
// of the image's PIN_INDEX-th line pin (LinePinsOfImage, from 0) to (X, Y), image pixels
// (MoveLinePinEndEdit).
bool RunLinePinMoveCommand(AppState* state, const std::string& arg, std::string* error);

// Push/pull: extrudes the face by `distance` project units along its outward normal (a
// negative distance pushes it in), core/mesh/extrude.h; the face stays selected.
bool PushPullFaceEdit(AppState* state, Id primitive_id, FaceId face, double distance);
// The push/pull distance a face starts with: 10 % of the primitive's size (the largest side
// of its bounding box), or 0.1 for an empty mesh.
double DefaultPushPullDistance(const Primitive& primitive);

// Removes the pins the last solve flagged as likely wrong clicks
// (state->last_update.joint.flagged_pins) as ONE undoable edit, "Drop N flagged pins", with
// the re-solve; the log names each dropped pin. Refused (logged, nothing changes) when none
// is flagged or none of them is still in the project.
bool DropFlaggedPinsEdit(AppState* state);

// Pins `vertex` at uv in the image (replacing its earlier pin there). Returns the pin id.
Id PinVertex(Project* project, Id image_id, const VertexRef& vertex, const Eigen::Vector2d& uv_px);

// Runs the current tool's action on a picked element (the image and 3D panels call it on a
// click): the operators, selection and V_connect's two-click state. `t` is the picked edge
// parameter. With `extend` (Shift held) the select tool adds the element to the selection or
// removes it (ToggleSelected), and a click on nothing keeps the selection. The line-pin tool
// selects the clicked edge. Returns true when the click was consumed.
bool ApplyToolClick(AppState* state, const ElementRef& picked, double t, bool extend);
// The same, with `extend` from the keyboard (ImGui's io.KeyShift, which scripts drive with
// `hold shift`).
bool ApplyToolClick(AppState* state, const ElementRef& picked, double t);

}  // namespace facet::app
