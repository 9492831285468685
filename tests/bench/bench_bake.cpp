// The texture bake after an edit with four 3072x2048 photos (the Strecha fountain's size):
// what the app's main thread paid per edit before the bake moved to a worker thread (a copy
// of every photo, then the bake), and what it pays now (a project snapshot, the untextured
// geometry, a thread start), beside the bake itself, which the worker now runs.
#include <benchmark/benchmark.h>

#include <cmath>
#include <future>
#include <random>
#include <vector>

#include "core/texture/textured_mesh.h"
#include "tests/synthetic_scene.h"

namespace {

constexpr int kWidthPx = 3072;
constexpr int kHeightPx = 2048;
constexpr int kViews = 4;

struct BakeScene {
  facet::Project project;
  std::vector<facet::ImageRgba8> photos;  // one per image, noise so no texel is trivial
};

// The synthetic box seen by four cameras spread over 60 degrees around it.
const BakeScene& FourViewScene() {
  static const BakeScene scene = [] {
    facet::testing::SyntheticSceneOptions o;
    o.width_px = kWidthPx;
    o.height_px = kHeightPx;
    o.focal_px *= static_cast<double>(kWidthPx) / 1024.0;
    BakeScene s;
    s.project = facet::testing::MakeBoxScene(o).project;
    const facet::Image first = s.project.images[0];
    const Eigen::Vector3d offset = o.camera_center - o.look_at;
    for (int v = 1; v < kViews; ++v) {
      facet::testing::SyntheticSceneOptions ov = o;
      const double angle = (20.0 * v) * M_PI / 180.0;
      ov.camera_center = o.look_at + Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()) * offset;
      facet::Image image = first;
      image.id = s.project.NewId();
      image.camera = facet::testing::MakeLookAtCamera(ov);
      s.project.images.push_back(image);
    }
    std::mt19937 rng(7);
    for (int v = 0; v < kViews; ++v) {
      facet::ImageRgba8 photo;
      photo.width = kWidthPx;
      photo.height = kHeightPx;
      photo.pixels.resize(static_cast<size_t>(kWidthPx) * kHeightPx * 4);
      for (auto& p : photo.pixels) p = static_cast<std::uint8_t>(rng());
      s.photos.push_back(std::move(photo));
    }
    return s;
  }();
  return scene;
}

double PhotoBytes(const BakeScene& scene) {
  double bytes = 0.0;
  for (const auto& p : scene.photos) bytes += static_cast<double>(p.pixels.size());
  return bytes;
}

// Before: the main thread copied every photo into a vector and baked (app_state.cpp until
// this change).
void BM_EditMainThreadBefore(benchmark::State& state) {
  const BakeScene& scene = FourViewScene();
  for (auto _ : state) {
    std::vector<facet::ImageRgba8> copies;
    copies.reserve(scene.photos.size());
    for (const auto& p : scene.photos) copies.push_back(p);
    facet::TexturedMesh mesh;
    benchmark::DoNotOptimize(facet::BakeTexturedMesh(scene.project, copies, facet::TextureBakeOptions{}, &mesh));
  }
  state.counters["MB_copied"] = PhotoBytes(scene) / 1e6;
}
BENCHMARK(BM_EditMainThreadBefore)->Unit(benchmark::kMillisecond)->Iterations(5);

// The copy alone.
void BM_PhotoCopyPerEdit(benchmark::State& state) {
  const BakeScene& scene = FourViewScene();
  for (auto _ : state) {
    std::vector<facet::ImageRgba8> copies(scene.photos.begin(), scene.photos.end());
    benchmark::DoNotOptimize(copies.data());
  }
  state.counters["MB_copied"] = PhotoBytes(scene) / 1e6;
}
BENCHMARK(BM_PhotoCopyPerEdit)->Unit(benchmark::kMillisecond)->Iterations(5);

// The bake from pointers: what the worker thread runs now; no pixel is copied.
void BM_BakeFromPointers(benchmark::State& state) {
  const BakeScene& scene = FourViewScene();
  std::vector<const facet::ImageRgba8*> pointers;
  for (const auto& p : scene.photos) pointers.push_back(&p);
  int atlas_width = 0, atlas_height = 0;
  for (auto _ : state) {
    facet::TexturedMesh mesh;
    const auto summary = facet::BakeTexturedMesh(scene.project, pointers, facet::TextureBakeOptions{}, &mesh);
    atlas_width = summary.atlas_width;
    atlas_height = summary.atlas_height;
    benchmark::DoNotOptimize(mesh.atlas.pixels.data());
  }
  state.counters["atlas_w"] = atlas_width;
  state.counters["atlas_h"] = atlas_height;
  state.counters["MB_copied"] = 0.0;
}
BENCHMARK(BM_BakeFromPointers)->Unit(benchmark::kMillisecond)->Iterations(5);

// After: the main thread's share of an edit (app_state.cpp RefreshDerived/StartBake): the
// untextured geometry shown at once, the project snapshot the worker owns, the thread start.
void BM_EditMainThreadAfter(benchmark::State& state) {
  const BakeScene& scene = FourViewScene();
  std::vector<const facet::ImageRgba8*> pointers;
  for (const auto& p : scene.photos) pointers.push_back(&p);
  for (auto _ : state) {
    facet::TexturedMesh geometry = facet::BuildUntexturedMesh(scene.project);
    benchmark::DoNotOptimize(geometry.positions.data());
    auto job = std::async(std::launch::async, [snapshot = scene.project, photos = pointers]() {
      return snapshot.images.size() + photos.size();  // the bake itself is timed above
    });
    state.PauseTiming();  // the worker's run is not the main thread's
    benchmark::DoNotOptimize(job.get());
    state.ResumeTiming();
  }
  state.counters["MB_copied"] = 0.0;
}
BENCHMARK(BM_EditMainThreadAfter)->Unit(benchmark::kMicrosecond);

}  // namespace
