// Internals of the joint solve (core/solve/joint_solve.h), exposed for its tests: the problem built
// from a project, the residual blocks with their analytic Jacobians, the parameter update and
// the write-back. Not for use outside core/joint_solve*.cpp, core/solve/constraint_polish.cpp and
// tests/test_joint_solve*.cpp.
//
// Parameter vector (length JointProblem::num_parameters), blocks in this order per object:
// - camera: focal (px), principal point (2, px), rotation (3: d in cam_from_world <-
//   exp([d]x) * cam_from_world, radians), centre in world (3, world units), radial distortion
//   k1, k2 (2, Camera's model; only when Image::distortion_locked is false and intrinsics
//   are refined);
// - primitive: each unlocked shape parameter it owns (world units), rotation (3: d in
//   world_from_primitive <- exp([d]x) * world_from_primitive), translation (3);
// - free vertex (LocalDefinition::free): its local offset (3, primitive-local units).
// Every update is additive except the rotations.
//
// Attached primitives (Primitive::attached_to, AttachOnTop): a primitive on a box takes the
// footprint (params 0, 1) of the root of its chain of bases and the root's pose, raised by
// the heights (param 2) of its bases, so world = R_root (C theta' + offset + H e_z) + t_root.
// It owns only its parameters from index 2 on; its own pose is not a parameter.
//
// Residual blocks, each a few rows with a dense Jacobian over its own parameter columns:
// - pin (2 rows, px): project(vertex) - uv_px, through the camera's distortion, times the
//   block's robust weight (ResidualBlock::weight, 1 unless the pin is down-weighted);
// - segment (2 rows, px): signed distance of each endpoint to the line through the segment's
//   midpoint and the vanishing point K R e_axis (the second is minus the first). The user
//   draws on the distorted photo, so with distortion the endpoints are first undistorted with
//   the current f, principal point and k (Camera::UndistortPixel), derivatives included;
// - an edge-on-image-line constraint likewise undistorts its two line points and projects
//   the edge's endpoints through the pinhole part.
// Camera derivatives are ordered (focal, principal point 2, rotation 3, centre 3, k1, k2): 11.
// - constraint: scale-free residual c (ConstraintTerm below), multiplied by sqrt(mu) and
//   shifted by lambda / mu for the augmented Lagrangian (JointProblem::constraint_weight
//   and ConstraintTerm::multiplier).
#pragma once

#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "core/scene/project.h"

namespace facet::joint_solve_internal {

// Number of shape parameters a primitive kind uses (core/mesh/primitives.h).
int NumShapeParams(PrimitiveKind kind);

struct CameraState {
  double focal_px = 0.0;
  Eigen::Vector2d principal_point_px = Eigen::Vector2d::Zero();
  Eigen::Matrix3d cam_from_world_rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d center_in_world = Eigen::Vector3d::Zero();
  double k1 = 0.0;
  double k2 = 0.0;
};

struct PrimitiveState {
  PrimitiveParams params = PrimitiveParams::Zero();
  Eigen::Matrix3d world_from_primitive = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
};

// The values the solve changes.
struct JointState {
  std::vector<CameraState> cameras;           // JointProblem::cameras order
  std::vector<PrimitiveState> primitives;     // JointProblem::primitives order
  std::vector<Eigen::Vector3d> free_offsets;  // JointProblem::free_vertices order
};

struct CameraBlock {
  int image_index = -1;   // into Project::images
  int focal_offset = -1;  // -1: not a parameter
  int principal_point_offset = -1;
  int rotation_offset = -1;
  int center_offset = -1;
  int distortion_offset = -1;  // k1, k2
  // Image::lens_group: cameras of one group > 0 share the columns of the intrinsics they free
  // (focal_offset, principal_point_offset, distortion_offset), so one column can belong to
  // several cameras; BuildJointProblem starts them all from the mean of their values.
  int lens_group = 0;
};

struct PrimitiveBlock {
  int primitive_index = -1;  // into Project::primitives
  int root = -1;             // problem primitive whose footprint and pose this one uses (itself if not attached)
  std::vector<int> bases;    // problem primitives below this one, nearest first (empty if not attached)
  std::array<int, kMaxPrimitiveParams> param_offset = {-1, -1, -1, -1};
  int rotation_offset = -1;
  int translation_offset = -1;
};

struct FreeVertexBlock {
  VertexRef ref;
  int offset = -1;  // first of its 3 parameters
};

// A vertex used by some residual: its position and the 3 x cols Jacobian, evaluated once
// per iteration and shared by the blocks that read it.
struct VertexTerm {
  VertexRef ref;
  int primitive = -1;                                          // problem primitive
  int free_vertex = -1;                                        // into JointProblem::free_vertices, or -1
  ParamCoefficients coefficients = ParamCoefficients::Zero();  // LocalDefinition::Collapsed()
  Eigen::Vector3d fixed_offset = Eigen::Vector3d::Zero();      // offset of a vertex that is not free
  std::vector<int> cols;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Matrix<double, 3, Eigen::Dynamic> jacobian;
};

// Scale-free constraint residuals (rows), in terms of the constraint's world points:
//   kCoplanar        per vertex i beyond the 3 spanning ones: distance of p_i to the plane
//                    through p_s0, p_s1, p_s2 (chosen at build for the largest triangle) / S
//   kCollinear       per vertex beyond the 2 spanning ones: 2 components of
//                    (p_i - p_s0) x unit(p_s1 - p_s0) / S (the component along the axis most
//                    aligned with the line at build is dropped: it is always ~0)
//   kParallel        2 components of unit(a) x unit(b) (sines), same dropping rule
//   kPerpendicular   unit(a) . unit(b) (a cosine)
//   kEqualLength     (|a| - |b|) / S
//   kDistance        (|b - a| - value) / value
//   kFixedPoint      (p - point) / S (3)
//   kAlongAxis       the 2 components of unit(b - a) across the axis (sines)
//   kEdgeOnImageLine signed distance of each projected endpoint to the image line, in px,
//                    divided by the focal length at build (radians)
// S is the model size (JointProblem::model_size). Natural units for diagnostics: residual * S
// (lengths), * value (distance), degrees (angles), * focal (px).
struct ConstraintTerm {
  int constraint_index = -1;  // into Project::constraints
  ConstraintKind kind = ConstraintKind::kCoplanar;
  std::vector<int> vertices;                    // vertex terms, in the constraint's order
  std::array<int, 3> span = {0, 1, 2};          // kCoplanar / kCollinear spanning vertices (positions in `vertices`)
  std::array<int, 2> kept_components = {0, 1};  // kCollinear / kParallel / kAlongAxis
  int camera = -1;                              // kEdgeOnImageLine
  Eigen::Vector3d line_px = Eigen::Vector3d::Zero();    // normalised image line (a, b, c), a^2 + b^2 = 1
  Eigen::Vector2d line_a_px = Eigen::Vector2d::Zero();  // the line's points on the photo (distorted)
  Eigen::Vector2d line_b_px = Eigen::Vector2d::Zero();
  // The camera's k is a parameter: take the undistorted-line path even at k = 0 so that the
  // derivatives with respect to k are there.
  bool undistort_line = false;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  // kFixedPoint target
  double scale = 1.0;                               // the divisor of the residual
  int num_rows = 0;
  Eigen::VectorXd multiplier;  // augmented-Lagrangian multipliers, one per row
};

enum class BlockKind { kPin, kSegment, kConstraint };

struct ResidualBlock {
  BlockKind kind = BlockKind::kPin;
  int source = -1;  // pin / segment index in the project, or constraint term index
  int camera = -1;  // problem camera (pins, segments, edge-on-line constraints)
  int num_rows = 0;
  std::vector<int> cols;  // parameter columns, unique
  // Per vertex the block reads (pins: 1; constraints: the term's), the block columns of its
  // VertexTerm::cols.
  std::vector<int> vertices;
  std::vector<std::vector<int>> vertex_cols;
  // Block column of each camera derivative (focal, principal point 2, rotation 3, centre 3,
  // k1, k2), -1 when that camera parameter is not free.
  std::array<int, 11> camera_cols = {-1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1};
  Eigen::Vector2d uv_px = Eigen::Vector2d::Zero();  // a pin's pixel
  // Segment data (px): the line constants of the residual g.v / |M v|.
  Eigen::Vector3d segment_g = Eigen::Vector3d::Zero();
  Eigen::Matrix<double, 2, 3> segment_m = Eigen::Matrix<double, 2, 3>::Zero();
  Eigen::Vector2d segment_a_px = Eigen::Vector2d::Zero();  // the endpoints as drawn (distorted)
  Eigen::Vector2d segment_b_px = Eigen::Vector2d::Zero();
  int axis = 0;
  // Pins: the square root of the robust loss's weight (JointSolveOptions::robust_pins), which
  // multiplies the residual and its Jacobian; 1 for a pin the loss treats as an inlier.
  double weight = 1.0;
  // Evaluated values (weighted for constraints and down-weighted pins), and the unweighted
  // residual (constraints: scale-free; pins: px).
  Eigen::VectorXd residual;
  Eigen::MatrixXd jacobian;
  Eigen::VectorXd raw;
  // Scratch reused by every evaluation, so the hot loop does not allocate.
  std::vector<Eigen::Vector3d> points;
  Eigen::MatrixXd d_points;
  Eigen::MatrixXd d_camera;
};

struct JointProblem {
  std::vector<CameraBlock> cameras;
  std::vector<PrimitiveBlock> primitives;
  std::vector<FreeVertexBlock> free_vertices;
  std::vector<VertexTerm> vertices;
  std::vector<ConstraintTerm> constraints;
  std::vector<ResidualBlock> blocks;
  int num_parameters = 0;
  int num_residuals = 0;
  int num_skipped_pins = 0;
  double model_size = 1.0;                   // RMS distance of the used vertices from their centroid at the start
  double constraint_weight = 1e3;            // sqrt(mu) of the augmented Lagrangian
  std::vector<std::string> parameter_names;  // one per parameter, for diagnostics
  // Unlocked shape parameters that no used pin's or constraint's vertex moves with: held at
  // their values, not parameters (named as parameter_names would name them).
  struct HeldParameter {
    std::string name;
    double value = 0.0;
  };
  std::vector<HeldParameter> held_parameters;
  std::vector<std::string> warnings;
};

struct BuildOptions {
  bool refine_intrinsics = true;
  bool use_segments = true;

  // Every value is valid (two switches); present so that every options struct has one.
  bool Check(std::string* error) const { return true; }
};

// Collects the usable pins, segments and constraints, numbers the free parameters and fills
// *state with the project's values. Pins in uncalibrated images or naming missing objects and
// constraints naming missing vertices are skipped with a warning.
JointProblem BuildJointProblem(const Project& project, const BuildOptions& options, JointState* state);

// Vertex position and 3 x cols Jacobian for `state` (term->position, term->jacobian).
void EvaluateVertex(const JointProblem& problem, const JointState& state, VertexTerm* term);

// Evaluates every vertex and block: residuals always, Jacobians when `with_jacobian`.
// Returns false when a pinned vertex lies on or behind its camera (residuals then unusable).
bool EvaluateBlocks(JointProblem* problem, const JointState& state, bool with_jacobian);

// The unweighted scale-free residual of one constraint term and its derivative with respect
// to its points (rows x 3n, n = term.vertices.size()) and, for kEdgeOnImageLine, the camera's
// parameters in block order (focal, principal point, rotation, centre, k1, k2; rows x 11,
// full). With camera k1 = k2 = 0 and !undistort_line the line is term.line_px (fixed at build);
// otherwise the line through the undistorted term.line_a_px, line_b_px.
// Returns false when an edge-on-line endpoint lies on or behind the camera.
bool ConstraintResidual(const ConstraintTerm& term, const std::vector<Eigen::Vector3d>& points,
                        const CameraState* camera, Eigen::VectorXd* residual, Eigen::MatrixXd* d_points,
                        Eigen::MatrixXd* d_camera);

// Pin residual (px, through the distortion) and its derivatives with respect to the world
// point, the camera (focal, principal point, rotation, centre: 2 x 9) and, when asked, the
// distortion (k1, k2: 2 x 2). Returns false when the point lies on or behind the camera.
bool PinResidual(const CameraState& camera, const Eigen::Vector3d& point, const Eigen::Vector2d& uv_px,
                 Eigen::Vector2d* residual, Eigen::Matrix<double, 2, 3>* d_point, Eigen::Matrix<double, 2, 9>* d_camera,
                 Eigen::Matrix<double, 2, 2>* d_distortion = nullptr);

// Segment residual (px, endpoint a) of a pinhole camera (k ignored) from the line constants
// built from the drawn endpoints, and its derivative with respect to the camera's focal,
// principal point and rotation (1 x 6).
double SegmentResidual(const CameraState& camera, const Eigen::Vector3d& segment_g,
                       const Eigen::Matrix<double, 2, 3>& segment_m, int axis, Eigen::Matrix<double, 1, 6>* d_camera);
// The same from the drawn (distorted) endpoints, undistorted with the camera's k first;
// derivative with respect to (focal, principal point 2, rotation 3, k1, k2) (1 x 8). Equals
// SegmentResidual when k1 = k2 = 0.
double DistortedSegmentResidual(const CameraState& camera, const Eigen::Vector2d& a_px, const Eigen::Vector2d& b_px,
                                int axis, Eigen::Matrix<double, 1, 8>* d_camera);

// state <- state "+" delta.
void ApplyStep(const JointProblem& problem, const Eigen::VectorXd& delta, const JointState& state, JointState* stepped);

// Dense Jacobian (num_residuals x num_parameters) and residual of the last evaluation.
void DenseJacobian(const JointProblem& problem, Eigen::MatrixXd* jacobian, Eigen::VectorXd* residual);

// Writes cameras, owned primitive shapes and free-vertex offsets into *project and refreshes
// the cached vertex positions (RefreshAllPrimitives).
void WriteState(const JointProblem& problem, const JointState& state, Project* project);

// Constraint residual in its natural unit (see ConstraintDiagnostic) from the scale-free one.
double NaturalConstraintResidual(const JointProblem& problem, const ConstraintTerm& term, const Eigen::VectorXd& scaled,
                                 std::string* unit);

}  // namespace facet::joint_solve_internal
