#include "core/solve/scene_solve_internal.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include <Eigen/Dense>
#include <Eigen/SVD>

#include "core/geometry/camera.h"
#include "core/geometry/cross_product_matrix.h"
#include "core/util/eigen_decompositions.h"

namespace facet::scene_solve_internal {
namespace {

using internal::Skew;
// Built by appending: GCC 12 reports a false -Wrestrict on "literal" + std::string.
std::string QuotedOrId(const std::string& name, Id id) {
  std::string label = name.empty() ? "#" : "'";
  label.append(name.empty() ? std::to_string(id) : name);
  if (!name.empty()) label.append("'");
  return label;
}

std::string PrimitiveLabel(const Primitive& primitive) {
  return std::string(PrimitiveKindName(primitive.shape.kind)) + " " + QuotedOrId(primitive.name, primitive.id);
}

// What a user calls each shape parameter (core/mesh/primitives.h).
std::string ParamName(PrimitiveKind kind, int k) {
  switch (kind) {
    case PrimitiveKind::kPrism:
    case PrimitiveKind::kCylinder: return k == 0 ? "radius" : "height";
    default: {
      static const char* kNames[3] = {"width (x size)", "depth (y size)", "height (z size)"};
      return k < 3 ? kNames[k] : "parameter " + std::to_string(k);
    }
  }
}

std::string ImageLabel(const Image& image) { return QuotedOrId(image.path, image.id); }

// "x", "x and y", "x, y and z".
std::string JoinComponents(const std::vector<int>& components) {
  static const char* kNames[3] = {"x", "y", "z"};
  std::string out;
  for (size_t i = 0; i < components.size(); ++i) {
    if (i > 0) out += (i + 1 == components.size()) ? " and " : ", ";
    out += kNames[components[i]];
  }
  return out;
}

// What the user reads when a dimension is held because no pin sees it, with the fix.
std::string HeldParameterNote(const Primitive& primitive, int k) {
  const PrimitiveKind kind = primitive.shape.kind;
  const bool boxy = kind != PrimitiveKind::kPrism && kind != PrimitiveKind::kCylinder && k < 3;
  static const char* kBoxFaceNames[3] = {"+x side", "back", "top"};
  char value[64];
  std::snprintf(value, sizeof(value), "%.4g", primitive.shape.params[k]);
  return "the " + ParamName(kind, k) + " of " + PrimitiveLabel(primitive) + " is seen by no pin, so it keeps " + value +
         " until one does: pin a vertex on its " +
         (boxy ? std::string(kBoxFaceNames[k]) + " face" : std::string("far side")) +
         " (in a second photo if this one does not show it), or lock the " + ParamName(kind, k) +
         " at its known length";
}

// Whether the primitive's footprint (params 0, 1) follows a box it sits on (AttachOnTop's
// rule, as the joint solve applies it).
bool FootprintFollowsBase(const Project& project, const Primitive& primitive) {
  if (primitive.attached_to == kNoId || primitive.attached_to == primitive.id) return false;
  if (primitive.shape.kind == PrimitiveKind::kPrism || primitive.shape.kind == PrimitiveKind::kCylinder) return false;
  const Primitive* base = project.FindPrimitive(primitive.attached_to);
  return base != nullptr && base->shape.kind == PrimitiveKind::kBox;
}

}  // namespace

SceneProblem BuildSceneProblem(const Project& project, SceneState* state) {
  SceneProblem problem;
  const int num_images = static_cast<int>(project.images.size());
  const int num_primitives = static_cast<int>(project.primitives.size());
  auto image_index = [&](Id id) {
    for (int i = 0; i < num_images; ++i)
      if (project.images[i].id == id) return i;
    return -1;
  };
  auto primitive_index = [&](Id id) {
    for (int i = 0; i < num_primitives; ++i)
      if (project.primitives[i].id == id) return i;
    return -1;
  };

  // First pass: which pins take part, and which images and boxes they use.
  std::vector<std::pair<int, int>> pin_targets(project.pins.size(), {-1, -1});
  std::vector<char> image_used(num_images, 0), primitive_used(num_primitives, 0);
  std::map<int, int> uncalibrated_pin_counts;
  for (size_t p = 0; p < project.pins.size(); ++p) {
    const Pin& pin = project.pins[p];
    const int ii = image_index(pin.image_id);
    const int bi = primitive_index(pin.vertex.primitive_id);
    const std::string pin_label = "pin #" + std::to_string(pin.id);
    if (ii < 0) {
      problem.warnings.push_back(pin_label + " refers to a missing image and was skipped");
    } else if (bi < 0) {
      problem.warnings.push_back(pin_label + " refers to a missing primitive and was skipped");
    } else if (!project.primitives[bi].mesh.IsVertex(pin.vertex.vertex)) {
      problem.warnings.push_back(pin_label + " names vertex " + std::to_string(pin.vertex.vertex) +
                                 ", which its primitive does not have, and was skipped");
    } else if (!project.images[ii].camera_calibrated) {
      ++uncalibrated_pin_counts[ii];
    } else {
      pin_targets[p] = {ii, bi};
      image_used[ii] = 1;
      primitive_used[bi] = 1;
      continue;
    }
    ++problem.num_skipped_pins;
  }
  for (const auto& [ii, count] : uncalibrated_pin_counts) {
    problem.warnings.push_back(std::to_string(count) + (count == 1 ? " pin" : " pins") + " in image " +
                               ImageLabel(project.images[ii]) + " skipped: the image is not calibrated");
  }

  // Per primitive, the shape parameters some used pin's vertex depends on.
  std::vector<std::array<bool, kMaxPrimitiveParams>> seen_params(num_primitives, {false, false, false, false});
  for (size_t p = 0; p < project.pins.size(); ++p) {
    const int bi = pin_targets[p].second;
    if (bi < 0) continue;
    const ParamCoefficients c = project.primitives[bi].mesh.vertex(project.pins[p].vertex.vertex).local.Collapsed();
    for (int k = 0; k < kMaxPrimitiveParams; ++k) seen_params[bi][k] = seen_params[bi][k] || !c.col(k).isZero();
  }
  // Seen through a primitive on top (AttachOnTop): the joint solve fits a base's footprint
  // from the top's pinned vertices and every base's height below them. This solve treats the
  // primitives apart, so it still holds those; only the user's note must not call them unseen.
  std::vector<std::array<bool, kMaxPrimitiveParams>> seen_through_top(num_primitives, {false, false, false, false});
  for (size_t p = 0; p < project.pins.size(); ++p) {
    const int bi = pin_targets[p].second;
    if (bi < 0) continue;
    const ParamCoefficients c = project.primitives[bi].mesh.vertex(project.pins[p].vertex.vertex).local.Collapsed();
    const Primitive* top = &project.primitives[bi];
    for (int depth = 0; depth < 64 && FootprintFollowsBase(project, *top); ++depth) {
      const int base = primitive_index(top->attached_to);
      if (base < 0 || base == bi) break;
      seen_through_top[base][2] = true;
      for (int k = 0; k < 2; ++k) seen_through_top[base][k] = seen_through_top[base][k] || !c.col(k).isZero();
      top = &project.primitives[base];
    }
  }

  // Blocks in project order, so that the parameter numbering does not depend on pin order.
  std::vector<int> camera_of_image(num_images, -1), block_of_primitive(num_primitives, -1);
  int offset = 0;
  auto add_parameters = [&](ParameterKind kind, int block, int count, int first_component) {
    for (int k = 0; k < count; ++k) problem.parameters.push_back({kind, block, first_component + k});
    const int first = offset;
    offset += count;
    return first;
  };
  *state = SceneState();
  for (int i = 0; i < num_images; ++i) {
    if (!image_used[i]) continue;
    const Image& image = project.images[i];
    CameraBlock block;
    block.image_index = i;
    block.focal_px = image.camera.focal_px;
    block.principal_point_px = image.camera.principal_point_px;
    block.cam_from_world_rotation = image.camera.cam_from_world_rotation;
    camera_of_image[i] = static_cast<int>(problem.cameras.size());
    if (!image.pose_locked) {
      block.center_offset = add_parameters(ParameterKind::kCameraCenter, camera_of_image[i], 3, 0);
    }
    problem.cameras.push_back(block);
    state->camera_centers.push_back(image.camera.CenterInWorld());
  }
  for (int i = 0; i < num_primitives; ++i) {
    if (!primitive_used[i]) continue;
    const Primitive& primitive = project.primitives[i];
    PrimitiveBlock block;
    block.primitive_index = i;
    const int b = static_cast<int>(problem.primitives.size());
    block_of_primitive[i] = b;
    for (int k = 0; k < kMaxPrimitiveParams; ++k) {
      // A parameter no vertex depends on (unused by the kind) is not a parameter at all.
      bool used = false;
      const PolyMesh& mesh = primitive.mesh;
      for (VertexId v = 0; v < mesh.VertexIdEnd() && !used; ++v) {
        used = mesh.IsVertex(v) && !mesh.vertex(v).local.Collapsed().col(k).isZero();
      }
      if (!used || primitive.param_locked[k]) continue;
      // A dimension no pinned vertex depends on (a box's depth when only its front face is
      // pinned) has nothing to fit: as a parameter it would leave the linear start rank
      // deficient and the problem without a start. It keeps its current value until a pin
      // sees it, and the summary says so with the fix.
      if (!seen_params[i][k]) {
        // A top's footprint is its base box's (AttachOnTop): the joint solve fits it there,
        // so naming it here would name the wrong primitive (and a value that changes).
        if (!(k < 2 && FootprintFollowsBase(project, primitive)) && !seen_through_top[i][k]) {
          problem.held_parameters.push_back(HeldParameterNote(primitive, k));
        }
        continue;
      }
      block.param_offset[k] = add_parameters(ParameterKind::kPrimitiveParam, b, 1, k);
    }
    if (!primitive.rotation_locked) block.rotation_offset = add_parameters(ParameterKind::kPrimitiveRotation, b, 3, 0);
    if (!primitive.translation_locked) {
      block.translation_offset = add_parameters(ParameterKind::kPrimitiveTranslation, b, 3, 0);
    }
    problem.primitives.push_back(block);
    state->primitive_params.push_back(primitive.shape.params);
    state->primitive_rotations.push_back(RotationFromAngleAxis(primitive.shape.rotation));
    state->primitive_translations.push_back(primitive.shape.translation);
  }
  problem.num_parameters = offset;

  for (size_t p = 0; p < project.pins.size(); ++p) {
    const auto [ii, bi] = pin_targets[p];
    if (ii < 0) continue;
    Observation obs;
    obs.pin_index = static_cast<int>(p);
    obs.camera = camera_of_image[ii];
    obs.primitive = block_of_primitive[bi];
    const MeshVertex& vertex = project.primitives[bi].mesh.vertex(project.pins[p].vertex.vertex);
    obs.coefficients = vertex.local.Collapsed();
    obs.offset = vertex.local.offset;
    // The geometry solve holds the intrinsics, distortion included, so a pin on a distorted
    // photo is undistorted once here: the linear start and LM then work on the pinhole image,
    // whose residual vanishes exactly where the photo's does (it is measured in undistorted px,
    // a local rescaling of at most a few percent inside the image; the joint solve that follows
    // measures in the photo's px).
    obs.uv_px = project.images[ii].camera.UndistortPixel(project.pins[p].uv_px);
    problem.observations.push_back(obs);
  }
  return problem;
}

int EvaluateScene(const SceneProblem& problem, const SceneState& state, Eigen::VectorXd* residuals,
                  Eigen::MatrixXd* jacobian) {
  const int m = 2 * static_cast<int>(problem.observations.size());
  residuals->resize(m);
  if (jacobian != nullptr) jacobian->setZero(m, problem.num_parameters);
  int num_behind = 0;
  for (size_t o = 0; o < problem.observations.size(); ++o) {
    const Observation& obs = problem.observations[o];
    const CameraBlock& cam = problem.cameras[obs.camera];
    const PrimitiveBlock& block = problem.primitives[obs.primitive];
    const Eigen::Matrix3d& world_from_primitive = state.primitive_rotations[obs.primitive];
    const Eigen::Vector3d corner_rotated =
        world_from_primitive * (obs.coefficients * state.primitive_params[obs.primitive] + obs.offset);
    const Eigen::Vector3d corner_in_world = corner_rotated + state.primitive_translations[obs.primitive];
    const Eigen::Vector3d p_in_cam = cam.cam_from_world_rotation * (corner_in_world - state.camera_centers[obs.camera]);
    if (!(p_in_cam.z() > 0.0)) ++num_behind;
    const double inv_z = 1.0 / p_in_cam.z();
    const int row = 2 * static_cast<int>(o);
    (*residuals)(row) = cam.focal_px * p_in_cam.x() * inv_z + cam.principal_point_px.x() - obs.uv_px.x();
    (*residuals)(row + 1) = cam.focal_px * p_in_cam.y() * inv_z + cam.principal_point_px.y() - obs.uv_px.y();
    if (jacobian == nullptr) continue;

    // d uv / d p_in_cam, then through p_in_cam = R_cam (X - C) to d uv / d X.
    Eigen::Matrix<double, 2, 3> d_uv_d_cam;
    const double fz = cam.focal_px * inv_z;
    d_uv_d_cam << fz, 0.0, -fz * p_in_cam.x() * inv_z, 0.0, fz, -fz * p_in_cam.y() * inv_z;
    const Eigen::Matrix<double, 2, 3> d_uv_d_world = d_uv_d_cam * cam.cam_from_world_rotation;
    auto jblock = [&](int col) { return jacobian->block<2, 3>(row, col); };
    if (cam.center_offset >= 0) jblock(cam.center_offset) = -d_uv_d_world;
    for (int k = 0; k < kMaxPrimitiveParams; ++k) {
      if (block.param_offset[k] >= 0) {
        jacobian->block<2, 1>(row, block.param_offset[k]) =
            d_uv_d_world * (world_from_primitive * obs.coefficients.col(k));
      }
    }
    // exp([d]x) R q ~ R q + d x (R q): the derivative with respect to d is -[R q]x.
    if (block.rotation_offset >= 0) jblock(block.rotation_offset) = -d_uv_d_world * Skew(corner_rotated);
    if (block.translation_offset >= 0) jblock(block.translation_offset) = d_uv_d_world;
  }
  return num_behind;
}

void ApplySceneStep(const SceneProblem& problem, const Eigen::VectorXd& delta, SceneState* state) {
  for (size_t c = 0; c < problem.cameras.size(); ++c) {
    const int off = problem.cameras[c].center_offset;
    if (off >= 0) state->camera_centers[c] += delta.segment<3>(off);
  }
  for (size_t b = 0; b < problem.primitives.size(); ++b) {
    const PrimitiveBlock& block = problem.primitives[b];
    for (int k = 0; k < kMaxPrimitiveParams; ++k) {
      if (block.param_offset[k] >= 0) state->primitive_params[b](k) += delta(block.param_offset[k]);
    }
    if (block.rotation_offset >= 0) {
      state->primitive_rotations[b] =
          RotationFromAngleAxis(delta.segment<3>(block.rotation_offset)) * state->primitive_rotations[b];
    }
    if (block.translation_offset >= 0) {
      state->primitive_translations[b] += delta.segment<3>(block.translation_offset);
    }
  }
}

void WriteSceneState(const SceneProblem& problem, const SceneState& state, Project* project) {
  for (size_t c = 0; c < problem.cameras.size(); ++c) {
    const CameraBlock& cam = problem.cameras[c];
    if (cam.center_offset < 0) continue;
    Camera& camera = project->images[cam.image_index].camera;
    camera.SetPose(camera.cam_from_world_rotation, state.camera_centers[c]);
  }
  for (size_t b = 0; b < problem.primitives.size(); ++b) {
    const PrimitiveBlock& block = problem.primitives[b];
    PrimitiveShape& shape = project->primitives[block.primitive_index].shape;
    for (int k = 0; k < kMaxPrimitiveParams; ++k) {
      if (block.param_offset[k] >= 0) shape.params(k) = state.primitive_params[b](k);
    }
    if (block.rotation_offset >= 0) shape.rotation = AngleAxisFromRotation(state.primitive_rotations[b]);
    if (block.translation_offset >= 0) shape.translation = state.primitive_translations[b];
  }
  RefreshAllPrimitives(project);
}

namespace {

// The rows of observation `o` of the linear system: A_o x = rhs_o, 3 rows, over the columns
// named by size_col / translation_col / camera_col (-1: fixed, moved to the right-hand side).
struct LinearRows {
  Eigen::Matrix<double, 3, Eigen::Dynamic> primitive;  // columns of the observation's primitive, in order
  Eigen::Matrix3d camera = Eigen::Matrix3d::Zero();    // columns of its camera (when free)
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
};

using SizeColumns = std::vector<std::array<int, kMaxPrimitiveParams>>;

// The free columns of primitive b in order: its sizes, then its translation.
std::vector<int> PrimitiveColumns(const SizeColumns& size_col, const std::vector<int>& translation_col, size_t b) {
  std::vector<int> cols;
  for (int k = 0; k < kMaxPrimitiveParams; ++k)
    if (size_col[b][k] >= 0) cols.push_back(size_col[b][k]);
  if (translation_col[b] >= 0)
    for (int i = 0; i < 3; ++i) cols.push_back(translation_col[b] + i);
  return cols;
}

LinearRows ObservationRows(const SceneProblem& problem, const SceneState& state, const SizeColumns& size_col,
                           const std::vector<int>& translation_col, const std::vector<int>& camera_col,
                           const Observation& obs) {
  const CameraBlock& cam = problem.cameras[obs.camera];
  LinearRows rows;
  int num_cols = 0;
  for (int k = 0; k < kMaxPrimitiveParams; ++k) num_cols += size_col[obs.primitive][k] >= 0 ? 1 : 0;
  if (translation_col[obs.primitive] >= 0) num_cols += 3;
  rows.primitive = Eigen::Matrix<double, 3, Eigen::Dynamic>::Zero(3, num_cols);
  const Eigen::Vector3d ray = Eigen::Vector3d((obs.uv_px.x() - cam.principal_point_px.x()) / cam.focal_px,
                                              (obs.uv_px.y() - cam.principal_point_px.y()) / cam.focal_px, 1.0)
                                  .normalized();
  const Eigen::Matrix3d ray_cross = Skew(ray);
  const Eigen::Matrix3d m_world = ray_cross * cam.cam_from_world_rotation;
  const Eigen::Matrix3d& world_from_primitive = state.primitive_rotations[obs.primitive];
  int col = 0;
  for (int k = 0; k < kMaxPrimitiveParams; ++k) {
    const bool free = size_col[obs.primitive][k] >= 0;
    if (obs.coefficients.col(k).isZero()) {
      col += free ? 1 : 0;
      continue;
    }
    const Eigen::Vector3d coeff = m_world * (world_from_primitive * obs.coefficients.col(k));
    if (free) {
      rows.primitive.col(col++) = coeff;
    } else {
      rows.rhs -= coeff * state.primitive_params[obs.primitive](k);
    }
  }
  rows.rhs -= m_world * (world_from_primitive * obs.offset);
  if (translation_col[obs.primitive] >= 0) {
    rows.primitive.block<3, 3>(0, col) = m_world;
  } else {
    rows.rhs -= m_world * state.primitive_translations[obs.primitive];
  }
  const Eigen::Vector3d t = -cam.cam_from_world_rotation * state.camera_centers[obs.camera];
  if (camera_col[obs.camera] >= 0) {
    rows.camera = ray_cross;
  } else {
    rows.rhs -= ray_cross * t;
  }
  return rows;
}

// Above this many unknowns the linear start uses the Schur complement instead of a dense SVD.
constexpr int kDenseLinearInitMaxUnknowns = 300;

bool SolveLinearInitDense(const SceneProblem& problem, const SceneState& state, const SizeColumns& size_col,
                          const std::vector<int>& translation_col, const std::vector<int>& camera_col, int n,
                          const Eigen::VectorXd& current, Eigen::VectorXd* solution_out, std::string* why) {
  const int m = 3 * static_cast<int>(problem.observations.size());
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(m, n);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(m);
  for (size_t o = 0; o < problem.observations.size(); ++o) {
    const Observation& obs = problem.observations[o];
    const int row = 3 * static_cast<int>(o);
    const LinearRows rows = ObservationRows(problem, state, size_col, translation_col, camera_col, obs);
    const std::vector<int> cols = PrimitiveColumns(size_col, translation_col, obs.primitive);
    for (size_t j = 0; j < cols.size(); ++j) a.block<3, 1>(row, cols[j]) += rows.primitive.col(j);
    if (camera_col[obs.camera] >= 0) a.block<3, 3>(row, camera_col[obs.camera]) = rows.camera;
    rhs.segment<3>(row) = rows.rhs;
  }
  // Column scaling makes the rank test independent of the units.
  Eigen::VectorXd col_norm = a.colwise().norm();
  for (int j = 0; j < n; ++j) {
    if (col_norm(j) == 0.0) {
      *why = "the linear system is rank deficient (a free parameter appears in no pin)";
      return false;
    }
  }
  const Eigen::MatrixXd a_scaled = a * col_norm.cwiseInverse().asDiagonal();
  Eigen::BDCSVD<Eigen::MatrixXd> svd(a_scaled, Eigen::ComputeThinU | Eigen::ComputeFullV);
  const Eigen::VectorXd& sigma = svd.singularValues();
  constexpr double kRankTolerance = 1e-10;
  const double threshold = kRankTolerance * sigma(0);
  int rank = 0;
  for (int i = 0; i < sigma.size(); ++i) rank += sigma(i) > threshold ? 1 : 0;

  const bool homogeneous = rhs.norm() == 0.0;
  if (!homogeneous) {
    if (rank < n) {
      *why = "the linear system is rank deficient (rank " + std::to_string(rank) + " of " + std::to_string(n) + ")";
      return false;
    }
    *solution_out = col_norm.cwiseInverse().asDiagonal() * svd.solve(rhs);
  } else {
    // No known length: the solution is the null vector, with the scale of the current values.
    if (rank != n - 1) {
      *why = "the homogeneous linear system has a null space of dimension " + std::to_string(n - rank);
      return false;
    }
    const Eigen::VectorXd v = col_norm.cwiseInverse().asDiagonal() * svd.matrixV().col(n - 1);
    const double alpha = v.dot(current) / v.squaredNorm();
    if (!(std::abs(alpha) > 0.0)) {
      *why = "no known length and the current values give no scale";
      return false;
    }
    *solution_out = alpha * v;
  }
  return true;
}

// Relative to the largest eigenvalue of the unit-diagonal scaled normal matrix (or of S).
constexpr double kSchurRankTolerance = 1e-12;

// Each observation's linear rows, with the column scaling that gives the normal matrix a
// unit diagonal.
struct ScaledLinearRows {
  std::vector<LinearRows> rows;           // per observation
  std::vector<std::vector<int>> cols_of;  // per primitive: its columns
  Eigen::VectorXd inv_scale;              // per column: 1 / its norm
  bool homogeneous = true;                // no known length: every rhs is zero
};

// False (why says so) when a free parameter appears in no pin.
bool CollectScaledRows(const SceneProblem& problem, const SceneState& state, const SizeColumns& size_col,
                       const std::vector<int>& translation_col, const std::vector<int>& camera_col, int n,
                       ScaledLinearRows* out, std::string* why) {
  const size_t num_primitives = problem.primitives.size();
  std::vector<LinearRows>& all_rows = out->rows;
  all_rows.reserve(problem.observations.size());
  Eigen::VectorXd col_sq = Eigen::VectorXd::Zero(n);
  std::vector<std::vector<int>>& cols_of = out->cols_of;
  cols_of.resize(num_primitives);
  for (size_t b = 0; b < num_primitives; ++b) cols_of[b] = PrimitiveColumns(size_col, translation_col, b);
  bool homogeneous = true;
  for (const Observation& obs : problem.observations) {
    all_rows.push_back(ObservationRows(problem, state, size_col, translation_col, camera_col, obs));
    const LinearRows& rows = all_rows.back();
    const std::vector<int>& cols = cols_of[obs.primitive];
    for (size_t j = 0; j < cols.size(); ++j) col_sq(cols[j]) += rows.primitive.col(j).squaredNorm();
    if (camera_col[obs.camera] >= 0) {
      for (int i = 0; i < 3; ++i) col_sq(camera_col[obs.camera] + i) += rows.camera.col(i).squaredNorm();
    }
    homogeneous = homogeneous && rows.rhs.squaredNorm() == 0.0;
  }
  out->homogeneous = homogeneous;
  for (int j = 0; j < n; ++j) {
    if (col_sq(j) == 0.0) {
      *why = "the linear system is rank deficient (a free parameter appears in no pin)";
      return false;
    }
  }
  out->inv_scale = col_sq.cwiseSqrt().cwiseInverse();
  return true;
}

struct PrimitiveSystem {
  Eigen::MatrixXd u;                               // U_b
  Eigen::VectorXd b;                               // primitive part of A^T rhs
  std::vector<std::pair<int, Eigen::MatrixXd>> w;  // (reduced offset, W_bc)
};

// The scaled normal equations by blocks: per primitive, and the cameras' S and g (the reduced
// camera system once the primitives are eliminated).
struct SchurSystem {
  std::vector<PrimitiveSystem> prim;
  std::vector<int> reduced_of_camera;  // per camera: its offset in S, -1 when fixed
  int r = 0;                           // S's size
  Eigen::MatrixXd s;
  Eigen::VectorXd g;
};

SchurSystem AssembleSchurSystem(const SceneProblem& problem, const std::vector<int>& camera_col,
                                const ScaledLinearRows& scaled_rows) {
  const size_t num_primitives = problem.primitives.size();
  const std::vector<LinearRows>& all_rows = scaled_rows.rows;
  const std::vector<std::vector<int>>& cols_of = scaled_rows.cols_of;
  const Eigen::VectorXd& inv_scale = scaled_rows.inv_scale;
  SchurSystem system;
  // Free cameras get consecutive 3-blocks of the reduced system.
  std::vector<int>& reduced_of_camera = system.reduced_of_camera;
  reduced_of_camera.assign(problem.cameras.size(), -1);
  int num_reduced = 0;
  for (size_t c = 0; c < problem.cameras.size(); ++c)
    if (camera_col[c] >= 0) reduced_of_camera[c] = 3 * (num_reduced++);
  const int r = 3 * num_reduced;
  system.r = r;

  std::vector<PrimitiveSystem>& prim = system.prim;
  prim.resize(num_primitives);
  for (size_t b = 0; b < num_primitives; ++b) {
    const int nb = static_cast<int>(cols_of[b].size());
    prim[b].u = Eigen::MatrixXd::Zero(nb, nb);
    prim[b].b = Eigen::VectorXd::Zero(nb);
  }
  Eigen::MatrixXd& s = system.s;
  Eigen::VectorXd& g = system.g;
  s = Eigen::MatrixXd::Zero(r, r);
  g = Eigen::VectorXd::Zero(r);
  for (size_t o = 0; o < problem.observations.size(); ++o) {
    const Observation& obs = problem.observations[o];
    const std::vector<int>& cols = cols_of[obs.primitive];
    Eigen::MatrixXd ap = all_rows[o].primitive;
    for (size_t j = 0; j < cols.size(); ++j) ap.col(j) *= inv_scale(cols[j]);
    PrimitiveSystem& ps = prim[obs.primitive];
    ps.u.noalias() += ap.transpose() * ap;
    ps.b.noalias() += ap.transpose() * all_rows[o].rhs;
    const int rc = reduced_of_camera[obs.camera];
    if (rc < 0) continue;
    Eigen::Matrix3d ac = all_rows[o].camera;
    for (int i = 0; i < 3; ++i) ac.col(i) *= inv_scale(camera_col[obs.camera] + i);
    s.block<3, 3>(rc, rc).noalias() += ac.transpose() * ac;
    g.segment<3>(rc).noalias() += ac.transpose() * all_rows[o].rhs;
    auto it = std::find_if(ps.w.begin(), ps.w.end(), [rc](const auto& e) { return e.first == rc; });
    if (it == ps.w.end()) {
      ps.w.emplace_back(rc, Eigen::MatrixXd::Zero(cols.size(), 3));
      it = ps.w.end() - 1;
    }
    it->second.noalias() += ap.transpose() * ac;
  }
  return system;
}

// Eliminates each primitive block: S -= W^T U^-1 W, g -= W^T U^-1 b; u_factor receives each
// U_b's factorisation for the back-substitution. False (why says so) when a U_b is singular.
bool EliminatePrimitives(const SceneProblem& problem, SchurSystem* system,
                         std::vector<Eigen::LDLT<Eigen::MatrixXd>>* u_factor, std::string* why) {
  const size_t num_primitives = problem.primitives.size();
  Eigen::MatrixXd& s = system->s;
  Eigen::VectorXd& g = system->g;
  u_factor->resize(num_primitives);
  for (size_t b = 0; b < num_primitives; ++b) {
    const PrimitiveSystem& ps = system->prim[b];
    if (ps.u.rows() == 0) continue;
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(ps.u, Eigen::EigenvaluesOnly);
    if (!(eig.eigenvalues()(0) > kSchurRankTolerance * eig.eigenvalues().maxCoeff())) {
      *why = "the linear system is rank deficient (the pins do not fix primitive " +
             std::to_string(problem.primitives[b].primitive_index + 1) + " on their own)";
      return false;
    }
    (*u_factor)[b].compute(ps.u);
    const Eigen::VectorXd u_inv_b = (*u_factor)[b].solve(ps.b);
    for (const auto& [ri, wi] : ps.w) {
      const Eigen::MatrixXd u_inv_wi = (*u_factor)[b].solve(wi);
      g.segment<3>(ri).noalias() -= wi.transpose() * u_inv_b;
      for (const auto& [rj, wj] : ps.w) s.block<3, 3>(rj, ri).noalias() -= wj.transpose() * u_inv_wi;
    }
  }
  return true;
}

// The free cameras' (scaled) unknowns from the reduced system S x = g, or S's null vector when
// homogeneous. False (why says so) when the rank does not allow it.
bool SolveReducedCameras(const SchurSystem& system, bool homogeneous, Eigen::VectorXd* cameras_out, std::string* why) {
  const int r = system.r;
  Eigen::VectorXd& cameras = *cameras_out;
  cameras = Eigen::VectorXd::Zero(r);
  if (r > 0) {
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(system.s);
    const Eigen::VectorXd& ev = eig.eigenvalues();
    const double threshold = kSchurRankTolerance * std::max(1.0, ev.maxCoeff());
    int rank = 0;
    for (int i = 0; i < r; ++i) rank += ev(i) > threshold ? 1 : 0;
    if (!homogeneous) {
      if (rank < r) {
        *why = "the linear system is rank deficient (camera positions: rank " + std::to_string(rank) + " of " +
               std::to_string(r) + ")";
        return false;
      }
      cameras = eig.eigenvectors() * (eig.eigenvectors().transpose() * system.g).cwiseQuotient(ev);
    } else {
      if (rank != r - 1) {
        *why = "the homogeneous linear system has a null space of dimension " + std::to_string(r - rank);
        return false;
      }
      cameras = eig.eigenvectors().col(0);
    }
  } else if (homogeneous) {
    *why = "no known length and no free camera: the linear system has no scale";
    return false;
  }
  return true;
}

// The same least-squares problem through its normal equations, column-scaled: each primitive's
// small block U_b (sizes + translation) is eliminated, leaving the reduced camera system
// S = V - sum_b W_b^T U_b^-1 W_b (3 per free camera). A block or S with an eigenvalue below
// kSchurRankTolerance (relative, on the unit-diagonal scaled normal matrix) is rank deficient.
// With no known length the system is homogeneous and its null vector is S's, back-substituted.
bool SolveLinearInitSchur(const SceneProblem& problem, const SceneState& state, const SizeColumns& size_col,
                          const std::vector<int>& translation_col, const std::vector<int>& camera_col, int n,
                          const Eigen::VectorXd& current, Eigen::VectorXd* solution_out, std::string* why) {
  const size_t num_primitives = problem.primitives.size();
  ScaledLinearRows scaled_rows;
  if (!CollectScaledRows(problem, state, size_col, translation_col, camera_col, n, &scaled_rows, why)) return false;
  const bool homogeneous = scaled_rows.homogeneous;
  const std::vector<std::vector<int>>& cols_of = scaled_rows.cols_of;
  SchurSystem system = AssembleSchurSystem(problem, camera_col, scaled_rows);
  std::vector<Eigen::LDLT<Eigen::MatrixXd>> u_factor;
  if (!EliminatePrimitives(problem, &system, &u_factor, why)) return false;
  Eigen::VectorXd cameras;
  if (!SolveReducedCameras(system, homogeneous, &cameras, why)) return false;

  Eigen::VectorXd scaled(n);
  for (size_t b = 0; b < num_primitives; ++b) {
    const PrimitiveSystem& ps = system.prim[b];
    if (ps.u.rows() == 0) continue;
    Eigen::VectorXd rhs_b = homogeneous ? Eigen::VectorXd::Zero(ps.b.size()) : ps.b;
    for (const auto& [ri, wi] : ps.w) rhs_b.noalias() -= wi * cameras.segment<3>(ri);
    const Eigen::VectorXd x_b = u_factor[b].solve(rhs_b);
    for (size_t j = 0; j < cols_of[b].size(); ++j) scaled(cols_of[b][j]) = x_b(static_cast<int>(j));
  }
  for (size_t c = 0; c < problem.cameras.size(); ++c)
    if (camera_col[c] >= 0) scaled.segment<3>(camera_col[c]) = cameras.segment<3>(system.reduced_of_camera[c]);
  Eigen::VectorXd solution = scaled_rows.inv_scale.cwiseProduct(scaled);
  if (homogeneous) {
    const double alpha = solution.dot(current) / solution.squaredNorm();
    if (!(std::abs(alpha) > 0.0)) {
      *why = "no known length and the current values give no scale";
      return false;
    }
    solution *= alpha;
  }
  *solution_out = std::move(solution);
  return true;
}

}  // namespace

bool LinearInitialization(const SceneProblem& problem, SceneState* state, std::string* why, LinearInitMethod method) {
  // Unknowns: free sizes, free box translations, free camera translations t = -R C.
  std::vector<std::array<int, kMaxPrimitiveParams>> size_col(problem.primitives.size(), {-1, -1, -1, -1});
  std::vector<int> translation_col(problem.primitives.size(), -1), camera_col(problem.cameras.size(), -1);
  int n = 0;
  for (size_t b = 0; b < problem.primitives.size(); ++b) {
    for (int k = 0; k < kMaxPrimitiveParams; ++k) {
      if (problem.primitives[b].param_offset[k] >= 0) size_col[b][k] = n++;
    }
    if (problem.primitives[b].translation_offset >= 0) {
      translation_col[b] = n;
      n += 3;
    }
  }
  for (size_t c = 0; c < problem.cameras.size(); ++c) {
    if (problem.cameras[c].center_offset >= 0) {
      camera_col[c] = n;
      n += 3;
    }
  }
  if (n == 0) {
    *why = "no size or position is free";
    return false;
  }

  Eigen::VectorXd current(n);
  for (size_t b = 0; b < problem.primitives.size(); ++b) {
    for (int k = 0; k < kMaxPrimitiveParams; ++k) {
      if (size_col[b][k] >= 0) current(size_col[b][k]) = state->primitive_params[b](k);
    }
    if (translation_col[b] >= 0) current.segment<3>(translation_col[b]) = state->primitive_translations[b];
  }
  for (size_t c = 0; c < problem.cameras.size(); ++c) {
    if (camera_col[c] >= 0) {
      current.segment<3>(camera_col[c]) = -problem.cameras[c].cam_from_world_rotation * state->camera_centers[c];
    }
  }

  // Each observation's 3 rows touch one primitive's columns and one camera's: the dense SVD is
  // exact and names the rank for small systems, the Schur complement over the primitive blocks
  // keeps large scenes (hundreds of primitives) linear in their size.
  Eigen::VectorXd solution;
  const bool dense =
      method == LinearInitMethod::kDense || (method == LinearInitMethod::kAuto && n <= kDenseLinearInitMaxUnknowns);
  const bool solved =
      dense ? SolveLinearInitDense(problem, *state, size_col, translation_col, camera_col, n, current, &solution, why)
            : SolveLinearInitSchur(problem, *state, size_col, translation_col, camera_col, n, current, &solution, why);
  if (!solved) return false;
  if (!solution.allFinite()) {
    *why = "the linear solution is not finite";
    return false;
  }

  SceneState trial = *state;
  for (size_t b = 0; b < problem.primitives.size(); ++b) {
    for (int k = 0; k < kMaxPrimitiveParams; ++k) {
      if (size_col[b][k] >= 0) trial.primitive_params[b](k) = solution(size_col[b][k]);
    }
    if (translation_col[b] >= 0) trial.primitive_translations[b] = solution.segment<3>(translation_col[b]);
  }
  for (size_t c = 0; c < problem.cameras.size(); ++c) {
    if (camera_col[c] >= 0) {
      trial.camera_centers[c] =
          -problem.cameras[c].cam_from_world_rotation.transpose() * solution.segment<3>(camera_col[c]);
    }
  }
  Eigen::VectorXd residuals;
  const int num_behind = EvaluateScene(problem, trial, &residuals, nullptr);
  if (num_behind > 0) {
    *why = "the linear solution puts " + std::to_string(num_behind) + " pinned corner(s) behind the camera";
    return false;
  }
  for (size_t b = 0; b < problem.primitives.size(); ++b) {
    for (int k = 0; k < kMaxPrimitiveParams; ++k) {
      if (size_col[b][k] >= 0 && !(trial.primitive_params[b](k) > 0.0)) {
        *why = "the linear solution gives a primitive a dimension that is not positive";
        return false;
      }
    }
  }
  if (!residuals.allFinite()) {
    *why = "the linear solution gives non-finite residuals";
    return false;
  }
  *state = std::move(trial);
  return true;
}

namespace {

// The direction in parameter space (column-scaled) of a whole-scene scale (axis < 0) or
// shift along an axis.
Eigen::VectorXd GaugeDirection(const SceneProblem& problem, const SceneState& state, const Eigen::VectorXd& col_norm,
                               int axis) {
  const int n = problem.num_parameters;
  Eigen::VectorXd g = Eigen::VectorXd::Zero(n);
  for (int j = 0; j < n; ++j) {
    const ParameterInfo& info = problem.parameters[j];
    double value = 0.0;
    switch (info.kind) {
      case ParameterKind::kCameraCenter:
        value = axis < 0 ? state.camera_centers[info.block](info.component) : (info.component == axis ? 1.0 : 0.0);
        break;
      case ParameterKind::kPrimitiveTranslation:
        value =
            axis < 0 ? state.primitive_translations[info.block](info.component) : (info.component == axis ? 1.0 : 0.0);
        break;
      case ParameterKind::kPrimitiveParam:
        value = axis < 0 ? state.primitive_params[info.block](info.component) : 0.0;
        break;
      case ParameterKind::kPrimitiveRotation: break;
    }
    g(j) = value * col_norm(j);
  }
  return g;
}

// Whole-scene ambiguities (scale, position) are named once rather than per parameter.
// The directions named are removed from null_space, whose remaining columns are re-orthonormalised.
void WarnAboutGauges(const SceneProblem& problem, const SceneState& state, const Eigen::VectorXd& col_norm,
                     Eigen::MatrixXd* null_space_io, std::vector<std::string>* warnings) {
  Eigen::MatrixXd& null_space = *null_space_io;
  constexpr double kGaugeCosine = 0.99;
  std::vector<Eigen::VectorXd> gauges;
  bool scale_free = false, position_free = false;
  for (int axis = -1; axis < 3; ++axis) {
    Eigen::VectorXd g = GaugeDirection(problem, state, col_norm, axis);
    for (const auto& h : gauges) g -= h.dot(g) * h;
    if (g.norm() == 0.0) continue;
    g.normalize();
    if ((null_space.transpose() * g).norm() > kGaugeCosine) {
      gauges.push_back(g);
      (axis < 0 ? scale_free : position_free) = true;
    }
  }
  if (scale_free) {
    warnings->push_back("the scale of the scene is not fixed by the pins: lock a dimension whose length you know");
  }
  if (position_free) {
    warnings->push_back(
        "the position of the scene is not fixed by the pins: lock the translation of a primitive or the pose of a "
        "camera");
  }
  for (const auto& g : gauges) null_space -= g * (g.transpose() * null_space);
  if (!gauges.empty() && null_space.cols() > 0) {
    Eigen::JacobiSVD<Eigen::MatrixXd> basis(null_space, Eigen::ComputeThinU);
    int keep = 0;
    for (int i = 0; i < basis.singularValues().size(); ++i) keep += basis.singularValues()(i) > 0.5 ? 1 : 0;
    null_space = basis.matrixU().leftCols(keep);
  }
}

// A parameter is named when the unconstrained directions move it noticeably.
void WarnAboutParameters(const Project& project, const SceneProblem& problem, const Eigen::MatrixXd& null_space,
                         std::vector<std::string>* warnings) {
  const int n = problem.num_parameters;
  constexpr double kNameThreshold = 0.1;
  const Eigen::VectorXd weight = null_space.rowwise().norm();
  std::map<std::pair<int, int>, std::vector<int>> free_components;  // (kind, block) -> components
  for (int j = 0; j < n; ++j) {
    if (weight(j) <= kNameThreshold) continue;
    const ParameterInfo& info = problem.parameters[j];
    free_components[{static_cast<int>(info.kind), info.block}].push_back(info.component);
  }
  static const char* kBoxFaceNames[3] = {"+x side", "back", "top"};
  for (const auto& [key, components] : free_components) {
    const auto kind = static_cast<ParameterKind>(key.first);
    const int block = key.second;
    if (kind == ParameterKind::kCameraCenter) {
      const Image& image = project.images[problem.cameras[block].image_index];
      warnings->push_back("the " + JoinComponents(components) + " coordinate" + (components.size() > 1 ? "s" : "") +
                          " of the camera centre of image " + ImageLabel(image) +
                          (components.size() > 1 ? " are" : " is") +
                          " not determined by the pins: pin more vertices in this image or lock its pose");
      continue;
    }
    const Primitive& primitive = project.primitives[problem.primitives[block].primitive_index];
    const PrimitiveKind shape_kind = primitive.shape.kind;
    switch (kind) {
      case ParameterKind::kPrimitiveParam:
        for (int k : components) {
          const bool boxy = shape_kind != PrimitiveKind::kPrism && shape_kind != PrimitiveKind::kCylinder && k < 3;
          warnings->push_back("the " + ParamName(shape_kind, k) + " of " + PrimitiveLabel(primitive) +
                              " is not determined by the pins: pin a vertex on the " +
                              (boxy ? std::string(kBoxFaceNames[k]) + " face" : "far side") + " or add a second image");
        }
        break;
      case ParameterKind::kPrimitiveRotation:
        warnings->push_back("the rotation of " + PrimitiveLabel(primitive) +
                            " is not determined by the pins: pin more of its vertices or lock its rotation");
        break;
      case ParameterKind::kPrimitiveTranslation:
        warnings->push_back("the " + JoinComponents(components) + " position of " + PrimitiveLabel(primitive) +
                            " is not determined by the pins: pin more of its vertices or lock its translation");
        break;
      case ParameterKind::kCameraCenter: break;
    }
  }
}

}  // namespace

std::vector<std::string> UndeterminedParameterWarnings(const Project& project, const SceneProblem& problem,
                                                       const SceneState& state) {
  std::vector<std::string> warnings;
  const int n = problem.num_parameters;
  if (n == 0) return warnings;
  Eigen::VectorXd residuals;
  Eigen::MatrixXd jacobian;
  EvaluateScene(problem, state, &residuals, &jacobian);
  if (!jacobian.allFinite()) return warnings;

  // Rank of the column-scaled Jacobian; a column of zeros stays zero (its parameter is free).
  Eigen::VectorXd col_norm = jacobian.colwise().norm();
  Eigen::VectorXd inv_norm(n);
  for (int j = 0; j < n; ++j) inv_norm(j) = col_norm(j) > 0.0 ? 1.0 / col_norm(j) : 0.0;
  const Eigen::MatrixXd scaled = jacobian * inv_norm.asDiagonal();
  Eigen::BDCSVD<Eigen::MatrixXd> svd(scaled, Eigen::ComputeFullV);
  const Eigen::VectorXd& sigma = svd.singularValues();
  // A scaled singular value below this is a direction the pins do not constrain: moving along
  // it by one unit of "one column norm" changes the pixels by less than 1e-8 of the others.
  constexpr double kRankTolerance = 1e-8;
  const double threshold = sigma.size() > 0 ? kRankTolerance * sigma(0) : 0.0;
  int rank = 0;
  for (int i = 0; i < sigma.size(); ++i) rank += sigma(i) > threshold ? 1 : 0;
  if (rank == n) return warnings;
  Eigen::MatrixXd null_space = svd.matrixV().rightCols(n - rank);

  WarnAboutGauges(problem, state, col_norm, &null_space, &warnings);
  if (null_space.cols() == 0) return warnings;

  WarnAboutParameters(project, problem, null_space, &warnings);
  return warnings;
}

}  // namespace facet::scene_solve_internal
