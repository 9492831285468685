#include "core/model_update.h"

#include <chrono>

namespace facet {
namespace {

VpCalibrationOptions CalibrationOptionsFor(const Image& image) {
  VpCalibrationOptions options;
  options.width_px = image.width_px;
  options.height_px = image.height_px;
  options.principal_point_mode = image.principal_point_mode;
  options.fixed_principal_point_px = image.fixed_principal_point_px;
  switch (image.focal_mode) {
    case FocalMode::kSolve: break;
    case FocalMode::kFixed: options.fixed_focal_px = image.fixed_focal_px; break;
    case FocalMode::kPrior:
      options.focal_prior_px = image.focal_prior_px;
      options.focal_prior_std_px = image.focal_prior_std_px;
      break;
  }
  options.use_horizon = image.use_horizon;
  options.horizon_px = image.horizon_px;
  return options;
}

// A warm start can stall far from the answer (e.g. the first solve after calibration, when
// the camera still sits at the origin); a cold start is linear plus a few iterations, so it
// is cheap enough to try whenever the warm result looks wrong.
constexpr double kWarmStartSuspectRmsPx = 3.0;

}  // namespace

ModelUpdateSummary UpdateModel(const Project& edited, const ModelUpdateOptions& options, Project* updated) {
  const auto start = std::chrono::steady_clock::now();
  ModelUpdateSummary summary;
  Project calibrated = edited;

  if (options.calibrate) {
    for (Image& image : calibrated.images) {
      std::vector<Segment> segments;
      for (const Segment& s : calibrated.segments)
        if (s.image_id == image.id) segments.push_back(s);
      if (segments.empty()) continue;
      VpCalibrationSummary vp = CalibrateFromVanishingLines(segments, CalibrationOptionsFor(image));
      if (vp.IsUsable()) {
        // Calibration fixes intrinsics and rotation; the camera keeps its centre, which the
        // geometry solve then moves.
        const Eigen::Vector3d center = image.camera.CenterInWorld();
        image.camera.width_px = image.width_px;
        image.camera.height_px = image.height_px;
        image.camera.focal_px = vp.focal_px;
        image.camera.principal_point_px = vp.principal_point_px;
        image.camera.SetPose(vp.cam_from_world_rotation, center);
        image.camera_calibrated = true;
      } else {
        summary.messages.push_back("Image '" + image.path + "': " + vp.message);
      }
      summary.calibration[image.id] = std::move(vp);
    }
  }

  SceneSolveOptions solve_options = options.solve;
  Project solved;
  summary.solve = SolveScene(calibrated, solve_options, &solved);
  const bool warm_suspect = solve_options.warm_start &&
                            (!summary.solve.IsUsable() || summary.solve.reprojection_rms_px > kWarmStartSuspectRmsPx);
  if (warm_suspect) {
    SceneSolveOptions cold = solve_options;
    cold.warm_start = false;
    cold.max_iterations = std::max(cold.max_iterations, 50);
    Project cold_solved;
    SceneSolveSummary cold_summary = SolveScene(calibrated, cold, &cold_solved);
    if (cold_summary.IsUsable() &&
        (!summary.solve.IsUsable() || cold_summary.final_cost < summary.solve.final_cost)) {
      summary.solve = std::move(cold_summary);
      solved = std::move(cold_solved);
    }
  }

  if (summary.solve.IsUsable()) {
    *updated = std::move(solved);
  } else {
    // Nothing to do keeps the calibrated cameras; a failure leaves the whole project as the
    // edit made it (model_update.h: never half-updated).
    *updated = summary.solve.termination == SolveTermination::kNothingToSolve ? std::move(calibrated) : edited;
    if (summary.solve.termination != SolveTermination::kNothingToSolve) {
      summary.ok = false;
      summary.messages.push_back("Solve: " + summary.solve.message);
    }
  }

  if (options.joint_solve && summary.ok) {
    JointSolveOptions joint_options = options.joint;
    joint_options.warm_start = true;  // from the geometry solve's result
    Project joint_solved;
    summary.joint = SolveJoint(*updated, joint_options, &joint_solved);
    if (summary.joint.IsUsable()) {
      *updated = std::move(joint_solved);
    } else if (summary.joint.termination != JointSolveSummary::Termination::kNothingToSolve) {
      // The geometry solve's result stands; the joint refinement says why it did not apply.
      summary.messages.push_back("Joint solve: " + summary.joint.message);
    }
  }
  summary.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

}  // namespace facet
