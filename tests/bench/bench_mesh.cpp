// K-operator and triangulation timings against scene size (core/mesh/operators.h): a scene
// of N cylinders of 98 segments (100 faces each), N = 1, 10, 100 up to 10,000 faces. The
// operators must not grow with N; re-triangulating the changed faces must not either, while
// a full triangulation does. Linked into facet_bench, whose main is in bench_model.cpp.
#include <benchmark/benchmark.h>

#include <vector>

#include "core/mesh/mesh.h"
#include "core/mesh/operators.h"
#include "core/mesh/primitives.h"
#include "core/mesh/triangulate.h"

namespace {

using namespace facet;

constexpr int kSegments = 98;  // 98 side quads + 2 caps = 100 faces per primitive

PolyMesh Scene(int primitives) {
  PolyMesh mesh;
  for (int i = 0; i < primitives; ++i) {
    PrimitiveShape p = MakeCylinder(i + 1, kSegments, 1.0, 3.0);
    p.translation = Eigen::Vector3d(3.0 * (i % 10), 3.0 * (i / 10), 0.0);
    AddPrimitive(&mesh, p);
  }
  return mesh;
}

// Interior edges spread over the whole scene, so successive iterations touch cold memory.
std::vector<EdgeId> SpreadEdges(const PolyMesh& mesh, int count) {
  std::vector<EdgeId> edges;
  const EdgeId step = std::max<EdgeId>(1, mesh.EdgeIdEnd() / count);
  for (EdgeId e = 0; e < mesh.EdgeIdEnd() && static_cast<int>(edges.size()) < count; e += step) edges.push_back(e);
  return edges;
}

// Side quads (not caps) spread over the scene.
std::vector<FaceId> SpreadQuads(const PolyMesh& mesh, int count) {
  std::vector<FaceId> faces;
  const FaceId step = std::max<FaceId>(1, mesh.FaceIdEnd() / count);
  for (FaceId f = 0; f < mesh.FaceIdEnd() && static_cast<int>(faces.size()) < count; f += step) {
    if (FaceDegree(mesh, f) == 4) faces.push_back(f);
  }
  return faces;
}

// E_split with fresh ids followed by its inverse V_delete. Each pair leaves one dead vertex
// and edge slot behind (ids are never reused), so the iteration count is capped.
void BM_ESplitThenVDelete(benchmark::State& state) {
  PolyMesh mesh = Scene(static_cast<int>(state.range(0)));
  const std::vector<EdgeId> edges = SpreadEdges(mesh, 64);
  std::size_t i = 0;
  for (auto _ : state) {
    const ESplitResult s = ESplit(&mesh, edges[i++ % edges.size()], 0.3);
    benchmark::DoNotOptimize(UndoESplit(&mesh, s));
  }
  state.counters["faces"] = mesh.NumFaces();
}
BENCHMARK(BM_ESplitThenVDelete)->Arg(1)->Arg(10)->Arg(100)->Iterations(200000)->Unit(benchmark::kNanosecond);

// V_delete of a split vertex and its undo (E_split re-creating the same ids): no slot growth.
void BM_VDeleteThenESplit(benchmark::State& state) {
  PolyMesh mesh = Scene(static_cast<int>(state.range(0)));
  std::vector<VertexId> vertices;
  for (EdgeId e : SpreadEdges(mesh, 64)) vertices.push_back(ESplit(&mesh, e, 0.3).vertex);
  std::size_t i = 0;
  for (auto _ : state) {
    const VDeleteResult d = VDelete(&mesh, vertices[i++ % vertices.size()]);
    benchmark::DoNotOptimize(UndoVDelete(&mesh, d));
  }
  state.counters["faces"] = mesh.NumFaces();
}
BENCHMARK(BM_VDeleteThenESplit)->Arg(1)->Arg(10)->Arg(100)->Unit(benchmark::kNanosecond);

// V_connect across a side quad with fresh ids, then E_delete.
void BM_VConnectThenEDelete(benchmark::State& state) {
  PolyMesh mesh = Scene(static_cast<int>(state.range(0)));
  const std::vector<FaceId> faces = SpreadQuads(mesh, 64);
  std::vector<std::pair<VertexId, VertexId>> diagonals;
  for (FaceId f : faces) {
    const std::vector<VertexId> v = FaceVertices(mesh, f);
    diagonals.emplace_back(v[0], v[2]);
  }
  std::size_t i = 0;
  for (auto _ : state) {
    const std::size_t k = i++ % faces.size();
    const VConnectResult c = VConnect(&mesh, faces[k], diagonals[k].first, diagonals[k].second);
    benchmark::DoNotOptimize(UndoVConnect(&mesh, c));
  }
  state.counters["faces"] = mesh.NumFaces();
}
BENCHMARK(BM_VConnectThenEDelete)->Arg(1)->Arg(10)->Arg(100)->Iterations(200000)->Unit(benchmark::kNanosecond);

// E_delete of a diagonal and its undo (V_connect re-creating the same ids).
void BM_EDeleteThenVConnect(benchmark::State& state) {
  PolyMesh mesh = Scene(static_cast<int>(state.range(0)));
  std::vector<EdgeId> diagonals;
  for (FaceId f : SpreadQuads(mesh, 64)) {
    const std::vector<VertexId> v = FaceVertices(mesh, f);
    diagonals.push_back(VConnect(&mesh, f, v[0], v[2]).edge);
  }
  std::size_t i = 0;
  for (auto _ : state) {
    const EDeleteResult d = EDelete(&mesh, diagonals[i++ % diagonals.size()]);
    benchmark::DoNotOptimize(UndoEDelete(&mesh, d));
  }
  state.counters["faces"] = mesh.NumFaces();
}
BENCHMARK(BM_EDeleteThenVConnect)->Arg(1)->Arg(10)->Arg(100)->Unit(benchmark::kNanosecond);

// After an operator: re-triangulate only the two faces it touched.
void BM_RetriangulateChangedFaces(benchmark::State& state) {
  PolyMesh mesh = Scene(static_cast<int>(state.range(0)));
  MeshTriangulation tri = TriangulateMesh(mesh);
  const std::vector<EdgeId> edges = SpreadEdges(mesh, 64);
  std::size_t i = 0;
  for (auto _ : state) {
    const HalfedgeId h = PolyMesh::EdgeHalfedge(edges[i++ % edges.size()], 0);
    RetriangulateFaces(mesh, {mesh.Face(h), mesh.Face(PolyMesh::Twin(h))}, &tri);
    benchmark::DoNotOptimize(tri.by_face.data());
  }
  state.counters["faces"] = mesh.NumFaces();
}
BENCHMARK(BM_RetriangulateChangedFaces)->Arg(1)->Arg(10)->Arg(100)->Unit(benchmark::kNanosecond);

// The alternative: triangulate the whole scene again.
void BM_TriangulateWholeMesh(benchmark::State& state) {
  PolyMesh mesh = Scene(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(TriangulateMesh(mesh));
  state.counters["faces"] = mesh.NumFaces();
}
BENCHMARK(BM_TriangulateWholeMesh)->Arg(1)->Arg(10)->Arg(100)->Unit(benchmark::kMicrosecond);

}  // namespace
