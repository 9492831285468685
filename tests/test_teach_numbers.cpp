// The numbers teach mode shows and lets a course copy: matrices as plain text and LaTeX
// (core/util/matrix_text.h), F and the epipoles of two cameras (core/solve/multiview_init.h)
// checked against the geometry, the modelling state's counts per history state
// (core/scene/modelling_state.h) and the degrees of freedom the joint solve leaves; the closest
// points of two rays (core/geometry/ray_pair.h) that the epipolar overlay draws in 3D.
#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "core/geometry/ray_pair.h"
#include "core/mesh/operators.h"
#include "core/scene/modelling_state.h"
#include "core/solve/joint_solve.h"
#include "core/solve/multiview_init.h"
#include "core/util/matrix_text.h"
#include "tests/synthetic_scene.h"

namespace facet {
namespace {

// Reads back MatrixToText: whitespace-separated numbers, one row per line.
Eigen::MatrixXd ParseText(const std::string& text) {
  std::vector<std::vector<double>> rows;
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    std::istringstream in(line);
    rows.emplace_back();
    double x;
    while (in >> x) rows.back().push_back(x);
  }
  Eigen::MatrixXd m(rows.size(), rows.empty() ? 0 : rows[0].size());
  for (size_t r = 0; r < rows.size(); ++r) {
    REQUIRE(rows[r].size() == static_cast<size_t>(m.cols()));
    for (size_t c = 0; c < rows[r].size(); ++c) m(r, c) = rows[r][c];
  }
  return m;
}

TEST_CASE("matrix text: aligned rows that read back to the stated significant digits") {
  Eigen::Matrix3d m;
  m << 661.5, 0, 319.5, 0, -0.0, 239.5, 1.25e-7, -3.5e12, 1;
  const std::string text = MatrixToText(m, 6);
  CHECK(text ==
        "   661.5         0  319.5\n"
        "       0         0  239.5\n"
        "1.25e-07  -3.5e+12      1");
  // Read back within 6 significant digits (relative 5e-6 of each entry).
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> mantissa(-1.0, 1.0);
  std::uniform_int_distribution<int> exponent(-12, 12);
  for (int trial = 0; trial < 100; ++trial) {
    Eigen::MatrixXd r(3, 4);
    for (int i = 0; i < r.size(); ++i) {
      const double x = mantissa(rng);
      r(i) = x * std::pow(10.0, exponent(rng));
    }
    const Eigen::MatrixXd back = ParseText(MatrixToText(r, 6));
    REQUIRE(back.rows() == 3);
    REQUIRE(back.cols() == 4);
    for (int i = 0; i < r.size(); ++i) CHECK(std::abs(back(i) - r(i)) <= 5e-6 * std::abs(r(i)));
    const Eigen::MatrixXd exact = ParseText(MatrixToText(r, 17));
    CHECK(exact == r);  // 17 digits round-trip every double
  }
}

TEST_CASE("matrix LaTeX: a bmatrix, exponents as powers of ten") {
  Eigen::Matrix<double, 2, 3> m;
  m << 1, -2.5, 1.5e-7, 0, 3e20, -1e-100;
  CHECK(MatrixToLatex(m, 4) ==
        "\\begin{bmatrix}\n"
        "1 & -2.5 & 1.5 \\times 10^{-7} \\\\\n"
        "0 & 3 \\times 10^{20} & -1 \\times 10^{-100}\n"
        "\\end{bmatrix}");
  Eigen::Vector3d t(0.5, 0, -2);
  CHECK(MatrixToLatex(t, 4) == "\\begin{bmatrix}\n0.5 \\\\\n0 \\\\\n-2\n\\end{bmatrix}");
}

// A second camera of the box scene, from the other side of the box.
Camera SecondCamera(const testing::SyntheticScene& scene) {
  testing::SyntheticSceneOptions o;
  o.camera_center = {-5.0, -8.0, 4.0};
  o.roll_deg = -2.0;
  o.focal_px = 1100.0;
  o.principal_point_offset_px = {-20.0, 15.0};
  return testing::MakeLookAtCamera(o);
}

TEST_CASE("F from two cameras: x_b^T F x_a = 0 on projected points; the epipoles are the other centres") {
  // Noise-free: products of exact matrices; relative to |x_b| |F x_a|.
  constexpr double kNoiseFreeRelative = 1e-9;
  const testing::SyntheticScene scene = testing::MakeBoxScene();
  const Camera& a = scene.true_camera;
  const Camera b = SecondCamera(scene);
  const Eigen::Matrix3d F = FundamentalFromCameras(a, b);
  REQUIRE(F.norm() > 0.0);
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> coord(-2.0, 6.0);
  const EpipolePair epipoles = EpipolesOfCameras(a, b);
  for (int k = 0; k < 200; ++k) {
    const double x = coord(rng);
    const double y = coord(rng);
    const double z = coord(rng);
    const Eigen::Vector3d X(x, y, z);
    const Eigen::Vector3d xa = a.Project(X).homogeneous(), xb = b.Project(X).homogeneous();
    CHECK(std::abs(xb.dot(F * xa)) <= kNoiseFreeRelative * xb.norm() * (F * xa).norm());
    // The epipolar line of x_a in b passes through x_b and through the epipole e_b.
    const EpipolarLine line = EpipolarLineInImage(F, xa.head<2>(), b.width_px, b.height_px);
    CHECK(std::abs(line.line.dot(xb)) <= kNoiseFreeRelative * b.width_px);
    CHECK(std::abs(line.line.dot(epipoles.in_b)) <= kNoiseFreeRelative);
  }
  CHECK((F * epipoles.in_a).norm() <= kNoiseFreeRelative * F.norm());
  CHECK((F.transpose() * epipoles.in_b).norm() <= kNoiseFreeRelative * F.norm());
  // e_a is where image a sees b's centre.
  const Eigen::Vector3d seen = a.K() * a.CamFromWorld(b.CenterInWorld());
  CHECK((seen.head<2>() / seen.z() - epipoles.in_a.head<2>() / epipoles.in_a.z()).norm() < 1e-9 * a.width_px);
  CHECK(EpipolesOfCameras(a, a).in_a.isZero());
}

TEST_CASE("closest points of two rays: skew rays of known closest points, at 1e-3 and 1e3 scale, and a camera pair") {
  // Closed form on exact inputs: rounding, relative to the scene's size.
  constexpr double kRelative = 1e-9;
  std::mt19937 rng(15);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (const double scale : {1e-3, 1.0, 1e3}) {
    for (int k = 0; k < 50; ++k) {
      CAPTURE(scale);
      CAPTURE(k);
      // P on ray a, Q on ray b, PQ perpendicular to both directions: P and Q are the answer.
      const Eigen::Vector3d P = scale * Eigen::Vector3d(u(rng), u(rng), u(rng));
      const Eigen::Vector3d n = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
      const double gap = scale * (0.1 + std::abs(u(rng)));
      const Eigen::Vector3d Q = P + gap * n;
      Eigen::Vector3d da = Eigen::Vector3d(u(rng), u(rng), u(rng)), db = Eigen::Vector3d(u(rng), u(rng), u(rng));
      da = (da - da.dot(n) * n).normalized();
      db = (db - db.dot(n) * n).normalized();
      if (std::abs(da.dot(db)) > 0.99) continue;  // nearly parallel: not this case's subject
      const double s = scale * (1.0 + 3.0 * std::abs(u(rng))), t = scale * (1.0 + 3.0 * std::abs(u(rng)));
      const Eigen::Vector3d origin_a = P - s * da, origin_b = Q - t * db;
      // Directions of any length.
      const RayPairClosestPoints c = ClosestPointsOfRays(origin_a, 2.5 * da, origin_b, 0.3 * db);
      REQUIRE(c.valid);
      CHECK((c.on_a - P).norm() < kRelative * scale);
      CHECK((c.on_b - Q).norm() < kRelative * scale);
      CHECK((c.midpoint - 0.5 * (P + Q)).norm() < kRelative * scale);
      CHECK(std::abs(c.gap - gap) < kRelative * scale);
      CHECK(std::abs(c.s - s) < kRelative * scale);
      CHECK(std::abs(c.t - t) < kRelative * scale);
    }
  }
  // Two cameras' rays through one point's projections meet at the point.
  const testing::SyntheticScene scene = testing::MakeBoxScene();
  const Camera& a = scene.true_camera;
  const Camera b = SecondCamera(scene);
  for (int v = 0; v < 8; ++v) {
    const Eigen::Vector3d X = scene.true_box.mesh.vertex(v).position;
    const RayPairClosestPoints c = ClosestPointsOfRays(a.CenterInWorld(), a.RayDirectionInWorld(a.Project(X)),
                                                       b.CenterInWorld(), b.RayDirectionInWorld(b.Project(X)));
    REQUIRE(c.valid);
    const double size = (a.CenterInWorld() - X).norm();
    CHECK((c.on_a - X).norm() < kRelative * size);
    CHECK((c.on_b - X).norm() < kRelative * size);
    CHECK(c.gap < kRelative * size);
    CHECK(c.s > 0.0);
    CHECK(c.t > 0.0);
  }
  // Parallel rays, and a zero direction, have no closest pair.
  CHECK_FALSE(ClosestPointsOfRays({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-2, 0, 0}).valid);
  CHECK_FALSE(ClosestPointsOfRays({0, 0, 0}, {0, 0, 0}, {0, 1, 0}, {1, 0, 0}).valid);
}

TEST_CASE("the modelling state per history entry: counts of K and F in every state, undo and redo") {
  testing::SyntheticScene scene = testing::MakeBoxScene();
  Project start = scene.project;
  start.pins.clear();
  Document document(start);
  const ModellingStateCounts empty_pins = CountModellingState(document.project());
  CHECK(empty_pins.primitives == 1);
  CHECK(empty_pins.vertices == 8);
  CHECK(empty_pins.edges == 12);
  CHECK(empty_pins.faces == 6);
  CHECK(empty_pins.pins == 0);
  CHECK(empty_pins.images == 1);
  CHECK(empty_pins.segments == static_cast<int>(scene.project.segments.size()));
  // Three edits: two pins, a split edge (one vertex and one edge more), a coplanarity.
  Project p = document.project();
  p.pins.push_back(scene.project.pins[0]);
  p.pins.push_back(scene.project.pins[1]);
  REQUIRE(document.Commit("pins", p));
  PolyMesh& mesh = p.primitives[0].mesh;
  const EdgeId edge = 0;
  REQUIRE(mesh.IsEdge(edge));
  REQUIRE(ESplit(&mesh, edge, 0.5).ok);
  REQUIRE(document.Commit("split", p));
  Constraint c;
  c.id = p.NewId();
  c.kind = ConstraintKind::kCoplanar;
  c.vertices = {{scene.box_id, 0}, {scene.box_id, 1}, {scene.box_id, 2}, {scene.box_id, 3}};
  p.constraints.push_back(c);
  REQUIRE(document.Commit("coplanar", p));
  REQUIRE(document.Undo());  // the coplanarity becomes a redo state

  const std::vector<ModellingStateCounts> counts = HistoryStateCounts(document);
  REQUIRE(counts.size() == 4u);
  CHECK(counts[0] == empty_pins);
  CHECK(counts[1].pins == 2);
  CHECK(counts[1].vertices == 8);
  CHECK(counts[2].vertices == 9);
  CHECK(counts[2].edges == 13);
  CHECK(counts[2].faces == 6);
  CHECK(counts[2].spatial_constraints == 0);
  CHECK(counts[3].spatial_constraints == 1);
  CHECK(counts[2] == CountModellingState(document.project()));  // the current state
  // Walking the history left the document as it was.
  CHECK(document.undo_stack().size() == 2u);
  CHECK(document.redo_stack().size() == 1u);
}

TEST_CASE("degrees of freedom left: the box scene's, and one more (the scale) without its known length") {
  const testing::SyntheticScene scene = testing::MakeBoxScene();
  JointSolveOptions options;
  Project solved;
  const JointSolveSummary with_length = SolveJoint(scene.project, options, &solved);
  REQUIRE(with_length.IsUsable());
  REQUIRE(with_length.degrees_of_freedom_left >= 0);
  Project unscaled = scene.project;
  unscaled.primitives[0].param_locked = {false, false, false, false};
  const JointSolveSummary without_length = SolveJoint(unscaled, options, &solved);
  REQUIRE(without_length.IsUsable());
  CAPTURE(with_length.num_parameters);
  CAPTURE(without_length.num_parameters);
  CHECK(without_length.num_parameters == with_length.num_parameters + 1);
  CHECK(without_length.degrees_of_freedom_left == with_length.degrees_of_freedom_left + 1);
  options.compute_diagnostics = false;
  CHECK(SolveJoint(scene.project, options, &solved).degrees_of_freedom_left == -1);
}

}  // namespace
}  // namespace facet
