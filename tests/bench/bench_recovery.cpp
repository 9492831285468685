// Autosave's cost (issue 14, app/state/autosave.h) on the 100-primitive scene (100 boxes, 10
// images, 1,000 pins), for histories of 1, 10 and 30 edits. Each edit is what the app commits:
// one pin moved by 0.5 px and the model update's re-solve, which moves every free box and
// camera, so every edit records the whole scene twice (before and after).
// - BM_RecoveryDelta: the main thread's part of a write since the journal (recovery format 2):
//   the delta of the last edit (MakeRecoveryDelta), against BM_RecoverySnapshot, the copy of
//   the whole document that format 1 took.
// - BM_RecoveryJournal: a session of N edits written one write per edit as autosave does
//   (appends, and compactions when the journal outgrows the base). Counters: the bytes written
//   per edit (all writes / N), the last write's, the number of compactions and the file's size.
// - BM_RecoveryWrite: a whole write (what format 1 did after every edit; now a compaction).
// - BM_RecoveryRestore: read, check and rebuild.
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

void BM_RecoveryDelta(benchmark::State& state) {
  Document document = SceneWithHistory(static_cast<int>(state.range(0)));
  // What the journal was told before the last edit.
  document.Undo();
  RecoveryWritten before;
  MakeRecoveryDelta(document, nullptr, &before);
  document.Redo();
  for (auto _ : state) {
    RecoveryWritten written = before;
    RecoveryDelta delta = MakeRecoveryDelta(document, nullptr, &written);
    benchmark::DoNotOptimize(delta);
  }
}
BENCHMARK(BM_RecoveryDelta)->ArgName("edits")->Arg(1)->Arg(10)->Arg(30)->Unit(benchmark::kMillisecond);

void BM_RecoveryJournal(benchmark::State& state) {
  const int edits = static_cast<int>(state.range(0));
  const Document& full = SceneWithHistory(edits);
  Project first = full.project();
  for (size_t i = full.undo_stack().size(); i-- > 0;) RevertEdit(full.undo_stack()[i], &first);
  const std::string path = TempPath() + "_journal";
  std::uint64_t total = 0, last = 0, file = 0;
  int compactions = 0;
  for (auto _ : state) {
    std::filesystem::remove(path);
    Document document(first);
    RecoveryJournal journal;
    RecoveryWritten written;
    total = 0;
    compactions = 0;
    for (int i = 0; i < edits; ++i) {
      Project next = document.project();
      ApplyEdit(full.undo_stack()[static_cast<size_t>(i)], &next);
      document.Commit("Move pin", next);
      const RecoveryWriteResult result = journal.Write(path, MakeRecoveryDelta(document, nullptr, &written));
      if (!result.ok()) state.SkipWithError(result.error.c_str());
      total += result.bytes_written;
      last = result.bytes_written;
      file = result.file_bytes;
      compactions += result.compacted ? 1 : 0;
    }
  }
  state.counters["MB_per_edit"] = static_cast<double>(total) / 1e6 / edits;
  state.counters["last_MB"] = static_cast<double>(last) / 1e6;
  state.counters["file_MB"] = static_cast<double>(file) / 1e6;
  state.counters["compactions"] = compactions;
  std::filesystem::remove(path);
}
BENCHMARK(BM_RecoveryJournal)
    ->ArgName("edits")
    ->Arg(1)
    ->Arg(10)
    ->Arg(30)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->UseRealTime();

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
