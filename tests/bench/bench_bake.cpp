// The texture bake after an edit with four 3072x2048 photos (the Strecha fountain's size):
// what the app's main thread paid per edit before the bake moved to a worker thread (a copy
// of every photo, then the bake), and what it pays now (a project snapshot, the untextured
// geometry, a thread start), beside the bake itself, which the worker now runs.
#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>
#include <future>
#include <random>
#include <string>
#include <vector>

#include "core/image/image_io.h"
#include "core/io/project_io.h"
#include "core/mesh/primitives.h"
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

// ---- Issue 13: the bake itself, on the Leuven sample and on a 12 MP, 100-face, four-view scene.
// Wall time and the CPU time of all the bake's threads (it renders z-buffers and samples faces
// on one thread per core).

namespace bake13 {

// The bake settings a benchmark argument names: 0 the single best view per face (the paper's
// rule), 1 the default blended bake.
facet::TextureBakeOptions OptionsForMode(int mode, int max_atlas_size) {
  facet::TextureBakeOptions options;
  options.max_atlas_size = max_atlas_size;
  if (mode == 0) {
    options.source = facet::TextureSource::kBestView;
    options.compensate_exposure = false;
  }
  return options;
}

struct LoadedScene {
  facet::Project project;
  std::vector<facet::ImageRgba8> photos;
  std::string error;
};

// The shipped street (three houses with roofs, one 751 x 563 photo).
const LoadedScene& LeuvenStreet() {
  static const LoadedScene scene = [] {
    LoadedScene s;
    const std::string dir = std::string(FACET_SOURCE_DIR) + "/assets/samples/leuven/";
    facet::ProjectLoadResult loaded = facet::LoadProject(dir + "street.facet");
    if (!loaded.ok()) {
      s.error = loaded.error;
      return s;
    }
    s.project = loaded.project;
    for (const facet::Image& image : s.project.images) {
      facet::ImageReadResult read = facet::ReadImage(dir + image.path);
      if (!read.ok()) s.error = read.error;
      s.photos.push_back(std::move(read.image));
    }
    return s;
  }();
  return scene;
}

// 17 boxes (102 faces) on a 5 x 4 grid seen by four 4000 x 3000 cameras around it, photos of
// noise so that no texel is trivial: the "100 faces from four 12 MP photos".
const LoadedScene& TwelveMegapixelScene() {
  static const LoadedScene scene = [] {
    constexpr int kW = 4000, kH = 3000;
    LoadedScene s;
    facet::testing::SyntheticSceneOptions o;
    o.width_px = kW;
    o.height_px = kH;
    o.focal_px = 3200.0;
    o.look_at = {9.0, 7.0, 1.0};
    o.camera_center = {30.0, -18.0, 14.0};
    s.project = facet::testing::MakeBoxScene(o).project;
    std::string message;
    for (int k = 1; k < 17; ++k) {
      facet::PrimitiveShape box = facet::MakeBox(facet::kNoId, Eigen::Vector3d(2.0, 1.5, 1.0 + 0.25 * (k % 5)));
      box.translation = Eigen::Vector3d(4.5 * (k % 5), 4.0 * (k / 5), 0.0);
      facet::AddPrimitiveToProject(&s.project, box, "box", nullptr, &message);
    }
    const facet::Image first = s.project.images[0];
    s.project.images.clear();
    const Eigen::Vector3d offset = o.camera_center - o.look_at;
    std::mt19937 rng(13);
    for (int v = 0; v < 4; ++v) {
      facet::testing::SyntheticSceneOptions ov = o;
      ov.camera_center = o.look_at + Eigen::AngleAxisd(M_PI / 2 * v, Eigen::Vector3d::UnitZ()) * offset;
      facet::Image image = first;
      image.id = s.project.NewId();
      image.camera = facet::testing::MakeLookAtCamera(ov);
      s.project.images.push_back(image);
      facet::ImageRgba8 photo;
      photo.width = kW;
      photo.height = kH;
      photo.pixels.resize(static_cast<size_t>(kW) * kH * 4);
      for (auto& p : photo.pixels) p = static_cast<std::uint8_t>(rng());
      s.photos.push_back(std::move(photo));
    }
    return s;
  }();
  return scene;
}

void RunBake(benchmark::State& state, const LoadedScene& scene, int max_atlas_size) {
  if (!scene.error.empty()) {
    state.SkipWithError(scene.error.c_str());
    return;
  }
  std::vector<const facet::ImageRgba8*> pointers;
  for (const auto& p : scene.photos) pointers.push_back(&p);
  const facet::TextureBakeOptions options = OptionsForMode(static_cast<int>(state.range(0)), max_atlas_size);
  facet::TextureBakeSummary summary;
  std::uint32_t atlas_hash = 2166136261u;
  double encode_ms = 0.0;
  for (auto _ : state) {
    facet::TexturedMesh mesh;
    summary = facet::BakeTexturedMesh(scene.project, pointers, options, &mesh);
    benchmark::DoNotOptimize(mesh.atlas.pixels.data());
    state.PauseTiming();
    // FNV-1a of every atlas page: a speed-up that claims not to change the bake shows the same.
    atlas_hash = 2166136261u;
    for (int p = 0; p < mesh.AtlasPageCount(); ++p) {
      for (std::uint8_t byte : mesh.AtlasPage(p).pixels) atlas_hash = (atlas_hash ^ byte) * 16777619u;
    }
    // The export's PNG encoding of the pages (issue 13's split names it), outside the bake's time.
    const auto encode_start = std::chrono::steady_clock::now();
    for (int p = 0; p < mesh.AtlasPageCount(); ++p) benchmark::DoNotOptimize(facet::EncodePng(mesh.AtlasPage(p)).size());
    encode_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - encode_start).count();
    state.ResumeTiming();
  }
  if (!summary.IsUsable()) state.SkipWithError(summary.message.c_str());
  state.counters["atlas_fnv"] = atlas_hash;
  state.counters["faces"] = summary.faces_textured;
  state.counters["atlas_w"] = summary.atlas_width;
  state.counters["atlas_h"] = summary.atlas_height;
  // The split of the last run, ms.
  state.counters["depth_ms"] = summary.depth_maps_ms;
  state.counters["select_ms"] = summary.selection_ms;
  state.counters["pack_ms"] = summary.packing_ms;
  state.counters["gain_ms"] = summary.exposure_ms;
  state.counters["sample_ms"] = summary.sampling_ms;
  state.counters["encode_ms"] = encode_ms;
}

void BM_BakeLeuvenStreet(benchmark::State& state) { RunBake(state, LeuvenStreet(), 8192); }
BENCHMARK(BM_BakeLeuvenStreet)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();

void BM_Bake12MpFourViews(benchmark::State& state) { RunBake(state, TwelveMegapixelScene(), 4096); }
BENCHMARK(BM_Bake12MpFourViews)
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

}  // namespace bake13
