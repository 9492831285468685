// Running COLMAP (core/io/colmap_run.h) without COLMAP's cost: the child process layer
// (exit codes, the log, cancel ending the whole process group), the runner's refusals (no
// colmap: the install hint; too few photos; one file name twice) with a stand-in program,
// and the similarity fit that brings a reconstruction into another frame
// (core/estimators/similarity_fit.h), and a whole run with a stand-in whose mapper writes a
// text model (tests/fake_colmap.h). COLMAP itself runs in the real-data suite
// (tests/realdata/test_colmap_fountain.cpp).
#include <doctest/doctest.h>

#include <signal.h>
#include <sys/stat.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <thread>

#include <Eigen/Geometry>

#include "core/estimators/similarity_fit.h"
#include "core/io/colmap_model_write.h"
#include "core/io/colmap_run.h"
#include "core/util/child_process.h"
#include "tests/fake_colmap.h"

namespace fs = std::filesystem;
using namespace facet;

namespace {

fs::path TempDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("facet_test_colmap_run_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string ReadText(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// An executable shell script standing in for a program.
fs::path WriteScript(const fs::path& path, const std::string& body) {
  std::ofstream(path) << "#!/bin/sh\n" << body << "\n";
  fs::permissions(path, fs::perms::owner_all);
  return path;
}

}  // namespace

TEST_CASE("a child process: arguments as given (no shell), output in the log, the exit code") {
  const fs::path dir = TempDir("child");
  ChildProcessOptions options;
  options.executable = "sh";
  options.arguments = {"-c", "echo \"$1 $FACET_TEST_VALUE\"; pwd; exit 3", "sh", "two words; $(not run)"};
  options.working_dir = dir.string();
  options.log_path = (dir / "log.txt").string();
  options.environment = {{"FACET_TEST_VALUE", "set"}};
  const ChildProcessResult result = RunChildProcess(options);
  CHECK(result.started);
  CHECK(!result.Succeeded());
  CHECK(result.exit_code == 3);
  CHECK(ReadText(dir / "log.txt") == "two words; $(not run) set\n" + dir.string() + "\n");

  options.executable = "facet-no-such-program";
  const ChildProcessResult missing = RunChildProcess(options);
  CHECK(!missing.started);
  CHECK(missing.error.find("facet-no-such-program") != std::string::npos);
}

TEST_CASE("cancel ends the child and what it started (its process group), within the grace time") {
  const fs::path dir = TempDir("cancel");
  // The child starts a grandchild that would outlive it, and writes its pid.
  ChildProcessOptions options;
  options.executable = "sh";
  options.arguments = {"-c", "sleep 30 & echo $! > grandchild.pid; wait"};
  options.working_dir = dir.string();
  std::atomic<bool> cancel{false};
  options.should_cancel = [&] { return cancel.load(); };
  std::thread canceller([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    cancel = true;
  });
  const auto start = std::chrono::steady_clock::now();
  const ChildProcessResult result = RunChildProcess(options);
  canceller.join();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  CHECK(result.cancelled);
  CHECK(!result.Succeeded());
  CHECK(seconds < 5.0);
  std::ifstream pid_file(dir / "grandchild.pid");
  int grandchild = 0;
  REQUIRE(static_cast<bool>(pid_file >> grandchild));
  // The grandchild is gone (or a zombie about to be reaped by init): no live process with its
  // pid in state other than Z.
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  const std::string stat = ReadText("/proc/" + std::to_string(grandchild) + "/stat");
  const bool alive = !stat.empty() && stat.find(") Z") == std::string::npos;
  CHECK_MESSAGE(!alive, "grandchild " << grandchild << ": " << stat);
}

TEST_CASE("RunColmap without colmap says how to install it; bad inputs are refused before any run") {
  const fs::path dir = TempDir("refusals");
  const fs::path photo_a = dir / "a.jpg", photo_b = dir / "b.jpg";
  std::ofstream(photo_a) << "x";
  std::ofstream(photo_b) << "x";
  ColmapRunOptions options;
  options.colmap_executable = (dir / "no-colmap-here").string();
  options.working_dir = (dir / "work").string();
  options.photo_paths = {photo_a.string(), photo_b.string()};
  ColmapRunSummary summary = RunColmap(options);
  CHECK(summary.termination == SolverTermination::kInvalidInput);
  CHECK(summary.message.find("apt-get install colmap") != std::string::npos);
  CHECK(!fs::exists(dir / "work"));  // nothing made

  // A stand-in colmap that records its arguments and fails in the matcher.
  options.colmap_executable =
      WriteScript(dir / "fake-colmap", "echo \"$@\"; [ \"$1\" = exhaustive_matcher ] && exit 2; exit 0").string();
  options.photo_paths = {photo_a.string()};
  CHECK(RunColmap(options).message.find("at least two photos") != std::string::npos);
  fs::create_directories(dir / "other");
  std::ofstream(dir / "other" / "a.jpg") << "x";
  options.photo_paths = {photo_a.string(), (dir / "other" / "a.jpg").string()};
  CHECK(RunColmap(options).message.find("two photos are named a.jpg") != std::string::npos);

  options.photo_paths = {photo_a.string(), photo_b.string()};
  std::vector<ColmapStage> stages;
  options.progress = [&](ColmapStage stage, int, int) { stages.push_back(stage); };
  summary = RunColmap(options);
  CHECK(summary.termination == SolverTermination::kFailed);
  CHECK(summary.stage_reached == ColmapStage::kMatching);
  CHECK(summary.message.find("matching failed (exit code 2)") != std::string::npos);
  CHECK(stages ==
        std::vector<ColmapStage>{ColmapStage::kPreparing, ColmapStage::kFeatureExtraction, ColmapStage::kMatching});
  // The log keeps each stage's command and output; the CPU SIFT is asked for.
  const std::string log = ReadText(summary.log_path);
  CHECK(log.find("feature_extractor") != std::string::npos);
  CHECK(log.find("--SiftExtraction.use_gpu 0") != std::string::npos);
  CHECK(log.find("--SiftMatching.use_gpu 0") != std::string::npos);
  CHECK(fs::is_symlink(dir / "work" / "images" / "a.jpg"));
}

TEST_CASE("RunColmap cancelled mid-stage ends the stage and reports it") {
  const fs::path dir = TempDir("run_cancel");
  std::ofstream(dir / "a.jpg") << "x";
  std::ofstream(dir / "b.jpg") << "x";
  ColmapRunOptions options;
  options.colmap_executable = WriteScript(dir / "slow-colmap", "sleep 30").string();
  options.working_dir = (dir / "work").string();
  options.photo_paths = {(dir / "a.jpg").string(), (dir / "b.jpg").string()};
  std::atomic<bool> cancel{false};
  options.cancel = &cancel;
  options.progress = [&](ColmapStage stage, int, int) {
    if (stage == ColmapStage::kFeatureExtraction) cancel = true;  // as soon as it starts
  };
  const ColmapRunSummary summary = RunColmap(options);
  CHECK(summary.cancelled);
  CHECK(!summary.IsUsable());
  CHECK(summary.stage_reached == ColmapStage::kFeatureExtraction);
  CHECK(summary.time_ms < 5000.0);
  CHECK(summary.message.find("cancelled during feature extraction") != std::string::npos);
}

TEST_CASE("the similarity fit recovers a known scale, rotation and translation; refuses collinear points") {
  std::mt19937 rng(7);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<Eigen::Vector3d> source, target;
  const double scale = 3.7;
  const Eigen::Matrix3d rotation =
      Eigen::AngleAxisd(2.1, Eigen::Vector3d(0.3, -0.5, 0.8).normalized()).toRotationMatrix();
  const Eigen::Vector3d translation(1.0, -20.0, 5.0);
  for (int i = 0; i < 6; ++i) {
    source.emplace_back(normal(rng), normal(rng), normal(rng));
    target.push_back(scale * rotation * source.back() + translation);
  }
  SimilarityFit fit = FitSimilarity(source, target);
  REQUIRE(fit.ok);
  CHECK(std::abs(fit.transform.scale - scale) < 1e-12);
  CHECK((fit.transform.rotation - rotation).norm() < 1e-12);
  CHECK((fit.transform.translation - translation).norm() < 1e-11);
  CHECK(fit.rms_residual < 1e-12);

  // Noise: the residual is about the noise, the scale close.
  for (Eigen::Vector3d& t : target) t += 0.01 * Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
  fit = FitSimilarity(source, target);
  REQUIRE(fit.ok);
  CHECK(fit.rms_residual < 0.03);
  CHECK(std::abs(fit.transform.scale - scale) < 0.01);
  CHECK(fit.transform.rotation.determinant() == doctest::Approx(1.0));

  const std::vector<Eigen::Vector3d> line = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 1, 1),
                                             Eigen::Vector3d(2, 2, 2)};
  CHECK(!FitSimilarity(line, line).ok);
  CHECK(!FitSimilarity({source[0], source[1]}, {target[0], target[1]}).ok);
}

TEST_CASE("RunColmap with a stand-in colmap: the mapper's text model is read, the photos it placed are named") {
  const fs::path dir = TempDir("fake_mapper");
  for (const char* name : {"a.jpg", "b.jpg", "c.jpg"}) std::ofstream(dir / name) << "x";
  // A model of a.jpg and b.jpg only: c.jpg is the photo COLMAP could not place.
  ColmapModel model;
  for (std::uint32_t id : {1u, 2u}) {
    ColmapCamera camera;
    camera.camera_id = id;
    camera.model = ColmapCameraModel::kSimplePinhole;
    camera.width_px = 640;
    camera.height_px = 480;
    camera.params = {500.0, 320.0, 240.0};
    model.cameras.push_back(camera);
    ColmapImage image;
    image.image_id = id;
    image.camera_id = id;
    image.name = id == 1 ? "a.jpg" : "b.jpg";
    image.cam_from_world_translation = Eigen::Vector3d(id, 0.0, 0.0);
    model.images.push_back(image);
  }
  REQUIRE(WriteColmapModelText((dir / "model").string(), model) == "");
  testing::FakeColmapOptions fake;
  fake.model_dir = (dir / "model").string();
  ColmapRunOptions options;
  options.colmap_executable = testing::WriteFakeColmap(dir / "fake-colmap", fake);
  options.working_dir = (dir / "work").string();
  options.photo_paths = {(dir / "a.jpg").string(), (dir / "b.jpg").string(), (dir / "c.jpg").string()};
  const ColmapRunSummary summary = RunColmap(options);
  REQUIRE_MESSAGE(summary.IsUsable(), summary.message);
  CHECK(summary.stage_reached == ColmapStage::kDone);
  CHECK(summary.num_registered == 2);
  CHECK(summary.registered == std::vector<bool>{true, true, false});
  CHECK(summary.model.images.size() == 2);
  CHECK(summary.model_dir == (dir / "work" / "sparse" / "0").string());
  REQUIRE(summary.warnings.size() == 1);
  CHECK(summary.warnings[0] == "COLMAP could not place photo c.jpg");
  CHECK(ReadText(summary.log_path).find("fake colmap: mapper") != std::string::npos);

  // The mapper failing: kFailed, the log named.
  fake.mapper_exit_code = 7;
  options.colmap_executable = testing::WriteFakeColmap(dir / "failing-colmap", fake);
  const ColmapRunSummary failed = RunColmap(options);
  CHECK(failed.termination == SolverTermination::kFailed);
  CHECK(failed.message.find("mapping failed (exit code 7)") != std::string::npos);
}
