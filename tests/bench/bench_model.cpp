// Timings of what runs after every edit and during a drag, with OpenCV's nearest
// equivalents in the same run as the reference.
#include <benchmark/benchmark.h>

#include <opencv2/calib3d.hpp>

#include "core/estimators/calibrate_vp.h"
#include "core/mesh/extrude.h"
#include "core/mesh/primitives.h"
#include "core/solve/model_update.h"
#include "core/solve/scene_solve.h"
#include "core/texture/textured_mesh.h"
#include "tests/synthetic_scene.h"

namespace {

using facet::testing::MakeBoxScene;
using facet::testing::SyntheticSceneOptions;

std::vector<facet::Segment> SceneSegments(const facet::Project& p) { return p.segments; }

void BM_CalibrateThreeVanishingPoints(benchmark::State& state) {
  SyntheticSceneOptions o;
  o.noise_px = 0.5;
  o.extra_lines_per_axis = static_cast<int>(state.range(0));
  const auto scene = MakeBoxScene(o);
  facet::VpCalibrationOptions options;
  options.width_px = o.width_px;
  options.height_px = o.height_px;
  const auto segments = SceneSegments(scene.project);
  for (auto _ : state) benchmark::DoNotOptimize(facet::CalibrateFromVanishingLines(segments, options));
  state.counters["segments"] = static_cast<double>(segments.size());
}
BENCHMARK(BM_CalibrateThreeVanishingPoints)->Arg(4)->Arg(13)->Unit(benchmark::kMicrosecond);

// One drag step: a pin moved by a pixel, then exactly what the app runs per frame while a pin
// is dragged (DragFrameUpdateOptions, with a calibration cache as the app keeps one).
void BM_DragStep(benchmark::State& state) {
  SyntheticSceneOptions o;
  o.noise_px = 0.5;
  auto scene = MakeBoxScene(o);
  facet::Project current;
  facet::ModelUpdateOptions cold;
  facet::UpdateModel(scene.project, cold, &current);
  const facet::ModelUpdateOptions drag = facet::DragFrameUpdateOptions();
  facet::ModelUpdateCache cache;
  int step = 0;
  for (auto _ : state) {
    current.pins[0].uv_px.x() += (step++ % 2 == 0) ? 1.0 : -1.0;
    facet::Project next;
    benchmark::DoNotOptimize(facet::UpdateModel(current, drag, &next, &cache));
    current = std::move(next);
  }
}
BENCHMARK(BM_DragStep)->Unit(benchmark::kMicrosecond);

void BM_SolveSceneCold(benchmark::State& state) {
  SyntheticSceneOptions o;
  o.noise_px = 0.5;
  const auto scene = MakeBoxScene(o);
  facet::SceneSolveOptions options;
  for (auto _ : state) {
    facet::Project solved;
    benchmark::DoNotOptimize(facet::SolveScene(scene.project, options, &solved));
  }
}
BENCHMARK(BM_SolveSceneCold)->Unit(benchmark::kMicrosecond);

// Reference: OpenCV's iterative PnP on the same 8 pins (6 pose parameters, known box), the
// closest off-the-shelf problem to our camera-and-box solve (3 + 2 parameters).
void BM_OpenCvSolvePnPReference(benchmark::State& state) {
  SyntheticSceneOptions o;
  o.noise_px = 0.5;
  const auto scene = MakeBoxScene(o);
  std::vector<cv::Point3d> object;
  std::vector<cv::Point2d> image;
  for (const auto& pin : scene.project.pins) {
    const Eigen::Vector3d& corner = scene.true_box.mesh.vertex(pin.vertex.vertex).position;
    object.emplace_back(corner.x(), corner.y(), corner.z());
    image.emplace_back(pin.uv_px.x(), pin.uv_px.y());
  }
  const Eigen::Matrix3d k = scene.true_camera.K();
  const cv::Matx33d camera(k(0, 0), 0, k(0, 2), 0, k(1, 1), k(1, 2), 0, 0, 1);
  for (auto _ : state) {
    cv::Vec3d rvec, tvec;
    benchmark::DoNotOptimize(
        cv::solvePnP(object, image, camera, cv::noArray(), rvec, tvec, false, cv::SOLVEPNP_ITERATIVE));
  }
}
BENCHMARK(BM_OpenCvSolvePnPReference)->Unit(benchmark::kMicrosecond);

void BM_BakeTexture(benchmark::State& state) {
  const auto scene = MakeBoxScene();
  facet::ImageRgba8 photo;
  photo.width = scene.project.images[0].width_px;
  photo.height = scene.project.images[0].height_px;
  photo.pixels.assign(static_cast<size_t>(photo.width) * photo.height * 4, 128);
  const std::vector<facet::ImageRgba8> photos = {photo};
  for (auto _ : state) {
    facet::TexturedMesh mesh;
    benchmark::DoNotOptimize(facet::BakeTexturedMesh(scene.project, photos, facet::TextureBakeOptions{}, &mesh));
  }
}
BENCHMARK(BM_BakeTexture)->Unit(benchmark::kMillisecond);

// Push/pull: one extrusion of a quad and its undo, on a cylinder of range(0) segments (the
// mesh grows, the changed region does not): the time must stay flat. The mesh is reset every
// 1,000 iterations, outside the timing, because undone ids stay as dead slots.
void BM_ExtrudeQuadAndUndo(benchmark::State& state) {
  const facet::PrimitiveShape shape = facet::MakeCylinder(1, static_cast<int>(state.range(0)), 1.0, 2.0);
  facet::PolyMesh start;
  facet::AddPrimitive(&start, shape);
  facet::PolyMesh mesh = start;
  const facet::FaceId side_face = 2;  // a quad between the caps
  int since_reset = 0;
  for (auto _ : state) {
    const facet::ExtrudeResult x = facet::ExtrudeFace(&mesh, shape, side_face, 0.25);
    benchmark::DoNotOptimize(facet::UndoExtrudeFace(&mesh, x, nullptr));
    if (++since_reset == 1000) {
      state.PauseTiming();
      mesh = start;
      since_reset = 0;
      state.ResumeTiming();
    }
  }
  state.counters["faces"] = static_cast<double>(start.NumFaces());
}
BENCHMARK(BM_ExtrudeQuadAndUndo)->Arg(16)->Arg(1024)->Arg(16384)->Unit(benchmark::kMicrosecond);

// Extruding the n-gon cap: the work grows with the face's degree, as it must.
void BM_ExtrudeCap(benchmark::State& state) {
  const facet::PrimitiveShape shape = facet::MakeCylinder(1, static_cast<int>(state.range(0)), 1.0, 2.0);
  facet::PolyMesh start;
  facet::AddPrimitive(&start, shape);
  for (auto _ : state) {
    state.PauseTiming();
    facet::PolyMesh mesh = start;
    state.ResumeTiming();
    benchmark::DoNotOptimize(facet::ExtrudeFace(&mesh, shape, 1, 0.25));
  }
}
BENCHMARK(BM_ExtrudeCap)->Arg(16)->Arg(256)->Arg(4096)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
