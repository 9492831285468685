// Autosave's cost (issue 14, app/state/autosave.h) on the 100-primitive scene (100 boxes, 10
// images, 1,000 pins): the main thread's snapshot of the document (a copy) and the worker's
// serialisation + atomic write (fsync included) of the recovery file, for histories of 1, 10
// and 30 edits. Each edit is what the app commits: one pin moved by 0.5 px and the model
// update's re-solve, which moves every free box and camera, so every edit records the whole
// scene twice (before and after) and the file grows linearly with the history. Counters: the
// file's size (MB) and its share per edit. Also the restore (read, check and rebuild).
#include <benchmark/benchmark.h>

#include <unistd.h>

#include <filesystem>
#include <map>
#include <string>

#include "core/io/recovery_io.h"
#include "core/scene/document.h"
#include "core/solve/model_update.h"
#include "tests/bench/joint_scene.h"

namespace {

using namespace facet;

// A converged 100 / 10 / 1,000 scene with `edits` committed pin moves.
const Document& SceneWithHistory(int edits) {
  static std::map<int, Document> cache;
  auto it = cache.find(edits);
  if (it != cache.end()) return it->second;
  const testing::JointScene scene = testing::MakeJointScene(testing::JointSceneSize(100, 10, 1000));
  ModelUpdateOptions options = CommitUpdateOptions();
  options.calibrate = false;  // no line families in the scene: rotations are given
  Project project;
  UpdateModel(scene.start, options, &project);
  Document document(project);
  for (int i = 0; i < edits; ++i) {
    Project edited = document.project();
    edited.pins[(37 * i) % edited.pins.size()].uv_px.x() += 0.5;
    Project updated;
    UpdateModel(edited, options, &updated);
    document.Commit("Move pin", updated);
  }
  return cache.emplace(edits, std::move(document)).first->second;
}

std::string TempPath() {
  return (std::filesystem::temp_directory_path() / ("facet_bench_recovery_" + std::to_string(::getpid()))).string();
}

void BM_RecoverySnapshot(benchmark::State& state) {
  const Document& document = SceneWithHistory(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    Document copy = document;
    benchmark::DoNotOptimize(copy);
  }
}
BENCHMARK(BM_RecoverySnapshot)->ArgName("edits")->Arg(1)->Arg(10)->Arg(30)->Unit(benchmark::kMillisecond);

void BM_RecoveryWrite(benchmark::State& state) {
  const Document& document = SceneWithHistory(static_cast<int>(state.range(0)));
  const std::string path = TempPath();
  for (auto _ : state) {
    const std::string error = SaveRecovery(document, path);
    if (!error.empty()) state.SkipWithError(error.c_str());
  }
  const double mb = static_cast<double>(std::filesystem::file_size(path)) / 1e6;
  state.counters["file_MB"] = mb;
  state.counters["MB_per_edit"] = mb / static_cast<double>(state.range(0));
  std::filesystem::remove(path);
}
// Real time: the write waits for the disk (fsync), which the worker thread does.
BENCHMARK(BM_RecoveryWrite)->ArgName("edits")->Arg(1)->Arg(10)->Arg(30)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_RecoveryRestore(benchmark::State& state) {
  const Document& document = SceneWithHistory(static_cast<int>(state.range(0)));
  const std::string path = TempPath() + "_restore";
  const std::string error = SaveRecovery(document, path);
  if (!error.empty()) state.SkipWithError(error.c_str());
  for (auto _ : state) {
    const RecoveryLoadResult loaded = LoadRecovery(path);
    if (!loaded.ok()) state.SkipWithError(loaded.error.c_str());
  }
  std::filesystem::remove(path);
}
BENCHMARK(BM_RecoveryRestore)->ArgName("edits")->Arg(1)->Arg(10)->Arg(30)->Unit(benchmark::kMillisecond);

}  // namespace
