// A reconstruction's cameras into the project's frame (core/solve/colmap_alignment.h), on
// synthetic data: the project's own cameras, and the "reconstruction" the same cameras under a
// known similarity (scale 0.37, an arbitrary rotation, an offset), as a COLMAP model
// (ColmapModelFromProject) imported by ApplyAlignedColmapCameras. Noise-free, so the aligned
// cameras must equal the originals to 1e-9 (relative to the scene's size of ~10 units):
// - three cameras in common: everything from them;
// - one camera in common: rotation and position from it, the scale from a kept box size
//   triangulated from pins in two photos, or kept (and said) without one;
// - no camera in common: up and heading from line families (turn 0 from the first photo, or an
//   image's recorded quarter turn), else up from the cameras.
#include <doctest/doctest.h>

#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "core/io/colmap_import.h"
#include "core/io/colmap_model_write.h"
#include "core/mesh/box.h"
#include "core/io/project_io.h"
#include "core/solve/colmap_alignment.h"
#include "core/solve/model_update.h"
#include "core/solve/world_frames.h"

using namespace facet;

namespace {

constexpr double kExact = 1e-9;  // noise-free: rounding only, on a scene ~10 units across
constexpr double kRadToDeg = 180.0 / M_PI;

// reconstruction_from_project: what the reconstruction's frame is to the project's.
SimilarityTransform ReconstructionFromProject() {
  SimilarityTransform t;
  t.scale = 0.37;
  t.rotation = Eigen::AngleAxisd(2.3, Eigen::Vector3d(0.4, -0.7, 0.2).normalized()).toRotationMatrix();
  t.translation = Eigen::Vector3d(3.0, -11.0, 4.5);
  return t;
}

Camera LookAt(const Eigen::Vector3d& center, const Eigen::Vector3d& target) {
  Camera camera;
  camera.width_px = 1200;
  camera.height_px = 800;
  camera.focal_px = 1100.0;
  camera.principal_point_px = Eigen::Vector2d(601.0, 398.5);
  camera.k1 = -0.05;
  camera.SetPose(CamFromWorldLookingAlong((target - center).normalized()), center);
  return camera;
}

// Three photos of a box at the origin, from the front-left, front and front-right (x forward
// component positive for the first: its x family points into the photo).
Project ThreeCameraProject() {
  Project project;
  const std::vector<Eigen::Vector3d> centers = {{-6.0, -9.0, 1.6}, {1.0, -10.0, 2.4}, {8.0, -7.0, 1.2}};
  for (size_t i = 0; i < centers.size(); ++i) {
    Image image;
    image.id = project.NewId();
    image.path = "photos/p" + std::to_string(i) + ".jpg";
    image.width_px = 1200;
    image.height_px = 800;
    image.camera = LookAt(centers[i], Eigen::Vector3d(0.5, 0.0, 1.0));
    image.camera_calibrated = true;
    project.images.push_back(image);
  }
  return project;
}

// The project's photos as a COLMAP model in the reconstruction's frame.
ColmapModel Reconstruction(const Project& truth) {
  Project moved = truth;
  for (Image& image : moved.images) TransformCamera(ReconstructionFromProject(), &image.camera);
  ColmapModel model;
  ColmapExportOptions options;
  options.include_points = false;
  REQUIRE(ColmapModelFromProject(moved, options, &model) == "");
  return model;
}

void CheckCameraNear(const Camera& got, const Camera& want, double tolerance, const std::string& what) {
  const double center_error = (got.CenterInWorld() - want.CenterInWorld()).norm();
  const double rotation_error = (got.cam_from_world_rotation - want.cam_from_world_rotation).norm();
  INFO(what << ": centre off by " << center_error << ", rotation by " << rotation_error);
  CHECK(center_error < tolerance);
  CHECK(rotation_error < tolerance);
  CHECK(std::abs(got.focal_px - want.focal_px) < tolerance * want.focal_px);
  CHECK((got.principal_point_px - want.principal_point_px).norm() < tolerance * want.focal_px);
}

// Segments of the world-axis lines through a grid of points, as the photo shows them
// (distorted by its lens), for the family `axis`.
void AddLines(Project* project, const Image& image, Axis axis) {
  const int a = static_cast<int>(axis);
  for (int k = 0; k < 4; ++k) {
    Eigen::Vector3d start(-1.0 + 0.8 * k, 0.3 * k, 0.2 + 0.7 * k);
    start(a) = -1.0;
    Eigen::Vector3d end = start;
    end(a) = 2.0;
    Segment s;
    s.id = project->NewId();
    s.image_id = image.id;
    s.axis = axis;
    s.a_px = image.camera.Project(start);
    s.b_px = image.camera.Project(end);
    project->segments.push_back(s);
  }
}

}  // namespace

TEST_CASE("three cameras in common: the aligned cameras equal the project's to 1e-9") {
  const Project truth = ThreeCameraProject();
  Project project = truth;
  ColmapImportReport report;
  ColmapAlignmentSummary alignment;
  const std::string error =
      ApplyAlignedColmapCameras(Reconstruction(truth), ColmapAlignmentOptions{}, &project, &report, &alignment);
  REQUIRE_MESSAGE(error == "", error);
  CHECK(report.updated_images.size() == 3);
  CHECK(alignment.message == "rotation: 3 cameras in common; scale: 3 camera centres; position: 3 camera centres");
  CHECK(alignment.rotation_source == AlignmentSource::kCommonCameras);
  CHECK(alignment.scale_source == AlignmentSource::kCommonCameras);
  CHECK(std::abs(alignment.project_from_reconstruction.scale - 1.0 / 0.37) < kExact);
  CHECK(alignment.center_fit_rotation_deg >= 0.0);
  CHECK(alignment.center_fit_rotation_deg < 1e-6);
  CHECK(alignment.center_rms < kExact);
  CHECK(alignment.warnings.empty());
  for (size_t i = 0; i < truth.images.size(); ++i)
    CheckCameraNear(project.images[i].camera, truth.images[i].camera, kExact, truth.images[i].path);

  // Two in common (the third uncalibrated in the project): the same from their rotations and
  // two centres; the third camera lands on its true place too.
  Project two = truth;
  two.images[2].camera_calibrated = false;
  two.images[2].camera = Camera();
  REQUIRE(ApplyAlignedColmapCameras(Reconstruction(truth), ColmapAlignmentOptions{}, &two, &report, &alignment) == "");
  CHECK(alignment.message == "rotation: 2 cameras in common; scale: 2 camera centres; position: 2 camera centres");
  CHECK(alignment.center_fit_rotation_deg == -1.0);
  for (size_t i = 0; i < truth.images.size(); ++i)
    CheckCameraNear(two.images[i].camera, truth.images[i].camera, kExact, truth.images[i].path);
}

TEST_CASE("cameras in common that disagree with the reconstruction are named; mirrored centres are refused") {
  const Project truth = ThreeCameraProject();
  Project project = truth;
  // The project's second camera turned 5 deg: the others' rotations outvote it, and it is named.
  project.images[1].camera.SetPose(project.images[1].camera.cam_from_world_rotation *
                                       Eigen::AngleAxisd(5.0 / kRadToDeg, Eigen::Vector3d::UnitZ()).toRotationMatrix(),
                                   project.images[1].camera.CenterInWorld());
  ColmapImportReport report;
  ColmapAlignmentSummary alignment;
  REQUIRE(ApplyAlignedColmapCameras(Reconstruction(truth), ColmapAlignmentOptions{}, &project, &report, &alignment) ==
          "");
  bool named = false;
  for (const std::string& w : alignment.warnings) named |= w.find("photos/p1.jpg") != std::string::npos;
  CHECK_MESSAGE(named, "warnings: " << alignment.warnings.size());
  CHECK(alignment.rotation_rms_deg > 1.0);

  // Centres mirrored through their mean against the rotations: no positive scale, nothing changes.
  Project mirrored = truth;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Image& image : truth.images) mean += image.camera.CenterInWorld() / 3.0;
  for (Image& image : mirrored.images)
    image.camera.SetPose(image.camera.cam_from_world_rotation, 2.0 * mean - image.camera.CenterInWorld());
  const Project unchanged = mirrored;
  const std::string error =
      ApplyAlignedColmapCameras(Reconstruction(truth), ColmapAlignmentOptions{}, &mirrored, &report, &alignment);
  CHECK(error.find("no positive scale") != std::string::npos);
  CHECK(mirrored == unchanged);
}

TEST_CASE("one camera in common: rotation and position from it, the scale from a kept box size, else kept") {
  const Project truth = ThreeCameraProject();
  Project project = truth;
  for (size_t i = 1; i < project.images.size(); ++i) {
    project.images[i].camera_calibrated = false;
    project.images[i].camera = Camera();
  }
  // No known length: the scale is the reconstruction's, and said so.
  Project unscaled = project;
  ColmapImportReport report;
  ColmapAlignmentSummary alignment;
  REQUIRE(ApplyAlignedColmapCameras(Reconstruction(truth), ColmapAlignmentOptions{}, &unscaled, &report, &alignment) ==
          "");
  CHECK(alignment.message.find("rotation: 1 camera in common; scale: kept") == 0);
  CHECK(alignment.message.find("position: 1 camera in common") != std::string::npos);
  CHECK(alignment.scale_source == AlignmentSource::kKept);
  CHECK(alignment.project_from_reconstruction.scale == 1.0);
  CheckCameraNear(unscaled.images[0].camera, truth.images[0].camera, kExact, "the common camera");
  const double true_baseline = (truth.images[2].camera.CenterInWorld() - truth.images[0].camera.CenterInWorld()).norm();
  const double kept_baseline =
      (unscaled.images[2].camera.CenterInWorld() - unscaled.images[0].camera.CenterInWorld()).norm();
  CHECK(std::abs(kept_baseline / true_baseline - 0.37) < kExact);

  // A box 3 x 2 x 2.5 with its height kept, its corners 0 and 4 pinned in photos 1 and 2 (not
  // the common one): the height, triangulated in the reconstruction, sets the scale.
  Id box_id = kNoId;
  std::string message;
  REQUIRE(AddPrimitiveToProject(&project, MakeBox(0, Eigen::Vector3d(3.0, 2.0, 2.5)), "box", &box_id, &message));
  project.FindPrimitive(box_id)->param_locked[2] = true;
  for (VertexId v : {VertexId{0}, VertexId{4}})
    for (size_t i = 1; i < 3; ++i) {
      Pin pin;
      pin.id = project.NewId();
      pin.image_id = truth.images[i].id;
      pin.vertex = {box_id, v};
      pin.uv_px = truth.images[i].camera.Project(VertexInWorld(project, pin.vertex));
      project.pins.push_back(pin);
    }
  REQUIRE(ApplyAlignedColmapCameras(Reconstruction(truth), ColmapAlignmentOptions{}, &project, &report, &alignment) ==
          "");
  CHECK(alignment.message == "rotation: 1 camera in common; scale: known length 2.5 m; position: 1 camera in common");
  CHECK(alignment.scale_source == AlignmentSource::kKnownLength);
  CHECK(alignment.num_known_lengths == 1);
  for (size_t i = 0; i < truth.images.size(); ++i)
    CheckCameraNear(project.images[i].camera, truth.images[i].camera, 1e-8, truth.images[i].path);
}

TEST_CASE("no camera in common: up and heading from the line families, the scale and position kept") {
  const Project truth = ThreeCameraProject();
  Project project = truth;
  for (Image& image : project.images) {
    image.camera_calibrated = false;
    image.camera = Camera();
  }
  // Vertical lines on photos 0 and 2, horizontal x lines on photo 0 (the reference: turn 0),
  // y lines on photo 1 (no turn recorded: modulo 90 deg).
  AddLines(&project, truth.images[0], Axis::kZ);
  AddLines(&project, truth.images[2], Axis::kZ);
  AddLines(&project, truth.images[0], Axis::kX);
  AddLines(&project, truth.images[1], Axis::kY);
  REQUIRE(truth.images[0].camera.cam_from_world_rotation(2, 0) > 0.05);  // x points into photo 0
  Project aligned = project;
  ColmapImportReport report;
  ColmapAlignmentSummary alignment;
  REQUIRE(ApplyAlignedColmapCameras(Reconstruction(truth), ColmapAlignmentOptions{}, &aligned, &report, &alignment) ==
          "");
  CHECK(alignment.message ==
        "rotation: up from vertical lines in 2 photos, heading from horizontal lines in 2 photos; scale: kept (no "
        "camera in common and no known length the photos see); position: kept (no camera in common)");
  CHECK(alignment.rotation_source == AlignmentSource::kLineFamilies);
  CHECK(alignment.num_line_families == 4);
  CHECK(alignment.warnings.empty());
  for (size_t i = 0; i < truth.images.size(); ++i) {
    const double error =
        (aligned.images[i].camera.cam_from_world_rotation - truth.images[i].camera.cam_from_world_rotation).norm();
    INFO(truth.images[i].path << ": rotation off by " << error);
    CHECK(error < kExact);
  }
  // Scale and origin are the reconstruction's: the centres differ from the truth's by 0.37 and
  // a shift, no turn.
  const Eigen::Vector3d true_step = truth.images[2].camera.CenterInWorld() - truth.images[0].camera.CenterInWorld();
  const Eigen::Vector3d step = aligned.images[2].camera.CenterInWorld() - aligned.images[0].camera.CenterInWorld();
  CHECK((step - 0.37 * true_step).norm() < kExact);

  // The turn each photo with horizontal lines needs for its calibration from lines to keep
  // this heading is recorded: 0 for photo 0 (the reference) and photo 1 (y lines along y).
  CHECK(alignment.chosen_turns == std::vector<std::pair<Id, int>>{{truth.images[0].id, 0}, {truth.images[1].id, 0}});
  CHECK(aligned.images[1].axis_quarter_turns == 0);
  CHECK(aligned.images[2].axis_quarter_turns == Image::kAxisTurnsUnchosen);  // no horizontal lines

  // Photo 1's lines along the world's y labelled x (the labeller's choice): the heading is the
  // same (photo 1 counts modulo 90 deg), and its turn is 3, which makes its x family the world's y.
  Project relabelled = project;
  for (Segment& s : relabelled.segments)
    if (s.image_id == truth.images[1].id) s.axis = Axis::kX;
  REQUIRE(ApplyAlignedColmapCameras(Reconstruction(truth), ColmapAlignmentOptions{}, &relabelled, &report,
                                    &alignment) == "");
  CHECK((relabelled.images[1].camera.cam_from_world_rotation - truth.images[1].camera.cam_from_world_rotation).norm() <
        kExact);
  CHECK(relabelled.images[1].axis_quarter_turns == 3);
  CHECK(WorldAxisOfFamily(0, 3) == 1);

  // Photo 0's turn recorded as 1: its x family is the world's y, the world turned with it.
  project.images[0].axis_quarter_turns = 1;
  aligned = project;
  REQUIRE(ApplyAlignedColmapCameras(Reconstruction(truth), ColmapAlignmentOptions{}, &aligned, &report, &alignment) ==
          "");
  for (size_t i = 0; i < truth.images.size(); ++i) {
    const Eigen::Matrix3d want = truth.images[i].camera.cam_from_world_rotation * AxisTurn(1);
    CHECK((aligned.images[i].camera.cam_from_world_rotation - want).norm() < kExact);
  }
}

TEST_CASE("no camera in common and no line family: up from the cameras, said so") {
  const Project truth = ThreeCameraProject();
  // Level cameras (looking horizontally): the mean of their up vectors is the world's up.
  Project level = truth;
  for (Image& image : level.images) {
    Eigen::Vector3d forward = -image.camera.CenterInWorld();
    forward.z() = 0.0;
    image.camera.SetPose(CamFromWorldLookingAlong(forward.normalized()), image.camera.CenterInWorld());
  }
  Project project = level;
  for (Image& image : project.images) {
    image.camera_calibrated = false;
    image.camera = Camera();
  }
  ColmapImportReport report;
  ColmapAlignmentSummary alignment;
  REQUIRE(ApplyAlignedColmapCameras(Reconstruction(level), ColmapAlignmentOptions{}, &project, &report, &alignment) ==
          "");
  CHECK(alignment.rotation_source == AlignmentSource::kCameraUp);
  CHECK(alignment.message.find(
            "rotation: up from the mean of 3 cameras (no line family on the photos), heading kept") == 0);
  for (const Image& image : project.images) {
    const Eigen::Vector3d up = -image.camera.cam_from_world_rotation.row(1).transpose();
    CHECK((up - Eigen::Vector3d::UnitZ()).norm() < kExact);
  }
}

TEST_CASE("alignment refusals: no registered image, bad options") {
  Project project = ThreeCameraProject();
  const Project before = project;
  ColmapAlignmentSummary summary = AlignReconstructionToProject(before, {}, ColmapAlignmentOptions{}, &project);
  CHECK(summary.termination == SolverTermination::kInvalidInput);
  CHECK(project == before);
  ColmapAlignmentOptions bad;
  bad.min_forward_component = 1.5;
  summary = AlignReconstructionToProject(before, {before.images[0].id}, bad, &project);
  CHECK(summary.termination == SolverTermination::kInvalidInput);
  CHECK(summary.message.find("min_forward_component") != std::string::npos);
  CHECK(project == before);
}

TEST_CASE("cameras from COLMAP are held: the next update neither recalibrates them from their lines nor moves them") {
  // Photo 0 has all three line families, drawn 1.5 px off (a user's): its calibration from
  // lines alone lands degrees and percents away from COLMAP's camera. After the import, the
  // update that follows every edit must keep COLMAP's camera exactly.
  const Project truth = ThreeCameraProject();
  Project project = truth;
  for (Axis axis : {Axis::kX, Axis::kY, Axis::kZ}) AddLines(&project, truth.images[0], axis);
  int k = 0;
  for (Segment& s : project.segments) s.b_px += 1.5 * Eigen::Vector2d(std::cos(0.7 * ++k), std::sin(1.3 * k));
  for (Image& image : project.images) {
    image.camera_calibrated = false;
    image.camera = Camera();
  }
  // Without the import, the lines calibrate photo 0 by themselves: how far that is.
  Project from_lines;
  REQUIRE(UpdateModel(project, CommitUpdateOptions(), &from_lines).ok);
  REQUIRE(from_lines.images[0].camera_calibrated);
  const double lines_focal_error = std::abs(from_lines.images[0].camera.focal_px / truth.images[0].camera.focal_px - 1);

  Project imported = project;
  ColmapImportReport report;
  ColmapAlignmentSummary alignment;
  REQUIRE(ApplyAlignedColmapCameras(Reconstruction(truth), ColmapAlignmentOptions{}, &imported, &report, &alignment) ==
          "");
  for (const Image& image : imported.images) {
    CHECK(image.camera_from_reconstruction);
    CHECK(image.pose_locked);
    CHECK(image.focal_locked);
  }
  Project updated;
  const ModelUpdateSummary summary = UpdateModel(imported, CommitUpdateOptions(), &updated);
  CHECK(summary.ok);
  CHECK(summary.images_calibrated == 0);
  for (size_t i = 0; i < imported.images.size(); ++i) {
    CAPTURE(i);
    CHECK(updated.images[i].camera == imported.images[i].camera);  // bit for bit
  }
  MESSAGE("photo 0's lines alone: focal length " << 100 * lines_focal_error << " % off; held: unchanged");
  CHECK(lines_focal_error > 1e-3);  // the case shows what holding saves

  // The mark round-trips; files without it read as before.
  const ProjectLoadResult loaded = ProjectFromJson(ProjectToJson(updated));
  REQUIRE_MESSAGE(loaded.ok(), loaded.error);
  CHECK(loaded.project == updated);
  CHECK(ProjectToJson(project).find("camera_from_reconstruction") == std::string::npos);
}
