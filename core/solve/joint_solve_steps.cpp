#include "core/solve/joint_solve_steps.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

namespace facet {

JointSolveSteps BeginJointSolveSteps(const Project& start, const JointSolveOptions& options) {
  JointSolveSteps steps;
  steps.start = start;
  steps.current = start;
  steps.options = options;
  steps.options.polish_constraints = false;  // not a Levenberg-Marquardt iteration
  return steps;
}

bool StepJointSolve(JointSolveSteps* steps, JointSolveSummary* failure) {
  if (steps->finished) return false;
  JointSolveOptions options = steps->options;
  options.max_iterations = steps->steps + 1;
  Project next;
  std::vector<LmIteration> trace;
  const JointSolveSummary summary = SolveJointTraced(steps->start, options, &next, &trace);
  if (!summary.IsUsable()) {
    if (failure != nullptr) *failure = summary;
    return false;
  }
  ++steps->steps;
  steps->current = std::move(next);
  steps->trace = std::move(trace);
  steps->summary = summary;
  steps->finished = summary.termination != SolverTermination::kMaxIterations;
  return true;
}

void ResetJointSolveSteps(JointSolveSteps* steps) {
  steps->steps = 0;
  steps->current = steps->start;
  steps->trace.clear();
  steps->summary = JointSolveSummary();
  steps->finished = false;
}

JointSolveOptions SolveStepsOptions() {
  JointSolveOptions options;
  options.compute_diagnostics = false;
  return options;
}

Project PerturbForSteps(const Project& project, double amount) {
  Project out = project;
  if (amount == 0.0) return out;
  Eigen::AlignedBox3d bounds;
  for (const Primitive& primitive : project.primitives)
    for (VertexId v = 0; v < primitive.mesh.VertexIdEnd(); ++v)
      if (primitive.mesh.IsVertex(v)) bounds.extend(primitive.mesh.vertex(v).position);
  const double size = bounds.isEmpty() ? 1.0 : std::max(bounds.diagonal().norm(), 1e-9);
  const Eigen::Vector3d center = bounds.isEmpty() ? Eigen::Vector3d::Zero().eval() : bounds.center().eval();
  constexpr double kTurnPerAmountRad = 20.0 * M_PI / 180.0;
  // Fixed, oblique directions, so that every coordinate moves and no lesson depends on chance.
  const Eigen::Vector3d turn_axis = Eigen::Vector3d(1.0, -2.0, 3.0).normalized();
  const Eigen::Vector3d camera_shift = Eigen::Vector3d(1.0, -1.0, 0.5).normalized();
  const Eigen::Vector3d primitive_shift = Eigen::Vector3d(0.6, -0.3, 0.2).normalized();
  double sign = 1.0;
  for (Image& image : out.images) {
    if (!image.camera_calibrated) continue;
    Camera& camera = image.camera;
    if (!image.pose_locked) {
      const Eigen::Vector3d c = camera.CenterInWorld();
      const Eigen::Matrix3d turn = Eigen::AngleAxisd(sign * amount * kTurnPerAmountRad, turn_axis).toRotationMatrix();
      camera.SetPose(camera.cam_from_world_rotation * turn, c + sign * amount * (c - center).norm() * camera_shift);
    }
    if (!image.focal_locked) camera.focal_px *= 1.0 + amount;
    sign = -sign;
  }
  sign = 1.0;
  for (Primitive& primitive : out.primitives) {
    PrimitiveShape& shape = primitive.shape;
    for (int k = 0; k < shape.params.size(); ++k)
      if (!primitive.param_locked[k]) shape.params(k) *= 1.0 + (k % 2 == 0 ? amount : -amount);
    if (primitive.attached_to == kNoId) {
      if (!primitive.translation_locked) shape.translation += sign * amount * size * primitive_shift;
      if (!primitive.rotation_locked) shape.rotation.z() += sign * amount * kTurnPerAmountRad;
    }
    sign = -sign;
  }
  RefreshAllPrimitives(&out);
  return out;
}

}  // namespace facet
