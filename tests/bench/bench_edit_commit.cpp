// The app's path for one K-op edit at scale (issue 4: "editing and re-triangulating stays
// interactive with 100 primitives and 10,000 faces"): copy the project, E_split an edge of one
// primitive, commit it to the document (diff of every primitive against the previous state)
// and rebuild the untextured triangle mesh the 3D panel draws. N cylinders of 98 segments
// (100 faces each): N = 1, 10, 100.
#include <benchmark/benchmark.h>

#include <string>

#include "core/mesh/operators.h"
#include "core/mesh/primitives.h"
#include "core/scene/document.h"
#include "core/scene/project.h"
#include "core/texture/textured_mesh.h"

namespace {

using namespace facet;

Project CylinderScene(int primitives) {
  Project project;
  for (int i = 0; i < primitives; ++i) {
    PrimitiveShape shape = MakeCylinder(kNoId, 98, 1.0, 3.0);
    shape.translation = Eigen::Vector3d(3.0 * (i % 10), 3.0 * (i / 10), 0.0);
    AddPrimitiveToProject(&project, shape, "cylinder " + std::to_string(i), nullptr, nullptr);
  }
  return project;
}

// One edit as the app does it; the document grows by one history entry per iteration, which
// is what a long session does too.
void BM_SplitEdgeCommitAndRebuildMesh(benchmark::State& state) {
  Document document(CylinderScene(static_cast<int>(state.range(0))));
  int faces = 0;
  for (const Primitive& p : document.project().primitives) faces += p.mesh.NumFaces();
  std::size_t i = 0;
  for (auto _ : state) {
    Project edited = document.project();
    Primitive& primitive = edited.primitives[i++ % edited.primitives.size()];
    const ESplitResult split = ESplit(&primitive.mesh, 0, 0.5);
    if (!split.ok) state.SkipWithError(split.message.c_str());
    document.Commit("Split edge", edited);
    benchmark::DoNotOptimize(BuildUntexturedMesh(document.project()));
  }
  state.counters["faces"] = faces;
}
BENCHMARK(BM_SplitEdgeCommitAndRebuildMesh)->Arg(1)->Arg(10)->Arg(100)->Iterations(200)->Unit(benchmark::kMillisecond);

}  // namespace
