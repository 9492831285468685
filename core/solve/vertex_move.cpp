#include "core/solve/vertex_move.h"

#include <algorithm>
#include <cmath>

#include <Eigen/SVD>

#include "core/solve/model_sanity.h"
#include "core/util/eigen_decompositions.h"
#include "core/util/format.h"

namespace facet {
namespace {

std::string Describe(const Primitive& primitive) {
  return std::string(PrimitiveKindName(primitive.shape.kind)) + " '" + primitive.name + "'";
}

// The messages give sizes and distances to 6 significant digits, not core/util/format.h's
// default 4: a drag's change of 12.3456 -> 12.3461 must show.
constexpr int kMessageDigits = 6;

constexpr double kRoundOffRelative = 1e-14;

// One unknown of the shape solve: a shape parameter (index 0..3) or a translation component.
struct Unknown {
  bool is_param = true;
  int index = 0;
};

// Min-norm least-squares solve of M y = r with singular values below tol * max cut.
Eigen::VectorXd PseudoSolve(const Eigen::MatrixXd& m, const Eigen::VectorXd& r, double tolerance, int* rank) {
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(m, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const Eigen::VectorXd& s = svd.singularValues();
  const double cut = s.size() > 0 ? tolerance * s(0) : 0.0;
  Eigen::VectorXd y = Eigen::VectorXd::Zero(m.cols());
  int r_count = 0;
  for (int i = 0; i < s.size(); ++i) {
    if (!(s(i) > cut) || s(i) == 0.0) break;
    y += svd.matrixV().col(i) * (svd.matrixU().col(i).dot(r) / s(i));
    ++r_count;
  }
  if (rank) *rank = r_count;
  return y;
}

double PrimitiveSize(const Primitive& primitive) {
  const int count = ShapeParamCount(primitive.shape.kind);
  double size = 0.0;
  for (int k = 0; k < count; ++k) size = std::max(size, std::abs(primitive.shape.params[k]));
  return std::max(1.0, size);
}

// The dragged vertex's position after the move, how far it is from the target, and how far
// the primitive's other vertices moved, into the summary.
void RecordPosition(const Primitive& source, const Project& moved, const VertexRef& vertex,
                    const Eigen::Vector3d& target_in_world, double reach_distance, VertexMoveSummary* summary) {
  const Primitive& after = *moved.FindPrimitive(vertex.primitive_id);
  summary->position = after.mesh.vertex(vertex.vertex).position;
  summary->distance_to_target = (summary->position - target_in_world).norm();
  summary->reached = summary->distance_to_target <= reach_distance;
  summary->params_after = after.shape.params;
  summary->translation_after = after.shape.translation;
  for (VertexId v = 0; v < after.mesh.VertexIdEnd(); ++v) {
    if (v == vertex.vertex || !after.mesh.IsVertex(v)) continue;
    summary->max_other_displacement = std::max(summary->max_other_displacement,
                                               (after.mesh.vertex(v).position - source.mesh.vertex(v).position).norm());
  }
}

// Whatever keeps the direction `missing` fixed, in the words of the properties panel.
std::vector<std::string> LockReasons(const Project& project, const Primitive& source, const MeshVertex& dragged,
                                     const Eigen::Matrix3d& world_from_primitive, bool attached,
                                     const Eigen::Vector3d& missing) {
  const PrimitiveShape& shape = source.shape;
  std::vector<std::string> reasons;
  if (attached) {
    const Primitive* base = project.FindPrimitive(source.attached_to);
    reasons.push_back("its footprint and position follow " + Describe(*base) + " (move the base's vertices)");
  }
  if (!attached && source.translation_locked) reasons.push_back("its translation is locked (unlock it to shift it)");
  const ParamCoefficients c = dragged.local.Collapsed();
  for (int k = 0; k < ShapeParamCount(shape.kind); ++k) {
    if (!source.param_locked[k]) continue;
    const Eigen::Vector3d column = world_from_primitive * c.col(k);
    // A locked dimension limits the move only when it could have carried the vertex
    // towards the target.
    if (std::abs(column.dot(missing)) > 1e-12 * column.norm() * std::max(missing.norm(), 1e-300)) {
      reasons.push_back(std::string(ShapeParamLabel(shape.kind, k)) + " is locked (unlock it to change it)");
    }
  }
  return reasons;
}

// The step of the unknowns that takes the dragged vertex towards `wanted` and moves the
// primitive's other vertices least (the header's nullspace method).
Eigen::VectorXd SmallestStep(const Primitive& source, VertexId dragged, const std::vector<Unknown>& unknowns,
                             const Eigen::Matrix3d& world_from_primitive, const Eigen::Vector3d& wanted,
                             const VertexMoveOptions& options, double size) {
  const int n = static_cast<int>(unknowns.size());
  // A_i = d w_i / dx for every live vertex; row block 3 * i.
  std::vector<VertexId> others;
  for (VertexId v = 0; v < source.mesh.VertexIdEnd(); ++v) {
    if (v != dragged && source.mesh.IsVertex(v)) others.push_back(v);
  }
  auto jacobian_of = [&](VertexId v) {
    Eigen::Matrix<double, 3, Eigen::Dynamic> a(3, n);
    const ParamCoefficients c = source.mesh.vertex(v).local.Collapsed();
    for (int u = 0; u < n; ++u) {
      a.col(u) = unknowns[u].is_param ? Eigen::Vector3d(world_from_primitive * c.col(unknowns[u].index))
                                      : Eigen::Vector3d::Unit(unknowns[u].index);
    }
    return a;
  };
  const Eigen::MatrixXd a_dragged = jacobian_of(dragged);
  Eigen::MatrixXd a_others(3 * others.size(), n);
  for (size_t i = 0; i < others.size(); ++i) a_others.middleRows(3 * i, 3) = jacobian_of(others[i]);

  // Nullspace method: x0 reaches the projection of `wanted` onto A_d's range (min norm), N
  // spans the steps that leave the dragged vertex where x0 puts it, and z minimises the other
  // vertices' displacement |A_o (x0 + N z)|^2 over them (min norm when that is not unique).
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(a_dragged, Eigen::ComputeFullV | Eigen::ComputeThinU);
  const Eigen::VectorXd& s = svd.singularValues();
  int rank = 0;
  while (rank < s.size() && s(rank) > options.rank_tolerance * s(0) && s(rank) > 0.0) ++rank;
  Eigen::VectorXd x0 = Eigen::VectorXd::Zero(n);
  for (int i = 0; i < rank; ++i) x0 += svd.matrixV().col(i) * (svd.matrixU().col(i).dot(wanted) / s(i));
  const Eigen::MatrixXd nullspace = svd.matrixV().rightCols(n - rank);
  Eigen::VectorXd dx = x0;
  if (nullspace.cols() > 0 && a_others.rows() > 0) {
    dx += nullspace * PseudoSolve(a_others * nullspace, -a_others * x0, options.rank_tolerance, nullptr);
  }

  // Round-off in directions the optimum leaves alone would show as "shifted by 1e-16".
  for (int u = 0; u < n; ++u) {
    if (std::abs(dx(u)) <= kRoundOffRelative * size) dx(u) = 0.0;
  }
  return dx;
}

// What the move changed ("box 'house': Size y 3 -> 4, shifted by 0.5"), and how far short of
// the target it stopped and why.
std::string DescribeMove(const Primitive& source, const PrimitiveShape& out, const VertexMoveSummary& summary) {
  const PrimitiveShape& shape = source.shape;
  std::string text = Describe(source) + ":";
  for (int k = 0; k < ShapeParamCount(shape.kind); ++k) {
    if (out.params[k] != shape.params[k]) {
      text += std::string(" ") + ShapeParamLabel(shape.kind, k) + " " +
              internal::FormatNumber(shape.params[k], kMessageDigits) + " -> " +
              internal::FormatNumber(out.params[k], kMessageDigits) + ",";
    }
  }
  if (out.translation != shape.translation) {
    text += " shifted by " + internal::FormatNumber((out.translation - shape.translation).norm(), kMessageDigits) + ",";
  }
  text.pop_back();
  if (!summary.reached) {
    text += "; " + internal::FormatNumber(summary.distance_to_target, kMessageDigits) + " short of the target:";
    for (const std::string& r : summary.limited_by) text += " " + r + ";";
    text.pop_back();
  }
  return text;
}

}  // namespace

bool VertexMoveOptions::Check(std::string* error) const {
  if (!(rank_tolerance > 0.0 && rank_tolerance < 1.0)) {
    *error = "rank_tolerance must lie in (0, 1)";
    return false;
  }
  if (!(reach_tolerance > 0.0)) {
    *error = "reach_tolerance must be positive";
    return false;
  }
  return true;
}

const char* ShapeParamLabel(PrimitiveKind kind, int index) {
  switch (kind) {
    case PrimitiveKind::kPrism:
    case PrimitiveKind::kCylinder: return index == 0 ? "Radius" : "Height";
    case PrimitiveKind::kPyramid:
    case PrimitiveKind::kWedge: return index == 0 ? "Size x" : index == 1 ? "Size y" : "Height";
    default: return index == 0 ? "Size x" : index == 1 ? "Size y" : "Size z";
  }
}

int ShapeParamCount(PrimitiveKind kind) {
  switch (kind) {
    case PrimitiveKind::kBox:
    case PrimitiveKind::kWedge:
    case PrimitiveKind::kPyramid: return 3;
    case PrimitiveKind::kPrism:
    case PrimitiveKind::kCylinder:
    case PrimitiveKind::kPlane: return 2;
  }
  return 0;
}

namespace {

// The check every solve's result passes (core/solve/model_sanity.h), for a drag: a drag ray
// almost parallel to its plane puts the point at 1e9 m, and a size dragged to nothing is no
// model either. Sizes at or below zero are named by the caller with their own hint.
std::string WhyMoveDegenerate(const Project& before, const Project& moved) {
  const ModelChangeCheck check = CheckModelChange(before, moved);
  if (check.fault == ModelChangeFault::kCollapsed) return "the move would collapse the model: " + check.what;
  if (check.fault == ModelChangeFault::kGrew || check.fault == ModelChangeFault::kRanAway)
    return "the move would take the model beyond any camera's reach: " + check.what;
  return "";
}

}  // namespace

VertexMoveSummary MoveVertex(const Project& project, const VertexRef& vertex, const Eigen::Vector3d& target_in_world,
                             const VertexMoveOptions& options, Project* moved) {
  VertexMoveSummary summary;
  *moved = project;
  auto refuse = [&](std::string message, SolverTermination termination = SolverTermination::kFailed) {
    summary.termination = termination;
    summary.message = std::move(message);
    *moved = project;
    return summary;
  };
  std::string error;
  if (!options.Check(&error)) return refuse("invalid options: " + error, SolverTermination::kInvalidInput);
  const Primitive* source = project.FindPrimitive(vertex.primitive_id);
  if (source == nullptr) return refuse("the primitive #" + std::to_string(vertex.primitive_id) + " does not exist", SolverTermination::kInvalidInput);
  if (!source->mesh.IsVertex(vertex.vertex)) {
    return refuse(Describe(*source) + " has no vertex " + std::to_string(vertex.vertex), SolverTermination::kInvalidInput);
  }
  if (!target_in_world.allFinite()) return refuse("the target position is not finite", SolverTermination::kInvalidInput);

  Primitive& primitive = *moved->FindPrimitive(vertex.primitive_id);
  const PrimitiveShape& shape = source->shape;
  const Eigen::Matrix3d world_from_primitive = RotationFromAngleAxis(shape.rotation);
  const MeshVertex& dragged = source->mesh.vertex(vertex.vertex);
  const Eigen::Vector3d start = world_from_primitive * dragged.LocalPosition(shape.params) + shape.translation;
  const Eigen::Vector3d wanted = target_in_world - start;
  summary.params_before = summary.params_after = shape.params;
  summary.translation_before = summary.translation_after = shape.translation;
  const double size = PrimitiveSize(*source);

  if (dragged.local.free) {
    // The offset is in primitive-local units; the rotation maps the world step into them.
    primitive.mesh.vertex(vertex.vertex).local.offset += world_from_primitive.transpose() * wanted;
    RefreshPrimitive(moved, &primitive);
    if (const std::string why = WhyMoveDegenerate(project, *moved); !why.empty()) return refuse(why);
    summary.termination = SolverTermination::kConverged;
    summary.moved_offset = true;
    RecordPosition(*source, *moved, vertex, target_in_world, options.reach_tolerance * size, &summary);
    summary.message = Describe(*source) + ": free vertex " + std::to_string(vertex.vertex) + " moved";
    return summary;
  }

  // The unknowns the locks and the attachment leave free.
  const int param_count = ShapeParamCount(shape.kind);
  const bool attached = source->attached_to != kNoId && project.FindPrimitive(source->attached_to) != nullptr;
  std::vector<Unknown> unknowns;
  for (int k = 0; k < param_count; ++k) {
    if (!source->param_locked[k] && !(attached && k < 2)) unknowns.push_back({true, k});
  }
  const bool translation_free = !source->translation_locked && !attached;
  if (translation_free) {
    for (int j = 0; j < 3; ++j) unknowns.push_back({false, j});
  }
  const int n = static_cast<int>(unknowns.size());

  if (n == 0) {
    summary.limited_by = LockReasons(project, *source, dragged, world_from_primitive, attached, wanted);
    std::string text = Describe(*source) + " cannot change:";
    for (const std::string& r : summary.limited_by) text += " " + r + ";";
    if (summary.limited_by.empty()) text += " every dimension is locked;";
    text.pop_back();
    return refuse(text);
  }

  const Eigen::VectorXd dx =
      SmallestStep(*source, vertex.vertex, unknowns, world_from_primitive, wanted, options, size);
  PrimitiveShape& out = primitive.shape;
  for (int u = 0; u < n; ++u) {
    if (unknowns[u].is_param) {
      out.params[unknowns[u].index] += dx(u);
    } else {
      out.translation[unknowns[u].index] += dx(u);
    }
  }
  for (int k = 0; k < param_count; ++k) {
    if (!(out.params[k] > 0.0)) {
      return refuse(Describe(*source) + ": " + ShapeParamLabel(shape.kind, k) + " would become " +
                    internal::FormatNumber(out.params[k], kMessageDigits) +
                    " (the drag went through the opposite face)");
    }
  }
  RefreshAllPrimitives(moved);
  if (const std::string why = WhyMoveDegenerate(project, *moved); !why.empty()) return refuse(why);
  RecordPosition(*source, *moved, vertex, target_in_world, options.reach_tolerance * size, &summary);

  const Eigen::Vector3d missing = target_in_world - summary.position;
  if (!summary.reached)
    summary.limited_by = LockReasons(project, *source, dragged, world_from_primitive, attached, missing);
  if (dx.norm() <= options.rank_tolerance * size && !summary.reached) {
    std::string text = Describe(*source) + ": vertex " + std::to_string(vertex.vertex) + " cannot move that way:";
    for (const std::string& r : summary.limited_by) text += " " + r + ";";
    if (summary.limited_by.empty()) text += " no free parameter moves it;";
    text.pop_back();
    return refuse(text);  // keeps limited_by
  }

  summary.termination = SolverTermination::kConverged;
  summary.message = DescribeMove(*source, out, summary);
  return summary;
}

PrimitiveMoveSummary MovePrimitive(const Project& project, Id primitive_id, const Eigen::Vector3d& delta_in_world,
                                   Project* moved) {
  PrimitiveMoveSummary summary;
  *moved = project;
  const Primitive* source = project.FindPrimitive(primitive_id);
  if (source == nullptr) {
    summary.message = "the primitive #" + std::to_string(primitive_id) + " does not exist";
    return summary;  // kInvalidInput, as default-constructed
  }
  if (!delta_in_world.allFinite()) {
    summary.message = "the move is not finite";
    return summary;
  }
  if (source->attached_to != kNoId && project.FindPrimitive(source->attached_to) != nullptr) {
    summary.message = Describe(*source) + " sits on " + Describe(*project.FindPrimitive(source->attached_to)) +
                      " and follows it: move the base instead";
    return summary;
  }
  if (source->translation_locked) {
    summary.message = Describe(*source) + ": its translation is locked (unlock it to move the primitive)";
    return summary;
  }
  moved->FindPrimitive(primitive_id)->shape.translation += delta_in_world;
  RefreshAllPrimitives(moved);
  if (const std::string why = WhyMoveDegenerate(project, *moved); !why.empty()) {
    summary.message = why;
    *moved = project;
    return summary;
  }
  summary.termination = SolverTermination::kConverged;
  summary.message = Describe(*source) + " moved by " + internal::FormatNumber(delta_in_world.norm(), kMessageDigits);
  return summary;
}

}  // namespace facet
