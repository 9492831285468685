#include "core/solve/model_update.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

namespace facet {

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

namespace {

// The segments with their endpoints mapped (distorted photo px -> pinhole px).
template <typename Map>
std::vector<Segment> MapSegments(const std::vector<Segment>& segments, const Map& map) {
  std::vector<Segment> out = segments;
  for (Segment& s : out) {
    s.a_px = map(s.a_px);
    s.b_px = map(s.b_px);
  }
  return out;
}

// Distance from `center_px` to the farthest image corner (pixel centres at integers).
double MaxRadiusPx(const Image& image, const Eigen::Vector2d& center_px) {
  double r = 0.0;
  for (double u : {-0.5, image.width_px - 0.5}) {
    for (double v : {-0.5, image.height_px - 0.5}) r = std::max(r, (Eigen::Vector2d(u, v) - center_px).norm());
  }
  return r;
}

// The plumb-line estimate (k1) from an image's segments: each segment a 2-point polyline whose
// family is its axis, so the three families' vanishing points carry the information.
PlumbLineSummary EstimateDistortion(const Image& image, const std::vector<Segment>& segments) {
  std::vector<PlumbLine> lines;
  for (const Segment& s : segments) lines.push_back({{s.a_px, s.b_px}, static_cast<int>(s.axis)});
  PlumbLineOptions options;
  options.width_px = image.width_px;
  options.height_px = image.height_px;
  if (image.principal_point_mode == PrincipalPointMode::kFixed) options.center_px = image.fixed_principal_point_px;
  // k1 only: a user's segments are 2-point lines, from which k2 is mostly noise (k2 = 0.26 on
  // a distortion-free synthetic photo with 0.5 px clicks, enough to fold the model inside the
  // image); k1 carries the barrel or pincushion a wide lens shows.
  options.estimate_k2 = false;
  return EstimateRadialDistortion(lines, options);
}

// The camera's OpenCV k1, k2 for a plumb-line model at this focal length (the conversion
// depends on f: to first order k1_cv = -k1 (s / f)^2).
void SetOpenCvDistortion(const Image& image, const RadialDistortion& plumb, double focal_px, Camera* camera) {
  const OpenCvRadialCoefficients k =
      OpenCvFromRadialDistortion(plumb, focal_px, MaxRadiusPx(image, plumb.center_px), /*fit_k2=*/true);
  camera->k1 = k.k1;
  camera->k2 = k.k2;
}

// Calibrates one image from its segments. The segments are drawn on the photo, so they are
// straightened first: by the plumb-line model when distortion is estimated, else by the
// camera's own k (when non-zero). Both depend on the focal length the calibration finds, so
// the calibration runs twice: once to get f (and the principal point), once more with the
// segments undistorted by the camera model at that f. *camera receives k1, k2 (the other
// fields are the caller's to set from the summary).
VpCalibrationSummary CalibrateImage(const Image& image, const std::vector<Segment>& segments,
                                    const VpCalibrationOptions& options, const PlumbLineSummary* plumb,
                                    Camera* camera) {
  camera->width_px = image.width_px;
  camera->height_px = image.height_px;
  auto refine = [&](VpCalibrationSummary first) {
    if (!first.IsUsable()) return first;
    camera->focal_px = first.focal_px;
    camera->principal_point_px = first.principal_point_px;
    VpCalibrationSummary again = CalibrateFromVanishingLines(
        MapSegments(segments, [&](const Eigen::Vector2d& uv) { return camera->UndistortPixel(uv); }), options);
    return again.IsUsable() ? again : first;
  };
  if (plumb != nullptr && plumb->IsUsable()) {
    const RadialDistortion& d = plumb->distortion;
    VpCalibrationSummary vp = CalibrateFromVanishingLines(
        MapSegments(segments, [&](const Eigen::Vector2d& uv) { return d.Undistort(uv); }), options);
    if (!vp.IsUsable()) return vp;
    SetOpenCvDistortion(image, d, vp.focal_px, camera);
    vp = refine(std::move(vp));
    SetOpenCvDistortion(image, d, vp.focal_px, camera);
    return vp;
  }
  if (!camera->HasDistortion()) return CalibrateFromVanishingLines(segments, options);
  // k from the file: it refers to the camera's focal length, so a camera never calibrated
  // gets f from the raw segments first.
  if (!image.camera_calibrated) {
    const VpCalibrationSummary pinhole = CalibrateFromVanishingLines(segments, options);
    if (pinhole.IsUsable()) {
      camera->focal_px = pinhole.focal_px;
      camera->principal_point_px = pinhole.principal_point_px;
    }
  }
  return refine(CalibrateFromVanishingLines(
      MapSegments(segments, [&](const Eigen::Vector2d& uv) { return camera->UndistortPixel(uv); }), options));
}

// The image as the calibration step reads it, without its camera (ImageCalibrationCacheEntry).
Image CalibrationKey(const Image& image) {
  Image key = image;
  key.camera = Camera();
  key.axis_quarter_turns = Image::kAxisTurnsUnchosen;  // applied after the calibration
  key.axis_turn_provisional = false;
  return key;
}

// The intrinsics CalibrateImage reads from a camera with distortion (size and pose cleared).
Camera IntrinsicsOf(const Camera& camera) {
  Camera intrinsics;
  intrinsics.focal_px = camera.focal_px;
  intrinsics.principal_point_px = camera.principal_point_px;
  intrinsics.k1 = camera.k1;
  intrinsics.k2 = camera.k2;
  return intrinsics;
}

// A warm start can stall far from the answer (e.g. the first solve after calibration, when
// the camera still sits at the origin); a cold start is linear plus a few iterations, so it
// is cheap enough to try whenever the warm result looks wrong.
constexpr double kWarmStartSuspectRmsPx = 3.0;
// A plumb-line k1 must exceed this many standard deviations to be applied.
constexpr double kDistortionSignificanceSigmas = 3.0;

// The geometry solve, warm when asked, retried cold when the warm result looks wrong; the
// better of the two by cost.
void GeometrySolve(const Project& project, const SceneSolveOptions& options, SceneSolveSummary* summary,
                   Project* solved) {
  *summary = SolveScene(project, options, solved);
  const bool warm_suspect =
      options.warm_start && (!summary->IsUsable() || summary->reprojection_rms_px > kWarmStartSuspectRmsPx);
  if (!warm_suspect) return;
  SceneSolveOptions cold = options;
  cold.warm_start = false;
  cold.max_iterations = std::max(cold.max_iterations, 50);
  Project cold_solved;
  SceneSolveSummary cold_summary = SolveScene(project, cold, &cold_solved);
  if (cold_summary.IsUsable() && (!summary->IsUsable() || cold_summary.final_cost < summary->final_cost)) {
    *summary = std::move(cold_summary);
    *solved = std::move(cold_solved);
  } else if (!summary->IsUsable() && !cold_summary.IsUsable()) {
    // Both failed: the cold one's reason names why the pins give no start, which the user can act on.
    *summary = std::move(cold_summary);
  }
}

// Calibrates each image with line segments from its vanishing points (and its distortion from
// plumb lines when asked), reusing the cached results of images whose input did not change.
// *unchosen receives the images calibrated here whose world-frame turn is not chosen yet.
void CalibrateFromLines(Project* calibrated, ModelUpdateCache* cache, ModelUpdateSummary* summary,
                        std::vector<Id>* unchosen) {
  const auto calibration_start = std::chrono::steady_clock::now();
  std::map<Id, ImageCalibrationCacheEntry> next_cache;
  for (Image& image : calibrated->images) {
    ImageCalibrationCacheEntry entry;
    for (const Segment& s : calibrated->segments)
      if (s.image_id == image.id) entry.segments.push_back(s);
    // A camera from a reconstruction is better than its lines make it (Image::
    // camera_from_reconstruction): the joint solve still reads the lines, this step does not.
    if (entry.segments.empty() || image.camera_from_reconstruction) continue;
    entry.image = CalibrationKey(image);
    ImageCalibrationCacheEntry* cached = nullptr;
    if (cache != nullptr) {
      const auto it = cache->images.find(image.id);
      if (it != cache->images.end() && it->second.image == entry.image && it->second.segments == entry.segments)
        cached = &it->second;
    }

    entry.estimated_distortion = image.estimate_distortion;
    const PlumbLineSummary* plumb = nullptr;
    if (image.estimate_distortion) {
      if (cached != nullptr && cached->estimated_distortion) {
        entry.distortion = cached->distortion;
      } else {
        entry.distortion = EstimateDistortion(image, entry.segments);
        ++summary->distortion_estimates_run;
      }
      summary->distortion[image.id] = entry.distortion;
      if (!entry.distortion.IsUsable()) {
        summary->messages.push_back("Image '" + image.path +
                                    "': distortion not estimated: " + entry.distortion.message);
      }
      plumb = &entry.distortion;
    }
    Camera camera = image.camera;
    // An estimate within kDistortionSignificanceSigmas of zero is noise (a lens without
    // visible distortion, or too few lines): the camera stays a pinhole rather than take it.
    if (plumb != nullptr && plumb->IsUsable() &&
        !(std::abs(plumb->distortion.k1) > kDistortionSignificanceSigmas * plumb->k1_std)) {
      char text[200];
      std::snprintf(text, sizeof(text), "Image '%s': distortion k1 = %.4f +- %.4f is not significant; kept at 0",
                    image.path.c_str(), plumb->distortion.k1, plumb->k1_std);
      summary->messages.push_back(text);
      plumb = nullptr;
      camera.k1 = camera.k2 = 0.0;
    }
    // CalibrateImage reads the camera's intrinsics only to undistort the segments by its own k.
    entry.camera_read = !(plumb != nullptr && plumb->IsUsable()) && camera.HasDistortion();
    if (entry.camera_read) entry.camera = IntrinsicsOf(camera);
    if (cached != nullptr && cached->camera_read == entry.camera_read && cached->camera == entry.camera) {
      entry.calibration = std::move(cached->calibration);
      entry.k1 = cached->k1;
      entry.k2 = cached->k2;
      ++summary->images_reused;
    } else {
      entry.calibration = CalibrateImage(image, entry.segments, CalibrationOptionsFor(image), plumb, &camera);
      entry.k1 = camera.k1;
      entry.k2 = camera.k2;
      ++summary->images_calibrated;
    }
    const VpCalibrationSummary& vp = entry.calibration;
    if (vp.IsUsable()) {
      // Calibration fixes intrinsics and rotation; the camera keeps its centre, which the
      // geometry solve then moves.
      const Eigen::Vector3d center = image.camera.CenterInWorld();
      image.camera.width_px = image.width_px;
      image.camera.height_px = image.height_px;
      image.camera.focal_px = vp.focal_px;
      image.camera.principal_point_px = vp.principal_point_px;
      image.camera.k1 = entry.k1;
      image.camera.k2 = entry.k2;
      // The recorded turn about the vertical puts the lines' axes in the model's world frame
      // (core/solve/world_frames.h); an image without one, or with a provisional one, is
      // chosen after this loop from the lines' own axes.
      const bool choose = image.axis_quarter_turns == Image::kAxisTurnsUnchosen || image.axis_turn_provisional;
      if (choose) unchosen->push_back(image.id);
      image.camera.SetPose(vp.cam_from_world_rotation * AxisTurn(choose ? 0 : image.axis_quarter_turns), center);
      image.camera_calibrated = true;
    } else {
      (vp.incomplete ? summary->progress : summary->messages).push_back("Image '" + image.path + "': " + vp.message);
    }
    summary->calibration[image.id] = vp;
    if (cache != nullptr) next_cache[image.id] = std::move(entry);
  }
  if (cache != nullptr) cache->images = std::move(next_cache);
  summary->calibration_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - calibration_start).count();
}

// Cameras of images without line families, from their pins (core/solve/multiview_init.h). After
// the geometry solve: resection reads the solved model's vertex positions; then the geometry
// solve runs again with the new cameras taking part.
void InitializeFromPinsAndResolve(const MultiViewInitOptions& multiview_options, const SceneSolveOptions& solve_options,
                                  Project* updated, ModelUpdateSummary* summary) {
  Project initialised;
  summary->multiview = CalibrateImagesFromPins(*updated, multiview_options, &initialised);
  for (const std::string& m : summary->multiview.messages) summary->messages.push_back(m);
  // A guessed focal length (two views without a known lens) is only a start: the joint
  // solve refines it, which a user can lock again once it settles.
  for (const MultiViewImageReport& report : summary->multiview.images) {
    if (!report.initialized || !report.focal_guessed) continue;
    if (Image* image = initialised.FindImage(report.image_id)) image->focal_locked = false;
  }
  if (summary->multiview.num_initialized > 0) {
    SceneSolveSummary again;
    Project resolved;
    GeometrySolve(initialised, solve_options, &again, &resolved);
    if (again.IsUsable()) {
      summary->solve = std::move(again);
      *updated = std::move(resolved);
    } else {
      *updated = std::move(initialised);
      if (again.termination != SolverTermination::kNothingToSolve)
        summary->messages.push_back("Solve with the cameras from pins: " + again.message);
    }
  }
}

}  // namespace

bool ModelUpdateOptions::Check(std::string* error) const {
  std::string why;
  auto fail = [&](const char* step) {
    if (error != nullptr) *error = std::string(step) + ": " + why;
    return false;
  };
  if (!solve.Check(&why)) return fail("geometry solve");
  if (!multiview.Check(&why)) return fail("initialisation from pins");
  if (!joint.Check(&why)) return fail("joint solve");
  return true;
}

ModelUpdateOptions CommitUpdateOptions() {
  ModelUpdateOptions options;
  options.solve.warm_start = true;
  options.solve.max_iterations = 100;
  options.joint.polish_constraints = true;
  return options;
}

ModelUpdateOptions DragFrameUpdateOptions(int iterations) {
  ModelUpdateOptions options;
  options.solve.warm_start = true;
  options.solve.max_iterations = iterations;
  options.joint.max_iterations = iterations;
  options.joint.compute_diagnostics = false;
  options.joint.polish_constraints = false;
  // Plain least squares while a pin is dragged: the model follows the pin the user moves
  // (the robust loss would down-weight it as soon as it left the others' spread, and the
  // drag would seem to do nothing). The release's commit solve is robust and flags the pin
  // if the other pins disagree with where it was left.
  options.joint.robust_pins = false;
  options.initialize_from_pins = false;
  options.geometry_solve_when_warm = false;
  return options;
}

ModelUpdateSummary UpdateModel(const Project& edited, const ModelUpdateOptions& options, Project* updated,
                               ModelUpdateCache* cache) {
  const auto start = std::chrono::steady_clock::now();
  ModelUpdateSummary summary;
  Project calibrated = edited;

  if (options.calibrate) {
    std::vector<Id> unchosen;
    CalibrateFromLines(&calibrated, cache, &summary, &unchosen);
    if (!unchosen.empty()) {
      summary.world_frames = ReconcileWorldFrames(unchosen, &calibrated);
      for (const WorldFrameChoice& choice : summary.world_frames) {
        if (choice.note.empty()) continue;
        (choice.provisional ? summary.warnings : summary.notes).push_back(choice.note);
      }
    }
  }

  // The per-frame path: the joint solve alone, warm; the geometry solve below only when that
  // does not hold up.
  if (options.solve.warm_start && options.joint_solve && !options.geometry_solve_when_warm) {
    JointSolveOptions joint_options = options.joint;
    joint_options.warm_start = true;
    Project joint_solved;
    JointSolveSummary joint = SolveJoint(calibrated, joint_options, &joint_solved);
    if (joint.IsUsable() && joint.reprojection_rms_px <= kWarmStartSuspectRmsPx) {
      summary.joint = std::move(joint);
      *updated = std::move(joint_solved);
      summary.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
      return summary;
    }
  }

  SceneSolveOptions solve_options = options.solve;
  Project solved;
  GeometrySolve(calibrated, solve_options, &summary.solve, &solved);

  std::string degenerate_geometry;
  if (summary.solve.IsUsable()) degenerate_geometry = WhySolvedModelDegenerate(edited, solved);
  if (!degenerate_geometry.empty()) {
    // Its linear start or its steps took a size to zero or below: no result (issue 14).
    *updated = edited;
    summary.ok = false;
    summary.messages.push_back("Solve: " + degenerate_geometry + "; the model is unchanged");
  } else if (summary.solve.IsUsable()) {
    *updated = std::move(solved);
  } else {
    // Nothing to do keeps the calibrated cameras; a failure leaves the whole project as the
    // edit made it (model_update.h: never half-updated).
    *updated = summary.solve.termination == SolverTermination::kNothingToSolve ? std::move(calibrated) : edited;
    if (summary.solve.termination != SolverTermination::kNothingToSolve) {
      summary.ok = false;
      summary.messages.push_back("Solve: " + summary.solve.message);
    }
  }

  if (options.initialize_from_pins && summary.ok)
    InitializeFromPinsAndResolve(options.multiview, solve_options, updated, &summary);
  // A dimension held because no pin sees it is the likely surprise in the result (a box as
  // deep as it was made): the user reads why and what would fix it.
  for (const std::string& held : summary.solve.held_parameters) summary.messages.push_back("Solve: " + held);

  if (options.joint_solve && summary.ok) {
    JointSolveOptions joint_options = options.joint;
    joint_options.warm_start = true;  // from the geometry solve's result
    Project joint_solved;
    summary.joint = SolveJoint(*updated, joint_options, &joint_solved);
    for (const std::string& held : summary.joint.held_intrinsics) summary.messages.push_back("Joint solve: " + held);
    if (summary.joint.IsUsable()) {
      *updated = std::move(joint_solved);
      // A pin far beyond the others' spread is most likely a wrong click: named so that the
      // user can move or drop it (the robust loss already keeps it from pulling the cameras).
      for (const FlaggedPin& flagged : summary.joint.flagged_pins)
        summary.messages.push_back("Joint solve: " + flagged.sentence);
    } else if (summary.joint.degenerate || summary.joint.termination == SolverTermination::kFailed) {
      // Its sizes went to zero or below, or it diverged from the geometry solve's result: the
      // model keeps the state the edit left it in, as the joint solve's message says ("the
      // model is unchanged"). Keeping the geometry solve's result instead saved a camera
      // 4,728 km away under that message (k1 = 1e308, issue 25).
      *updated = edited;
      summary.ok = false;
      summary.messages.push_back("Joint solve: " + summary.joint.message);
    } else if (summary.joint.termination != SolverTermination::kNothingToSolve) {
      // The geometry solve's result stands; the joint refinement says why it did not apply.
      summary.messages.push_back("Joint solve: " + summary.joint.message);
    }
  }
  // Whichever step gave it, a model with a size at or below zero or shrunk to nothing is no
  // result (issue 14): the project stays as the edit made it.
  if (const std::string degenerate = WhySolvedModelDegenerate(edited, *updated); !degenerate.empty()) {
    *updated = edited;
    summary.ok = false;
    summary.messages.push_back("Solve: " + degenerate + "; the model is unchanged");
  }
  summary.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

}  // namespace facet
