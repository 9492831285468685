// Issue 5's F-operators on a multi-selection in the real application offscreen (`facet render`
// with an input script): coplanar on four free vertices of different box faces, collinear on
// three vertices, parallel between two selected edges, each solved on commit, undone and
// redone; refusals that say why; an edge pinned to an image line by the script and by a drag
// of the Line pin tool; Shift+click multi-selection in the image panel, highlighted, and
// Escape; the selection's upkeep after undo; parallel faces as two parallel-edge constraints.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/SVD>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/io/project_io.h"
#include "core/mesh/operators.h"
#include "core/mesh/primitives.h"
#include "core/util/eigen_decompositions.h"
#include "tests/app/app_test_util.h"
#include "tests/synthetic_scene.h"

using namespace facet::testing;


// These cases check that points land exactly where the mouse went: the Snap option off
// (render --no-snap); tests/app/test_snapping.cpp covers snapping.
const bool kRenderWithoutSnapping = (RenderWithoutSnapping() = true);

namespace {

// The joint solve polishes hard constraints on commit: what a noise-free constraint must
// reach, relative to the model's size (or in degrees / pixels where named).
constexpr double kCoplanarRelTolerance = 1e-9;
constexpr double kCollinearRelTolerance = 1e-9;
constexpr double kParallelToleranceDeg = 1e-6;
constexpr double kLinePinTolerancePx = 1e-6;
constexpr double kStartOffRel = 1e-2;  // a start that is this far from the answer is not it

Eigen::Vector3d P(const facet::Project& project, facet::Id primitive_id, facet::VertexId v) {
  return facet::VertexInWorld(project, {primitive_id, v});
}

// Largest distance of the points from their best-fitting plane.
double PlaneDistance(const std::vector<Eigen::Vector3d>& points) {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const auto& p : points) centre += p / static_cast<double>(points.size());
  Eigen::MatrixXd m(points.size(), 3);
  for (size_t i = 0; i < points.size(); ++i) m.row(i) = (points[i] - centre).transpose();
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(m, Eigen::ComputeFullV);
  const Eigen::Vector3d normal = svd.matrixV().col(2);
  double worst = 0.0;
  for (const auto& p : points) worst = std::max(worst, std::abs((p - centre).dot(normal)));
  return worst;
}

// Distance of p from the line through a and b.
double LineDistance(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& p) {
  return (p - a).cross((b - a).normalized()).norm();
}

double AngleDeg(const Eigen::Vector3d& u, const Eigen::Vector3d& v) {
  return std::atan2(u.cross(v).norm(), std::abs(u.dot(v))) * 180.0 / M_PI;
}

double ModelSize(const facet::Project& project) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
  for (const facet::Primitive& p : project.primitives) {
    for (facet::VertexId v = 0; v < p.mesh.VertexIdEnd(); ++v) {
      if (!p.mesh.IsVertex(v)) continue;
      lo = lo.cwiseMin(p.mesh.vertex(v).position);
      hi = hi.cwiseMax(p.mesh.vertex(v).position);
    }
  }
  return (hi - lo).norm();
}

facet::EdgeId EdgeBetween(const facet::PolyMesh& mesh, facet::VertexId a, facet::VertexId b) {
  const facet::HalfedgeId h = facet::FindHalfedge(mesh, a, b);
  REQUIRE(h != facet::kNoElement);
  return facet::PolyMesh::EdgeOf(h);
}

// A unit box (all dimensions locked, so only free vertices move) whose edges 0 (x), 5 (y),
// 10 (z) and 3 (x) are split, the new vertices freed and pushed off their edges by different
// offsets: four free vertices on different faces, not coplanar.
struct FreeVertexBox {
  std::string path;
  facet::Id box_id = facet::kNoId;
  std::vector<facet::VertexId> split;               // the four new vertices
  std::vector<facet::EdgeId> split_edge;            // which edge each split (now origin -> new vertex)
  std::vector<facet::EdgeId> new_edge;              // new vertex -> the split edge's old destination
  facet::VertexId plain_split = facet::kNoElement;  // edge 7 split, not freed: on its edge's line
  facet::VertexId plain_ends[2] = {facet::kNoElement, facet::kNoElement};
  facet::Project project;
};

FreeVertexBox WriteFreeVertexBox(const TempDir& dir) {
  FreeVertexBox f;
  facet::Project& p = f.project;
  std::string message;
  REQUIRE(facet::AddPrimitiveToProject(&p, facet::MakeBox(facet::kNoId, Eigen::Vector3d::Ones()), "box 1", &f.box_id,
                                       &message));
  facet::Primitive& box = *p.FindPrimitive(f.box_id);
  box.param_locked = {true, true, true, true};
  const facet::EdgeId edges[4] = {0, 5, 10, 3};
  const double ts[4] = {0.3, 0.5, 0.6, 0.4};
  const Eigen::Vector3d offsets[4] = {{0.0, -0.15, 0.1}, {0.2, 0.0, -0.1}, {-0.1, 0.12, 0.0}, {0.0, 0.1, 0.25}};
  for (int i = 0; i < 4; ++i) {
    const facet::ESplitResult r = facet::ESplit(&box.mesh, edges[i], ts[i]);
    REQUIRE(r.ok);
    box.mesh.vertex(r.vertex).local.free = true;
    box.mesh.vertex(r.vertex).local.offset = offsets[i];
    f.split.push_back(r.vertex);
    f.split_edge.push_back(edges[i]);
    f.new_edge.push_back(r.new_edge);
  }
  f.plain_ends[0] = box.mesh.Origin(2 * 7);
  f.plain_ends[1] = box.mesh.Dest(2 * 7);
  const facet::ESplitResult plain = facet::ESplit(&box.mesh, 7, 0.5);
  REQUIRE(plain.ok);
  f.plain_split = plain.vertex;
  facet::UpdatePrimitivePositions(&box.mesh, box.shape);
  f.path = dir / "box.facet";
  REQUIRE(facet::SaveProject(p, f.path) == "");
  return f;
}

std::string SelectScript(const std::string& first_kind, facet::Id primitive, const std::vector<std::string>& rest) {
  std::ostringstream s;
  s << "frames 2\ncommand tool select\n" << first_kind << "\n";
  for (const std::string& r : rest) s << r << "\n";
  s << "frames 2\n";
  (void)primitive;
  return s.str();
}

std::string Vertex(const char* command, facet::Id primitive, facet::VertexId v) {
  return std::string("command ") + command + " vertex " + std::to_string(primitive) + " " + std::to_string(v);
}
std::string Edge(const char* command, facet::Id primitive, facet::EdgeId e) {
  return std::string("command ") + command + " edge " + std::to_string(primitive) + " " + std::to_string(e);
}

// The edit, then save / undo + save / redo + save; returns the three saved projects.
struct History {
  facet::Project after, undone, redone;
  nlohmann::json report;
};
History RunWithHistory(const TempDir& dir, const std::string& project_path, const std::string& name,
                       const std::string& script) {
  std::ostringstream s;
  s << script << "frames 2\ncommand save " << (dir / (name + "_after.facet")) << "\nframes 1\n";
  s << "command undo\nframes 2\ncommand save " << (dir / (name + "_undone.facet")) << "\nframes 1\n";
  s << "command redo\nframes 2\ncommand save " << (dir / (name + "_redone.facet")) << "\nframes 1\n";
  History h;
  h.report = RenderScript(dir, project_path, name, s.str());
  h.after = LoadProjectFile(dir / (name + "_after.facet"));
  h.undone = LoadProjectFile(dir / (name + "_undone.facet"));
  h.redone = LoadProjectFile(dir / (name + "_redone.facet"));
  return h;
}

}  // namespace

TEST_CASE("multi-selection: coplanar on four free vertices of different faces, solved, undone, redone") {
  TempDir dir("fops_coplanar");
  const FreeVertexBox f = WriteFreeVertexBox(dir);
  const double size = ModelSize(f.project);
  std::vector<Eigen::Vector3d> start;
  for (facet::VertexId v : f.split) start.push_back(P(f.project, f.box_id, v));
  CAPTURE(PlaneDistance(start));
  REQUIRE(PlaneDistance(start) > kStartOffRel * size);  // the start is not the answer

  const std::string script =
      SelectScript(Vertex("select", f.box_id, f.split[0]), f.box_id,
                   {Vertex("select-add", f.box_id, f.split[1]), Vertex("select-add", f.box_id, f.split[2]),
                    Vertex("select-add", f.box_id, f.split[3])}) +
      "command constrain coplanar\n";
  const History h = RunWithHistory(dir, f.path, "coplanar", script);
  INFO("log: " << ReportLog(h.report));

  REQUIRE(h.after.constraints.size() == 1);
  const facet::Constraint& c = h.after.constraints[0];
  CHECK(c.kind == facet::ConstraintKind::kCoplanar);
  REQUIRE(c.vertices.size() == 4);
  for (int i = 0; i < 4; ++i) CHECK(c.vertices[i] == facet::VertexRef{f.box_id, f.split[i]});
  std::vector<Eigen::Vector3d> solved;
  for (facet::VertexId v : f.split) solved.push_back(P(h.after, f.box_id, v));
  const double distance = PlaneDistance(solved);
  MESSAGE("coplanar: plane distance after the solve " << distance << " (model size " << size << ", start "
                                                      << PlaneDistance(start) << ")");
  CHECK(distance <= kCoplanarRelTolerance * size);
  const nlohmann::json& undo = h.report.at("undo_stack");
  CHECK(undo.back().dump().find("Coplanar (4 vertices)") != std::string::npos);

  // Undo: no constraint, the vertices back where they were; redo: both again.
  CHECK(h.undone.constraints.empty());
  for (size_t i = 0; i < f.split.size(); ++i) CHECK((P(h.undone, f.box_id, f.split[i]) - start[i]).norm() < 1e-12);
  REQUIRE(h.redone.constraints.size() == 1);
  CHECK(h.redone.constraints[0] == c);
  std::vector<Eigen::Vector3d> redone;
  for (facet::VertexId v : f.split) redone.push_back(P(h.redone, f.box_id, v));
  CHECK(PlaneDistance(redone) <= kCoplanarRelTolerance * size);
}

TEST_CASE("multi-selection: collinear on three vertices and parallel between two selected edges") {
  TempDir dir("fops_collinear");
  const FreeVertexBox f = WriteFreeVertexBox(dir);
  const double size = ModelSize(f.project);
  const facet::PolyMesh& mesh = f.project.FindPrimitive(f.box_id)->mesh;
  // Edge 0's split vertex and the two corners of that edge (its ends before the split).
  const facet::VertexId m = f.split[0];
  const facet::VertexId a =
      mesh.Origin(2 * f.split_edge[0]) == m ? mesh.Dest(2 * f.split_edge[0]) : mesh.Origin(2 * f.split_edge[0]);
  const facet::EdgeId new_edge = f.new_edge[0];
  const facet::VertexId b = mesh.Dest(2 * new_edge) == m ? mesh.Origin(2 * new_edge) : mesh.Dest(2 * new_edge);
  REQUIRE(b != m);
  REQUIRE(a != b);
  REQUIRE(a != m);
  const double start_off =
      LineDistance(P(f.project, f.box_id, a), P(f.project, f.box_id, b), P(f.project, f.box_id, m));
  CAPTURE(start_off);
  REQUIRE(start_off > kStartOffRel * size);

  SUBCASE("collinear") {
    const std::string script = SelectScript(Vertex("select", f.box_id, a), f.box_id,
                                            {Vertex("select-add", f.box_id, m), Vertex("select-add", f.box_id, b)}) +
                               "command constrain collinear\n";
    const History h = RunWithHistory(dir, f.path, "collinear", script);
    INFO("log: " << ReportLog(h.report));
    REQUIRE(h.after.constraints.size() == 1);
    CHECK(h.after.constraints[0].kind == facet::ConstraintKind::kCollinear);
    CHECK(h.after.constraints[0].vertices.size() == 3);
    const double off = LineDistance(P(h.after, f.box_id, a), P(h.after, f.box_id, b), P(h.after, f.box_id, m));
    MESSAGE("collinear: distance from the line after the solve " << off << " (start " << start_off << ")");
    CHECK(off <= kCollinearRelTolerance * size);
    CHECK(h.undone.constraints.empty());
    CHECK((P(h.undone, f.box_id, m) - P(f.project, f.box_id, m)).norm() < 1e-12);
    REQUIRE(h.redone.constraints.size() == 1);
    CHECK(LineDistance(P(h.redone, f.box_id, a), P(h.redone, f.box_id, b), P(h.redone, f.box_id, m)) <=
          kCollinearRelTolerance * size);
    CHECK(h.report.at("undo_stack").back().dump().find("Collinear (3 vertices)") != std::string::npos);
  }

  SUBCASE("parallel between two selected edges") {
    // The half of edge 0 from its first corner to the free vertex, and edge 1 (along x).
    const facet::EdgeId half = EdgeBetween(mesh, a, m);
    const facet::PolyMesh& pm = mesh;
    const Eigen::Vector3d d1 = P(f.project, f.box_id, pm.Dest(2 * half)) - P(f.project, f.box_id, pm.Origin(2 * half));
    const Eigen::Vector3d d2 = P(f.project, f.box_id, pm.Dest(2)) - P(f.project, f.box_id, pm.Origin(2));
    const double start_deg = AngleDeg(d1, d2);
    CAPTURE(start_deg);
    REQUIRE(start_deg > 1.0);
    const std::string script =
        SelectScript(Edge("select", f.box_id, half), f.box_id, {Edge("select-add", f.box_id, 1)}) +
        "command constrain parallel\n";
    const History h = RunWithHistory(dir, f.path, "parallel", script);
    INFO("log: " << ReportLog(h.report));
    REQUIRE(h.after.constraints.size() == 1);
    const facet::Constraint& c = h.after.constraints[0];
    CHECK(c.kind == facet::ConstraintKind::kParallel);
    REQUIRE(c.vertices.size() == 4);
    auto angle = [&](const facet::Project& p) {
      return AngleDeg(facet::VertexInWorld(p, c.vertices[1]) - facet::VertexInWorld(p, c.vertices[0]),
                      facet::VertexInWorld(p, c.vertices[3]) - facet::VertexInWorld(p, c.vertices[2]));
    };
    MESSAGE("parallel: angle after the solve " << angle(h.after) << " deg (start " << start_deg << ")");
    CHECK(angle(h.after) < kParallelToleranceDeg);
    CHECK(h.undone.constraints.empty());
    CHECK(std::abs(angle(h.undone) - start_deg) < 1e-9);
    REQUIRE(h.redone.constraints.size() == 1);
    CHECK(angle(h.redone) < kParallelToleranceDeg);
  }

  SUBCASE("refusals say why") {
    // Two distinct vertices for a coplanar; three collinear of four (a plain split vertex and
    // its edge's ends); the same set twice; an element selected twice. A refused command
    // stops the script with the reason.
    const std::string too_few =
        SelectScript(Edge("select", f.box_id, 1), f.box_id, {Vertex("select-add", f.box_id, mesh.Origin(2))}) +
        "command constrain coplanar\n";
    const std::string err1 = RenderScriptRefused(dir, f.path, "refuse_few", too_few);
    CHECK(err1.find("needs 4 or more different vertices (2 selected") != std::string::npos);
    const std::string three_collinear =
        SelectScript(Vertex("select", f.box_id, f.plain_ends[0]), f.box_id,
                     {Vertex("select-add", f.box_id, f.plain_split), Vertex("select-add", f.box_id, f.plain_ends[1]),
                      Vertex("select-add", f.box_id, f.split[0])}) +
        "command constrain coplanar\n";
    const std::string err2 = RenderScriptRefused(dir, f.path, "refuse_collinear", three_collinear);
    CHECK(err2.find("are collinear: with a fourth point they are always coplanar") != std::string::npos);
    // The bottom face's corners (box vertices 0..3, core/mesh/box.h), constrained twice.
    const std::string twice = SelectScript(Vertex("select", f.box_id, 0), f.box_id,
                                           {Vertex("select-add", f.box_id, 1), Vertex("select-add", f.box_id, 2),
                                            Vertex("select-add", f.box_id, 3)}) +
                              "command constrain coplanar\nframes 2\ncommand constrain coplanar\n";
    const std::string err3 = RenderScriptRefused(dir, f.path, "refuse_twice", twice);
    CHECK(err3.find("the same constraint exists already") != std::string::npos);
    const std::string same_edge =
        SelectScript(Edge("select", f.box_id, 1), f.box_id, {Edge("select-add", f.box_id, 1)});
    const std::string err4 = RenderScriptRefused(dir, f.path, "refuse_dup", same_edge);
    CHECK(err4.find("is selected already") != std::string::npos);
  }
}

TEST_CASE("line pin: the selected edge on an image line, by the script and by a drag of the Line pin tool") {
  TempDir dir("fops_linepin");
  const LineScene f = WriteLineScene(dir);
  const facet::Id box = f.scene.box_id;
  const facet::PolyMesh& mesh = f.scene.project.FindPrimitive(box)->mesh;
  const facet::EdgeId edge = EdgeBetween(mesh, 4, 5);
  constexpr double kShiftPx = 3.0;
  Eigen::Vector2d a, b;
  ShiftedLine(f, kShiftPx, &a, &b);

  SUBCASE("script") {
    std::ostringstream s;
    s << "frames 2\n"
      << Edge("select", box, edge) << "\nframes 1\ncommand line-pin 0 " << FormatXY(a) << " " << FormatXY(b) << "\n";
    const History h = RunWithHistory(dir, f.path, "linepin", s.str());
    INFO("log: " << ReportLog(h.report));
    REQUIRE(h.after.constraints.size() == 1);
    const facet::Constraint& c = h.after.constraints[0];
    CHECK(c.kind == facet::ConstraintKind::kEdgeOnImageLine);
    CHECK(c.image_id == f.scene.image_id);
    CHECK((c.line_a_px - a).norm() < 1e-9);
    CHECK((c.line_b_px - b).norm() < 1e-9);
    // The start (the solved scene without the pin) is about kShiftPx off the line.
    const double start_px = LinePinDistancePx(h.undone, c);
    const double after_px = LinePinDistancePx(h.after, c);
    MESSAGE("line pin (script): edge ends from the line " << after_px << " px after the solve (start " << start_px
                                                          << " px)");
    CHECK(start_px > 0.5 * kShiftPx);
    CHECK(after_px < kLinePinTolerancePx);
    CHECK(h.undone.constraints.empty());
    REQUIRE(h.redone.constraints.size() == 1);
    CHECK(LinePinDistancePx(h.redone, h.redone.constraints[0]) < kLinePinTolerancePx);
    CHECK(h.report.at("undo_stack").back().dump().find("Line pin") != std::string::npos);
  }

  SUBCASE("mouse: a click on the edge selects it, a drag along the photo's line pins it") {
    const auto corners = BoxCorners(f.scene.true_box);
    const Eigen::Vector2d mid = f.view.ToScreen(f.scene.true_camera.Project(0.5 * (corners[4] + corners[5])));
    const Eigen::Vector2d sa = f.view.ToScreen(a), sb = f.view.ToScreen(b);
    REQUIRE(f.view.Inside(sa, 5.0));
    REQUIRE(f.view.Inside(sb, 5.0));
    std::ostringstream s;
    s << "frames 2\ncommand tool line-pin\nframes 1\nclick left " << FormatXY(mid) << "\nframes 2\n";
    s << "drag left " << FormatXY(sa) << " " << FormatXY(sb) << " 12\nframes 3\n";
    const History h = RunWithHistory(dir, f.path, "linepin_mouse", s.str());
    INFO("log: " << ReportLog(h.report));
    REQUIRE(h.after.constraints.size() == 1);
    const facet::Constraint& c = h.after.constraints[0];
    CHECK(c.kind == facet::ConstraintKind::kEdgeOnImageLine);
    REQUIRE(c.vertices.size() == 2);
    // The clicked edge (either direction).
    const bool same = (c.vertices[0].vertex == 4 && c.vertices[1].vertex == 5) ||
                      (c.vertices[0].vertex == 5 && c.vertices[1].vertex == 4);
    CHECK(same);
    // The dragged points, to the whole screen pixel the mouse is rounded to.
    const double pixel = 1.0 / f.view.zoom;
    CAPTURE(c.line_a_px.transpose());
    CAPTURE(c.line_b_px.transpose());
    CHECK((c.line_a_px - a).norm() < 1.5 * pixel);
    CHECK((c.line_b_px - b).norm() < 1.5 * pixel);
    const double after_px = LinePinDistancePx(h.after, c);
    MESSAGE("line pin (drag): edge ends from the line " << after_px << " px after the solve (start "
                                                        << LinePinDistancePx(h.undone, c) << " px)");
    CHECK(after_px < kLinePinTolerancePx);
    CHECK(h.undone.constraints.empty());
    CHECK(h.redone.constraints.size() == 1);
  }
}

TEST_CASE("Shift+click in the image panel: a multi-selection, highlighted, toggled, made coplanar") {
  TempDir dir("fops_shift");
  const LineScene f = WriteLineScene(dir);
  const facet::Id box = f.scene.box_id;
  const auto corners = BoxCorners(f.scene.true_box);
  auto screen = [&](const Eigen::Vector3d& x) { return f.view.ToScreen(f.scene.true_camera.Project(x)); };
  std::ostringstream s;
  s << "frames 2\ncommand tool select\nframes 1\nclick left " << FormatXY(screen(corners[4])) << "\nframes 1\n";
  s << "hold shift\nframes 1\n";
  // Corner 5, then the pinned corners 0 and 1 (a Shift+click on a pin takes its vertex).
  for (int c : {5, 0, 1}) s << "click left " << FormatXY(screen(corners[c])) << "\nframes 1\n";
  // An edge and corner 6 added and removed again.
  const Eigen::Vector2d edge_mid = screen(0.5 * (corners[4] + corners[6]));
  for (int i = 0; i < 2; ++i) s << "click left " << FormatXY(edge_mid) << "\nframes 1\n";
  for (int i = 0; i < 2; ++i) s << "click left " << FormatXY(screen(corners[6])) << "\nframes 1\n";
  s << "release shift\nmove 5 5\nframes 3\nscreenshot " << (dir / "multi.png") << "\nframes 1\n";
  const std::string selected = s.str();
  s << "command constrain coplanar\nframes 2\ncommand save " << (dir / "after.facet") << "\nframes 1\n";
  const nlohmann::json report = RenderScript(dir, f.path, "shift", s.str());
  // Escape over the image panel leaves the main element only: collinear then has 1 vertex.
  const Eigen::Vector2d over_image(f.view.rect_x + 5.0, f.view.rect_y + 5.0);
  const std::string err = RenderScriptRefused(
      dir, f.path, "escape",
      selected + "move " + FormatXY(over_image) + "\nframes 1\nkey escape\nframes 1\ncommand constrain collinear\n");
  CHECK(err.find("needs 3 or more different vertices (1 selected") != std::string::npos);
  // A second Escape, with nothing half done, clears the selection itself (as the hint says).
  const nlohmann::json cleared = RenderScript(
      dir, f.path, "escape_twice",
      selected + "move " + FormatXY(over_image) + "\nframes 1\nkey escape\nframes 1\nkey escape\nframes 1\n");
  CHECK(cleared["selection"]["primitive_id"] == 0);
  CHECK(cleared["selection"]["extra"].empty());
  INFO("log: " << ReportLog(report));
  const facet::Project after = LoadProjectFile(dir / "after.facet");
  REQUIRE(after.constraints.size() == 1);
  const facet::Constraint& c = after.constraints[0];
  CHECK(c.kind == facet::ConstraintKind::kCoplanar);
  std::vector<facet::VertexId> ids;
  for (const facet::VertexRef& v : c.vertices) ids.push_back(v.vertex);
  CHECK(ids == std::vector<facet::VertexId>{4, 5, 0, 1});

  // The screenshot: each of the four selected corners carries the selection's orange.
  const cv::Mat shot = cv::imread(dir / "multi.png");
  REQUIRE(!shot.empty());
  constexpr int kOrangeTolerance = 40;
  auto orange_near = [&](const Eigen::Vector2d& p) {
    const int cx = static_cast<int>(std::floor(p.x())), cy = static_cast<int>(std::floor(p.y()));
    int count = 0;
    for (int y = cy - 3; y <= cy + 3; ++y) {
      for (int x = cx - 3; x <= cx + 3; ++x) {
        if (x < 0 || y < 0 || x >= shot.cols || y >= shot.rows) continue;
        const cv::Vec3b bgr = shot.at<cv::Vec3b>(y, x);
        count += std::abs(bgr[2] - 255) <= kOrangeTolerance && std::abs(bgr[1] - 140) <= kOrangeTolerance &&
                 std::abs(bgr[0] - 30) <= kOrangeTolerance;
      }
    }
    return count;
  };
  for (int corner : {4, 5, 0, 1}) {
    const int n = orange_near(screen(corners[corner]));
    CAPTURE(corner);
    CAPTURE(n);
    CHECK(n >= 4);
  }
  // Corners 6 and 7 (not selected) have none.
  CHECK(orange_near(screen(corners[6])) == 0);
  CHECK(orange_near(screen(corners[7])) == 0);
}

TEST_CASE("selection upkeep: an undo drops gone extras and the builder's first edge; so does a cleared selection") {
  TempDir dir("fops_upkeep");
  facet::Project empty;
  const facet::Id box = empty.next_id;
  const std::string path = dir / "empty.facet";
  REQUIRE(facet::SaveProject(empty, path) == "");
  const std::string add = "frames 2\ncommand add box\nframes 1\ncommand tool select\nframes 1\n";

  // The first edge of a two-click parallel, then its box undone and redone: the next click
  // stores a first edge again instead of pairing with the stale one.
  std::ostringstream undo_first;
  undo_first << add << Edge("select", box, 0) << "\ncommand constrain parallel\nframes 1\ncommand undo\nframes 2\n"
             << "command redo\nframes 2\n"
             << Edge("select", box, 1) << "\ncommand constrain parallel\nframes 2\n";
  nlohmann::json report = RenderScript(dir, path, "undo_first", undo_first.str());
  INFO("log: " << ReportLog(report));
  CHECK(report.at("project").at("constraints").empty());
  CHECK(ReportLog(report).find("Parallel: first edge box 1 edge 1") != std::string::npos);

  // The same with the selection cleared in between.
  std::ostringstream cleared;
  cleared << add << Edge("select", box, 0) << "\ncommand constrain parallel\nframes 1\ncommand select none\nframes 2\n"
          << Edge("select", box, 1) << "\ncommand constrain parallel\nframes 2\n";
  report = RenderScript(dir, path, "cleared", cleared.str());
  CHECK(report.at("project").at("constraints").empty());
  // Without either, the two clicks pair (the control).
  std::ostringstream paired;
  paired << add << Edge("select", box, 0) << "\ncommand constrain parallel\nframes 1\n"
         << Edge("select", box, 1) << "\ncommand constrain parallel\nframes 2\n";
  report = RenderScript(dir, path, "paired", paired.str());
  CHECK(report.at("project").at("constraints").size() == 1);

  // A multi-selection whose box an undo removes is gone after the redo.
  std::ostringstream extras;
  extras << add << Vertex("select", box, 0) << "\n"
         << Vertex("select-add", box, 1) << "\n"
         << Vertex("select-add", box, 2) << "\n"
         << Vertex("select-add", box, 3)
         << "\nframes 1\ncommand undo\nframes 2\ncommand redo\nframes 2\ncommand constrain coplanar\n";
  const std::string err = RenderScriptRefused(dir, path, "extras", extras.str());
  CHECK(err.find("(0 selected") != std::string::npos);
}

TEST_CASE("parallel faces: two parallel-edge constraints in one edit; perpendicular faces refused") {
  TempDir dir("fops_faces");
  facet::Project empty;
  const facet::Id box = empty.next_id;
  const std::string path = dir / "empty.facet";
  REQUIRE(facet::SaveProject(empty, path) == "");
  // The app's new box has the mesh of MakeBox: find its faces by their normals here.
  facet::Project scratch;
  facet::Id scratch_id = facet::kNoId;
  std::string message;
  REQUIRE(facet::AddPrimitiveToProject(&scratch, facet::MakeBox(facet::kNoId, Eigen::Vector3d::Ones()), "b",
                                       &scratch_id, &message));
  const facet::PolyMesh& mesh = scratch.FindPrimitive(scratch_id)->mesh;
  auto face_along = [&](const Eigen::Vector3d& n) {
    for (facet::FaceId f = 0; f < mesh.FaceIdEnd(); ++f) {
      if (mesh.IsFace(f) && facet::FaceNormal(mesh, f).dot(n) > 0.99) return f;
    }
    return facet::kNoFace;
  };
  const facet::FaceId top = face_along(Eigen::Vector3d::UnitZ()), bottom = face_along(-Eigen::Vector3d::UnitZ());
  const facet::FaceId front = face_along(-Eigen::Vector3d::UnitY());
  REQUIRE(top != facet::kNoFace);
  REQUIRE(bottom != facet::kNoFace);
  REQUIRE(front != facet::kNoFace);
  auto face = [&](const char* command, facet::FaceId f) {
    return std::string("command ") + command + " face " + std::to_string(box) + " " + std::to_string(f) + "\n";
  };
  const std::string add = "frames 2\ncommand add box\nframes 1\ncommand tool select\nframes 1\n";
  const nlohmann::json report = RenderScript(dir, path, "faces",
                                             add + face("select", top) + face("select-add", bottom) +
                                                 "frames 1\ncommand constrain parallel-faces\nframes 2\n");
  INFO("log: " << ReportLog(report));
  const facet::ProjectLoadResult after = facet::ProjectFromJson(report.at("project").dump());
  REQUIRE(after.ok());
  REQUIRE(after.project.constraints.size() == 2);
  for (const facet::Constraint& c : after.project.constraints) {
    CHECK(c.kind == facet::ConstraintKind::kParallel);
    REQUIRE(c.vertices.size() == 4);
    // Edge a on the top face (z = 1), edge b on the bottom one (z = 0).
    const facet::Primitive& p = after.project.primitives.at(0);
    CHECK(std::abs(p.mesh.vertex(c.vertices[0].vertex).position.z() -
                   p.mesh.vertex(c.vertices[1].vertex).position.z()) < 1e-12);
    CHECK(std::abs(p.mesh.vertex(c.vertices[2].vertex).position.z() -
                   p.mesh.vertex(c.vertices[3].vertex).position.z()) < 1e-12);
  }
  CHECK(report.at("undo_stack").size() == 2);  // add box, parallel faces
  CHECK(report.at("undo_stack").back().dump().find("Parallel faces") != std::string::npos);
  const std::string err = RenderScriptRefused(
      dir, path, "faces_refused",
      add + face("select", top) + face("select-add", front) + "frames 1\ncommand constrain parallel-faces\n");
  CHECK(err.find("no two pairs of edges within 15 deg of parallel") != std::string::npos);
}

TEST_CASE("Shift+click on corners where line segments end: each corner joins the multi-selection") {
  // What the tutorial's author hit: snapping puts a box's corners on the ends of the
  // detected lines, and a Shift+click on such a corner took the segment's end (selecting the
  // segment, dropping the corners chosen before).
  TempDir dir("fops_shift_segments");
  const LineScene f = WriteLineScene(dir);
  facet::Project p = LoadProjectFile(f.path);
  const facet::Camera& cam = f.scene.true_camera;
  const auto corners = BoxCorners(f.scene.true_box);
  // A segment ending at each top corner 5, 6 and 7, along an edge of the box, as the
  // detected lines do.
  for (const auto& [corner, other] : std::vector<std::pair<int, int>>{{5, 4}, {6, 2}, {7, 3}}) {
    facet::Segment s;
    s.id = p.NewId();
    s.image_id = p.images.front().id;
    s.axis = corner == 5 ? facet::Axis::kX : facet::Axis::kZ;
    s.a_px = cam.Project(corners[corner]);
    s.b_px = cam.Project(0.5 * (corners[corner] + corners[other]));
    p.segments.push_back(s);
  }
  const std::string path = dir / "segments_at_corners.facet";
  REQUIRE(facet::SaveProject(p, path) == "");
  auto screen = [&](int c) { return f.view.ToScreen(cam.Project(corners[c])); };
  std::ostringstream s;
  s << "frames 2\ncommand tool select\nframes 1\nclick left " << FormatXY(screen(4))
    << "\nframes 1\nhold shift\nframes 1\n";
  for (int c : {5, 6, 7}) s << "click left " << FormatXY(screen(c)) << "\nframes 1\n";
  s << "release shift\nframes 2\n";
  const nlohmann::json report = RenderScript(dir, path, "shift_on_segment_ends", s.str());
  INFO("log: " << ReportLog(report));
  const nlohmann::json& selection = report.at("selection");
  CHECK(selection.at("segment_id") == 0);
  std::vector<int> ids = {selection.at("element").at("id").get<int>()};
  for (const auto& e : selection.at("extra")) {
    CHECK(e.at("kind") == "vertex");
    ids.push_back(e.at("id").get<int>());
  }
  CHECK(selection.at("element").at("kind") == "vertex");
  CHECK(ids == std::vector<int>{4, 5, 6, 7});
}
