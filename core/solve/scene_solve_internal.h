// Internals of the geometry solve (core/solve/scene_solve.h), exposed for its tests: the problem
// built from a project, the residuals with their analytic Jacobian, and the parameter update.
// Not for use outside core/solve/scene_solve.cpp and tests/test_scene_solve.cpp.
//
// Parameter vector (length SceneProblem::num_parameters), in the order blocks are listed:
// - a free camera: its centre in world (3, world units), additive update;
// - a primitive: each unlocked shape parameter (world units), additive update; if the
//   rotation is free, 3 components of a small rotation d applied on the left,
//   world_from_primitive <- exp([d]x) * world_from_primitive (radians); if the translation is
//   free, 3 components (world units), additive update.
// A pinned vertex's local position is C * params + offset (core/mesh/mesh.h, LocalDefinition).
// Residuals: 2 per observation, in observation order, project(vertex) - uv_px (px).
#pragma once

#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/scene/project.h"

namespace facet::scene_solve_internal {

struct CameraBlock {
  int image_index = -1;  // into Project::images
  double focal_px = 0.0;
  Eigen::Vector2d principal_point_px = Eigen::Vector2d::Zero();
  Eigen::Matrix3d cam_from_world_rotation = Eigen::Matrix3d::Identity();
  int center_offset = -1;  // first parameter of the centre; -1 when the pose is locked
};

struct PrimitiveBlock {
  int primitive_index = -1;                                              // into Project::primitives
  std::array<int, kMaxPrimitiveParams> param_offset = {-1, -1, -1, -1};  // -1: locked or unused
  int rotation_offset = -1;
  int translation_offset = -1;
};

struct Observation {
  int pin_index = -1;  // into Project::pins
  int camera = -1;     // into SceneProblem::cameras
  int primitive = -1;  // into SceneProblem::primitives
  // The vertex's local definition, collapsed: p_in_primitive = coefficients * params + offset.
  ParamCoefficients coefficients = ParamCoefficients::Zero();
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  Eigen::Vector2d uv_px = Eigen::Vector2d::Zero();
};

enum class ParameterKind { kCameraCenter, kPrimitiveParam, kPrimitiveRotation, kPrimitiveTranslation };

struct ParameterInfo {
  ParameterKind kind = ParameterKind::kCameraCenter;
  int block = -1;     // into SceneProblem::cameras or ::primitives
  int component = 0;  // x, y, z for vectors; the parameter index for kPrimitiveParam
};

// The values the solve changes, one entry per block.
struct SceneState {
  std::vector<Eigen::Vector3d> camera_centers;
  std::vector<PrimitiveParams> primitive_params;
  std::vector<Eigen::Matrix3d> primitive_rotations;  // world_from_primitive
  std::vector<Eigen::Vector3d> primitive_translations;
};

struct SceneProblem {
  std::vector<CameraBlock> cameras;        // calibrated cameras that see at least one used pin
  std::vector<PrimitiveBlock> primitives;  // primitives with at least one used pin
  std::vector<Observation> observations;
  std::vector<ParameterInfo> parameters;  // size num_parameters
  int num_parameters = 0;
  int num_skipped_pins = 0;
  std::vector<std::string> warnings;  // about skipped pins
  // Unlocked shape parameters that no used pin's vertex depends on: held at their current
  // values (not parameters), one sentence each naming the cause and the fix.
  std::vector<std::string> held_parameters;
};

// Collects the usable pins of `project` and numbers the free parameters; fills *state with
// the project's current values. Pins in uncalibrated images, or naming a missing image or
// primitive or vertex, are skipped with a warning.
SceneProblem BuildSceneProblem(const Project& project, SceneState* state);

// Residuals (size 2 * observations) and, when `jacobian` is not null, their derivatives
// (2 * observations x num_parameters). Returns the number of observations whose vertex
// lies on or behind its camera's image plane (their residuals are still computed).
int EvaluateScene(const SceneProblem& problem, const SceneState& state, Eigen::VectorXd* residuals,
                  Eigen::MatrixXd* jacobian);

// state <- state "+" delta, with the parameterisation described above.
void ApplySceneStep(const SceneProblem& problem, const Eigen::VectorXd& delta, SceneState* state);

// Writes the state back into the cameras and primitives of *project (the project the problem was
// built from, or a copy of it).
void WriteSceneState(const SceneProblem& problem, const SceneState& state, Project* project);

// The linear initialisation: with rotations and intrinsics fixed, each observation gives
// [x]x (R_cam (R_prim (C p + o) + T) + t) = 0 with x the normalised image ray, linear in the
// free parameters p, primitive translations T and camera translations t. Solves it by least squares and
// writes the result into *state. Returns false (state untouched, *why set) when the system
// is rank deficient or the solution is not usable. kAuto takes a dense SVD up to 300 unknowns
// and the Schur complement over the primitive blocks (reduced camera system) above, so that a
// cold start of hundreds of primitives stays in milliseconds; the others force one (tests).
enum class LinearInitMethod { kAuto, kDense, kSchur };
bool LinearInitialization(const SceneProblem& problem, SceneState* state, std::string* why,
                          LinearInitMethod method = LinearInitMethod::kAuto);

// Names the parameters that the pins do not determine, from the rank of the column-scaled
// Jacobian at `state`. One sentence per primitive or camera; an overall scale or position
// ambiguity of the whole scene is reported once.
std::vector<std::string> UndeterminedParameterWarnings(const Project& project, const SceneProblem& problem,
                                                       const SceneState& state);

}  // namespace facet::scene_solve_internal
