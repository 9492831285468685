// The modeling state of a Facet project: images with their cameras, the user's line
// segments, the primitives (topology K and parameters) and the constraints F (pins and
// spatial constraints).
// Plain structs; every object has a stable id and is referred to by it, never by index.
// Edits go through core/scene/document.h so that each one is undoable.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/geometry/axis.h"
#include "core/geometry/camera.h"
#include "core/geometry/ids.h"
#include "core/geometry/intrinsics_modes.h"
#include "core/geometry/segment.h"
#include "core/mesh/mesh.h"
#include "core/mesh/primitives.h"

namespace facet {

struct Image {
  Id id = kNoId;
  std::string path;  // as stored in the project file: relative to the project file's folder
  int width_px = 0;
  int height_px = 0;
  Camera camera;
  bool camera_calibrated = false;  // true once calibration produced intrinsics and rotation
  PrincipalPointMode principal_point_mode = PrincipalPointMode::kSolve;
  Eigen::Vector2d fixed_principal_point_px = Eigen::Vector2d::Zero();  // for kFixed
  FocalMode focal_mode = FocalMode::kSolve;
  double fixed_focal_px = 0.0;      // for FocalMode::kFixed
  double focal_prior_px = 0.0;      // for FocalMode::kPrior
  double focal_prior_std_px = 0.0;  // for FocalMode::kPrior
  // The horizon, two points (x1, y1, x2, y2) in px on the image of the horizontal plane at
  // infinity: with a known focal length it lets one horizontal line family fix the rotation
  // (VpCalibrationOptions::horizon_px).
  bool use_horizon = false;
  Eigen::Vector4d horizon_px = Eigen::Vector4d::Zero();
  // Estimate radial distortion (camera.k1, k2) from the image's straight lines (plumb-line,
  // core/estimators/plumb_line.h) before the vanishing-point calibration.
  bool estimate_distortion = false;
  bool pose_locked = false;  // the geometry solve keeps this camera's position
  // Whether the geometry solve keeps the intrinsics calibration gave (issue 5 frees them).
  bool focal_locked = true;
  bool principal_point_locked = true;
  bool distortion_locked = true;  // the joint solve keeps camera.k1, k2
  // Photos taken with one camera and lens (the same focal setting) share its intrinsics in the
  // joint solve, as a calibration group does in photogrammetry: the images with the same
  // lens_group > 0 have one focal length, one principal point and one k1, k2 among those of
  // them the solve refines (focal_locked etc. off), which start from the mean of their values.
  // A photo that faces a wall fixes f poorly on its own; two such photos with pins in common
  // fix one f together. 0: the photo's own lens.
  int lens_group = 0;
  // How the world axes of this image's line families sit in the model's world frame: the
  // camera's rotation is the vanishing-point rotation times a turn about the vertical by
  // axis_quarter_turns x 90 deg (core/solve/model_update.h). Lines alone leave that turn open
  // (which side of the building the photo shows; which horizontal family is x), so it is
  // chosen once, from pins shared with the model, and kept so that re-solves and undo agree.
  // kAxisTurnsUnchosen until then (and in files written before it existed).
  static constexpr int kAxisTurnsUnchosen = -1;
  int axis_quarter_turns = kAxisTurnsUnchosen;
  // The turn above was the best of the four by too small a margin to keep (two pins, or
  // pins that fit two turns nearly as well): it is used, and chosen again at every update
  // until the pins tell the turns apart (core/solve/world_frames.h).
  bool axis_turn_provisional = false;
  // The camera came from a reconstruction (COLMAP, core/io/colmap_import.h): its lines no
  // longer calibrate it (the calibration from lines would replace COLMAP's intrinsics and
  // rotation, good to a tenth of a degree, by their own, good to a degree or two). The import
  // also locks its pose and intrinsics, which the user may free; this stays until the next
  // import.
  bool camera_from_reconstruction = false;
  // Whether the texture bake may take colour from this photo at all (false: e.g. a passer-by
  // stands in front of the model; the photo still calibrates and pins as before).
  bool use_for_texture = true;
};

// The user's say over where one face's texture comes from (issue 13): a photo forced as its
// source (kNoId: chosen by the bake) and photos that never texture it. The bake honours a
// forced photo where it sees the face and takes the texels it does not see from the next
// view (core/texture/textured_mesh.h says how it reports that). An override that names a face
// or photo no longer in the project is kept, and ignored by the bake.
struct FaceTextureOverride {
  FaceId face = kNoElement;
  Id source_image = kNoId;
  std::vector<Id> excluded_images;  // ascending, each once
  bool IsDefault() const { return source_image == kNoId && excluded_images.empty(); }
  friend bool operator==(const FaceTextureOverride&, const FaceTextureOverride&) = default;
};

// K_create: a primitive with its own mesh. The shape (kind, parameters, pose) is the
// Facade-style parameterisation; the mesh is its topology as the K-ops left it, every vertex
// defined in primitive-local coordinates as a linear function of the parameters
// (core/mesh/mesh.h, LocalDefinition), so world = R(shape.rotation) * C * params + translation.
// The mesh holds this primitive only (one component), and its vertex ids are what pins and
// constraints refer to: a box's corner i (core/mesh/box.h bit code) is vertex i.
struct Primitive {
  Id id = kNoId;
  std::string name;
  PrimitiveShape shape;  // shape.id == id
  PolyMesh mesh;         // world positions cached: UpdatePrimitivePositions after a change
  // Parameters the geometry solve must keep (by index into shape.params). A locked
  // dimension is a known length: it fixes the scale of the scene.
  std::array<bool, kMaxPrimitiveParams> param_locked = {false, false, false, false};
  bool rotation_locked = true;  // aligned with the world axes found by calibration
  bool translation_locked = true;
  // The box this primitive sits on (AttachOnTop in core/mesh/primitives.h), or kNoId. Its
  // footprint and pose follow the base's after every change.
  Id attached_to = kNoId;
  // Per-face texture overrides, ascending by face, never a default one (SetFaceTextureOverride).
  std::vector<FaceTextureOverride> face_textures;
};

// The override of `face`, or null when the bake chooses freely.
const FaceTextureOverride* FindFaceTextureOverride(const Primitive& primitive, FaceId face);
// Stores `entry` (its face names which one) in the primitive's list, normalised: excluded
// images sorted and unique, a default entry removed, the list kept ascending by face.
void SetFaceTextureOverride(Primitive* primitive, FaceTextureOverride entry);

// A vertex of a primitive's mesh.
struct VertexRef {
  Id primitive_id = kNoId;
  VertexId vertex = kNoElement;
  friend bool operator==(const VertexRef&, const VertexRef&) = default;
};

// V_proj: a model vertex pinned to a pixel of an image.
struct Pin {
  Id id = kNoId;
  Id image_id = kNoId;
  VertexRef vertex;
  Eigen::Vector2d uv_px = Eigen::Vector2d::Zero();
};

// V_space and edge-to-image-line F-ops: g(v) = 0 over model vertices (issue 5). Which
// fields a kind reads:
//   kCoplanar        vertices: 4 or more (a face's vertices, or any set)
//   kCollinear       vertices: 3 or more
//   kParallel        vertices: (a0, a1, b0, b1), edge a parallel to edge b
//   kPerpendicular   vertices: (a0, a1, b0, b1)
//   kEqualLength     vertices: (a0, a1, b0, b1)
//   kDistance        vertices: (a, b); value = |b - a| in the project's units (sets the scale)
//   kFixedPoint      vertices: (a); point = its world position (e.g. the origin)
//   kAlongAxis       vertices: (a, b); axis = the world axis edge a -> b is parallel to
//   kEdgeOnImageLine vertices: (a, b); image_id, line_a_px, line_b_px: the edge projects onto
//                    the image line through those two pixels
enum class ConstraintKind {
  kCoplanar = 0,
  kCollinear,
  kParallel,
  kPerpendicular,
  kEqualLength,
  kDistance,
  kFixedPoint,
  kAlongAxis,
  kEdgeOnImageLine,
};
const char* ConstraintKindName(ConstraintKind kind);  // "coplanar", "collinear", ...
std::optional<ConstraintKind> ConstraintKindFromName(const std::string& name);

struct Constraint {
  Id id = kNoId;
  ConstraintKind kind = ConstraintKind::kCoplanar;
  std::vector<VertexRef> vertices;
  double value = 0.0;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Axis axis = Axis::kZ;
  Id image_id = kNoId;
  Eigen::Vector2d line_a_px = Eigen::Vector2d::Zero();
  Eigen::Vector2d line_b_px = Eigen::Vector2d::Zero();
};

// Reference geometry (issue 13): a mesh made elsewhere (a Wavefront OBJ or a binary glTF),
// drawn in both panels to model against and offered as a snap target when moving vertices.
// It is not part of the model: never solved, textured or exported. The project stores where
// the file is and how its axes sit; the triangles are read from the file
// (core/io/reference_mesh.h), so a file that has gone missing loses nothing but its drawing.
struct Reference {
  Id id = kNoId;
  std::string path;  // as stored: relative to the project file's folder, like Image::path
  // The file's axes. True (OBJ's and glTF's convention, and what `facet export` writes): file
  // (x, y, z) is world (x, -z, y), so an exported model comes back where it was. False: file
  // coordinates are world coordinates (Z up).
  bool y_up = true;
  bool visible = true;
  friend bool operator==(const Reference&, const Reference&) = default;
};

struct Project {
  // 1: boxes with corner pins (read and migrated); 2: primitives with meshes, vertex pins
  // and constraints; 3: the user's texture choices (Image::use_for_texture,
  // Primitive::face_textures), which version 2 files migrate to "none"; 4: reference geometry
  // (references), none in older files; 5: Image::lens_group, 0 (own lens) in older files.
  static constexpr int kFormatVersion = 5;
  std::vector<Image> images;
  std::vector<Segment> segments;
  std::vector<Primitive> primitives;
  std::vector<Pin> pins;
  std::vector<Constraint> constraints;
  std::vector<Reference> references;
  std::string units = "m";
  Id next_id = 1;  // ids are never reused within a project

  Id NewId() { return next_id++; }

  const Image* FindImage(Id id) const;
  Image* FindImage(Id id);
  const Segment* FindSegment(Id id) const;
  Segment* FindSegment(Id id);
  const Primitive* FindPrimitive(Id id) const;
  Primitive* FindPrimitive(Id id);
  const Pin* FindPin(Id id) const;
  Pin* FindPin(Id id);
  const Constraint* FindConstraint(Id id) const;
  Constraint* FindConstraint(Id id);
  const Reference* FindReference(Id id) const;
  Reference* FindReference(Id id);
  // The vertex record a reference names, or null when the primitive or vertex is gone.
  const MeshVertex* FindVertex(const VertexRef& ref) const;
};

// World position of a referenced vertex (cached in the mesh); the caller checks FindVertex.
Eigen::Vector3d VertexInWorld(const Project& project, const VertexRef& ref);

// K_create for the project: a primitive of `shape` with a fresh id (shape.id is replaced),
// its mesh built and placed. Returns false with a message when the shape is invalid
// (non-positive dimensions, too few segments); the project is then unchanged.
bool AddPrimitiveToProject(Project* project, PrimitiveShape shape, const std::string& name, Id* new_id,
                           std::string* message);

// Recomputes the cached world positions of the primitive's vertices from its shape, after
// re-applying AttachOnTop when it sits on another primitive. Call after changing a shape.
void RefreshPrimitive(Project* project, Primitive* primitive);
// RefreshPrimitive for every primitive, bases before the primitives attached to them.
void RefreshAllPrimitives(Project* project);
// How many bases the primitive sits on (0: none), counted up to kMaxAttachmentDepth
// (core/util/input_limits.h), which a file or an edit may not exceed.
int AttachmentDepth(const Project& project, const Primitive& primitive);

bool operator==(const Camera& a, const Camera& b);
bool operator==(const Image& a, const Image& b);
bool operator==(const Primitive& a, const Primitive& b);
bool operator==(const PrimitiveShape& a, const PrimitiveShape& b);
bool operator==(const Constraint& a, const Constraint& b);
bool operator==(const Pin& a, const Pin& b);
bool operator==(const Project& a, const Project& b);

}  // namespace facet
