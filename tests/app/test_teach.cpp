// Teach mode through the real application (View > Teach, app/state/teach.h): the geometry the
// overlays draw, read back from the render report, against the synthetic cameras that made the
// scene: the vanishing construction (orthocentre = principal point, circles, f, horizon,
// directions), the epipolar lines of a selected pin and of the pointer, the Numbers window's
// F (x_b^T F x_a = 0) and its copy buttons, the modelling state per History entry, the two
// rays of a selected vertex's pins and their closest points in 3D; the Solver steps window
// (N steps = one solve of N iterations, Reset, residual vectors, the document untouched), and
// the same for the vanishing-point fit (residuals per segment, the vanishing points' paths, f
// per step) and the two-view refinement of F (epipolar lines and distances per match);
// File > Export view headless (`render --panel`). Then the screenshots of each overlay
// (FACET_BINARY_DIR/teach/; README "Teaching with Facet" shows copies from
// assets/samples/leuven/teach/).
#include <doctest/doctest.h>

#include "core/estimators/fit_steps.h"
#include "core/geometry/camera.h"
#include "core/geometry/ray_pair.h"
#include "core/solve/joint_solve_steps.h"
#include "core/solve/model_update.h"
#include "core/util/matrix_text.h"
#include "tests/app/app_test_util.h"

namespace facet::testing {
namespace {

// Noise-free scene: the calibration refines exact vanishing points and the solve starts at
// the truth, so what the overlay reports is the truth up to rounding through the fits
// (relative to the image size or f).
constexpr double kNoiseFreeRelative = 1e-9;
// Directions and lines pass through the solves' rotations (~1e-12 rad here).
constexpr double kDirectionTolerance = 1e-8;

Eigen::Vector2d Vec2(const nlohmann::json& j) { return {j.at(0).get<double>(), j.at(1).get<double>()}; }
Eigen::Vector3d Vec3(const nlohmann::json& j) {
  return {j.at(0).get<double>(), j.at(1).get<double>(), j.at(2).get<double>()};
}
Eigen::Matrix3d Mat3(const nlohmann::json& j) {
  Eigen::Matrix3d m;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m(r, c) = j.at(r).at(c).get<double>();
  return m;
}
double SignFree(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::min((a.normalized() - b.normalized()).norm(), (a.normalized() + b.normalized()).norm());
}

void WriteGreyPhoto(const std::string& path, const Camera& camera) {
  const cv::Mat photo(camera.height_px, camera.width_px, CV_8UC3, cv::Scalar(120, 120, 120));
  REQUIRE(cv::imwrite(path, photo));
}

// The box scene's photo and project in `dir`; `edit` may change the project first.
std::string WriteScene(const TempDir& dir, const SyntheticScene& scene, const Project& project) {
  WriteGreyPhoto(dir / "synthetic.png", scene.true_camera);
  const std::string path = dir / "scene.facet";
  REQUIRE(SaveProject(project, path) == "");
  return path;
}

// A second camera of the box scene from the other side, for the two-view cases.
Camera SecondCamera() {
  SyntheticSceneOptions o;
  o.camera_center = {-5.0, -8.0, 4.0};
  o.roll_deg = -2.0;
  o.focal_px = 1100.0;
  o.principal_point_offset_px = {-20.0, 15.0};
  return MakeLookAtCamera(o);
}

// The box scene with a second calibrated photo seeing all eight corners.
Project TwoViewProject(const SyntheticScene& scene, Id* second_id) {
  Project p = scene.project;
  Image second;
  second.id = p.NewId();
  second.path = "second.png";
  second.camera = SecondCamera();
  second.width_px = second.camera.width_px;
  second.height_px = second.camera.height_px;
  second.camera_calibrated = true;
  p.images.push_back(second);
  for (int c = 0; c < 8; ++c) {
    Pin pin;
    pin.id = p.NewId();
    pin.image_id = second.id;
    pin.vertex = {scene.box_id, static_cast<VertexId>(c)};
    pin.uv_px = second.camera.Project(scene.true_box.mesh.vertex(c).position);
    p.pins.push_back(pin);
  }
  *second_id = second.id;
  return p;
}

TEST_CASE("vanishing overlay: the construction read back from the app is the true camera's") {
  TempDir dir("teach_vp");
  const SyntheticScene scene = MakeBoxScene();
  const std::string path = WriteScene(dir, scene, scene.project);
  const nlohmann::json report = RenderScript(
      dir, path, "vp", "frames 3\ncommand teach vanishing on\nframes 3\nscreenshot " + (dir / "vp_shot.png"));
  CHECK(report.at("teach").at("view").at("vanishing").get<bool>());
  REQUIRE(report.at("teach").at("vanishing").size() == 1u);
  const nlohmann::json& v = report.at("teach").at("vanishing").at(0);
  const Camera& truth = scene.true_camera;
  const double size = std::hypot(double(truth.width_px), double(truth.height_px));
  const double tol = kNoiseFreeRelative * size;
  CHECK(v.at("kind").get<std::string>() == "three points");
  CHECK_FALSE(v.at("principal_point_assumed").get<bool>());
  const Eigen::Vector2d p = Vec2(v.at("principal_point_px"));
  CAPTURE(p.transpose());
  CHECK((p - truth.principal_point_px).norm() < tol);
  CHECK(std::abs(v.at("focal_px").get<double>() - truth.focal_px) < kNoiseFreeRelative * truth.focal_px);
  std::array<Eigen::Vector2d, 3> true_vp;
  for (int a = 0; a < 3; ++a) {
    const Eigen::Vector3d h = truth.K() * truth.cam_from_world_rotation.col(a);
    true_vp[a] = h.head<2>() / h.z();
    CHECK((Vec2(v.at("points_px").at(a)) - true_vp[a]).norm() < kNoiseFreeRelative * true_vp[a].norm());
    // Noise-free segments: the ellipse has (next to) no size.
    const nlohmann::json& cov = v.at("covariance_px2").at(a);
    REQUIRE_FALSE(cov.at(0).at(0).is_null());
    CHECK(cov.at(0).at(0).get<double>() + cov.at(1).at(1).get<double>() < 1e-12);
  }
  REQUIRE(v.at("focal_constructions").size() == 3u);
  for (const nlohmann::json& c : v.at("focal_constructions")) {
    const int i = c.at("axes").at(0).get<int>(), j = c.at("axes").at(1).get<int>();
    REQUIRE(c.at("valid").get<bool>());
    CHECK((Vec2(c.at("circle_center_px")) - 0.5 * (true_vp[i] + true_vp[j])).norm() <
          kNoiseFreeRelative * true_vp[i].norm());
    CHECK(std::abs(c.at("circle_radius_px").get<double>() - 0.5 * (true_vp[i] - true_vp[j]).norm()) <
          kNoiseFreeRelative * (true_vp[i] - true_vp[j]).norm());
    const Eigen::Vector2d q = Vec2(c.at("turned_center_px"));
    CHECK(std::abs((true_vp[i] - q).normalized().dot((true_vp[j] - q).normalized())) < kNoiseFreeRelative);
    CHECK(std::abs((Vec2(c.at("focal_end_px")) - truth.principal_point_px).norm() - truth.focal_px) <
          kNoiseFreeRelative * truth.focal_px);
  }
  const Eigen::Vector3d true_horizon = truth.K().inverse().transpose() * truth.cam_from_world_rotation.col(2);
  CHECK(SignFree(Vec3(v.at("horizon")), true_horizon) < kNoiseFreeRelative * size);
  for (int a = 0; a < 3; ++a)
    CHECK(SignFree(Vec3(v.at("directions_in_world").at(a)), Eigen::Vector3d::Unit(a)) < kDirectionTolerance);
  CHECK((Vec3(v.at("camera_center_in_world")) - truth.CenterInWorld()).norm() < kDirectionTolerance * 20.0);
  CHECK(v.at("assumptions").size() == 1u);  // only the orthogonality of the families

  // Drawn where computed: the principal point's marker on the screenshot.
  const View view = ViewFromReport(report);
  const cv::Mat shot = cv::imread(dir / "vp_shot.png");
  REQUIRE(!shot.empty());
  const Eigen::Vector2d s = view.ToScreen(truth.principal_point_px);
  REQUIRE(view.Inside(s, 10.0));
  const cv::Vec3b bgr = shot.at<cv::Vec3b>(static_cast<int>(std::lround(s.y())), static_cast<int>(std::lround(s.x())));
  CAPTURE(bgr);
  CHECK(std::abs(bgr[2] - 255) <= 30);  // kPrincipalPointColor (255, 90, 220)
  CHECK(std::abs(bgr[1] - 90) <= 30);
  CHECK(std::abs(bgr[0] - 220) <= 30);
}

TEST_CASE("vanishing overlay with two families: principal point assumed at the centre, written beside it") {
  TempDir dir("teach_vp2");
  SyntheticSceneOptions options;
  options.principal_point_offset_px = Eigen::Vector2d::Zero();  // the assumption holds
  const SyntheticScene scene = MakeBoxScene(options);
  Project p = scene.project;
  std::erase_if(p.segments, [](const Segment& s) { return s.axis == Axis::kZ; });
  p.images[0].principal_point_mode = PrincipalPointMode::kImageCenter;
  const std::string path = WriteScene(dir, scene, p);
  const nlohmann::json report = RenderScript(dir, path, "vp2", "frames 3\ncommand teach vanishing on\nframes 2\n");
  REQUIRE(report.at("teach").at("vanishing").size() == 1u);
  const nlohmann::json& v = report.at("teach").at("vanishing").at(0);
  CHECK(v.at("kind").get<std::string>() == "two points");
  CHECK(v.at("principal_point_assumed").get<bool>());
  const Camera& truth = scene.true_camera;
  CHECK((Vec2(v.at("principal_point_px")) - truth.principal_point_px).norm() < 1e-9 * truth.width_px);
  CHECK(std::abs(v.at("focal_px").get<double>() - truth.focal_px) < kNoiseFreeRelative * truth.focal_px);
  bool says_centre = false;
  for (const auto& a : v.at("assumptions"))
    says_centre |= a.get<std::string>().find("image centre") != std::string::npos;
  CHECK(says_centre);
  const Eigen::Vector3d true_horizon = truth.K().inverse().transpose() * truth.cam_from_world_rotation.col(2);
  CHECK(SignFree(Vec3(v.at("horizon")), true_horizon) < kNoiseFreeRelative * truth.width_px);
}

TEST_CASE("epipolar overlay: a selected vertex's pins and the pointer give the true epipolar lines") {
  TempDir dir("teach_epi");
  const SyntheticScene scene = MakeBoxScene();
  Id second_id = kNoId;
  const Project project = TwoViewProject(scene, &second_id);
  WriteGreyPhoto(dir / "second.png", SecondCamera());
  const std::string path = WriteScene(dir, scene, project);
  const Camera& a = scene.true_camera;
  const Camera b = SecondCamera();
  // The pointer over image a at a pixel that sees a known point: the box corner 6's top.
  const Eigen::Vector3d corner = scene.true_box.mesh.vertex(6).position;
  const Eigen::Vector2d pointer = a.Project(corner) + Eigen::Vector2d(30.0, -20.0);
  const nlohmann::json report = RenderScript(
      dir, path, "epi",
      "frames 3\ncommand teach epipolar on\ncommand select vertex " + std::to_string(scene.box_id) +
          " 2\nframes 2\nmove image " + FormatXY(pointer) + "\nframes 2\nscreenshot " + (dir / "epi_shot.png"));
  const nlohmann::json& lines = report.at("teach").at("epipolar");
  int pin_lines = 0, pointer_lines = 0;
  for (const nlohmann::json& l : lines) {
    const Eigen::Vector3d line = Vec3(l.at("line"));
    const bool into_b = l.at("in_image_id").get<Id>() == second_id;
    const Camera& from = into_b ? a : b;
    const Camera& in = into_b ? b : a;
    // The line passes through the epipole, which is the other camera's centre seen by `in`.
    const Eigen::Vector3d e = Vec3(l.at("epipole"));
    const Eigen::Vector3d true_e = in.K() * in.CamFromWorld(from.CenterInWorld());
    CHECK(SignFree(e, true_e) < kDirectionTolerance);
    CHECK(std::abs(line.dot(true_e.normalized())) < kDirectionTolerance);
    if (l.at("from_pointer").get<bool>()) {
      ++pointer_lines;
      CHECK(into_b);  // the pointer is over the active image a
      // The pointer is where the mouse went, to a screen pixel (and snapping) of the view.
      const Eigen::Vector2d at = Vec2(l.at("from_uv_px"));
      CHECK((at - pointer).norm() < 10.0 / ViewFromReport(report).zoom);
      // Every point on the pointer's ray projects onto the line in b.
      for (const double depth : {2.0, 9.0, 40.0}) {
        const Eigen::Vector3d x = a.CenterInWorld() + depth * a.RayDirectionInWorld(at);
        CHECK(std::abs(line.dot(b.Project(x).homogeneous())) < kNoiseFreeRelative * b.width_px);
      }
    } else {
      ++pin_lines;
      // The selected vertex's pin in the other photo lies on its line (noise-free pins).
      const Eigen::Vector2d truth_there = in.Project(scene.true_box.mesh.vertex(2).position);
      CHECK(std::abs(line.dot(truth_there.homogeneous())) < 1e-6);
      CHECK(l.at("pin_distance_px").get<double>() < 1e-6);
    }
  }
  CHECK(pin_lines == 2);      // vertex 2's pin in a drawn in b, and its pin in b drawn in a
  CHECK(pointer_lines == 1);  // the pointer in a, drawn in b's inset

  // In 3D: the rays from the two camera centres through vertex 2's pins meet at the vertex.
  const nlohmann::json& rays = report.at("teach").at("rays");
  REQUIRE(rays.size() == 1u);
  const nlohmann::json& r = rays.at(0);
  const Eigen::Vector3d vertex = scene.true_box.mesh.vertex(2).position;
  const double size = (a.CenterInWorld() - vertex).norm();
  CHECK((Vec3(r.at("center_a")) - a.CenterInWorld()).norm() < kDirectionTolerance * size);
  CHECK((Vec3(r.at("center_b")) - b.CenterInWorld()).norm() < kDirectionTolerance * size);
  CHECK((Vec3(r.at("on_a")) - vertex).norm() < kDirectionTolerance * size);
  CHECK((Vec3(r.at("on_b")) - vertex).norm() < kDirectionTolerance * size);
  CHECK(r.at("gap").get<double>() < kDirectionTolerance * size);
  CHECK(r.at("gap_px_in_a").get<double>() < 1e-6);
  CHECK(r.at("gap_px_in_b").get<double>() < 1e-6);
  // The closest points are where the reported rays are nearest (not only near the truth).
  const RayPairClosestPoints c = ClosestPointsOfRays(Vec3(r.at("center_a")), Vec3(r.at("direction_a")),
                                                     Vec3(r.at("center_b")), Vec3(r.at("direction_b")));
  CHECK((c.on_a - Vec3(r.at("on_a"))).norm() < kNoiseFreeRelative * size);
  CHECK((c.on_b - Vec3(r.at("on_b"))).norm() < kNoiseFreeRelative * size);
}

// The largest difference between the stepped cameras and primitives of the report's
// teach.steps and a project's, relative to their size.
double MaxRelativeDifference(const nlohmann::json& steps, const Project& p) {
  double worst = 0.0;
  auto compare = [&](double x, double y) { worst = std::max(worst, std::abs(x - y) / std::max(1.0, std::abs(y))); };
  REQUIRE(steps.at("images").size() == p.images.size());
  for (size_t i = 0; i < p.images.size(); ++i) {
    const nlohmann::json& j = steps.at("images").at(i);
    const Camera& c = p.images[i].camera;
    REQUIRE(j.at("id").get<Id>() == p.images[i].id);
    compare(j.at("focal_px").get<double>(), c.focal_px);
    for (int k = 0; k < 2; ++k) compare(j.at("principal_point_px").at(k).get<double>(), c.principal_point_px(k));
    const Eigen::Matrix3d R = Mat3(j.at("cam_from_world_rotation"));
    for (int k = 0; k < 9; ++k) compare(R(k), c.cam_from_world_rotation(k));
    for (int k = 0; k < 3; ++k)
      compare(j.at("cam_from_world_translation").at(k).get<double>(), c.cam_from_world_translation(k));
  }
  REQUIRE(steps.at("primitives").size() == p.primitives.size());
  for (size_t i = 0; i < p.primitives.size(); ++i) {
    const nlohmann::json& j = steps.at("primitives").at(i);
    const PrimitiveShape& shape = p.primitives[i].shape;
    REQUIRE(j.at("id").get<Id>() == p.primitives[i].id);
    for (int k = 0; k < shape.params.size(); ++k) compare(j.at("params").at(k).get<double>(), shape.params(k));
    for (int k = 0; k < 3; ++k) compare(j.at("rotation").at(k).get<double>(), shape.rotation(k));
    for (int k = 0; k < 3; ++k) compare(j.at("translation").at(k).get<double>(), shape.translation(k));
  }
  return worst;
}

TEST_CASE(
    "solver steps: N steps in the app are one solve of N iterations; Reset restores the start; the project stays") {
  // The same arithmetic in the same order (core's SolveJointTraced in both processes), read
  // back through JSON's round-trip doubles: equal to rounding.
  constexpr double kSameSolveRelative = 1e-12;
  constexpr double kRoundingPx = 1e-9;
  constexpr int kSteps = 4;
  constexpr double kDrawnScale = 200.0;
  TempDir dir("teach_steps");
  SyntheticSceneOptions options;
  options.noise_px = 0.5;
  const SyntheticScene scene = MakeBoxScene(options);
  const std::string path = WriteScene(dir, scene, scene.project);
  const std::string before_path = dir / "before.facet";
  std::string script = "frames 3\ncommand save " + before_path + "\ncommand teach steps on\nframes 1\n";
  for (int k = 0; k < kSteps; ++k) script += "command teach step\nframes 1\n";
  // Vectors long enough to find on the screenshot (the scale the window starts with suits the
  // start's residuals, which the steps have shrunk).
  script += "command teach residual-scale " + std::to_string(static_cast<int>(kDrawnScale)) +
            "\nframes 2\nscreenshot " + (dir / "steps_shot.png");
  const nlohmann::json report = RenderScript(dir, path, "steps", script);
  const nlohmann::json& steps = report.at("teach").at("steps");
  INFO(steps.at("message").get<std::string>());
  REQUIRE(steps.at("active").get<bool>());
  CHECK(steps.at("start").get<std::string>() == "perturbed");
  REQUIRE(steps.at("steps").get<int>() == kSteps);

  // Stepping never edits the document: it is the saved project, with no history.
  const Project before = LoadProjectFile(before_path);
  CHECK(report.at("project") == nlohmann::json::parse(ProjectToJson(before)));
  CHECK(report.at("undo_stack").empty());

  const Project start = PerturbForSteps(before, steps.at("perturbation").get<double>());
  JointSolveOptions budget = SolveStepsOptions();
  budget.max_iterations = kSteps;
  Project solved;
  std::vector<LmIteration> trace;
  const JointSolveSummary once = SolveJointTraced(start, budget, &solved, &trace);
  REQUIRE(once.IsUsable());
  CHECK(MaxRelativeDifference(steps, solved) <= kSameSolveRelative);
  CHECK(std::abs(steps.at("final_cost").get<double>() - once.final_cost) <= kSameSolveRelative * once.final_cost);
  CHECK(std::abs(steps.at("initial_cost").get<double>() - once.initial_cost) <= kSameSolveRelative * once.initial_cost);
  REQUIRE(steps.at("trace").size() == trace.size());
  for (size_t i = 0; i < trace.size(); ++i) {
    const nlohmann::json& t = steps.at("trace").at(i);
    CHECK(std::abs(t.at("cost").get<double>() - trace[i].cost) <= kSameSolveRelative * trace[i].cost);
    CHECK(std::abs(t.at("lambda").get<double>() - trace[i].lambda) <= kSameSolveRelative * trace[i].lambda);
    CHECK(t.at("accepted").get<bool>() == trace[i].accepted);
  }
  // The start was not the answer: the cost fell.
  CHECK(once.final_cost < 0.5 * once.initial_cost);
  CHECK(steps.at("finished").get<bool>() == (once.termination != SolverTermination::kMaxIterations));

  // The residual vectors drawn are projection minus pin in the stepped state.
  REQUIRE(steps.at("pins").size() == solved.pins.size());
  for (const nlohmann::json& j : steps.at("pins")) {
    const Pin* pin = solved.FindPin(j.at("pin_id").get<Id>());
    REQUIRE(pin != nullptr);
    const Camera& camera = solved.FindImage(pin->image_id)->camera;
    const Eigen::Vector2d projection = camera.Project(VertexInWorld(solved, pin->vertex));
    CHECK((Vec2(j.at("projection_px")) - projection).norm() < kRoundingPx);
    CHECK((Vec2(j.at("uv_px")) - pin->uv_px).norm() == 0.0);
    CHECK((Vec2(j.at("residual_px")) - (projection - pin->uv_px)).norm() < kRoundingPx);
  }
  // Drawn where computed: halfway along each vector (long enough to tell, at the scale the
  // script set), the screenshot is the vectors' white, not the grey photo.
  const double scale = steps.at("residual_scale").get<double>();
  CHECK(scale == kDrawnScale);
  const View view = ViewFromReport(report);
  const cv::Mat shot = cv::imread(dir / "steps_shot.png");
  REQUIRE(!shot.empty());
  int long_vectors = 0, white_middles = 0;
  for (const nlohmann::json& j : steps.at("pins")) {
    const Eigen::Vector2d a = view.ToScreen(Vec2(j.at("uv_px")));
    const Eigen::Vector2d b = view.ToScreen(Vec2(j.at("uv_px")) + scale * Vec2(j.at("residual_px")));
    const Eigen::Vector2d middle = 0.5 * (a + b);
    if ((b - a).norm() < 20.0 || !view.Inside(middle, 30.0)) continue;
    ++long_vectors;
    bool white = false;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const cv::Vec3b bgr = shot.at<cv::Vec3b>(static_cast<int>(std::lround(middle.y())) + dy,
                                                 static_cast<int>(std::lround(middle.x())) + dx);
        white |= bgr[2] > 235 && bgr[1] > 235 && bgr[0] > 235;  // kResidualColor on the grey photo
      }
    white_middles += white ? 1 : 0;
  }
  CHECK(long_vectors >= 3);
  CHECK(white_middles == long_vectors);

  // Reset: back to the start exactly, the residuals there.
  const nlohmann::json reset_report =
      RenderScript(dir, before_path, "steps_reset",
                   "frames 3\ncommand teach steps on\ncommand teach step\ncommand teach step\ncommand teach reset\n"
                   "frames 2\n");
  const nlohmann::json& reset = reset_report.at("teach").at("steps");
  REQUIRE(reset.at("active").get<bool>());
  CHECK(reset.at("steps").get<int>() == 0);
  CHECK(reset.at("trace").empty());
  CHECK(MaxRelativeDifference(reset, start) == 0.0);
  for (const nlohmann::json& j : reset.at("pins")) {
    const Pin* pin = start.FindPin(j.at("pin_id").get<Id>());
    REQUIRE(pin != nullptr);
    const Eigen::Vector2d projection =
        start.FindImage(pin->image_id)->camera.Project(VertexInWorld(start, pin->vertex));
    CHECK((Vec2(j.at("projection_px")) - projection).norm() == 0.0);
  }
  CHECK(reset_report.at("project") == nlohmann::json::parse(ProjectToJson(before)));
}

TEST_CASE(
    "solver steps, vanishing points: N steps in the app are the fit with N iterations; Reset restores the start") {
  // The same fit (core's CalibrateFromVanishingLines) in both processes, through JSON's
  // round-trip doubles: equal to rounding.
  constexpr double kSameFitRelative = 1e-12;
  constexpr int kSteps = 3;
  TempDir dir("teach_vp_steps");
  SyntheticSceneOptions options;
  options.noise_px = 0.5;
  const SyntheticScene scene = MakeBoxScene(options);
  // The principal point held at the centre, 15 px from the truth: the fit has iterations to show.
  Project project = scene.project;
  project.images[0].principal_point_mode = PrincipalPointMode::kImageCenter;
  const std::string path = WriteScene(dir, scene, project);
  const std::string before_path = dir / "before.facet";
  std::string script =
      "frames 3\ncommand save " + before_path + "\ncommand teach steps on\ncommand teach subject vanishing\nframes 1\n";
  for (int k = 0; k < kSteps; ++k) script += "command teach step\nframes 1\n";
  const nlohmann::json report = RenderScript(dir, path, "vp_steps", script + "frames 2\n");
  const nlohmann::json& steps = report.at("teach").at("steps");
  INFO(steps.at("message").get<std::string>());
  CHECK(steps.at("subject").get<std::string>() == "vanishing");
  REQUIRE(steps.contains("vanishing"));
  const nlohmann::json& vp = steps.at("vanishing");
  REQUIRE(vp.at("steps").get<int>() == kSteps);
  // Stepping never edits the document.
  const Project before = LoadProjectFile(before_path);
  CHECK(report.at("project") == nlohmann::json::parse(ProjectToJson(before)));
  CHECK(report.at("undo_stack").empty());

  // The fit as the calibration step runs it, one round, with a budget of kSteps and of 0.
  const Image& image = before.images[0];
  std::vector<Segment> segments;
  for (const Segment& seg : before.segments)
    if (seg.image_id == image.id) segments.push_back(seg);
  VpCalibrationOptions budget = CalibrationOptionsFor(image);
  budget.refit_without_outliers = false;
  budget.record_joint_trace = true;
  // The window's default start: the fit's answer moved off by the amount the report states.
  REQUIRE(steps.at("start").get<std::string>() == "perturbed");
  const VpCalibrationSummary answer = CalibrateFromVanishingLines(segments, budget);
  REQUIRE(answer.IsUsable());
  budget = PerturbVpStart(answer, budget, steps.at("perturbation").get<double>());
  budget.max_joint_iterations = kSteps;
  const VpCalibrationSummary once = CalibrateFromVanishingLines(segments, budget);
  REQUIRE(once.IsUsable());
  budget.max_joint_iterations = 0;
  const VpCalibrationSummary start = CalibrateFromVanishingLines(segments, budget);
  REQUIRE(start.IsUsable());
  const auto same = [&](double a, double b) {
    return std::abs(a - b) <= kSameFitRelative * std::max(1.0, std::abs(b));
  };
  CHECK(same(vp.at("focal_px").get<double>(), once.focal_px));
  CHECK((Mat3(vp.at("cam_from_world_rotation")) - once.cam_from_world_rotation).norm() <= kSameFitRelative);
  // f per step: the start's, then each step's.
  REQUIRE(vp.at("path").size() == static_cast<size_t>(kSteps + 1));
  CHECK(same(vp.at("path").at(0).at("focal_px").get<double>(), start.focal_px));
  CHECK(same(vp.at("path").at(0).at("cost").get<double>(), start.final_cost));
  CHECK(same(vp.at("path").at(kSteps).at("cost").get<double>(), once.final_cost));
  for (int a = 0; a < 3; ++a) {
    CHECK((Vec3(vp.at("path").at(0).at("vanishing_points").at(a)) - start.vanishing_points[a]).norm() <=
          kSameFitRelative);
    CHECK((Vec3(vp.at("path").at(kSteps).at("vanishing_points").at(a)) - once.vanishing_points[a]).norm() <=
          kSameFitRelative);
  }
  // The start was not the answer: the vanishing points moved and the cost fell.
  CHECK(once.final_cost < 0.9 * start.final_cost);
  CHECK((once.vanishing_points[0] - start.vanishing_points[0]).norm() > 1e-6);
  const double px2 = once.conditioning_scale_px * once.conditioning_scale_px;
  REQUIRE(vp.at("trace").size() == once.joint_trace.size());
  for (size_t i = 0; i < once.joint_trace.size(); ++i) {
    CHECK(same(vp.at("trace").at(i).at("trial_cost").get<double>(), once.joint_trace[i].trial_cost * px2));
    CHECK(vp.at("trace").at(i).at("lambda").get<double>() == once.joint_trace[i].lambda);
  }
  // Each segment's residual drawn: from each endpoint to the line through its midpoint and its
  // family's vanishing point, as long as the fit's residual.
  REQUIRE(vp.at("segments").size() == segments.size());
  for (size_t i = 0; i < segments.size(); ++i) {
    const nlohmann::json& j = vp.at("segments").at(i);
    CHECK(j.at("segment_id").get<Id>() == segments[i].id);
    CHECK(same(j.at("residual_px").get<double>(), once.segment_residuals_px[i]));
    const Eigen::Vector2d foot = Vec2(j.at("a_px")) + Vec2(j.at("offset_a_px"));
    const Eigen::Vector3d v = once.vanishing_points[static_cast<int>(segments[i].axis)];
    const Eigen::Vector2d mid = 0.5 * (segments[i].a_px + segments[i].b_px);
    // The foot lies on the line through mid and v (cross product of the two directions ~ 0).
    const Eigen::Vector2d to_v = (v.head<2>() - v.z() * mid).normalized();
    const Eigen::Vector2d to_foot = foot - mid;
    CHECK(std::abs(to_v.x() * to_foot.y() - to_v.y() * to_foot.x()) <= 1e-9 * std::max(1.0, to_foot.norm()));
    CHECK(std::abs(Vec2(j.at("offset_a_px")).norm() - std::abs(once.segment_residuals_px[i])) <= 1e-9);
  }

  // Reset: the start exactly.
  const nlohmann::json reset_report = RenderScript(
      dir, before_path, "vp_steps_reset",
      "frames 3\ncommand teach steps on\ncommand teach subject vanishing\ncommand teach step\ncommand teach step\n"
      "command teach reset\nframes 2\n");
  const nlohmann::json& reset = reset_report.at("teach").at("steps").at("vanishing");
  CHECK(reset.at("steps").get<int>() == 0);
  CHECK(reset.at("trace").empty());
  REQUIRE(reset.at("path").size() == 1u);
  CHECK(reset.at("path").at(0) == vp.at("path").at(0));
  CHECK(reset.at("focal_px").get<double>() == vp.at("path").at(0).at("focal_px").get<double>());
  CHECK(reset_report.at("project") == nlohmann::json::parse(ProjectToJson(before)));
}

// The box scene with a second photo and two more boxes, every corner pinned in both photos
// with `noise_px` noise (the first box's pins in the first photo are the scene's): 24 matches
// for F.
Project TwoViewMatchesProject(const SyntheticScene& scene, double noise_px = 0.7) {
  Project p = scene.project;
  const Camera second_camera = SecondCamera();
  Image second;
  second.id = p.NewId();
  second.path = "second.png";
  second.camera = second_camera;
  second.width_px = second_camera.width_px;
  second.height_px = second_camera.height_px;
  second.camera_calibrated = true;
  p.images.push_back(second);
  for (const auto& [size, translation] :
       {std::pair<Eigen::Vector3d, Eigen::Vector3d>{{1.5, 1.0, 1.2}, {1.0, -3.0, 0.0}},
        std::pair<Eigen::Vector3d, Eigen::Vector3d>{{2.0, 1.5, 1.0}, {0.5, 0.5, 3.0}}}) {
    PrimitiveShape shape = MakeBox(kNoId, size);
    shape.translation = translation;
    Id id = kNoId;
    AddPrimitiveToProject(&p, shape, "box", &id, nullptr);
  }
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, noise_px);
  for (const Primitive& primitive : p.primitives) {
    for (VertexId c = 0; c < 8; ++c) {
      const Eigen::Vector3d x = primitive.mesh.vertex(c).position;
      for (const Image* image : {&p.images[0], &p.images[1]}) {
        const bool first_box = primitive.id == scene.box_id;
        if (first_box && image == &p.images[0]) continue;  // the scene pinned these
        Pin pin;
        pin.id = p.NewId();
        pin.image_id = image->id;
        pin.vertex = {primitive.id, c};
        const double dx = noise(rng);
        const double dy = noise(rng);
        pin.uv_px = image->camera.Project(x) + Eigen::Vector2d(dx, dy);
        REQUIRE(image->camera.CamFromWorld(x).z() > 0.0);
        p.pins.push_back(pin);
      }
    }
  }
  return p;
}

TEST_CASE("solver steps, two views: N steps in the app are the refinement of F with N iterations; Reset restores it") {
  constexpr double kSameFitRelative = 1e-12;
  constexpr int kSteps = 2;
  TempDir dir("teach_two_view_steps");
  SyntheticSceneOptions options;
  options.noise_px = 0.5;
  const SyntheticScene scene = MakeBoxScene(options);
  const Project project = TwoViewMatchesProject(scene);
  WriteGreyPhoto(dir / "second.png", SecondCamera());
  const std::string path = WriteScene(dir, scene, project);
  const std::string before_path = dir / "before.facet";
  std::string script = "frames 3\ncommand save " + before_path +
                       "\ncommand teach steps on\ncommand teach subject two-view\ncommand teach second-image 1\n";
  for (int k = 0; k < kSteps; ++k) script += "command teach step\nframes 1\n";
  const nlohmann::json report = RenderScript(dir, path, "two_view_steps", script + "frames 2\n");
  const nlohmann::json& steps = report.at("teach").at("steps");
  INFO(steps.at("message").get<std::string>());
  REQUIRE(steps.contains("two_view"));
  const nlohmann::json& two = steps.at("two_view");
  REQUIRE(two.at("steps").get<int>() == kSteps);
  // Stepping never edits the document.
  const Project opened = LoadProjectFile(before_path);
  CHECK(report.at("project") == nlohmann::json::parse(ProjectToJson(opened)));
  CHECK(two.at("image_a").get<Id>() == opened.images[0].id);
  CHECK(two.at("image_b").get<Id>() == opened.images[1].id);

  // The matches as the window takes them: pins of one vertex in both photos, RANSAC's inliers.
  std::vector<Eigen::Vector2d> uv_a, uv_b;
  for (const Pin& pa : opened.pins) {
    if (pa.image_id != opened.images[0].id) continue;
    for (const Pin& pb : opened.pins)
      if (pb.image_id == opened.images[1].id && pb.vertex == pa.vertex) {
        uv_a.push_back(pa.uv_px);
        uv_b.push_back(pb.uv_px);
        break;
      }
  }
  REQUIRE(uv_a.size() == 24u);
  const FundamentalSummary full = EstimateFundamentalMatrix(uv_a, uv_b, FundamentalOptions());
  REQUIRE(full.IsUsable());
  std::vector<Eigen::Vector2d> in_a, in_b;
  for (size_t i = 0; i < uv_a.size(); ++i)
    if (full.inliers[i]) in_a.push_back(uv_a[i]), in_b.push_back(uv_b[i]);
  FundamentalOptions budget;
  budget.use_ransac = false;
  budget.record_refine_trace = true;
  // The window's default start: the refined F moved off by the amount the report states.
  REQUIRE(steps.at("start").get<std::string>() == "perturbed");
  const FundamentalSummary answer = EstimateFundamentalMatrix(in_a, in_b, budget);
  REQUIRE(answer.IsUsable());
  budget.warm_start = true;
  budget.warm_start_F = PerturbFundamental(answer.F, in_a, in_b, steps.at("perturbation").get<double>());
  budget.max_refine_iterations = kSteps;
  const FundamentalSummary once = EstimateFundamentalMatrix(in_a, in_b, budget);
  REQUIRE(once.IsUsable());
  budget.max_refine_iterations = 0;
  const FundamentalSummary start = EstimateFundamentalMatrix(in_a, in_b, budget);
  CHECK((Mat3(two.at("F")) - once.F).norm() <= kSameFitRelative);
  REQUIRE(two.at("path").size() == static_cast<size_t>(kSteps + 1));
  CHECK((Mat3(two.at("path").at(0)) - start.F).norm() <= kSameFitRelative);
  CHECK(std::abs(two.at("cost").get<double>() - once.final_cost) <= kSameFitRelative * once.final_cost);
  CHECK(once.final_cost < start.final_cost);  // the start was not the answer
  REQUIRE(two.at("trace").size() == once.refine_trace.size());
  for (size_t i = 0; i < once.refine_trace.size(); ++i)
    CHECK(two.at("trace").at(i).at("lambda").get<double>() == once.refine_trace[i].lambda);
  // Per match: the lines under the current F and the start's, the symmetric distances.
  REQUIRE(two.at("matches").size() == in_a.size());
  int drawn = 0;
  for (size_t i = 0; i < in_a.size(); ++i) {
    const nlohmann::json& m = two.at("matches").at(i);
    CHECK((Vec2(m.at("uv_a")) - in_a[i]).norm() == 0.0);
    const Eigen::Vector3d xa(in_a[i].x(), in_a[i].y(), 1.0), xb(in_b[i].x(), in_b[i].y(), 1.0);
    CHECK(SignFree(Vec3(m.at("line_in_b")), once.F * xa) <= 1e-9);
    CHECK(SignFree(Vec3(m.at("line_in_a")), once.F.transpose() * xb) <= 1e-9);
    CHECK(SignFree(Vec3(m.at("start_line_in_b")), start.F * xa) <= 1e-9);
    const Eigen::Vector2d d = SymmetricEpipolarDistances(once.F, in_a[i], in_b[i]);
    CHECK((Vec2(m.at("distances_px")) - d).norm() <= 1e-9);
    drawn += m.at("drawn").get<bool>() ? 1 : 0;
  }
  CHECK(drawn == 6);

  const nlohmann::json reset_report =
      RenderScript(dir, path, "two_view_reset",
                   "frames 3\ncommand teach steps on\ncommand teach subject two-view\ncommand teach second-image 1\n"
                   "command teach step\ncommand teach step\ncommand teach reset\nframes 2\n");
  const nlohmann::json& reset = reset_report.at("teach").at("steps").at("two_view");
  CHECK(reset.at("steps").get<int>() == 0);
  CHECK(reset.at("trace").empty());
  REQUIRE(reset.at("path").size() == 1u);
  CHECK(reset.at("F") == two.at("path").at(0));
}

TEST_CASE("export view: render --panel writes the image or the 3D panel alone, at the asked size") {
  TempDir dir("teach_export");
  const SyntheticScene scene = MakeBoxScene();
  const std::string path = WriteScene(dir, scene, scene.project);
  // The photo: left half red, right half blue, so that the picture shows which part is where.
  const Camera& camera = scene.true_camera;
  cv::Mat photo(camera.height_px, camera.width_px, CV_8UC3, cv::Scalar(220, 40, 40));  // BGR blue
  photo(cv::Rect(0, 0, camera.width_px / 2, camera.height_px)).setTo(cv::Scalar(40, 40, 220));
  REQUIRE(cv::imwrite(dir / "synthetic.png", photo));

  constexpr int kW = 640, kH = 400;
  const RunResult image_run = RunRender(dir, "'" + path + "' -o '" + (dir / "image.png") + "' --panel image --size " +
                                                 std::to_string(kW) + "x" + std::to_string(kH));
  INFO("stderr: " << image_run.stderr_text);
  REQUIRE(image_run.exit_code == 0);
  const cv::Mat image = cv::imread(dir / "image.png");
  REQUIRE(!image.empty());
  CHECK(image.cols == kW);
  CHECK(image.rows == kH);
  // The view is the app's (fitted, centred), scaled to the picture: the photo's middle is the
  // picture's middle, red to its left and blue to its right (the model's lines cross a few).
  auto share = [&](int cx, int cy, const cv::Vec3b& bgr) {
    int hits = 0, all = 0;
    for (int y = cy - 10; y <= cy + 10; ++y)
      for (int x = cx - 10; x <= cx + 10; ++x, ++all) {
        const cv::Vec3b p = image.at<cv::Vec3b>(y, x);
        hits += std::abs(p[0] - bgr[0]) + std::abs(p[1] - bgr[1]) + std::abs(p[2] - bgr[2]) < 30 ? 1 : 0;
      }
    return static_cast<double>(hits) / all;
  };
  const cv::Vec3b red(40, 40, 220), blue(220, 40, 40);
  CHECK(share(kW / 2 - 40, kH / 2, red) > 0.3);
  CHECK(share(kW / 2 - 40, kH / 2, blue) < 0.02);
  CHECK(share(kW / 2 + 40, kH / 2, blue) > 0.3);
  CHECK(share(kW / 2 + 40, kH / 2, red) < 0.02);
  // With its overlays: the projected model.
  int model = 0;
  for (int y = 0; y < image.rows; ++y)
    for (int x = 0; x < image.cols; ++x) model += IsModelColor(image.at<cv::Vec3b>(y, x), 40) ? 1 : 0;
  CHECK(model > 50);

  const RunResult viewport_run =
      RunRender(dir, "'" + path + "' -o '" + (dir / "3d.png") + "' --panel 3d --size 480x320");
  INFO("stderr: " << viewport_run.stderr_text);
  REQUIRE(viewport_run.exit_code == 0);
  const cv::Mat view3d = cv::imread(dir / "3d.png");
  REQUIRE(!view3d.empty());
  CHECK(view3d.cols == 480);
  CHECK(view3d.rows == 320);
  // The 3D panel's backdrop (RenderScene's clear colour, RGB 37 40 45) around the model.
  int backdrop = 0;
  for (int y = 0; y < view3d.rows; ++y)
    for (int x = 0; x < view3d.cols; ++x) {
      const cv::Vec3b p = view3d.at<cv::Vec3b>(y, x);
      backdrop += std::abs(p[0] - 45) + std::abs(p[1] - 40) + std::abs(p[2] - 37) < 12 ? 1 : 0;
    }
  const double backdrop_share = static_cast<double>(backdrop) / (view3d.rows * view3d.cols);
  CAPTURE(backdrop_share);
  CHECK(backdrop_share > 0.2);
  CHECK(backdrop_share < 0.98);

  CHECK(RunRender(dir, "'" + path + "' -o '" + (dir / "bad.png") + "' --panel history --size 480x320").exit_code != 0);

  // Through the menu: File > Export view..., a name typed, Enter: the dialog's default, the
  // image panel at 1920 x 1080.
  const std::string figure = dir / "figure.png";
  const nlohmann::json menu = RenderScript(dir, path, "export_menu",
                                           "frames 3\nclick left item menu.file\nframes 2\nclick left item "
                                           "menu.export_view\nframes 3\nkey ctrl+a\ntype " +
                                               figure + "\nkey enter\nframes 3\n");
  CHECK(menu.at("dialog").get<std::string>() == "");
  CHECK(ReportLog(menu).find("Exported the image view (1920 x 1080 px)") != std::string::npos);
  const cv::Mat from_menu = cv::imread(figure);
  REQUIRE(!from_menu.empty());
  CHECK(from_menu.cols == 1920);
  CHECK(from_menu.rows == 1080);
}

// Light grey, nearly colourless pixels: the 3D panel's help and counts text.
int LightGreyPixels(const cv::Mat& bgr, const cv::Rect& area) {
  int n = 0;
  const cv::Rect clipped = area & cv::Rect(0, 0, bgr.cols, bgr.rows);
  for (int y = clipped.y; y < clipped.y + clipped.height; ++y)
    for (int x = clipped.x; x < clipped.x + clipped.width; ++x) {
      const cv::Vec3b p = bgr.at<cv::Vec3b>(y, x);
      const int lo = std::min({p[0], p[1], p[2]}), hi = std::max({p[0], p[1], p[2]});
      n += lo > 150 && hi - lo < 20 ? 1 : 0;
    }
  return n;
}

TEST_CASE("issue 25: File > Export view of the 3D panel leaves out the panel's help ('drag: orbit ...')") {
  TempDir dir("export_no_help");
  const SyntheticScene scene = MakeBoxScene();
  const std::string path = WriteScene(dir, scene, scene.project);
  cv::Mat photo(scene.true_camera.height_px, scene.true_camera.width_px, CV_8UC3, cv::Scalar(40, 40, 220));
  REQUIRE(cv::imwrite(dir / "synthetic.png", photo));
  // On screen the help is there, and the detector sees it.
  const nlohmann::json shown = RenderScript(dir, path, "window", "frames 3\n");
  REQUIRE(shown.at("items").contains("viewport.help"));
  const nlohmann::json& help = shown.at("items").at("viewport.help");
  const cv::Rect help_rect(static_cast<int>(help.at("x").get<double>()), static_cast<int>(help.at("y").get<double>()),
                           static_cast<int>(help.at("w").get<double>()), static_cast<int>(help.at("h").get<double>()));
  const cv::Mat window = cv::imread(dir / "window.png");
  REQUIRE(!window.empty());
  const int on_screen = LightGreyPixels(window, help_rect);
  CAPTURE(on_screen);
  REQUIRE(on_screen > 100);
  // The exported picture's bottom-left corner, where the help would be: no text.
  constexpr int kW = 800, kH = 500;
  const std::string figure = dir / "figure.png";
  RenderScript(dir, path, "export",
               "frames 3\ncommand export-view 3d " + std::to_string(kW) + "x" + std::to_string(kH) + " " + figure +
                   "\nframes 2\n");
  const cv::Mat exported = cv::imread(figure);
  REQUIRE(exported.cols == kW);
  REQUIRE(exported.rows == kH);
  const int in_export =
      LightGreyPixels(exported, cv::Rect(0, kH - help_rect.height - 12, help_rect.width + 12, help_rect.height + 12));
  CAPTURE(in_export);
  // A tenth of the text's count at most: grid or model edges in that corner stay below it.
  CHECK(in_export * 10 < on_screen);
}

// app/state/teach.h: vanishing points farther than this many photo diagonals stay out of view.
constexpr double kMaxVanishingViewDiagonals = 2.0;

TEST_CASE("issue 25: Teach > Vanishing points on the app's sample: construction in view, thinned, text off the photo") {
  TempDir dir("teach_street");
  const std::string street = std::string(FACET_SOURCE_DIR) + "/assets/samples/leuven/street.facet";
  const nlohmann::json fitted = RenderScript(dir, street, "fitted", "frames 3\n");
  const nlohmann::json r = RenderScript(dir, street, "vanishing", "frames 3\ncommand teach vanishing on\nframes 3\n");
  const nlohmann::json& image_view = r.at("image_view");
  const ProjectLoadResult loaded = ProjectFromJson(r.at("project").dump());
  REQUIRE_MESSAGE(loaded.ok(), loaded.error);
  const Project& project = loaded.project;
  const Image* image = project.FindImage(image_view.at("image_id").get<Id>());
  REQUIRE(image != nullptr);
  REQUIRE(r.at("teach").at("vanishing").size() >= 1u);
  const nlohmann::json& v = r.at("teach").at("vanishing").at(0);
  const double zoom = image_view.at("zoom").get<double>(), ox = image_view.at("origin_x").get<double>(),
               oy = image_view.at("origin_y").get<double>();
  const nlohmann::json& rect = image_view.at("rect");
  const double rx = rect.at("x").get<double>(), ry = rect.at("y").get<double>(), rw = rect.at("w").get<double>(),
               rh = rect.at("h").get<double>();
  // Zoomed out from Fit: the finite vanishing points the construction uses (within
  // kMaxVanishingViewDiagonals of the photo) and the photo are all in view.
  CHECK(zoom < fitted.at("image_view").at("zoom").get<double>());
  const Eigen::Vector2d size(image->width_px, image->height_px);
  int shown_points = 0;
  for (const auto& p : v.at("points_px")) {
    if (p.is_null()) continue;
    const Eigen::Vector2d uv(p.at(0).get<double>(), p.at(1).get<double>());
    if ((uv - 0.5 * size).norm() > kMaxVanishingViewDiagonals * size.norm()) continue;
    const double sx = ox + zoom * uv.x(), sy = oy + zoom * uv.y();
    CAPTURE(uv.transpose());
    CHECK(sx >= rx);
    CHECK(sx <= rx + rw);
    CHECK(sy >= ry);
    CHECK(sy <= ry + rh);
    ++shown_points;
  }
  CHECK(shown_points >= 1);
  // At most 8 extensions per family, however many segments the sample has.
  int families = 0;
  for (const auto& present : v.at("present")) families += present.get<bool>() ? 1 : 0;
  const size_t extended = v.at("extended_segment_ids").size();
  CAPTURE(project.segments.size());
  CHECK(extended <= 8u * static_cast<size_t>(families));
  CHECK(extended < project.segments.size());
  // The text box starts below the photo's bottom edge.
  REQUIRE(r.at("items").contains("teach.text"));
  const double photo_bottom = oy + zoom * (image->height_px - 0.5);
  CHECK(r.at("items").at("teach.text").at("y").get<double>() >= photo_bottom);
}

TEST_CASE("Numbers window: K, R, t of the active camera, F of two photos, copied as text and LaTeX") {
  TempDir dir("teach_numbers");
  const SyntheticScene scene = MakeBoxScene();
  Id second_id = kNoId;
  const Project project = TwoViewProject(scene, &second_id);
  WriteGreyPhoto(dir / "second.png", SecondCamera());
  const std::string path = WriteScene(dir, scene, project);
  const std::string saved = dir / "saved.facet";
  const nlohmann::json probe = RenderScript(
      dir, path, "numbers_probe", "frames 3\ncommand teach numbers on\ncommand teach second-image 1\nframes 3\n");
  const nlohmann::json& items = probe.at("items");
  REQUIRE(items.contains("teach.copy.K"));
  REQUIRE(items.contains("teach.copy_latex.F"));
  const nlohmann::json text_report =
      RenderScript(dir, path, "numbers_text",
                   "frames 3\ncommand teach numbers on\ncommand teach second-image 1\n"
                   "frames 3\nclick left " +
                       ItemCenter(items, "teach.copy.K") + "\nframes 2\ncommand save " + saved + "\n");
  const nlohmann::json& numbers = text_report.at("teach").at("numbers");
  const Eigen::Matrix3d K = Mat3(numbers.at("K"));
  CHECK(text_report.at("teach").at("clipboard").get<std::string>() == MatrixToText(K, 10));
  const Project solved = LoadProjectFile(saved);
  const Camera& a = solved.FindImage(numbers.at("image_id").get<Id>())->camera;
  const Camera& b = solved.FindImage(numbers.at("second_image_id").get<Id>())->camera;
  CHECK((K - a.K()).norm() == 0.0);
  CHECK((Mat3(numbers.at("R")) - a.cam_from_world_rotation).norm() == 0.0);
  CHECK((Vec3(numbers.at("t")) - a.cam_from_world_translation).norm() == 0.0);
  // F is the two cameras' geometry: x_b^T F x_a = 0 on projected points.
  const Eigen::Matrix3d F = Mat3(numbers.at("F"));
  CHECK(std::abs(F.norm() - 1.0) < 1e-12);
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d x = scene.true_box.mesh.vertex(c).position + Eigen::Vector3d(0.3 * c, -0.2, 0.1 * c);
    const Eigen::Vector3d xa = a.Project(x).homogeneous(), xb = b.Project(x).homogeneous();
    CHECK(std::abs(xb.dot(F * xa)) <= kNoiseFreeRelative * xb.norm() * (F * xa).norm());
  }
  const nlohmann::json latex_report = RenderScript(
      dir, path, "numbers_latex",
      "frames 3\ncommand teach numbers on\ncommand teach second-image 1\nframes 3\nclick left " +
          ItemCenter(items, "teach.copy_latex.F") + "\nframes 2\nscreenshot " + (dir / "numbers_shot.png"));
  CHECK(latex_report.at("teach").at("clipboard").get<std::string>() ==
        MatrixToLatex(Mat3(latex_report.at("teach").at("numbers").at("F")), 10));
}

TEST_CASE("modelling state: the (K, F) counts per History entry, with the teach option on") {
  TempDir dir("teach_state");
  const SyntheticScene scene = MakeBoxScene();
  const std::string path = WriteScene(dir, scene, scene.project);
  const nlohmann::json report =
      RenderScript(dir, path, "state",
                   "frames 3\ncommand teach state on\ncommand add box\nframes 2\nscreenshot " + (dir / "state.png"));
  const nlohmann::json& counts = report.at("teach").at("history_counts");
  REQUIRE(counts.size() == report.at("undo_stack").size() + 1);
  REQUIRE(counts.size() == 2u);
  CHECK(counts.at(1).at("primitives").get<int>() == counts.at(0).at("primitives").get<int>() + 1);
  CHECK(counts.at(1).at("vertices").get<int>() == counts.at(0).at("vertices").get<int>() + 8);
  CHECK(counts.at(1).at("faces").get<int>() == counts.at(0).at("faces").get<int>() + 6);
  CHECK(counts.at(0).at("pins").get<int>() == 8);
  CHECK(report.at("teach").at("degrees_of_freedom_left").get<int>() >= 0);
}

// The pictures of README's "Teaching with Facet", each overlay on the Leuven sample (the
// epipolar one needs two photos: the synthetic two-view scene).
TEST_CASE("screenshots of each teach overlay") {
  TempDir dir("teach_shots");
  const fs::path shots = fs::path(FACET_BINARY_DIR) / "teach";
  fs::create_directories(shots);
  const std::string leuven = std::string(FACET_SOURCE_DIR) + "/assets/samples/leuven/leuven.facet";
  // The app opens the project by its file name from the project's folder, as a user does, so
  // that the pictures' log shows no folder of the machine that made them.
  auto shot = [&](const std::string& project, const std::string& name, const std::string& script) {
    const std::string png = (shots / (name + ".png")).string();
    fs::remove(png);
    WriteText(dir / (name + ".txt"), script + "\nscreenshot " + png + "\n");
    const fs::path project_path(project);
    const RunResult run =
        RunRender(dir,
                  "'" + project_path.filename().string() + "' -o '" + (dir / (name + ".png")) + "' --script '" +
                      (dir / (name + ".txt")) + "' --report '" + (dir / (name + ".json")) + "'",
                  project_path.parent_path().string());
    INFO("stderr: " << run.stderr_text);
    REQUIRE(run.exit_code == 0);
    const nlohmann::json report = ReadJson(dir / (name + ".json"));
    CHECK(report.at("log").dump().find(project_path.parent_path().string()) == std::string::npos);
    const cv::Mat picture = cv::imread(png);
    REQUIRE_MESSAGE(!picture.empty(), name);
    // The README's copy: a small JPEG (a few hundred KB for all four).
    cv::Mat small;
    cv::resize(picture, small, cv::Size(), 0.625, 0.625, cv::INTER_AREA);
    CHECK(cv::imwrite((shots / (name + ".jpg")).string(), small, {cv::IMWRITE_JPEG_QUALITY, 75}));
    return report;
  };
  // The sample the app opens, as the overlay frames it when it turns on (issue 25).
  const std::string street_sample = std::string(FACET_SOURCE_DIR) + "/assets/samples/leuven/street.facet";
  nlohmann::json r = shot(street_sample, "teach-vanishing", "frames 3\ncommand teach vanishing on\nframes 3");
  CHECK(r.at("teach").at("vanishing").size() >= 1u);
  r = shot(leuven, "teach-numbers", "frames 3\ncommand teach numbers on\nframes 3");
  CHECK(r.at("teach").contains("numbers"));
  r = shot(leuven, "teach-state", "frames 3\ncommand teach state on\ncommand add box\nframes 3");
  CHECK(r.at("teach").at("history_counts").size() == 2u);
  const SyntheticScene scene = MakeBoxScene();
  Id second_id = kNoId;
  const Project project = TwoViewProject(scene, &second_id);
  WriteGreyPhoto(dir / "second.png", SecondCamera());
  const std::string path = WriteScene(dir, scene, project);
  const Eigen::Vector2d pointer = scene.true_camera.Project(scene.true_box.mesh.vertex(6).position);
  r = shot(path, "teach-epipolar",
           "frames 3\ncommand teach epipolar on\ncommand select vertex " + std::to_string(scene.box_id) +
               " 2\nframes 2\nmove image " + FormatXY(pointer) + "\nframes 2");
  CHECK(r.at("teach").at("epipolar").size() == 3u);
  // The solver stepped on the street: two steps from the perturbed start (the residuals still
  // tens of px), and the 3D panel of the same state exported through File > Export view's
  // command.
  // The sample copied beside its photo into the test's folder, so that the export goes to a
  // path relative to it and the picture's log names no folder of this machine.
  const fs::path sample_dir = fs::path(FACET_SOURCE_DIR) / "assets/samples/leuven";
  const fs::path street_dir = dir / "street";
  fs::create_directories(street_dir);
  for (const char* file : {"street.facet", "leuvenA.jpg"}) {
    fs::copy_file(sample_dir / file, street_dir / file, fs::copy_options::overwrite_existing);
  }
  const std::string street = (street_dir / "street.facet").string();
  const std::string steps_3d = (street_dir / "teach-steps-3d.png").string();
  r = shot(street, "teach-steps",
           "frames 3\ncommand teach steps on\ncommand teach step\ncommand teach step\ncommand teach residual-scale 4\n"
           "frames 2\ncommand export-view 3d 960x540 teach-steps-3d.png\nframes 2");
  const nlohmann::json& steps = r.at("teach").at("steps");
  REQUIRE(steps.at("steps").get<int>() == 2);
  // With spatial constraints (the augmented Lagrangian's rounds) too, the app's steps are the
  // solve's own iterates (the opened project is the file: opening keeps its stored solution),
  // and the violations listed are the solve's.
  JointSolveOptions budget = SolveStepsOptions();
  budget.max_iterations = 2;
  Project solved;
  std::vector<LmIteration> trace;
  const JointSolveSummary once = SolveJointTraced(
      PerturbForSteps(LoadProjectFile(street), steps.at("perturbation").get<double>()), budget, &solved, &trace);
  REQUIRE(once.IsUsable());
  CHECK(MaxRelativeDifference(steps, solved) <= 1e-12);
  REQUIRE(steps.at("constraints").size() == once.constraints.size());
  REQUIRE(once.constraints.size() == 3u);
  for (size_t i = 0; i < once.constraints.size(); ++i) {
    const nlohmann::json& c = steps.at("constraints").at(i);
    CHECK(c.at("constraint_id").get<Id>() == once.constraints[i].constraint_id);
    CHECK(std::abs(c.at("residual").get<double>() - once.constraints[i].residual) <=
          1e-12 * std::max(1.0, std::abs(once.constraints[i].residual)));
    CHECK(c.at("satisfied").get<bool>() == once.constraints[i].satisfied);
  }
  // The vanishing-point fit stepped on the Leuven photo and the two-view refinement on the
  // synthetic pair with noisy pins, each three steps from the default start (the answer moved
  // off by 20 %), so that the window's plots show a descent; the residuals at the scale
  // stepping chose.
  const std::string three_steps = "command teach step\ncommand teach step\ncommand teach step\n";
  r = shot(leuven, "teach-steps-vp",
           "frames 3\ncommand teach steps on\ncommand teach subject vanishing\n" + three_steps + "frames 3");
  REQUIRE(r.at("teach").at("steps").contains("vanishing"));
  CHECK(r.at("teach").at("steps").at("vanishing").at("path").size() == 4u);  // the start and 3 steps
  // 1.5 px clicks.
  SyntheticSceneOptions noisy;
  noisy.noise_px = 1.5;
  const SyntheticScene noisy_scene = MakeBoxScene(noisy);
  const std::string pair_path = WriteScene(dir, noisy_scene, TwoViewMatchesProject(noisy_scene, 1.5));
  r = shot(pair_path, "teach-steps-two-view",
           "frames 3\ncommand teach steps on\ncommand teach subject two-view\ncommand teach second-image 1\n" +
               three_steps + "command select-image 1\nframes 3");
  REQUIRE(r.at("teach").at("steps").contains("two_view"));
  CHECK(r.at("teach").at("steps").at("two_view").at("steps").get<int>() == 3);
  const cv::Mat exported = cv::imread(steps_3d);
  REQUIRE(!exported.empty());
  CHECK(exported.cols == 960);
  CHECK(exported.rows == 540);
  CHECK(cv::imwrite((shots / "teach-steps-3d.jpg").string(), exported, {cv::IMWRITE_JPEG_QUALITY, 75}));
}

}  // namespace
}  // namespace facet::testing
